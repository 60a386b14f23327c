"""Self-motion families traced by numerical continuation, for continua a sweep of theta* cannot see.

A sweep finds a family along theta* as a flat stretch of its residual. A continuum along which theta* stays fixed
and another joint ``j`` moves (the C-Arm's theta2 self-motion under the automatic decomposition, which sweeps the
rail) shows up only as a few isolated candidates, where the reduction's closed form leaves ``j`` free
(``Reduction.continuum_joints``). From such a certified candidate, ``continuum_families`` follows the solution set
with ``j`` as its parameter: ``j`` is stepped, the other joints predicted from the last two members and corrected by
Newton steps on the full pose with ``j`` held (``polish.polish``). The traced members are kept as nodes; a member at
any ``j`` in the traced interval is corrected from the nodes around it (:class:`Traced`), so that a family reported
this way (``Family.reduction`` a ``Traced``) gives exact members like any other, and is cut to the joint limits and
certified as any other (``families.families_of``).

A fixed joint in the Newton step is well posed along a continuum: the Jacobian has rank 5 there, its null vector
(the continuum's tangent) moves ``j``, so the five other columns are independent.
"""

from __future__ import annotations

import numpy as np
from numba import float64, int64, types
from numpy.typing import NDArray

from sweepik._jit import inlined, writable
from sweepik.engine import parallel
from sweepik.engine.candidates import Spans
from sweepik.engine.certify import chain_args, polish_row, polish_work
from sweepik.engine.families import certified_members, families_of, off_families
from sweepik.engine.jacobi import singular_values
from sweepik.engine.polish import polished, pose_and_jacobian
from sweepik.engine.search import PARALLEL_MIN
from sweepik.engine.settings import (
    BACKTRACK,
    MAX_TRACES,
    PINV_RCOND,
    PROBE_ERROR,
    PROBE_STEP,
    SEED_BATCH,
    TRACE_FLOOR,
    TRACE_HALVINGS,
    TRACE_JUMP,
    TRACE_MIN,
    TRACE_NEWTON,
    TRACE_SETTLED,
    TRACE_SHARE,
    TRACE_SINGULAR,
    TRACE_STEPS,
)
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import Reduction
from sweepik.reductions.kernels import lazy_njit
from sweepik.results import Family, weighted_joint_distance
from sweepik.subproblems.trig import wrap_pi

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]


def scaled_singular(robot: Robot, q: Array) -> tuple[Array, Array]:
    """Singular values ``(K, 6)`` (decreasing) and right singular vectors ``(K, n, n)`` (rows) of the Jacobian at
    configurations ``q (K, n)``, lengths over the arm's length scale (a slide's column: per length scale)."""
    _, s, vt = np.linalg.svd(scaled_jacobians(robot, q))
    return s, vt


def second_singular(robot: Robot, q: Array, cold: NDArray[np.bool_]) -> Array:
    """``(K,)``: the second least singular value over the largest of ``scaled_singular``'s Jacobians at ``q (K, n)``,
    compiled (``jacobi.singular_values``: ~1.5 us a configuration where LAPACK's ``gesdd`` through NumPy took ~15;
    the crossing search asks for tens of thousands on a batch with families). Each row's rotations start from the
    last row's (neighbouring members of a family: one or two sweeps), but where ``cold``."""
    out = np.empty(q.shape[0])
    _ratios(scaled_jacobians(robot, q), np.ascontiguousarray(cold, dtype=np.bool_), 2, out)
    return out


def least_singular(robot: Robot, q: Array) -> Array:
    """``(K,)``: the least singular value over the largest of ``scaled_singular``'s Jacobians at ``q (K, n)``,
    compiled as ``second_singular`` (each row on its own: ~1.5 us a configuration, where NumPy's SVD of a few took
    ~40 us in all)."""
    out = np.empty(q.shape[0])
    _ratios(scaled_jacobians(robot, q), np.ones(q.shape[0], dtype=np.bool_), 1, out)
    return out


def scaled_jacobians(robot: Robot, q: Array) -> Array:
    """Jacobians ``(K, 6, n)`` at configurations ``q (K, n)`` as ``scaled_singular`` takes them: lengths over the arm's
    length scale (a slide's column: per length scale)."""
    J = pose_and_jacobian(robot, q)[1]
    J[:, :3, :] /= robot.length_scale
    J[:, :, ~robot.is_revolute] *= robot.length_scale
    return J


@lazy_njit((float64[:, :, ::1], types.boolean[::1], types.int64, float64[::1]), cache=True, nogil=True)
def _ratios(J, cold, back, out):  # pragma: no cover
    """``second_singular``'s and ``least_singular``'s kernel: the ``back``-th singular value from the least (1: the
    least) over the largest."""
    K, m, n = J.shape
    r = min(m, n)
    B, V, s = np.empty((m, n)), np.empty((n, n)), np.empty(r)
    for k in range(K):  # (warm from the last row, unless cold or its values were NaN)
        singular_values(J[k], B, V, s, k > 0 and not cold[k] and out[k - 1] == out[k - 1])
        out[k] = s[r - back] / s[0]


def _singular_along(robot: Robot, q: Array, joint: int) -> NDArray[np.bool_]:
    """``(K,)``: the configurations ``q (K, n)`` are singular with nearly null directions that move ``joint``
    (``TRACE_SINGULAR``, ``TRACE_SHARE``): the only places a continuum along it can pass (elsewhere the arm's
    solutions are isolated)."""
    s, vt = scaled_singular(robot, q)
    null = s <= TRACE_SINGULAR * s[:, :1]  # (K, 6): the nearly null directions (two where singular sets meet)
    share = np.sqrt(np.sum(np.where(null, vt[:, :6, joint] ** 2, 0.0), axis=1))
    return np.asarray(null[:, -1] & (share >= TRACE_SHARE))


def _world(robot: Robot, chain: Array) -> Array:
    """World tool poses of chain poses (the inverse of the solver's ``_chain_poses``)."""
    return robot.T_world_base @ chain @ robot.T_flange_tool


def correct(robot: Robot, q: Array, world: Array, joint: int | IntArray, tol: float) -> tuple[Array, Array]:
    """Newton steps on configurations ``q (K, n)`` towards ``world (K, 4, 4)`` with ``joint`` held (one for all, or
    one per configuration ``(K,)``): ``(q, errors)``."""
    weight = orientation_weight(robot.length_unit)
    fixed = np.zeros(q.shape, dtype=bool)
    fixed[np.arange(q.shape[0]), joint] = True
    return polished(robot, q, world, weight, iterations=TRACE_NEWTON, fixed=fixed, floor=TRACE_FLOOR * tol)


def _trace_one(robot: Robot, world: Array, q0: Array, joint: int, tol: float) -> tuple[Array, Array, bool] | None:
    """Members of the continuum through ``q0`` with ``joint`` as parameter, both ways from ``q0[joint]`` (a revolute
    joint over one turn at most, a prismatic one within its limits): ``(theta (M,), q (M, n), closed)`` in increasing
    theta (not wrapped), ``closed`` when a revolute joint came back to ``q0`` after a whole turn. None when the
    stretch is shorter than ``TRACE_MIN`` steps (``q0`` is isolated)."""
    periodic = bool(robot.is_revolute[joint])
    x0 = float(q0[joint])
    if periodic:
        total, lo, hi = 2.0 * np.pi, -np.inf, np.inf
    else:
        lo, hi = float(robot.lower[joint]), float(robot.upper[joint])
        if not hi - lo < 1e6 * robot.length_scale:  # no practical end: around the arm
            lo, hi = x0 - robot.length_scale, x0 + robot.length_scale
        total = hi - lo
    h0 = total / TRACE_STEPS
    sides: list[tuple[Array, Array]] = []
    closed = False
    for sign in (1.0, -1.0):
        reach = total - (sides[0][0][-1] - x0 if sides else 0.0) if periodic else (hi - x0 if sign > 0 else x0 - lo)
        xs, qs, done = _side(robot, world, x0, q0, joint, sign, reach, h0, tol)
        sides.append((xs, qs))
        back_home = weighted_joint_distance(robot, qs[-1], q0) <= TRACE_JUMP * 1e-3
        if periodic and sign > 0 and done >= reach and back_home:
            closed = True
            break
    theta, q = sides[0]
    if len(sides) > 1:
        theta = np.concatenate([sides[1][0][:0:-1], theta])
        q = np.concatenate([sides[1][1][:0:-1], q])
    if theta[-1] - theta[0] < TRACE_MIN * h0:
        return None
    return theta, q, closed


def _side(
    robot: Robot, world: Array, x0: float, q0: Array, joint: int, sign: float, reach: float, h0: float, tol: float
) -> tuple[Array, Array, float]:
    """The members of one side of the continuum through ``q0`` (``sign``: the way ``joint`` goes), ``reach`` far at
    most, from the seed on: ``(joint values (M,), members (M, n), distance gone)``. Each step predicts the next member
    by the secant through the last two, corrects it with the joint held, and keeps it when it solves the pose, lies
    near its prediction (``TRACE_JUMP``) and the member halfway solves the pose too (a step may not leap over a gap in
    the solution set: a KR 6 pose whose wrist centre sits on axis 1 at full stretch holds stretches of a continuum
    along joint 1 with gaps between them, where the interpolated members missed the pose by 6e-5 of the arm's size);
    a failed step is halved. In compiled calls (``_trace_side``), each filling a buffer of members; a full one is
    handed on and the trace resumed from its last two members."""
    n = robot.n_joints
    scale = np.where(robot.is_revolute, 1.0, 1.0 / orientation_weight(robot.length_unit))
    args = (*chain_args(robot), np.ascontiguousarray(world, dtype=np.float64), int(joint), float(sign), float(reach))
    consts = (float(h0), float(tol), scale, orientation_weight(robot.length_unit))
    xs, qs = np.empty(_BUFFER), np.empty((_BUFFER, n))
    xs[0], qs[0] = x0, q0
    count, h, done = 1, h0 * PROBE_STEP, 0.0
    parts_x: list[Array] = []
    parts_q: list[Array] = []
    while True:
        count, h, done, full = _trace_side(*args, *consts, xs, qs, count, h, done)
        if not full:
            break
        parts_x.append(xs[: count - 2].copy())
        parts_q.append(qs[: count - 2].copy())
        xs[:2], qs[:2] = xs[count - 2 : count], qs[count - 2 : count]
        count = 2
    parts_x.append(xs[:count])
    parts_q.append(qs[:count])
    return np.concatenate(parts_x), np.concatenate(parts_q), done


#: Members a compiled trace call holds before it hands them on (``_side``).
_BUFFER = 512

_CHAIN = (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1])


@inlined
def _distance(a, b, rev, scale):
    """``results.weighted_joint_distance`` of two configurations."""
    s = 0.0
    for i in range(a.shape[0]):
        d = wrap_pi(a[i] - b[i]) if rev[i] else a[i] - b[i]
        s += (d * scale[i]) ** 2
    return np.sqrt(s)


@inlined
def _correct_row(H, P, rev, R_end, q, world, weight, held, tol, work):
    """:func:`correct` of one configuration ``q`` in place (the ``held`` joint held): its error after."""
    floor, settled = TRACE_FLOOR * tol, TRACE_SETTLED * tol
    return polish_row(
        H, P, rev, R_end, q, world, weight, held, TRACE_NEWTON, BACKTRACK, PINV_RCOND, floor, work, settled
    )


@lazy_njit(
    types.Tuple((int64, float64, float64, types.boolean))(
        *_CHAIN,
        float64[:, ::1],
        int64,
        float64,
        float64,
        float64,
        float64,
        float64[::1],
        float64,
        float64[::1],
        float64[:, ::1],
        int64,
        float64,
        float64,
    ),
    cache=True,
    nogil=True,
)
def _trace_side(H, P, rev, R_end, world, joint, sign, reach, h0, tol, scale, weight, xs, qs, count, h, done):
    """:func:`_side` from the members ``xs[:count], qs[:count]`` on (the seed alone, or the last two members of a
    trace handed on), with the step ``h`` and the distance ``done`` it had: ``(count, h, done, full)``, ``full``
    when the buffer filled before the side ended."""
    n = H.shape[0]
    work = polish_work(n)
    held = np.zeros(n, dtype=np.bool_)
    held[joint] = True
    pred, mid = np.empty(n), np.empty(n)
    # (its steps halved below the probe's once the trace has gone far enough, or once the first step reached the pose:
    # a continuum's, where only the jump failed, as next to a nearly straight wrist that swings fast)
    on = False
    while done < reach and h >= h0 * (2.0**-TRACE_HALVINGS if on or done >= TRACE_MIN * h0 else PROBE_STEP):
        if count == xs.shape[0]:
            return count, h, done, True
        step = min(h, reach - done)
        x, q = xs[count - 1], qs[count - 1]
        for i in range(n):
            pred[i] = q[i]
        if count > 1:  # secant through the last two members
            f = step / abs(x - xs[count - 2])
            for i in range(n):
                pred[i] = q[i] + (q[i] - qs[count - 2, i]) * f
        pred[joint] = x + sign * step
        corr = qs[count]
        for i in range(n):
            corr[i] = pred[i]
        err = _correct_row(H, P, rev, R_end, corr, world, weight, held, tol, work)
        if count == 1 and not err <= PROBE_ERROR * tol:  # (see PROBE_ERROR)
            break
        on = on or count == 1
        ok = err <= tol and _distance(corr, pred, rev, scale) <= TRACE_JUMP
        if ok:  # the member halfway solves the pose too (``_bridged``)
            for i in range(n):
                mid[i] = 0.5 * (q[i] + corr[i])
            ok = _correct_row(H, P, rev, R_end, mid, world, weight, held, tol, work) <= tol
        if ok:
            xs[count] = x + sign * step
            count += 1
            done += step
            h = min(2.0 * h, h0)
        else:
            h *= 0.5
    return count, h, done, False


@lazy_njit(
    (*_CHAIN, int64[::1], float64[::1], float64[:, ::1], int64[::1], float64[::1], types.boolean, int64)
    + (float64[:, :, ::1], int64, float64, float64, float64[:, ::1], float64[::1], int64, int64),
    cache=True,
    nogil=True,
)
def _traced_rows(H, P, rev, R_end, offsets, xs, qs, br, x, periodic, per, world, joint, tol, weight, q, err, start,
                 stop):  # fmt: skip
    """:meth:`Traced.corrected` compiled, rows ``start .. stop - 1``: the member of branch ``br[k]`` at ``x[k]``
    interpolated between its nodes (``x[k]`` moved by whole turns next to them when ``periodic``, and clipped to
    them, as ``Traced._unwrapped`` and ``np.interp``), then corrected towards ``world[k // per]`` with the joint
    held (``correct``); ``q[k]`` and ``err[k]`` written (left NaN and inf where there is no member)."""
    n = H.shape[0]
    work = polish_work(n)
    held = np.zeros(n, dtype=np.bool_)
    held[joint] = True
    for k in range(start, stop):
        b = br[k]
        if b < 0 or b >= offsets.size - 1 or not np.isfinite(x[k]):
            continue
        s0, s1 = offsets[b], offsets[b + 1]
        if s1 == s0:
            continue
        t = x[k]
        if periodic:  # (by whole turns next to the nodes' middle)
            mid = 0.5 * (xs[s0] + xs[s1 - 1])
            t = mid - wrap_pi(mid - t)
        t = min(max(t, xs[s0]), xs[s1 - 1])
        i = min(max(np.searchsorted(xs[s0:s1], t, side="right") - 1, 0), max(s1 - s0 - 2, 0))
        a = s0 + i
        if s1 - s0 == 1 or t <= xs[a]:
            for c in range(n):
                q[k, c] = qs[a, c]
        elif t >= xs[a + 1]:
            for c in range(n):
                q[k, c] = qs[a + 1, c]
        else:
            f = (t - xs[a]) / (xs[a + 1] - xs[a])
            for c in range(n):
                q[k, c] = qs[a, c] + f * (qs[a + 1, c] - qs[a, c])
        q[k, joint] = x[k]
        finite = True
        for c in range(n):
            finite = finite and np.isfinite(q[k, c])
        if finite:
            err[k] = _correct_row(H, P, rev, R_end, q[k], world[k // per], weight, held, tol, work)


class Traced(Reduction):
    """The members of traced continua along one joint: branch ``k`` is a traced one (``nodes[k]``: the joint's values
    ``(M,)``, increasing, and the members there ``(M, n)``), its member at a value of the joint corrected from the
    nodes around it (linear interpolation, then Newton steps with the joint held, to within ``tol``). Used only as the
    ``reduction`` of the families it traced (no residual: it is not swept); a store keeps a family's nodes."""

    name = "traced"

    def __init__(self, robot: Robot, joint: int, nodes: dict[int, tuple[Array, Array]], tol: float) -> None:
        super().__init__(robot, joint, max(nodes, default=-1) + 1)
        self.nodes = nodes
        self.tol = tol
        self._pack: tuple[NDArray[np.int64], Array, Array] | None = None

    def add(self, theta: Array, q: Array) -> int:
        """A traced continuum as a new branch: its index."""
        b = self.n_branches
        self.nodes[b] = (theta, q)
        self.n_branches = b + 1
        return b

    def _unwrapped(self, branch: int, x: Array) -> Array:
        """``x`` moved by whole turns into the nodes' stretch of ``branch`` (a revolute joint), then clipped to it."""
        th = self.nodes[branch][0]
        if self.periodic:
            mid = 0.5 * (th[0] + th[-1])
            x = x + 2.0 * np.pi * np.round((mid - x) / (2.0 * np.pi))
        return np.clip(x, th[0], th[-1])

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        return self.corrected(poses, theta, branch)[0]

    def corrected(self, poses: Array, theta: Array, branch: IntArray | None = None) -> tuple[Array, Array]:
        """``solve_rest``'s members ``(..., n)`` and their geodesic errors ``(...)`` as the Newton steps left them
        (a member solves the pose where its error is within the certification's tolerance: no second FK needed;
        NaN members, infinite errors, where there is none)."""
        n, j = self.robot.n_joints, self.free_joint
        if branch is None:  # every branch
            each = [
                self.corrected(poses, theta, np.full(theta.shape, b, dtype=np.intp))
                if b in self.nodes
                else (np.full((*theta.shape, n), np.nan), np.full(theta.shape, np.inf))
                for b in range(self.n_branches)
            ]
            return np.stack([q for q, _ in each], axis=-2), np.stack([e for _, e in each], axis=-1)
        br = np.array(np.broadcast_to(branch, theta.shape).reshape(-1), dtype=np.int64)
        x = writable(np.reshape(theta, -1))
        world = _world(self.robot, poses)  # (one per pose: theta's rows are poses)
        q, err = np.full((x.size, n), np.nan), np.full(x.size, np.inf)
        offsets, xs, qs = self._packed()
        weight = orientation_weight(self.robot.length_unit)
        per = max(int(theta.shape[1]), 1)
        args = (offsets, xs, qs, br, x, self.periodic, per, writable(world), j, float(self.tol), weight, q, err)
        parallel.run(_traced_rows, x.size, PARALLEL_MIN, *chain_args(self.robot), *args)
        return q.reshape(*theta.shape, n), err.reshape(theta.shape)

    def _packed(self) -> tuple[NDArray[np.int64], Array, Array]:
        """The nodes of every branch end to end, as the compiled members take them: ``(offsets (B + 1,), joint values,
        members)``, branch ``b``'s at ``offsets[b]:offsets[b + 1]`` (none for a branch without nodes). Kept until a
        branch is added."""
        if self._pack is None or self._pack[0].size != self.n_branches + 1:
            counts = [self.nodes[b][0].size if b in self.nodes else 0 for b in range(self.n_branches)]
            offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
            n = self.robot.n_joints
            have = [b for b in range(self.n_branches) if b in self.nodes]
            xs = np.concatenate([np.zeros(0)] + [np.asarray(self.nodes[b][0], dtype=np.float64) for b in have])
            qs = np.concatenate([np.zeros((0, n))] + [np.asarray(self.nodes[b][1], dtype=np.float64) for b in have])
            self._pack = (offsets, np.ascontiguousarray(xs), np.ascontiguousarray(qs))
        return self._pack


def _pieces(pose: int, branch: int, theta: Array, closed: bool, periodic: bool) -> list[tuple[int, int, float, float]]:
    """The spans ``(pose, branch, lo, hi)`` of a traced stretch ``theta`` (increasing, not wrapped): a revolute joint's
    in ``[-pi, pi]`` (the whole circle when ``closed``; else one piece, or two where it crosses pi)."""
    if not periodic:
        return [(pose, branch, float(theta[0]), float(theta[-1]))]
    if closed:
        return [(pose, branch, -np.pi, np.pi)]
    lo = float(np.mod(theta[0] + np.pi, 2.0 * np.pi) - np.pi)
    hi = lo + float(theta[-1] - theta[0])
    if hi <= np.pi:
        return [(pose, branch, lo, hi)]
    return [(pose, branch, lo, np.pi), (pose, branch, -np.pi, hi - 2.0 * np.pi)]


def continuum_families(
    robot: Robot,
    chain: Array,
    world: Array,
    pose: IntArray,
    q: Array,
    joint: IntArray,
    limits: bool,
    tol: float,
) -> tuple[dict[int, list[Family]], IntArray, Array]:
    """Families traced from certified configurations ``q (K, n)`` of poses ``pose (K,)`` (chain poses ``chain``, world
    poses ``world``), each along its ``joint (K,)``: ``(families per pose, pose index, q)`` as ``families_of`` gives
    them (pieces that shrink to a point, at the limits, as isolated members). A configuration on a family already
    traced from another of its pose is not traced again; one that cannot be followed (an isolated solution) gives
    nothing. At most ``MAX_TRACES`` families are traced a pose and joint (more: a self-motion of two or more
    dimensions, of which the families are curves)."""
    out: dict[int, list[Family]] = {}
    iso_p: list[IntArray] = [np.zeros(0, dtype=np.intp)]
    iso_q: list[Array] = [np.zeros((0, robot.n_joints))]
    for j in np.unique(joint).tolist():
        spans: list[tuple[int, int, float, float]] = []
        traced = Traced(robot, j, {}, tol)
        ks = np.nonzero(joint == j)[0]
        for i in np.unique(pose[ks]).tolist():
            left = q[ks[pose[ks] == i]]
            traces = 0
            while left.shape[0] and traces < MAX_TRACES:
                # onto the solution set first, a few at a time (a candidate where the closed form leaves j free is
                # rough; a pose on a continuum can have thousands, most of them on the first family traced)
                head = left[:SEED_BATCH]
                head, err = correct(robot, head, np.repeat(world[i][None], head.shape[0], axis=0), j, tol)
                good = np.nonzero(err <= tol)[0]
                good = good[_singular_along(robot, head[good], j)]
                if good.size == 0:
                    left = left[SEED_BATCH:]
                    continue
                seed, left = head[good[0]], left[good[0] + 1 :]
                stretch = _trace_one(robot, world[i], seed, j, tol)
                if stretch is None:
                    continue
                traces += 1
                th, Q, closed = stretch
                new = _pieces(i, traced.add(th, Q), th, closed, traced.periodic)
                spans += new
                if left.shape[0]:  # the other seeds on it are not traced again (those left are off the others)
                    mine = tuple(
                        Family(j, (lo, hi), traced, chain[i], b, members=certified_members) for _, b, lo, hi in new
                    )
                    left = left[off_families(robot, [(left, mine)])[0]]
        if not spans:
            continue
        p_, b_, lo_, hi_ = (np.array(c) for c in zip(*spans, strict=True))
        found = Spans(p_.astype(np.intp), b_.astype(np.intp), lo_.astype(np.float64), hi_.astype(np.float64))
        fams, fp, fq = families_of(robot, traced, chain, world, found, limits, tol)
        for i, f in fams.items():
            out.setdefault(i, []).extend(f)
        iso_p.append(fp)
        iso_q.append(fq)
    return out, np.concatenate(iso_p).astype(np.intp), np.concatenate(iso_q)
