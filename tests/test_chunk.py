"""One chunk of poses solved by one reduction (sweepik.engine.chunk): a batch's chunk gives each pose what a single
solve gives it, the chain poses take the base and tool off, and a prismatic theta* without finite limits is
refused."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from sweepik import ShapeError, load_robot, solve, solve_many
from sweepik.engine import chunk
from sweepik.reductions import get_reduction


def test_a_chunk_gives_each_pose_its_single_solve() -> None:
    """``solve_chunk`` of 12 KR 6 poses (two of them singular) gives each pose the solutions ``solve`` gives it alone,
    in the same order, to rounding."""
    robot = load_robot("kuka_kr6_r900")
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.lower, robot.upper, (12, 6))
    q[:2, 4] = 0.0  # wrist singular
    poses = robot.fk(q)
    red = get_reduction(robot, None)
    block = chunk.solve_chunk(robot, red, poses, "precise", True, 64)
    for i, T in enumerate(poses):
        one, mine = solve(robot, T), block.solutions(i)
        assert len(one) == len(mine) and len(one.families) == len(mine.families)
        np.testing.assert_allclose(mine.q, one.q, atol=1e-9)


def test_chain_poses_take_base_and_tool_off() -> None:
    """``chain_poses(robot, FK(q))`` is the pose of the bare chain (identity base and tool) at q."""
    robot = load_robot("ur5")
    base = np.eye(4)
    base[:3, 3] = [0.1, -0.2, 0.3]
    base[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    tool = np.eye(4)
    tool[:3, 3] = [0.0, 0.0, 0.12]
    moved = dataclasses.replace(robot, T_world_base=base, T_flange_tool=tool)
    q = np.random.default_rng(0).uniform(-2.0, 2.0, (5, 6))
    np.testing.assert_allclose(chunk.chain_poses(moved, moved.fk(q)), robot.fk(q), atol=1e-12)


def test_a_prismatic_theta_without_finite_limits_is_refused() -> None:
    """The C-Arm's rail (theta* of carm-d1) with limits +-1e308 (a range that overflows) cannot be swept over its
    limits (the paper's strategy sweeps them): ``theta_range`` says so."""
    robot = load_robot("carm")
    joints = list(robot.joints)
    joints[0] = dataclasses.replace(joints[0], lower=-1e308, upper=1e308)
    open_rail = dataclasses.replace(robot, joints=tuple(joints))
    red = get_reduction(open_rail, "carm-d1")
    chain = chunk.chain_poses(open_rail, open_rail.fk(np.zeros((1, 6))))
    with pytest.raises(ShapeError, match="finite limits"):
        chunk.theta_range(open_rail, red, chain, paper_limits=True)


def test_the_c_arms_theta2_blind_spot_is_swept_by_the_d1_reduction() -> None:
    """The C-Arm swept on theta2 is blind at theta2 = +-90 deg with the wrist near the rail's axis (``CArmTheta2.
    blind_spot``): there the d1 reduction's sweep (compiled, like every search where the reduction has kernels)
    supplies the solutions. Poses around it: the same solution sets as the d1 reduction alone, the generating
    configuration among them (limits off; a family is compared by its presence)."""
    from oracles import same_solution_set
    from singular import recovered

    robot = load_robot("carm")
    rng = np.random.default_rng(5)
    q = rng.uniform(robot.lower, robot.upper, (60, 6))
    q[:, 1] = np.where(rng.random(60) < 0.5, np.pi / 2, -np.pi / 2) + rng.normal(0.0, 0.02, 60)
    poses = robot.fk(q)
    blind = get_reduction(robot, "carm-theta2").blind_spot(chunk.chain_poses(robot, poses))
    assert blind is not None and blind[0].size >= 10  # (the case is exercised)
    theta2 = solve_many(robot, poses, reduction="carm-theta2", limits=False)
    d1 = solve_many(robot, poses, reduction="carm-d1", limits=False)
    for k in range(len(q)):
        assert recovered(robot, theta2[k], q[k]), k
        assert bool(theta2[k].families) == bool(d1[k].families), k
        if not theta2[k].families:
            assert same_solution_set(theta2[k].q, d1[k].q, robot.is_revolute, robot.length_scale), k
