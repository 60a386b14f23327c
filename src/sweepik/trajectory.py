"""Following a Cartesian path with branch continuity, and reading/writing path files.

* :func:`follow_path` solves every pose of a path (all solutions, :func:`sweepik.solving.solve_many`) and
  picks, pose after pose, the solution nearest the previous configuration.
* :func:`load_poses` reads poses from CSV, NPY or JSON; :func:`write_joint_path` writes the joint path as
  CSV or JSON (degrees for revolute joints, the robot's length unit for prismatic ones).

Distances between configurations mix lengths and angles. The paper's own exchange rate is used (eq. 6c:
100 mm of length weigh as much as 1 rad of angle), so a prismatic difference is divided by that weight
(``sweepik.model.units.orientation_weight``) before the Euclidean norm; angles are compared modulo 2 pi.
"""

from __future__ import annotations

import csv
import json
import math
import os
import tokenize
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from os import PathLike
from pathlib import Path
from typing import Any, BinaryIO, Literal

import numpy as np
from numpy.lib import format as npy_format
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import PoseFileError, ShapeError, SweepikError, UnknownOptionError
from sweepik.model.pose import pose_error_paper, pose_from_xyz_zyz
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.model.validate import (
    as_path,
    check_configuration,
    check_poses,
    decode_text,
    file_status,
    read_file_bytes,
    short_repr,
)
from sweepik.reductions import Reduction
from sweepik.results import Solutions, check_tolerance, joint_distance, joint_metric, weighted_joint_distance
from sweepik.solving import Progress, iter_solve

__all__ = [
    "BRANCH_SWITCH_ANGLE_RAD",
    "BRANCH_SWITCH_LENGTH_REL",
    "PathResult",
    "PoseFileError",
    "follow_path",
    "weighted_joint_distance",
    "branch_switch_thresholds",
    "load_poses",
    "write_joint_path",
]

Array = NDArray[np.float64]

#: A step between consecutive path points is a *branch switch* when a revolute joint moves more than this
#: (30 degrees). Consecutive points of a sensibly sampled path move each joint by a few degrees; a switch
#: to another IK branch (elbow flip, theta2 + 180 deg, ...) moves some joint by tens of degrees at once.
BRANCH_SWITCH_ANGLE_RAD = math.radians(30.0)
#: ... or when a prismatic joint moves more than this share of its range (C-Arm rail: 10 % of 2000 mm).
#: Joints without a finite range use the robot's ``length_scale`` instead of the range.
BRANCH_SWITCH_LENGTH_REL = 0.1


def branch_switch_thresholds(robot: Robot) -> Array:
    """Per-joint step ``(n,)`` above which a step counts as a branch switch (radians / length unit)."""
    span = robot.upper - robot.lower
    span = np.where(np.isfinite(span), span, robot.length_scale)
    return np.where(robot.is_revolute, BRANCH_SWITCH_ANGLE_RAD, BRANCH_SWITCH_LENGTH_REL * span)


@dataclass(frozen=True, eq=False)
class PathResult:
    """A joint path along a Cartesian path of ``N`` poses for an ``n``-joint robot.

    Attributes:
        q: ``(N, n)`` chosen configurations (radians / length unit); NaN rows where a pose has no solution.
        error: ``(N,)`` the paper's error J (eq. 6, length unit) of each chosen configuration; NaN where
            there is none.
        found: ``(N,)`` bool, the pose has at least one solution.
        n_solutions: ``(N,)`` isolated solutions of each pose (self-motion families not counted).
        steps: ``(N - 1, n)`` absolute joint change between consecutive points (angles modulo 2 pi); a row is
            NaN when either point has no solution.
        max_joint_step: ``(n,)`` largest change of each joint over the path (radians / length unit), over
            the steps between points that both have a solution (0 if there is none).
        branch_switches: number of steps with some joint change above :func:`branch_switch_thresholds`.
        switch_steps: indices ``k`` of those steps (between point ``k`` and ``k + 1``).
    """

    q: Array
    error: Array
    found: NDArray[np.bool_]
    n_solutions: NDArray[np.intp]
    steps: Array
    max_joint_step: Array
    branch_switches: int
    switch_steps: tuple[int, ...]

    @property
    def recall(self) -> float:
        """Share of path points with a solution."""
        return float(np.mean(self.found)) if self.found.size else 0.0


def _choose(
    robot: Robot, sols: Solutions, ref: Array | None, weight: float, metric: str, tol: float | None
) -> tuple[Array, float] | None:
    """The solution of ``sols`` nearest ``ref`` by ``metric`` within ``tol`` (:meth:`Solutions.nearest`; the first
    one when ``ref`` is None) and its error J; None when there is none."""
    if len(sols) and ref is None:
        return sols.q[0].copy(), float(sols.error[0])
    if not sols:
        return None
    if ref is None:
        best: Array | None = sols.families[0].at(sols.families[0].interval[0])
    else:
        best = sols.nearest(ref, metric=metric, tol=tol)
    if best is None:
        return None
    return best, float(pose_error_paper(robot.fk(best), sols.pose, weight))


def follow_path(
    robot: Robot,
    poses: ArrayLike,
    q_start: ArrayLike | None = None,
    *,
    reduction: str | Reduction | None = None,
    free_joint: int | str | None = None,
    strategy: Literal["precise", "paper"] = "precise",
    limits: bool = True,
    progress: Progress | None = None,
    locked: Mapping[Any, float] | None = None,
    metric: str = "weighted",
    tol: float | None = None,
) -> PathResult:
    """Joint path along ``poses (N, 4, 4)`` (world frame, robot's length unit), keeping to one IK branch.

    Every pose is solved for all its solutions; the first point takes the solution nearest ``q_start``
    (``(n,)``, radians / length unit), or the first solution reported when ``q_start`` is None; every later
    point takes the solution nearest the previous chosen configuration (see :func:`weighted_joint_distance`;
    members of self-motion families count). ``metric``: ``"weighted"`` (the Euclidean norm, the default) or
    ``"linf"`` (the largest joint move), see :meth:`Solutions.nearest`; with ``tol``, a point whose nearest
    solution is farther than ``tol`` from the previous configuration is not taken (a NaN row: the branch cannot
    be kept there without a jump). A pose without solution gets a NaN row and the next point is compared with the
    last configuration found. The poses are solved a chunk at a time (:func:`iter_solve`), so
    memory grows with the path's joint rows only; ``progress("path", done, total)`` follows the solves.
    ``reduction``, ``free_joint``, ``strategy``, ``limits`` and ``locked`` are passed to :func:`iter_solve` (see
    :func:`solve`); with ``locked``, configurations are full length (``q_start`` too).

    >>> import numpy as np
    >>> from sweepik import load_robot
    >>> arm = load_robot("carm")
    >>> q = np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]) + np.linspace(0, 0.05, 5)[:, None]
    >>> res = follow_path(arm, arm.fk(q), q_start=q[0])
    >>> bool(np.allclose(res.q, q, atol=1e-8)), res.branch_switches
    (True, 0)
    """
    joint_metric(metric)
    check_tolerance(tol)
    P = check_poses(poses, "poses")
    if P.ndim != 3 or P.shape[0] == 0:
        raise ShapeError(f"poses must have shape (N, 4, 4) with N >= 1, got {P.shape}")
    ref = None if q_start is None else check_configuration(q_start, robot.n_joints, "q_start")
    if ref is not None and ref.ndim != 1:
        raise ShapeError(f"q_start must have shape ({robot.n_joints},), got {ref.shape}")
    report = None if progress is None else (lambda _stage, done, total: progress("path", done, total))
    sols = iter_solve(
        robot,
        P,
        reduction=reduction,
        free_joint=free_joint,
        strategy=strategy,
        limits=limits,
        progress=report,
        locked=locked,
    )
    weight = orientation_weight(robot.length_unit)
    N, n = P.shape[0], robot.n_joints
    q = np.full((N, n), np.nan)
    err = np.full(N, np.nan)
    n_solutions = np.zeros(N, dtype=np.intp)
    for k, s in enumerate(sols):
        n_solutions[k] = len(s)
        pick = _choose(robot, s, ref, weight, metric, tol)
        if pick is not None:
            q[k], err[k] = pick
            ref = q[k]
    found = np.all(np.isfinite(q), axis=-1)
    steps = joint_distance(robot, q[1:], q[:-1]) if N > 1 else np.zeros((0, n))
    valid = np.all(np.isfinite(steps), axis=-1)
    max_step = steps[valid].max(axis=0) if np.any(valid) else np.zeros(n)
    over = valid & np.any(np.where(np.isfinite(steps), steps, 0.0) > branch_switch_thresholds(robot), axis=-1)
    switch = tuple(int(i) for i in np.nonzero(over)[0])
    return PathResult(q, err, found, n_solutions, steps, max_step, len(switch), switch)


# ---------------------------------------------------------------------------------------------- files

_POSE_LAYOUTS = (
    "CSV: one pose per row, 16 numbers (row-major 4x4) or 6 numbers x y z alpha beta gamma "
    "(Z-Y-Z Euler angles in degrees); NPY: array (N, 4, 4); JSON: a list of 4x4 nested lists or of "
    '{"xyz": [x, y, z], "zyz_deg": [alpha, beta, gamma]} objects'
)
#: Text pose files (CSV, JSON) larger than this are refused before they are read: 128 MiB, about 400,000 poses
#: of 16 numbers (a bigger set fits an .npy file, or call ``solve_many`` on an array).
MAX_POSE_TEXT_BYTES = 128 << 20
#: An .npy pose file may hold at most this many poses: 2**23 = 8,388,608 (1 GiB of float64), checked against
#: the header before any data is read.
MAX_NPY_POSES = 1 << 23


def _poses_from_rows(rows: Array, where: str) -> Array:
    if rows.ndim != 2 or rows.shape[1] not in (6, 16):
        width = rows.shape[1] if rows.ndim == 2 else rows.shape
        raise PoseFileError(f"{where}: expected 16 or 6 numbers per row, got {width}. Layouts: {_POSE_LAYOUTS}")
    if rows.shape[1] == 16:
        return rows.reshape(-1, 4, 4)
    return _pose_of_xyz_zyz_deg(rows[:, :3], rows[:, 3:], where)


def _pose_of_xyz_zyz_deg(xyz: Array, zyz_deg: Array, where: str) -> Array:
    """``pose_from_xyz_zyz`` of a file's numbers (Z-Y-Z in degrees); a bad value raises its error naming ``where``."""
    try:
        return pose_from_xyz_zyz(xyz, np.radians(zyz_deg))
    except SweepikError as exc:
        raise type(exc)(f"{where}: {exc}") from None


def _is_number(text: str) -> bool:
    try:
        float(text)
    except ValueError:
        return False
    return True


def _read_text(path: Path, what: str) -> str:
    return decode_text(
        read_file_bytes(path, MAX_POSE_TEXT_BYTES, PoseFileError, "pose file"), path, PoseFileError, what
    )


def _read_csv(path: Path) -> Array:
    text = _read_text(path, "CSV pose file")
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    dialect_delim = "," if any("," in ln for ln in lines) else None
    rows: list[list[float]] = []
    for lineno, line in enumerate(lines, start=1):
        fields = [f.strip() for f in (line.split(dialect_delim) if dialect_delim else line.split())]
        fields = [f for f in fields if f != ""]
        if lineno == 1 and fields and not any(_is_number(f) for f in fields):
            continue  # a header row of column names (a first row with some numbers is data, checked below)
        try:
            rows.append([float(f) for f in fields])
        except ValueError:
            shown = line.strip() if len(line.strip()) <= 80 else line.strip()[:77] + "..."
            raise PoseFileError(f"{path}: data row {lineno} holds a non-numeric field: {shown!r}") from None
    if not rows:
        raise PoseFileError(f"{path}: no poses found. Layouts: {_POSE_LAYOUTS}")
    widths = {len(r) for r in rows}
    if len(widths) != 1:
        shown_widths = sorted(widths)[:10]
        raise PoseFileError(f"{path}: rows have different numbers of fields {shown_widths}; expected all 16 or all 6")
    return _poses_from_rows(np.array(rows, dtype=np.float64), str(path))


#: What NumPy's .npy header parser (``ast.literal_eval`` after a ``tokenize`` pass) raises on a malformed header.
_NPY_HEADER_ERRORS = (ValueError, TypeError, SyntaxError, EOFError, OSError, tokenize.TokenError, RecursionError)


def _npy_header(fh: BinaryIO, path: Path) -> tuple[tuple[int, ...], bool, np.dtype[Any]]:
    """Shape, Fortran order and dtype from an .npy header (bounded: NumPy refuses headers over 10,000 bytes).
    The parser's warnings on odd headers are silenced: the header is either accepted or refused here."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            version = npy_format.read_magic(fh)
            if version == (1, 0):
                return npy_format.read_array_header_1_0(fh)
            if version == (2, 0):
                return npy_format.read_array_header_2_0(fh)
    except _NPY_HEADER_ERRORS as exc:
        raise PoseFileError(f"{path}: not an .npy array file ({type(exc).__name__}: {str(exc)[:160]})") from None
    raise PoseFileError(f"{path}: .npy format version {version[0]}.{version[1]} is not supported for poses")


def _read_npy(path: Path) -> Array:
    """Poses from an .npy file: the header (magic, dtype, shape) is checked against the file size and the
    ``MAX_NPY_POSES`` bound before the data is read; pickled objects are never loaded."""
    try:
        with path.open("rb") as fh:
            shape, fortran, dtype = _npy_header(fh, path)
            if dtype.kind not in "fiu":
                raise PoseFileError(f"{path}: expected an array of real numbers, got dtype {str(dtype)[:80]}")
            if shape == (4, 4):
                shape = (1, 4, 4)
            if len(shape) != 3 or shape[1:] != (4, 4):
                raise PoseFileError(f"{path}: expected an array of shape (N, 4, 4), got {shape}")
            if not 1 <= shape[0] <= MAX_NPY_POSES:
                raise PoseFileError(f"{path}: holds {shape[0]} poses; a pose file holds 1 to {MAX_NPY_POSES}")
            needed = shape[0] * 16 * dtype.itemsize
            available = os.fstat(fh.fileno()).st_size - fh.tell()
            if available < needed:
                raise PoseFileError(
                    f"{path}: truncated: the header declares shape {shape} ({needed} bytes of data), "
                    f"the file holds {available}"
                )
            data = np.fromfile(fh, dtype=dtype, count=shape[0] * 16)
            if data.size != shape[0] * 16:
                raise PoseFileError(f"{path}: truncated while reading the data of shape {shape}")
    except OSError as exc:
        raise PoseFileError(f"{path}: cannot read pose file: {exc.strerror or exc}") from None
    order: Literal["C", "F"] = "F" if fortran else "C"
    return data.reshape(shape, order=order).astype(np.float64, copy=False)


def _json_number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise PoseFileError(f"{where}: expected a number, got {short_repr(value, 40)}")
    try:
        return float(value)
    except OverflowError:
        raise PoseFileError(f"{where}: {short_repr(value)} is beyond the floating-point range") from None


def _json_vector(value: Any, n: int, where: str) -> list[float]:
    if not isinstance(value, list) or len(value) != n:
        raise PoseFileError(f"{where}: expected a list of {n} numbers, got {short_repr(value, 40)}")
    return [_json_number(v, where) for v in value]


def _json_item(item: Any, i: int, where: str) -> Array:
    if isinstance(item, dict):
        if "xyz" not in item or "zyz_deg" not in item:
            keys = short_repr(sorted(item), 80)
            raise PoseFileError(f"{where}: pose {i} is an object without 'xyz' and 'zyz_deg' keys: {keys}")
        xyz = _json_vector(item["xyz"], 3, f"{where}: pose {i}: 'xyz'")
        zyz = _json_vector(item["zyz_deg"], 3, f"{where}: pose {i}: 'zyz_deg'")
        return _pose_of_xyz_zyz_deg(np.array(xyz), np.array(zyz), f"{where}: pose {i}")
    if not isinstance(item, list):
        raise PoseFileError(f"{where}: pose {i} is neither a 4x4 list of numbers nor an xyz/zyz_deg object")
    if len(item) != 4:
        raise PoseFileError(f"{where}: pose {i} must be a 4x4 nested list, got {len(item)} rows")
    return np.array([_json_vector(row, 4, f"{where}: pose {i} row {r}") for r, row in enumerate(item)])


def _read_json(path: Path) -> Array:
    text = _read_text(path, "JSON pose file")
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise PoseFileError(f"{path}: invalid JSON ({exc})") from None
    except RecursionError:
        raise PoseFileError(f"{path}: not a pose file: lists nested too deeply") from None
    except ValueError:  # an integer beyond Python's int-string conversion limit
        raise PoseFileError(f"{path}: not a pose file: a number with thousands of digits") from None
    if isinstance(data, dict) and "poses" in data:
        data = data["poses"]
    if not isinstance(data, list) or not data:
        raise PoseFileError(f"{path}: expected a non-empty JSON list of poses. Layouts: {_POSE_LAYOUTS}")
    return np.stack([_json_item(item, i, str(path)) for i, item in enumerate(data)])


_READERS = {".csv": _read_csv, ".txt": _read_csv, ".npy": _read_npy, ".json": _read_json}


def load_poses(path: str | PathLike[str]) -> Array:
    """Poses ``(N, 4, 4)``, ``N >= 1``, read from a CSV, NPY or JSON file (chosen by extension).

    * CSV (``.csv``, ``.txt``): one pose per row; 16 numbers (a row-major 4x4 matrix) or 6 numbers
      ``x y z alpha beta gamma`` (position in the robot's length unit, Z-Y-Z Euler angles in **degrees**).
      Separated by commas or whitespace; ``#`` comment lines and one header row of names (a first row with no
      number in it) are skipped. UTF-8 text (a byte-order mark is allowed).
    * NPY: a real numeric array ``(N, 4, 4)`` (or a single ``(4, 4)``), ``N <= MAX_NPY_POSES`` (8,388,608);
      the header is checked against the file size before any data is read, pickled objects are refused.
    * JSON: a list (or ``{"poses": [...]}``) of 4x4 nested lists of numbers or of
      ``{"xyz": [x, y, z], "zyz_deg": [alpha, beta, gamma]}`` objects (``true``/``false`` and strings are not
      numbers). UTF-8 text.

    CSV and JSON files larger than ``MAX_POSE_TEXT_BYTES`` (128 MiB) are refused before they are read.

    Raises:
        PoseFileError: not a str/path, missing file, a directory or device, unreadable, too large, unknown
            extension, not UTF-8, malformed content, no pose (messages name the file).
        InvalidPoseError / NonFiniteError: a matrix that is not a rigid transform, NaN or inf values
            (messages name the file).
    """
    p = as_path(path, PoseFileError, "pose file")
    reader = _READERS.get(p.suffix.lower())
    if reader is None:
        raise PoseFileError(f"{p}: unknown pose file extension {p.suffix!r}; use one of {', '.join(_READERS)}")
    if file_status(p, PoseFileError, "pose file") is None:
        raise PoseFileError(f"{p}: no such file")
    return check_poses(reader(p), f"{p}: poses")


def _display_units(robot: Robot) -> list[str]:
    return ["deg" if rev else robot.length_unit for rev in robot.is_revolute]


def write_joint_path(path: str | PathLike[str], q: ArrayLike, robot: Robot) -> Path:
    """Write a joint path ``q (N, n)`` (radians / length unit) to ``path`` as CSV or JSON (by extension).

    Revolute joints are written in **degrees**, prismatic ones in the robot's length unit; rows of a pose
    without solution are ``nan`` (CSV) or ``null`` (JSON).

    * CSV: a ``#`` comment line stating robot and units, a header row ``<joint>_<unit>``, one row per point.
    * JSON: ``{"robot": ..., "joints": [...], "units": [...], "q": [[...], ...]}``.

    Returns the path written. Raises UnknownOptionError for another extension, ShapeError for a bad ``q``.
    """
    p = Path(path)
    qa = np.asarray(q, dtype=np.float64)
    if qa.ndim != 2 or qa.shape[1] != robot.n_joints:
        raise ShapeError(f"q must have shape (N, {robot.n_joints}), got {qa.shape}")
    shown = np.where(robot.is_revolute, np.degrees(qa), qa)
    units = _display_units(robot)
    names = robot.joint_names
    ext = p.suffix.lower()
    if ext == ".csv":
        with p.open("w", newline="") as fh:
            unit_text = ", ".join(f"{nm} in {u}" for nm, u in zip(names, units, strict=True))
            fh.write(f"# sweepik joint path, robot {robot.name}: {unit_text}\n")
            w = csv.writer(fh)
            w.writerow([f"{nm}_{u}" for nm, u in zip(names, units, strict=True)])
            for row in shown:
                w.writerow([repr(float(v)) if np.isfinite(v) else "nan" for v in row])
    elif ext == ".json":
        rows: Sequence[list[float | None]] = [[float(v) if np.isfinite(v) else None for v in row] for row in shown]
        doc = {"robot": robot.name, "joints": names, "units": units, "q": rows}
        p.write_text(json.dumps(doc, indent=1) + "\n")
    else:
        raise UnknownOptionError(f"{p}: unknown joint-path file extension {p.suffix!r}; use .csv or .json")
    return p
