"""Multiple roots, multiplicity, families vs. high-order roots, numerical continua, limits, refused geometry."""

from __future__ import annotations

import copy
import tomllib
from importlib import resources

import numpy as np
import pytest
from oracles import numpy_engine
from oracles.numpy_engine import numpy_reduction

import sweepik
from sweepik import RobotDefinitionError, load_robot, solve, solve_many
from sweepik.engine.families import MAX_ISOLATED_SOLUTIONS
from sweepik.io.robot_file import robot_from_dict
from sweepik.model.pose import pose_error_geodesic
from sweepik.reductions import get_reduction
from sweepik.results import joint_distance

CARM = load_robot("carm")
REDUCTIONS = ["carm-d1", "carm-theta2"]
#: acceptance of a solution (position + 100 mm x angle), as the solver's
ACCEPT = 2e-13 * CARM.length_scale


def _deg(*q: float) -> np.ndarray:
    return np.array([q[0], *np.radians(q[1:])])


def _index_of(sol: sweepik.Solutions, q: np.ndarray, tol: float = 1e-4) -> int | None:
    if len(sol) == 0:
        return None
    d = joint_distance(CARM, sol.q, q).max(axis=-1)
    return int(np.argmin(d)) if d.min() <= tol else None


def _certified(sol: sweepik.Solutions, T: np.ndarray) -> bool:
    if len(sol) == 0:
        return True
    return bool(np.all(pose_error_geodesic(CARM.fk(sol.q), T, 100.0) <= ACCEPT))


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_issue_example_double_root_found_by_both_reductions(reduction: str) -> None:
    # theta2 = 0 with theta3 + theta4 = 90 deg: link L2 along joint 2's axis, a double root next to a simple one
    q = _deg(300, 0, 45, 45, 2, 0)
    sol = solve(CARM, CARM.fk(q), reduction=reduction)
    i = _index_of(sol, q)
    assert i is not None
    assert sol.multiplicity[i] == 2
    assert _certified(sol, CARM.fk(q))


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_triple_root_is_one_solution_not_a_family(reduction: str) -> None:
    # theta2 = 0, theta5 = 0, theta3 + theta4 = -90 deg: the pose error grows as delta^3 off the solution
    q = _deg(500, 0, -60, -30, 0, -60)
    sol = solve(CARM, CARM.fk(q), reduction=reduction)
    assert sol.families == ()
    i = _index_of(sol, q)
    assert i is not None
    assert sol.multiplicity[i] == 3
    # one solution there, not a cluster of near-copies
    assert np.sum(joint_distance(CARM, sol.q, q).max(axis=-1) <= 1e-2) == 1


def test_generic_solutions_are_simple(rng: np.random.Generator) -> None:
    q = rng.uniform(CARM.lower, CARM.upper, (200, 6))
    for sol, qq in zip(solve_many(CARM, CARM.fk(q)), q, strict=True):
        i = _index_of(sol, qq, 1e-6)
        assert i is not None
        assert sol.multiplicity[i] == 1
        assert sol.multiplicity.dtype.kind == "i" and sol.multiplicity.shape == (len(sol),)


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_double_root_theta2_90_theta3_0(reduction: str, rng: np.random.Generator) -> None:
    # the paper's 600 excluded grid points: theta2 = +-90 deg with theta3 = 0
    q = rng.uniform(CARM.lower, CARM.upper, (60, 6))
    q[:, 1] = rng.choice([-1.0, 1.0], 60) * np.pi / 2
    q[:, 2] = 0.0
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.05, 0.3, q[:, 4])  # theta5 = 0 would be a self-motion
    for sol, qq in zip(solve_many(CARM, CARM.fk(q), reduction=reduction), q, strict=True):
        i = _index_of(sol, qq)
        assert i is not None
        assert sol.multiplicity[i] >= 2


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_triple_root_at_the_rail_end_is_kept_within_limits(reduction: str) -> None:
    # the root is pinned down to its flat stretch (~0.02 mm); its middle may fall just outside the rail.
    # carm-d1 clips it to the rail end; through theta2 the rail is not theta* (a documented limitation)
    q = np.array([0.0, 0.0, -np.pi / 12, -5 * np.pi / 12, -np.pi, np.pi / 3])
    T = CARM.fk(q)
    sol = solve(CARM, T, reduction=reduction)
    if reduction == "carm-d1":
        assert _index_of(sol, q) is not None
    free = solve(CARM, T, reduction=reduction, limits=False)
    assert _index_of(free, q, 1e-3) is not None
    assert len(sol) == int(np.sum(free.within_limits))


def _same_sets(a: np.ndarray, b: np.ndarray) -> bool:
    if a.shape != b.shape:
        return False
    if a.size == 0:
        return True
    d = joint_distance(CARM, a[:, None, :], b[None, :, :]).max(axis=-1)
    return bool(d.min(axis=1).max() <= 1e-6 and d.min(axis=0).max() <= 1e-6)


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_limits_true_is_limits_false_filtered(reduction: str, rng: np.random.Generator) -> None:
    n = 300
    q = rng.uniform(CARM.lower - 0.2 * (CARM.upper - CARM.lower), CARM.upper, (n, 6))
    k = n // 3
    q[:k, 1], q[:k, 3] = 0.0, rng.choice([-1.0, 1.0], k) * np.pi / 2 - q[:k, 2]  # theta2 = 0, theta3+4 = +-90
    q[k : 2 * k, 0] = rng.choice([0.0, 2000.0], k)  # rail ends
    q[k : k + k // 2, 4] = 0.0
    T = CARM.fk(q)
    with_limits = solve_many(CARM, T, reduction=reduction)
    without = solve_many(CARM, T, reduction=reduction, limits=False)
    for a, b in zip(with_limits, without, strict=True):
        assert _same_sets(a.q, b.q[b.within_limits])
        assert len(a.families) <= len(b.families)


@pytest.mark.parametrize("scale", [1e-7, 1e-6, 1e-5])
def test_near_continuum_is_not_hundreds_of_copies(scale: float, rng: np.random.Generator) -> None:
    # within ~1e-4 rad of the wrist on joint 2's axis at full stretch, joints 2 and 5 are almost coaxial: a
    # whole arc of configurations reproduces the pose to rounding level
    q = rng.uniform(CARM.lower, CARM.upper, (60, 6))
    q[:, 2] = rng.normal(0.0, scale, 60)
    q[:, 3] = -np.pi / 2 + rng.normal(0.0, scale, 60)
    T = CARM.fk(q)
    for sol, TT in zip(solve_many(CARM, T), T, strict=True):
        assert len(sol) <= 2 * MAX_ISOLATED_SOLUTIONS
        assert _certified(sol, TT)


@pytest.mark.parametrize("reduction", REDUCTIONS)
def test_kernel_and_numpy_reduction_agree_on_the_singular_set(reduction: str, rng: np.random.Generator) -> None:
    """The reduction with its compiled kernels and without them (its NumPy residual called back from the search, its
    configurations in NumPy: ``numpy_engine.numpy_reduction``) give the same solutions, multiplicities and families
    on the C-Arm's singular set."""
    q = rng.uniform(CARM.lower, CARM.upper, (150, 6))
    q[:, 1] = 0.0
    q[:, 3] = rng.choice([-1.0, 1.0], 150) * np.pi / 2 - q[:, 2]
    q[:50, 4] = 0.0
    q = q[CARM.within_limits(q)]
    T = CARM.fk(q)
    fast = solve_many(CARM, T, reduction=reduction)
    ref = solve_many(CARM, T, reduction=numpy_reduction(get_reduction(CARM, reduction)))
    for a, b, qq in zip(fast, ref, q, strict=True):
        assert _index_of(a, qq) is not None and _index_of(b, qq) is not None
        assert len(a) == len(b) and len(a.families) == len(b.families)
        np.testing.assert_array_equal(np.sort(a.multiplicity), np.sort(b.multiplicity))


def _carm_variant(joint: int, field: str, value: object) -> dict:
    data = tomllib.loads((resources.files("sweepik.io") / "robots" / "carm.toml").read_text())
    data = copy.deepcopy(data)
    data["joints"][joint][field] = value
    return data


@pytest.mark.parametrize(
    ("joint", "field", "value"), [(3, "a", -350.0), (4, "d", -402.0), (4, "d", 0.0), (3, "a", 0.0)]
)
def test_reduction_refuses_lengths_it_cannot_solve(joint: int, field: str, value: float) -> None:
    robot = robot_from_dict(_carm_variant(joint, field, value), "variant.toml")
    with pytest.raises(RobotDefinitionError, match="L1 .* > 0"):
        solve(robot, robot.fk(np.array([500.0, 0.3, 0.2, -0.4, 0.5, 0.1])))


@pytest.mark.parametrize("reduction", ["carm-d1", "carm-theta2"])
def test_equal_links_with_the_wrist_on_the_elbow_axis_solve_as_the_automatic_decomposition(reduction: str) -> None:
    """L1 = L2 (another C-Arm): with Px = Py = 0 the samples reach the wrist on joint 3's axis (rho = 0), where the
    closed-form elbow divides 0 by 0. The kernels give NaN there, as the NumPy reference does (no exception, no
    spurious root), and the solutions are those of the automatic decomposition, each reproducing the pose."""
    data = _carm_variant(3, "a", 400.0)
    data["joints"][4]["d"] = 400.0
    robot = robot_from_dict(data, "equal.toml")
    T0 = robot.fk(np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]))
    for z in (900.0, 1200.0, 400.0):
        T = T0.copy()
        T[:3, 3] = [0.0, 0.0, z]
        got, ref = solve(robot, T, reduction=reduction, limits=False), solve(robot, T, reduction="auto", limits=False)
        assert len(got) == len(ref) > 0
        for q in ref.q:
            assert joint_distance(robot, got.q, q).max(axis=-1).min() <= 1e-6
        assert np.all(pose_error_geodesic(robot.fk(got.q), T, 100.0) <= 2e-13 * robot.length_scale)


def test_huge_rail_limits_solve_every_pose(rng: np.random.Generator) -> None:
    robot = robot_from_dict(_carm_variant(0, "limits", [-1e300, 1e300]), "rail.toml")
    assert robot.length_scale < 1e5  # tolerances do not grow with the rail
    q = rng.uniform(CARM.lower, CARM.upper, (300, 6))
    q[:, 0] = rng.uniform(-5000.0, 5000.0, 300)
    T = robot.fk(q)
    for sol, qq, TT in zip(solve_many(robot, T), q, T, strict=True):
        assert len(sol) and joint_distance(robot, sol.q, qq).max(axis=-1).min() <= 1e-6
        assert np.all(pose_error_geodesic(robot.fk(sol.q), TT, 100.0) <= 2e-13 * robot.length_scale)


@pytest.mark.parametrize("name", ["ur3", "ur5", "ur10"])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_closed_form_reports_a_double_root_as_the_sweeps_do(name: str, seed: int) -> None:
    """Elbow straight (joint 3 at 0 on a UR arm: the Jacobian loses rank): the closed form's two elbow branches
    meet. Its solutions are those of a sweep of joint 2 (another decomposition), each with the sweep's
    multiplicity (2 at the merged elbow), not 1."""
    robot = load_robot(name)
    q = np.random.default_rng(seed).uniform(-2.5, 2.5, 6)
    q[2] = 0.0
    T = robot.fk(q)
    closed, swept = solve(robot, T, limits=False), solve(robot, T, limits=False, free_joint=1)
    assert sweepik.analyze(robot)["chosen"]["closed_form"] and len(closed) == len(swept) > 0
    for qs, m in zip(swept.q, swept.multiplicity, strict=True):
        k = _index_of(closed, qs)
        assert k is not None and closed.multiplicity[k] == m
    assert closed.multiplicity[_index_of(closed, q)] == 2


@pytest.mark.parametrize("family", ["three_parallel", "three_parallel_offset", "slide_parallel"])
def test_closed_form_elbow_double_root_is_one_solution_at_the_root(family: str) -> None:
    """An elbow stretched straight (joint 3 at 0) on closed-form arms of random dimensions: the elbow's two branches
    meet there, a double root. The closed form's cosine lands at 1 only up to rounding magnified by the arm's
    lengths (up to ~1e-12: two certified roots ~1e-6 rad either side); they are reported as one solution of
    multiplicity 2 at the root: IK(FK(q)) holds q to 1e-6."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_any_arm import FAMILIES, _arm

    for seed in range(10):
        rng = np.random.default_rng(seed + 100)
        robot = _arm(FAMILIES[family](rng), rng, "standard")
        q = rng.uniform(robot.lower, robot.upper, (8, 6))
        q[:, 2] = 0.0
        for qq, sols in zip(q, [solve(robot, T) for T in robot.fk(q)], strict=True):
            d = joint_distance(robot, sols.q, qq) / np.where(robot.is_revolute, 1.0, robot.length_scale)
            k = int(np.argmin(d.max(axis=-1)))
            assert d[k].max() < 1e-6, (family, seed, qq.tolist(), d[k].max())
            assert sols.multiplicity[k] >= 2


def test_near_pairs_compiled_is_the_reference(rng: np.random.Generator) -> None:
    """``dedupe.near_pairs`` (compiled) finds the pairs its NumPy reference finds: rows of one pose within a reach
    per joint, revolute ones modulo 2 pi (pairs straddling +-pi included), dropped rows left out."""
    from sweepik.engine import dedupe

    robot = load_robot("stanford")  # (a slide among the joints)
    K = 400
    pose = rng.integers(0, 60, K)
    w = rng.uniform(-np.pi, np.pi, (K, 6))
    near = rng.choice(K, 80, replace=False)
    for a in near:  # a partner close to row a, of the same pose, some across +-pi
        w = np.vstack([w, w[a] + rng.normal(scale=3e-5, size=6)])
        pose = np.append(pose, pose[a])
    w[K::3, 0] = np.where(w[K::3, 0] > 0, w[K::3, 0] - 2 * np.pi, w[K::3, 0] + 2 * np.pi)
    keep = rng.random(w.shape[0]) > 0.1
    reach = np.full(6, 1e-4)
    got = dedupe.near_pairs(robot, pose, w, keep, reach)
    want = numpy_engine.near_pairs(robot, pose, w, keep, reach)
    assert want.shape[0] > 40
    np.testing.assert_array_equal(got, want)


@pytest.mark.parametrize("name", ["ur3", "ur5", "ur10"])
@pytest.mark.parametrize("a5", [3e-5, -6e-5, 2e-4])
def test_shoulder_double_root_with_the_wrist_nearly_straight(name: str, a5: float) -> None:
    """A UR arm at its shoulder singularity (det J = 0 along joint 2) with A5 3e-5 ... 2e-4 from 0 (issue 35, the UR16e
    of ssik's catalogue): joint 1's two roots meet, the closed form splits them by the rounding of joint 1 (~1e-8),
    which the wrist magnifies by 1 / sin A5 into two certified solutions up to ~3e-4 either side of the root. They are
    one solution at the root (IK(FK(q)) holds q to 1e-6, multiplicity 2), not two 1e-4 off it."""
    from scipy.optimize import brentq

    robot = load_robot(name)
    rng = np.random.default_rng(int(1e6 * abs(a5)) + len(name))
    found = 0
    while found < 3:
        q = rng.uniform(-2.5, 2.5, 6)
        q[4] = a5
        xs = np.linspace(-np.pi, np.pi, 361)
        Q = np.repeat(q[None], xs.size, axis=0)
        Q[:, 1] = xs
        det = np.linalg.det(robot.jacobian(Q))
        idx = np.flatnonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0)
        if idx.size == 0:
            continue

        def f(x: float, q: np.ndarray = q) -> float:
            qq = q.copy()
            qq[1] = x
            return float(np.linalg.det(robot.jacobian(qq)))

        q[1] = brentq(f, xs[idx[0]], xs[idx[0] + 1], xtol=1e-15)
        found += 1
        sols = solve(robot, robot.fk(q), limits=False)
        d = joint_distance(robot, sols.q, q).max(axis=-1)
        k = int(np.argmin(d))
        assert d[k] < 1e-6, (name, q.tolist(), d[k])
        assert sols.multiplicity[k] >= 2


def test_two_roots_next_to_the_elbow_fold_stay_two() -> None:
    """PUMA 560 with its elbow 1e-7 rad short of straight: two distinct roots 3e-4 apart, each solving the pose to
    rounding. Their polished midpoint misses it by 6e-15 of the arm's size (well within the certification, 60 times
    more than they do): merging them as one split double root lost the configuration (``settings.MEET_NEAR``)."""
    from singular import recovered

    robot = load_robot("puma560")
    q = np.array([2.0175502070911824, 3.0274166388510366, 1.6177743431429834, -0.4768530155683983, 3.013973045327825,
                  2.9781318484005785])  # fmt: skip
    sols = solve(robot, robot.fk(q), limits=False)
    assert recovered(robot, sols, q)
    assert np.all(sols.multiplicity == 1)


@pytest.mark.parametrize("name", ["piper_ik", "m1013_ik"])
def test_a_sweep_gives_no_root_twice_on_a_vendor_arms_singular_set(name: str) -> None:
    """ssik's AgileX Piper and Doosan M1013 (swept; the M1013 with a companion plan) on the 50 configurations on and
    next to their singular sets that ``scripts/ssik_catalogue.py --singular 50`` draws: next to a fold a double root is
    a flat valley solving the pose to rounding, which the sweep reached from several samples and branches, each polish
    stopping elsewhere in it (a Piper pose gave five points 1e-6 ... 1e-5 apart, each of multiplicity 2; 19 and 20
    such copies on the 250 poses before ``settle.meetings`` took sweeps). No two solutions of a pose are one root
    (``singular.one_root``: their midpoint, or an arc between them, solves the pose as well as they do), and every
    configuration comes back."""
    pytest.importorskip("ssik")
    from catalogue import catalogue_configurations
    from singular import one_root, recovered

    robot, Q = catalogue_configurations(name)
    twice = []
    for k, q in enumerate(Q[200:]):
        s = solve(robot, robot.fk(q), limits=False)
        assert recovered(robot, s, q), (name, k)
        if s.families:
            continue
        twice += [(k, a, b) for a in range(len(s)) for b in range(a + 1, len(s)) if one_root(robot, s.q[a], s.q[b])]
    assert not twice
