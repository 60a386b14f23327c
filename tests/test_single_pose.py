"""A single pose in one compiled call (``engine.single_pose``): the general path's answer bit for bit, on the bundled
closed forms and sweeps and on arms written otherwise (base and tool frames, millimetres, axis signs, offsets);
targets that are not rigid transforms raise what they raised; other arrays take the general path."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from one_call import (
    answered_as_the_general_path,
    answered_by_one_call,
    assert_reproduced,
    assert_same,
    configurations,
    general_path,
)
from rewrites import rewrite

import sweepik
from sweepik import load_robot, solving
from sweepik.engine import chunk, one_pose, single_pose
from sweepik.engine.single_pose import SinglePose
from sweepik.results import Solutions

CLOSED = ["puma560", "puma560_std", "ur5", "abb_irb140", "kuka_kr6_r900", "stanford", "standardbots_spark"]
SWEPT = ["kinova_jaco2", "fanuc_crx10ia", "xarm6", "yaskawa_hc10"]


@pytest.mark.parametrize("name", CLOSED + SWEPT)
@pytest.mark.parametrize("seed", [0, 1])
def test_the_one_call_is_the_general_path_on_arms_written_otherwise(
    name: str, seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The arm as bundled (seed 0) and rewritten at random (seed 1: frames, units, axis signs, offsets): each pose's
    solutions are the general path's, bit for bit, limits on and off; most poses are answered by the one call; every
    solution reproduces the pose and the generating configuration is among them (modulo 2 pi)."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    if seed:
        robot = rewrite(robot, rng).robot
    q = configurations(robot, rng, 24 if name in CLOSED else 8)
    # (half of the 2 x 24 solves: the random quarter and more)
    assert answered_as_the_general_path(monkeypatch, robot, q) >= len(q)


@pytest.mark.parametrize("name", ["xarm6", "kinova_jaco2"])
@pytest.mark.parametrize("seed", [0, 1])
def test_a_pose_due_a_polish_resumes_from_the_calls_candidates(
    name: str, seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A sweep's pose with a candidate due a polish (status ``DUE``: 2-22 % of random poses of these arms) is not
    searched again: the rest of the general way takes the call's candidates (``chunk.resumed``), and the answer is
    the general path's bit for bit, limits on and off."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    if seed:
        robot = rewrite(robot, rng).robot
    fast = solving._single_pose(robot, None)
    assert isinstance(fast, SinglePose)
    q = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), (150, robot.n_joints))
    T = np.ascontiguousarray(robot.fk(q))
    due = [i for i in range(len(T)) if fast.call(T[i], True)[0] == one_pose.DUE][:6]
    assert due
    calls = []
    monkeypatch.setattr(single_pose, "resumed", lambda *a: calls.append(1) or chunk.resumed(*a))
    for i in due:
        for limits in (True, False):
            sol = sweepik.solve(robot, T[i], limits=limits)
            assert_same(sol, general_path(monkeypatch, robot, T[i], limits=limits))
        assert_reproduced(robot, sweepik.solve(robot, T[i], limits=False), T[i], q[i])
    assert len(calls) == 3 * len(due)


@pytest.mark.parametrize(
    ("name", "seed", "q0"),
    [
        ("xarm6", 1005, [-0.80246608601609, 0.71138588657811, -2.52734510425291, -2.53380923469828, 1.86142383934798,
                         2.87485880270184]),
        ("doosan_m0609", 1012, [2.76303058512111, 1.35688672768910, -2.62519766853518, 2.07338640588516,
                                -2.11570463910082, -0.33389360475117]),
    ],
)  # fmt: skip
def test_two_roots_that_meet_outside_the_limits_are_counted_once(
    name: str, seed: int, q0: list[float], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A pose none of whose solutions lies within the limits, two of them one root (a fold): the one call handed it on
    only when two solutions within the limits met, and its reason counted the pair twice ("6 solution(s) reach the
    pose but violate the limits" where the general path says 5). Found by an auditing helper on arms rewritten at
    random (xarm6 a plain sweep, the M0609 with a companion)."""
    robot = rewrite(load_robot(name), np.random.default_rng(seed)).robot
    T = robot.fk(np.array(q0))
    for limits in (True, False):
        sol = sweepik.solve(robot, T, limits=limits)
        assert_same(sol, general_path(monkeypatch, robot, T, limits=limits))
    assert sweepik.solve(robot, T).reason == general_path(monkeypatch, robot, T).reason
    assert "violate the limits" in str(sweepik.solve(robot, T).reason)


@pytest.mark.parametrize(("name", "joint"), [("kuka_iiwa14", "A3"), ("franka_panda", "joint7")])
def test_a_locked_arm_at_new_values(name: str, joint: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """A seven-joint arm held at a new value each pose, its held arm built for the value (not ``engine.held_pose``'s
    call with the value an argument: tests/test_held_pose.py): the general path's solutions, the held value in
    place."""
    monkeypatch.setattr(solving, "_held_pose", lambda robot, k: None)
    robot = load_robot(name)
    k = robot.joint_names.index(joint)
    rng = np.random.default_rng(4)
    q = rng.uniform(robot.lower, robot.upper, (10, robot.n_joints))
    for qq, T in zip(q, robot.fk(q), strict=True):
        locked = {joint: float(qq[k])}
        sol = sweepik.solve(robot, T, locked=locked)
        assert_same(sol, general_path(monkeypatch, robot, T, locked=locked))
        assert answered_by_one_call(robot, T, locked=locked)
        assert np.all(sol.q[:, k] == qq[k]) and np.min(np.max(np.abs(sol.q - qq), axis=1)) < 1e-6


def _bad_poses(robot: sweepik.Robot) -> list[np.ndarray]:
    T = robot.fk(np.full(robot.n_joints, 0.3))
    out = []
    for i, j, v in ((0, 0, np.nan), (1, 3, np.inf), (3, 0, 0.5), (0, 1, 0.01), (2, 3, 1e31)):
        B = T.copy()
        B[i, j] = v
        out.append(B)
    M = T.copy()
    M[:3, 0] *= -1.0  # (a reflection: det -1)
    out.append(M)
    return out


@pytest.mark.parametrize("name", ["puma560", "kuka_kr6_r900"])
def test_targets_that_are_no_rigid_transform_raise_as_before(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """Not finite, a bottom row off, a rotation not orthonormal, a reflection, a translation out of range: the same
    error, with the same message, as the general path's."""
    robot = load_robot(name)
    for B in _bad_poses(robot):
        with pytest.raises(sweepik.SweepikError) as fast:
            sweepik.solve(robot, B)
        with pytest.raises(sweepik.SweepikError) as general:
            general_path(monkeypatch, robot, B)
        assert type(fast.value) is type(general.value) and str(fast.value) == str(general.value)


def test_other_arrays_and_options_take_the_general_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """A read-only, Fortran-ordered, float32 or nested-list pose gives the same solutions (by the general path where
    the one call does not take it); a batch shape is refused as before."""
    robot = load_robot("ur5")
    T = robot.fk(np.array([0.1, -1.2, 1.3, -0.4, 1.1, 0.3]))
    want = sweepik.solve(robot, T)
    frozen = T.copy()
    frozen.flags.writeable = False
    for other in (frozen, np.asfortranarray(T), T.tolist()):
        assert_same(sweepik.solve(robot, other), want)
    single = sweepik.solve(robot, T.astype(np.float32))
    assert len(single) == len(want)
    with pytest.raises(sweepik.ShapeError, match="solve_many"):
        sweepik.solve(robot, T[None])
    assert_same(sweepik.solve(robot, T, limits=True, strategy="precise"), want)


def test_which_reductions_qualify() -> None:
    """Closed forms and sweeps of a revolute theta* whose checks are compiled qualify; the C-Arm (a prismatic theta*,
    its own reduction) does not (arms solved with a companion: ``test_joined_pose``)."""
    assert solving._single_pose(load_robot("carm"), None) is None
    for name in CLOSED + SWEPT:
        assert isinstance(solving._single_pose(load_robot(name), None), SinglePose)


def test_settled_solutions_are_the_constructors() -> None:
    """``Solutions.settled`` sets every field the constructor sets, to the same values."""
    robot = load_robot("ur5")
    q = np.random.default_rng(0).uniform(-1, 1, (3, 6))
    e, ins, mu = np.zeros(3), np.ones(3, dtype=bool), np.ones(3, dtype=np.intp)
    args = dict(q=q, error=e, error_geodesic=e, within_limits=ins, multiplicity=mu, reason=None, pose=np.eye(4))
    a = Solutions.settled(**args, robot=robot)  # type: ignore[arg-type]
    b = Solutions(**args, families=(), robot=robot)  # type: ignore[arg-type]
    assert set(vars(a)) == set(vars(b)) == {f.name for f in dataclasses.fields(Solutions)}
    assert_same(a, b)


def test_the_default_reduction_named_takes_the_one_call_too(monkeypatch: pytest.MonkeyPatch) -> None:
    """``reduction="auto"`` on an arm whose file names no reduction is its default: the one call answers, the same
    solutions; another reduction's name goes the general way."""
    robot = load_robot("ur5")
    T = robot.fk(np.array([0.1, -1.2, 1.3, -0.4, 1.1, 0.3]))
    assert isinstance(solving._single_pose(robot, None, "auto"), SinglePose)
    assert_same(sweepik.solve(robot, T, reduction="auto"), sweepik.solve(robot, T))
    carm = load_robot("carm")
    assert solving._single_pose(carm, None, "auto") is None and solving._single_pose(carm, None, "carm-d1") is None
