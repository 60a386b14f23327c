"""An arm in origin + axis form (as URDF writes it), and arms with some joints held at fixed values.

Every :class:`~sweepik.model.robot.Robot` has an equivalent in origin + axis form (``dh_convention="none"``): joint i
carries ``origin_i`` (the fixed transform from the previous joint's frame, or the base, to joint i's frame at
q = 0) and a unit ``axis_i`` in that frame, and ``fk(q) = T_world_base @ origin_1 @ M_1(q_1) @ ... @ origin_n @
M_n(q_n) @ T_flange_tool`` with ``M_i`` a rotation about (or a translation along) ``axis_i``.

* Modified DH (Craig): the row's fixed part ``RotX(alpha) TransX(a) RotZ(theta) TransZ(d)`` comes before the
  motion about z (the rotation about z commutes with the translation along it), so it is the origin.
* Standard DH: the motion comes first, ``RotZ(q) [RotZ(theta) TransZ(d) TransX(a) RotX(alpha)]``: joint i's
  origin is row i - 1's fixed part (the identity for joint 1) and row n's fixed part moves into the tool.

A joint **held** at a value is folded away: ``origin_k @ M_k(v)`` multiplies into the next joint's origin (or
into the tool, for the last joint). :func:`hold_joints` builds that smaller arm; :class:`HeldJoints` maps its
configurations back to full length.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import LockedJointError, RobotDefinitionError
from sweepik.model import kinematics
from sweepik.model.chain import rotation_about
from sweepik.model.robot import Joint, Robot
from sweepik.model.validate import MAX_JOINT_VALUE

__all__ = ["origin_axis_form", "joint_origins", "hold_joints", "held_values", "lock_runs", "HeldJoints"]

Array = NDArray[np.float64]


def _motion(axis: Array, revolute: bool, value: float) -> Array:
    M = np.eye(4)
    if revolute:
        M[:3, :3] = rotation_about(axis, value)
    else:
        M[:3, 3] = axis * value
    return M


def joint_origins(robot: Robot) -> tuple[Array, Array, Array]:
    """``(origins (n, 4, 4), axes (n, 3), T_last_tool (4, 4))``: the arm in origin + axis form.

    ``T_last_tool`` is the fixed transform from the last joint's frame to the tool (``T_flange_tool`` for
    modified DH and origin + axis arms). The base transform is ``robot.T_world_base`` in every form.
    """
    n = robot.n_joints
    if robot.dh_convention == "none":
        origins = np.array([j.origin for j in robot.joints], dtype=np.float64)
        axes = np.array([j.axis for j in robot.joints], dtype=np.float64)
        return origins, axes, np.array(robot.T_flange_tool)
    # a DH row at joint value 0 is its fixed part (the motion about z commutes with the row's part along z)
    fixed = kinematics.link_transforms(robot, np.zeros(n))
    axes = np.tile([0.0, 0.0, 1.0], (n, 1))
    if robot.dh_convention == "modified":
        return fixed, axes, np.array(robot.T_flange_tool)
    origins = np.concatenate([np.eye(4)[None], fixed[:-1]])
    return origins, axes, fixed[-1] @ robot.T_flange_tool


def link_masses(robot: Robot) -> tuple[Array, Array]:
    """``(masses (n,), coms (n, 3))``: each joint's link mass (kg) and centre of mass in that joint's frame of the
    origin + axis form (:func:`joint_origins`); the same point as ``Joint.com`` in the robot's own link frame.

    Only standard DH moves the frame: its link frame i is the origin + axis frame i times row i's fixed part.
    """
    masses = np.array([j.mass for j in robot.joints], dtype=np.float64)
    coms = np.array([j.com for j in robot.joints], dtype=np.float64).reshape(-1, 3)
    if robot.dh_convention == "standard":
        fixed = kinematics.link_transforms(robot, np.zeros(robot.n_joints))
        coms = np.einsum("kij,kj->ki", fixed[:, :3, :3], coms) + fixed[:, :3, 3]
    return masses, coms


def _as_origin_tuple(T: Array) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in T)


def origin_axis_form(robot: Robot) -> Robot:
    """The same arm (same FK, names, limits, unit, base) written in origin + axis form."""
    if robot.dh_convention == "none":
        return robot
    origins, axes, tool = joint_origins(robot)
    masses, coms = link_masses(robot)
    joints = tuple(
        Joint(
            type=j.type,
            lower=j.lower,
            upper=j.upper,
            name=name,
            origin=_as_origin_tuple(org),
            axis=tuple(a),
            mass=float(m),
            com=tuple(c),
        )
        for j, name, org, a, m, c in zip(robot.joints, robot.joint_names, origins, axes, masses, coms, strict=True)
    )
    return Robot(
        name=robot.name,
        joints=joints,
        dh_convention="none",
        T_world_base=np.array(robot.T_world_base),
        T_flange_tool=tool,
        length_unit=robot.length_unit,
        default_reduction=None,
        description=robot.description,
        gravity=robot.gravity,
    )


@dataclass(frozen=True)
class HeldJoints:
    """An arm with some joints held: ``robot`` is the full arm, ``arm`` the smaller one that is solved.

    Attributes:
        free: indices (into the full arm) of the joints ``arm`` keeps, in order.
        held: ``(index, value)`` of each held joint (radians or length unit), in index order.
    """

    robot: Robot
    arm: Robot
    free: tuple[int, ...]
    held: tuple[tuple[int, float], ...]

    def expand(self, q: ArrayLike) -> Array:
        """Full-length configurations ``(..., n)`` from the smaller arm's ``(..., n - len(held))``."""
        qa = np.asarray(q, dtype=np.float64)
        out = np.empty((*qa.shape[:-1], self.robot.n_joints))
        out[..., list(self.free)] = qa
        for k, v in self.held:
            out[..., k] = v
        return out


def _joint_index(robot: Robot, key: object) -> int:
    names = robot.joint_names
    if isinstance(key, str):
        if key in names:
            return names.index(key)
        raise LockedJointError(f"locked: {robot.name!r} has no joint named {key!r}; its joints: {', '.join(names)}")
    if isinstance(key, bool) or not isinstance(key, int | np.integer):
        raise LockedJointError(f"locked: a joint is named by its name or index, got {type(key).__name__} {key!r}")
    k = int(key)
    if not 0 <= k < robot.n_joints:
        raise LockedJointError(f"locked: joint index {k} is outside 0..{robot.n_joints - 1} for {robot.name!r}")
    return k


def held_values(robot: Robot, locked: Mapping[Any, Any]) -> tuple[tuple[int, float], ...]:
    """``locked`` (joint name or index -> value) checked against ``robot``: ``((index, value), ...)`` sorted.

    A value must be a finite number inside the joint's limits (with the solver's limit tolerance): a solution
    holding a joint outside its range would not be a solution the arm can reach. A value inside the limits is kept
    as given (a joint turning more than once: 4 rad is not -2.28 rad); a revolute value outside them is taken
    modulo 2 pi into them when it can be.
    """
    if not isinstance(locked, Mapping):
        raise LockedJointError(
            f"locked must be a mapping of joint name (or index) to value, got {type(locked).__name__}"
        )
    out: dict[int, float] = {}
    for key, value in locked.items():
        k = _joint_index(robot, key)
        if k in out:
            raise LockedJointError(f"locked: joint {robot.joint_names[k]!r} is given twice")
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "iuf":
            value = value.item()  # (a number held in a 0-d array, as NumPy gives one)
        if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
            raise LockedJointError(f"locked: joint {robot.joint_names[k]!r} needs a number, got {value!r}")
        v = float(value)
        if not (math.isfinite(v) and abs(v) <= MAX_JOINT_VALUE):
            raise LockedJointError(
                f"locked: joint {robot.joint_names[k]!r} needs a finite value of magnitude at most "
                f"{MAX_JOINT_VALUE:g}, got {v!r}"
            )
        tol = float(robot.limit_tol[k])
        inside = robot.lower[k] - tol <= v <= robot.upper[k] + tol
        if robot.is_revolute[k] and not inside:  # an angle given modulo 2 pi: its turn inside the limits
            v = float(robot.wrap(np.where(np.arange(robot.n_joints) == k, v, 0.0))[k])
        if not robot.lower[k] - tol <= v <= robot.upper[k] + tol:
            unit = "rad" if robot.is_revolute[k] else robot.length_unit
            raise LockedJointError(
                f"locked: {robot.joint_names[k]} = {float(value):.12g} {unit} is outside its limits "
                f"[{robot.lower[k]:.12g}, {robot.upper[k]:.12g}]"
            )
        out[k] = v
    return tuple(sorted(out.items()))


def per_pose(locked: object) -> bool:
    """Whether ``locked`` gives some joint a sequence of values (one per pose) rather than one number."""
    return isinstance(locked, Mapping) and any(
        isinstance(v, list | tuple | np.ndarray) and np.ndim(v) > 0 for v in locked.values()
    )


def lock_runs(robot: Robot, locked: Mapping[Any, Any], n: int) -> list[tuple[int, int, dict[int, float]]]:
    """``locked`` with a value per pose for some joints (a sequence of ``n``; a number holds every pose) as runs
    of consecutive poses that hold the same values: ``[(start, stop, {joint index: value}), ...]`` covering
    ``0 .. n``. Every pose's values are checked here (``held_values``: a LockedJointError names the first pose whose
    value is refused), so that a batch fails before it is solved."""
    keys = [_joint_index(robot, key) for key in locked]
    if len(set(keys)) < len(keys):
        held_values(robot, locked)  # (names the joint given twice)
    columns = []
    for k, value in zip(keys, locked.values(), strict=True):
        name = robot.joint_names[k]
        if isinstance(value, list | tuple | np.ndarray) and np.ndim(value) > 0:
            if _booleans(value):
                raise LockedJointError(f"locked: joint {name!r} needs numbers, one per pose, not booleans")
            try:
                raw = np.asarray(value)
            except (TypeError, ValueError):  # (ragged)
                raise LockedJointError(f"locked: joint {name!r} needs numbers, one per pose") from None
            if raw.dtype.kind not in "iuf":  # (text NumPy would convert, None, ...: refused as one such value is)
                bad = next((x for x in raw.ravel().tolist() if not isinstance(x, int | float)), raw.dtype)
                raise LockedJointError(f"locked: joint {name!r} needs numbers, one per pose, got {bad!r}")
            col = raw.astype(np.float64)
            if col.shape != (n,):
                raise LockedJointError(
                    f"locked: joint {name!r} has values of shape {col.shape}; give one number, or one per pose ({n})"
                )
        else:
            held_values(robot, {k: value})  # (one number: its checks and message)
            col = np.full(n, float(value))
        columns.append(col)
    if n == 0:
        return []
    rows = np.stack(columns, axis=1)
    starts = [0, *(np.nonzero(np.any(rows[1:] != rows[:-1], axis=1))[0] + 1).tolist()]
    runs = []
    for s, e in zip(starts, [*starts[1:], n], strict=True):
        values = dict(zip(keys, rows[s].tolist(), strict=True))
        try:
            held_values(robot, values)
        except LockedJointError as err:
            raise LockedJointError(f"pose {s}: {err}") from None
        runs.append((s, e, values))
    return runs


def _booleans(values: list[Any] | tuple[Any, ...] | np.ndarray) -> bool:
    """Per-pose lock values given as booleans (refused as a single ``True`` is: not a joint value)."""
    if isinstance(values, np.ndarray):
        return values.dtype.kind == "b"
    return any(isinstance(x, bool | np.bool_) for x in values)


def hold_joints(robot: Robot, locked: Mapping[Any, Any], n_free: int | None = 6) -> HeldJoints:
    """The arm with the joints in ``locked`` (name or index -> value, radians / length unit) held.

    ``n_free`` is how many joints must remain (6 for the solver; ``None`` for any number). Raises
    :class:`LockedJointError` naming the problem.
    """
    held = held_values(robot, locked)
    n_left = robot.n_joints - len(held)
    if n_free is not None and n_left != n_free:
        raise LockedJointError(
            f"{robot.name!r} has {robot.n_joints} joints and {len(held)} locked: {n_left} left to solve for, "
            f"sweepik solves exactly {n_free}"
            + (" (an arm with fewer than six free joints is out of scope)" if n_left < n_free else "")
        )
    return _hold(robot, held)


#: A held arm's joints, kept: a new value of a held joint moves only the joints next to it, and the others (checked
#: once, each ~25 us) are the same for every value.
_joint = lru_cache(maxsize=256)(Joint)


@lru_cache(maxsize=64)
def _hold(robot: Robot, held: tuple[tuple[int, float], ...]) -> HeldJoints:
    origins, axes, tool = joint_origins(robot)
    masses, coms = link_masses(robot)
    values = dict(held)
    free = tuple(k for k in range(robot.n_joints) if k not in values)
    if not free:
        raise LockedJointError(f"{robot.name!r}: every joint is locked, nothing is left to solve for")
    carry = np.eye(4)  # from the last free joint's frame (or the base) to the current one
    base = np.array(robot.T_world_base)
    joints: list[Joint] = []
    for k in range(robot.n_joints):
        j = robot.joints[k]
        org = carry @ origins[k]
        if k in values:
            carry = org @ _motion(axes[k], j.is_revolute, values[k])
            if joints and masses[k] > 0.0:  # a held link rides on the last free one (on the base: no effect)
                joints[-1] = joints[-1].with_added_mass(float(masses[k]), carry[:3, :3] @ coms[k] + carry[:3, 3])
            continue
        carry = np.eye(4)
        joints.append(
            _joint(
                type=j.type,
                lower=j.lower,
                upper=j.upper,
                name=robot.joint_names[k],
                origin=_as_origin_tuple(org),
                axis=tuple(axes[k]),
                mass=float(masses[k]),
                com=tuple(coms[k]),
            )
        )
    units = ["rad" if r else robot.length_unit for r in robot.is_revolute]
    label = ", ".join(f"{robot.joint_names[k]}={v:.6g} {units[k]}" for k, v in held)
    try:
        arm = Robot(
            name=f"{robot.name} ({label} locked)",
            joints=tuple(joints),
            dh_convention="none",
            T_world_base=base,
            T_flange_tool=carry @ tool,
            length_unit=robot.length_unit,
            description=robot.description,
            gravity=robot.gravity,
        )
    except RobotDefinitionError as exc:  # pragma: no cover - the parts are valid transforms by construction
        raise LockedJointError(str(exc)) from None
    # The held arm's tolerances are the full arm's, whatever the values held: its own sum of link offsets would
    # change with them (a held joint turns two offsets into one), and with it every threshold of a solve
    # (``engine.held_pose`` takes the value as an argument of one compiled call, its thresholds fixed).
    arm.__dict__["length_scale"] = robot.length_scale  # (``Robot.length_scale`` is a cached property)
    return HeldJoints(robot, arm, free, held)
