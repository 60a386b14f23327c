"""The engine's one compiled forward kinematics, Jacobian and pose errors (sweepik.engine.certify) against the NumPy
model (``Robot.fk``, ``Robot.jacobian``, ``pose_error_geodesic``, ``pose_error_paper``) on random arms of every
convention, with base and tool transforms; and certification itself: a candidate's configuration and errors."""

from __future__ import annotations

import numpy as np
from conftest import random_configs, random_dh_robot
from hypothesis import given
from hypothesis import strategies as st

from sweepik import load_robot
from sweepik.engine import certify
from sweepik.model.pose import pose_error_geodesic, pose_error_paper
from sweepik.model.units import orientation_weight


@given(seed=st.integers(0, 2**32 - 1), convention=st.sampled_from(["modified", "standard"]))
def test_compiled_pose_and_jacobian_match_the_numpy_ones(seed: int, convention: str) -> None:
    """``pose_and_jacobian`` and ``tool_poses`` (the polish's compiled FK, Jacobian and errors) equal
    ``Robot.fk``, ``Robot.jacobian`` and ``pose_error_geodesic`` to rounding on random arms (mixed joint types,
    1-7 joints, base and tool transforms)."""
    rng = np.random.default_rng(seed)
    robot = random_dh_robot(rng, convention)
    q = random_configs(robot, rng, 8, spread=3.0)
    T, J = certify.pose_and_jacobian(robot, q)
    scale = max(1.0, robot.length_scale)
    np.testing.assert_allclose(T, robot.fk(q), rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(J, robot.jacobian(q), rtol=0, atol=1e-12 * scale)
    target = robot.fk(q + rng.normal(0.0, 1e-2, q.shape))
    T2, err = certify.tool_poses(robot, q, target, 0.5)
    np.testing.assert_array_equal(T2, T)
    np.testing.assert_allclose(err, pose_error_geodesic(robot.fk(q), target, 0.5), rtol=1e-9, atol=1e-14 * scale)
    # read-only inputs (e.g. a memory-mapped file's) are taken too, with the same results
    q.flags.writeable = target.flags.writeable = False
    np.testing.assert_array_equal(certify.pose_and_jacobian(robot, q)[1], J)
    np.testing.assert_array_equal(certify.tool_poses(robot, q, target, 0.5)[1], err)


@given(seed=st.integers(0, 2**32 - 1), convention=st.sampled_from(["modified", "standard"]))
def test_flange_poses_are_the_last_link_frames(seed: int, convention: str) -> None:
    """``flange_poses``: the world pose of the last link frame (the tool transform taken off), as
    ``Robot.frames`` gives it, to rounding, on random arms with base and tool transforms."""
    rng = np.random.default_rng(seed)
    robot = random_dh_robot(rng, convention)
    q = random_configs(robot, rng, 8, spread=3.0)
    scale = max(1.0, robot.length_scale)
    np.testing.assert_allclose(certify.flange_poses(robot, q), robot.frames(q)[:, -2], rtol=0, atol=1e-12 * scale)


@given(seed=st.integers(0, 2**32 - 1), convention=st.sampled_from(["modified", "standard"]))
def test_pose_errors_are_the_model_errors(seed: int, convention: str) -> None:
    """``pose_errors`` (the errors certification computes) are ``pose_error_geodesic`` and ``pose_error_paper`` of
    the model to rounding, at configurations near the target and far from it; a configuration with a NaN is never
    certified (infinite errors)."""
    rng = np.random.default_rng(seed)
    robot = random_dh_robot(rng, convention)
    q = random_configs(robot, rng, 8, spread=3.0)
    target = robot.fk(q + rng.normal(0.0, rng.choice([1e-6, 1e-1]), q.shape))
    w = orientation_weight(robot.length_unit)
    geo, paper = certify.pose_errors(robot, q, target, w)
    scale = max(1.0, robot.length_scale)
    np.testing.assert_allclose(geo, pose_error_geodesic(robot.fk(q), target, w), rtol=1e-9, atol=1e-13 * scale)
    small = geo <= certify.J_CUTOFF_FACTOR * w  # (J is wanted only near a solution: far away it is given as inf)
    assert np.all(np.isinf(paper[~small]))
    np.testing.assert_allclose(
        paper[small], pose_error_paper(robot.fk(q), target, w)[small], rtol=1e-7, atol=1e-13 * scale
    )
    q[0, 0] = np.nan
    geo, paper = certify.pose_errors(robot, q, target, w)
    assert np.isinf(geo[0]) and np.isinf(paper[0])


def test_certified_candidates_reproduce_the_pose() -> None:
    """``certify``: every candidate's configuration comes with its errors against the pose; at the sweep's roots of
    the C-Arm's poses (rounding-level roots) the configurations reproduce the poses, and their errors are what the
    model says."""
    from sweepik.engine.chunk import chain_poses, theta_range
    from sweepik.engine.search import search
    from sweepik.reductions import get_reduction

    robot = load_robot("carm")
    rng = np.random.default_rng(4)
    poses = robot.fk(rng.uniform(robot.lower, robot.upper, (20, 6)))
    red = get_reduction(robot, None)
    chain = chain_poses(robot, poses)
    lo, hi = theta_range(robot, red, chain)
    cand, _ = search(red, chain, lo, hi, 64)
    q, geo, paper = certify.certify(robot, red, chain, poses, cand.pose, cand.theta, cand.branch)
    w = orientation_weight(robot.length_unit)
    ok = np.isfinite(q).all(axis=1)
    np.testing.assert_allclose(geo[ok], pose_error_geodesic(robot.fk(q[ok]), poses[cand.pose[ok]], w), atol=1e-9)
    assert np.all(np.isinf(geo[~ok]))
    # every pose has a certified candidate: its generating configuration's neighbourhood
    certified = ok & (geo <= 1e-9 * robot.length_scale)
    assert set(cand.pose[certified].tolist()) == set(range(len(poses)))


def test_every_branch_certified_at_once_is_each_branch_certified_alone() -> None:
    """``certify_every_branch`` takes each branch's FK on from the joints it shares with the one before
    (``_poe_fk_after``: a spherical wrist's flips share three, the shoulder's sides one): its configurations and both
    errors are ``certify``'s, which works out every branch's FK whole, bit for bit; on wrist-singular poses too, and
    on an arm whose two position branches coincide (the IRB 140's: all six joints shared)."""
    from sweepik.engine.chunk import chain_poses
    from sweepik.reductions import get_reduction

    for name in ("puma560", "ur5", "abb_irb140", "stanford"):
        robot = load_robot(name)
        rng = np.random.default_rng(7)
        q = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), (40, 6))
        q[:10, 4] = 0.0
        poses = robot.fk(q)
        red = get_reduction(robot, None)
        chain = chain_poses(robot, poses)
        every = certify.certify_every_branch(robot, red, chain, poses)
        nb = red.n_branches
        pose = np.repeat(np.arange(len(poses)), nb)
        branch = np.tile(np.arange(nb), len(poses))
        alone = certify.certify(robot, red, chain, poses, pose, np.zeros(pose.size), branch)
        shared = np.array([np.argmax(np.r_[a != b, True]) for a, b in zip(every[0][1:], every[0][:-1], strict=True)])
        assert (shared >= 1).sum() >= len(poses), name  # (branches do share joints)
        for x, y in zip(every, alone, strict=True):
            np.testing.assert_array_equal(x, y, err_msg=name)
