"""Self-motion families (sweepik.engine.families): members that solve the pose, no duplicates between reductions,
the compiled family steps equal to the NumPy ones, and cuts at the limits where bisection puts them."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

import sweepik
from sweepik import load_robot
from sweepik.engine import chunk, settings
from sweepik.experiments.bench import grid_configurations

CARM = load_robot("carm")


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


@pytest.mark.parametrize(
    ("name", "reduction"), [("carm", "carm-d1"), ("carm", "auto"), ("ur5", "auto"), ("xarm6", None)]
)
def test_compiled_family_steps_are_the_numpy_ones(name: str, reduction: str | None) -> None:
    """The family pieces' compiled steps give the NumPy steps' values bit for bit: the cut location
    (``certify.locate_cuts`` against ``families._locate_cuts``, with and without limits) and
    the golden-section search for limit dips (``certify.dip_search`` against ``families._golden_dips``,
    including members that do not exist, NaN limit excess, and the common stop of all dips)."""
    from sweepik.engine import certify, families

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, reduction)
    if red.closed_form:  # (its fallback sweep is what has families)
        red = sweepik.reductions.get_reduction(robot, red.fallback)
    rng = np.random.default_rng(6)
    q = rng.uniform(robot.lower, robot.upper, size=(40, robot.n_joints))
    q[:20, 4] = 0.0
    world = robot.fk(q)
    chain = chunk.chain_poses(robot, world)
    lo, hi = chunk.theta_range(robot, red, chain)
    K = 300
    pose = rng.integers(0, len(q), K).astype(np.intp)
    branch = rng.integers(0, red.n_branches, K).astype(np.intp)
    a = lo[pose] + (hi - lo)[pose] * rng.random(K)
    b = a + (hi - lo)[pose] * rng.uniform(-0.1, 0.1, K)
    tol = settings.ACCEPT_TOL_REL * robot.length_scale
    for limits in (True, False):
        for steps in (12, 32):
            got = certify.locate_cuts(robot, red, chain, world, pose, branch, a, b, steps, limits, tol)
            ref = families._locate_cuts(robot, red, chain, world, pose, branch, a, b, steps, limits, tol)
            np.testing.assert_array_equal(got[0], ref[0])
            np.testing.assert_array_equal(got[1], ref[1])
    best_x = 0.5 * (a + b)
    best_e = np.full(K, 10.0 * robot.length_scale)
    ref = families._golden_dips(robot, red, chain, pose, branch, a, b, best_x, best_e)
    got = certify.dip_search(robot, red, chain, pose, branch, a, b, best_x, best_e, settings.DIP_STEPS)
    np.testing.assert_array_equal(got[0], ref[0])
    np.testing.assert_array_equal(got[1], ref[1])


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


def test_members_of_many_families_at_once_are_each_familys() -> None:
    """``families.certified_members_of`` (the families of one reduction in one call: the crossing search's grids)
    gives each family's members as ``certified_members`` does, bit for bit, nudges included: C-Arm families at
    theta2 = 90 deg (whose members where the wrist crosses joint 2's axis are nudged off the blind point)."""
    from sweepik.engine.families import certified_members, certified_members_of

    rng = np.random.default_rng(8)
    q = np.tile(np.array([1000.0, np.pi / 2, 0.3, -0.5, 0.0, 0.2]), (6, 1))
    q[:, 0] += rng.uniform(-300.0, 300.0, 6)
    q[:, 2:4] += rng.uniform(-0.3, 0.3, (6, 2))
    fams = [f for s in sweepik.solve_many(CARM, CARM.fk(q)) for f in s.families]
    assert len(fams) >= 6 and len({id(f.reduction) for f in fams}) == 1
    theta = np.array([np.linspace(*f.interval, 33) for f in fams])
    theta[:, 16] = [f.chain_pose[2, 3] for f in fams]  # (d1 = Pz: the wrist on joint 2's axis, if inside)
    theta = np.clip(theta, *np.array([f.interval for f in fams]).T[:, :, None])
    lo, hi = np.array([f.interval for f in fams]).T
    many = certified_members_of(
        fams[0].reduction, np.array([f.chain_pose for f in fams]), np.array([f.branch for f in fams]), theta, lo, hi
    )
    for f, th, m in zip(fams, theta, many, strict=True):
        np.testing.assert_array_equal(m, certified_members(f.reduction, f.chain_pose, f.branch, th, *f.interval))


@pytest.mark.parametrize(
    ("name", "q", "locked"),
    [
        ("stanford", [0.3, -0.5, 0.8, np.radians(170), 0.0, np.radians(170)], None),
        ("kuka_iiwa14", [0.5, -0.7, 0.3, -1.5, np.radians(170), 0.0, np.radians(175)], {"A1": 0.5}),
        ("kuka_iiwa14", [0.5, -0.7, 0.3, -1.5, np.radians(170), 0.0, np.radians(175)], {"A3": 0.3}),
        ("carm", [300.0, np.pi / 2, np.radians(116), np.radians(66), np.pi, 0.3], None),
    ],
)
def test_a_family_touching_a_corner_of_the_limits_keeps_that_point(name: str, q: list[float], locked: Any) -> None:
    """A configuration on a self-motion with two joints at their limits at once (the wrist's two joints on its
    singular circle; the C-Arm's joints 3 and 4): inside the limits the family is a stretch plus that one point,
    where one joint leaves its limits as the other comes back in. The point was dropped (the worst joint's excess, a
    V touching zero there, is no local minimum among the samples next to an inside stretch); now the crossing is
    located between the two samples outside (``families._limit_corners``) and the point is an isolated solution.
    Found by a property-testing helper."""
    from oracles import recovers

    robot = load_robot(name)
    qq = np.array(q)
    assert robot.within_limits(qq)
    T = robot.fk(qq)
    for sols in (sweepik.solve(robot, T, locked=locked), sweepik.solve_many(robot, T[None], locked=locked)[0]):
        assert recovers(robot, sols, qq)
        assert robot.within_limits(sols.q).all()


def test_a_family_in_a_narrow_window_a_turn_from_zero_is_kept() -> None:
    """UR5 with its wrist straight (joint 5 at pi: a continuum) and joint 4 limited to a window 0.1 rad wide one turn
    from zero: the family was dropped whole (its members' limit excess, measured from the value ``wrap`` gives,
    jumped by a turn outside the window, and no cut was found); the same window without the turn kept it. Now the
    excess is measured from the middle of the limits (``Robot.limit_excess``). Found by a property-testing helper."""
    import dataclasses

    from oracles import recovers

    base = load_robot("ur5")
    for turn in (0.0, 2.0 * np.pi, -2.0 * np.pi):
        joints = list(base.joints)
        joints[3] = dataclasses.replace(joints[3], lower=0.45 + turn, upper=0.55 + turn)
        arm = dataclasses.replace(base, joints=tuple(joints))
        q = np.array([0.3, -1.0, 1.2, 0.5 + turn, np.pi, 0.2])
        sols = sweepik.solve(arm, arm.fk(q))
        assert sols.families and recovers(arm, sols, q), turn


def test_nearest_with_windings_takes_the_family_members_winding() -> None:
    """``windings=True`` compares rows as they are, not modulo 2 pi: a family member must be turned to its winding
    nearest the reference too (it was compared modulo 2 pi and returned a turn away). Found by a property-testing
    helper: PUMA 560 with its wrist straight, joint 6 at -226 deg (limits +-266)."""
    robot = load_robot("puma560")
    q = np.array([2.457662365440189, 0.04128659553241709, 3.9269908169872414, 0.19905312751236304, 0.0, -3.94246786])
    sols = sweepik.solve(robot, robot.fk(q), windings=True)
    assert sols.families
    np.testing.assert_allclose(sols.nearest(q), q, atol=1e-9)
