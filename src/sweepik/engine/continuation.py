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
from numpy.typing import NDArray

from sweepik.engine.candidates import Spans
from sweepik.engine.families import certified_members, families_of, off_families
from sweepik.engine.polish import polished, pose_and_jacobian
from sweepik.engine.settings import (
    PROBE_ERROR,
    PROBE_STEP,
    SEED_BATCH,
    TRACE_HALVINGS,
    TRACE_JUMP,
    TRACE_MIN,
    TRACE_NEWTON,
    TRACE_SHARE,
    TRACE_SINGULAR,
    TRACE_STEPS,
)
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import Reduction
from sweepik.results import Family, weighted_joint_distance

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]


def scaled_singular(robot: Robot, q: Array) -> tuple[Array, Array]:
    """Singular values ``(K, 6)`` (decreasing) and right singular vectors ``(K, n, n)`` (rows) of the Jacobian at
    configurations ``q (K, n)``, lengths over the arm's length scale (a slide's column: per length scale)."""
    J = pose_and_jacobian(robot, q)[1]
    J[:, :3, :] /= robot.length_scale
    J[:, :, ~robot.is_revolute] *= robot.length_scale
    _, s, vt = np.linalg.svd(J)
    return s, vt


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
    return polished(robot, q, world, weight, iterations=TRACE_NEWTON, fixed=fixed, floor=1e-3 * tol)


def _bridged(robot: Robot, world: Array, a: Array, b: Array, joint: int, tol: float) -> bool:
    """The member halfway between members ``a`` and ``b`` (the joint's midpoint, the others interpolated and corrected
    as :class:`Traced` does) solves the pose: a step of the trace may not leap over a gap in the solution set (a
    KR 6 pose whose wrist centre sits on axis 1 at full stretch holds stretches of a continuum along joint 1 with
    gaps between them, where the interpolated members missed the pose by 6e-5 of the arm's size)."""
    _, err = correct(robot, (0.5 * (a + b))[None], world[None], joint, tol)
    return bool(err[0] <= tol)


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
    sides: list[list[tuple[float, Array]]] = []
    closed = False
    for sign in (1.0, -1.0):
        reach = total - (sides[0][-1][0] - x0 if sides else 0.0) if periodic else (hi - x0 if sign > 0 else x0 - lo)
        nodes: list[tuple[float, Array]] = [(x0, q0)]
        h, done = h0 * PROBE_STEP, 0.0
        while done < reach and h >= h0 * (2.0**-TRACE_HALVINGS if done >= TRACE_MIN * h0 else PROBE_STEP):
            step = min(h, reach - done)
            x, q = nodes[-1]
            pred = q.copy()
            if len(nodes) > 1:  # secant through the last two members
                xp, qp = nodes[-2]
                pred = q + (q - qp) * (step / abs(x - xp))
            pred[joint] = x + sign * step
            corr, err = correct(robot, pred[None], world[None], joint, tol)
            if len(nodes) == 1 and not err[0] <= PROBE_ERROR * tol:  # (see PROBE_ERROR)
                break
            if (
                err[0] <= tol
                and weighted_joint_distance(robot, corr[0], pred) <= TRACE_JUMP
                and _bridged(robot, world, q, corr[0], joint, tol)
            ):
                nodes.append((x + sign * step, corr[0]))
                done += step
                h = min(2.0 * h, h0)
            else:
                h *= 0.5
        sides.append(nodes)
        back_home = weighted_joint_distance(robot, nodes[-1][1], q0) <= TRACE_JUMP * 1e-3
        if periodic and sign > 0 and done >= reach and back_home:
            closed = True
            break
    back = sides[1][:0:-1] if len(sides) > 1 else []
    ordered = back + sides[0]
    theta = np.array([x for x, _ in ordered])
    if theta[-1] - theta[0] < TRACE_MIN * h0:
        return None
    return theta, np.array([q for _, q in ordered]), closed


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
        if branch is None:  # every branch (NaN where there is none)
            each = [
                self.solve_rest(poses, theta, np.full(theta.shape, b, dtype=np.intp))
                if b in self.nodes
                else np.full((*theta.shape, self.robot.n_joints), np.nan)
                for b in range(self.n_branches)
            ]
            return np.stack(each, axis=-2)
        n, j = self.robot.n_joints, self.free_joint
        br = np.broadcast_to(branch, theta.shape).reshape(-1)
        x = np.asarray(theta, dtype=np.float64).reshape(-1)
        world = np.repeat(_world(self.robot, poses), theta.shape[1], axis=0)
        q = np.full((x.size, n), np.nan)
        for b in np.unique(br).tolist():
            rows = np.nonzero(br == b)[0]
            th, Q = self.nodes[b]
            xu = self._unwrapped(b, x[rows])
            q[rows] = np.stack([np.interp(xu, th, Q[:, i]) for i in range(n)], axis=-1)
            q[rows, j] = x[rows]
        ok = np.all(np.isfinite(q), axis=1) & np.isfinite(x)
        q[ok] = correct(self.robot, q[ok], world[ok], j, self.tol)[0]
        return q.reshape(*theta.shape, n)


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
    nothing."""
    out: dict[int, list[Family]] = {}
    iso_p: list[IntArray] = [np.zeros(0, dtype=np.intp)]
    iso_q: list[Array] = [np.zeros((0, robot.n_joints))]
    for j in np.unique(joint).tolist():
        spans: list[tuple[int, int, float, float]] = []
        traced = Traced(robot, j, {}, tol)
        ks = np.nonzero(joint == j)[0]
        for i in np.unique(pose[ks]).tolist():
            left = q[ks[pose[ks] == i]]
            while left.shape[0]:
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
                th, Q, closed = stretch
                spans += _pieces(i, traced.add(th, Q), th, closed, traced.periodic)
                if left.shape[0]:  # the other seeds on it are not traced again
                    mine = tuple(
                        Family(j, (lo, hi), traced, chain[i], b, members=certified_members)
                        for p, b, lo, hi in spans
                        if p == i
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
