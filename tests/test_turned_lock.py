"""The first or the last joint of a seven-joint arm held: every value solved by the held arm at one reference value,
the pose turned (``engine.turned_lock``).

Properties: the turn is exact (the forward kinematics at a value is the turned forward kinematics at the reference);
the solutions at a value are those of the held arm built at that value and solved the general way (same count, same
configurations to rounding), on the bundled arms and on them rewritten at random (axis signs, zeros, base and tool
frames, units), the generating configuration recovered and the value in its column; ``solve_many`` with a value per
pose and ``iter_solve`` give ``solve``'s answers; a pose with self-motion families is answered at its own value (the
families' members hold it); a target that is not a rigid transform is named as the caller gave it; joints in the
middle, slides and six-joint arms are not turned.
"""

from __future__ import annotations

import numpy as np
import pytest
from oracles import in_limit_configurations, recovers
from rewrites import rewrite

import sweepik
from sweepik import InvalidPoseError, load_robot, solving
from sweepik.engine.turned_lock import reference_value, turned_lock
from sweepik.model.validate import check_poses

LOCKS = [
    ("kinova_gen3", "joint_1"),  # (a sweep with a companion plan: each value built its held arm, ~18 ms)
    ("kinova_gen3", "joint_7"),
    ("franka_panda", "joint1"),
    ("franka_panda", "joint7"),
    ("kuka_iiwa14", "A1"),
    ("kuka_iiwa14", "A7"),
]
_OPTIONS = dict(
    reduction=None, strategy="precise", limits=True, n_samples=solving.N_SAMPLES, chunk_size=1, free_joint=None
)


def _at_value(robot: sweepik.Robot, T: np.ndarray, k: int, value: float) -> sweepik.Solutions:
    """The held arm built at ``value`` and solved the general way (no turn)."""
    block = next(iter(solving._held_run(robot, T[None], {k: value}, _OPTIONS, turned=False)))
    return block.solutions(0)


def _same(a: sweepik.Solutions, b: sweepik.Solutions, robot: sweepik.Robot) -> None:
    assert len(a) == len(b)
    if len(a):
        d = np.sort(a.q, axis=0) - np.sort(b.q, axis=0)
        assert np.abs(d).max() < 1e-8 * max(1.0, robot.length_scale)
        np.testing.assert_array_equal(np.sort(a.within_limits), np.sort(b.within_limits))
    assert a.reason == b.reason


@pytest.mark.parametrize(("name", "joint"), LOCKS)
def test_a_value_is_the_reference_turned(name: str, joint: str) -> None:
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    q = in_limit_configurations(robot, 20, np.random.default_rng(k))
    for qq in q:
        turn = turned_lock(robot, {k: float(qq[k])})
        assert turn is not None and turn.reference == reference_value(robot, k)
        at_ref = qq.copy()
        at_ref[k] = turn.reference
        np.testing.assert_allclose(turn.poses(robot.fk(qq)), robot.fk(at_ref), atol=1e-12 * robot.length_scale)


@pytest.mark.parametrize(("name", "joint"), LOCKS)
def test_the_solutions_are_the_held_arms_at_the_value(name: str, joint: str) -> None:
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    q = in_limit_configurations(robot, 10, np.random.default_rng(k + 1))
    for qq, T in zip(q, robot.fk(q), strict=True):
        v = float(qq[k])
        sols = sweepik.solve(robot, T, locked={joint: v})
        _same(sols, _at_value(robot, T, k, v), robot)
        assert np.all(sols.q[:, k] == v) and recovers(robot, sols, qq)
        F = robot.fk(sols.q)
        assert np.abs(F - T).max(initial=0.0) < 1e-9 * max(1.0, robot.length_scale)
        np.testing.assert_array_equal(sols.pose, T)


@pytest.mark.parametrize(("name", "joint"), [("kinova_gen3", "joint_1"), ("kuka_iiwa14", "A7")])
@pytest.mark.parametrize("seed", [1, 2])
def test_arms_written_otherwise(name: str, joint: str, seed: int) -> None:
    """Axis signs, zeros, base and tool frames and units rewritten at random: the turn is the rewritten arm's own,
    and the solutions are the held arm's at the value."""
    rng = np.random.default_rng(seed)
    original = load_robot(name)
    rw = rewrite(original, rng)
    robot = rw.robot
    k = original.joint_names.index(joint)
    q0 = in_limit_configurations(original, 6, rng)
    q0 = q0[np.all((rw.forward(q0) >= robot.lower) & (rw.forward(q0) <= robot.upper), axis=1)]
    assert len(q0)
    for qq in q0:
        q2 = rw.forward(qq)
        T = robot.fk(q2)
        sols = sweepik.solve(robot, T, locked={k: float(q2[k])})
        _same(sols, _at_value(robot, T, k, float(q2[k])), robot)
        assert recovers(robot, sols, q2)


@pytest.mark.parametrize(("name", "joint"), [("kinova_gen3", "joint_1"), ("franka_panda", "joint1")])
def test_solve_many_and_iter_solve_with_a_value_per_pose_are_solve(name: str, joint: str) -> None:
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    q = in_limit_configurations(robot, 12, np.random.default_rng(5))
    T = robot.fk(q)
    batch = sweepik.solve_many(robot, T, locked={joint: q[:, k]})
    streamed = list(sweepik.iter_solve(robot, T, locked={joint: q[:, k]}))
    for i in range(len(q)):
        one = sweepik.solve(robot, T[i], locked={joint: float(q[i, k])})
        for other in (batch[i], streamed[i]):
            _same(other, one, robot)
            assert np.all(other.q[:, k] == q[i, k])
    # one value for a whole run (batched by the held arm at the reference)
    v = float(q[0, k])
    at_v = q.copy()
    at_v[:, k] = v
    run = sweepik.solve_many(robot, robot.fk(at_v), locked={joint: v})
    for sols, qq in zip(run, at_v, strict=True):
        assert np.all(sols.q[:, k] == v) and recovers(robot, sols, qq)


def test_a_pose_with_families_is_answered_at_its_own_value() -> None:
    """The iiwa with its wrist straight (A6 = 0: A5 and A7 on one line) and A1 held: a continuum; the families come
    from the held arm at the value, their members holding it."""
    robot = load_robot("kuka_iiwa14")
    q = np.array([0.7, 0.5, 0.3, -1.2, 0.4, 0.0, 0.6])
    T = robot.fk(q)
    sols = sweepik.solve(robot, T, locked={"A1": 0.7})
    assert sols.families and recovers(robot, sols, q)
    for fam in sols.families:
        lo, hi = fam.interval
        members = fam.at(np.linspace(lo, hi, 5))
        assert np.all(members[:, 0] == 0.7)
        assert np.abs(robot.fk(members) - T).max() < 1e-8 * robot.length_scale


def _refused_as_given(robot: sweepik.Robot, q: np.ndarray, locked: dict[str, float]) -> np.ndarray:
    """The pose of ``q`` spoilt (not a rotation): ``solve`` refuses it with the message ``check_poses`` gives for it
    as the caller wrote it (not turned). Returns the spoilt pose."""
    T = robot.fk(q)
    T[0, 0] = 2.0
    with pytest.raises(InvalidPoseError) as want:
        check_poses(T, "pose")
    with pytest.raises(InvalidPoseError) as err:
        sweepik.solve(robot, T, locked=locked)
    assert str(err.value) == str(want.value)
    return T


def test_a_target_that_is_not_rigid_is_named_as_given() -> None:
    robot = load_robot("kinova_gen3")
    T = _refused_as_given(robot, np.full(7, 0.2), {"joint_1": 0.4})
    T[1, 3] = np.nan
    with pytest.raises(sweepik.SweepikError, match="pose"):
        sweepik.solve(robot, T, locked={"joint_1": 0.4})
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve_many(robot, T[None], locked={"joint_1": [0.4]})


def test_what_is_not_turned() -> None:
    """A joint in the middle, a value at the reference, a six-joint arm, two joints held: not turned."""
    gen3 = load_robot("kinova_gen3")
    assert turned_lock(gen3, {"joint_4": 0.3}) is None
    assert turned_lock(gen3, {"joint_1": reference_value(gen3, 0)}) is None
    assert turned_lock(load_robot("ur5"), {0: 0.3}) is None
    assert turned_lock(gen3, {"joint_1": 0.3, "joint_2": 0.1}) is None
    assert turned_lock(gen3, {"joint_7": 0.3}) is not None


def test_the_reference_value() -> None:
    """0 where the limits hold it, else their middle; a value held elsewhere is solved there and turned back."""
    import dataclasses

    panda = load_robot("franka_panda")
    assert reference_value(panda, 0) == 0.0
    joints = list(panda.joints)
    joints[6] = dataclasses.replace(joints[6], lower=0.5, upper=2.5)
    moved = dataclasses.replace(panda, joints=tuple(joints))
    assert reference_value(moved, 6) == 1.5
    q = np.array([0.3, 0.2, -0.1, -1.5, 0.4, 1.8, 2.1])
    sols = sweepik.solve(moved, moved.fk(q), locked={"joint7": 2.1})
    assert np.all(sols.q[:, 6] == 2.1) and recovers(moved, sols, q)


def test_a_turned_lock_in_one_compiled_call(monkeypatch: pytest.MonkeyPatch) -> None:
    """Where ``HeldPose`` does not take the first or last joint but the held arm at the reference value is one
    closed form (``SinglePose``), ``solve`` turns the pose into that call (``solving.TurnedAt``): the same solutions
    as the held arm at the value, the caller's pose named in a refusal. (No bundled or ssik arm needs it today:
    ``HeldPose`` is made to refuse the iiwa's A1 here.)"""
    robot = load_robot("kuka_iiwa14")
    monkeypatch.setattr(solving, "_held_pose", lambda robot, k: None)
    solving._reference_pose.cache_clear()
    fast = solving._single_pose(robot, {"A1": 0.4})
    assert isinstance(fast, solving.TurnedAt)
    q = in_limit_configurations(robot, 10, np.random.default_rng(9))
    answered = 0
    for qq, T in zip(q, robot.fk(q), strict=True):
        v = float(qq[0])
        status, sol = solving._single_pose(robot, {"A1": v}).solve(np.ascontiguousarray(T), True)
        if sol is not None:
            answered += 1
            _same(sol, _at_value(robot, T, 0, v), robot)
        _same(sweepik.solve(robot, T, locked={"A1": v}), _at_value(robot, T, 0, v), robot)
        assert recovers(robot, sweepik.solve(robot, T, locked={"A1": v}), qq)
    assert answered >= 8
    _refused_as_given(robot, q[0], {"A1": 0.4})
    solving._reference_pose.cache_clear()
