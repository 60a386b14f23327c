"""Forward kinematics, frames and the Jacobian (sweepik.model.kinematics through Robot)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_configs, random_dh_robot, rot_x, rot_z, trans
from hypothesis import given
from hypothesis import strategies as st
from numpy.typing import NDArray

from sweepik import Joint, Robot, load_robot

L1, L2 = 350.0, 402.0  # the paper's C-Arm link lengths (Table 1), mm


def carm_closed_form(q: NDArray[np.float64]) -> NDArray[np.float64]:
    """The paper's eq. (1a) = (1b) @ (1c), written out independently of sweepik, for q (N, 6)."""
    d1, t2, t3, t4, t5, t6 = q.T
    C2, S2 = np.cos(t2), np.sin(t2)
    C3, S3 = np.cos(t3), np.sin(t3)
    C34, S34 = np.cos(t3 + t4), np.sin(t3 + t4)
    C5, S5 = np.cos(t5), np.sin(t5)
    C6, S6 = np.cos(t6), np.sin(t6)
    zero, one = np.zeros_like(d1), np.ones_like(d1)
    B_2T = np.stack(
        [
            np.stack([C2, -S2, zero, zero], -1),
            np.stack([zero, zero, -one, zero], -1),
            np.stack([S2, C2, zero, d1], -1),
            np.stack([zero, zero, zero, one], -1),
        ],
        -2,
    )
    T2_W = np.stack(
        [
            np.stack([S34 * C5 * C6 + C34 * S6, C34 * C6 - S34 * C5 * S6, S34 * S5, S3 * L1 + C34 * L2], -1),
            np.stack([-S5 * C6, S5 * S6, C5, zero], -1),
            np.stack([C34 * C5 * C6 - S34 * S6, -S34 * C6 - C34 * C5 * S6, C34 * S5, C3 * L1 - S34 * L2], -1),
            np.stack([zero, zero, zero, one], -1),
        ],
        -2,
    )
    return B_2T @ T2_W


def assert_poses_close(
    T: NDArray[np.float64], T_ref: NDArray[np.float64], rel: float, length: float | NDArray[np.float64]
) -> None:
    """Rotations equal to ``rel``, translations equal to ``rel * length`` (length: a scale per pose)."""
    np.testing.assert_allclose(T[..., :3, :3], T_ref[..., :3, :3], rtol=0, atol=rel)
    scale = np.asarray(length, dtype=np.float64)[..., None]
    np.testing.assert_allclose(T[..., :3, 3] / scale, T_ref[..., :3, 3] / scale, rtol=0, atol=rel)
    np.testing.assert_array_equal(T[..., 3, :], np.broadcast_to([0.0, 0.0, 0.0, 1.0], T[..., 3, :].shape))


# --------------------------------------------------------------------------------------------------
# The C-Arm against the paper's closed form
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("spread", [1.0, 3.0], ids=["inside-limits", "3x-range"])
def test_carm_fk_equals_paper_closed_form(carm: Robot, rng: np.random.Generator, spread: float) -> None:
    q = random_configs(carm, rng, 10_000, spread=spread)
    if spread > 1:
        assert not np.all(carm.within_limits(q)), "the 3x sample must leave the limits"
    T = carm.fk(q)
    assert T.shape == (10_000, 4, 4)
    # 1e-9 relative: rotation entries are O(1); translations relative to the arm's reach at that d1.
    assert_poses_close(T, carm_closed_form(q), rel=1e-9, length=L1 + L2 + np.abs(q[:, 0]))


def test_carm_zero_pose_is_the_papers(carm: Robot) -> None:
    # At theta = 0 the closed form gives R = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]], p = (L2, -L1, d1).
    T = carm.fk([500.0, 0, 0, 0, 0, 0])
    expected = np.array([[0, 1, 0, L2], [-1, 0, 0, -L1], [0, 0, 1, 500.0], [0, 0, 0, 1]])
    np.testing.assert_allclose(T, expected, rtol=0, atol=1e-12 * (L1 + L2 + 500))


# --------------------------------------------------------------------------------------------------
# Shapes
# --------------------------------------------------------------------------------------------------


def test_single_configuration_gives_single_pose(carm: Robot, rng: np.random.Generator) -> None:
    q = random_configs(carm, rng, 1)[0]
    assert carm.fk(q).shape == (4, 4)
    assert carm.fk(q.tolist()).shape == (4, 4)
    assert carm.frames(q).shape == (carm.n_joints + 2, 4, 4)
    assert carm.jacobian(q).shape == (6, carm.n_joints)


@pytest.mark.parametrize("batch", [(), (1,), (3, 2), (2, 1, 3)])
def test_batched_shapes_match_elementwise(carm: Robot, rng: np.random.Generator, batch: tuple[int, ...]) -> None:
    q = random_configs(carm, rng, batch, spread=2.0)
    assert q.shape == (*batch, 6)
    n = carm.n_joints
    T, F, J = carm.fk(q), carm.frames(q), carm.jacobian(q)
    assert T.shape == (*batch, 4, 4)
    assert F.shape == (*batch, n + 2, 4, 4)
    assert J.shape == (*batch, 6, n)
    for idx in np.ndindex(*batch):
        np.testing.assert_allclose(T[idx], carm.fk(q[idx]), rtol=0, atol=1e-12 * 3000)
        np.testing.assert_allclose(F[idx], carm.frames(q[idx]), rtol=0, atol=1e-12 * 3000)
        np.testing.assert_allclose(J[idx], carm.jacobian(q[idx]), rtol=0, atol=1e-12 * 3000)


def test_frames_start_at_base_and_end_at_tool(rng: np.random.Generator) -> None:
    for convention in ("modified", "standard"):
        robot = random_dh_robot(rng, convention, n=5)
        q = random_configs(robot, rng, (4, 3))
        F = robot.frames(q)
        assert F.shape == (4, 3, 7, 4, 4)
        np.testing.assert_allclose(F[..., 0, :, :], np.broadcast_to(robot.T_world_base, (4, 3, 4, 4)), atol=0)
        np.testing.assert_allclose(F[..., -1, :, :], robot.fk(q), rtol=0, atol=1e-14)
        # The tool frame is the last link frame times T_flange_tool (not equal to it for a real tool).
        np.testing.assert_allclose(F[..., -1, :, :], F[..., -2, :, :] @ robot.T_flange_tool, rtol=0, atol=1e-14)
        assert not np.allclose(F[..., -1, :, :], F[..., -2, :, :])


def test_carm_frames_last_equals_fk(carm: Robot, rng: np.random.Generator) -> None:
    q = random_configs(carm, rng, 50, spread=3.0)
    F = carm.frames(q)
    np.testing.assert_array_equal(F[:, -1], carm.fk(q))
    np.testing.assert_array_equal(F[:, 0], np.broadcast_to(np.eye(4), (50, 4, 4)))
    # Frame 1 sits on the rail at height d1 (prismatic along base z).
    np.testing.assert_allclose(F[:, 1, :3, 3], np.stack([0 * q[:, 0], 0 * q[:, 0], q[:, 0]], -1), atol=1e-12)


# --------------------------------------------------------------------------------------------------
# DH conventions: a naive product of elementary transforms, and standard == modified equivalent
# --------------------------------------------------------------------------------------------------


def naive_fk(robot: Robot, q: NDArray[np.float64]) -> NDArray[np.float64]:
    """FK of one configuration as the literal product of elementary transforms of each convention."""
    T = robot.T_world_base.copy()
    for j, qi in zip(robot.joints, q, strict=True):
        theta = j.theta + (qi if j.is_revolute else 0.0)
        d = j.d + (0.0 if j.is_revolute else qi)
        if robot.dh_convention == "modified":
            T = T @ rot_x(j.alpha) @ trans(x=j.a) @ rot_z(theta) @ trans(z=d)
        else:
            T = T @ rot_z(theta) @ trans(z=d) @ trans(x=j.a) @ rot_x(j.alpha)
    return T @ robot.T_flange_tool


@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_fk_is_product_of_elementary_transforms(rng: np.random.Generator, convention: str) -> None:
    for _ in range(20):
        robot = random_dh_robot(rng, convention)
        q = random_configs(robot, rng, 5, spread=3.0)
        T = robot.fk(q)
        for k in range(5):
            np.testing.assert_allclose(T[k], naive_fk(robot, q[k]), rtol=0, atol=1e-12)


def modified_equivalent(std: Robot) -> Robot:
    """The same arm in Craig's modified convention: row i takes a_{i-1}, alpha_{i-1} of standard row i-1,
    row 1 has a = alpha = 0, and the last standard row's TransX(a_n) RotX(alpha_n) moves into the tool."""
    a = [0.0, *(j.a for j in std.joints[:-1])]
    alpha = [0.0, *(j.alpha for j in std.joints[:-1])]
    joints = tuple(
        Joint(j.type, a=ai, alpha=al, d=j.d, theta=j.theta, lower=j.lower, upper=j.upper, name=j.name)
        for j, ai, al in zip(std.joints, a, alpha, strict=True)
    )
    last = std.joints[-1]
    tool = trans(x=last.a) @ rot_x(last.alpha) @ std.T_flange_tool
    return Robot(std.name + "_mod", joints, "modified", std.T_world_base, tool, std.length_unit)


@given(seed=st.integers(0, 2**32 - 1))
def test_standard_and_modified_equivalent_give_identical_fk(seed: int) -> None:
    rng = np.random.default_rng(seed)
    std = random_dh_robot(rng, "standard")
    mod = modified_equivalent(std)
    q = random_configs(std, rng, 20, spread=3.0)
    np.testing.assert_allclose(mod.fk(q), std.fk(q), rtol=0, atol=1e-12)
    # Same joint axes, so the same Jacobian (the standard one uses z of frame i-1, the modified z of frame i).
    np.testing.assert_allclose(mod.jacobian(q), std.jacobian(q), rtol=0, atol=1e-12)


def test_standard_table_read_as_modified_differs(rng: np.random.Generator) -> None:
    """Guards the test above: the two conventions really are different maps."""
    std = random_dh_robot(rng, "standard", n=6)
    same_rows = Robot("m", std.joints, "modified", std.T_world_base, std.T_flange_tool)
    q = random_configs(std, rng, 5)
    assert np.abs(std.fk(q) - same_rows.fk(q)).max() > 1e-3


def test_puma560_modified_and_standard_bundles_agree(puma: Robot, puma_std: Robot, rng: np.random.Generator) -> None:
    for spread in (1.0, 3.0):
        q = random_configs(puma, rng, 2000, spread=spread)
        np.testing.assert_allclose(puma.fk(q), puma_std.fk(q), rtol=0, atol=1e-12)
        np.testing.assert_allclose(puma.jacobian(q), puma_std.jacobian(q), rtol=0, atol=1e-12)


# --------------------------------------------------------------------------------------------------
# Jacobian against central finite differences of fk
# --------------------------------------------------------------------------------------------------


def finite_difference_jacobian(robot: Robot, q: NDArray[np.float64], h: float) -> NDArray[np.float64]:
    """(6, n): linear part from the tool position, angular part from (dR/dq_i) R^T (a skew matrix)."""
    n = robot.n_joints
    J = np.empty((6, n))
    R = robot.fk(q)[:3, :3]
    for i in range(n):
        e = np.zeros(n)
        e[i] = h
        Tp, Tm = robot.fk(q + e), robot.fk(q - e)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ R.T
        J[3:, i] = 0.5 * np.array([W[2, 1] - W[1, 2], W[0, 2] - W[2, 0], W[1, 0] - W[0, 1]])
    return J


@pytest.mark.parametrize("name", ["carm", "puma560", "puma560_std"])
def test_jacobian_matches_finite_differences(name: str, rng: np.random.Generator) -> None:
    robot = load_robot(name)
    q = random_configs(robot, rng, 30, spread=2.0)
    J = robot.jacobian(q)
    reach = robot.length_scale
    for k in range(len(q)):
        Jfd = finite_difference_jacobian(robot, q[k], h=1e-6)
        # Central differences: truncation ~h^2 * reach, rounding ~eps * reach / h, both < 1e-7 * reach.
        np.testing.assert_allclose(J[k, :3], Jfd[:3], rtol=0, atol=1e-7 * reach)
        np.testing.assert_allclose(J[k, 3:], Jfd[3:], rtol=0, atol=1e-7)


@given(seed=st.integers(0, 2**32 - 1), convention=st.sampled_from(["modified", "standard"]))
def test_jacobian_matches_finite_differences_random_arms(seed: int, convention: str) -> None:
    rng = np.random.default_rng(seed)
    robot = random_dh_robot(rng, convention)
    q = random_configs(robot, rng, 1, spread=3.0)[0]
    Jfd = finite_difference_jacobian(robot, q, h=1e-6)
    np.testing.assert_allclose(robot.jacobian(q), Jfd, rtol=0, atol=1e-7 * max(1.0, robot.length_scale))


def test_prismatic_jacobian_column_is_the_axis(carm: Robot, rng: np.random.Generator) -> None:
    # The C-Arm's rail moves the tool along base z and does not rotate it.
    J = carm.jacobian(random_configs(carm, rng, 10, spread=3.0))
    np.testing.assert_allclose(J[:, :, 0], np.broadcast_to([0, 0, 1, 0, 0, 0], (10, 6)), atol=1e-15)
