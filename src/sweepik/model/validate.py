"""Input checks shared by the public entry points (raise SweepikError subclasses, never assert).

One place for each check: arrays (:func:`as_float_array`, :func:`check_configuration`, :func:`check_poses`),
scalar options (:func:`check_int`, :func:`check_bool`, :func:`check_choice`) and input files
(:func:`read_file_bytes`, :func:`decode_text`: the size is checked before anything is read, and every message
names the file).
"""

from __future__ import annotations

import errno
import math
import numbers
import os
import stat
from collections.abc import Sequence
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import InvalidPoseError, NonFiniteError, ShapeError, SweepikError, UnknownOptionError

#: Largest deviation of R^T R from I (and of det R from 1) accepted for a pose's rotation.
#: 1e-6 admits poses typed with 7 significant digits and rejects anything that is not a rotation.
ORTHONORMAL_TOL = 1e-6
#: Largest pose translation coordinate accepted (length unit): far beyond any arm (robot files bound lengths at
#: 1e12), and the solver's products of a few coordinates stay finite (at 1e150 they overflow).
MAX_TRANSLATION = 1e30
#: Joint values beyond this magnitude (radians or length unit) are refused: their poses would overflow.
MAX_JOINT_VALUE = 1e30

#: Lengths in robot files (a, d, base/tool offsets; URDF origins) beyond this magnitude are refused: no arm in any
#: unit is that large, and sums and squares of such numbers overflow.
MAX_LENGTH = 1e12
#: Angles (alpha, theta, base/tool Z-Y-Z angles; degrees) beyond this magnitude are refused:
#: no DH table needs more than a turn, and 1e6 degrees (about 2,800 turns) keeps the rounding of the angle in
#: radians (ulp 4e-12 rad at 1.7e4 rad) far below the angle tolerances (e.g. ``robot.LIMIT_TOL``, 1e-9 rad).
MAX_ANGLE_DEG = 1e6
#: Joint limits (degrees or length unit) beyond this magnitude are refused, so that a range ``upper - lower``
#: stays finite. Huge limits are allowed on purpose: ``[-1e300, 1e300]`` is a joint without a practical end
#: (``Robot.length_scale`` caps how much a prismatic range counts).
MAX_LIMIT = 1e300
#: Link masses (kg) beyond this are refused (a typo, not a link: the heaviest industrial arms weigh a few tonnes).
MAX_MASS = 1e6
#: dtype kinds taken as real numbers: floats, signed and unsigned integers (object arrays: checked per element).
_REAL_KINDS = "fiu"
_KIND_NAMES = {
    "b": "booleans",
    "U": "strings",
    "S": "bytes",
    "V": "structured records",
    "M": "datetimes",
    "m": "timedeltas",
}


def short_repr(value: object, width: int = 60) -> str:
    """``repr(value)`` cut to ``width`` characters (huge integers described by their number of digits)."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) >= 10**30:
        return f"an integer of {len(str(abs(value)))} digits"
    text = repr(value)
    return text if len(text) <= width else text[: width - 3] + "..."


def as_float_array(x: ArrayLike, what: str) -> NDArray[np.float64]:
    """``x`` as a float64 array, or ShapeError naming ``what``.

    Accepted: real floats and integers (Python or NumPy scalars, lists, arrays; object arrays holding only such
    numbers). Refused rather than cast: complex values, booleans, strings and bytes (even ``"1.5"``), records,
    datetimes, ragged or over-deep nesting (more than NumPy's 64 dimensions), integers beyond the float range.
    """
    try:
        arr = np.asarray(x)
    except (TypeError, ValueError, OverflowError, RecursionError) as exc:
        raise ShapeError(f"{what} must be a numeric array, got {type(x).__name__}: {str(exc)[:120]}") from None
    kind = arr.dtype.kind
    if kind == "c":
        raise ShapeError(f"{what} must be real, got complex values")
    if kind == "O":
        for v in arr.flat:
            if isinstance(v, numbers.Real) and not isinstance(v, bool):
                continue
            if isinstance(v, numbers.Complex) and not isinstance(v, bool):
                raise ShapeError(f"{what} must be real, got complex values")
            raise ShapeError(f"{what} must be numeric (real numbers), got {type(v).__name__} {short_repr(v, 40)}")
    elif kind not in _REAL_KINDS:
        raise ShapeError(
            f"{what} must be numeric (real numbers), got {_KIND_NAMES.get(kind, 'values')} (dtype {arr.dtype})"
        )
    try:
        return arr.astype(np.float64, copy=False)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ShapeError(f"{what} must be numeric (real numbers within the float range): {str(exc)[:120]}") from None


def check_int(value: object, what: str, lo: int, hi: int) -> int:
    """``value`` as an int in [lo, hi]; bools, floats (even 64.0), NaN and strings are refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise UnknownOptionError(f"{what} must be an integer in [{lo}, {hi}], got {short_repr(value)}")
    v = int(value)
    if not lo <= v <= hi:
        raise UnknownOptionError(f"{what} must be an integer in [{lo}, {hi}], got {short_repr(v)}")
    return v


def check_bool(value: object, what: str) -> bool:
    """``value`` as a bool; only True/False (and NumPy bools) are accepted, not 'no', 0 or None."""
    if not isinstance(value, bool | np.bool_):
        raise UnknownOptionError(f"{what} must be True or False, got {short_repr(value)}")
    return bool(value)


def check_choice(value: object, what: str, choices: Sequence[str]) -> str:
    """``value`` as one of the strings ``choices``; anything else (another string, a list, an array, None) is
    refused with the valid options."""
    if not isinstance(value, str) or value not in choices:
        raise UnknownOptionError(f"unknown {what} {short_repr(value)}; choose one of {', '.join(choices)}")
    return value


def check_finite(arr: NDArray[np.float64], what: str) -> None:
    if not np.all(np.isfinite(arr)):
        bad = np.argwhere(~np.isfinite(arr))[0]
        raise NonFiniteError(f"{what} holds NaN or infinite values (first at index {tuple(int(i) for i in bad)})")


def check_configuration(q: ArrayLike, n: int, what: str = "q", finite: bool = True) -> NDArray[np.float64]:
    """Return ``q`` as float array of shape (..., n), finite and at most ``MAX_JOINT_VALUE`` in magnitude unless
    ``finite=False``."""
    arr = as_float_array(q, what)
    if arr.ndim == 0 or arr.shape[-1] != n:
        raise ShapeError(f"{what} must have shape (..., {n}) for this {n}-joint robot, got shape {arr.shape}")
    if finite:
        check_finite(arr, what)
        if arr.size and np.abs(arr).max() > MAX_JOINT_VALUE:
            raise NonFiniteError(
                f"{what}: joint values must be at most {MAX_JOINT_VALUE:g} in magnitude (radians or length unit), "
                f"got {arr.ravel()[np.argmax(np.abs(arr))]:g}"
            )
    return arr


def check_poses(T: ArrayLike, what: str = "pose") -> NDArray[np.float64]:
    """Return poses as float array of shape (..., 4, 4) after checking they are rigid transforms.

    Rotation orthonormal and right-handed within ``ORTHONORMAL_TOL``; bottom row (0, 0, 0, 1) within the same;
    translation coordinates of magnitude at most ``MAX_TRANSLATION`` (1e30 length units).
    """
    arr = as_float_array(T, what)
    if arr.ndim < 2 or arr.shape[-2:] != (4, 4):
        raise ShapeError(f"{what} must have shape (..., 4, 4), got shape {arr.shape}")
    if arr.ndim == 2 and _one_pose_ok(arr):  # (the checks below on one pose cost ~60 us in NumPy calls)
        return arr
    check_finite(arr, what)
    bottom = arr[..., 3, :] - np.array([0.0, 0.0, 0.0, 1.0])
    if np.any(np.abs(bottom) > ORTHONORMAL_TOL):
        idx = np.argwhere(np.any(np.abs(bottom) > ORTHONORMAL_TOL, axis=-1))
        where = f" (pose {tuple(int(i) for i in idx[0])})" if arr.ndim > 2 else ""
        raise InvalidPoseError(f"{what} bottom row must be (0, 0, 0, 1){where}, got {arr[..., 3, :].reshape(-1, 4)[0]}")
    t_abs = np.abs(arr[..., :3, 3])
    if t_abs.size and t_abs.max() > MAX_TRANSLATION:
        far = np.any(t_abs > MAX_TRANSLATION, axis=-1)
        idx = np.argwhere(np.atleast_1d(far))[0]
        where = f" (pose {tuple(int(i) for i in idx)})" if arr.ndim > 2 else ""
        t = arr[..., :3, 3][far][0]
        raise InvalidPoseError(
            f"{what} translation must be at most {MAX_TRANSLATION:g} in magnitude (length unit){where}, got {t}"
        )
    check_rotations(arr[..., :3, :3], what, "pose")
    return arr


def check_rotations(R: NDArray[np.float64], what: str, item: str = "rotation") -> None:
    """InvalidPoseError unless every rotation ``R (..., 3, 3)`` (finite) is orthonormal with det +1 within
    ``ORTHONORMAL_TOL``; the message names the first bad ``item`` of a stack."""
    dev, det = _gram_deviation_det(R)
    bad = (dev > ORTHONORMAL_TOL) | (np.abs(det - 1.0) > ORTHONORMAL_TOL)
    if np.any(bad):
        idx = np.argwhere(np.atleast_1d(bad))[0]
        where = f" ({item} {tuple(int(i) for i in idx)})" if R.ndim > 2 else ""
        worst = float(np.atleast_1d(dev)[tuple(idx)])
        d = float(np.atleast_1d(det)[tuple(idx)])
        raise InvalidPoseError(
            f"{what} rotation must be orthonormal with det +1 (tolerance {ORTHONORMAL_TOL:g}){where}: "
            f"max |R^T R - I| = {worst:.3g}, det = {d:.6g}"
        )


def _gram_deviation_det(R: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``max |R^T R - I|`` and ``det R`` of rotations ``R (..., 3, 3)``, from the columns' dot products and triple
    product (element-wise: a stack of 3 x 3 matrix products or LAPACK determinants costs ~1 us per pose)."""
    c = [R[..., :, k] for k in range(3)]
    dev = np.zeros(R.shape[:-2])
    for i in range(3):
        for j in range(i, 3):
            g = c[i][..., 0] * c[j][..., 0] + c[i][..., 1] * c[j][..., 1] + c[i][..., 2] * c[j][..., 2]
            dev = np.maximum(dev, np.abs(g - 1.0) if i == j else np.abs(g))
    a, b, c2 = R[..., 0, 0], R[..., 0, 1], R[..., 0, 2]
    d, e, f = R[..., 1, 0], R[..., 1, 1], R[..., 1, 2]
    g, h, k = R[..., 2, 0], R[..., 2, 1], R[..., 2, 2]
    det = a * (e * k - f * h) - b * (d * k - f * g) + c2 * (d * h - e * g)
    return dev, det


def _one_pose_ok(arr: NDArray[np.float64]) -> bool:
    """One pose ``(4, 4)`` passes every check of ``check_poses`` (``rigid_values``; a pose that fails goes through
    those checks for their message)."""
    return rigid_values(*arr.ravel().tolist())


def rigid_values(
    a: float, b: float, c: float, x: float, d: float, e: float, f: float, y: float,
    g: float, h: float, k: float, z: float, r0: float, r1: float, r2: float, r3: float,
) -> bool:  # fmt: skip
    """The pose with rows ``(a, b, c, x), (d, e, f, y), (g, h, k, z), (r0, r1, r2, r3)`` passes every check of
    ``check_poses``: the same tests in scalar arithmetic (plain Python, compiled too by ``engine.closed_pose``)."""
    # (a sum is finite only if every term is; one that overflows merely sends the pose to the full checks)
    if not math.isfinite(a + b + c + x + d + e + f + y + g + h + k + z + r0 + r1 + r2 + r3):
        return False
    if max(abs(r0), abs(r1), abs(r2), abs(r3 - 1.0)) > ORTHONORMAL_TOL:
        return False
    if max(abs(x), abs(y), abs(z)) > MAX_TRANSLATION:
        return False
    dev = max(  # the columns' dot products against the identity's
        abs(a * a + d * d + g * g - 1.0),
        abs(b * b + e * e + h * h - 1.0),
        abs(c * c + f * f + k * k - 1.0),
        abs(a * b + d * e + g * h),
        abs(a * c + d * f + g * k),
        abs(b * c + e * f + h * k),
    )
    det = a * (e * k - f * h) - b * (d * k - f * g) + c * (d * h - e * g)
    return dev <= ORTHONORMAL_TOL and abs(det - 1.0) <= ORTHONORMAL_TOL


# ---------------------------------------------------------------------------------------------- files


def as_path(path: object, error: type[SweepikError], what: str) -> Path:
    """``path`` (a ``str`` or ``os.PathLike``) as a Path; anything else raises ``error``."""
    if isinstance(path, Path):
        return path
    if isinstance(path, str) or (isinstance(path, os.PathLike) and isinstance(os.fspath(path), str)):
        return Path(path)
    raise error(f"{what} path must be a str or os.PathLike, got {type(path).__name__} {short_repr(path, 40)}")


def file_status(path: Path, error: type[SweepikError], what: str) -> os.stat_result | None:
    """``os.stat`` of ``path``, None when there is no such file; ``error`` (naming the file) when the path cannot be
    examined (a name too long, a NUL byte, no permission) or names a directory or other non-regular file."""
    try:
        st = path.stat()
    except ValueError:  # an embedded NUL byte
        raise error(f"{str(path)!r}: not a valid file name (it holds a NUL byte)") from None
    except OSError as exc:
        if exc.errno in (errno.ENOENT, errno.ENOTDIR):
            return None
        raise error(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    if stat.S_ISDIR(st.st_mode):
        raise error(f"{path}: is a directory, not a {what}")
    if not stat.S_ISREG(st.st_mode):
        raise error(f"{path}: is not a regular file (a device, pipe or socket), not a {what}")
    return st


def read_file_bytes(path: Path, max_bytes: int, error: type[SweepikError], what: str) -> bytes:
    """The content of the regular file ``path``, at most ``max_bytes`` bytes.

    The size is checked with ``stat`` before the file is opened, and at most ``max_bytes + 1`` bytes are read (a
    file that grows meanwhile is caught too). Every failure raises ``error`` naming the file: no such file, a
    directory or device, no permission, larger than ``max_bytes``.
    """
    st = file_status(path, error, what)
    if st is None:
        raise error(f"{path}: no such file")
    if st.st_size > max_bytes:
        raise error(f"{path}: {st.st_size} bytes, larger than the {max_bytes} bytes a {what} may have")
    try:
        with path.open("rb") as fh:
            blob = fh.read(max_bytes + 1)
    except OSError as exc:
        raise error(f"{path}: cannot read {what}: {exc.strerror or exc}") from None
    if len(blob) > max_bytes:
        raise error(f"{path}: larger than the {max_bytes} bytes a {what} may have")
    return blob


def decode_text(blob: bytes, path: Path, error: type[SweepikError], what: str) -> str:
    """``blob`` decoded as UTF-8 (a leading byte-order mark is dropped), or ``error`` naming the file and byte."""
    try:
        return blob.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        hint = " (it looks like UTF-16)" if blob[:2] in (b"\xff\xfe", b"\xfe\xff") else ""
        raise error(f"{path}: not UTF-8 text at byte {exc.start}{hint}; a {what} is UTF-8 text") from None
