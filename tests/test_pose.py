"""Z-Y-Z Euler angles, pose construction and the pose error metrics (sweepik.model.pose)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import axis_angle, random_pose, random_rotation
from hypothesis import given
from hypothesis import strategies as st
from numpy.typing import NDArray

from sweepik import (
    load_robot,
    matrix_from_zyz,
    pose_error_geodesic,
    pose_error_paper,
    pose_from_xyz_zyz,
    rotation_angle,
    wrap_angle,
    xyz_zyz_from_pose,
    zyz_from_matrix,
)
from sweepik.model.pose import GIMBAL_TOL

angles = st.floats(-np.pi, np.pi, allow_nan=False)
#: Betas at and near both gimbal cases, and regular ones.
GIMBAL_BETAS = [
    0.0,
    1e-15,
    1e-13,
    1e-11,
    1e-9,
    1e-7,
    0.5 * GIMBAL_TOL,
    2 * GIMBAL_TOL,
    1e-3,
    np.pi - 1e-3,
    np.pi - 1e-7,
    np.pi - 1e-9,
    np.pi - 1e-11,
    np.pi - 1e-15,
    np.pi,
]


def rz(a: float) -> NDArray[np.float64]:
    return axis_angle(np.array([0.0, 0.0, 1.0]), a)


def ry(a: float) -> NDArray[np.float64]:
    return axis_angle(np.array([0.0, 1.0, 0.0]), a)


def pose(R: NDArray[np.float64], p: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


# --------------------------------------------------------------------------------------------------
# Z-Y-Z Euler angles
# --------------------------------------------------------------------------------------------------


def test_matrix_from_zyz_is_rz_ry_rz() -> None:
    # Craig's Z-Y-Z: R = Rz(alpha) Ry(beta) Rz(gamma), built here from Rodrigues rotations.
    a, b, g = 0.3, 1.1, -2.0
    np.testing.assert_allclose(matrix_from_zyz([a, b, g]), rz(a) @ ry(b) @ rz(g), rtol=0, atol=1e-15)


def test_zyz_round_trip_random_rotations(rng: np.random.Generator) -> None:
    R = np.stack([random_rotation(rng) for _ in range(2000)])
    e = zyz_from_matrix(R)
    assert e.shape == (2000, 3)
    np.testing.assert_allclose(matrix_from_zyz(e), R, rtol=0, atol=1e-14)
    assert np.all((e[:, 1] >= 0) & (e[:, 1] <= np.pi))
    assert np.all(np.abs(e[:, [0, 2]]) <= np.pi)


@given(alpha=angles, beta=st.floats(1e-3, np.pi - 1e-3), gamma=angles)
def test_zyz_angles_round_trip_away_from_gimbal(alpha: float, beta: float, gamma: float) -> None:
    e = zyz_from_matrix(matrix_from_zyz([alpha, beta, gamma]))
    # Compare angles modulo 2 pi (alpha = -pi and pi are the same angle); beta in (0, pi) is unique.
    np.testing.assert_allclose(wrap_angle(e - [alpha, beta, gamma]), 0.0, atol=1e-11)


@pytest.mark.parametrize("beta", [0.0, np.pi])
@pytest.mark.parametrize(("alpha", "gamma"), [(0.0, 0.0), (0.4, -1.3), (2.5, 2.0), (-3.0, 3.1)])
def test_zyz_exact_gimbal_chooses_alpha_zero(alpha: float, gamma: float, beta: float) -> None:
    R = rz(alpha) @ ry(beta) @ rz(gamma)
    a, b, g = zyz_from_matrix(R)
    assert a == 0.0
    assert b == beta
    # Only alpha + gamma (beta = 0) or alpha - gamma (beta = pi) is defined; with alpha = 0 ...
    expected_gamma = alpha + gamma if beta == 0.0 else gamma - alpha
    np.testing.assert_allclose(wrap_angle(g - expected_gamma), 0.0, atol=1e-14)
    np.testing.assert_allclose(matrix_from_zyz([a, b, g]), R, rtol=0, atol=1e-14)


@pytest.mark.parametrize("beta", GIMBAL_BETAS)
def test_zyz_reproduces_rotations_from_zyz_at_and_near_gimbal(beta: float, rng: np.random.Generator) -> None:
    a, g = rng.uniform(-np.pi, np.pi, (2, 200))
    R = matrix_from_zyz(np.stack([a, np.full_like(a, beta), g], -1))
    e = zyz_from_matrix(R)
    np.testing.assert_allclose(matrix_from_zyz(e), R, rtol=0, atol=1e-12)
    assert np.all((e[:, 1] >= 0) & (e[:, 1] <= np.pi))


@pytest.mark.parametrize("beta", [1e-11, 1e-9, np.pi - 1e-9, np.pi - 1e-11])
def test_zyz_reproduces_generic_rotations_near_gimbal(beta: float, rng: np.random.Generator) -> None:
    """Rotations near gimbal lock carrying ordinary rounding (~1e-16 in every entry) must round trip too."""
    worst = 0.0
    for _ in range(200):
        a, g = rng.uniform(-np.pi, np.pi, 2)
        Q = random_rotation(rng)
        R = ((rz(a) @ ry(beta) @ rz(g)) @ Q) @ Q.T  # the same rotation, with rounding in small entries
        worst = max(worst, float(np.abs(matrix_from_zyz(zyz_from_matrix(R)) - R).max()))
    assert worst <= 1e-12


def test_zyz_alpha_and_gamma_in_half_open_range() -> None:
    R = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, -0.0], [1.0, 0.0, 0.0]])  # Ry(-pi/2); r23 = -0.0
    R2 = np.array([[-1.0, -0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, 1.0]])  # Rz(pi) at the gimbal, r12 = -0.0
    e = zyz_from_matrix(np.stack([R, R2]))
    np.testing.assert_allclose(matrix_from_zyz(e), np.stack([R, R2]), atol=1e-15)
    assert np.all((e[:, [0, 2]] > -np.pi) & (e[:, [0, 2]] <= np.pi)), e


def test_zyz_accepts_poses_and_batches(rng: np.random.Generator) -> None:
    T = np.stack([random_pose(rng, 10.0) for _ in range(6)]).reshape(3, 2, 4, 4)
    e = zyz_from_matrix(T)
    assert e.shape == (3, 2, 3)
    np.testing.assert_array_equal(e, zyz_from_matrix(T[..., :3, :3]))
    assert zyz_from_matrix(T[0, 0]).shape == (3,)


def test_pose_from_and_to_xyz_zyz(rng: np.random.Generator) -> None:
    xyz = rng.uniform(-5, 5, (4, 3))
    zyz = np.stack([rng.uniform(-3, 3, 4), rng.uniform(0.1, 3, 4), rng.uniform(-3, 3, 4)], -1)
    T = pose_from_xyz_zyz(xyz, zyz)
    assert T.shape == (4, 4, 4)
    np.testing.assert_array_equal(T[:, 3], np.broadcast_to([0, 0, 0, 1.0], (4, 4)))
    p, e = xyz_zyz_from_pose(T)
    np.testing.assert_array_equal(p, xyz)
    np.testing.assert_allclose(e, zyz, atol=1e-12)
    # Broadcasting: one orientation for many positions.
    assert pose_from_xyz_zyz(xyz, zyz[0]).shape == (4, 4, 4)


@pytest.mark.parametrize(
    ("x", "expected"),
    [
        (0.0, 0.0),
        (np.pi, np.pi),
        (-np.pi, np.pi),
        (3 * np.pi, np.pi),
        (2 * np.pi, 0.0),
        (-0.5, -0.5),
        (np.pi + 0.25, -np.pi + 0.25),
        (-7.0, -7.0 + 2 * np.pi),
    ],
)
def test_wrap_angle_into_half_open_interval(x: float, expected: float) -> None:
    np.testing.assert_allclose(wrap_angle(x), expected, rtol=0, atol=1e-15)
    assert -np.pi < wrap_angle(x) <= np.pi


# --------------------------------------------------------------------------------------------------
# The paper's error J (eq. 6)
# --------------------------------------------------------------------------------------------------


def test_pose_error_paper_is_zero_for_identical_poses(rng: np.random.Generator) -> None:
    T = np.stack([random_pose(rng, 1000.0) for _ in range(500)])
    np.testing.assert_array_equal(pose_error_paper(T, T), np.zeros(500))


@pytest.mark.parametrize("beta", GIMBAL_BETAS)
def test_pose_error_paper_zero_for_identical_gimbal_poses(beta: float) -> None:
    T = pose_from_xyz_zyz([1.0, 2.0, 3.0], [0.7, beta, -2.1])
    assert pose_error_paper(T, T) == 0.0


def test_pose_error_paper_zero_at_carm_zero_pose() -> None:
    carm = load_robot("carm")
    T = carm.fk([500.0, 0, 0, 0, 0, 0])
    assert zyz_from_matrix(T)[1] == 0.0  # a gimbal pose
    assert pose_error_paper(T, T) == 0.0
    # The same pose written with another split of alpha + gamma is still the same pose.
    other = pose_from_xyz_zyz(T[:3, 3], [1.0, 0.0, -np.pi / 2 - 1.0])
    np.testing.assert_allclose(other, T, atol=1e-12)
    assert pose_error_paper(other, T) < 1e-9


@pytest.mark.parametrize("beta", [0.0, 0.3 * GIMBAL_TOL, np.pi - 0.3 * GIMBAL_TOL, np.pi])
def test_pose_error_paper_ignores_split_of_gimbal_angles(beta: float) -> None:
    # alpha + gamma (beta ~ 0) or alpha - gamma (beta ~ pi) fixed, split changed by 0.5 rad.
    s = -1.0 if beta < 1 else 1.0
    T1 = pose_from_xyz_zyz([0.0, 0.0, 0.0], [0.3, beta, 0.4])
    T2 = pose_from_xyz_zyz([0.0, 0.0, 0.0], [0.8, beta, 0.4 + s * 0.5])
    # The poses differ by at most ~2 sin(beta/2) * 0.5 rad, so J is at most about 100 mm times that.
    assert pose_error_paper(T1, T2) <= 100.0 * 1e-4
    assert pose_error_paper(T1, T2) <= 100.0 * (rotation_angle(T1[:3, :3].T @ T2[:3, :3]) + 1e-9)


def test_pose_error_paper_across_gimbal_band_measures_beta() -> None:
    # One pose exactly at beta = 0, the other inside the band with the same alpha + gamma: J = 100 * d(beta).
    T1 = pose_from_xyz_zyz([0.0, 0.0, 0.0], [0.0, 0.0, 0.7])
    T2 = pose_from_xyz_zyz([0.0, 0.0, 0.0], [0.3, 0.5 * GIMBAL_TOL, 0.4])
    np.testing.assert_allclose(pose_error_paper(T2, T1), 100.0 * 0.5 * GIMBAL_TOL, rtol=1e-6)


@pytest.mark.parametrize("which", [0, 2])
def test_pose_error_paper_wraps_angle_differences(which: int) -> None:
    e1 = np.array([0.2, 1.0, -0.4])
    e2 = e1.copy()
    e1[which], e2[which] = np.radians(179.9), np.radians(-179.9)
    J = pose_error_paper(pose_from_xyz_zyz([0, 0, 0], e1), pose_from_xyz_zyz([0, 0, 0], e2))
    np.testing.assert_allclose(J, 100.0 * np.radians(0.2), rtol=1e-9)


def test_pose_error_paper_matches_hand_computation_of_eq6() -> None:
    e1, e2 = np.array([0.10, 0.50, 0.20]), np.array([0.15, 0.45, 0.10])
    p1, p2 = np.array([1.0, 2.0, 3.0]), np.array([1.3, 1.6, 3.5])
    T1, T2 = pose_from_xyz_zyz(p1, e1), pose_from_xyz_zyz(p2, e2)
    Jp = np.sqrt(0.3**2 + 0.4**2 + 0.5**2)
    Jo = np.sqrt(0.05**2 + 0.05**2 + 0.10**2)
    np.testing.assert_allclose(pose_error_paper(T1, T2), np.sqrt(Jp**2 + (100.0 * Jo) ** 2), rtol=1e-12)
    np.testing.assert_allclose(pose_error_paper(T1, T2, weight=1.0), np.sqrt(Jp**2 + Jo**2), rtol=1e-12)
    np.testing.assert_allclose(pose_error_paper(T1, T2, weight=0.0), Jp, rtol=1e-12)


def test_pose_error_paper_batches(rng: np.random.Generator) -> None:
    T = np.stack([random_pose(rng) for _ in range(6)]).reshape(2, 3, 4, 4)
    Td = random_pose(rng)
    J = pose_error_paper(T, Td)
    assert J.shape == (2, 3)
    for idx in np.ndindex(2, 3):
        np.testing.assert_allclose(J[idx], pose_error_paper(T[idx], Td), rtol=1e-15)


# --------------------------------------------------------------------------------------------------
# Geodesic error and rotation angle
# --------------------------------------------------------------------------------------------------


def test_pose_error_geodesic_is_distance_plus_weighted_angle(rng: np.random.Generator) -> None:
    for _ in range(200):
        Td = random_pose(rng, 500.0)
        angle = rng.uniform(0.0, np.pi)
        T = np.eye(4)
        T[:3, :3] = Td[:3, :3] @ axis_angle(rng.normal(size=3), angle)
        T[:3, 3] = Td[:3, 3] + rng.normal(size=3)
        expected = np.linalg.norm(T[:3, 3] - Td[:3, 3]) + 100.0 * angle
        np.testing.assert_allclose(pose_error_geodesic(T, Td), expected, rtol=1e-7)
        np.testing.assert_allclose(pose_error_geodesic(T, Td, weight=2.0), expected - 98.0 * angle, rtol=1e-7)


def test_pose_error_geodesic_zero_for_identical_poses(rng: np.random.Generator) -> None:
    T = np.stack([random_pose(rng, 1000.0) for _ in range(100)] + [load_robot("carm").fk([500.0, 0, 0, 0, 0, 0])])
    np.testing.assert_allclose(pose_error_geodesic(T, T), 0.0, rtol=0, atol=1e-12)


@pytest.mark.parametrize("angle", [1e-14, 1e-10, 1e-7, 1e-4, 0.5, 2.0, np.pi - 1e-6, np.pi])
def test_rotation_angle_accurate(angle: float, rng: np.random.Generator) -> None:
    for _ in range(20):
        R = axis_angle(rng.normal(size=3), angle)
        got = rotation_angle(R)
        # Relative accuracy even for tiny angles (arccos of the trace would lose everything below ~1e-8).
        rtol = 1e-6 if angle > np.pi - 1e-3 else 1e-9
        np.testing.assert_allclose(got, angle, rtol=rtol)
        assert 0.0 <= got <= np.pi


def test_rotation_angle_batches_and_identity(rng: np.random.Generator) -> None:
    R = np.stack([random_rotation(rng) for _ in range(6)]).reshape(3, 2, 3, 3)
    assert rotation_angle(R).shape == (3, 2)
    assert rotation_angle(np.eye(3)) == 0.0
    # The angle of R equals that of R^T and of Q R Q^T.
    Q = random_rotation(rng)
    np.testing.assert_allclose(rotation_angle(np.swapaxes(R, -1, -2)), rotation_angle(R), rtol=1e-12)
    np.testing.assert_allclose(rotation_angle(Q @ R @ Q.T), rotation_angle(R), rtol=1e-9)


def test_compiled_wrap_is_the_numpy_wrap_bit_for_bit() -> None:
    """``_wrap.wrap_pi`` (compiled code's wrap, with a fast path for |pi - x| < 2 pi) gives exactly what the NumPy
    expression gives: at the fast path's ends, at multiples of pi, at +-0, an ulp from the ends, far out, inf, NaN."""
    numba = pytest.importorskip("numba")
    from sweepik.subproblems.trig import wrap_pi

    @numba.njit
    def wrapped(xs: NDArray[np.float64]) -> NDArray[np.float64]:
        out = np.empty_like(xs)
        for k in range(xs.shape[0]):
            out[k] = wrap_pi(xs[k])
        return out

    special = [0.0, -0.0, np.pi, -np.pi, 2 * np.pi, -2 * np.pi, 3 * np.pi, -3 * np.pi, 1e300, -1e300, np.inf, -np.inf]
    edges = np.array([np.pi, -np.pi, 3 * np.pi, 2 * np.pi, 0.0])
    near = np.concatenate([np.nextafter(edges, np.inf), np.nextafter(edges, -np.inf)])
    xs = np.concatenate([special, near, np.random.default_rng(3).uniform(-20.0, 20.0, 20_000), [np.nan]])
    with np.errstate(invalid="ignore"):
        ref = np.pi - np.mod(np.pi - xs, 2.0 * np.pi)
    got = wrapped(xs)
    assert np.array_equal(got, ref, equal_nan=True)
    assert np.array_equal(np.signbit(got), np.signbit(ref))
