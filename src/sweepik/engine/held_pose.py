"""A seven-joint arm with one joint held, its lock value an argument of the compiled call (issue 39).

Holding joint ``k`` of a chain at ``v`` makes a six-joint chain whose geometry is the full chain's with the joints
after ``k`` (and the tool) moved by joint ``k``'s motion at ``v``: a rotation about its axis, or a slide along it.
The held arm, its plan and its kernel arguments were built for each new value (~2 ms on the iiwa); but when the plan
is the same at every value, everything else in them is the full arm's geometry moved by that motion. Here the
compiled call takes ``v`` and builds the held chain, the plan's parameter row (its axes, segments, wrist centre and
meeting point) and the certification's chain itself, then settles every branch as ``single_pose`` does: a new value
costs what the same value costs.

When the plan holds at every value (``HeldPose.of``): the plan chosen for the held arm at five values spread over
the joint's range (``REFERENCES``) must be the same family, case, theta* and chain direction at each; its wrist
centre and meeting point each either fixed in the world or carried by the held joint's motion (a point on the held
axis is both); and this module's parameter row, chain and tool vectors must equal the held arm's at those values to
rounding. That makes the plan's structure hold at every value: axes that meet at a point fixed in the world, or
carried with them, meet whatever the value; a direction turned by the held joint is a trigonometric polynomial of
degree one in the value, so one parallel to another at five values is parallel at all. (Axes that meet at a point
sliding along one of them are not taken: they are parallel at some value, where the plan changes - Panda joint 6.)
The arguments that do not depend on the geometry are the held arm's at every value (its length scale is the full
arm's: ``origin_axis.hold_joints``); the singular set's thresholds (typical step amplitudes, probed) are the largest
of the five: a pose nearer its singular set than that goes the general way, where the held arm at its own value
answers. So does every pose the one call does not settle (``single_pose``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from numba import boolean, float64, int64
from numpy.typing import NDArray

from sweepik._jit import inlined, writable
from sweepik.engine.one_pose import OK, SETTLE_CLOSED_SIG, every_branch_settled
from sweepik.engine.settings import MAX_ISOLATED_SOLUTIONS
from sweepik.engine.single_pose import NOT_RIGID, SinglePose, answer, rigid_pose
from sweepik.model.chain import rotation_about
from sweepik.model.origin_axis import HeldJoints, hold_joints
from sweepik.model.robot import Robot
from sweepik.model.structure import INTERSECT_TOL_REL, PARALLEL_TOL
from sweepik.reductions import GeometricReduction, Reduction
from sweepik.reductions.geometric import LAYOUT, N_PARAMS, pose_rows
from sweepik.reductions.kernels import lazy_njit
from sweepik.results import Block, Solutions
from sweepik.subproblems.vec import add, dot, rot, scale, sub

__all__ = ["HeldPose", "REFERENCES", "COAXIAL", "coaxial_values"]

Array = NDArray[np.float64]

#: Where in the held joint's range (a revolute one's cut to one turn) the plan is checked: five values, none at the
#: middle or an end (a symmetric range's 0 and +-pi/2 are where axes of many arms line up).
REFERENCES = (0.0731, 0.2689, 0.4623, 0.6571, 0.8817)
#: The parameter row, chain and tool vectors built here equal the held arm's to this, times the length scale.
MATCH_REL = 1e-12
#: A lock value this near (radians, or the length unit) one where two axes of the held arm coincide is solved the
#: general way (its own plan, or a refusal): the one call's plan has no meaning there.
COAXIAL_NEAR = 1e-6
#: ``HeldPose.solve``'s status for such a value.
COAXIAL = -2

_H, _P, _W, _O = LAYOUT["H"], LAYOUT["P"], LAYOUT["W"], LAYOUT["O"]
_M = LAYOUT["M"]


@inlined
def _moved(x, value, h, o, slide):  # pragma: no cover
    """The point ``x`` moved by the joint of axis ``h`` through ``o`` at ``value`` (a tuple)."""
    if slide:
        return add(x, scale(value, h))
    return add(o, rot(h, value, sub(x, o)))


@inlined
def _turned(d, value, h, slide):  # pragma: no cover
    """The direction ``d`` turned by that joint (a slide turns nothing)."""
    return (d[0], d[1], d[2]) if slide else rot(h, value, d)


@inlined
def _held_chain(value, GH, pts, GR, k, slide):  # pragma: no cover
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
        x = (pts[i, 0], pts[i, 1], pts[i, 2]) if i < k else _moved(pts[i], value, h, o, slide)
        d = sub(x, prev)
        P[j, 0], P[j, 1], P[j, 2] = d
        prev = x
        if i < n:
            a = (GH[i, 0], GH[i, 1], GH[i, 2]) if i < k else _turned(GH[i], value, h, slide)
            H[j, 0], H[j, 1], H[j, 2] = a
        j += 1
    for c in range(3):
        R_end[0, c], R_end[1, c], R_end[2, c] = _turned(GR[:, c], value, h, slide)
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
def _held_args(value, GH, pts, GR, k, slide, reverse, marks, moves, template):  # pragma: no cover
    """The held chain ``(H, P, R_end)`` at ``value`` and ``pose_rows``' arguments for its plan: the row (``template``
    with the solved chain's axes, segments, wrist centre and meeting point: ``marks`` at value 0 in the world,
    ``moves``: carried by the held joint), the solved chain's tool orientation and the wrist centre in the tool
    frame."""
    H, P, R_end = _held_chain(value, GH, pts, GR, k, slide)
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
        x = (marks[m, 0], marks[m, 1], marks[m, 2])
        if moves[m]:
            x = _moved(x, value, GH[k], pts[k], slide)
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


_GEOMETRY_SIG = (
    float64, float64[:, ::1], float64[:, ::1], float64[:, ::1], int64, boolean, boolean, float64[:, ::1],
    boolean[::1], float64[::1],
)  # fmt: skip


@lazy_njit(_GEOMETRY_SIG, cache=True, nogil=True)
def held_args(value, GH, pts, GR, k, slide, reverse, marks, moves, template):  # pragma: no cover
    """``_held_args`` called from Python (``HeldPose.of`` checks it against the held arm's)."""
    return _held_args(value, GH, pts, GR, k, slide, reverse, marks, moves, template)


@lazy_njit(
    (float64[:, ::1],) + _GEOMETRY_SIG + SETTLE_CLOSED_SIG[:1] + SETTLE_CLOSED_SIG[3:4] + SETTLE_CLOSED_SIG[6:7]
    + SETTLE_CLOSED_SIG[8:],
    cache=True,
    nogil=True,
)  # fmt: skip
def _held_closed_pose(
    world, value, GH, pts, GR, k, slide, reverse, marks, moves, template, addr, nb, rev, weight, thr, lrev, lower,
    upper, ltol, beyond, reach, tol, scale, s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """``single_pose._closed_pose`` for the held chain at ``value`` (``_held_args``' arguments after ``world``):
    ``(status, certified, reachable, q, error, error_geodesic, within_limits, multiplicity)`` with ``q`` full length,
    ``value`` in column ``k``."""
    if not rigid_pose(world):
        none = np.empty(0)
        return NOT_RIGID, 0, 0, np.empty((0, GH.shape[0])), none, none, np.empty(0, np.bool_), np.empty(0, np.int64)
    H, P, R_end, row, r_end, w_tool = _held_args(value, GH, pts, GR, k, slide, reverse, marks, moves, template)
    eye = np.eye(4)
    params = np.empty((1, N_PARAMS))
    pose_rows(world.reshape((1, 4, 4)), eye, eye, reverse, r_end, w_tool, row, params)
    st, c, reachable, q, ep, eg, ins, mu, _ = every_branch_settled(
        addr, params, world.reshape((1, 4, 4)), nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond,
        reach, tol, scale, s_thr, meet, only_inside,
    )  # fmt: skip
    full = np.empty((q.shape[0], q.shape[1] + 1))
    for r in range(q.shape[0]):
        j = 0
        for i in range(full.shape[1]):
            if i == k:
                full[r, i] = value
            else:
                full[r, i] = q[r, j]
                j += 1
    return st, c, reachable, full, ep, eg, ins, mu


class HeldPose:
    """A seven-joint arm with joint ``k`` held, its closed form's arguments built in the compiled call from the lock
    value (module docstring): ``of(robot, k, reduction_of)``, then ``solve(pose, value, limits)`` per pose."""

    __slots__ = ("robot", "joint", "arm", "coaxial", "_geometry", "_tail", "_period")

    def __init__(
        self, robot: Robot, joint: int, arm: Robot, geometry: tuple[Any, ...], tail: tuple[Any, ...]
    ) -> None:  # fmt: skip
        self.robot = robot
        self.joint = joint
        self.arm = arm  # (the held arm at a reference value: what its reduction is named)
        GH, pts, _, _, slide = geometry[:5]
        #: values at which two axes of the held arm coincide (``coaxial_values``)
        self.coaxial = coaxial_values(robot, joint, GH, pts)
        self._period = math.inf if slide else 2.0 * math.pi
        self._geometry = geometry  # (the full chain, the joint, the plan's direction, marks and row)
        self._tail = tail  # (the settling's arguments, as ``SinglePose``'s without the chain)

    @classmethod
    def of(cls, robot: Robot, k: int, reduction_of: Callable[[HeldJoints], Reduction]) -> HeldPose | None:
        """``robot`` with joint ``k`` held, its plan checked at ``REFERENCES`` (``reduction_of(held)``: the held
        arm's default reduction); None where it does not qualify (not seven joints, a plan that is not the same
        closed form of ``SinglePose`` at every reference, a row that is not the full chain moved)."""
        if robot.n_joints != 7:
            return None
        lo, hi = float(robot.lower[k]), float(robot.upper[k])
        slide = not bool(robot.is_revolute[k])
        if not slide:
            lo, hi = max(lo, -math.pi), min(hi, math.pi)
        if not hi > lo:
            return None
        refs = [lo + f * (hi - lo) for f in REFERENCES]
        found = []
        for v in refs:
            held = hold_joints(robot, {k: v})
            try:
                red = reduction_of(held)
            except Exception:  # noqa: BLE001 (a value the arm refuses: the general path says why)
                return None
            sp = SinglePose.of(held.arm, red, held) if isinstance(red, GeometricReduction) else None
            if sp is None or sp._sweeps or not red.closed_form:
                return None
            found.append((v, red, sp))
        return cls._checked(robot, k, slide, found)

    @classmethod
    def _checked(cls, robot: Robot, k: int, slide: bool, found: list[tuple[float, Any, SinglePose]]) -> HeldPose | None:
        """``of`` once the references' reductions are found: the same plan at each, and this module's arguments
        equal to theirs."""
        plan0 = found[0][1].plan
        same = ("family", "reversed", "free", "case", "branches", "conditional")
        if any(tuple(getattr(r.plan, a) for a in same) != tuple(getattr(plan0, a) for a in same) for _, r, _ in found):
            return None
        ch = robot.chain
        GH = writable(ch.H)
        pts = writable(np.concatenate([ch.points, ch.P.sum(axis=0)[None]]))
        GR = writable(ch.R_end)
        reverse = bool(plan0.reversed)
        marks, moves = cls._marks(robot, k, slide, found, pts, GH)
        if marks is None:
            return None
        tails = [sp._tail for _, _, sp in found]
        template = writable(found[0][2]._head[5])
        geometry = (GH, pts, GR, int(k), slide, reverse, marks, moves, template)
        tol = MATCH_REL * robot.length_scale
        for (v, _, sp), tail in zip(found, tails, strict=True):
            H, P, R_end, row, r_end, w_tool = held_args(v, *geometry)
            head = sp._head
            fixed = np.r_[row[:_M], row[_W:]] - np.r_[head[5][:_M], head[5][_W:]]
            if not (
                np.abs(fixed).max() <= tol
                and np.abs(w_tool - head[4]).max() <= tol
                and np.abs(r_end - head[3]).max() <= MATCH_REL
                and np.abs(H - tail[2]).max() <= MATCH_REL
                and np.abs(P - tail[3]).max() <= tol
                and np.abs(R_end - tail[5]).max() <= MATCH_REL
            ):
                return None
        # the arguments that are not the chain's: the same at every reference (the singular thresholds: the largest)
        keep = (0, 1, 4, *range(6, 16), 17)
        for tail in tails[1:]:
            for i in keep:
                a, b = tails[0][i], tail[i]
                if not (a is b or np.array_equal(np.asarray(a), np.asarray(b))):
                    return None
        s_thr = writable(np.max([t[16] for t in tails], axis=0))
        t0 = tails[0]
        return cls(robot, int(k), found[0][1].robot, geometry, (t0[0], t0[1], t0[4], *t0[6:16], s_thr, t0[17]))

    @staticmethod
    def _marks(
        robot: Robot, k: int, slide: bool, found: list[tuple[float, Any, SinglePose]], pts: Array,
        GH: Array,
    ) -> tuple[Array | None, NDArray[np.bool_]]:  # fmt: skip
        """The plan's wrist centre and meeting point at value 0 in the world ``(2, 3)`` and whether each moves with
        the held joint; None where one is neither fixed nor carried."""
        tol = MATCH_REL * 10.0 * robot.length_scale
        marks, moves = np.empty((2, 3)), np.zeros(2, dtype=np.bool_)
        for m in range(2):
            fixed, carried = [], []
            for v, red, _ in found:
                x = np.asarray(red.plan.W if m == 0 else red.plan.meet, dtype=np.float64)
                if red.plan.reversed:
                    ch = red.robot.chain
                    x = ch.R_end @ x + ch.P.sum(axis=0)
                fixed.append(x)
                if slide:
                    carried.append(x - v * GH[k])
                else:
                    R = rotation_about(GH[k], -v)
                    carried.append(R @ (x - pts[k]) + pts[k])
            for i, cand in enumerate((fixed, carried)):
                if np.abs(np.array(cand) - cand[0]).max() <= tol:
                    marks[m], moves[m] = cand[0], bool(i)
                    break
            else:
                return None, moves
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
            got = self._call(poses[i], float(values[i]), limits)
            if got[0] == OK and got[1] <= MAX_ISOLATED_SOLUTIONS:
                rows.append(got)
                continue
            if rows:
                out.append(self._block(poses[start:i], rows))
            out.extend(general(i))
            rows, start = [], i + 1
        if rows:
            out.append(self._block(poses[start:], rows))
        return out

    def _block(self, poses: Array, rows: list[tuple[Any, ...]]) -> Block:
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

    def _call(self, pose: Array, value: float, limits: bool) -> tuple[Any, ...]:
        """The compiled call's answer for ``pose`` at ``value``; ``(COAXIAL, 0)`` within ``COAXIAL_NEAR`` of a value
        where two of the held arm's axes coincide."""
        for c in self.coaxial:
            d = abs(value - c) % self._period  # (a turn away is the same angle)
            if min(d, self._period - d) < COAXIAL_NEAR:
                return COAXIAL, 0
        return _held_closed_pose(pose, value, *self._geometry, *self._tail, limits)

    def solve(self, pose: Array, value: float, limits: bool) -> tuple[int, Solutions | None]:
        """``SinglePose.solve`` with the held joint at ``value`` (checked by the caller: ``held_values``)."""
        out = self._call(pose, value, limits)
        if out[0] == COAXIAL:
            return COAXIAL, None
        return answer(out, pose, self.robot)


def coaxial_values(robot: Robot, k: int, GH: Array, pts: Array) -> tuple[float, ...]:
    """The values of joint ``k`` at which its neighbours' axes coincide, both revolute (a continuum at every pose),
    or run along one direction, both slides: the held arm is degenerate there, and its plan is not the plan of the
    other values. (Only the neighbours: no joint between them moves one against the other.) ``GH``, ``pts``: the
    full chain's axes and joint points at zero."""
    a, b, rev = k - 1, k + 1, robot.is_revolute
    if a < 0 or b >= GH.shape[0] or rev[a] != rev[b]:
        return ()
    hk, ok = GH[k], pts[k]
    out: list[float] = []
    for target in (GH[a], -GH[a]):
        if rev[k]:  # the angle turning b's direction onto a's about hk (sp1), where there is one
            u, w = GH[b] - (GH[b] @ hk) * hk, target - (target @ hk) * hk
            v = math.atan2(float(hk @ np.cross(u, w)), float(u @ w))
            R = rotation_about(hk, v)
            if np.abs(R @ GH[b] - target).max() > PARALLEL_TOL:
                continue
            point = R @ (pts[b] - ok) + ok
        else:  # a slide turns nothing: parallel directions, the slide that puts b's point on a's line
            s = hk - (hk @ target) * target
            if np.abs(GH[b] - target).max() > PARALLEL_TOL or not rev[b] or s @ s < PARALLEL_TOL:
                continue  # (two slides: parallel at every value or none; the plan says which)
            e = pts[b] - pts[a]
            v = -float((e - (e @ target) * target) @ s) / float(s @ s)
            point = pts[b] + v * hk
        d = point - pts[a]
        if not rev[b] or np.linalg.norm(d - (d @ target) * target) <= INTERSECT_TOL_REL * robot.length_scale:
            out.append(float(v))
    return tuple(out)
