"""Robot files (TOML, written by hand) and the bundled robots.

File format (angles in degrees, lengths in ``length_unit``)::

    name = "carm"
    dh_convention = "modified"        # or "standard"
    length_unit = "mm"
    default_reduction = "carm-d1"     # optional: the IK reduction ``solve`` uses by default

    [[joints]]
    name = "d1"
    type = "prismatic"                # or "revolute"
    a = 0.0                           # DH row constants; the joint value adds to theta (revolute) or d
    alpha = 0.0
    d = 0.0
    theta = 0.0
    limits = [0.0, 2000.0]            # degrees for revolute joints, length unit for prismatic ones

    [base]                            # optional, likewise [tool]
    xyz = [0.0, 0.0, 0.0]
    zyz = [0.0, 0.0, 0.0]             # degrees

Missing ``a``, ``alpha``, ``d``, ``theta`` default to 0; ``type`` and ``limits`` are required.

Bounds (a file outside them raises :class:`~sweepik.errors.RobotFileError` naming the file, joint and field):

* the file: UTF-8 TOML of at most ``MAX_ROBOT_FILE_BYTES`` (1 MiB), checked before it is read;
* lengths (``a``, ``d``, ``[base]``/``[tool]`` ``xyz``): finite, ``|x| <= MAX_LENGTH`` (1e12 length units);
* angles (``alpha``, ``theta``, ``zyz``): finite, ``|x| <= MAX_ANGLE_DEG`` (1e6 degrees);
* ``limits``: finite, ``|x| <= MAX_LIMIT`` (1e300 degrees or length units: huge limits mean no practical end);
* text fields (``name``, ``description``, ``length_unit``, ``default_reduction``, joint ``name``): strings.
"""

from __future__ import annotations

import tomllib
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from ._validate import as_path, decode_text, file_status, read_file_bytes, short_repr
from .errors import RobotFileError, UnknownRobotError
from .pose import pose_from_xyz_zyz
from .robot import Joint, Robot

__all__ = ["load_robot", "bundled_robots", "robot_from_dict"]

_REQUIRED = ("type", "limits")
_KNOWN_JOINT_KEYS = {"name", "type", "a", "alpha", "d", "theta", "limits"}
_KNOWN_TOP_KEYS = {"name", "description", "dh_convention", "length_unit", "default_reduction", "joints", "base", "tool"}


def bundled_robots() -> list[str]:
    """Names of the robots shipped with sweepik."""
    files = resources.files("sweepik") / "robots"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


#: Robot files larger than this are refused before they are read (a 6-joint arm takes about 1 KiB).
MAX_ROBOT_FILE_BYTES = 1 << 20
#: Lengths (a, d, base/tool offsets) beyond this magnitude are refused: no arm in any unit is that large, and
#: sums and squares of such numbers overflow.
MAX_LENGTH = 1e12
#: Angles (alpha, theta, base/tool Z-Y-Z angles; degrees) beyond this magnitude are refused:
#: no DH table needs more than a turn, and 1e6 degrees (about 2,800 turns) keeps the rounding of the angle in
#: radians (ulp 4e-12 rad at 1.7e4 rad) far below the angle tolerances (e.g. ``robot.LIMIT_TOL``, 1e-9 rad).
MAX_ANGLE_DEG = 1e6
#: Joint limits (degrees or length unit) beyond this magnitude are refused, so that a range ``upper - lower``
#: stays finite. Huge limits are allowed on purpose: ``[-1e300, 1e300]`` is a joint without a practical end
#: (``Robot.length_scale`` caps how much a prismatic range counts).
MAX_LIMIT = 1e300


def _number(value: Any, where: str, field: str, bound: float) -> float:
    """``value`` as a float of magnitude at most ``bound`` (``MAX_LENGTH``, ``MAX_ANGLE_DEG`` or ``MAX_LIMIT``)."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotFileError(f"{where}: field '{field}' must be a finite number, got {_short(value)}")
    try:
        x = float(value)
    except OverflowError:
        x = np.inf
    if not np.isfinite(x) or abs(x) > bound:
        unit = " degrees" if bound == MAX_ANGLE_DEG else ""
        raise RobotFileError(
            f"{where}: field '{field}' must be a finite number of magnitude at most {bound:g}{unit}, "
            f"got {_short(value)}"
        )
    return x


def _short(value: Any) -> str:
    return short_repr(value)


def _text(data: dict[str, Any], key: str, where: str, default: str | None) -> str | None:
    value = data.get(key, default)
    if value is not None and not isinstance(value, str):
        raise RobotFileError(f"{where}: field '{key}' must be a string, got {_short(value)}")
    return value


def _transform(table: Any, where: str) -> np.ndarray:
    if not isinstance(table, dict):
        raise RobotFileError(f"{where}: must be a table with 'xyz' and 'zyz' (degrees)")
    unknown = set(table) - {"xyz", "zyz"}
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field(s) {short_repr(sorted(unknown, key=str), 200)}; expected 'xyz' and 'zyz'"
        )
    vecs = []
    for key in ("xyz", "zyz"):
        v = table.get(key, [0.0, 0.0, 0.0])
        if not isinstance(v, list) or len(v) != 3:
            raise RobotFileError(f"{where}: field '{key}' must be a list of 3 numbers, got {_short(v)}")
        vecs.append([_number(x, where, key, MAX_LENGTH if key == "xyz" else MAX_ANGLE_DEG) for x in v])
    return pose_from_xyz_zyz(vecs[0], np.radians(vecs[1]))


def robot_from_dict(data: dict[str, Any], source: str = "<dict>") -> Robot:
    """Build a Robot from the parsed contents of a robot file; errors name ``source``, the joint and field."""
    if not isinstance(data, dict):
        raise RobotFileError(f"{source}: a robot description must be a table (dict), got {type(data).__name__}")
    unknown = set(data) - _KNOWN_TOP_KEYS
    if unknown:
        raise RobotFileError(f"{source}: unknown top-level field(s) {short_repr(sorted(unknown, key=str), 200)}")
    joints_raw = data.get("joints")
    if not isinstance(joints_raw, list) or not joints_raw:
        raise RobotFileError(f"{source}: needs at least one [[joints]] table")
    name = _text(data, "name", source, Path(source).stem) or Path(source).stem
    joints = []
    for i, jd in enumerate(joints_raw):
        raw_label = jd.get("name") if isinstance(jd, dict) else None
        label = raw_label if isinstance(raw_label, str) and 0 < len(raw_label) <= 60 else f"#{i + 1}"
        where = f"{source}: joint {label}"
        if not isinstance(jd, dict):
            raise RobotFileError(f"{where}: must be a table")
        for key in _REQUIRED:
            if key not in jd:
                raise RobotFileError(f"{where}: missing required field '{key}'")
        extra = set(jd) - _KNOWN_JOINT_KEYS
        if extra:
            raise RobotFileError(f"{where}: unknown field(s) {short_repr(sorted(extra, key=str), 200)}")
        jtype = jd["type"]
        if jtype not in ("revolute", "prismatic"):
            raise RobotFileError(f"{where}: field 'type' must be 'revolute' or 'prismatic', got {_short(jtype)}")
        lim = jd["limits"]
        if not isinstance(lim, list) or len(lim) != 2:
            raise RobotFileError(f"{where}: field 'limits' must be [lower, upper], got {_short(lim)}")
        lo, hi = (_number(x, where, "limits", MAX_LIMIT) for x in lim)
        if lo > hi:
            raise RobotFileError(f"{where}: field 'limits': lower limit {lo:g} is above upper limit {hi:g}")
        if jtype == "revolute":
            lo, hi = np.radians(lo), np.radians(hi)
        joints.append(
            Joint(
                type=jtype,
                a=_number(jd.get("a", 0.0), where, "a", MAX_LENGTH),
                alpha=float(np.radians(_number(jd.get("alpha", 0.0), where, "alpha", MAX_ANGLE_DEG))),
                d=_number(jd.get("d", 0.0), where, "d", MAX_LENGTH),
                theta=float(np.radians(_number(jd.get("theta", 0.0), where, "theta", MAX_ANGLE_DEG))),
                lower=float(lo),
                upper=float(hi),
                name=_text(jd, "name", where, f"q{i + 1}") or f"q{i + 1}",
            )
        )
    conv = data.get("dh_convention", "modified")
    if conv not in ("modified", "standard"):
        raise RobotFileError(f"{source}: field 'dh_convention' must be 'modified' or 'standard', got {_short(conv)}")
    return Robot(
        name=name,
        joints=tuple(joints),
        dh_convention=conv,
        T_world_base=_transform(data["base"], f"{source}: [base]") if "base" in data else np.eye(4),
        T_flange_tool=_transform(data["tool"], f"{source}: [tool]") if "tool" in data else np.eye(4),
        length_unit=_text(data, "length_unit", source, "mm") or "mm",
        default_reduction=_text(data, "default_reduction", source, None),
        description=_text(data, "description", source, "") or "",
    )


def load_robot(name_or_path: str | Path | Robot) -> Robot:
    """Load a bundled robot by name (e.g. ``"carm"``) or a robot file (TOML) by path.

    A path is taken as a file when it ends in ``.toml`` or exists. Every problem with the file raises a
    :class:`~sweepik.errors.RobotFileError` naming it (a directory, no permission, larger than
    ``MAX_ROBOT_FILE_BYTES``, not UTF-8, not TOML, nested too deeply, a field out of the bounds in the module
    docstring); an unknown name or a missing file raises :class:`~sweepik.errors.UnknownRobotError` listing the
    bundled robots.

    >>> load_robot("carm").n_joints
    6
    """
    if isinstance(name_or_path, Robot):
        return name_or_path
    bundled = bundled_robots()
    if not isinstance(name_or_path, str | PathLike):
        raise UnknownRobotError(
            f"robot must be a bundled robot's name, a robot file path or a Robot, got "
            f"{type(name_or_path).__name__} {short_repr(name_or_path, 40)}; bundled robots: {', '.join(bundled)}"
        )
    path = as_path(name_or_path, RobotFileError, "robot file")
    if str(path) in bundled:
        res = resources.files("sweepik") / "robots" / f"{path}.toml"
        return _parse(res.read_text(encoding="utf-8"), f"{path}.toml (bundled)")
    st = file_status(path, RobotFileError, "robot file")
    if st is None:
        if path.suffix.lower() == ".toml":
            raise UnknownRobotError(f"robot file {str(path)!r} does not exist; bundled robots: {', '.join(bundled)}")
        raise UnknownRobotError(
            f"unknown robot {str(path)!r}: not a bundled robot nor a file; bundled robots: {', '.join(bundled)}"
        )
    blob = read_file_bytes(path, MAX_ROBOT_FILE_BYTES, RobotFileError, "robot file")
    return _parse(decode_text(blob, path, RobotFileError, "robot file (TOML)"), str(path))


def _parse(raw: str, source: str) -> Robot:
    try:
        data = tomllib.loads(raw)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise RobotFileError(f"{source}: not a robot file: arrays or tables nested too deeply") from None
    except ValueError:  # an integer beyond Python's int-string conversion limit (4300 digits)
        raise RobotFileError(f"{source}: not a robot file: a number with thousands of digits") from None
    return robot_from_dict(data, source)
