"""Input checks shared by the public entry points (raise SweepikError subclasses, never assert)."""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidPoseError, NonFiniteError, ShapeError, UnknownOptionError

#: Largest deviation of R^T R from I (and of det R from 1) accepted for a pose's rotation.
#: 1e-6 admits poses typed with 7 significant digits and rejects anything that is not a rotation.
ORTHONORMAL_TOL = 1e-6


def as_float_array(x: ArrayLike, what: str) -> NDArray[np.float64]:
    """Convert ``x`` to a float64 array or raise ShapeError naming ``what`` (complex values are refused, not cast)."""
    if np.iscomplexobj(x):
        raise ShapeError(f"{what} must be real, got complex values")
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ShapeError(f"{what} must be numeric, got {type(x).__name__}: {str(exc)[:120]}") from None
    return arr


def check_int(value: object, what: str, lo: int, hi: int) -> int:
    """``value`` as an int in [lo, hi]; bools, floats (even 64.0), NaN and strings are refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise UnknownOptionError(f"{what} must be an integer in [{lo}, {hi}], got {value!r}")
    v = int(value)
    if not lo <= v <= hi:
        raise UnknownOptionError(f"{what} must be an integer in [{lo}, {hi}], got {v}")
    return v


def check_bool(value: object, what: str) -> bool:
    """``value`` as a bool; only True/False (and NumPy bools) are accepted, not 'no', 0 or None."""
    if not isinstance(value, bool | np.bool_):
        raise UnknownOptionError(f"{what} must be True or False, got {value!r}")
    return bool(value)


def check_finite(arr: NDArray[np.float64], what: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise NonFiniteError(f"{what} holds NaN or infinite values (first at index {tuple(int(i) for i in bad)})")


def check_configuration(q: ArrayLike, n: int, what: str = "q", finite: bool = True) -> NDArray[np.float64]:
    """Return ``q`` as float array of shape (..., n), finite unless ``finite=False``."""
    arr = as_float_array(q, what)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ShapeError(f"{what} must have shape (..., {n}) for this {n}-joint robot, got shape {arr.shape}")
    if finite:
        check_finite(arr, what)
    return arr


def check_poses(T: ArrayLike, what: str = "pose") -> NDArray[np.float64]:
    """Return poses as float array of shape (..., 4, 4) after checking they are rigid transforms.

    Rotation orthonormal and right-handed within ``ORTHONORMAL_TOL``; bottom row (0, 0, 0, 1) within the same.
    """
    arr = as_float_array(T, what)
    if arr.ndim < 2 or arr.shape[-2:] != (4, 4):
        raise ShapeError(f"{what} must have shape (..., 4, 4), got shape {arr.shape}")
    check_finite(arr, what)
    bottom = arr[..., 3, :] - np.array([0.0, 0.0, 0.0, 1.0])
    if np.any(np.abs(bottom) > ORTHONORMAL_TOL):
        idx = np.argwhere(np.any(np.abs(bottom) > ORTHONORMAL_TOL, axis=-1))
        where = f" (pose {tuple(int(i) for i in idx[0])})" if arr.ndim > 2 else ""
        raise InvalidPoseError(f"{what} bottom row must be (0, 0, 0, 1){where}, got {arr[..., 3, :].reshape(-1, 4)[0]}")
    R = arr[..., :3, :3]
    dev = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(axis=(-1, -2))
    det = np.linalg.det(R)
    bad = (dev > ORTHONORMAL_TOL) | (np.abs(det - 1.0) > ORTHONORMAL_TOL)
    if np.any(bad):
        idx = np.argwhere(np.atleast_1d(bad))[0]
        where = f" (pose {tuple(int(i) for i in idx)})" if arr.ndim > 2 else ""
        worst = float(np.atleast_1d(dev)[tuple(idx)])
        d = float(np.atleast_1d(det)[tuple(idx)])
        raise InvalidPoseError(
            f"{what} rotation must be orthonormal with det +1 (tolerance {ORTHONORMAL_TOL:g}){where}: "
            f"max |R^T R - I| = {worst:.3g}, det = {d:.6g}"
        )
    return arr
