"""Pose helpers: Z-Y-Z Euler angles (Craig's convention), pose construction and pose error metrics.

Conventions
-----------
* A pose is a homogeneous transform ``(..., 4, 4)``; rotations are ``(..., 3, 3)``.
* ``R = Rz(alpha) @ Ry(beta) @ Rz(gamma)`` (Craig 2005, Z-Y-Z Euler angles), radians,
  ``beta`` in [0, pi], ``alpha`` and ``gamma`` in (-pi, pi].
* At the gimbal cases ``beta = 0`` (only ``alpha + gamma`` is defined) and ``beta = pi`` (only
  ``alpha - gamma``), Craig's choice ``alpha = 0`` is made (for sin(beta) <= 1e-12, where alpha would be
  rounding noise).
* Errors are in the robot's length unit; the orientation part is weighted by a length (default
  100 mm, the paper's choice) that turns radians into that unit.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import ShapeError
from sweepik.model.validate import as_float_array, check_finite, check_rotations

__all__ = [
    "GIMBAL_TOL",
    "zyz_from_matrix",
    "matrix_from_zyz",
    "pose_from_xyz_zyz",
    "xyz_zyz_from_pose",
    "matrix_from_rpy",
    "rpy_from_matrix",
    "pose_from_xyz_rpy",
    "wrap_angle",
    "rotation_angle",
    "pose_error_paper",
    "pose_error_geodesic",
]

#: Below this beta (or pi - beta), in radians, alpha and gamma of a Z-Y-Z decomposition are only
#: defined through their sum (difference). alpha is computed from matrix entries of size sin(beta), so its
#: rounding error is about 2e-16 / sin(beta): at 1e-4 rad that is 2e-12 rad, i.e. 2e-10 mm of J at the
#: paper's 100 mm weight. Inside the band the gimbal form is used (see ``pose_error_paper``).
GIMBAL_TOL = 1e-4

Array = NDArray[np.float64]

#: sin(beta) at or below which a rotation is treated as exactly gimbal-locked by ``zyz_from_matrix``
#: (alpha from entries this small would be pure rounding noise).
_EXACT_GIMBAL = 1e-12


def _floats(x: ArrayLike, what: str) -> Array:
    """``x`` as a float64 array (an array that already is one passes as it is; others: ``as_float_array``)."""
    if isinstance(x, np.ndarray) and x.dtype == np.float64:
        return x
    return as_float_array(x, what)


def _trailing(x: ArrayLike, what: str, shape: tuple[int, ...], finite: bool = True) -> Array:
    """``x`` as floats whose last dimensions are ``shape`` (ShapeError otherwise), finite if asked."""
    arr = _floats(x, what)
    if arr.shape[arr.ndim - len(shape) :] != shape or arr.ndim < len(shape):
        want = ", ".join(str(k) for k in shape)
        raise ShapeError(f"{what} must have shape (..., {want}), got {arr.shape}")
    if finite:
        check_finite(arr, what)
    return arr


def _pose_pair(T: ArrayLike, T_desired: ArrayLike) -> tuple[Array, Array]:
    """Two stacks of poses ``(..., 4, 4)`` that broadcast together (ShapeError otherwise; values not checked)."""
    a = _trailing(T, "T", (4, 4), finite=False)
    b = _trailing(T_desired, "T_desired", (4, 4), finite=False)
    if a.shape != b.shape:
        try:
            np.broadcast_shapes(a.shape, b.shape)
        except ValueError:
            raise ShapeError(f"T {a.shape} and T_desired {b.shape} do not broadcast together") from None
    return a, b


def wrap_angle(x: ArrayLike) -> Array:
    """Wrap angles (radians) into (-pi, pi]."""
    x = _floats(x, "angles")
    return np.pi - np.mod(np.pi - x, 2.0 * np.pi)


def zyz_from_matrix(R: ArrayLike) -> Array:
    """Z-Y-Z Euler angles ``(..., 3)`` = (alpha, beta, gamma) in radians of rotations ``(..., 3, 3)``.

    Also accepts poses ``(..., 4, 4)`` (the rotation block is used). A matrix that is not a rotation (not
    orthonormal with det +1, to 1e-6), or not finite, is refused (a SweepikError).

    >>> import numpy as np
    >>> np.round(zyz_from_matrix(matrix_from_zyz([0.1, 0.2, 0.3])), 12).tolist()
    [0.1, 0.2, 0.3]
    """
    arr = _floats(R, "R")
    if arr.ndim < 2 or arr.shape[-2:] not in ((3, 3), (4, 4)):
        raise ShapeError(f"R must have shape (..., 3, 3) or (..., 4, 4), got {arr.shape}")
    check_finite(arr, "R")
    check_rotations(arr[..., :3, :3], "R")
    return _zyz(arr)


def _zyz(R: Array) -> Array:
    """``zyz_from_matrix`` without its checks."""
    R = R[..., :3, :3]
    r13, r23, r33 = R[..., 0, 2], R[..., 1, 2], R[..., 2, 2]
    r31, r32 = R[..., 2, 0], R[..., 2, 1]
    sb = np.hypot(r31, r32)
    beta = np.arctan2(sb, r33)
    alpha = np.arctan2(r23, r13)
    # gamma from the first two columns rotated back by alpha: well conditioned for every beta
    ca, sa = np.cos(alpha), np.sin(alpha)
    gamma = np.arctan2(ca * R[..., 1, 0] - sa * R[..., 0, 0], ca * R[..., 1, 1] - sa * R[..., 0, 1])
    # Gimbal cases (exactly degenerate up to rounding): Craig's choice alpha = 0.
    zero = sb <= _EXACT_GIMBAL
    up = zero & (r33 > 0)
    down = zero & (r33 <= 0)
    alpha = np.where(zero, 0.0, alpha)  # beta keeps its value (continuous across the threshold)
    gamma = np.where(up, np.arctan2(-R[..., 0, 1], R[..., 0, 0]), gamma)
    gamma = np.where(down, np.arctan2(R[..., 0, 1], -R[..., 0, 0]), gamma)
    return np.stack([wrap_angle(alpha), beta, wrap_angle(gamma)], axis=-1)


def _rot_z(a: Array) -> Array:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([c, -s, z], -1), np.stack([s, c, z], -1), np.stack([z, z, o], -1)], -2)


def _rot_y(a: Array) -> Array:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([c, z, s], -1), np.stack([z, o, z], -1), np.stack([-s, z, c], -1)], -2)


def matrix_from_zyz(angles: ArrayLike) -> Array:
    """Rotation matrices ``(..., 3, 3)`` from Z-Y-Z Euler angles ``(..., 3)`` in radians."""
    a = np.asarray(angles, dtype=np.float64)
    return _rot_z(a[..., 0]) @ _rot_y(a[..., 1]) @ _rot_z(a[..., 2])


def pose_from_xyz_zyz(xyz: ArrayLike, zyz: ArrayLike) -> Array:
    """Pose ``(..., 4, 4)`` from a position ``(..., 3)`` (length unit) and Z-Y-Z angles ``(..., 3)`` (radians);
    ShapeError / NonFiniteError for other lengths, NaN or infinite values."""
    p = _trailing(xyz, "xyz", (3,))
    a = _trailing(zyz, "zyz", (3,))
    try:
        np.broadcast_shapes(p.shape[:-1], a.shape[:-1])
    except ValueError:
        raise ShapeError(f"xyz {p.shape} and zyz {a.shape} do not broadcast together") from None
    return _pose(p, matrix_from_zyz(a))


def _pose(xyz: ArrayLike, R: Array) -> Array:
    """Poses ``(..., 4, 4)`` from positions ``(..., 3)`` and rotations ``(..., 3, 3)`` (broadcast)."""
    p = np.asarray(xyz, dtype=np.float64)
    shape = np.broadcast_shapes(p.shape[:-1], R.shape[:-2])
    T = np.zeros((*shape, 4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def xyz_zyz_from_pose(T: ArrayLike) -> tuple[Array, Array]:
    """Split poses ``(..., 4, 4)`` into positions ``(..., 3)`` and Z-Y-Z angles ``(..., 3)`` (radians)."""
    T = _trailing(T, "T", (4, 4))
    return T[..., :3, 3].copy(), zyz_from_matrix(T)


def _rot_x(a: Array) -> Array:
    c, s = np.cos(a), np.sin(a)
    z, o = np.zeros_like(a), np.ones_like(a)
    return np.stack([np.stack([o, z, z], -1), np.stack([z, c, -s], -1), np.stack([z, s, c], -1)], -2)


def matrix_from_rpy(rpy: ArrayLike) -> Array:
    """Rotation matrices ``(..., 3, 3)`` from roll-pitch-yaw ``(..., 3)`` in radians, URDF's convention: fixed
    axes x, then y, then z, i.e. ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``."""
    a = np.asarray(rpy, dtype=np.float64)
    return _rot_z(a[..., 2]) @ _rot_y(a[..., 1]) @ _rot_x(a[..., 0])


def rpy_from_matrix(R: ArrayLike) -> Array:
    """Roll-pitch-yaw ``(..., 3)`` (radians, pitch in [-pi/2, pi/2]) of rotations ``(..., 3, 3)``: the inverse of
    :func:`matrix_from_rpy`. At pitch = +-pi/2 only roll -+ yaw is defined; roll is then 0.

    >>> import numpy as np
    >>> np.round(rpy_from_matrix(matrix_from_rpy([0.1, -0.2, 0.3])), 12).tolist()
    [0.1, -0.2, 0.3]
    """
    R = np.asarray(R, dtype=np.float64)[..., :3, :3]
    pitch = np.arctan2(-R[..., 2, 0], np.hypot(R[..., 0, 0], R[..., 1, 0]))
    yaw = np.arctan2(R[..., 1, 0], R[..., 0, 0])
    # roll from the last two columns rotated back by yaw and pitch: well conditioned for every pitch
    cy, sy = np.cos(yaw), np.sin(yaw)
    roll = np.arctan2(sy * R[..., 0, 2] - cy * R[..., 1, 2], cy * R[..., 1, 1] - sy * R[..., 0, 1])
    gimbal = np.hypot(R[..., 0, 0], R[..., 1, 0]) <= _EXACT_GIMBAL
    # gimbal: R = Rz(yaw) Ry(+-pi/2) with roll 0; yaw from the second column
    yaw = np.where(gimbal, np.arctan2(-R[..., 0, 1], R[..., 1, 1]), yaw)
    roll = np.where(gimbal, 0.0, roll)
    return np.stack([roll, pitch, yaw], axis=-1)


def pose_from_xyz_rpy(xyz: ArrayLike, rpy: ArrayLike) -> Array:
    """Pose ``(..., 4, 4)`` from a position ``(..., 3)`` and roll-pitch-yaw ``(..., 3)`` (radians, URDF's)."""
    return _pose(xyz, matrix_from_rpy(rpy))


def rotation_angle(R: ArrayLike) -> Array:
    """Angle (radians, in [0, pi]) of rotations ``(..., 3, 3)``; accurate near 0 (atan2 form, not arccos)."""
    R = np.asarray(R, dtype=np.float64)
    v = np.stack([R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]], -1)
    s = 0.5 * np.linalg.norm(v, axis=-1)
    c = 0.5 * (R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2] - 1.0)
    return np.arctan2(s, c)


def pose_error_paper(T: ArrayLike, T_desired: ArrayLike, weight: float = 100.0) -> Array:
    """The paper's error J (eq. 6) between poses ``(..., 4, 4)``, in the poses' length unit.

    ``J = sqrt(Jp**2 + (weight * Jo)**2)`` with ``Jp`` the position distance and ``Jo`` the norm of the
    Z-Y-Z angle differences, each difference wrapped into (-pi, pi]. ``weight`` is a length (the paper:
    100 mm). Where either pose is within ``GIMBAL_TOL`` of a gimbal case, alpha and gamma are not separately
    defined: there the decomposition of ``T`` nearest ``T_desired`` is used, i.e. the alpha difference is
    zero and the gamma difference is the wrapped difference of ``alpha + gamma`` (``alpha - gamma`` at
    beta = pi). ShapeError for poses not ``(..., 4, 4)`` or that do not broadcast together.
    """
    T, Td = _pose_pair(T, T_desired)
    jp = np.linalg.norm(T[..., :3, 3] - Td[..., :3, 3], axis=-1)
    e = _zyz(T)
    ed = _zyz(Td)
    da = wrap_angle(e[..., 0] - ed[..., 0])
    db = e[..., 1] - ed[..., 1]
    dg = wrap_angle(e[..., 2] - ed[..., 2])
    near0 = (e[..., 1] < GIMBAL_TOL) | (ed[..., 1] < GIMBAL_TOL)
    nearpi = (np.pi - e[..., 1] < GIMBAL_TOL) | (np.pi - ed[..., 1] < GIMBAL_TOL)
    dsum = wrap_angle((e[..., 0] + e[..., 2]) - (ed[..., 0] + ed[..., 2]))
    ddiff = wrap_angle((e[..., 0] - e[..., 2]) - (ed[..., 0] - ed[..., 2]))
    dg = np.where(near0, dsum, np.where(nearpi, ddiff, dg))
    da = np.where(near0 | nearpi, 0.0, da)
    jo = np.sqrt(da**2 + db**2 + dg**2)
    return np.asarray(np.sqrt(jp**2 + (weight * jo) ** 2))


def pose_error_geodesic(T: ArrayLike, T_desired: ArrayLike, weight: float = 100.0) -> Array:
    """Position distance plus ``weight`` times the rotation angle of ``R_desired^T R`` (length unit)."""
    T, Td = _pose_pair(T, T_desired)
    jp = np.linalg.norm(T[..., :3, 3] - Td[..., :3, 3], axis=-1)
    dR = np.swapaxes(Td[..., :3, :3], -1, -2) @ T[..., :3, :3]
    return np.asarray(jp + weight * rotation_angle(dR))
