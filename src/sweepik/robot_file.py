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
"""

from __future__ import annotations

import tomllib
from importlib import resources
from pathlib import Path
from typing import Any

import numpy as np

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


def _number(value: Any, where: str, field: str, bound: float = np.inf) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise RobotFileError(f"{where}: field '{field}' must be a finite number, got {value!r}")
    try:
        x = float(value)
    except OverflowError:
        x = np.inf
    if not np.isfinite(x) or abs(x) > bound:
        limit = "" if bound == np.inf else f" of magnitude at most {bound:g}"
        raise RobotFileError(f"{where}: field '{field}' must be a finite number{limit}, got {_short(value)}")
    return x


def _short(value: Any) -> str:
    text = (
        repr(value)
        if not isinstance(value, int) or abs(value) < 10**30
        else f"an integer of {len(str(abs(value)))} digits"
    )
    return text if len(text) <= 60 else text[:57] + "..."


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
        raise RobotFileError(f"{where}: unknown field(s) {sorted(unknown)}; expected 'xyz' and 'zyz'")
    vecs = []
    for key in ("xyz", "zyz"):
        v = table.get(key, [0.0, 0.0, 0.0])
        if not isinstance(v, list) or len(v) != 3:
            raise RobotFileError(f"{where}: field '{key}' must be a list of 3 numbers, got {v!r}")
        vecs.append([_number(x, where, key, MAX_LENGTH if key == "xyz" else np.inf) for x in v])
    return pose_from_xyz_zyz(vecs[0], np.radians(vecs[1]))


def robot_from_dict(data: dict[str, Any], source: str = "<dict>") -> Robot:
    """Build a Robot from the parsed contents of a robot file; errors name ``source``, the joint and field."""
    unknown = set(data) - _KNOWN_TOP_KEYS
    if unknown:
        raise RobotFileError(f"{source}: unknown top-level field(s) {sorted(unknown)}")
    joints_raw = data.get("joints")
    if not isinstance(joints_raw, list) or not joints_raw:
        raise RobotFileError(f"{source}: needs at least one [[joints]] table")
    name = _text(data, "name", source, Path(source).stem) or Path(source).stem
    joints = []
    for i, jd in enumerate(joints_raw):
        label = jd.get("name", f"#{i + 1}") if isinstance(jd, dict) else f"#{i + 1}"
        where = f"{source}: joint {label}"
        if not isinstance(jd, dict):
            raise RobotFileError(f"{where}: must be a table")
        for key in _REQUIRED:
            if key not in jd:
                raise RobotFileError(f"{where}: missing required field '{key}'")
        extra = set(jd) - _KNOWN_JOINT_KEYS
        if extra:
            raise RobotFileError(f"{where}: unknown field(s) {sorted(extra)}")
        jtype = jd["type"]
        if jtype not in ("revolute", "prismatic"):
            raise RobotFileError(f"{where}: field 'type' must be 'revolute' or 'prismatic', got {jtype!r}")
        lim = jd["limits"]
        if not isinstance(lim, list) or len(lim) != 2:
            raise RobotFileError(f"{where}: field 'limits' must be [lower, upper], got {lim!r}")
        lo, hi = (_number(x, where, "limits") for x in lim)
        if lo > hi:
            raise RobotFileError(f"{where}: field 'limits': lower limit {lo:g} is above upper limit {hi:g}")
        if jtype == "revolute":
            lo, hi = np.radians(lo), np.radians(hi)
        joints.append(
            Joint(
                type=jtype,
                a=_number(jd.get("a", 0.0), where, "a", MAX_LENGTH),
                alpha=float(np.radians(_number(jd.get("alpha", 0.0), where, "alpha"))),
                d=_number(jd.get("d", 0.0), where, "d", MAX_LENGTH),
                theta=float(np.radians(_number(jd.get("theta", 0.0), where, "theta"))),
                lower=float(lo),
                upper=float(hi),
                name=_text(jd, "name", where, f"q{i + 1}") or f"q{i + 1}",
            )
        )
    conv = data.get("dh_convention", "modified")
    if conv not in ("modified", "standard"):
        raise RobotFileError(f"{source}: field 'dh_convention' must be 'modified' or 'standard', got {conv!r}")
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

    >>> load_robot("carm").n_joints
    6
    """
    if isinstance(name_or_path, Robot):
        return name_or_path
    text_name = str(name_or_path)
    path = Path(text_name)
    bundled = bundled_robots()
    if text_name in bundled:
        res = resources.files("sweepik") / "robots" / f"{text_name}.toml"
        raw, source = res.read_text(encoding="utf-8"), f"{text_name}.toml (bundled)"
    elif path.suffix == ".toml" or path.exists():
        if not path.exists():
            raise UnknownRobotError(f"robot file {text_name!r} does not exist; bundled robots: {', '.join(bundled)}")
        if not path.is_file():
            raise RobotFileError(f"{text_name}: is not a file")
        source = str(path)
        try:
            with path.open("rb") as fh:
                blob = fh.read(MAX_ROBOT_FILE_BYTES + 1)
        except OSError as exc:
            raise RobotFileError(f"{path}: cannot read robot file: {exc.strerror or exc}") from None
        if len(blob) > MAX_ROBOT_FILE_BYTES:
            raise RobotFileError(f"{path}: larger than {MAX_ROBOT_FILE_BYTES} bytes; not a robot file")
        try:
            raw = blob.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise RobotFileError(f"{path}: not UTF-8 text (byte {exc.start}); robot files are TOML") from None
    else:
        raise UnknownRobotError(
            f"unknown robot {text_name!r}: not a bundled robot nor a file; bundled robots: {', '.join(bundled)}"
        )
    try:
        data = tomllib.loads(raw)
    except tomllib.TOMLDecodeError as exc:
        raise RobotFileError(f"{source}: not valid TOML: {exc}") from None
    except RecursionError:
        raise RobotFileError(f"{source}: not a robot file: arrays or tables nested too deeply") from None
    except ValueError:  # an integer beyond Python's int-string conversion limit (4300 digits)
        raise RobotFileError(f"{source}: not a robot file: a number with thousands of digits") from None
    return robot_from_dict(data, source)
