"""The first or the last joint held: every lock value is one held arm, turned (issue 39).

Holding joint ``k`` of a chain at ``v`` leaves the other joints' geometry as it is at any other value, but for a
rigid turn: the first joint (``k = 0``) turns everything after it about its axis, fixed in the world, so the held arm
at ``v`` is the held arm at a reference value ``v0`` with its base turned by ``v - v0``; the last joint turns only the
tool about its axis, fixed in the tool frame. So ``FK(q, v) = M(v - v0) FK(q, v0)`` (first joint) or
``FK(q, v0) N(v - v0)`` (last), and the solutions of a pose ``T`` at ``v`` are, joint for joint, those of the pose
``M(v0 - v) T`` (or ``T N(v0 - v)``) at ``v0``. Solving there, where the held arm, its plan and its kernel
arguments are built once, makes a new value cost what the same value costs, whatever the arm (a companion plan, the
general method, a near-structure of the joints after the held one: the YuMi, the Kassow, the Gen3's joint 1, which
each built their held arm anew, 2-30 ms a value).

The solutions come back with the value ``v`` in column ``k``, the caller's pose, and their errors worked out again
against it (a turn moves the pose's rounding, and the paper's Z-Y-Z error is not the same in a turned frame): a
solution that would not be certified against the caller's pose, or a pose with self-motion families (whose members
the held arm at ``v0`` gives), is answered by the held arm at ``v`` instead (``None`` here).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.certify import pose_errors
from sweepik.engine.settle import settle_bounds
from sweepik.model.origin_axis import held_values
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.results import Block, Solutions

__all__ = ["TurnedLock", "turned_at", "turned_lock", "reference_value"]

Array = NDArray[np.float64]


@dataclasses.dataclass(frozen=True)
class TurnedLock:
    """Joint ``joint`` (the first or the last) held at ``value``, solved at ``reference``."""

    joint: int
    value: float
    reference: float
    #: the turn taking a pose at ``value`` to the same joints at ``reference`` ``(4, 4)``: applied on the left (the
    #: first joint) or on the right (the last)
    turn: Array
    left: bool

    @property
    def locked(self) -> dict[int, float]:
        """The lock solved instead: the joint at ``reference``."""
        return {self.joint: self.reference}

    def poses(self, P: Array) -> Array:
        """The poses ``P (..., 4, 4)`` solved at ``reference``."""
        out = self.turn @ P if self.left else P @ self.turn
        out[..., 3, :] = (0.0, 0.0, 0.0, 1.0)
        return out

    def solutions(self, robot: Robot, at_reference: Solutions, pose: Array) -> Solutions | None:
        """``at_reference`` (the solutions of ``poses(pose)`` at ``reference``) as the solutions of ``pose`` at
        ``value``; None where the held arm at ``value`` must answer (module docstring)."""
        if at_reference.families or at_reference.wound:
            return None
        back = self._back(robot, at_reference.q, pose[None].repeat(len(at_reference), axis=0))
        if back is None:
            return None
        q, e_paper, e_geo = back
        return Solutions.settled(
            q, e_paper, e_geo, at_reference.within_limits, at_reference.multiplicity, at_reference.reason,
            pose.copy(), robot,
        )  # fmt: skip

    def block(self, robot: Robot, at_reference: Block, P: Array) -> Block | None:
        """``at_reference`` (a block of ``poses(P)`` at ``reference``) as the block of ``P`` at ``value``; None as
        ``solutions``."""
        if at_reference.families or at_reference.winding_of is not None:
            return None
        rows = np.repeat(np.arange(P.shape[0]), np.diff(at_reference.bounds))
        back = self._back(robot, at_reference.q, P[rows])
        if back is None:
            return None
        q, e_paper, e_geo = back
        return dataclasses.replace(at_reference, poses=P.copy(), q=q, error=e_paper, error_geodesic=e_geo)

    def _back(self, robot: Robot, q: Array, targets: Array) -> tuple[Array, Array, Array] | None:
        """``q`` with ``value`` in its column and their errors against ``targets``: None where one is not certified
        there."""
        q = q.copy()
        q[:, self.joint] = self.value
        if not q.shape[0]:
            return q, np.zeros(0), np.zeros(0)
        e_geo, e_paper = pose_errors(robot, q, np.ascontiguousarray(targets), orientation_weight(robot.length_unit))
        if not np.all(e_geo <= settle_bounds(robot)[3]):
            return None
        return q, e_paper, e_geo


def turned_lock(robot: Robot, locked: object) -> TurnedLock | None:
    """``locked`` as a ``TurnedLock`` where it holds one revolute joint, the first or the last, of an arm of seven
    joints or more at a value other than the reference; else None (raises ``held_values``' errors)."""
    if not (isinstance(locked, Mapping) and len(locked) == 1 and robot.n_joints >= 7):
        return None
    ((k, v),) = held_values(robot, locked)
    return turned_at(robot, k, v)


@lru_cache(maxsize=256)
def turned_at(robot: Robot, k: int, v: float) -> TurnedLock | None:
    """``turned_lock`` of joint ``k`` at ``v`` (checked by ``held_values``), kept: a solve asks for it a few times."""
    n = robot.n_joints
    if k not in (0, n - 1) or not robot.is_revolute[k]:
        return None
    v0 = reference_value(robot, k)
    if v == v0:
        return None
    h, p = _axis(robot, k)
    line = _turn_about(h, p, v0 - v)
    if k == 0:
        return TurnedLock(k, v, v0, line, True)
    F0, F0_inv = _tool_at_zero(robot)
    return TurnedLock(k, v, v0, F0_inv @ line @ F0, False)


@lru_cache(maxsize=64)
def _axis(robot: Robot, k: int) -> tuple[Array, Array]:
    """Joint ``k``'s axis and a point of it, in the world at the zero configuration."""
    ch = robot.chain
    return ch.H[k].copy(), ch.points[k].copy()


@lru_cache(maxsize=64)
def _tool_at_zero(robot: Robot) -> tuple[Array, Array]:
    """The tool pose at the zero configuration and its inverse."""
    F0 = robot.fk(np.zeros(robot.n_joints))
    return F0, np.asarray(np.linalg.inv(F0), dtype=np.float64)


def reference_value(robot: Robot, k: int) -> float:
    """The value every value of joint ``k`` is solved at: 0 where the limits hold it, else their middle."""
    lo, hi = float(robot.lower[k]), float(robot.upper[k])
    if lo <= 0.0 <= hi:
        return 0.0
    return 0.5 * (lo + hi) if math.isfinite(lo + hi) else (lo if math.isfinite(lo) else hi)


def _turn_about(h: Array, p: Array, angle: float) -> Array:
    """The rigid turn ``(4, 4)`` by ``angle`` about the line through ``p`` along the unit ``h`` (``rotation_about``'s
    Rodrigues, in scalars: a solve at a new value builds one)."""
    c, s = math.cos(angle), math.sin(angle)
    x, y, z = float(h[0]), float(h[1]), float(h[2])
    t = 1.0 - c
    R = np.array(
        [
            [c + x * x * t, x * y * t - z * s, x * z * t + y * s],
            [y * x * t + z * s, c + y * y * t, y * z * t - x * s],
            [z * x * t - y * s, z * y * t + x * s, c + z * z * t],
        ]
    )
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = R, p - R @ p
    return M
