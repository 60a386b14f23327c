"""The sweep engines: the compiled search (Numba) and the NumPy reference agree; building blocks behave."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import sweepik
from sweepik import load_robot, solve_many
from sweepik.engine import search
from sweepik.engine.rootfind import find_roots
from sweepik.experiments.bench import grid_configurations
from sweepik.results import joint_distance

CARM = load_robot("carm")


def _stress(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    q = rng.uniform(CARM.lower, CARM.upper, (n, 6))
    k = n // 5
    q[:k, 4] = rng.normal(0.0, 1e-3, k)
    q[k : 2 * k, 1] = np.pi / 2 * rng.choice([-1, 1], k) + rng.normal(0.0, 1e-4, k)
    q[2 * k : 3 * k, 0] = rng.choice([0.0, 2000.0], k)
    return q


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize("reduction", ["carm-d1", "carm-theta2"])
def test_compiled_and_numpy_engines_agree(reduction: str, monkeypatch: pytest.MonkeyPatch) -> None:
    T = CARM.fk(_stress(600, seed=3))
    fast = solve_many(CARM, T, reduction=reduction)
    monkeypatch.setattr(search, "AVAILABLE", False)
    ref = solve_many(CARM, T, reduction=reduction)
    for a, b in zip(fast, ref, strict=True):
        assert len(a) == len(b)
        assert len(a.families) == len(b.families)
        if len(a):
            d = joint_distance(CARM, a.q[:, None, :], b.q[None, :, :]).max(axis=-1)
            assert d.min(axis=1).max() <= 1e-8


def test_find_roots_vectorised_to_full_precision() -> None:
    c = np.linspace(-0.9, 0.9, 101)

    def f(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
        return np.sin(x) - c[idx]

    a, b = np.full(c.size, -1.5), np.full(c.size, 1.5)
    x = find_roots(f, a, b, f(a, np.arange(c.size)), f(b, np.arange(c.size)), 1e-15)
    np.testing.assert_allclose(x, np.arcsin(c), rtol=0, atol=4e-16)


def test_self_motion_family_members_solve_the_pose() -> None:
    q = np.array([1000.0, np.pi / 2, np.radians(30), np.radians(-60), 0.0, np.radians(20)])
    sol = sweepik.solve(CARM, CARM.fk(q))
    assert sol.families, "theta2 = 90 deg with theta5 = 0 is a self-motion"
    for fam in sol.families:
        lo, hi = fam.interval
        members = fam.at(np.linspace(lo, hi, 11))
        np.testing.assert_allclose(CARM.fk(members), np.broadcast_to(CARM.fk(q), (11, 4, 4)), atol=1e-8)
        assert np.all(CARM.within_limits(members))
    np.testing.assert_allclose(sol.nearest(q), q, atol=1e-6)
    with pytest.raises(sweepik.SweepikError, match="outside the family"):
        sol.families[0].at(sol.families[0].interval[1] + 10.0)


@pytest.mark.parametrize("reduction", ["carm-d1", "carm-theta2"])
def test_self_motion_reported_by_both_reductions_without_duplicates(reduction: str) -> None:
    q = np.array([1000.0, np.pi / 2, 0.3, -0.5, 0.0, 0.2])
    sol = sweepik.solve(CARM, CARM.fk(q), reduction=reduction)
    assert sol.families
    keys = [(f.free_joint, round(f.interval[0], 6), round(f.interval[1], 6), f.branch) for f in sol.families]
    assert len(keys) == len(set(keys))
    np.testing.assert_allclose(sol.nearest(q), q, atol=1e-6)


def test_subclass_overriding_the_residual_does_not_run_the_parents_kernel() -> None:
    arm = sweepik.load_robot("carm")

    class NoResidual(sweepik.reductions.CArmD1):
        def residual(self, poses, theta, branch=None):  # type: ignore[no-untyped-def]
            return None

    class Renamed(sweepik.reductions.CArmD1):
        name = "renamed"

    assert sweepik.reductions.CArmD1(arm).uses_kernel and Renamed(arm).uses_kernel
    assert not NoResidual(arm).uses_kernel
    q = np.array([700.0, 0.4, 0.3, -0.5, 0.6, 0.2])
    sols = sweepik.solve(arm, arm.fk(q), reduction=NoResidual(arm))
    assert np.abs(sols.nearest(q) - q).max() < 1e-6


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
def test_all_branch_kernel_is_bitwise_the_branch_kernel() -> None:
    """carm-d1's all-branch residual kernel (used for the uniform samples) gives exactly, bit for bit, what the
    one-branch kernel gives: same roots, same extrema, same families as branch-by-branch evaluation."""
    from sweepik.reductions import kernels

    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    q = _stress(400, seed=11)
    q[:20, 0] = 800.0  # with theta2 = 0 below: the wrist on joint 2's axis at d1 = Pz (r = 0)
    q[:20, 1] = 0.0
    chain = CARM.fk(q)
    params = red.kernel_params(chain)
    hints = red.sample_hints(chain)
    rng = np.random.default_rng(5)
    lo, hi = red.search_range(chain).T
    out = np.empty(4)
    for i in range(len(q)):
        thetas = np.concatenate([hints[i], rng.uniform(lo[i], hi[i], 40), [chain[i, 2, 3]]])
        for th in thetas[np.isfinite(thetas)]:
            kernels.carm_d1_residuals(params[i], float(th), out)
            one = np.array([kernels.carm_d1_residual(params[i], float(th), b) for b in range(4)])
            np.testing.assert_array_equal(out, one)
    assert search._kernel_residuals(red) is kernels.carm_d1_residuals

    class OwnKernel(sweepik.reductions.CArmD1):
        kernel = (kernels.carm_theta2_residual, kernels.carm_theta2_configuration)

    assert search._kernel_residuals(OwnKernel(CARM)) is None


def test_carm_d1_twin_branches_have_the_same_residual_bit_for_bit() -> None:
    """carm-d1 declares branches (sigma, eps) and (-sigma, -eps) twins (the engine searches one of each pair and
    hands its roots to the other): their residuals agree bit for bit, in the NumPy reference and in the kernels,
    also with the wrist on joint 2's axis (r = 0), outside the elbow's domain (NaN) and at range ends; their
    configurations differ."""
    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    assert red.twins == ((0, 3), (1, 2)) and red.search_branches == [0, 1]
    q = _stress(300, seed=12)
    q[:20, 0], q[:20, 1] = 800.0, 0.0  # the wrist on joint 2's axis at d1 = Pz
    chain = CARM.fk(q)
    lo, hi = red.search_range(chain).T
    rng = np.random.default_rng(8)
    theta = np.concatenate([lo[:, None] + (hi - lo)[:, None] * rng.random((len(q), 30)), chain[:, 2, 3, None],
                            lo[:, None], hi[:, None]], axis=1)  # fmt: skip
    f = red.residual(chain, theta)
    assert np.isnan(f).any() and np.isfinite(f).any()
    for a, b in red.twins:
        np.testing.assert_array_equal(f[..., a], f[..., b])
        cfg_a = red.solve_rest(chain, theta, np.full(theta.shape, a))
        cfg_b = red.solve_rest(chain, theta, np.full(theta.shape, b))
        both = np.all(np.isfinite(cfg_a), axis=-1) & np.all(np.isfinite(cfg_b), axis=-1)
        assert both.any() and np.all(np.any(cfg_a[both] != cfg_b[both], axis=-1))
    if search.AVAILABLE:
        from sweepik.reductions import kernels

        params = red.kernel_params(chain)
        for i in range(0, len(q), 7):
            for th in theta[i]:
                for a, b in red.twins:
                    fa = kernels.carm_d1_residual(params[i], float(th), a)
                    fb = kernels.carm_d1_residual(params[i], float(th), b)
                    assert fa == fb or (np.isnan(fa) and np.isnan(fb))


def test_carm_d1_hints_kernel_is_bitwise_sample_hints() -> None:
    """carm-d1's compiled hints (with them the engine builds a pose's samples in one pass) are exactly what
    ``sample_hints`` gives: where Px is tiny (snapped to 0 in the kernel parameters, not in the hints), where the
    wrist is out of every rail position's reach (NaN), and on random poses. A subclass that overrides
    ``sample_hints`` is not bypassed by the kernel."""
    from sweepik.reductions import kernels

    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    chain = CARM.fk(_stress(300, seed=12))
    chain[:10, 0, 3] = [0.0, -0.0, 1e-14, -1e-14, 1e-9, 3e-12, -3e-12, 1e-300, 5.0, -5.0]
    chain[10:20, :2, 3] *= 50.0  # out of reach of the outer circle
    params = red.kernel_params(chain)
    assert params[2, 0] == 0.0 and params[2, 17] == 1e-14  # (the snap, and the value as given)
    ref = red.sample_hints(chain)
    assert np.isnan(ref[10:20, :4]).all()
    out = np.empty(kernels.N_D1_HINTS)
    for i in range(len(chain)):
        kernels.carm_d1_hints(params[i], out)
        np.testing.assert_array_equal(out, ref[i])
    assert search._hints_kernel(red) is kernels.carm_d1_hints

    class OwnHints(sweepik.reductions.CArmD1):
        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return super().sample_hints(poses)[:, :5]

    assert search._hints_kernel(OwnHints(CARM)) is None


def test_hints_kernel_of_a_periodic_theta_is_wrapped_as_sample_hints() -> None:
    """A reduction's own hints kernel over a revolute theta* (hints beyond +-pi, NaN, on the grid, repeated): the
    compiled samples are the reference's, the hints wrapped into [-pi, pi] the same way."""
    import numba

    from sweepik import solving
    from sweepik.engine import sweep
    from sweepik.reductions import kernels

    values = np.array([0.3, 4.0, -7.5, np.nan, np.pi, -np.pi, 0.3, 1e3])

    def hints_row(p, out):
        for k in range(values.size):
            out[k] = values[k] + 0.0 * p[0]

    class OwnHints(sweepik.reductions.CArmTheta2):
        kernel = sweepik.reductions.CArmTheta2.kernel
        kernel_hints = numba.njit(kernels.HINTS_SIG)(hints_row)
        n_kernel_hints = values.size

        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return np.broadcast_to(values, (poses.shape[0], values.size)).copy()

    red = OwnHints(CARM)
    assert red.periodic and search._hints_kernel(red) is OwnHints.kernel_hints
    chain = CARM.fk(_stress(50, seed=13))
    lo, hi = solving._theta_range(CARM, red, chain)
    ref = sweep.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
    grid, count = search.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
    np.testing.assert_array_equal(grid, ref)  # (a hints kernel's NaN hint is a spare sample, as in the reference)
    assert (count == ref.shape[1]).all()


@pytest.mark.skipif(not search.AVAILABLE, reason="the compiled engine calls kernels by address")
def test_a_kernel_of_the_wrong_signature_is_refused_and_one_without_is_compiled_for_the_engine() -> None:
    """A reduction's kernel is called through its address: one compiled for another signature (here a float32
    result) would read its arguments wrong and is refused with a clear error; a plain Python function too. A Numba
    function not yet compiled for the engine's signature is compiled for it and used."""
    import numba

    from sweepik.reductions import kernels

    pose = CARM.fk(np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]))

    @numba.njit("float32(float64[::1], float64, int64)")
    def wrong(p, x, b):
        return 0.0

    @numba.njit
    def lazy(p, x, b):
        return kernels._carm_d1(p, x, b)

    class Wrong(sweepik.reductions.CArmD1):
        kernel = (wrong, kernels.carm_d1_configuration)

    class Plain(sweepik.reductions.CArmD1):
        kernel = (lambda p, x, b: 0.0, kernels.carm_d1_configuration)

    class Lazy(sweepik.reductions.CArmD1):
        kernel = (lazy, kernels.carm_d1_configuration)

    for red, match in ((Wrong(CARM), "compiled for"), (Plain(CARM), "must be a Numba function")):
        with pytest.raises(sweepik.UnknownOptionError, match=match):
            sweepik.solve(CARM, pose, reduction=red)
    got, ref = sweepik.solve(CARM, pose, reduction=Lazy(CARM)), sweepik.solve(CARM, pose, reduction="carm-d1")
    np.testing.assert_array_equal(got.q, ref.q)
    assert len(ref) > 0

    class Uncounted(sweepik.reductions.CArmD1):
        kernel = sweepik.reductions.CArmD1.kernel
        kernel_hints = kernels.carm_d1_hints

    with pytest.raises(sweepik.UnknownOptionError, match="n_kernel_hints"):
        sweepik.solve(CARM, pose, reduction=Uncounted(CARM))


def _pair_reductions() -> list[sweepik.reductions.GeometricReduction]:
    """Every pair plan (swept theta*) of the bundled swept arms and of the C-Arm (its four plans: three position
    cases, a prismatic and two revolute theta*)."""
    from sweepik.reductions.decompose import plans

    out = []
    for name in ("carm", "kinova_jaco2", "xarm6", "fanuc_crx10ia", "yaskawa_hc10"):
        robot = load_robot(name)
        for plan in plans(robot):
            if plan.family == "pair":
                out.append(sweepik.reductions.GeometricReduction(robot, plan))
    return out


@pytest.mark.parametrize("red", _pair_reductions(), ids=lambda r: f"{r.robot.name}-{r.name}-{r.plan.case}")
def test_pair_family_all_branch_kernels_are_bitwise_the_one_branch_kernels(
    red: sweepik.reductions.GeometricReduction,
) -> None:
    """The generic pair family's all-branch residual, margin and amplitude kernels (the position case's branches
    share their first steps) give exactly, bit for bit, what the one-branch kernels give, on the branches and steps
    the search asks for (twins and constant steps are skipped: their entries are never read); so does the kernel that
    computes the residuals and margins at once for the engine's uniform samples, where the plan has one
    (``EdgeSearch.every``)."""
    from sweepik import solving

    robot = red.robot
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.lower, robot.upper, size=(60, robot.n_joints))
    q[:10, 4] = 0.0  # a straight wrist
    chain = solving._chain_poses(robot, robot.fk(q))
    params = red.kernel_params(chain)
    lo, hi = solving._theta_range(robot, red, chain)
    ck = red._case_kernels
    branches, margins, amplitudes = red.search_branches, red._steps[0], red._steps[1]
    assert branches and search._kernel_residuals(red) is ck.pair_residuals
    out = np.full(max(3, red.n_branches), np.nan)
    every = red.edge_search().every != 0
    assert every == (red.n_branches == 4 and {b // 2 for b in branches} == {0, 1})  # (both first-step branches)
    shared = np.full(red.n_branches + 3, np.nan)

    def same(a: float, b: float) -> bool:
        return a == b or (np.isnan(a) and np.isnan(b))

    for i in range(len(q)):
        for th in np.concatenate([rng.uniform(lo[i], hi[i], 30), [lo[i], hi[i]]]):
            ck.pair_residuals(params[i], float(th), out)
            for b in branches:
                assert same(out[b], ck.pair_residual(params[i], float(th), b))
            ck.pair_margins(params[i], float(th), out)
            for k in margins:
                assert same(out[k], ck.pair_margin(params[i], float(th), k))
            ck.amplitudes(params[i], float(th), out)
            for k in amplitudes:
                assert same(out[k], ck.amplitude(params[i], float(th), k))
            if every:
                ck.pair_every(params[i], float(th), shared)
                for b in branches:
                    assert same(shared[b], ck.pair_residual(params[i], float(th), b))
                for k in margins:
                    assert same(shared[4 + k], ck.pair_margin(params[i], float(th), k))


def _closed_form_reductions() -> list[sweepik.reductions.GeometricReduction]:
    """Every closed-form plan of the wrist family (spherical wrist) and the parallel family (UR-like) of bundled
    arms and of random arms of those structures (2 || 3 shoulder, Stanford-like RRP, Cartesian PPP; three parallel
    axes with and without a wrist offset, after a revolute joint or an oblique slide; base and tool transforms)."""
    from test_any_arm import FAMILIES, _arm

    from sweepik.reductions.decompose import plans

    robots = [load_robot(n) for n in ("puma560", "puma560_std", "kuka_kr6_r900", "abb_irb140", "stanford")]
    robots += [load_robot(n) for n in ("carm_swapped", "ur5", "ur10")]
    rng = np.random.default_rng(8)
    families = ("wrist_parallel", "wrist_rrp", "wrist_ppp", "three_parallel", "three_parallel_offset")
    robots += [_arm(FAMILIES[f](rng), rng) for f in (*families, "slide_parallel", "slide_parallel_offset")]
    return [
        sweepik.reductions.GeometricReduction(r, p)
        for r in robots
        for p in plans(r)
        if p.family in ("wrist", "parallel")
    ]


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize(
    "red", _closed_form_reductions(), ids=lambda r: f"{r.robot.name}-{r.plan.family}-{r.plan.case}"
)
def test_closed_form_all_branch_configurations_are_bitwise_the_one_branch_ones(
    red: sweepik.reductions.GeometricReduction,
) -> None:
    """A closed form's all-branch configuration kernel (branches share their first steps: position branches, a
    wrist's sp2, the planar arm's elbows) gives bit for bit the one-branch kernel's configurations, NaN rows
    included, also at and next to a singular wrist; the solver's every-branch certification equals the
    branch-by-branch one."""
    from sweepik import solving
    from sweepik.engine import certify
    from sweepik.reductions import geometric
    from sweepik.reductions.kernels import owned_kernel

    robot = red.robot
    every_kernel, one_kernel = owned_kernel(red, "kernel_configurations"), red.kernel[1]
    if red.plan.family == "wrist":
        assert every_kernel is red._case_kernels.wrist_configurations
    else:
        assert every_kernel is geometric.parallel_configurations
    rng = np.random.default_rng(5)
    q = rng.uniform(robot.lower, robot.upper, size=(80, robot.n_joints))
    q[:10, 4] = 0.0  # joint 5 straight: joint 6's axis on joint 4's, a continuum
    q[10:20, 4] = rng.choice([-1.0, 1.0], 10) * 1e-7
    world = robot.fk(q)
    chain = solving._chain_poses(robot, world)
    params = red.kernel_params(chain)
    out = np.full((red.n_branches, robot.n_joints), 7.0)
    one = np.empty(robot.n_joints)
    for i in range(len(q)):
        every_kernel(params[i], 0.0, out)
        for b in range(red.n_branches):
            one_kernel(params[i], 0.0, b, one)
            np.testing.assert_array_equal(out[b], one)
    cand = solving._every_branch(len(q), red.n_branches)
    every = certify.certify_every_branch(robot, red, chain, world, params)
    each = certify.certify(robot, red, chain, world, cand.pose, cand.theta, cand.branch, params)
    for a, b in zip(every, each, strict=True):
        np.testing.assert_array_equal(a, b)

    class OwnKernel(sweepik.reductions.GeometricReduction):
        kernel = (red.kernel[0], red.kernel[1])

    assert owned_kernel(OwnKernel(robot, red.plan), "kernel_configurations") is None


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize(
    ("name", "reduction"), [("carm", "carm-d1"), ("carm", "auto"), ("ur5", "auto"), ("xarm6", None)]
)
def test_compiled_family_steps_are_the_numpy_ones(name: str, reduction: str | None) -> None:
    """The family pieces' compiled steps give the NumPy steps' values bit for bit: the cut location
    (``fastcertify.locate_cuts`` against ``families._locate_cuts``, with and without limits) and
    the golden-section search for limit dips (``fastcertify.dip_search`` against ``families._golden_dips``,
    including members that do not exist, NaN limit excess, and the common stop of all dips)."""
    from sweepik import solving
    from sweepik.engine import certify, families

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, reduction)
    if red.closed_form:  # (its fallback sweep is what has families)
        red = sweepik.reductions.get_reduction(robot, red.fallback)
    rng = np.random.default_rng(6)
    q = rng.uniform(robot.lower, robot.upper, size=(40, robot.n_joints))
    q[:20, 4] = 0.0
    world = robot.fk(q)
    chain = solving._chain_poses(robot, world)
    lo, hi = solving._theta_range(robot, red, chain)
    K = 300
    pose = rng.integers(0, len(q), K).astype(np.intp)
    branch = rng.integers(0, red.n_branches, K).astype(np.intp)
    a = lo[pose] + (hi - lo)[pose] * rng.random(K)
    b = a + (hi - lo)[pose] * rng.uniform(-0.1, 0.1, K)
    tol = solving.ACCEPT_TOL_REL * robot.length_scale
    for limits in (True, False):
        for steps in (12, 32):
            got = certify.locate_cuts(robot, red, chain, world, pose, branch, a, b, steps, limits, tol)
            ref = families._locate_cuts(robot, red, chain, world, pose, branch, a, b, steps, limits, tol)
            np.testing.assert_array_equal(got[0], ref[0])
            np.testing.assert_array_equal(got[1], ref[1])
    best_x = 0.5 * (a + b)
    best_e = np.full(K, 10.0 * robot.length_scale)
    ref = families._golden_dips(robot, red, chain, pose, branch, a, b, best_x, best_e)
    got = certify.dip_search(robot, red, chain, pose, branch, a, b, best_x, best_e, families._DIP_STEPS)
    np.testing.assert_array_equal(got[0], ref[0])
    np.testing.assert_array_equal(got[1], ref[1])


@pytest.mark.skipif(not search.AVAILABLE, reason="the compiled merge (the reference is the NumPy engine's grid)")
def test_compiled_sample_grid_is_the_numpy_one() -> None:
    """``fastsweep.sample_grid`` (compiled merge) gives the reference's samples of each pose alone, bit for bit, with
    no sample for a NaN hint (the reference makes it a spare midpoint, so that its rows have one length): hints
    inside and outside the range, NaN hints, hints on the uniform grid and repeated (runs of equal samples spread),
    real reductions. A pose's samples therefore do not depend on the batch it is solved in."""
    from sweepik import solving
    from sweepik.engine import sweep

    def check(red: sweepik.reductions.Reduction, chain: np.ndarray, lo: np.ndarray, hi: np.ndarray, n: int) -> int:
        grid, count = search.sample_grid(red, chain, lo, hi, n)
        hints = sweep.grid_hints(red, chain)
        assert grid.shape[0] == count.shape[0] == chain.shape[0]
        dropped = 0
        for i in range(chain.shape[0]):
            own = None if hints is None else hints[i : i + 1, np.isfinite(hints[i])]
            ref = sweep.merge_grid(lo[i : i + 1], hi[i : i + 1], n, own)[0]
            assert count[i] == ref.size
            np.testing.assert_array_equal(grid[i, : count[i]], ref)
            assert np.isnan(grid[i, count[i] :]).all()
            dropped += grid.shape[1] - count[i]
        return dropped

    rng = np.random.default_rng(4)
    dropped = 0
    for name, reduction in (("carm", "carm-d1"), ("carm", "carm-theta2"), ("carm", "auto"), ("xarm6", "auto")):
        robot = load_robot(name)
        red = sweepik.reductions.get_reduction(robot, reduction)
        chain = solving._chain_poses(robot, robot.fk(rng.uniform(robot.lower, robot.upper, (200, robot.n_joints))))
        lo, hi = solving._theta_range(robot, red, chain)
        if search._hints_kernel(red) is None:
            dropped += check(red, chain, lo, hi, sweep.N_SAMPLES)
        else:  # (a hints kernel writes as many for every pose: the reference's grid exactly)
            grid, count = search.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
            np.testing.assert_array_equal(grid, sweep.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES))
            assert (count == grid.shape[1]).all()
    assert dropped > 0  # (xArm 6's poses differ in their number of hints)

    class Hinted(sweepik.reductions.CArmD1):
        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return hints

    N, n = 300, 11
    lo = rng.uniform(-900.0, 0.0, N)
    hi = lo + rng.uniform(1.0, 3000.0, N)
    on_grid = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n)[rng.integers(0, n, (N, 8))]
    hints = np.where(rng.random((N, 8)) < 0.5, on_grid, rng.uniform(-2000.0, 4000.0, (N, 8)))
    hints[rng.random((N, 8)) < 0.2] = np.nan
    hints[:, 3] = hints[:, 2]
    assert check(Hinted(CARM), np.broadcast_to(np.eye(4), (N, 4, 4)), lo, hi, n) > 0


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
def test_margins_made_per_call_share_their_pair_plans_engine_plan() -> None:
    """The generic sweeps' margins are a reduction made afresh for each solve: the engine's plan of them (kernels,
    branches, limits) is worked out once per pair plan (``plan_key``), and is the one a fresh plan would be."""
    from sweepik.reductions.generic import _Margins

    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, "auto")
    m1, m2 = _Margins(red, np.zeros((1, 0))), _Margins(red, np.zeros((2, 0)))
    assert search._plan(m1) is search._plan(m2)
    fresh = search._make_plan(m2)
    got = search._plan(m2)
    assert (got.residual, got.residuals, got.n_all, got.hints) == (fresh.residual, fresh.residuals, fresh.n_all, None)
    assert np.array_equal(got.branches, fresh.branches) and np.array_equal(got.ends, fresh.ends)
    other = sweepik.reductions.get_reduction(load_robot("kinova_jaco2"), "auto")
    if not other.closed_form:
        assert search._plan(_Margins(other, np.zeros((1, 0)))) is not search._plan(m1)


def _captured_cuts(monkeypatch: pytest.MonkeyPatch, solve: Any) -> list[tuple[Any, ...]]:
    """The arguments of every cut location a solve asks for (compiled or NumPy)."""
    from sweepik.engine import certify, families

    seen: list[tuple[Any, ...]] = []
    compiled, reference = certify.locate_cuts, families._locate_cuts

    def spy_compiled(*args: Any) -> Any:
        seen.append(args)
        return compiled(*args)

    def spy_reference(*args: Any) -> Any:
        seen.append(args)
        return reference(*args)

    monkeypatch.setattr(certify, "locate_cuts", spy_compiled)
    monkeypatch.setattr(families, "_locate_cuts", spy_reference)
    solve()
    monkeypatch.undo()
    return seen


@pytest.mark.parametrize("name", ["carm", "kuka_iiwa14"])
def test_family_cuts_are_where_bisection_puts_them(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The family pieces' ends (``families._locate_cuts``: false position on the limit excess, bisection elsewhere)
    on real cuts, with and without limits: the end stays a certified member and the point past it is not, the
    bracket is as narrow as asked, and the end is where 60 plain bisections of ``_members_ok`` put it."""
    from sweepik.engine import families

    robot = load_robot(name)
    if name == "carm":
        P = robot.fk(grid_configurations(include_singular=True)[6840:6880])
        kw: dict[str, Any] = {}
    else:  # (A3 locked, the wrist singular: families cut by the limits of the other joints)
        q = np.random.default_rng(0).uniform(robot.lower, robot.upper, size=(12, 7))
        q[:, 2], q[:, 5] = 0.3, 0.0
        P, kw = robot.fk(q), {"locked": {"A3": 0.3}}
    calls = []
    for limits in (True, False):
        calls += _captured_cuts(monkeypatch, lambda lim=limits: sweepik.solve_many(robot, P, limits=lim, **kw))
    assert any(c[9] for c in calls) and sum(c[6].size for c in calls) >= 10
    for arm, red, chain, world, pose, branch, a, b, steps, limits, tol in calls:
        got_a, got_b = families._locate_cuts(arm, red, chain, world, pose, branch, a, b, steps, limits, tol)

        def ok(x: np.ndarray) -> np.ndarray:
            return families._members_ok(arm, red, chain, world, pose, branch, x[:, None], limits, tol)[:, 0]  # noqa: B023

        assert ok(got_a).all() and not ok(got_b).any()
        target = np.ldexp(np.abs(b - a), -steps)
        assert np.all(np.abs(got_b - got_a) <= target * (1 + 1e-9))
        ra, rb = np.array(a), np.array(b)
        for _ in range(60):
            mid = 0.5 * (ra + rb)
            on = ok(mid)
            ra, rb = np.where(on, mid, ra), np.where(on, rb, mid)
        assert np.all(np.abs(got_a - ra) <= 2.0 * target), np.max(np.abs(got_a - ra) / target)


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
def test_search_without_multiplicities_finds_the_same_candidates() -> None:
    """``fastsweep.search(..., multiplicity=False)`` (the margins' search) gives the same candidates and spans, each
    with multiplicity 1; with multiplicities, poses with a double root (theta2 = +-90 deg, theta3 = 0, the paper's
    excluded grid points) and random ones have some above 1 and some of 1, so the comparison sees what it ignores."""
    from sweepik import solving
    from sweepik.engine import sweep

    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    q = _stress(100, seed=5)
    q[:30, 1] = np.pi / 2
    q[:30, 2] = 0.0
    q[:30, 4] = 0.3
    chain = solving._chain_poses(CARM, CARM.fk(q))
    lo, hi = solving._theta_range(CARM, red, chain)
    full, spans = search.search(red, chain, lo, hi, sweep.N_SAMPLES)
    bare, spans2 = search.search(red, chain, lo, hi, sweep.N_SAMPLES, multiplicity=False)
    for a, b in ((full.pose, bare.pose), (full.branch, bare.branch), (full.theta, bare.theta)):
        np.testing.assert_array_equal(a, b)
    assert (bare.mult == 1).all() and (full.mult > 1).any() and (full.mult == 1).any()
    np.testing.assert_array_equal(spans.lo, spans2.lo)


def _same_search(a: Any, b: Any) -> None:
    (ca, sa), (cb, sb) = a, b
    for x, y in zip((ca.pose, ca.branch, ca.theta, ca.mult), (cb.pose, cb.branch, cb.theta, cb.mult), strict=True):
        np.testing.assert_array_equal(x, y)
    for x, y in zip((sa.pose, sa.branch, sa.lo, sa.hi), (sb.pose, sb.branch, sb.lo, sb.hi), strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.skipif(not search.AVAILABLE, reason="numba not installed")
@pytest.mark.parametrize(
    ("name", "reduction"),
    [
        ("fanuc_crx10ia", "auto"),
        ("kinova_jaco2", "auto"),
        ("xarm6", "auto"),
        ("yaskawa_hc10", "auto"),
        ("carm", "auto"),
        ("carm", "carm-d1"),
    ],
)
def test_one_pass_search_is_the_staged_search(name: str, reduction: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The search in one compiled pass per pose finds what the staged search finds (every pose's samples first, by
    ``sample_grid``, then the search: ``one_pass=False``), bit for bit, batched and pose by pose: a generic sweep
    (its swing samples, its margins' zeros, its candidates: ``fastsweep.EdgeSearch``), theta* revolute or prismatic
    (the C-Arm's rail, automatic decomposition), and a reduction with a hints kernel (carm-d1). Random poses, and
    poses on the singular set (joint 5 at 0, joint 3 at 0, both). With the buffers cut to one candidate, every pose
    overflows and is redone by the NumPy engine, in both; cut to the median count (carm-d1), some are: the same
    candidates in the same order, twins' copies included."""
    from sweepik import solving
    from sweepik.engine import sweep

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, reduction)
    assert search._plan(red).one_pass is not None  # (the one-pass search is what is tested)
    rng = np.random.default_rng(11)
    q = rng.uniform(robot.lower, robot.upper, (60, 6))
    q[:10, 4] = 0.0
    q[10:20, 2] = 0.0
    q[20:25, 2] = 0.0
    q[20:25, 4] = 0.0
    chain = solving._chain_poses(robot, robot.fk(q))
    lo, hi = solving._theta_range(robot, red, chain)
    n = sweep.N_SAMPLES
    one_pass = search.search(red, chain, lo, hi, n)
    _same_search(one_pass, search.search(red, chain, lo, hi, n, one_pass=False))
    assert one_pass[0].pose.size >= chain.shape[0]  # (candidates found: the comparison is not of empty sets)
    for i in range(0, 60, 7):
        one = search.search(red, chain[i : i + 1], lo[i : i + 1], hi[i : i + 1], n)
        _same_search(one, search.search(red, chain[i : i + 1], lo[i : i + 1], hi[i : i + 1], n, one_pass=False))
    monkeypatch.setattr(search, "MAX_CAND", 1)
    few = slice(0, 25, 6)
    _same_search(
        search.search(red, chain[few], lo[few], hi[few], n),
        search.search(red, chain[few], lo[few], hi[few], n, one_pass=False),
    )
    if reduction == "auto":
        # (a generic sweep redoes a pose whose margins overflow as a whole, the staged search its margins alone:
        # with buffers cut below the margins' zeros they differ, as they may; MAX_CAND is far above them)
        return
    # some poses redone, the others not: the redone ones (and their twins' copies) in their place
    counts = np.bincount(one_pass[0].pose, minlength=chain.shape[0])
    cut = int(np.median(counts))
    assert (counts > cut).any() and (counts <= cut).any()
    monkeypatch.setattr(search, "MAX_CAND", cut)
    _same_search(search.search(red, chain, lo, hi, n), search.search(red, chain, lo, hi, n, one_pass=False))


def test_residual_rows_is_the_residual_of_those_rows() -> None:
    """``Reduction.residual_rows`` (the NumPy engine's residual of poses picked by index, from parameters kept for
    the poses) gives what ``residual`` gives on the picked poses, value for value: a generic sweep, its margins,
    and a subclass with a residual of its own (which must be the one called)."""
    from sweepik.reductions.generic import GeometricReduction, _Margins

    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, None)
    assert isinstance(red, GeometricReduction)
    rng = np.random.default_rng(3)
    poses = robot.fk(rng.uniform(robot.lower, robot.upper, (12, 6)))
    rows = rng.integers(0, 12, 30)
    theta = rng.uniform(-np.pi, np.pi, (30, 5))
    branch = rng.integers(0, red.n_branches, 30)[:, None]
    margins = _Margins(red, np.zeros((12, 0)), poses)
    for r, b in ((red, branch), (margins, branch % 3)):
        want = r.residual(poses[rows], theta, np.broadcast_to(b, theta.shape))
        got = r.residual_rows(poses, rows, theta, np.broadcast_to(b, theta.shape))
        assert got is not None and want is not None and np.isfinite(want).any()
        np.testing.assert_array_equal(got, want)

    class Shifted(GeometricReduction):
        def residual(self, poses: Any, theta: Any, branch: Any = None) -> Any:
            out = super().residual(poses, theta, branch)
            return None if out is None else out + 1.0

    shifted = Shifted(robot, red.plan)
    got = shifted.residual_rows(poses, rows, theta, np.broadcast_to(branch, theta.shape))
    np.testing.assert_array_equal(got, red.residual(poses[rows], theta, np.broadcast_to(branch, theta.shape)) + 1.0)


@pytest.mark.parametrize("engine", ["compiled", "numpy"])
def test_edge_samples_far_from_zero_are_no_candidates(engine: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A sample next to a branch-domain edge or at the range's ends is a candidate only where its residual is within
    ``FAR_NOISE`` x noise of zero (as an extremum): a root there would make it small. Every candidate the search
    gives is then that close to zero; before, over half the CRX-10iA's candidates were such samples, far from it.
    (Next to a family's samples they stay candidates: the C-Arm's grid poses are unchanged, see docs/performance.md.)
    """
    from sweepik import solving
    from sweepik.engine import sweep

    if engine == "compiled" and not search.AVAILABLE:
        pytest.skip("numba not installed")
    if engine == "numpy":
        monkeypatch.setattr(search, "AVAILABLE", False)
    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, None)
    chain = solving._chain_poses(robot, robot.fk(np.random.default_rng(4).uniform(robot.lower, robot.upper, (30, 6))))
    lo, hi = solving._theta_range(robot, red, chain)
    if engine == "compiled":
        cand, _ = search.search(red, chain, lo, hi, sweep.N_SAMPLES)
    else:
        cand, _ = sweep.find_candidates(red, chain, lo, hi, sweep.N_SAMPLES)
    f = red.residual(chain[cand.pose], cand.theta[:, None], cand.branch[:, None])[:, 0]
    assert cand.theta.size >= 4 * len(chain)  # (the arm's roots: 7.8 solutions a pose on average)
    assert np.all(np.abs(f) <= sweep.FAR_NOISE * red.residual_noise)


@pytest.mark.parametrize("name", ["fanuc_crx10ia", "xarm6"])
def test_edge_intervals_left_alone_hide_no_roots(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """An interval beside a branch-domain edge that sits at a sample is resampled at the first level only where it
    bends in that edge's coordinate (``sweep.EDGE_PROBE_REL``). Those left alone hide no pair of roots: sampled
    densely (in the edge's coordinate, where a pair would sit), the residual changes sign exactly as often as its two
    ends show (once or not at all), and comes no nearer zero than they do unless it crosses. Random poses and poses
    on the singular set (joints at 0 and 90 deg)."""
    from sweepik import solving
    from sweepik.engine import sweep

    monkeypatch.setattr(search, "AVAILABLE", False)
    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, None)
    rng = np.random.default_rng(8)
    q = rng.uniform(robot.lower, robot.upper, (40, 6))
    q[20:30, 4] = 0.0
    q[30:, 2] = np.pi / 2
    chain = solving._chain_poses(robot, robot.fk(q))
    lo, hi = solving._theta_range(robot, red, chain)
    seen: list[tuple[Any, ...]] = []
    judge = sweep._Search._edge_at_sample

    def recorded(self: Any, p: Any, b: Any, th: Any, fin: Any, *rest: Any) -> Any:
        judged, bent = judge(self, p, b, th, fin, *rest)
        i, j = np.nonzero(judged & ~bent)
        seen.append((p[i], b[i], th[i, j], th[i, j + 1], fin[i, j], fin[i, j + 1], rest[2][i, j + 1]))
        return judged, bent

    monkeypatch.setattr(sweep._Search, "_edge_at_sample", recorded)
    sweep.find_candidates(red, chain, lo, hi, sweep.N_SAMPLES)
    p, b, t0, t1, f0, f1, right = (np.concatenate(c) for c in zip(*seen, strict=True))
    assert p.size >= len(chain)  # (most edges' intervals are left alone: the test is not vacuous)
    # dense samples, uniform in sqrt(|theta - edge|)
    edge, other = np.where(right, t1, t0), np.where(right, t0, t1)
    x = np.linspace(0.0, 1.0, 2001)[None, :] ** 2
    dense = edge[:, None] + (other - edge)[:, None] * x
    f = red.residual(chain[p], dense, np.broadcast_to(b[:, None], dense.shape))
    assert np.isfinite(f).all()
    changes = np.count_nonzero(np.sign(f[:, 1:]) * np.sign(f[:, :-1]) < 0, axis=1)
    crosses = f0 * f1 < 0
    np.testing.assert_array_equal(changes, crosses.astype(int))
    ends = np.minimum(np.abs(f0), np.abs(f1))
    assert np.all(crosses | (np.abs(f).min(axis=1) >= 0.5 * ends))


@pytest.mark.parametrize("name", ["xarm6", "kuka_kr6_r900", "kinova_jaco2", "fanuc_crx10ia", "ur5"])
def test_compiled_parameter_rows_are_the_numpy_ones(name: str) -> None:
    """A generic sweep's parameter rows (``geometric.pose_rows``) are those NumPy computes, to rounding (the sums run
    in another order), on arms with a reversed chain (xArm 6), a base and a tool transform (KR6 R900), a base
    (JACO2), a tool (CRX-10iA) or neither (UR5); the probing rows too."""
    from sweepik import solving

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, "auto")
    chain = solving._chain_poses(robot, robot.fk(np.random.default_rng(9).uniform(robot.lower, robot.upper, (40, 6))))
    for probing in (False, True):
        fast, ref = red._params(chain, probing), red._params_numpy(chain, probing)
        assert fast.shape == ref.shape
        np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-14 * max(1.0, robot.length_scale))
