"""MJCF (MuJoCo's XML) robots: the serial chain of hinge and slide joints between two bodies, through ``mujoco``.

MuJoCo's own compiler reads the file (``mujoco.MjSpec``: defaults and classes, ``<compiler angle=... eulerseq=...>``,
every orientation form, ``<include>``), so a file means here what it means in MuJoCo. Meshes, height fields and
textures are dropped before compiling (the kinematics does not depend on them, and their files need not be present);
bodies left without mass get MuJoCo's lower bounds. A body's joints act in the order written, each about its anchor
``pos`` in the body frame (as ``mj_kinematics`` does): joint ``k`` of the chain becomes origin ``Trans(-p_(k-1)) @
(fixed bodies) @ Trans(p_k)`` with its axis, and a site or body after the last joint becomes the tool transform.

Units: metres and radians (MuJoCo's compiled model; ``angle="degree"`` ranges are converted by MuJoCo). A hinge
without a range gets +-pi (as a URDF continuous joint); a slide without one is refused. Masses are not read (0).
"""

from __future__ import annotations

import logging
from os import PathLike
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.errors import MjcfError, RobotDefinitionError
from sweepik.model.robot import Joint, Robot
from sweepik.model.validate import as_path, file_status

__all__ = ["read_mjcf"]

Array = NDArray[np.float64]

_HINGE, _SLIDE = 3, 2
_log = logging.getLogger(__name__)
_JOINT_KINDS = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}


def _mujoco() -> Any:
    try:
        import mujoco
    except ImportError:
        raise MjcfError("reading an MJCF file needs the mujoco package: pip install 'sweepik[mjcf]'") from None
    return mujoco


def _compiled(path: str) -> Any:
    """The file's compiled ``MjModel``, without meshes, height fields, textures or skins. MuJoCo's warnings (e.g.
    "XML contains a 'NaN'") are logged rather than printed (MuJoCo would print them on the terminal and append them
    to ``MUJOCO_LOG.TXT`` in the working directory): what they warn of, sweepik's own checks refuse with an error."""
    mujoco = _mujoco()
    before = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda msg: _log.info("MuJoCo on %s: %s", path, msg))
    try:
        return _compile(mujoco, path)
    finally:
        mujoco.set_mju_user_warning(before)


def _compile(mujoco: Any, path: str) -> Any:
    try:
        spec = mujoco.MjSpec.from_file(path)
        for g in spec.geoms:
            if g.type in (mujoco.mjtGeom.mjGEOM_MESH, mujoco.mjtGeom.mjGEOM_HFIELD, mujoco.mjtGeom.mjGEOM_SDF):
                g.type = mujoco.mjtGeom.mjGEOM_SPHERE
                g.size = [0.01, 0.0, 0.0]
                g.meshname = ""
                g.hfieldname = ""
        for kind in ("skins", "meshes", "hfields", "textures", "materials"):
            for item in list(getattr(spec, kind)):
                spec.delete(item)
        for g in spec.geoms:
            g.material = ""
        spec.compiler.boundmass = 1e-6
        spec.compiler.boundinertia = 1e-9
        return spec.compile()
    except (ValueError, TypeError) as exc:  # MuJoCo's parse and compile errors
        raise MjcfError(f"{path}: MuJoCo cannot read it: {str(exc).strip()[:300]}") from None


def _frame(pos: Array, quat: Array) -> Array:
    """The transform of a MuJoCo position and unit quaternion (w, x, y, z)."""
    w, x, y, z = quat / np.linalg.norm(quat)
    T = np.eye(4)
    T[:3, :3] = [
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ]
    T[:3, 3] = pos
    return T


def _shift(p: Array) -> Array:
    T = np.eye(4)
    T[:3, 3] = p
    return T


def _names(model: Any, kind: str, count: int) -> list[str]:
    return [getattr(model, kind)(i).name for i in range(count)]


def _default_tip(model: Any, base: int, below: list[int], path: str) -> int:
    """The body of the last joint when the joints below ``base`` form one chain (else MjcfError)."""
    bodies = sorted({int(model.jnt_bodyid[j]) for j in below}, key=lambda b: _depth(model, b))
    tip = bodies[-1]
    chain = set(_bodies_between(model, base, tip) or [])
    off = [b for b in bodies if b not in chain]
    if off:
        names = _names(model, "body", model.nbody)
        raise MjcfError(
            f"{path}: the joints below body {names[base]!r} are not one chain (bodies {names[tip]!r} and "
            f"{names[off[0]]!r} lie on different branches); give tip_link (a body or site name)"
        )
    return tip


def _depth(model: Any, b: int) -> int:
    d = 0
    while b != 0:
        b, d = int(model.body_parentid[b]), d + 1
    return d


def _bodies_between(model: Any, base: int, tip: int) -> list[int] | None:
    """Bodies from just below ``base`` down to ``tip`` (in order), or None if ``tip`` is not below ``base``."""
    out = []
    b = tip
    while b != base:
        if b == 0:
            return None
        out.append(b)
        b = int(model.body_parentid[b])
    return out[::-1]


def _find(names: list[str], name: str, what: str, path: str) -> int:
    if name not in names:
        shown = ", ".join(repr(n) for n in names[:40] if n)
        raise MjcfError(f"{path}: {what} {name!r} is not in the file; its names: {shown}")
    return names.index(name)


def read_mjcf(path: str | PathLike[str], base_link: str | None = None, tip_link: str | None = None) -> Robot:
    """The chain of hinge and slide joints from body ``base_link`` (default: the world) to ``tip_link`` (a body or
    a site; default: the body of the last joint, when the joints below the base form one chain) of an MJCF file,
    as a Robot in origin + axis form (metres, radians). MjcfError naming the file for a file MuJoCo cannot read, an
    unknown name, a ball or free joint on the chain, a slide without a range; mujoco must be installed (the
    ``mjcf`` extra)."""
    p = as_path(path, MjcfError, "MJCF file")
    if file_status(p, MjcfError, "MJCF file") is None:
        raise MjcfError(f"MJCF file {str(p)!r} does not exist")
    source = str(p)
    model = _compiled(source)
    try:
        return _read(model, source, base_link, tip_link)
    except UnicodeDecodeError:
        raise MjcfError(f"{source}: a name in the file is not UTF-8 text") from None


def _read(model: Any, source: str, base_link: str | None, tip_link: str | None) -> Robot:
    """``read_mjcf`` of the compiled ``model``."""
    bodies = _names(model, "body", model.nbody)
    base = 0 if base_link is None else _find(bodies, base_link, "base_link (body)", source)
    tip_T = np.eye(4)
    if tip_link is None:
        below = [j for j in range(model.njnt) if _bodies_between(model, base, int(model.jnt_bodyid[j])) is not None]
        if not below:
            raise MjcfError(f"{source}: no joint below body {bodies[base]!r}: there is no chain to solve for")
        tip = _default_tip(model, base, below, source)
        tip_name = bodies[tip]
    elif tip_link in bodies:
        tip, tip_name = bodies.index(tip_link), tip_link
    else:
        site = _find(_names(model, "site", model.nsite), tip_link, "tip_link (body or site)", source)
        tip, tip_name = int(model.site_bodyid[site]), tip_link
        tip_T = _frame(model.site_pos[site], model.site_quat[site])
    chain = _bodies_between(model, base, tip)
    if chain is None:
        raise MjcfError(f"{source}: tip_link {tip_name!r} is not below base_link {bodies[base]!r}")
    return _chain_robot(model, chain, tip_T, source, f"{bodies[base]} -> {tip_name}")


def _chain_robot(model: Any, chain: list[int], tip_T: Array, source: str, span: str) -> Robot:
    joints: list[Joint] = []
    carry = np.eye(4)
    names = _names(model, "jnt", model.njnt)
    for b in chain:
        carry = carry @ _frame(model.body_pos[b], model.body_quat[b])
        for j in range(int(model.body_jntadr[b]), int(model.body_jntadr[b]) + int(model.body_jntnum[b])):
            kind = int(model.jnt_type[j])
            where = f"{source}: joint {names[j] or j!r}"
            if kind not in (_HINGE, _SLIDE):
                raise MjcfError(f"{where} on the chain {span} is a {_JOINT_KINDS.get(kind, kind)} joint; sweepik "
                                "models hinge and slide joints")  # fmt: skip
            lo, hi = (float(v) for v in model.jnt_range[j])
            if not model.jnt_limited[j]:
                if kind == _SLIDE:
                    raise MjcfError(f'{where} is a slide without a range; give it range="lo hi" (metres)')
                lo, hi = -np.pi, np.pi
            anchor = np.asarray(model.jnt_pos[j], dtype=np.float64)
            T = carry @ _shift(anchor)
            try:
                joints.append(
                    Joint(
                        type="revolute" if kind == _HINGE else "prismatic",
                        lower=lo,
                        upper=hi,
                        name=names[j] or f"joint{j}",
                        origin=tuple(tuple(float(v) for v in row) for row in T),
                        axis=(float(model.jnt_axis[j][0]), float(model.jnt_axis[j][1]), float(model.jnt_axis[j][2])),
                    )
                )
            except RobotDefinitionError as exc:
                raise MjcfError(f"{where}: {exc}") from None
            carry = _shift(-anchor)
    if not joints:
        raise MjcfError(f"{source}: no hinge or slide joint on the chain {span}: there is no chain to solve for")
    try:
        return Robot(
            name=model.names[: model.names.index(b"\0")].decode() or "mjcf",
            joints=tuple(joints),
            dh_convention="none",
            T_flange_tool=carry @ tip_T,
            length_unit="m",
            description=f"read from MJCF {source}, chain {span}",
        )
    except RobotDefinitionError as exc:
        raise MjcfError(f"{source}: {exc}") from None
