"""The generic families' kernels (sweepik.reductions.geometric, generic): the all-branch residuals and
configurations bit for bit the one-branch ones, and the compiled parameter rows equal to the NumPy ones."""

from __future__ import annotations

import numpy as np
import pytest

import sweepik
from sweepik import load_robot
from sweepik.engine import chunk, search
from sweepik.reductions import geometric


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

    robot = red.robot
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.lower, robot.upper, size=(60, robot.n_joints))
    q[:10, 4] = 0.0  # a straight wrist
    chain = chunk.chain_poses(robot, robot.fk(q))
    params = red.kernel_params(chain)
    lo, hi = chunk.theta_range(robot, red, chain)
    ck = red._case_kernels
    branches, margins, amplitudes = red.search_branches, red._steps[0], red._steps[1]
    assert branches and search._kernel_residuals(red) is ck.pair_residuals
    out = np.full(max(geometric.SWING_STEPS, red.n_branches), np.nan)
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
    chain = chunk.chain_poses(robot, world)
    params = red.kernel_params(chain)
    out = np.full((red.n_branches, robot.n_joints), 7.0)
    one = np.empty(robot.n_joints)
    for i in range(len(q)):
        every_kernel(params[i], 0.0, out)
        for b in range(red.n_branches):
            one_kernel(params[i], 0.0, b, one)
            np.testing.assert_array_equal(out[b], one)
    cand = chunk.every_branch(len(q), red.n_branches)
    every = certify.certify_every_branch(robot, red, chain, world, params)
    each = certify.certify(robot, red, chain, world, cand.pose, cand.theta, cand.branch, params)
    for a, b in zip(every, each, strict=True):
        np.testing.assert_array_equal(a, b)

    class OwnKernel(sweepik.reductions.GeometricReduction):
        kernel = (red.kernel[0], red.kernel[1])

    assert owned_kernel(OwnKernel(robot, red.plan), "kernel_configurations") is None


@pytest.mark.parametrize("name", ["xarm6", "kuka_kr6_r900", "kinova_jaco2", "fanuc_crx10ia", "ur5"])
def test_compiled_parameter_rows_are_the_numpy_ones(name: str) -> None:
    """A generic sweep's parameter rows (``geometric.pose_rows``) are those NumPy computes, to rounding (the sums run
    in another order), on arms with a reversed chain (xArm 6), a base and a tool transform (KR6 R900), a base
    (JACO2), a tool (CRX-10iA) or neither (UR5); the probing rows too."""

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, "auto")
    chain = chunk.chain_poses(robot, robot.fk(np.random.default_rng(9).uniform(robot.lower, robot.upper, (40, 6))))
    for probing in (False, True):
        fast, ref = red._params(chain, probing), red._params_numpy(chain, probing)
        assert fast.shape == ref.shape
        np.testing.assert_allclose(fast, ref, rtol=0, atol=1e-14 * max(1.0, robot.length_scale))
