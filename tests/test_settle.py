"""The stepwise settling steps (sweepik.engine.settle): a solution a hair outside a joint limit is moved onto it and
stays certified, one too far outside is left alone, and the errors of configurations are the model's."""

from __future__ import annotations

import dataclasses

import numpy as np

from sweepik import load_robot
from sweepik.engine import settle
from sweepik.engine.settings import ACCEPT_TOL_REL, SNAP_REACH
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.units import orientation_weight


def _ur5_with_joint_limit(upper: float):  # type: ignore[no-untyped-def]
    robot = load_robot("ur5")
    joints = list(robot.joints)
    joints[1] = dataclasses.replace(joints[1], lower=-1.0, upper=upper)  # (a range under a turn: no other winding)
    return dataclasses.replace(robot, joints=tuple(joints))


def test_a_solution_just_past_a_limit_is_snapped_onto_it() -> None:
    """A configuration exactly at joint 2's upper limit solves its pose; given 1e-7 rad beyond the limit (as the
    pose pins a solution down near a singular configuration), ``snap_to_limits`` clamps it, polishes the others
    with joint 2 held, and the result is inside the limits and certified; 10 x ``SNAP_REACH`` beyond, it is left
    outside."""
    robot = _ur5_with_joint_limit(0.7)
    rng = np.random.default_rng(2)
    q = rng.uniform(-2.0, 2.0, (6, 6))
    q[:, 1] = 0.7
    poses = robot.fk(q)
    w = orientation_weight(robot.length_unit)
    off = q.copy()
    off[:3, 1] += 1e-7
    off[3:, 1] += 10 * SNAP_REACH
    err_geo, err_paper = settle.errors_of(robot, off, poses, w)
    pose_idx = np.arange(6)
    wrapped, inside = settle.snap_to_limits(robot, off, err_geo, err_paper, poses, pose_idx, w)
    assert inside[:3].all() and not inside[3:].any()
    np.testing.assert_array_equal(off[:3, 1], 0.7)
    tol = ACCEPT_TOL_REL * robot.length_scale
    assert np.all(err_geo[:3] <= tol)
    np.testing.assert_allclose(err_geo[:3], pose_error_geodesic(robot.fk(off[:3]), poses[:3], w), atol=tol)
    np.testing.assert_allclose(off[:3], q[:3], atol=1e-6)


def test_errors_of_configurations_are_the_models() -> None:
    """``errors_of`` (the stepwise path's errors) are the model's geodesic errors of the configurations' poses."""
    robot = load_robot("kuka_kr6_r900")
    rng = np.random.default_rng(5)
    q = rng.uniform(robot.lower, robot.upper, (10, 6))
    target = robot.fk(q + rng.normal(0.0, 1e-3, q.shape))
    w = orientation_weight(robot.length_unit)
    geo, _ = settle.errors_of(robot, q, target, w)
    np.testing.assert_allclose(geo, pose_error_geodesic(robot.fk(q), target, w), rtol=1e-9, atol=1e-14)
