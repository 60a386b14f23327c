"""Settling a chunk's candidates step by step: the precise strategy's thresholds, the errors of configurations, the
snap of solutions just outside a limit onto it, the meeting branches of a closed form merged, close partners next
to folds (``partners``) added. The one compiled pass that does most of it is ``dedupe.settle``."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import certify
from sweepik.engine.dedupe import (
    duplicate_tolerance,
    finish,
    inside_limits,
    merged_multiplicity,
    near_pairs,
    wrap_inside,
)
from sweepik.engine.families import (
    MAX_ISOLATED_SOLUTIONS,
)
from sweepik.engine.partners import close_partners, nearly_singular, valley_bottoms
from sweepik.engine.polish import polish, polished
from sweepik.engine.settings import (
    ACCEPT_TOL_REL,
    MEET_ARC,
    MEET_ARC_STEPS,
    MEET_NEAR,
    MEET_PASSES,
    MEET_REL,
    MEET_ROUNDING_REL,
    MEET_STAY,
    POLISH_ABOVE_REL,
    POLISH_BELOW_REL,
    POLISH_MULTIPLE_REL,
    POLISH_PAPER_ABOVE_REL,
    SNAP_ITERATIONS,
    SNAP_REACH,
    VALLEY_ABOVE_REL,
)
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.results import joint_distance

Array = NDArray[np.float64]


def settle_bounds(robot: Robot) -> tuple[float, float, float, float, float, float]:
    """The precise strategy's thresholds, absolute (times the arm's length scale): polish below, polish above, polish
    above on the paper's J, acceptance, polish below for a multiple root's candidate, a valley's slope above
    (``POLISH_BELOW_REL`` ... ``ACCEPT_TOL_REL``, ``POLISH_MULTIPLE_REL``, ``VALLEY_ABOVE_REL``); the stepwise path
    and ``dedupe.settle`` take the same values (the last: the one-pose kernels and ``chunk._settled_rows``)."""
    ls = robot.length_scale
    return (
        POLISH_BELOW_REL * ls,
        POLISH_ABOVE_REL * ls,
        POLISH_PAPER_ABOVE_REL * ls,
        ACCEPT_TOL_REL * ls,
        POLISH_MULTIPLE_REL * ls,
        VALLEY_ABOVE_REL * ls,
    )


@lru_cache(maxsize=64)
def per_joint(robot: Robot, value: float) -> Array:
    """``value`` per joint: as it is for a revolute one (radians), times the length scale for a prismatic one. Cached
    (robots are values; the solver asks for the same ones on every chunk; the compiled kernels take it, writable, and
    do not write it)."""
    return np.where(robot.is_revolute, value, value * robot.length_scale)


def snap_reach(robot: Robot) -> Array:
    """``SNAP_REACH`` per joint."""
    return per_joint(robot, SNAP_REACH)


def snap_to_limits(
    robot: Robot, q: Array, err_geo: Array, err_paper: Array, poses: Array, pose_idx: NDArray[np.intp], weight: float
) -> tuple[Array, NDArray[np.bool_]]:
    """In place: certified configurations ``q (K, n)`` of poses ``poses[pose_idx]`` just outside the limits are
    clamped to them and polished with the clamped joints held; where that still certifies, it replaces them (with
    their errors). Returns ``wrap_inside(robot, q)`` of the result (what the deduplication starts from)."""
    w_all, inside = wrap_inside(robot, q)
    out = np.nonzero(~inside)[0]
    if out.size == 0:
        return w_all, inside
    w = w_all[out]
    over = np.maximum(robot.lower - robot.limit_tol - w, w - robot.upper - robot.limit_tol)
    near = np.all(over <= snap_reach(robot), axis=-1)
    k, w, over = out[near], w[near], over[near]
    if k.size == 0:
        return w_all, inside
    held = over > 0
    start = np.clip(w, robot.lower, robot.upper)
    target = poses[pose_idx[k]]
    moved = polish(robot, start, target, weight, SNAP_ITERATIONS, fixed=held)
    eg, ep = errors_of(robot, moved, target, weight)
    ok = (eg <= ACCEPT_TOL_REL * robot.length_scale) & inside_limits(robot, moved)
    k = k[ok]
    q[k], err_geo[k], err_paper[k] = moved[ok], eg[ok], ep[ok]
    if k.size:
        w_all[k], inside[k] = wrap_inside(robot, q[k])
    return w_all, inside


def meetings(
    robot: Robot,
    poses: Array,
    pose_idx: NDArray[np.intp],
    q: Array,
    err_geo: Array,
    err_paper: Array,
    inside: NDArray[np.bool_],
    keep: NDArray[np.bool_],
    mult: NDArray[np.intp],
    closed_form: bool,
) -> tuple[Array, NDArray[np.intp]]:
    """Solutions of a pose that are one root to the precision the pose fixes it, merged into one (in place of
    ``err_*``, ``inside`` and ``keep``). Returns ``(q, mult)`` (copies where changed).

    A closed form's branches that meet: one solution, a multiple root, whether the deduplication found them one
    (``keep``: the dropped copies' multiplicities added) or the closed form's rounding split them in two (their
    multiplicities added). A sweep's: two certified points of a flat valley next to the singular set (its polish
    stops anywhere along a curve that solves the pose to rounding: a Piper on its singular set gave five points
    1e-6 ... 1e-5 apart, each a double root), one double root (or the larger multiplicity of the two): copies of one
    root found from several samples or branches, not branches that meet."""
    if closed_form and not keep.all():
        mult = merged_multiplicity(robot, pose_idx, q, keep, mult)
    asked = keep
    if not closed_form:  # (not a pose with more than an arm has: a numerical continuum, reported once later)
        count = np.bincount(pose_idx[keep], minlength=int(pose_idx.max(initial=-1)) + 1)
        asked = keep & (count[pose_idx] <= MAX_ISOLATED_SOLUTIONS)
    pair = _meeting_pairs(robot, pose_idx, q, asked)
    if pair.size:
        q, mult = q.copy(), mult.copy()
    for _ in range(MEET_PASSES):  # (a merged pair's root moved: its pairs with the rest of a cluster asked again)
        if not (
            pair.size
            and _merge_meeting(robot, poses, pair, q, err_geo, err_paper, inside, keep, mult, pose_idx, closed_form)
        ):
            break
        pair = _meeting_pairs(robot, pose_idx, q, keep & asked)
    return q, mult


def _meeting_pairs(robot: Robot, pose_idx: NDArray[np.intp], w: Array, keep: NDArray[np.bool_]) -> NDArray[np.intp]:
    """``(P, 2)`` pairs of kept rows of one pose whose configurations ``w`` (wrapped) are within ``MEET_REL``."""
    return near_pairs(robot, pose_idx, w, keep, per_joint(robot, MEET_REL))


def _merge_meeting(
    robot: Robot,
    poses: Array,
    pair: NDArray[np.intp],
    w: Array,
    err_geo: Array,
    err_paper: Array,
    inside: NDArray[np.bool_],
    keep: NDArray[np.bool_],
    mult: NDArray[np.intp],
    pose_idx: NDArray[np.intp],
    summed: bool = True,
) -> bool:
    """In place: each pair of ``_meeting_pairs`` that is ``one_root`` becomes that root (its errors, its limit
    check, the pair's multiplicities summed; not ``summed``: the larger, at least 2), the second row dropped.
    Whether any pair was merged."""
    merged = False
    for a, b in pair.tolist():
        if not (keep[a] and keep[b]):
            continue
        root = one_root(robot, poses[pose_idx[a]], w[a], w[b], err_geo[a], err_geo[b])
        if root is not None and (root[3] or not (inside[a] or inside[b])):
            w[a], err_geo[a], err_paper[a], inside[a] = root
            mult[a] = mult[a] + mult[b] if summed else max(mult[a], mult[b], 2)
            keep[b] = False
            merged = True
    return merged


def one_root(
    robot: Robot, pose: Array, wa: Array, wb: Array, ea: float, eb: float
) -> tuple[Array, float, float, bool] | None:
    """The one root that two close certified solutions ``wa``, ``wb`` of ``pose (4, 4)`` (pose errors ``ea``,
    ``eb``) are to the precision the pose fixes it: their midpoint, polished, if it solves the pose as well as the
    better of them, or at rounding level (``POLISH_ABOVE_REL``), and the polish leaves it between them (or the
    midpoint itself solves the pose as well as they do: a flat valley); as
    ``(q, error_geodesic, error, within_limits)``. None: two roots (next to the singular set two roots this close
    keep apart: between them the pose error grows quadratically, far above theirs)."""
    weight = orientation_weight(robot.length_unit)
    d = wb - wa
    d = np.where(robot.is_revolute, np.mod(d + np.pi, 2.0 * np.pi) - np.pi, d)
    target = pose[None]
    # (polished: the pair's other joints carry rounding of their own, which moves the pose linearly)
    half = (wa + 0.5 * d)[None]
    moved = polish(robot, half, target, weight, SNAP_ITERATIONS)
    # (the polish may not carry the midpoint over to one of the pair: two distinct roots are not one)
    step = np.where(robot.is_revolute, np.mod(moved - half + np.pi, 2.0 * np.pi) - np.pi, moved - half)
    unit = per_joint(robot, 1.0)
    apart = float(np.max(np.abs(d) / unit))
    if np.max(np.abs(step[0]) / unit) > MEET_STAY * apart:
        # (or a flat valley, along which the polish drifts: the midpoint itself solves the pose as well as the pair,
        # or a curved one, on which points of the segment corrected with the joint that moves most held lie --
        # where between two roots the error rises quadratically)
        flat = max(2.0 * max(ea, eb), MEET_ROUNDING_REL * robot.length_scale)
        if errors_of(robot, half, target, weight)[0][0] > flat and not _on_one_arc(robot, pose, wa, d, flat):
            return None
    mid, mid_inside = wrap_inside(robot, moved)
    eg, ep = errors_of(robot, mid, target, weight)
    # (better than both, or at rounding level as they may be: ``POLISH_ABOVE_REL``; a pair farther apart than
    # ``MEET_NEAR``: no worse than twice the worse of them as far as a polish takes them -- a closed form's
    # values below ``POLISH_ABOVE_REL`` are not polished, and may miss the pose by as much as a valley between
    # two roots rises -- or than ``MEET_ROUNDING_REL``)
    best = max(min(ea, eb), POLISH_ABOVE_REL * robot.length_scale)
    if apart > MEET_NEAR:
        _, pair_err = polished(robot, np.stack([wa, wb]), np.repeat(target, 2, axis=0), weight, SNAP_ITERATIONS)
        worse = max(min(ea, pair_err[0]), min(eb, pair_err[1]))
        best = max(2.0 * worse, MEET_ROUNDING_REL * robot.length_scale)
    if eg[0] > best:
        return None
    return mid[0], float(eg[0]), float(ep[0]), bool(mid_inside[0])


def _on_one_arc(robot: Robot, pose: Array, wa: Array, d: Array, flat: float) -> bool:
    """The segment from ``wa`` to ``wa + d`` lies along an arc of solutions of ``pose``: its points at
    ``MEET_ARC`` of the way, each polished with the joint that moves most along it held, solve the pose to ``flat``
    and stay within ``MEET_STAY`` of the segment's length of it (a valley that curves: an AgileX Piper's pair 7e-6
    apart, their midpoint at 3e-13 of its size, the corrected points at 2e-15 like the pair)."""
    unit = per_joint(robot, 1.0)
    t = np.asarray(MEET_ARC)[:, None]
    start = wa[None] + t * d[None]
    held = np.zeros(start.shape, dtype=np.bool_)
    held[:, int(np.argmax(np.abs(d) / unit))] = True
    target = np.broadcast_to(pose, (t.size, 4, 4)).copy()
    moved, err = polished(robot, start, target, orientation_weight(robot.length_unit), MEET_ARC_STEPS, fixed=held)
    off = np.max(np.abs(moved - start) / unit) <= MEET_STAY * float(np.max(np.abs(d) / unit))
    return bool(off and np.all(err <= flat))


def next_to_folds(
    robot: Robot,
    poses: Array,
    pose_idx: NDArray[np.intp],
    q: Array,
    mult: NDArray[np.intp],
    err_geo: Array,
    err_paper: Array,
    rows: NDArray[np.intp],
    probed: NDArray[np.bool_],
) -> tuple[NDArray[np.intp], Array, NDArray[np.intp], Array, Array]:
    """Certified solutions next to a fold of the solution set (:mod:`.partners`): those of ``rows`` in a flat valley
    moved to its bottom (in place; never out of the limits, as the polish's drift), and a close partner on the far
    side of the fold of those ``probed`` marks (one entry a candidate: the polish gave them) added after the solution
    it was found from (a pose's rows stay together): the candidates ``(pose_idx, q, mult, err_geo, err_paper)``."""
    if rows.size:  # (only nearly singular ones: most are not)
        rows = rows[nearly_singular(robot, q[rows])]
    if rows.size == 0:
        return pose_idx, q, mult, err_geo, err_paper
    accept = ACCEPT_TOL_REL * robot.length_scale
    weight = orientation_weight(robot.length_unit)
    q_v, moved = valley_bottoms(robot, q[rows], poses[pose_idx[rows]], accept)
    if moved.any():
        moved &= inside_limits(robot, q_v) | ~inside_limits(robot, q[rows])
        m = rows[moved]
        q[m] = q_v[moved]
        err_geo[m], err_paper[m] = errors_of(robot, q[m], poses[pose_idx[m]], weight)
    rows = rows[probed[rows]]
    # each distinct one once, and none of a pose with more of them than an arm has solutions (a numerical continuum,
    # along which no partner is taken)
    distinct = rows[finish(robot, pose_idx[rows], q[rows], err_geo[rows])[2]]
    count = np.bincount(pose_idx[distinct], minlength=len(poses))
    distinct = distinct[count[pose_idx[distinct]] <= MAX_ISOLATED_SOLUTIONS]
    row, q_p, _ = close_partners(robot, q[distinct], poses[pose_idx[distinct]], accept)
    if row.size:  # (each once, and none its pose has already: found again, it would add to a multiplicity)
        new = _new_rows(robot, pose_idx, q, distinct[row], q_p)
        row, q_p = row[new], q_p[new]
    if row.size == 0:
        return pose_idx, q, mult, err_geo, err_paper
    src = distinct[row]
    eg_p, ep_p = errors_of(robot, q_p, poses[pose_idx[src]], weight)
    order = np.argsort(np.concatenate([np.arange(pose_idx.size), src]), kind="stable")
    return (
        np.concatenate([pose_idx, pose_idx[src]])[order],
        np.concatenate([q, q_p])[order],
        np.concatenate([mult, np.ones(src.size, dtype=mult.dtype)])[order],
        np.concatenate([err_geo, eg_p])[order],
        np.concatenate([err_paper, ep_p])[order],
    )


def _new_rows(
    robot: Robot, pose_idx: NDArray[np.intp], q: Array, src: NDArray[np.intp], q_new: Array
) -> NDArray[np.bool_]:
    """``(K,)``: the configurations ``q_new (K, n)`` of the poses of rows ``src`` that are neither one of their pose's
    rows of ``q`` nor an earlier one of ``q_new`` (within ``dedupe.duplicate_tolerance``)."""
    tol = duplicate_tolerance(robot)
    out = np.zeros(src.size, dtype=bool)
    for k in range(src.size):
        mine = pose_idx == pose_idx[src[k]]
        known = np.concatenate([q[mine], q_new[:k][out[:k] & (pose_idx[src[:k]] == pose_idx[src[k]])]])
        out[k] = not np.any(np.all(joint_distance(robot, known, q_new[k]) <= tol, axis=-1))
    return out


def errors_of(robot: Robot, q: Array, target: Array, weight: float) -> tuple[Array, Array]:
    """Geodesic error and the paper's J ``(K,)`` of configurations ``q (K, n)`` against ``target (K, 4, 4)``:
    compiled as certification computes them (``certify.pose_errors``)."""
    return certify.pose_errors(robot, q, target, weight)
