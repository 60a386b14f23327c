"""The one-call path of a single pose (``one_pose.settle_one``, ``one_pose.settle_closed``,
``chunk.settled``) gives what the general path gives, bit for bit, and hands the poses it cannot settle
to it."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np
import pytest

import sweepik
from sweepik import load_robot, solving
from sweepik.engine import chunk, one_pose, search, settle
from sweepik.engine.single_pose import SinglePose


def _poses(robot: sweepik.Robot, seed: int) -> np.ndarray:
    """Random configurations' poses, and poses on the singular set (joint 5 at 0, joint 3 at 0, both)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(robot.lower, robot.upper, (48, 6))
    q[:8, 4] = 0.0
    q[8:16, 2] = 0.0
    q[16:20, 2] = 0.0
    q[16:20, 4] = 0.0
    return robot.fk(q)


def _assert_same(a: sweepik.Solutions, b: sweepik.Solutions) -> None:
    for x, y in (
        (a.q, b.q),
        (a.error, b.error),
        (a.error_geodesic, b.error_geodesic),
        (a.multiplicity, b.multiplicity),
        (a.within_limits, b.within_limits),
    ):
        assert x.dtype == y.dtype
        np.testing.assert_array_equal(x, y)
    assert len(a.families) == len(b.families)
    assert a.reason == b.reason
    np.testing.assert_array_equal(a.pose, b.pose)


def _general(monkeypatch: pytest.MonkeyPatch, robot: sweepik.Robot, poses: np.ndarray, **kw: Any) -> list[Any]:
    with monkeypatch.context() as m:
        m.setattr(solving, "settled", lambda *args: None)
        m.setattr(chunk, "settled", lambda *args: None)
        m.setattr(solving, "_single_pose", lambda *args: None)
        return [sweepik.solve(robot, T, **kw) for T in poses]


def _counted(monkeypatch: pytest.MonkeyPatch) -> Counter[int]:
    """Counts of the one call's statuses from now on (``settle_one``, ``settle_closed``, ``SinglePose.solve``)."""
    seen: Counter[int] = Counter()
    for name in ("settle_one", "settle_closed"):
        real = getattr(one_pose, name)

        def counting(*args: Any, real: Any = real) -> Any:
            out = real(*args)
            seen[-1 if out is None else out.status] += 1
            return out

        monkeypatch.setattr(one_pose, name, counting)
    real_single = SinglePose.solve

    def single(*args: Any) -> Any:  # (``single_pose``: the same statuses)
        status, sol = real_single(*args)
        seen[status] += 1
        return status, sol

    monkeypatch.setattr(SinglePose, "solve", single)
    return seen


def _both_ways(monkeypatch: pytest.MonkeyPatch, robot: sweepik.Robot, poses: np.ndarray, **kw: Any) -> Counter[int]:
    """Solves ``poses`` the one-call way and the general way, asserts the same solutions, and returns the one-call
    statuses seen."""
    seen = _counted(monkeypatch)
    fast = [sweepik.solve(robot, T, **kw) for T in poses]
    for a, b in zip(fast, _general(monkeypatch, robot, poses, **kw), strict=True):
        _assert_same(a, b)
    return seen


@pytest.mark.parametrize(
    ("name", "reduction"),
    [
        ("carm", None),
        ("carm", "auto"),
        ("fanuc_crx10ia", None),
        ("kinova_jaco2", None),
        ("xarm6", None),
        ("ur5", None),
        ("puma560", None),
        ("carm_swapped", None),
    ],
)
@pytest.mark.parametrize("limits", [True, False])
def test_one_call_is_the_general_path(
    name: str, reduction: str | None, limits: bool, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every pose's solutions are the general path's bit for bit: those settled in one call (most of them) and
    those it hands over (families, a polish due, a continuum along another joint, a closed form's singular poses).
    theta* revolute and prismatic, a hints kernel (carm-d1), generic sweeps, closed forms."""
    robot = load_robot(name)
    poses = _poses(robot, 5)
    seen = _both_ways(monkeypatch, robot, poses, reduction=reduction, limits=limits)
    assert seen[one_pose.OK] >= len(poses) // 2  # (the one-call path is what is tested)


@pytest.mark.parametrize("name", ["ur5", "fanuc_crx10ia", "carm"])
def test_unreachable_poses_meeting_branches_singular_wrists(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A pose out of reach gets the general path's empty solutions and reason from the one call; a closed form's
    branches that meet (UR5 with joint 3 at 0: the elbow straight, a double root the closed form's rounding splits
    in two) are handed over (``MEET``) and merged the general way into one solution of multiplicity 2; its poses
    with a singular wrist (joint 5 at 0) are handed over too (``SINGULAR``: its kernel checks them in the call, where
    its branches do not meet first) and solved by the fallback sweep, which reports the wrist's continuum as a
    family."""
    robot = load_robot(name)
    far = np.eye(4)
    far[:3, 3] = 10.0 * robot.length_scale
    seen = _both_ways(monkeypatch, robot, far[None])
    assert seen[one_pose.OK] == 1
    sol = sweepik.solve(robot, far)
    assert len(sol) == 0 and sol.reason is not None and "unreachable" in sol.reason
    if name == "ur5":
        q = np.random.default_rng(13).uniform(robot.lower, robot.upper, (6, 6))
        q[:, 2] = 0.0
        assert _both_ways(monkeypatch, robot, robot.fk(q)) == {one_pose.MEET: len(q)}
        assert all((sweepik.solve(robot, T).multiplicity == 2).any() for T in robot.fk(q))
        q[:, 2] = 0.4
        q[:, 4] = 0.0
        seen = _both_ways(monkeypatch, robot, robot.fk(q))  # (the wrist's branches meet there too: MEET first)
        assert one_pose.OK not in seen and seen[one_pose.SINGULAR] > 0
        assert all(sweepik.solve(robot, T).families for T in robot.fk(q))


def test_a_class_overriding_the_singular_checks_keeps_them(monkeypatch: pytest.MonkeyPatch) -> None:
    """A closed form whose class overrides ``degenerate`` (and not ``singular_kernel``) has it asked in Python on every
    pose the one call settles: here it flags every pose, so each goes to the fallback sweep, the general way."""
    robot = load_robot("ur5")
    red = sweepik.reductions.get_reduction(robot, None)
    asked: list[int] = []

    class EveryPoseDegenerate(sweepik.reductions.GeometricReduction):
        def degenerate(self, poses: np.ndarray) -> np.ndarray:
            asked.append(len(poses))
            return np.ones(len(poses), dtype=bool)

    own = EveryPoseDegenerate(robot, red.plan)
    poses = _poses(robot, 14)[24:30]  # (random ones: the kernel would flag none)
    seen = _counted(monkeypatch)
    settled: list[object] = []
    real = chunk.settled
    spy = lambda *args: settled.append(real(*args)) or settled[-1]  # noqa: E731
    monkeypatch.setattr(solving, "settled", spy)
    monkeypatch.setattr(chunk, "settled", spy)
    for T in poses:
        assert len(sweepik.solve(robot, T, reduction=own)) > 0
    assert seen[one_pose.OK] == len(poses) and asked and settled == [None] * len(poses)


@pytest.mark.parametrize(("name", "names"), [("ur5", ["auto"]), ("carm", ["carm-d1", "d1"])])
def test_the_default_reduction_named_takes_the_one_call(
    name: str, names: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """``reduction`` naming the arm's default (``"auto"`` for an arm whose file names none, the C-Arm's ``carm-d1``
    or its alias) solves as ``reduction=None`` does, bit for bit, without checking the options again
    (``reductions.is_default``); another reduction, or an unknown name, is not taken for it."""
    from sweepik.reductions import is_default

    robot = load_robot(name)
    poses = _poses(robot, 15)[20:26]
    want = [sweepik.solve(robot, T) for T in poses]
    monkeypatch.setattr(solving, "prepare", lambda *args: pytest.fail("options checked again"))
    for r in names:
        assert is_default(robot, r)
        for a, b in zip([sweepik.solve(robot, T, reduction=r) for T in poses], want, strict=True):
            _assert_same(a, b)
    assert not is_default(robot, "carm-theta2" if name == "carm" else "carm-d1")
    assert not is_default(robot, "no-such-reduction") and not is_default(robot, 3)
    monkeypatch.undo()
    with pytest.raises(sweepik.SweepikError, match="unknown reduction"):
        sweepik.solve(robot, poses[0], reduction="no-such-reduction")


@pytest.mark.parametrize("name", ["franka_panda", "kuka_iiwa14"])
def test_a_locked_arm_takes_the_one_call(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A seven-joint arm with a joint locked (its held arm a closed form) takes the one call too, its solutions full
    length with the held value in place, the general path's bit for bit; poses with the held arm's wrist singular
    go the general way. (Built for the value held, not ``engine.held_pose``'s call with the value an argument:
    tests/test_held_pose.py.)"""
    from sweepik.experiments.bench import _bench_lock

    monkeypatch.setattr(solving, "_held_pose", lambda robot, k: None)
    robot = load_robot(name)
    locked = _bench_lock(robot)
    assert locked
    q = np.random.default_rng(16).uniform(robot.lower, robot.upper, (24, robot.n_joints))
    for j, v in locked.items():
        q[:, j] = v
    seen = _both_ways(monkeypatch, robot, robot.fk(q), locked=locked)
    assert seen[one_pose.OK] >= len(q) // 2
    for T, qq in zip(robot.fk(q), q, strict=True):
        sols = sweepik.solve(robot, T, locked=locked)
        assert sols.q.shape[1] == robot.n_joints and np.all(sols.q[:, list(locked)] == list(locked.values()))
        assert np.min(np.max(np.abs(sols.q - qq), axis=1)) < 1e-6


def test_overflowing_buffers_go_the_general_way(monkeypatch: pytest.MonkeyPatch) -> None:
    """With the candidate buffer cut to one, every pose overflows it: each goes the general way (whose engine redoes
    it), with the same solutions."""
    robot = load_robot("fanuc_crx10ia")
    poses = _poses(robot, 6)[::6]
    monkeypatch.setattr(search, "MAX_CAND", 1)
    assert _both_ways(monkeypatch, robot, poses) == {one_pose.SEARCH_ELSEWHERE: len(poses)}
    assert all(len(sweepik.solve(robot, T)) > 0 for T in poses)


def test_a_pose_due_a_polish_goes_the_general_way(monkeypatch: pytest.MonkeyPatch) -> None:
    """A candidate that needs the Newton polish (here: every certified one, with the polish threshold above them)
    sends its pose the general way, which polishes it."""
    robot = load_robot("carm")
    poses = _poses(robot, 7)[20:26]
    monkeypatch.setattr(settle, "POLISH_ABOVE_REL", 0.0)
    monkeypatch.setattr(settle, "POLISH_PAPER_ABOVE_REL", 0.0)
    assert _both_ways(monkeypatch, robot, poses) == {one_pose.DUE: len(poses)}
    assert all(len(sweepik.solve(robot, T)) > 0 for T in poses)


@pytest.mark.parametrize(
    ("name", "n_samples", "one_call"), [("carm", 17, True), ("carm", 100, True), ("xarm6", 100, False)]
)
def test_other_sample_counts(name: str, n_samples: int, one_call: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """Another ``n_samples``: a hints kernel's one-pass search takes any (its grid kept per count), a generic sweep's
    only its own (the pose goes the general way); the same solutions either way."""
    robot = load_robot(name)
    poses = _poses(robot, 9)[::4]
    assert (_both_ways(monkeypatch, robot, poses, n_samples=n_samples)[one_pose.OK] > 0) == one_call
