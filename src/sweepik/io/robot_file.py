"""Robot files (TOML, written by hand) and the bundled robots.

File format (angles in degrees, lengths in ``length_unit``)::

    name = "carm"
    dh_convention = "modified"        # or "standard"; or "none": joints by origin and axis (below)
    length_unit = "mm"
    default_reduction = "carm-d1"     # optional: the IK reduction ``solve`` uses by default
    gravity = [0.0, 1.0, 0.0]         # optional: direction of gravity in the world frame (default [0, 0, -1])

    [[joints]]
    name = "d1"
    type = "prismatic"                # or "revolute"
    a = 0.0                           # DH row constants; the joint value adds to theta (revolute) or d
    alpha = 0.0
    d = 0.0
    theta = 0.0
    limits = [0.0, 2000.0]            # degrees for revolute joints, length unit for prismatic ones
    mass = 2.5                        # optional: kg, the link this joint moves (default 0)
    com = [0.0, 0.0, 120.0]           # optional: its centre of mass in this joint's link frame (length unit)

    [base]                            # optional, likewise [tool]
    xyz = [0.0, 0.0, 0.0]
    zyz = [0.0, 0.0, 0.0]             # degrees

Missing ``a``, ``alpha``, ``d``, ``theta`` default to 0; ``type`` and ``limits`` are required.

**Joints by origin and axis** (as URDF describes them, no DH table): ``dh_convention = "none"`` (the default when
a joint has ``origin`` or ``axis``), and each joint gives, instead of ``a``/``alpha``/``d``/``theta``::

    [[joints]]
    name = "shoulder_lift"
    type = "revolute"
    origin = { xyz = [0.0, 0.13585, 0.0], rpy = [0.0, 90.0, 0.0] }   # from the previous joint's frame
    axis = [0.0, 1.0, 0.0]                                          # in this joint's frame (default z)
    limits = [-360.0, 360.0]

``origin`` is the fixed transform from the previous joint's frame (the base frame for the first joint) to this
joint's frame at zero joint value: ``xyz`` in ``length_unit``, ``rpy`` roll-pitch-yaw in **degrees** (URDF's
fixed-axis convention, ``R = Rz(yaw) Ry(pitch) Rx(roll)``); both default to zeros. The joint turns about (or
slides along) ``axis``. ``[tool]`` is then the transform from the last joint's frame to the tool; it may be
given as ``xyz`` + ``rpy`` instead of ``zyz`` (likewise ``[base]``).

Bounds (a file outside them raises :class:`~sweepik.errors.RobotFileError` naming the file, joint and field):

* the file: UTF-8 TOML of at most ``MAX_ROBOT_FILE_BYTES`` (1 MiB), checked before it is read;
* lengths (``a``, ``d``, ``[base]``/``[tool]`` ``xyz``): finite, ``|x| <= MAX_LENGTH`` (1e12 length units);
* angles (``alpha``, ``theta``, ``zyz``): finite, ``|x| <= MAX_ANGLE_DEG`` (1e6 degrees);
* ``limits``: finite, ``|x| <= MAX_LIMIT`` (1e300 degrees or length units: huge limits mean no practical end);
* text fields (``name``, ``description``, ``length_unit``, ``default_reduction``, joint ``name``): strings.
"""

from __future__ import annotations

import difflib
import tomllib
from importlib import resources
from os import PathLike
from pathlib import Path
from typing import Any

import numpy as np

from sweepik.errors import RobotFileError, UnknownOptionError, UnknownRobotError
from sweepik.model.pose import pose_from_xyz_rpy, pose_from_xyz_zyz
from sweepik.model.robot import Joint, Robot
from sweepik.model.validate import (
    MAX_ANGLE_DEG,
    MAX_LENGTH,
    MAX_LIMIT,
    MAX_MASS,
    as_path,
    decode_text,
    file_status,
    read_file_bytes,
    short_repr,
)

__all__ = ["load_robot", "bundled_robots", "robot_from_dict", "robot_to_toml"]

_REQUIRED = ("type", "limits")
_DH_KEYS = ("a", "alpha", "d", "theta")
_ORIGIN_AXIS_KEYS = ("origin", "axis")
_MASS_KEYS = ("mass", "com")
_KNOWN_JOINT_KEYS = {"name", "type", "limits", *_DH_KEYS, *_ORIGIN_AXIS_KEYS, *_MASS_KEYS}
_KNOWN_TOP_KEYS = {
    "name",
    "description",
    "dh_convention",
    "length_unit",
    "default_reduction",
    "gravity",
    "joints",
    "base",
    "tool",
}


def bundled_robots() -> list[str]:
    """Names of the robots shipped with sweepik."""
    files = resources.files("sweepik.io") / "robots"
    return sorted(p.name[:-5] for p in files.iterdir() if p.name.endswith(".toml"))


#: Robot files larger than this are refused before they are read (a 6-joint arm takes about 1 KiB).
MAX_ROBOT_FILE_BYTES = 1 << 20


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


def _triple(table: dict[str, Any], key: str, where: str, bound: float, default: list[float]) -> list[float]:
    v = table.get(key, default)
    if not isinstance(v, list) or len(v) != 3:
        raise RobotFileError(f"{where}: field '{key}' must be a list of 3 numbers, got {_short(v)}")
    return [_number(x, where, key, bound) for x in v]


def _transform(table: Any, where: str, rpy_only: bool = False) -> np.ndarray:
    """A transform written as ``xyz`` (length unit) and ``zyz`` or ``rpy`` angles (degrees)."""
    angles = ("rpy",) if rpy_only else ("zyz", "rpy")
    expected = "'xyz' and " + " or ".join(f"'{a}'" for a in angles) + " (degrees)"
    if not isinstance(table, dict):
        raise RobotFileError(f"{where}: must be a table with {expected}")
    unknown = set(table) - {"xyz", *angles}
    if unknown:
        raise RobotFileError(
            f"{where}: unknown field(s) {short_repr(sorted(unknown, key=str), 200)}; expected {expected}"
        )
    if "zyz" in table and "rpy" in table:
        raise RobotFileError(f"{where}: give the rotation as 'zyz' or as 'rpy', not both")
    xyz = _triple(table, "xyz", where, MAX_LENGTH, [0.0, 0.0, 0.0])
    if "rpy" in table:
        return pose_from_xyz_rpy(xyz, np.radians(_triple(table, "rpy", where, MAX_ANGLE_DEG, [])))
    return pose_from_xyz_zyz(xyz, np.radians(_triple(table, "zyz", where, MAX_ANGLE_DEG, [0.0, 0.0, 0.0])))


def _joint_geometry(jd: dict[str, Any], where: str, convention: str) -> dict[str, Any]:
    """The ``Joint`` keywords of a joint's geometry: DH constants, or origin + axis (``convention == "none"``)."""
    if convention != "none":
        bad = [k for k in _ORIGIN_AXIS_KEYS if k in jd]
        if bad:
            raise RobotFileError(
                f"{where}: field '{bad[0]}' describes a joint by origin and axis; this file uses DH rows "
                f"(dh_convention {convention!r}): write every joint one way"
            )
        return {
            "a": _number(jd.get("a", 0.0), where, "a", MAX_LENGTH),
            "alpha": float(np.radians(_number(jd.get("alpha", 0.0), where, "alpha", MAX_ANGLE_DEG))),
            "d": _number(jd.get("d", 0.0), where, "d", MAX_LENGTH),
            "theta": float(np.radians(_number(jd.get("theta", 0.0), where, "theta", MAX_ANGLE_DEG))),
        }
    bad = [k for k in _DH_KEYS if k in jd]
    if bad:
        raise RobotFileError(
            f"{where}: field '{bad[0]}' is a DH constant; this file describes joints by origin and axis "
            "(dh_convention 'none'): write every joint one way"
        )
    origin = _transform(jd.get("origin", {}), f"{where}: origin", rpy_only=True)
    axis = _triple(jd, "axis", where, MAX_LENGTH, [0.0, 0.0, 1.0])
    if float(np.linalg.norm(axis)) < 1e-9:
        raise RobotFileError(f"{where}: field 'axis' must not be zero, got {_short(jd.get('axis'))}")
    return {"origin": tuple(tuple(float(v) for v in row) for row in origin), "axis": tuple(axis)}


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
    by_origin = any(isinstance(jd, dict) and any(k in jd for k in _ORIGIN_AXIS_KEYS) for jd in joints_raw)
    conv = data.get("dh_convention", "none" if by_origin else "modified")
    if conv not in ("modified", "standard", "none"):
        raise RobotFileError(
            f"{source}: field 'dh_convention' must be 'modified', 'standard' or 'none', got {_short(conv)}"
        )
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
                lower=float(lo),
                upper=float(hi),
                name=_text(jd, "name", where, f"q{i + 1}") or f"q{i + 1}",
                **_joint_geometry(jd, where, conv),
                **_joint_mass(jd, where),
            )
        )
    return Robot(
        name=name,
        joints=tuple(joints),
        dh_convention=conv,
        T_world_base=_transform(data["base"], f"{source}: [base]") if "base" in data else np.eye(4),
        T_flange_tool=_transform(data["tool"], f"{source}: [tool]") if "tool" in data else np.eye(4),
        length_unit=_text(data, "length_unit", source, "mm") or "mm",
        default_reduction=_text(data, "default_reduction", source, None),
        description=_text(data, "description", source, "") or "",
        gravity=_gravity(data, source),
    )


def _joint_mass(jd: dict[str, Any], where: str) -> dict[str, Any]:
    """``mass`` (kg, >= 0) and ``com`` (length unit, in the joint's link frame) of a joint's link."""
    mass = _number(jd.get("mass", 0.0), where, "mass", MAX_MASS)
    if mass < 0.0:
        raise RobotFileError(f"{where}: field 'mass' must be >= 0 kg, got {_short(jd.get('mass'))}")
    return {"mass": mass, "com": tuple(_triple(jd, "com", where, MAX_LENGTH, [0.0, 0.0, 0.0]))}


def _gravity(data: dict[str, Any], source: str) -> tuple[float, float, float]:
    g = _triple(data, "gravity", source, MAX_LENGTH, [0.0, 0.0, -1.0])
    if float(np.linalg.norm(g)) < 1e-9:
        raise RobotFileError(f"{source}: field 'gravity' must be a direction (not all zero), got {_short(g)}")
    return (g[0], g[1], g[2])


def load_robot(name_or_path: str | Path | Robot, base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """Load a robot: a bundled one by name (e.g. ``"carm"``, any case), a robot file (TOML), a URDF (``.urdf``) or an
    MJCF file (``.xml`` / ``.mjcf``, read by MuJoCo: the ``mjcf`` extra) by path, or an arm of the catalogues people
    use by its name there (:mod:`sweepik.io.catalogues`): a robot_descriptions name (``"ur10e_description"``,
    ``"ur5e_mj_description"``) whose description is in robot_descriptions' cache, or an example-robot-data name
    (``"example-robot-data:ur5"``, or a bare one no bundled arm has, such as ``"panda"``).

    ``base_link`` and ``tip_link`` choose the chain of a URDF or MJCF (see :func:`sweepik.io.urdf.read_urdf` and
    :func:`sweepik.io.mjcf.read_mjcf`: by default its root and the last moving joint's link, when the moving joints
    form one chain; an MJCF tip may be a site); they are refused for other robots. A path is taken as a file when it
    ends in ``.toml``, ``.urdf``, ``.xml`` or ``.mjcf`` or exists (an existing file of another extension whose text
    starts with ``<`` is read as URDF, or as MJCF when it starts with ``<mujoco``). Every problem with the file
    raises a :class:`~sweepik.errors.RobotFileError` naming it (a directory, no permission, larger than
    ``MAX_ROBOT_FILE_BYTES``, not UTF-8, not TOML, nested too deeply, a field out of the bounds in the module
    docstring); an unknown name or a missing file raises :class:`~sweepik.errors.UnknownRobotError` listing the
    bundled robots and the names closest to the one given; a catalogue name whose file is not here (not installed,
    not downloaded) says what would fetch it.

    >>> load_robot("carm").n_joints
    6
    >>> load_robot("UR5").name
    'ur5'
    """
    for what, link in (("base_link", base_link), ("tip_link", tip_link)):
        if link is not None and not isinstance(link, str):
            raise UnknownOptionError(f"{what} must be a link name (a string), got {type(link).__name__}")
    links = {"base_link": base_link, "tip_link": tip_link}
    if isinstance(name_or_path, Robot):
        if base_link is not None or tip_link is not None:
            raise UnknownOptionError("base_link/tip_link choose the chain of a URDF file, not of a loaded Robot")
        return name_or_path
    bundled = bundled_robots()
    if not isinstance(name_or_path, str | PathLike):
        raise UnknownRobotError(
            f"robot must be a bundled robot's name, a robot file path or a Robot, got "
            f"{type(name_or_path).__name__} {short_repr(name_or_path, 40)}; bundled robots: {', '.join(bundled)}"
        )
    path = as_path(name_or_path, RobotFileError, "robot file")
    suffix = path.suffix.lower()
    if suffix in _XML_SUFFIXES:
        return _read_xml(path, suffix, **links)
    name = _bundled_name(str(path), bundled) if suffix != ".toml" else None
    if name is not None:
        if base_link is not None or tip_link is not None:
            raise UnknownOptionError(
                f"base_link/tip_link choose the chain of a URDF or MJCF file; {name!r} is a bundled robot"
            )
        res = resources.files("sweepik.io") / "robots" / f"{name}.toml"
        return _parse(res.read_text(encoding="utf-8"), f"{name}.toml (bundled)")
    st = file_status(path, RobotFileError, "robot file")
    if st is None:
        if suffix == ".toml":
            raise UnknownRobotError(f"robot file {str(path)!r} does not exist; bundled robots: {', '.join(bundled)}")
        return _from_catalogue(str(path), bundled, **links)
    blob = read_file_bytes(path, MAX_ROBOT_FILE_BYTES, RobotFileError, "robot file")
    if suffix != ".toml" and blob.lstrip()[:1] == b"<":
        return _read_xml(path, ".mjcf" if blob.lstrip()[:7] == b"<mujoco" else ".urdf", **links)
    if base_link is not None or tip_link is not None:
        raise UnknownOptionError(
            f"base_link/tip_link choose the chain of a URDF or MJCF file; {str(path)!r} is a TOML robot file"
        )
    return _parse(decode_text(blob, path, RobotFileError, "robot file (TOML)"), str(path))


#: File suffixes read as XML robots: URDF, and MJCF (MuJoCo's ``.xml``).
_XML_SUFFIXES = (".urdf", ".xml", ".mjcf")


def _read_xml(path: Path, suffix: str, base_link: str | None, tip_link: str | None) -> Robot:
    """A URDF (``.urdf``) or MJCF (``.xml``, ``.mjcf``) file's chain; the XML readers are loaded only for them."""
    if suffix == ".urdf":
        from sweepik.io.urdf import read_urdf

        return read_urdf(path, base_link=base_link, tip_link=tip_link)
    from sweepik.io.mjcf import read_mjcf

    return read_mjcf(path, base_link=base_link, tip_link=tip_link)


def _bundled_name(name: str, bundled: list[str]) -> str | None:
    """The bundled robot ``name`` names, compared without case (``"UR5"`` is ``"ur5"``); None if none."""
    if name in bundled:
        return name
    folded = {b.casefold(): b for b in bundled}
    return folded.get(name.casefold())


def _from_catalogue(name: str, bundled: list[str], base_link: str | None, tip_link: str | None) -> Robot:
    """A catalogue's arm (``catalogues.find_in_catalogues``), or UnknownRobotError with the closest names."""
    from sweepik.io.catalogues import catalogue_names, find_in_catalogues

    entry = find_in_catalogues(name)
    if entry is None:
        known = list(dict.fromkeys([*bundled, *catalogue_names()]))
        close = [k for k in (f"{name}_description", f"{name}_mj_description") if k in known]
        close += [c for c in difflib.get_close_matches(name.casefold(), known, n=3, cutoff=0.6) if c not in close]
        hint = f" Did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownRobotError(
            f"unknown robot {name!r}: not a bundled robot nor a file, nor a robot_descriptions or example-robot-data "
            f"name.{hint} Bundled robots: {', '.join(bundled)}"
        )
    if not entry.path.is_file():
        raise UnknownRobotError(f"{name!r}: {entry.origin} should hold {entry.path}, which is not there")
    tip = tip_link if tip_link is not None else entry.tip_link
    return _read_xml(entry.path, "." + entry.format, base_link, tip)


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


_TOML_ESCAPES = {"\\": "\\\\", '"': '\\"', "\n": "\\n", "\t": "\\t", "\r": "\\r"}


def _control(c: str) -> bool:
    return ord(c) < 0x20 or ord(c) == 0x7F


def _toml_value(v: object) -> str:
    """A TOML literal for a string, a float (``repr``: read back exactly) or a list of them."""
    if isinstance(v, str):  # a TOML basic string: backslash, quote and control characters escaped
        return '"' + "".join(_TOML_ESCAPES.get(c) or (f"\\u{ord(c):04X}" if _control(c) else c) for c in v) + '"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(_toml_value(x) for x in v) + "]"
    return repr(float(v))  # type: ignore[arg-type]


def _transform_table(T: np.ndarray, rpy: bool) -> dict[str, list[float]]:
    from sweepik.model.pose import rpy_from_matrix, zyz_from_matrix

    angles = rpy_from_matrix(T) if rpy else zyz_from_matrix(T)
    return {"xyz": [float(x) for x in T[:3, 3]], "rpy" if rpy else "zyz": [float(x) for x in np.degrees(angles)]}


def robot_to_toml(robot: Robot) -> str:
    """The text of a robot file for ``robot`` (read back by :func:`load_robot` with the same FK to rounding).

    DH arms keep their DH rows; origin + axis arms (URDF imports, locked arms) are written joint by joint with
    ``origin`` (``xyz``, ``rpy`` in degrees) and ``axis``. Angles in degrees, lengths in the robot's unit.
    """
    none = robot.dh_convention == "none"
    lines = [f"# written by sweepik from robot {robot.name!r}", f"name = {_toml_value(robot.name)}"]
    if robot.description:
        lines.append(f"description = {_toml_value(robot.description)}")
    lines += [f"dh_convention = {_toml_value(robot.dh_convention)}", f"length_unit = {_toml_value(robot.length_unit)}"]
    if robot.default_reduction:
        lines.append(f"default_reduction = {_toml_value(robot.default_reduction)}")
    if robot.gravity != (0.0, 0.0, -1.0):
        lines.append(f"gravity = {_toml_value(list(robot.gravity))}")
    for name, j in zip(robot.joint_names, robot.joints, strict=True):
        lim = [j.lower, j.upper]
        lim = [float(np.degrees(x)) for x in lim] if j.is_revolute else lim
        lines += ["", "[[joints]]", f"name = {_toml_value(name)}", f"type = {_toml_value(j.type)}"]
        if none:
            org = _transform_table(np.array(j.origin), rpy=True)
            lines.append(f"origin = {{ xyz = {_toml_value(org['xyz'])}, rpy = {_toml_value(org['rpy'])} }}")
            lines.append(f"axis = {_toml_value(list(j.axis))}")
        else:
            lines += [f"a = {_toml_value(j.a)}", f"alpha = {_toml_value(float(np.degrees(j.alpha)))}"]
            lines += [f"d = {_toml_value(j.d)}", f"theta = {_toml_value(float(np.degrees(j.theta)))}"]
        lines.append(f"limits = {_toml_value(lim)}")
        if j.mass or j.com != (0.0, 0.0, 0.0):
            lines += [f"mass = {_toml_value(j.mass)}", f"com = {_toml_value(list(j.com))}"]
    for table, T in (("base", robot.T_world_base), ("tool", robot.T_flange_tool)):
        if not np.array_equal(T, np.eye(4)):
            lines += ["", f"[{table}]"]
            lines += [f"{k} = {_toml_value(v)}" for k, v in _transform_table(T, rpy=none).items()]
    return "\n".join(lines) + "\n"
