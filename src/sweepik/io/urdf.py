"""URDF in and out: read a serial chain from a URDF file safely, and write any Robot as URDF.

Conventions (those of URDF, http://wiki.ros.org/urdf/XML/joint):

* Lengths in metres, angles in radians. A robot read from URDF has ``length_unit="m"``; ``urdf_text`` converts
  the robot's lengths to metres (``units.MM_PER_UNIT``).
* ``<origin xyz="x y z" rpy="roll pitch yaw">`` is the fixed transform from the parent link's frame to the joint
  frame (= the child link's frame at q = 0); rpy are fixed-axis angles, ``R = Rz(yaw) @ Ry(pitch) @ Rx(roll)``.
  A missing origin (or attribute) is the identity (zero).
* ``<axis xyz>`` is in the joint frame; it defaults to (1, 0, 0) and is normalised. A revolute or continuous joint
  turns about it, a prismatic one slides along it: the child frame is ``origin @ Rot(axis, q)`` (or
  ``origin @ Trans(axis * q)``), exactly sweepik's ``dh_convention="none"`` (see :mod:`sweepik.model.robot`).

Reading is safe by construction: the XML goes through ``defusedxml`` with document type declarations refused
(so no entity expansion, no external entity, nothing fetched), the size is bounded before parsing
(``MAX_URDF_BYTES``, and ``MAX_URDF_TAGS`` counted in C), the parser builds no tree (it keeps only the links and
joints of ``<robot>`` and stops at ``MAX_URDF_JOINTS`` joints or ``MAX_URDF_DEPTH`` levels of nesting), and
meshes, ``package://`` resources, visuals and collisions are never looked at.

Masses: a link's ``<inertial>`` gives its ``<mass value>`` (kg) and centre of mass (``<origin xyz>``, in the link's
frame); a chain link becomes the mass and ``com`` of the joint that moves it, and links rigidly attached to it on
the chain (fixed joints) are merged into it. Links before the first moving joint ride on the base (no effect on
joint torques) and links off the chain are left out; inertia tensors are not used (statics needs none).
"""

from __future__ import annotations

import math
import re
import xml.etree.ElementTree as ET
from collections import deque
from dataclasses import dataclass, field
from os import PathLike
from pathlib import Path

import defusedxml
import numpy as np
from defusedxml.ElementTree import DefusedXMLParser, ParseError
from numpy.typing import NDArray

from sweepik.errors import RobotDefinitionError, UnknownOptionError, UrdfError
from sweepik.model.origin_axis import joint_origins, link_masses
from sweepik.model.pose import matrix_from_rpy, rpy_from_matrix
from sweepik.model.robot import AXIS_MIN_NORM, Joint, Robot
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import MAX_ANGLE_DEG, MAX_LENGTH, MAX_LIMIT, MAX_MASS, as_path, read_file_bytes, short_repr

__all__ = [
    "read_urdf",
    "robot_from_urdf",
    "urdf_text",
    "MAX_URDF_BYTES",
    "MAX_URDF_TAGS",
    "MAX_URDF_ATTRIBUTES",
    "MAX_URDF_JOINTS",
    "MAX_URDF_DEPTH",
]

Array = NDArray[np.float64]

#: URDF files (or texts, UTF-8 encoded) larger than this are refused before parsing. The largest robot in
#: example-robot-data (PR2, every visual, collision and inertial inline) is 130 kB, a 7-axis arm 20-60 kB: 4 MiB
#: leaves 30 times that (a few MB of URDF is a generated file of thousands of links, beyond any serial arm).
MAX_URDF_BYTES = 4 << 20
#: Texts with more markup characters ``<`` than this (an upper bound on the number of elements, tags and comments,
#: counted in C before parsing) are refused: defusedxml parses with Python callbacks, 1.5-3 us a tag, so 4 MiB
#: of empty tags would take 1.5 s; 100,000 tags take at most about 0.3 s and are 28 times PR2's 3,600.
MAX_URDF_TAGS = 100_000
#: ... and at most this many '=' (attributes; also counted in C before parsing): the parser hands every
#: attribute of an element to Python, and 4 MiB of attributes on one element took 2-4 s to refuse. A URDF element
#: has a handful (a 7-axis arm's file: ~1,500 in all).
MAX_URDF_ATTRIBUTES = 100_000
#: More ``<joint>`` elements than this are refused as soon as the parser meets the next one: a humanoid has about
#: 50 joints, a full mobile manipulator with hands about 100; a serial arm 6-7.
MAX_URDF_JOINTS = 1000
#: Elements nested deeper than this are refused: URDF nests 5 levels (robot/link/visual/geometry/mesh), plugin
#: blocks a few more. (No tree is built, so depth costs nothing here; deeper nesting is simply not a URDF.)
MAX_URDF_DEPTH = 64
#: Candidate tip links listed at most in the "not a chain" message (and links or roots in other messages).
MAX_LISTED = 10
#: Bounds of the numbers read: lengths as the TOML robot files (metres here), angles the same bound in radians.
MAX_ANGLE_RAD = math.radians(MAX_ANGLE_DEG)

_JOINT_TYPES = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
_JOINT_CHILDREN = ("parent", "child", "origin", "axis", "limit", "mimic")
#: A decimal number as URDF writes it (no ``nan``, ``inf``, ``0x``, ``1_000`` that Python's float() would take).
_NUMBER = re.compile(r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
#: Characters XML 1.0 cannot hold (control characters other than tab/newline/return, surrogates, U+FFFE/F).
_NOT_XML = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\ud800-\udfff\ufffe\uffff]")


@dataclass
class _RawJoint:
    """A ``<joint>`` as found: its attributes and those of its ``parent``/``child``/``origin``/... children."""

    name: str
    type: str
    tags: dict[str, dict[str, str]] = field(default_factory=dict)


@dataclass(frozen=True)
class _UrdfJoint:
    """A checked joint: link names, origin (4, 4), unit axis (3,), limits (radians or metres), mimic flag."""

    name: str
    type: str
    parent: str
    child: str
    origin: Array
    axis: Array
    lower: float
    upper: float
    mimic: bool


def _cut(names: list[str]) -> str:
    shown = ", ".join(repr(n) for n in names[:MAX_LISTED])
    return shown + (f", ... ({len(names)} in all)" if len(names) > MAX_LISTED else "")


class _Collector:
    """Parser target keeping only ``<robot>``'s ``<link>``/``<joint>`` elements (no tree is built); raises
    UrdfError on the first element past the bounds, which stops the parser there."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.depth = 0
        self.robot_name = ""
        self.links: dict[str, None] = {}  # ordered set, in file order
        self.joints: list[_RawJoint] = []
        self._joint_names: set[str] = set()
        self._joint: _RawJoint | None = None
        self._link: str | None = None
        self._in_inertial = False
        #: link name -> attributes of its ``<inertial>``'s ``<mass>`` and ``<origin>`` children
        self.inertials: dict[str, dict[str, dict[str, str]]] = {}

    def start(self, tag: str, attrib: dict[str, str]) -> None:
        self.depth += 1
        src = self.source
        if self.depth > MAX_URDF_DEPTH:
            raise UrdfError(f"{src}: elements nested more than {MAX_URDF_DEPTH} deep; a URDF nests a few levels")
        if self.depth == 1:
            if tag != "robot":
                raise UrdfError(f"{src}: the root element must be <robot>, got <{tag[:40]}>")
            self.robot_name = attrib.get("name", "")
        elif self.depth == 2 and tag == "link":
            name = attrib.get("name")
            if not name:
                raise UrdfError(f"{src}: link #{len(self.links) + 1}: missing attribute 'name'")
            if name in self.links:
                raise UrdfError(f"{src}: link {name!r} is defined twice")
            if len(self.links) > MAX_URDF_JOINTS:
                raise UrdfError(f"{src}: more than {MAX_URDF_JOINTS + 1} links; sweepik reads at most that many")
            self.links[name] = None
            self._link = name
        elif self.depth == 3 and self._link is not None and tag == "inertial":
            self._in_inertial = True
            self.inertials.setdefault(self._link, {})
        elif self.depth == 4 and self._in_inertial and self._link is not None and tag in ("mass", "origin"):
            self.inertials[self._link][tag] = dict(attrib)
        elif self.depth == 2 and tag == "joint":
            name = attrib.get("name")
            where = f"{src}: joint {name!r}" if name else f"{src}: joint #{len(self.joints) + 1}"
            if not name:
                raise UrdfError(f"{where}: missing attribute 'name'")
            if name in self._joint_names:
                raise UrdfError(f"{where} is defined twice")
            if len(self.joints) >= MAX_URDF_JOINTS:
                raise UrdfError(f"{src}: more than {MAX_URDF_JOINTS} joints; sweepik reads at most that many")
            jtype = attrib.get("type")
            if jtype not in _JOINT_TYPES:
                raise UrdfError(
                    f"{where}: unknown joint type {short_repr(jtype, 40)}; URDF's types: {', '.join(_JOINT_TYPES)}"
                )
            self._joint = _RawJoint(name, jtype)
            self._joint_names.add(name)
            self.joints.append(self._joint)
        elif self.depth == 3 and self._joint is not None and tag in _JOINT_CHILDREN:
            if tag in self._joint.tags:
                raise UrdfError(f"{src}: joint {self._joint.name!r}: two <{tag}> elements (URDF allows one)")
            self._joint.tags[tag] = dict(attrib)

    def end(self, tag: str) -> None:
        if self.depth == 2:
            self._joint = None
            self._link = None
        elif self.depth == 3:
            self._in_inertial = False
        self.depth -= 1

    def data(self, text: str) -> None:
        """Text is not used by URDF's kinematics."""

    def close(self) -> None:
        """Nothing to build."""


def _collect(blob: bytes, source: str, from_text: bool) -> _Collector:
    target = _Collector(source)
    # Text was encoded to UTF-8 here, whatever its XML declaration says; bytes are decoded as they declare.
    parser = DefusedXMLParser(
        target=target,
        encoding="utf-8" if from_text else None,
        forbid_dtd=True,
        forbid_entities=True,
        forbid_external=True,
    )
    try:
        parser.feed(blob)
        parser.close()
    except defusedxml.DefusedXmlException as exc:
        raise UrdfError(
            f"{source}: document type declaration (<!DOCTYPE>) refused ({type(exc).__name__}): a URDF needs none, "
            f"and the entities it declares could expand to gigabytes or read local files"
        ) from None
    except ParseError as exc:
        raise UrdfError(f"{source}: not well-formed XML: {exc}") from None
    except (LookupError, ValueError) as exc:  # an XML declaration naming an unknown or multi-byte encoding
        raise UrdfError(f"{source}: unsupported text encoding: {exc}") from None
    return target


def _numbers(text: str | None, n: int, where: str, what: str, bound: float, default: str) -> list[float]:
    """``n`` numbers separated by spaces from an attribute (``default`` when absent), each finite and at most
    ``bound`` in magnitude."""
    raw = default if text is None else text
    parts = raw.split()
    count = "a number" if n == 1 else f"{n} numbers separated by spaces"
    if len(parts) != n or not all(_NUMBER.fullmatch(p) for p in parts):
        raise UrdfError(f"{where}: {what} must be {count}, got {short_repr(raw)}")
    values = [float(p) for p in parts]
    if not all(math.isfinite(v) and abs(v) <= bound for v in values):
        raise UrdfError(f"{where}: {what} must be finite, at most {bound:g} in magnitude, got {short_repr(raw)}")
    return values


def _checked(raw: _RawJoint, links: dict[str, None], source: str) -> _UrdfJoint:
    where = f"{source}: joint {raw.name!r}"
    ends = []
    for end in ("parent", "child"):
        link = raw.tags.get(end, {}).get("link")
        if not link:
            raise UrdfError(f"{where}: missing <{end} link=...>")
        if link not in links:
            raise UrdfError(f"{where}: missing {end} link {link!r} (no <link name={link!r}> in the file)")
        ends.append(link)
    org = raw.tags.get("origin", {})
    T = np.eye(4)
    T[:3, 3] = _numbers(org.get("xyz"), 3, where, "origin xyz", MAX_LENGTH, "0 0 0")
    T[:3, :3] = matrix_from_rpy(_numbers(org.get("rpy"), 3, where, "origin rpy", MAX_ANGLE_RAD, "0 0 0"))
    axis = np.array([1.0, 0.0, 0.0])
    if raw.type in ("revolute", "continuous", "prismatic", "planar"):  # fixed/floating joints have no axis
        axis = np.array(_numbers(raw.tags.get("axis", {}).get("xyz"), 3, where, "axis xyz", MAX_LENGTH, "1 0 0"))
        norm = float(np.linalg.norm(axis))
        if norm < AXIS_MIN_NORM:
            raise UrdfError(f"{where}: axis xyz is zero (norm {norm:.3g}); a joint needs a direction")
        axis /= norm
    lower, upper = -math.pi, math.pi
    limit = raw.tags.get("limit")
    if raw.type in ("revolute", "prismatic"):
        if limit is None:
            raise UrdfError(f"{where}: a {raw.type} joint needs <limit lower=... upper=...> (URDF requires it)")
        # URDF: lower and upper default to 0 on revolute and prismatic joints.
        lower = _numbers(limit.get("lower"), 1, where, "limit lower", MAX_LIMIT, "0")[0]
        upper = _numbers(limit.get("upper"), 1, where, "limit upper", MAX_LIMIT, "0")[0]
    elif raw.type == "continuous" and limit is not None and ("lower" in limit or "upper" in limit):
        if "lower" not in limit or "upper" not in limit:
            raise UrdfError(f"{where}: a continuous joint's <limit> needs both lower and upper, or neither (+-pi)")
        lower = _numbers(limit["lower"], 1, where, "limit lower", MAX_LIMIT, "0")[0]
        upper = _numbers(limit["upper"], 1, where, "limit upper", MAX_LIMIT, "0")[0]
    if lower > upper:
        raise UrdfError(f"{where}: limit lower {lower:g} is above upper {upper:g}")
    return _UrdfJoint(raw.name, raw.type, ends[0], ends[1], T, axis, lower, upper, "mimic" in raw.tags)


def _tree(joints: list[_UrdfJoint], links: dict[str, None], source: str) -> tuple[dict[str, _UrdfJoint], str]:
    """``(parent joint of each non-root link, root link)``; UrdfError for two parents, a cycle, several roots."""
    parent_of: dict[str, _UrdfJoint] = {}
    for j in joints:
        if j.child in parent_of:
            raise UrdfError(
                f"{source}: link {j.child!r} has two parent joints, {parent_of[j.child].name!r} and {j.name!r} "
                f"(URDF is a tree)"
            )
        parent_of[j.child] = j
    state: dict[str, int] = {}  # 1: on the walk being followed, 2: leads to a root
    for start in links:
        walk = []
        link = start
        while link in parent_of and link not in state:
            state[link] = 1
            walk.append(link)
            link = parent_of[link].parent
        if state.get(link) == 1:  # came back onto this walk
            cycle = walk[walk.index(link) :]
            raise UrdfError(
                f"{source}: the joints {_cut([parent_of[k].name for k in reversed(cycle)])} form a cycle "
                f"(URDF is a tree)"
            )
        for k in walk:
            state[k] = 2
    if not links:
        raise UrdfError(f"{source}: no <link> element in <robot>: nothing to read")
    roots = [k for k in links if k not in parent_of]
    if len(roots) != 1:  # none would be a cycle, found above
        raise UrdfError(
            f"{source}: {len(roots)} root links (links no joint leads to): {_cut(roots)}; a URDF has exactly one"
        )
    return parent_of, roots[0]


def _path(parent_of: dict[str, _UrdfJoint], base: str, tip: str) -> list[_UrdfJoint] | None:
    """The joints from ``base`` down to ``tip`` in order, or None when ``tip`` is not below ``base``."""
    path = []
    link = tip
    while link != base:
        if link not in parent_of:
            return None
        path.append(parent_of[link])
        link = parent_of[link].parent
    return path[::-1]


def _default_tip(joints: list[_UrdfJoint], parent_of: dict[str, _UrdfJoint], base: str, source: str) -> str:
    """The child link of the last moving joint when every moving joint below ``base`` lies on one path, followed
    further along fixed joints as long as the tree does not branch (a single tool frame is part of the chain; of
    several, e.g. ``ee_link`` and ``tool0``, none is)."""
    children: dict[str, list[_UrdfJoint]] = {}
    for j in joints:
        children.setdefault(j.parent, []).append(j)
    depth = {base: 0}
    order = []  # links below base, breadth first
    queue = deque([base])
    while queue:
        link = queue.popleft()
        order.append(link)
        for j in children.get(link, []):
            depth[j.child] = depth[link] + 1
            queue.append(j.child)
    moving = [j for j in joints if j.parent in depth and j.type != "fixed"]
    if not moving:
        raise UrdfError(f"{source}: no moving joint below link {base!r}: there is no chain to solve for")
    last = max(moving, key=lambda j: depth[j.child])
    on_path = {j.name for j in _path(parent_of, base, last.child) or []}
    off = [j.name for j in moving if j.name not in on_path]
    if off:
        leaves = [k for k in order if k not in children]
        raise UrdfError(
            f"{source}: the tree below {base!r} is not a chain: moving joints {last.name!r} and {off[0]!r} lie on "
            f"different branches; give tip_link, e.g. one of the leaf links {_cut(leaves)}"
        )
    tip = last.child
    while len(children.get(tip, [])) == 1 and children[tip][0].type == "fixed":  # an unbranched tool frame
        tip = children[tip][0].child
    return tip


def robot_from_urdf(
    text: str | bytes, source: str = "<urdf>", base_link: str | None = None, tip_link: str | None = None
) -> Robot:
    """The serial chain from ``base_link`` to ``tip_link`` of a URDF document, as a Robot in origin + axis form.

    Args:
        text: the URDF (``str``, or ``bytes`` decoded as its XML declaration says, UTF-8 by default), at most
            ``MAX_URDF_BYTES`` bytes (UTF-8) and ``MAX_URDF_JOINTS`` joints.
        source: the name used in error messages (the file name).
        base_link: the chain's first link; default: the tree's root. Its frame is the robot's world frame
            (``T_world_base`` is the identity).
        tip_link: the chain's last link. Default: when every moving (non-fixed) joint below ``base_link`` lies on
            one path, the child link of the last of them, followed along fixed joints while the tree does not
            branch (a single tool frame is included; of several, e.g. UR's ``ee_link`` and ``tool0``, none is:
            name one as ``tip_link`` to get it as the tool transform). Otherwise (a gripper with two fingers, a
            humanoid) UrdfError listing leaf links to choose from.

    Returns:
        ``Robot`` with ``dh_convention="none"``, ``length_unit="m"``, the name of ``<robot name>`` (else the
        stem of ``source``) and one joint per moving joint on the chain, with the URDF's name and limits
        (radians, metres; a continuous joint gets +-pi unless its ``<limit>`` gives lower and upper). Fixed joints
        fold into the next moving joint's origin, or into ``T_flange_tool`` after the last one.

    Raises:
        UrdfError naming ``source`` and the joint or link: not XML, a DTD/entity (refused), too large, root not
        ``<robot>``, duplicate names, unknown joint type, a missing parent or child link, a link with two parents,
        a cycle, several roots, a number that is not finite (origin, axis, limits), a zero axis, lower > upper, a
        revolute or prismatic joint without ``<limit>``, base or tip link not found or tip not below base, and a
        ``mimic``, ``floating`` or ``planar`` joint on the chain (off the chain they are ignored).

    >>> r = robot_from_urdf('''<robot name="arm"><link name="a"/><link name="b"/>
    ...   <joint name="j" type="continuous"><parent link="a"/><child link="b"/><axis xyz="0 0 2"/></joint>
    ... </robot>''')
    >>> r.joints[0].axis, r.limits.round(4).tolist()
    ((0.0, 0.0, 1.0), [[-3.1416, 3.1416]])
    """
    for what, value in (("base_link", base_link), ("tip_link", tip_link)):
        if value is not None and not isinstance(value, str):
            raise UrdfError(f"{source}: {what} must be a link name (str) or None, got {short_repr(value, 40)}")
    if isinstance(text, str):
        if len(text) > MAX_URDF_BYTES:  # each character takes at least one byte
            raise UrdfError(f"{source}: {len(text)} characters, more than the {MAX_URDF_BYTES} bytes a URDF may have")
        try:
            blob = text.encode("utf-8")
        except UnicodeEncodeError as exc:
            raise UrdfError(f"{source}: not valid text (a lone surrogate at character {exc.start})") from None
    elif isinstance(text, bytes | bytearray):
        blob = bytes(text)
    else:
        raise UrdfError(f"{source}: URDF text must be str or bytes, got {type(text).__name__}")
    if len(blob) > MAX_URDF_BYTES:
        raise UrdfError(f"{source}: {len(blob)} bytes, larger than the {MAX_URDF_BYTES} bytes a URDF may have")
    tags = blob.count(b"<")
    if tags > MAX_URDF_TAGS:
        raise UrdfError(f"{source}: {tags} markup characters '<', more than the {MAX_URDF_TAGS} a URDF may have")
    attributes = blob.count(b"=")
    if attributes > MAX_URDF_ATTRIBUTES:
        raise UrdfError(
            f"{source}: {attributes} characters '=', more than the {MAX_URDF_ATTRIBUTES} a URDF's attributes may have"
        )
    found = _collect(blob, source, isinstance(text, str))
    joints = [_checked(raw, found.links, source) for raw in found.joints]
    parent_of, root = _tree(joints, found.links, source)
    base = root if base_link is None else base_link
    for what, link in (("base_link", base), ("tip_link", tip_link)):
        if link is not None and link not in found.links:
            raise UrdfError(
                f"{source}: {what} {link!r} is not a link of the file; its links: {_cut(list(found.links))}"
            )
    tip = _default_tip(joints, parent_of, base, source) if tip_link is None else tip_link
    path = _path(parent_of, base, tip)
    if path is None:
        raise UrdfError(f"{source}: tip_link {tip!r} is not below base_link {base!r}")
    masses = {link: _inertial(attrs, f"{source}: link {link!r}") for link, attrs in found.inertials.items()}
    return _chain_robot(path, found.robot_name or Path(source).stem or "urdf", source, base, tip, masses)


def _inertial(attrs: dict[str, dict[str, str]], where: str) -> tuple[float, Array]:
    """A link's mass (kg) and centre of mass (its frame, metres) from its ``<inertial>``."""
    mass = _numbers(attrs.get("mass", {}).get("value"), 1, where, "inertial mass value", MAX_MASS, "0")[0]
    if mass < 0.0:
        raise UrdfError(f"{where}: inertial mass value must be >= 0 kg, got {mass:g}")
    com = _numbers(attrs.get("origin", {}).get("xyz"), 3, where, "inertial origin xyz", MAX_LENGTH, "0 0 0")
    return mass, np.array(com)


def _chain_robot(
    path: list[_UrdfJoint],
    name: str,
    source: str,
    base: str,
    tip: str,
    masses: dict[str, tuple[float, Array]] | None = None,
) -> Robot:
    masses = masses or {}
    carry = np.eye(4)
    joints: list[Joint] = []
    for j in path:
        where = f"{source}: joint {j.name!r}"
        if j.mimic:
            raise UrdfError(f"{where} on the chain {base!r} -> {tip!r} mimics another joint; sweepik cannot model it")
        if j.type in ("floating", "planar"):
            raise UrdfError(
                f"{where} on the chain {base!r} -> {tip!r} is {j.type} (several degrees of freedom); sweepik models "
                f"revolute, continuous, prismatic and fixed joints"
            )
        T = carry @ j.origin
        m, c = masses.get(j.child, (0.0, np.zeros(3)))
        if j.type == "fixed":
            carry = T
            if joints and m > 0.0:  # rigidly on the last moving link: merge (before the first one: the base)
                joints[-1] = joints[-1].with_added_mass(m, carry[:3, :3] @ c + carry[:3, 3])
            continue
        carry = np.eye(4)
        try:
            joints.append(
                Joint(
                    type="prismatic" if j.type == "prismatic" else "revolute",
                    lower=j.lower,
                    upper=j.upper,
                    name=j.name,
                    origin=tuple(tuple(float(v) for v in row) for row in T),
                    axis=(float(j.axis[0]), float(j.axis[1]), float(j.axis[2])),
                    mass=m,
                    com=(float(c[0]), float(c[1]), float(c[2])),
                )
            )
        except RobotDefinitionError as exc:
            raise UrdfError(f"{where}: {exc}") from None
    if not joints:
        raise UrdfError(f"{source}: no moving joint between {base!r} and {tip!r}: there is no chain to solve for")
    try:
        return Robot(
            name=name,
            joints=tuple(joints),
            dh_convention="none",
            T_flange_tool=carry,
            length_unit="m",
            description=f"read from URDF {source}, chain {base} -> {tip}",
        )
    except RobotDefinitionError as exc:
        raise UrdfError(f"{source}: {exc}") from None


def read_urdf(path: str | PathLike[str], base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """The chain ``base_link`` -> ``tip_link`` of a URDF file, as :func:`robot_from_urdf` reads it.

    The file's size is checked before it is read (at most ``MAX_URDF_BYTES``); every problem raises UrdfError
    naming the file. No other file is opened (meshes and ``package://`` paths are ignored) and nothing is fetched.
    """
    p = as_path(path, UrdfError, "URDF file")
    blob = read_file_bytes(p, MAX_URDF_BYTES, UrdfError, "URDF file")
    return robot_from_urdf(blob, str(p), base_link, tip_link)


# ---------------------------------------------------------------------------------------------- writing


def _num(x: float) -> str:
    return repr(float(x) + 0.0)  # shortest text that reads back to the same float (+ 0.0: no "-0.0")


def _origin(parent: ET.Element, T: Array, m_per_unit: float) -> None:
    rpy = rpy_from_matrix(T[:3, :3])
    xyz = " ".join(_num(v * m_per_unit) for v in T[:3, 3])
    ET.SubElement(parent, "origin", xyz=xyz, rpy=" ".join(_num(v) for v in rpy))


def _unique(names: list[str]) -> list[str]:
    """``names`` with repeats made unique by a ``_2``, ``_3``... suffix (URDF joint names must differ)."""
    seen: set[str] = set()
    out = []
    for name in names:
        new, k = name, 1
        while new in seen:
            k += 1
            new = f"{name}_{k}"
        seen.add(new)
        out.append(new)
    return out


def urdf_text(robot: Robot) -> str:
    """The robot as URDF text: links ``world``, ``base_link``, ``link1``...``linkN``, ``tool``.

    Joint ``base_joint`` (fixed, ``world`` -> ``base_link``) carries ``T_world_base``; joint i (the robot's joint
    name; repeats get a ``_2`` suffix, and so does a fixed joint's name that a moving joint has taken) moves
    ``link{i-1}`` -> ``link{i}`` with the origin and axis of :func:`~sweepik.model.origin_axis.joint_origins` (any DH
    convention); ``tool_joint`` (fixed, ``link{N}`` -> ``tool``) carries the rest of the chain and
    ``T_flange_tool``. Link i's ``<inertial>`` holds joint i's link mass and centre of mass (no inertia tensor:
    sweepik does not know it). Lengths are converted to metres, angles stay radians;
    revolute joints are written ``revolute`` with their limits, prismatic ones ``prismatic`` with limits in
    metres. Effort and velocity, which URDF's ``<limit>`` requires and sweepik does not know, are written as 0.
    Numbers are written with all their digits, so ``robot_from_urdf(urdf_text(r))`` (base ``world``, tip
    ``tool`` by default) has the same FK as ``r`` in metres, to rounding.

    >>> from sweepik import load_robot
    >>> back = robot_from_urdf(urdf_text(load_robot("carm")))
    >>> back.length_unit, back.n_joints
    ('m', 6)
    """
    if not isinstance(robot, Robot):
        raise UnknownOptionError(f"urdf_text needs a Robot, got {type(robot).__name__} {short_repr(robot, 40)}")
    m = mm_per_unit(robot.length_unit) / 1000.0
    origins, axes, T_last_tool = joint_origins(robot)
    masses, coms = link_masses(robot)
    n = robot.n_joints
    # the robot's joint names first: a fixed joint gives way to a moving one called "base_joint" or "tool_joint"
    unique = _unique([*robot.joint_names, "base_joint", "tool_joint"])
    names = [unique[n], *unique[:n], unique[n + 1]]
    for text in [robot.name, *names]:
        if _NOT_XML.search(text):
            raise UrdfError(f"{robot.name!r}: the name {text!r} holds characters XML cannot write")
    link_names = ["world", "base_link", *(f"link{i + 1}" for i in range(n)), "tool"]
    root = ET.Element("robot", name=robot.name)
    root.append(ET.Comment(" written by sweepik: lengths in metres, angles in radians "))
    ET.SubElement(root, "link", name=link_names[0])
    for k, jname in enumerate(names):
        link = ET.SubElement(root, "link", name=link_names[k + 1])
        if 0 < k <= n and masses[k - 1] > 0.0:
            inertial = ET.SubElement(link, "inertial")
            ET.SubElement(inertial, "origin", xyz=" ".join(_num(v * m) for v in coms[k - 1]))
            ET.SubElement(inertial, "mass", value=_num(masses[k - 1]))
        moving = 0 < k <= n
        j = robot.joints[k - 1] if moving else None
        joint = ET.SubElement(root, "joint", name=jname, type="fixed" if j is None else j.type)
        ET.SubElement(joint, "parent", link=link_names[k])
        ET.SubElement(joint, "child", link=link_names[k + 1])
        T = robot.T_world_base if k == 0 else T_last_tool if j is None else origins[k - 1]
        _origin(joint, np.asarray(T), m)
        if j is not None:
            ET.SubElement(joint, "axis", xyz=" ".join(_num(v) for v in axes[k - 1]))
            s = 1.0 if j.is_revolute else m
            ET.SubElement(joint, "limit", lower=_num(j.lower * s), upper=_num(j.upper * s), effort="0", velocity="0")
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"
