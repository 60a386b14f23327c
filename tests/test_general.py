"""The general method (issue 37): arms no structured decomposition covers, solved by elimination.

Random arms without structure (``general_arms.random_arm``: 6R, 5R1P, 4R2P, random base and tool), configurations
uniform over a turn and on or next to the singular set: every generating configuration comes back
(``singular.recovered``), every solution reproduces the pose, and the sets equal a many-start numerical search's. The
full measurement (20 + 10 arms, 250 poses each, ssik beside) is ``scripts/general_arms.py``.
"""

from __future__ import annotations

import numpy as np
import pytest
from general_arms import poses_of, random_arm
from oracles import numerical_solutions, pose_errors, same_solution_set
from singular import recovered

import sweepik
from sweepik import NoReductionError
from sweepik.reductions.decompose import plans

ARMS = [("6r", 0), ("6r", 1), ("5r1p", 0), ("4r2p", 1)]


@pytest.mark.parametrize(("kind", "seed"), ARMS)
def test_random_arm_without_structure_recovers_every_configuration(kind: str, seed: int) -> None:
    robot = random_arm(kind, seed)
    assert plans(robot) == ()
    assert sweepik.analyze(robot)["chosen"]["family"] == "general"
    Q = poses_of(robot, 40, 12, seed=seed)
    T = robot.fk(Q)
    batch = sweepik.solve_many(robot, T, limits=False)
    for k, (q, sols) in enumerate(zip(Q, batch, strict=True)):
        assert recovered(robot, sols, q), (kind, seed, k, q.tolist())
        if len(sols):
            dp, ang = pose_errors(robot.fk(sols.q), T[k], robot.length_scale)
            assert np.all(np.maximum(dp, ang) <= 1e-9), (k, dp, ang)
    # one call per pose gives the same sets as the batch
    for k in (0, 1, len(Q) - 1):
        single = sweepik.solve(robot, T[k], limits=False)
        assert same_solution_set(single.q, batch[k].q, robot.is_revolute, robot.length_scale)


@pytest.mark.parametrize(("kind", "seed"), ARMS)
def test_random_arm_without_structure_agrees_with_a_numerical_search(kind: str, seed: int) -> None:
    robot = random_arm(kind, seed)
    Q = poses_of(robot, 3, 0, seed=100 + seed)
    for q in Q:
        T = robot.fk(q)
        ours = sweepik.solve(robot, T, limits=False)
        num = numerical_solutions(robot, T, n_starts=400, full_circle=True)
        assert same_solution_set(ours.q, num, robot.is_revolute, robot.length_scale), (ours.q, num)


def test_general_method_applies_limits() -> None:
    """Limits around one solution keep that one alone; without limits the others come back too."""
    q = np.array([0.3, -0.2, 0.5, 1.0, -0.7, 0.2])
    robot = random_arm("6r", 2)
    T = robot.fk(q)
    assert len(sweepik.solve(robot, T, limits=False)) >= 2
    tight = random_arm("6r", 2, around=q)
    inside = sweepik.solve(tight, T)
    assert len(inside) == 1 and np.allclose(inside.q[0], q, atol=1e-8)


def test_free_joint_is_refused_for_the_general_method() -> None:
    robot = random_arm("6r", 0)
    with pytest.raises(NoReductionError, match="no decomposition sweeps"):
        sweepik.solve(robot, robot.fk(np.zeros(6)), free_joint=2)
