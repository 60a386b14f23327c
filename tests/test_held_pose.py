"""A seven-joint arm with one joint held, its lock value an argument of one compiled call (``engine.held_pose``).

Properties: where the plan is the same at every value, the one call's solutions are those of the held arm built at
that value and solved the general way (same count, same configurations to rounding), on the bundled arms and on
them rewritten at random (axis signs, zeros, frames, units); the configuration a pose was made from is recovered,
at random values and where axes line up (0, +-pi/2, the limits) and with the wrist straight; ``solve_many`` with a
value per pose gives ``solve``'s answers bit for bit; an arm whose plan is not one closed form at every value is not
taken; what the one call does not settle goes the general way.
"""

from __future__ import annotations

import numpy as np
import pytest
from one_call import fk_ok, held_general, same_to_rounding
from oracles import in_limit_configurations, recovers
from rewrites import rewrite

import sweepik
from sweepik import LockedJointError, load_robot, solving
from sweepik.engine import held_pose
from sweepik.engine.held_pose import HeldPose
from sweepik.engine.lock_windows import in_windows
from sweepik.engine.one_pose import OK
from sweepik.reductions import first_held_reduction

#: (arm, joint) of the bundled seven-joint arms whose held arm is one closed form at every value.
TAKEN = [
    ("kuka_iiwa14", "A1"),
    ("kuka_iiwa14", "A2"),
    ("kuka_iiwa14", "A3"),
    ("kuka_iiwa14", "A5"),
    ("kuka_iiwa14", "A6"),
    ("kuka_iiwa14", "A7"),
    ("franka_panda", "joint5"),
    ("franka_panda", "joint6"),  # (axes 5 and 7 meet at a point that slides along axis 5 with the value)
    ("franka_panda", "joint7"),
]
#: ... and whose held arm is one sweep at every value.
SWEPT = [("franka_panda", "joint1"), ("franka_panda", "joint3"), ("kinova_gen3", "joint_5"), ("kinova_gen3", "joint_7")]


@pytest.mark.parametrize(("name", "joint"), TAKEN + SWEPT)
def test_the_one_call_is_the_held_arm_at_each_value(name: str, joint: str) -> None:
    """Random values and poses: the one call answers (most poses) with the held arm's own solutions."""
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    fast = solving._held_pose(robot, k)
    assert isinstance(fast, HeldPose)
    q = in_limit_configurations(robot, 12, np.random.default_rng(k))
    answered = 0
    for qq, T in zip(q, robot.fk(q), strict=True):
        status, sol = fast.solve(np.ascontiguousarray(T), float(qq[k]), True)
        if sol is None:
            continue
        answered += 1
        same_to_rounding(sol, held_general(robot, T, k, float(qq[k])), robot)
        fk_ok(robot, sol, T)
        assert np.all(sol.q[:, k] == qq[k]) and recovers(robot, sol, qq)
    assert answered >= 10


@pytest.mark.parametrize(
    ("name", "joint"),
    [("kuka_iiwa14", "A3"), ("franka_panda", "joint7"), ("kuka_iiwa14", "A6"), ("franka_panda", "joint6")],
)
@pytest.mark.parametrize("seed", [1, 2])
def test_arms_written_otherwise(name: str, joint: str, seed: int) -> None:
    """Rewritten at random (axis signs, zeros, base and tool frames, units): the one call is taken and gives the held
    arm's solutions, mapped back they hold the original configuration."""
    rng = np.random.default_rng(seed)
    original = load_robot(name)
    rw = rewrite(original, rng)
    robot = rw.robot
    k = original.joint_names.index(joint)
    assert solving._held_pose(robot, k) is not None
    q0 = in_limit_configurations(original, 8, rng)
    q0 = q0[np.all((rw.forward(q0) >= robot.lower) & (rw.forward(q0) <= robot.upper), axis=1)]
    for qq in q0:
        q2 = rw.forward(qq)
        T = robot.fk(q2)
        sol = sweepik.solve(robot, T, locked={joint: float(q2[k])})
        same_to_rounding(sol, held_general(robot, T, k, float(q2[k])), robot)
        fk_ok(robot, sol, T)
        assert recovers(robot, sol, q2)


@pytest.mark.parametrize(
    ("name", "joint"),
    [("kuka_iiwa14", "A3"), ("franka_panda", "joint7"), ("kuka_iiwa14", "A1"), ("franka_panda", "joint6")],
)
def test_values_where_axes_line_up_and_singular_wrists(name: str, joint: str) -> None:
    """The held joint at 0, +-pi/2 and its limits (where the held arm has more structure than at other values), the
    wrist straight or the elbow at 0: every solution reaches the pose and the generating configuration is found."""
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    rng = np.random.default_rng(7)
    values = [0.0, np.pi / 2, -np.pi / 2, robot.lower[k], robot.upper[k]]
    for v in values:
        if not robot.lower[k] <= v <= robot.upper[k]:
            continue
        q = in_limit_configurations(robot, 6, rng)
        q[:, k] = v
        for rows, j in ((slice(0, 2), 5), (slice(2, 4), 3)):  # (not the held joint itself)
            if j != k and robot.lower[j] <= 0.0 <= robot.upper[j]:
                q[rows, j] = 0.0
        for qq, T in zip(q, robot.fk(q), strict=True):
            sol = sweepik.solve(robot, T, locked={joint: float(v)})
            fk_ok(robot, sol, T)
            assert np.all(sol.q[:, k] == v) and recovers(robot, sol, qq)


@pytest.mark.parametrize(("name", "joint"), [("kuka_iiwa14", "A3"), ("franka_panda", "joint5")])
def test_solve_many_with_a_value_per_pose_is_solve(name: str, joint: str) -> None:
    """A value per pose, with singular poses among them (the general way): each pose's solutions are ``solve``'s,
    bit for bit; a grid of values on one pose too."""
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    q = in_limit_configurations(robot, 16, np.random.default_rng(11))
    q[3, 5] = q[9, 5] = 0.0  # (wrists straight: the one call hands them on)
    T = robot.fk(q)
    batch = sweepik.solve_many(robot, T, locked={joint: q[:, k]})
    for i in range(len(q)):
        one = sweepik.solve(robot, T[i], locked={joint: float(q[i, k])})
        got = batch[i]
        assert len(got) == len(one) and len(got.families) == len(one.families)
        np.testing.assert_array_equal(got.q, one.q)
        np.testing.assert_array_equal(got.error, one.error)
        assert recovers(robot, got, q[i])
    seen: list[int] = []
    streamed = sweepik.iter_solve(
        robot, T, locked={joint: q[:, k]}, chunk_size=5, progress=lambda _, d, n: seen.append(d)
    )
    for got, one in zip(streamed, batch, strict=True):
        np.testing.assert_array_equal(got.q, one.q)
    assert seen[0] == 0 and seen[-1] == 16 and seen == sorted(seen) and max(np.diff(seen)) <= 5
    grid = np.linspace(robot.lower[k], robot.upper[k], 9)[1:-1]
    for v, sols in zip(grid, sweepik.solve_many(robot, T[0], locked={joint: grid}), strict=True):
        np.testing.assert_array_equal(sols.q, sweepik.solve(robot, T[0], locked={joint: float(v)}).q)


def test_the_one_call_hands_on_what_it_does_not_settle() -> None:
    """A straight wrist (a continuum of the held arm) is not settled by the one call; ``solve`` answers it the general
    way, with the family that holds the pose."""
    robot = load_robot("kuka_iiwa14")
    q = np.array([0.4, 0.7, 0.3, -1.1, 0.2, 0.0, 0.5])
    T = robot.fk(q)
    status, sol = solving._held_pose(robot, 2).solve(np.ascontiguousarray(T), 0.3, True)
    assert status != OK and sol is None
    got = sweepik.solve(robot, T, locked={"A3": 0.3})
    assert got.families and recovers(robot, got, q)


def test_arms_whose_plan_is_not_one_closed_form_at_every_value_are_not_taken() -> None:
    """A held arm that needs a companion (Gen3 joint 1) or is refused (iiwa A4: every pose a continuum) is not
    taken; nor references of two different arms (their rows are not one chain moved), nor a six-joint arm. Panda
    joint 6 is taken, its axes 5 and 7 meeting at a point that slides along axis 5 with the value, but not at 0 and
    pi, where they are parallel (another plan there): those values go the general way."""
    panda, gen3, iiwa = load_robot("franka_panda"), load_robot("kinova_gen3"), load_robot("kuka_iiwa14")
    six = solving._held_pose(panda, 5)
    assert six is not None and in_windows(0.0, six.windows) and in_windows(np.pi, six.windows)
    held = sweepik.model.origin_axis.hold_joints(panda, {5: 0.0})
    assert solving._default_reduction(held.arm, held).plan.case != "ab_int"  # (the plan at 0 is another)
    assert solving._held_pose(gen3, 0) is None
    assert solving._held_pose(iiwa, 3) is None
    with pytest.raises(sweepik.NoReductionError):
        sweepik.solve(iiwa, iiwa.fk(np.full(7, 0.3)), locked={"A4": 0.3})
    assert HeldPose.of(load_robot("ur5"), 0, first_held_reduction) is None
    # a reference from another arm (the iiwa's A3 held, but one reference's plan of A5 held): refused
    found = []
    for f in held_pose.REFERENCES:
        v = -2.9 + 5.8 * f
        held = sweepik.model.origin_axis.hold_joints(iiwa, {2: v})
        red = solving._default_reduction(held.arm, held)
        found.append((v, red, sweepik.engine.single_pose.SinglePose.of(held.arm, red, held)))
    assert HeldPose.from_references(iiwa, 2, found) is not None
    other = sweepik.model.origin_axis.hold_joints(iiwa, {4: 0.5})
    red = solving._default_reduction(other.arm, other)
    found[2] = (found[2][0], red, sweepik.engine.single_pose.SinglePose.of(other.arm, red, other))
    assert HeldPose.from_references(iiwa, 2, found) is None


@pytest.mark.parametrize(("name", "joint"), [("franka_panda", "joint6"), ("kuka_iiwa14", "A3")])
def test_values_just_outside_the_windows_are_the_held_arm(name: str, joint: str) -> None:
    """Next to a window (axes nearly parallel or nearly meeting: a sliding meeting point far away, the plan badly
    conditioned) the one call's answers, where it gives them, are still the held arm's at that value, and the
    generating configuration is recovered either way."""
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    fast = solving._held_pose(robot, k)
    assert fast is not None and fast.windows.size
    edges = fast.windows[np.isfinite(fast.windows)]
    values = [e + d for e in edges for d in (-3e-3, -5e-4, 5e-4, 3e-3)]
    values = [v for v in values if robot.lower[k] <= v <= robot.upper[k] and not in_windows(v, fast.windows)]
    assert values
    rng = np.random.default_rng(11)
    answered = 0
    for v in values:
        q = in_limit_configurations(robot, 3, rng)
        q[:, k] = v
        for qq, T in zip(q, robot.fk(q), strict=True):
            status, sol = fast.solve(np.ascontiguousarray(T), float(v), True)
            if sol is not None:
                answered += 1
                same_to_rounding(sol, held_general(robot, T, k, float(v)), robot)
                fk_ok(robot, sol, T)
            assert recovers(robot, sweepik.solve(robot, T, locked={joint: float(v)}), qq)
    assert answered >= 1  # (the others, badly conditioned there, went the general way)


def test_a_window_chooses_the_companion_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """Values in one window of the Panda held at joint 6 (a nearly parallel pair of axes round 0, where the general
    way joins a second plan to the one vouched for): every plan is checked once for the window, at its reference
    value, not at each value (0.2-0.6 s a value before); the solutions reach the pose and recover the configuration
    they were made from, and do not depend on the value of the window solved first."""
    from sweepik import reductions
    from sweepik.reductions import decompose

    robot = load_robot("franka_panda")
    k = 5
    fast = solving._held_pose(robot, k)
    assert fast is not None
    lo, hi = next((a, b) for a, b in fast.windows if a < 0.0 < b)
    values = [lo + f * (hi - lo) for f in (0.15, 0.45, 0.8, 0.6)]
    rng = np.random.default_rng(5)
    q = in_limit_configurations(robot, len(values), rng)
    q[:, k] = values
    full = []
    real = decompose.choice
    monkeypatch.setattr(decompose, "choice", lambda arm, *a, **kw: full.append((arm, a[1:])) or real(arm, *a, **kw))
    answers = {}
    for order in (slice(None), slice(None, None, -1)):
        reductions._WINDOW_CHOICES.clear()
        solving._default_reduction.cache_clear()
        full.clear()
        for qq, T in list(zip(q, robot.fk(q), strict=True))[order]:
            sol = sweepik.solve(robot, T, locked={k: float(qq[k])})
            fk_ok(robot, sol, T)
            assert recovers(robot, sol, qq)
            answers.setdefault(float(qq[k]), []).append(sol)
        assert len({id(arm) for arm, hints in full if not hints or not hints[0]}) == 1  # (the window's, once)
    for first, second in answers.values():
        np.testing.assert_array_equal(first.q, second.q)


def test_values_are_checked_as_before() -> None:
    """A value outside the limits or not finite: the same LockedJointError as the held arm's."""
    robot = load_robot("kuka_iiwa14")
    T = robot.fk(np.full(7, 0.3))
    for v, needle in [(3.1, "outside its limits"), (float("nan"), "finite")]:
        with pytest.raises(LockedJointError, match=needle):
            sweepik.solve(robot, T, locked={"A3": v})
    bad = T.copy()
    bad[0, 0] = np.nan
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve(robot, bad, locked={"A3": 0.3})


@pytest.mark.parametrize("seed", [0, 3])
def test_values_where_the_neighbouring_axes_coincide_are_refused_as_before(seed: int) -> None:
    """iiwa A2 held at 0 puts A1 and A3 on one line (every pose a continuum): a special value (``lock_windows``),
    refused with NoReductionError, as the held arm built at that value is, also a hair off it and on the arm
    rewritten (where that value is another number); a hundredth of a radian off it, solved by the one call."""
    original = load_robot("kuka_iiwa14")
    rw = rewrite(original, np.random.default_rng(seed)) if seed else None
    robot = original if rw is None else rw.robot
    fast = solving._held_pose(robot, 1)
    assert fast is not None
    zero = float(rw.forward(np.zeros(7))[1]) if rw is not None else 0.0
    assert in_windows(zero, fast.windows) and not in_windows(zero + 0.01, fast.windows)
    q = in_limit_configurations(original, 3, np.random.default_rng(seed))
    for off in (0.0, 1e-9):
        q[:, 1] = off
        for qq in q:
            q2 = qq if rw is None else rw.forward(qq)
            T = robot.fk(q2)
            with pytest.raises(sweepik.NoReductionError):
                sweepik.solve(robot, T, locked={1: float(q2[1])})
    q[:, 1] = 1e-2
    for qq in q:
        q2 = qq if rw is None else rw.forward(qq)
        sol = sweepik.solve(robot, robot.fk(q2), locked={1: float(q2[1])})
        assert recovers(robot, sol, q2)


def test_long_runs_of_one_value_are_solved_batched(monkeypatch: pytest.MonkeyPatch) -> None:
    """A batch held at one value (a run of ``HELD_RUN_MIN`` poses or more) goes the batched way, by the held arm; the
    short runs around it pose by pose; the solutions are each pose's, the held value in place."""
    robot = load_robot("kuka_iiwa14")
    q = in_limit_configurations(robot, solving.HELD_RUN_MIN + 6, np.random.default_rng(3))
    q[3 : 3 + solving.HELD_RUN_MIN, 2] = 0.7
    T = robot.fk(q)
    taken: list[int] = []
    blocks = HeldPose.blocks
    monkeypatch.setattr(HeldPose, "blocks", lambda self, P, *a: taken.append(len(P)) or blocks(self, P, *a))
    batch = sweepik.solve_many(robot, T, locked={"A3": q[:, 2]})
    assert taken == [3, 3]
    for i in range(len(q)):
        assert np.all(batch[i].q[:, 2] == q[i, 2]) and recovers(robot, batch[i], q[i])
    taken.clear()
    sweepik.solve_many(robot, T[:10], locked={"A3": 0.7})
    assert taken == [10]
    sweepik.solve_many(robot, T, locked={"A3": 0.7})
    assert taken == [10]


@pytest.mark.parametrize(("name", "joint"), TAKEN + SWEPT)
def test_the_general_way_builds_the_vouched_plan_as_it_would_find_it(name: str, joint: str) -> None:
    """A pose the one call does not settle goes the general way, whose held arm at a new value takes the plan
    ``HeldPose`` vouched for (``reductions.vouch_held_plan``) without looking for it again: at random values outside
    the windows it is the plan ``first_plan`` finds there, to the last bit of its wrist centre and meeting point; in
    the windows nothing is vouched for."""
    from sweepik.reductions import _vouched
    from sweepik.reductions.plan import first_plan

    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    fast = solving._held_pose(robot, k)
    assert fast is not None
    rng = np.random.default_rng(k + 17)
    lo, hi = max(robot.lower[k], -np.pi), min(robot.upper[k], np.pi)
    values = [v for v in rng.uniform(lo, hi, 25) if not fast.special(v)]
    for v in values:
        arm = sweepik.model.origin_axis.hold_joints(robot, {k: float(v)}).arm
        assert _vouched(robot, (k,), arm, (float(v),)) == (first_plan(arm), None)
    for v in fast.windows[np.isfinite(fast.windows)]:
        if robot.lower[k] <= v <= robot.upper[k]:
            arm = sweepik.model.origin_axis.hold_joints(robot, {k: float(v)}).arm
            assert _vouched(robot, (k,), arm, (float(v),)) is None
