"""NumPy references of compiled engine steps (they were the engine's NumPy twins; the tests compare the two):
the wrap/limits/dedupe pass (``sweepik.engine.dedupe.finish``), the near pairs, the Newton polish, one side of a
traced continuum."""

from __future__ import annotations

import copy

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import correct
from sweepik.engine.dedupe import duplicate_tolerance
from sweepik.engine.settings import (
    BACKTRACK,
    ITERATIONS,
    PINV_RCOND,
    PINV_WIDEN,
    PROBE_ERROR,
    PROBE_STEP,
    TRACE_HALVINGS,
    TRACE_JUMP,
    TRACE_MIN,
)
from sweepik.model import kinematics
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.robot import Robot
from sweepik.reductions.base import Reduction
from sweepik.results import joint_distance, weighted_joint_distance

Array = NDArray[np.float64]


def numpy_reduction(red: Reduction) -> Reduction:
    """A copy of ``red`` without its compiled kernels: the engine then calls its NumPy ``residual`` back from the
    search (``sweepik.engine.callback``) and works out its configurations and families' members in NumPy, as for a
    reduction written in NumPy."""
    out = copy.copy(red)
    out.kernel = None
    return out


def finish(
    robot: Robot, pose_idx: NDArray[np.intp], q: Array, err: Array
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """``dedupe.finish`` in NumPy: ``(wrapped q, inside, keep)``."""
    w, inside = robot.wrapped_within_limits(q)
    score = np.where(inside, err, err + robot.length_scale)
    return w, inside, _dedupe(robot, pose_idx, w, score)


def near_pairs(
    robot: Robot, pose_idx: NDArray[np.intp], w: Array, keep: NDArray[np.bool_], reach: Array
) -> NDArray[np.intp]:
    """``near_pairs`` in NumPy (the reference): the pairs of each pose, compared joint by joint."""
    kept = np.nonzero(keep)[0]
    order = kept[np.argsort(pose_idx[kept], kind="stable")]
    p = pose_idx[order]
    pairs = []
    for d in range(1, order.size):  # (a pose's rows are adjacent in ``order``)
        same = np.nonzero(p[d:] == p[:-d])[0]
        if same.size == 0:
            break
        a, b = order[same], order[same + d]
        close = np.all(joint_distance(robot, w[a], w[b]) <= reach, axis=-1)
        pairs.append(np.sort(np.stack([a[close], b[close]], axis=1), axis=1))
    out = np.concatenate(pairs) if pairs else np.zeros((0, 2), dtype=np.intp)
    return out[np.lexsort((out[:, 1], out[:, 0]))].astype(np.intp)


def _dedupe(robot: Robot, pose_idx: NDArray[np.intp], q: Array, err: Array) -> NDArray[np.bool_]:
    """Keep-mask over candidates: per pose, drop any candidate equal (modulo 2 pi) to a better one, ties going to
    the earlier candidate (the reference of the compiled ``_dedupe_compiled``: every pair of a pose compared).

    Poses with at most ``_SMALL_GROUP`` candidates (almost all) are compared together, padded to that size; a pose
    with more (a numerical continuum) on its own, a block of rows at a time so that memory stays bounded.
    """
    K, n = q.shape
    keep = np.ones(K, dtype=bool)
    if K == 0:
        return keep
    tol = duplicate_tolerance(robot)
    order = np.argsort(pose_idx, kind="stable")
    starts = np.concatenate([[0], np.flatnonzero(np.diff(pose_idx[order])) + 1])
    sizes = np.diff(np.concatenate([starts, [K]]))
    small = np.nonzero((sizes > 1) & (sizes <= _SMALL_GROUP))[0]
    if small.size:
        # (G, m) candidate indices, padded with -1
        col = np.arange(_SMALL_GROUP)
        idx = np.where(col < sizes[small, None], order[np.minimum(starts[small, None] + col, K - 1)], -1)
        keep[idx[idx >= 0]] = _keep_pairwise(robot, q, err, idx, idx, tol)[idx >= 0]
    for g in np.nonzero(sizes > _SMALL_GROUP)[0]:
        members = order[starts[g] : starts[g] + sizes[g]]
        rows = max(1, _BLOCK_ELEMENTS // (members.size * n))
        for b in range(0, members.size, rows):
            keep[members[b : b + rows]] = _keep_pairwise(
                robot, q, err, members[None, b : b + rows], members[None], tol
            )[0]
    return keep


def _keep_pairwise(robot: Robot, q: Array, err: Array, rows: NDArray[np.intp], cols: NDArray[np.intp], tol: Array):
    """``(G, r)``: candidate ``rows[g, i]`` has no better equal among ``cols[g]`` (index -1: padding, never equal)."""
    d = joint_distance(robot, q[rows][:, :, None, :], q[cols][:, None, :, :])
    same = (
        np.all(d <= tol, axis=-1)
        & (rows[:, :, None] >= 0)
        & (cols[:, None, :] >= 0)
        & (rows[:, :, None] != cols[:, None, :])
    )
    er, ec = err[rows][:, :, None], err[cols][:, None, :]
    better = (ec < er) | ((ec == er) & (cols[:, None, :] < rows[:, :, None]))
    return ~np.any(same & better, axis=-1)


#: Poses with at most this many candidates are compared together in ``_dedupe`` (padded arrays).
_SMALL_GROUP = 32
#: Elements (rows x candidates x joints) of one block of a large pose's comparison in ``_dedupe``.
_BLOCK_ELEMENTS = 1 << 22


def polished(
    robot: Robot,
    q: Array,
    target: Array,
    weight: float,
    iterations: int = ITERATIONS,
    fixed: NDArray[np.bool_] | None = None,
    floor: float = 0.0,
) -> tuple[Array, Array]:
    """``polish.polished`` in NumPy: the same damped Newton steps, vectorised over the configurations."""
    q = q.copy()
    err = geodesic_errors(robot, q, target, weight)
    scale = np.array([1.0, 1.0, 1.0, weight, weight, weight])
    active = np.arange(q.shape[0])
    for _ in range(iterations):
        qa, ta = q[active], target[active]
        T, J = pose_and_jacobian(robot, qa)
        dp = ta[:, :3, 3] - T[:, :3, 3]
        dR = ta[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2)
        w = 0.5 * np.stack([dR[:, 2, 1] - dR[:, 1, 2], dR[:, 0, 2] - dR[:, 2, 0], dR[:, 1, 0] - dR[:, 0, 1]], -1)
        e = np.concatenate([dp, w], axis=-1) * scale
        Js = J * scale[:, None]
        if fixed is not None:
            Js = np.where(fixed[active][:, None, :], 0.0, Js)
        improved = np.zeros(active.size, dtype=bool)
        todo = np.arange(active.size)
        for widen in PINV_WIDEN:
            # pseudo-inverse per candidate: singular Jacobians (rank-deficient arms poses) stay bounded
            step = np.einsum("kij,kj->ki", np.linalg.pinv(Js, rcond=PINV_RCOND * widen), e)
            if fixed is not None:  # (a held joint's zero column gives a step of rounding size: none at all)
                step = np.where(fixed[active], 0.0, step)
            for _ in range(BACKTRACK + 1):
                q_new = qa[todo] + step[todo]
                err_new = geodesic_errors(robot, q_new, ta[todo], weight)
                better = np.isfinite(err_new) & (err_new < err[active[todo]])
                rows = active[todo[better]]
                q[rows], err[rows] = q_new[better], err_new[better]
                improved[todo[better]] = True
                todo = todo[~better]
                if todo.size == 0:
                    break
                step[todo] *= 0.5
            if todo.size == 0:
                break
        active = active[improved & (err[active] > floor)]
        if active.size == 0:
            break
    return q, err


def _pose(robot: Robot, q: Array) -> Array:
    return kinematics.chain_frames(robot, q)[:, -1] @ robot.T_flange_tool


def geodesic_errors(robot: Robot, q: Array, target: Array, weight: float) -> Array:
    return pose_error_geodesic(_pose(robot, q), target, weight)


def pose_and_jacobian(robot: Robot, q: Array) -> tuple[Array, Array]:
    return _pose(robot, q), kinematics.geometric_jacobian(robot, q)


def trace_side(
    robot: Robot, world: Array, x0: float, q0: Array, joint: int, sign: float, reach: float, h0: float, tol: float
) -> tuple[Array, Array, float]:
    """The members of one side of the continuum through ``q0`` (``sign``: the way ``joint`` goes), ``reach`` far at
    most, from the seed on: ``(joint values (M,), members (M, n), distance gone)``. Each step predicts the next member
    by the secant through the last two, corrects it with the joint held, and keeps it when it solves the pose, lies
    near its prediction (``TRACE_JUMP``) and the member halfway solves the pose too (``_bridged``); a failed step
    is halved (below the first step's ``PROBE_STEP`` only once the trace has gone ``TRACE_MIN`` or that first step
    reached the pose). The reference of the compiled ``continuation._side``."""
    nodes: list[tuple[float, Array]] = [(x0, q0)]
    h, done, on = h0 * PROBE_STEP, 0.0, False  # (on: the first step reached the pose, so steps halve below it)
    while done < reach and h >= h0 * (2.0**-TRACE_HALVINGS if on or done >= TRACE_MIN * h0 else PROBE_STEP):
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
        on = True
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
    return np.array([x for x, _ in nodes]), np.array([q for _, q in nodes]), done


def _bridged(robot: Robot, world: Array, a: Array, b: Array, joint: int, tol: float) -> bool:
    """The member halfway between members ``a`` and ``b`` (the joint's midpoint, the others interpolated and corrected
    as :class:`Traced` does) solves the pose: a step of the trace may not leap over a gap in the solution set (a
    KR 6 pose whose wrist centre sits on axis 1 at full stretch holds stretches of a continuum along joint 1 with
    gaps between them, where the interpolated members missed the pose by 6e-5 of the arm's size)."""
    _, err = correct(robot, (0.5 * (a + b))[None], world[None], joint, tol)
    return bool(err[0] <= tol)
