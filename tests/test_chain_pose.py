"""World tool poses to chain poses (``engine.chain_pose``): the arm's base and tool frames taken off, each only where
the arm has one; what a target that is not finite gives (NaN, no error: the solver's checks say what is wrong)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from rewrites import random_transform

from sweepik import load_robot, solve
from sweepik.engine.chain_pose import chain_poses

UR5 = load_robot("ur5")


@pytest.mark.parametrize("frames", ["base", "tool", "both"])
def test_chain_poses_take_the_frames_off(frames: str) -> None:
    rng = np.random.default_rng(len(frames))
    base = random_transform(rng, 0.5) if frames != "tool" else np.eye(4)
    tool = random_transform(rng, 0.2) if frames != "base" else np.eye(4)
    arm = dataclasses.replace(UR5, T_world_base=base, T_flange_tool=tool)
    q = rng.uniform(-np.pi, np.pi, (50, 6))
    chain = chain_poses(arm, arm.fk(q))
    np.testing.assert_allclose(chain, UR5.fk(q), atol=1e-12)
    expected = np.linalg.inv(base) @ arm.fk(q) @ np.linalg.inv(tool)
    np.testing.assert_allclose(chain, expected, atol=1e-13)
    # the solutions of a target are those of its chain pose on the arm without frames
    T = arm.fk(q[0])
    np.testing.assert_allclose(solve(arm, T).q, solve(UR5, chain[0]).q, atol=1e-9)


def test_an_arm_without_frames_solves_its_targets_as_given() -> None:
    P = UR5.fk(np.zeros((3, 6)))
    assert chain_poses(UR5, P) is P


def test_a_target_not_finite_gives_nan_not_an_error() -> None:
    arm = dataclasses.replace(UR5, T_flange_tool=random_transform(np.random.default_rng(0), 0.1))
    P = arm.fk(np.zeros((2, 6)))
    P[1, 0, 3] = np.nan
    chain = chain_poses(arm, P)
    assert np.isfinite(chain[0]).all()
    assert np.isnan(chain[1, 0]).any()
