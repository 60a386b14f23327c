"""A seven-joint arm with one joint held, its lock value an argument of the compiled call (issue 39).

Holding joint ``k`` of a chain at ``v`` makes a six-joint chain whose geometry is the full chain's with the joints after
``k`` (and the tool) turned by ``v`` about joint ``k``'s axis (a revolute joint: a held slide is left to the general
way). The held arm, its plan and its kernel arguments were built for each new value (~2 ms on the iiwa); but when the
plan is the same at every value, everything else in them is the full arm's geometry moved by that motion. Here the
compiled call takes ``v`` and builds the held chain, the plan's parameter row (its axes, segments, wrist centre and
meeting point) and the certification's chain itself, then settles the pose as ``single_pose`` does (every branch of a
closed form, or a sweep's search): a new value costs what the same value costs.

When the plan holds at every value (``HeldPose.of``): the plan chosen for the held arm at five values spread over the
joint's range (``REFERENCES``; the choice at a value seen first, ``reductions.first_held_reduction``, so that what is
taken does not depend on what was solved before) must be the same family, case, theta* and chain direction at each; its
wrist centre and meeting point each either fixed in the world or carried by the held joint's motion (a point on the held
axis is both); and this module's parameter row, chain and tool vectors must equal the held arm's at those values to
rounding. That makes the plan's structure hold at every value: axes that meet at a point fixed in the world, or carried
with them, meet whatever the value; a direction turned by the held joint is a trigonometric polynomial of degree one in
the value, so one parallel to another at five values is parallel at all. Axes that meet at a point sliding along one of
them (Panda joint 6: axes 5 and 7, one turned by the held joint, in a plane across it) meet at every value where
they meet at five (their being coplanar is a trigonometric polynomial of degree two in the value): the meeting point
is worked out in the compiled call; where they turn parallel the held arm is another arm (``lock_windows``). The
arguments that do not depend on the geometry are the held arm's at every value (its length scale is the full arm's:
``origin_axis.hold_joints``); the singular set's thresholds (typical step amplitudes, probed) are the largest of the
five: a pose nearer its singular set than that goes the general way, where the held arm at its own value answers. So
does every pose the one call does not settle (``single_pose``), and every value near which the held arm is another arm
(a near-structure, another structure, another plan: ``lock_windows``).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from numba import boolean, float64, int64
from numpy.typing import NDArray

from sweepik._jit import inlined, writable
from sweepik.engine import search
from sweepik.engine.lock_windows import in_windows, special_windows, window_reference
from sweepik.engine.one_pose import OK, SETTLE_CLOSED_SIG, SETTLE_ONE_SIG, every_branch_settled
from sweepik.engine.settings import MAX_ISOLATED_SOLUTIONS
from sweepik.engine.single_pose import SinglePose, answer, not_rigid, pose_row, rigid_pose, swept_settled
from sweepik.model.chain import Chain, rotation_about
from sweepik.model.origin_axis import hold_joints
from sweepik.model.robot import Robot
from sweepik.reductions import GeometricReduction, Plan, Reduction, general, vouch_held_plan
from sweepik.reductions.geometric import LAYOUT
from sweepik.reductions.kernels import lazy_njit
from sweepik.results import Block, Solutions
from sweepik.subproblems.vec import add, dot, rot, sub

__all__ = ["HeldPose", "REFERENCES", "SPECIAL", "at_turn", "references"]

Array = NDArray[np.float64]

#: Where in the held joint's range (a revolute one's cut to one turn) the plan is checked: five values, none at the
#: middle or an end (a symmetric range's 0 and +-pi/2 are where axes of many arms line up); the first is where a held
#: arm that takes the general method ranks its elimination's arrangements (``reductions.general.REFERENCE``).
REFERENCES = (general.REFERENCE, 0.2689, 0.4623, 0.6571, 0.8817)
#: The parameter row, chain and tool vectors built here equal the held arm's to this, times the length scale.
MATCH_REL = 1e-12
#: ``HeldPose.solve``'s status for a value in its ``windows`` (the general way answers).
SPECIAL = -2

_H, _P, _W, _O = LAYOUT["H"], LAYOUT["P"], LAYOUT["W"], LAYOUT["O"]
#: How the wrist centre and the meeting point follow the value (``HeldPose._marks``): fixed in the world, carried by
#: the held joint, or (the meeting point) where two axes of the solved chain meet, worked out at each value.
_FIXED, _CARRIED, _MET = 0, 1, 2
#: The base and tool transforms ``pose_rows`` takes: the held chain is the world chain (none to take off).
_EYE = np.eye(4)
_M = LAYOUT["M"]


@inlined
def _moved(x, value, h, o):  # pragma: no cover
    """The point ``x`` turned by ``value`` about the axis ``h`` through ``o`` (a tuple)."""
    return add(o, rot(h, value, sub(x, o)))


@inlined
def _held_chain(value, GH, pts, GR, k):  # pragma: no cover
    """The world chain of the full chain (axes ``GH (n, 3)``, joint points then the tool's ``pts (n + 1, 3)``, tool
    orientation ``GR``) with joint ``k`` held at ``value``: ``(H (n-1, 3), P (n, 3), R_end)``."""
    n = GH.shape[0]
    H, P, R_end = np.empty((n - 1, 3)), np.empty((n, 3)), np.empty((3, 3))
    h, o = GH[k], pts[k]
    prev = (0.0, 0.0, 0.0)
    j = 0
    for i in range(n + 1):
        if i == k:
            continue
        x = (pts[i, 0], pts[i, 1], pts[i, 2]) if i < k else _moved(pts[i], value, h, o)
        d = sub(x, prev)
        P[j, 0], P[j, 1], P[j, 2] = d
        prev = x
        if i < n:
            a = (GH[i, 0], GH[i, 1], GH[i, 2]) if i < k else rot(h, value, GH[i])
            H[j, 0], H[j, 1], H[j, 2] = a
        j += 1
    for c in range(3):
        R_end[0, c], R_end[1, c], R_end[2, c] = rot(h, value, GR[:, c])
    return H, P, R_end


@inlined
def _solved(H, P, R_end, reverse):  # pragma: no cover
    """The chain a plan solves: as it is, or ``Chain.reversed`` (the inverse pose's, in the tool frame at zero)."""
    if not reverse:
        return H, P, R_end
    n = H.shape[0]
    Hr, Pr, Rr = np.empty_like(H), np.empty_like(P), np.empty((3, 3))
    for a in range(3):
        for c in range(3):
            Rr[a, c] = R_end[c, a]
    for i in range(n):
        for a in range(3):
            Hr[i, a] = -(H[n - 1 - i, 0] * R_end[0, a] + H[n - 1 - i, 1] * R_end[1, a] + H[n - 1 - i, 2] * R_end[2, a])
    for i in range(n + 1):
        for a in range(3):
            Pr[i, a] = -(P[n - i, 0] * R_end[0, a] + P[n - i, 1] * R_end[1, a] + P[n - i, 2] * R_end[2, a])
    return Hr, Pr, Rr


@inlined
def _held_args(value, GH, pts, GR, k, reverse, marks, moves, template):  # pragma: no cover
    """The held chain ``(H, P, R_end)`` at ``value`` and ``pose_rows``' arguments for its plan: the row (``template``
    with the solved chain's axes, segments, wrist centre and meeting point: ``marks`` at value 0 in the world,
    ``moves[m]`` how each follows the value, ``_FIXED``, ``_CARRIED`` or ``_MET``: where the solved chain's axes
    ``moves[2]`` and ``moves[3]`` meet), the solved chain's tool orientation and the wrist centre in the tool
    frame."""
    H, P, R_end = _held_chain(value, GH, pts, GR, k)
    end = _sum_rows(P)
    Hs, Ps, Rs = _solved(H, P, R_end, reverse)
    row = template.copy()
    n = Hs.shape[0]
    for i in range(n):
        for a in range(3):
            row[_H + 3 * i + a] = Hs[i, a]
    for i in range(n + 1):
        for a in range(3):
            row[_P + 3 * i + a] = Ps[i, a]
    w = (0.0, 0.0, 0.0)
    for m in range(2):
        if moves[m] == _MET:  # (in the solved chain's frame already)
            x = _meeting(Hs, Ps, moves[2], moves[3])
        else:
            x = (marks[m, 0], marks[m, 1], marks[m, 2])
            if moves[m] == _CARRIED:
                x = _moved(x, value, GH[k], pts[k])
            if reverse:  # (the reversed chain's world is the tool frame at zero)
                x = _inverse_turned(R_end, sub(x, end))
        at = _W if m == 0 else _O
        row[at], row[at + 1], row[at + 2] = x
        if m == 0:
            w = x
    w_tool = np.empty(3)
    w_tool[0], w_tool[1], w_tool[2] = _inverse_turned(Rs, sub(w, _sum_rows(Ps)))
    return H, P, R_end, row, Rs, w_tool


@inlined
def _meeting(H, P, a, b):  # pragma: no cover
    """Where the axes ``a`` and ``b`` of the chain ``H, P`` (zero configuration) meet: the point of axis ``a``
    nearest axis ``b`` (a tuple)."""
    pa, pb = _sum_rows(P[: a + 1]), _sum_rows(P[: b + 1])
    ha, hb = (H[a, 0], H[a, 1], H[a, 2]), (H[b, 0], H[b, 1], H[b, 2])
    r = sub(pa, pb)
    A, B, C, D, E = dot(ha, ha), dot(ha, hb), dot(hb, hb), dot(ha, r), dot(hb, r)
    t = (B * E - C * D) / (A * C - B * B)
    return (pa[0] + t * ha[0], pa[1] + t * ha[1], pa[2] + t * ha[2])


@inlined
def _sum_rows(P):  # pragma: no cover
    """The sum of the rows of ``P (m, 3)`` (a chain's tool point at zero), a tuple."""
    x = (0.0, 0.0, 0.0)
    for i in range(P.shape[0]):
        x = add(x, P[i])
    return x


@inlined
def _inverse_turned(R, v):  # pragma: no cover
    """``R^T v`` (a tuple)."""
    return (dot(R[:, 0], v), dot(R[:, 1], v), dot(R[:, 2], v))


_CHAIN_SIG = (float64, float64[:, ::1], float64[:, ::1], float64[:, ::1], int64)
_GEOMETRY_SIG = _CHAIN_SIG + (boolean, float64[:, ::1], int64[::1], float64[::1])


@lazy_njit(_CHAIN_SIG, cache=True, nogil=True)
def held_chain(value, GH, pts, GR, k):  # pragma: no cover
    """``_held_chain`` called from Python (``HeldPose.chain_at``)."""
    return _held_chain(value, GH, pts, GR, k)


@lazy_njit(_GEOMETRY_SIG, cache=True, nogil=True)
def held_args(value, GH, pts, GR, k, reverse, marks, moves, template):  # pragma: no cover
    """``_held_args`` called from Python (``HeldPose.of`` checks it against the held arm's)."""
    return _held_args(value, GH, pts, GR, k, reverse, marks, moves, template)


@lazy_njit(
    (float64[:, ::1],) + _GEOMETRY_SIG + SETTLE_CLOSED_SIG[:1] + SETTLE_CLOSED_SIG[3:4] + SETTLE_CLOSED_SIG[6:7]
    + SETTLE_CLOSED_SIG[8:],
    cache=True,
    nogil=True,
)  # fmt: skip
def _held_closed_pose(
    world, value, GH, pts, GR, k, reverse, marks, moves, template, addr, nb, rev, weight, thr, lrev, lower,
    upper, ltol, beyond, reach, tol, scale, s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """``single_pose._closed_pose`` for the held chain at ``value`` (``_held_args``' arguments after ``world``):
    ``(status, certified, reachable, q, error, error_geodesic, within_limits, multiplicity)`` with ``q`` full length,
    ``value`` in column ``k``."""
    if not rigid_pose(world):
        return not_rigid(GH.shape[0])
    H, P, R_end, row, r_end, w_tool = _held_args(value, GH, pts, GR, k, reverse, marks, moves, template)
    params = pose_row(world, _EYE, _EYE, reverse, r_end, w_tool, row)
    st, c, reachable, q, ep, eg, ins, mu, _ = every_branch_settled(
        addr, params, world.reshape((1, 4, 4)), nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond,
        reach, tol, scale, s_thr, meet, only_inside,
    )  # fmt: skip
    return st, c, reachable, _full(q, k, value), ep, eg, ins, mu


@inlined
def _full(q, k, value):  # pragma: no cover
    """The held arm's configurations ``q (m, n - 1)`` full length, ``value`` in column ``k``."""
    full = np.empty((q.shape[0], q.shape[1] + 1))
    for r in range(q.shape[0]):
        for i in range(k):
            full[r, i] = q[r, i]
        full[r, k] = value
        for i in range(k, q.shape[1]):
            full[r, i + 1] = q[r, i]
    return full


@lazy_njit(
    (float64[:, ::1],) + _GEOMETRY_SIG + SETTLE_ONE_SIG[:6] + SETTLE_ONE_SIG[11:18] + SETTLE_ONE_SIG[21:22]
    + SETTLE_ONE_SIG[23:],
    cache=True,
    nogil=True,
)  # fmt: skip
def _held_swept_pose(
    world, value, GH, pts, GR, k, reverse, marks, moves, template, addr, plan, branches, m_branches, steps,
    noise, s, ends, twins, max_cand, max_fam, limits, clip, rev, weight, thr, lrev, lower, upper, ltol, beyond, reach,
    tol, scale, c_joints, c_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """``single_pose._swept_pose`` for the held chain at ``value``, as ``_held_closed_pose``."""
    if not rigid_pose(world):
        return not_rigid(GH.shape[0])
    H, P, R_end, row, r_end, w_tool = _held_args(value, GH, pts, GR, k, reverse, marks, moves, template)
    params = pose_row(world, _EYE, _EYE, reverse, r_end, w_tool, row)
    st, c, reachable, q, ep, eg, ins, mu = swept_settled(
        world, params, addr, plan, branches, m_branches, steps, noise, s, ends, twins, max_cand, max_fam, limits, clip,
        H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, c_joints, c_thr, meet,
        only_inside,
    )  # fmt: skip
    return st, c, reachable, _full(q, k, value), ep, eg, ins, mu


#: The row's fields that say which steps' margins and amplitudes a sweep computes (bits, probed: a step that is the
#: twin of another at one value is left out there), and where the lists of those steps sit in a sweep's fixed
#: arguments: the union of the references' is taken (a step computed where it is a twin costs time, not solutions;
#: the Kinova Gen3 rewritten at random held at joint 4 left out one at one reference of five).
_NEED_BITS = (LAYOUT["need_margin"], LAYOUT["need_amplitude"])
_UNION_AT = {False: (), True: (3, 4)}
#: Where the chain's ``H``, ``P``, ``R_end`` and the probed thresholds (the largest of the references' taken) sit in
#: a ``SinglePose``'s fixed arguments after the row's (``_head[6:] + _tail``), for a closed form and a sweep.
_CHAIN_AT = {False: (2, 3, 5), True: (11, 12, 14)}
_LARGEST_AT = {False: (16,), True: (5, 26)}


class HeldPose:
    """A seven-joint arm with revolute joint ``k`` held, its closed form's or sweep's arguments built in the compiled
    call from the lock value (module docstring): ``of(robot, k, reduction_of)``, then ``solve(pose, value, limits)``
    per pose."""

    __slots__ = ("robot", "joint", "arm", "plan", "windows", "sweeps", "_geometry", "_fixed", "_kernel")

    def __init__(
        self, robot: Robot, joint: int, arm: Robot, plan: Plan, geometry: tuple[Any, ...], fixed: tuple[Any, ...],
        sweeps: bool,
    ) -> None:  # fmt: skip
        self.robot = robot
        self.joint = joint
        self.arm = arm  # (the held arm at a reference value: what its reduction is named)
        self.plan = plan  # (its plan there)
        #: the values the general way answers (``lock_windows.special_windows``; set by ``of``)
        self.windows = np.zeros((0, 2))
        self._geometry = geometry  # (the full chain, the joint, the plan's direction, marks and row)
        self._fixed = fixed  # (the settling's arguments, as ``SinglePose``'s without the chain)
        self.sweeps = sweeps  # (a sweep's call, else a closed form's)
        # (the compiled entry point itself: ``call`` passes the signature's types, its pose checked by the caller)
        self._kernel = (_held_swept_pose if sweeps else _held_closed_pose).unchecked

    @classmethod
    def of(cls, robot: Robot, k: int, reduction_of: Callable[[Robot], Reduction | None]) -> HeldPose | None:
        """``robot`` with joint ``k`` held, its plan checked at ``REFERENCES`` (``reduction_of(arm)``: the held arm's
        automatic reduction at a value seen for the first time, None where it checks every plan); None where it does
        not qualify (not seven joints, a slide held, a plan that is not the same closed form or sweep of
        ``SinglePose`` at every reference, a row that is not the full chain moved, a reference at a special value)."""
        values = references(robot, k)
        if values is None:
            return None
        found: list[tuple[float, GeometricReduction, SinglePose]] = []
        for v in values:
            held = hold_joints(robot, {k: v})
            red = reduction_of(held.arm)
            if not isinstance(red, GeometricReduction):
                return None
            sp = SinglePose.of(held.arm, red, held)
            if sp is None:
                return None
            found.append((v, red, sp))
        made = cls.from_references(robot, k, found)
        if made is None:
            return None
        windows = special_windows(robot, k, made.chain_at, lambda v: _plan_at(robot, k, v, reduction_of), found[0][0])
        if any(in_windows(v, windows) for v, _, _ in found):
            return None
        made.windows = windows
        plan = found[0][1].plan  # (the general way builds it at a new value as it is: ``vouch_held_plan``)
        vouch_held_plan(robot, (k,), (plan.family, plan.reversed, plan.free, plan.case), made.window_reference)
        return made

    def special(self, value: float) -> bool:
        """Whether ``value`` is in ``windows`` (the held arm there may be another arm)."""
        return in_windows(value, self.windows)

    def window_reference(self, value: float) -> float | None:
        """The reference value of the window of ``windows`` that holds ``value``, None outside them
        (``lock_windows.window_reference``)."""
        return window_reference(value, self.windows)

    def plan_at(self, value: float) -> Plan:
        """The held arm's plan at ``value`` (not in ``windows``): the references' with the wrist centre and meeting
        point the compiled call builds, the plan ``position_plan`` finds there to rounding (which takes ~0.3 ms)."""
        row = held_args(value, *self._geometry)[3]
        return dataclasses.replace(self.plan, W=tuple(row[_W : _W + 3].tolist()), meet=tuple(row[_O : _O + 3].tolist()))

    def chain_at(self, value: float) -> Chain:
        """The held arm's chain at ``value`` (world frame, as its ``Robot.chain``)."""
        GH, pts, GR, k = self._geometry[:4]
        H, P, R_end = held_chain(value, GH, pts, GR, k)
        return Chain(H, P, np.delete(self.robot.is_revolute, k), R_end)

    @classmethod
    def from_references(cls, robot: Robot, k: int, found: list[tuple[float, Any, SinglePose]]) -> HeldPose | None:
        """``of`` once the references' reductions are found (``(value, reduction, its SinglePose)`` at each of
        ``references``): the same plan at each, and this module's arguments equal to theirs; no ``windows`` yet."""
        plan0, sweeps = found[0][1].plan, found[0][2]._sweeps
        if any(_signature(r.plan) != _signature(plan0) or sp._sweeps != sweeps for _, r, sp in found):
            return None
        ch = robot.chain
        GH = writable(ch.H)
        pts = writable(np.concatenate([ch.points, ch.P.sum(axis=0)[None]]))
        marks, moves = cls._marks(robot, k, found, pts, GH)
        if marks is None:
            return None
        reverse, template = bool(plan0.reversed), found[0][2]._head[5].copy()
        for i in _NEED_BITS:  # (each reference's steps, all computed)
            template[i] = float(np.bitwise_or.reduce([int(sp._head[5][i]) for _, _, sp in found]))
        geometry = (GH, pts, writable(ch.R_end), int(k), reverse, marks, moves, template)
        tol = MATCH_REL * robot.length_scale
        chain_at, largest_at = _CHAIN_AT[sweeps], _LARGEST_AT[sweeps]
        rest = [(*sp._head[6:], *sp._tail) for _, _, sp in found]
        for (v, _, sp), args in zip(found, rest, strict=True):
            H, P, R_end, row, r_end, w_tool = held_args(v, *geometry)
            head, (at_H, at_P, at_R) = sp._head, chain_at
            own = head[5].copy()
            own[list(_NEED_BITS)] = template[list(_NEED_BITS)]
            fixed = np.r_[row[:_M], row[_W:]] - np.r_[own[:_M], own[_W:]]
            if not (
                np.abs(fixed).max() <= tol
                and np.abs(w_tool - head[4]).max() <= tol
                and np.abs(r_end - head[3]).max() <= MATCH_REL
                and np.abs(H - args[at_H]).max() <= MATCH_REL
                and np.abs(P - args[at_P]).max() <= tol
                and np.abs(R_end - args[at_R]).max() <= MATCH_REL
            ):
                return None
        # the arguments that are not the chain's: the same at every reference (the probed thresholds: the largest)
        out = []
        for i, a in enumerate(rest[0]):
            if i in chain_at:
                continue
            if i in largest_at:
                a = np.max([r[i] for r in rest], axis=0)
                out.append(writable(a) if np.ndim(a) else float(a))
            elif i in _UNION_AT[sweeps]:
                out.append(np.ascontiguousarray(np.unique(np.concatenate([r[i] for r in rest])), dtype=np.int64))
            elif all(r[i] is a or np.array_equal(np.asarray(r[i]), np.asarray(a)) for r in rest[1:]):
                out.append(a)
            else:
                return None
        return cls(robot, int(k), found[0][1].robot, plan0, geometry, tuple(out), sweeps)

    @staticmethod
    def _marks(
        robot: Robot, k: int, found: list[tuple[float, Any, SinglePose]], pts: Array, GH: Array
    ) -> tuple[Array | None, NDArray[np.int64]]:  # fmt: skip
        """The plan's wrist centre and meeting point at value 0 in the world ``(2, 3)`` and how each follows the value
        (``_held_args``' ``moves``): fixed, turned with the held joint, or (the meeting point of a plan whose first
        two position axes meet, ``ab_int``) where those axes meet at each value (Panda joint 6: axes 5 and 7 meet
        at a point that slides along axis 5; the row check of ``_checked`` confirms it); None where one does neither."""
        tol = MATCH_REL * 10.0 * robot.length_scale
        marks, moves = np.zeros((2, 3)), np.zeros(4, dtype=np.int64)
        for m in range(2):
            fixed, carried = [], []
            for v, red, _ in found:
                x = np.asarray(red.plan.W if m == 0 else red.plan.meet, dtype=np.float64)
                if red.plan.reversed:
                    ch = red.robot.chain
                    x = ch.R_end @ x + ch.P.sum(axis=0)
                fixed.append(x)
                carried.append(rotation_about(GH[k], -v) @ (x - pts[k]) + pts[k])
            for i, cand in enumerate((fixed, carried)):
                if np.abs(np.array(cand) - cand[0]).max() <= tol:
                    marks[m], moves[m] = cand[0], (_FIXED, _CARRIED)[i]
                    break
            else:
                plan = found[0][1].plan
                if m == 0 or plan.case != "ab_int":
                    return None, moves
                others = [i for i in range(4) if i != plan.free]
                moves[1], moves[2], moves[3] = _MET, others[0], others[1]
        return marks, moves

    def blocks(
        self, poses: Array, values: Array, limits: bool, general: Callable[[int], Iterable[Block]]
    ) -> list[Block]:  # fmt: skip
        """The solutions of ``poses (N, 4, 4)`` (checked, C-contiguous and writable), pose ``i`` with the held joint
        at ``values[i]``, as blocks in pose order: the poses the one call settles in blocks of their own, each other
        pose ``i`` as ``general(i)`` gives it."""
        out: list[Block] = []
        rows: list[tuple[Any, ...]] = []
        start = 0
        for i in range(poses.shape[0]):
            got = self.call(poses[i], float(values[i]), limits)
            if got[0] == OK and got[1] <= MAX_ISOLATED_SOLUTIONS:
                rows.append(got)
                continue
            if rows:
                out.append(self.block_of(poses[start:i], rows))
            out.extend(general(i))
            rows, start = [], i + 1
        if rows:
            out.append(self.block_of(poses[start:], rows))
        return out

    def block_of(self, poses: Array, rows: list[tuple[Any, ...]]) -> Block:
        """The block of consecutive ``poses`` from their kernels' answers ``rows``."""
        counts = [r[3].shape[0] for r in rows]
        return Block(
            robot=self.robot,
            poses=poses.copy(),
            bounds=np.concatenate([[0], np.cumsum(counts)]).astype(np.intp),
            q=np.concatenate([r[3] for r in rows]),
            error=np.concatenate([r[4] for r in rows]),
            error_geodesic=np.concatenate([r[5] for r in rows]),
            within_limits=np.concatenate([r[6] for r in rows]),
            multiplicity=np.concatenate([r[7] for r in rows]).astype(np.intp),
            families={},
            n_reachable=np.array([r[2] for r in rows], dtype=np.intp),
        )

    def call(self, pose: Array, value: float, limits: bool) -> tuple[Any, ...]:
        """The compiled call's answer for ``pose`` at ``value``; ``(SPECIAL, 0)`` at a value in ``windows``."""
        if in_windows(value, self.windows):
            return SPECIAL, 0
        if self.sweeps:  # (the buffers read here: a test may cut them)
            fixed = self._fixed
            buffers = (search.MAX_CAND, search.MAX_FAM)
            return self._kernel(pose, value, *self._geometry, *fixed[:9], *buffers, *fixed[9:], limits)
        return self._kernel(pose, value, *self._geometry, *self._fixed, limits)

    def solve(self, pose: Array, value: float, limits: bool) -> tuple[int, Solutions | None]:
        """``SinglePose.solve`` with the held joint at ``value`` (checked by the caller: ``held_values``)."""
        out = self.call(pose, value, limits)
        if out[0] == SPECIAL:
            return SPECIAL, None
        return answer(out, pose, self.robot)


def references(robot: Robot, k: int) -> list[float] | None:
    """The values at which ``HeldPose.of`` checks joint ``k``'s plan (``REFERENCES`` of its range cut to one turn);
    None where ``robot`` is not a seven-joint arm with ``k`` revolute and a range."""
    if robot.n_joints != 7 or not robot.is_revolute[k]:
        return None
    lo, hi = max(float(robot.lower[k]), -math.pi), min(float(robot.upper[k]), math.pi)
    if not hi > lo:
        return None
    return [lo + f * (hi - lo) for f in REFERENCES]


def _plan_at(robot: Robot, k: int, v: float, reduction_of: Callable[[Robot], Reduction | None]) -> object:
    """The plan (family, chain, theta*, case, branches, blind spot) that ``reduction_of`` chooses for ``robot`` held
    at ``v`` or a turn of it within the limits, None for none or one with a companion; ``"unreachable"`` where no
    turn of ``v`` is."""

    def plan(arm: Robot) -> object:
        red = reduction_of(arm)
        if not isinstance(red, GeometricReduction) or red.companion is not None:
            return None
        return _signature(red.plan)

    return at_turn(robot, k, v, plan)


def at_turn(robot: Robot, k: int, v: float, what: Callable[[Robot], object]) -> object:
    """``what`` of the held arm of ``robot`` with joint ``k`` at ``v`` or a turn of it within the limits;
    ``"unreachable"`` where no turn of ``v`` is."""
    for w in (v, v + 2.0 * math.pi, v - 2.0 * math.pi):
        tol = float(robot.limit_tol[k])
        if robot.lower[k] - tol <= w <= robot.upper[k] + tol:
            return what(hold_joints(robot, {k: w}).arm)
    return "unreachable"


def _signature(p: Any) -> tuple[Any, ...]:
    """What a plan is, its wrist centre and meeting point aside: family, chain, theta*, case, branches, blind spot."""
    return p.family, p.reversed, p.free, p.case, p.branches, p.conditional
