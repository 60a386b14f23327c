"""Certified configurations made final: revolute values wrapped into the limits, the limit check, duplicates dropped.

Compiled (one pass over the candidates, no per-call array overhead; the tests hold it against a NumPy reference,
``tests/oracles/numpy_engine.py``):

1. **wrap**: each revolute value into (-pi, pi], then moved by +-2 pi where that brings it inside its limits (the
   shift only when some revolute limit lies beyond +-pi), as :meth:`Robot.wrap`;
2. **inside**: every joint within its limits with the robot's tolerance, as :meth:`Robot.within_limits`;
3. **duplicates**: per pose, a candidate is dropped when another one of the same pose equals it (every revolute
   joint within ``DEDUPE_ANGLE`` modulo 2 pi, every prismatic one within ``DEDUPE_LENGTH_REL`` x the length scale)
   and is better: a smaller error, where a candidate outside the limits counts one length scale worse (so of two
   twins the one inside the limits is kept), ties going to the earlier candidate.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from numba import boolean, float64, int64
from numpy.typing import NDArray

from sweepik._jit import inlined, internal
from sweepik.engine import parallel
from sweepik.engine.settings import DEDUPE_ANGLE, DEDUPE_LENGTH_REL, POLISH_BELOW_REL, POLISH_SINGULAR_REL
from sweepik.reductions.kernels import lazy_njit
from sweepik.results import joint_distance
from sweepik.subproblems.trig import wrap_pi

if TYPE_CHECKING:
    from sweepik.model.robot import Robot

Array = NDArray[np.float64]

#: ``settings.POLISH_SINGULAR_REL`` over ``POLISH_BELOW_REL``: ``_settle`` takes the latter, absolute.
_SINGULAR_OVER_BELOW = POLISH_SINGULAR_REL / POLISH_BELOW_REL

__all__ = [
    "finish",
    "settle",
    "wrap_inside",
    "limit_args",
    "merged_multiplicity",
    "near_pairs",
    "duplicate_tolerance",
    "DEDUPE_ANGLE",
    "DEDUPE_LENGTH_REL",
]

#: A pose with more candidates than this (a numerical continuum) is deduplicated by buckets, not pair by pair.
_LARGE_GROUP = 64
#: ``settle`` runs on several threads from this many candidates on (fewer: a thread hand-off costs more).
_PARALLEL_ROWS = 4096


@lru_cache(maxsize=64)
def duplicate_tolerance(robot: Robot) -> Array:
    """Per joint, how close two solutions are to be the same (``DEDUPE_ANGLE``, ``DEDUPE_LENGTH_REL``; cached per
    robot: not to be written)."""
    return np.where(robot.is_revolute, DEDUPE_ANGLE, DEDUPE_LENGTH_REL * robot.length_scale)


@lru_cache(maxsize=64)
def limit_args(robot: Robot) -> tuple[NDArray[np.bool_], Array, Array, Array, bool]:
    """The robot's limits as the compiled ``wrap_inside_row`` takes them: ``(is_revolute, lower, upper, limit_tol,
    limits beyond pi)``, writable copies (the compiled signatures take writable arrays; nothing writes them), kept
    per robot (robots are values: equal robots share them)."""
    return (
        np.array(robot.is_revolute),
        np.array(robot.lower),
        np.array(robot.upper),
        np.array(robot.limit_tol),
        bool(robot._limits_beyond_pi),
    )


def wrap_inside(robot: Robot, q: Array) -> tuple[Array, NDArray[np.bool_]]:
    """``(wrapped q, inside)``: steps 1 and 2 of the module docstring."""
    w = np.array(q, dtype=np.float64, order="C")
    inside = np.empty(q.shape[0], dtype=np.bool_)
    _wrap_inside(w, *limit_args(robot), inside)
    return w, inside


def inside_limits(robot: Robot, q: Array) -> NDArray[np.bool_]:
    """``robot.within_limits(q)`` of configurations ``q (..., n)``, the same values in one compiled pass
    (``wrap_inside``: ~1.4 us for a few where ``Robot.within_limits``' NumPy steps take ~15)."""
    return wrap_inside(robot, q.reshape(-1, q.shape[-1]))[1].reshape(q.shape[:-1])


def finish(
    robot: Robot,
    pose_idx: NDArray[np.intp],
    q: Array,
    err: Array,
    wrapped: tuple[Array, NDArray[np.bool_]] | None = None,
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """``(wrapped q, inside, keep)`` for candidates ``q (K, n)`` of poses ``pose_idx (K,)`` with errors ``err (K,)``
    (see the module docstring); ``keep`` marks the candidates that are not a duplicate of a better one.
    ``wrapped``: ``wrap_inside(robot, q)`` when the caller has it already."""
    w, inside = wrap_inside(robot, q) if wrapped is None else wrapped
    score = np.where(inside, err, err + robot.length_scale)
    keep = np.empty(q.shape[0], dtype=np.bool_)
    _dedupe_compiled(pose_idx.astype(np.int64), w, score, limit_args(robot)[0], duplicate_tolerance(robot), keep)
    return w, inside, keep


def settle(
    robot: Robot,
    q: Array,
    err_geo: Array,
    err_paper: Array,
    pose_idx: NDArray[np.intp],
    mult: NDArray[np.intp],
    n_poses: int,
    thresholds: tuple[float, ...],
    reach: Array,
) -> tuple[NDArray[np.bool_], NDArray[np.intp], Array, NDArray[np.bool_], NDArray[np.bool_]] | None:
    """The solver's steps from candidates to final ones in one compiled pass, for the poses (of ``n_poses``) where
    none of its rarer steps is due: ``(due, rows, w, inside, keep)``. ``due (n_poses,)`` marks the poses left to the
    solver's steps: a candidate is due a polish (``err_geo`` at most ``thresholds[0]``, ``thresholds[4]`` for a
    multiple root's (``mult`` 2 or more), and up to ``POLISH_SINGULAR_REL`` for a simple root's, whose configuration
    the solver's steps polish if it is nearly singular; and above ``thresholds[1]``, or ``err_paper`` above
    ``thresholds[2]``), or
    a certified one lies outside the limits by at most ``reach`` (per joint: the solver tries it at the limit). Of
    the other poses, ``rows`` are the certified candidates (finite, ``err_geo`` within ``thresholds[3]``), in order,
    with ``finish``'s wrapped configurations ``w``, limit check and duplicate mask: the values the solver's NumPy
    steps give."""
    K = q.shape[0]
    pose = pose_idx.astype(np.int64)
    # parts of whole poses for the threads: a batch's candidates are mostly in pose order (a closed form's always)
    nt = parallel.threads() if K >= _PARALLEL_ROWS else 1
    if nt > 1 and bool(np.all(pose[1:] >= pose[:-1])):
        m = nt * parallel.PARTS_PER_THREAD
        cuts = np.searchsorted(pose, pose[(np.arange(1, m) * K) // m])
        parts = np.unique(np.concatenate([[0], cuts, [K]])).astype(np.int64)
    else:
        parts = np.array([0, K], dtype=np.int64)
    counts = np.zeros(parts.size - 1, dtype=np.int64)
    due = np.zeros(n_poses, dtype=np.bool_)
    rows = np.empty(K, dtype=np.int64)
    w = np.empty((K, robot.n_joints))
    score = np.empty(K)
    inside = np.empty(K, dtype=np.bool_)
    keep = np.empty(K, dtype=np.bool_)
    rev, lower, upper, ltol, beyond = limit_args(robot)
    parallel.run(
        _settle,
        parts.size - 1,
        2,
        np.ascontiguousarray(q, dtype=np.float64),
        np.ascontiguousarray(err_geo, dtype=np.float64),
        np.ascontiguousarray(err_paper, dtype=np.float64),
        pose,
        np.require(mult, np.int64, ["C", "W"]),  # (a writable copy where it is read-only: the signature's)
        np.array(thresholds, dtype=np.float64),
        rev,
        lower,
        upper,
        ltol,
        beyond,
        reach,
        duplicate_tolerance(robot),
        float(robot.length_scale),
        due,
        rows,
        w,
        score,
        inside,
        keep,
        parts,
        counts,
    )
    if counts.size == 1:
        c = int(counts[0])
        return due, rows[:c].astype(np.intp), w[:c], inside[:c], keep[:c]
    sel = np.concatenate([np.arange(a, a + c) for a, c in zip(parts[:-1], counts, strict=True)])
    return due, rows[sel].astype(np.intp), w[sel], inside[sel], keep[sel]


def merged_multiplicity(
    robot: Robot, pose_idx: NDArray[np.intp], w: Array, keep: NDArray[np.bool_], mult: NDArray[np.intp]
) -> NDArray[np.intp]:
    """``mult`` of the candidates ``w (K, n)`` (wrapped, as ``finish`` gives them) with each kept one's raised by
    the multiplicities of the dropped ones equal to it (step 3's equality): where branches of a closed form meet,
    the solution they share is a multiple root. The dropped candidates are few (singular poses): compared in
    NumPy."""
    out = np.array(mult, dtype=np.intp)
    tol = duplicate_tolerance(robot)
    kept = np.nonzero(keep)[0]
    for d in np.nonzero(~keep)[0]:
        k = kept[pose_idx[kept] == pose_idx[d]]
        same = k[np.all(joint_distance(robot, w[k], w[d]) <= tol, axis=-1)]
        if same.size:
            out[same[0]] += mult[d]
    return out


def near_pairs(
    robot: Robot, pose_idx: NDArray[np.intp], w: Array, keep: NDArray[np.bool_], reach: Array
) -> NDArray[np.intp]:
    """``(P, 2)`` pairs of kept candidates of one pose (``keep``) whose every joint is within ``reach (n,)`` of the
    other's (revolute ones modulo 2 pi), in order of their first row: compiled, one pass over each pose's pairs."""
    K = w.shape[0]
    out = np.empty((max(K, 1) * 4, 2), dtype=np.int64)
    count = np.zeros(1, dtype=np.int64)
    w = np.ascontiguousarray(w, dtype=np.float64)
    pose = pose_idx.astype(np.int64)
    _near_compiled(pose, w, keep, limit_args(robot)[0], reach, out, count)
    if count[0] > out.shape[0]:  # (more than the buffer holds, a continuum's many candidates: again, all of them)
        out = np.empty((int(count[0]), 2), dtype=np.int64)
        count[0] = 0
        _near_compiled(pose, w, keep, limit_args(robot)[0], reach, out, count)
    pairs = out[: count[0]].astype(np.intp)
    return pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))] if pairs.shape[0] > 1 else pairs


@lazy_njit((float64[:, ::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean, boolean[::1]), cache=True)
def _wrap_inside(q, rev, lower, upper, ltol, beyond, inside):  # pragma: no cover
    for k in range(q.shape[0]):
        inside[k] = wrap_inside_row(q[k], rev, lower, upper, ltol, beyond)


@inlined
def wrap_inside_row(q, rev, lower, upper, ltol, beyond):  # pragma: no cover
    """Steps 1 and 2 for one configuration ``q (n,)``: wrapped in place; whether it is inside the limits."""
    two_pi = 2.0 * math.pi
    ok = True
    for j in range(q.shape[0]):
        x = q[j]
        if rev[j] and math.isfinite(x):
            x = wrap_pi(x)
            if beyond and (x < lower[j] - ltol[j] or x > upper[j] + ltol[j]):
                # (the lowest value not below the lower limit, as ``Robot.wrap``: limits of any number of turns)
                c = x + two_pi * math.ceil(((lower[j] - ltol[j]) - x) / two_pi)
                if lower[j] - ltol[j] <= c <= upper[j] + ltol[j]:
                    x = c
            q[j] = x
        if not (lower[j] - ltol[j] <= x <= upper[j] + ltol[j]):
            ok = False
    return ok


@internal
def _group_order(pose):  # pragma: no cover
    """The candidates ordered by pose, keeping their order within a pose: a stable sort of ``pose``, counting
    the candidates of each pose (no compiled np.argsort: it adds seconds to the first compilation)."""
    K = pose.shape[0]
    order = np.empty(K, dtype=np.int64)
    if K == 0:
        return order
    lo, hi = pose[0], pose[0]
    for k in range(K):
        lo = pose[k] if pose[k] < lo else lo
        hi = pose[k] if pose[k] > hi else hi
    start = np.empty(hi - lo + 1, dtype=np.int64)
    for g in range(hi - lo + 1):
        start[g] = 0
    for k in range(K):
        start[pose[k] - lo] += 1
    total = 0
    for g in range(hi - lo + 1):
        total, start[g] = total + start[g], total
    for k in range(K):
        g = pose[k] - lo
        order[start[g]] = k
        start[g] += 1
    return order


@inlined
def _group_stop(pose, order, start):  # pragma: no cover
    """The end of the pose's group that starts at ``start`` in ``_group_order``'s ``order``."""
    stop = start + 1
    while stop < order.shape[0] and pose[order[stop]] == pose[order[start]]:
        stop += 1
    return stop


@lazy_njit(
    (int64[::1], float64[:, ::1], boolean[::1], boolean[::1], float64[::1], int64[:, ::1], int64[::1]), cache=True
)
def _near_compiled(pose, w, keep, rev, reach, out, count):  # pragma: no cover
    """``near_pairs``: the pairs into ``out`` (their number into ``count``, counted past the buffer too)."""
    K = w.shape[0]
    order = _group_order(pose)
    c = 0
    start = 0
    while start < K:
        stop = _group_stop(pose, order, start)
        for x in range(start, stop):
            a = order[x]
            if not keep[a]:
                continue
            for y in range(x + 1, stop):
                b = order[y]
                if not keep[b]:
                    continue
                if _rows_within(w, a, b, rev, reach):
                    if c < out.shape[0]:
                        out[c, 0], out[c, 1] = min(a, b), max(a, b)
                    c += 1
        start = stop
    count[0] = c


@lazy_njit(
    (int64[::1], float64[:, ::1], float64[::1], boolean[::1], float64[::1], boolean[::1]), cache=True, nogil=True
)
def _dedupe_compiled(pose, q, score, rev, tol, keep):  # pragma: no cover
    _dedupe_rows(pose, q, score, rev, tol, keep)


@inlined
def _rows_within(q, a, b, rev, tol):  # pragma: no cover
    """Every joint of rows ``a`` and ``b`` of ``q`` within ``tol`` (per joint) of the other's, revolute ones modulo
    2 pi."""
    two_pi = 2.0 * math.pi
    for j in range(q.shape[1]):
        d = q[a, j] - q[b, j]
        if rev[j]:
            # (clearly apart modulo 2 pi: the wrap, a costly float modulo, would not change that)
            if 2.0 * tol[j] < abs(d) < two_pi - 2.0 * tol[j]:
                return False
            d = wrap_pi(d)
        if not abs(d) <= tol[j]:
            return False
    return True


@internal
def _dedupe_rows(pose, q, score, rev, tol, keep):  # pragma: no cover
    """Step 3 (``keep``) for candidates ``q`` (wrapped) of poses ``pose`` with scores ``score``."""
    K = q.shape[0]
    for k in range(K):
        keep[k] = True
    order = _group_order(pose)
    start = 0
    while start < K:
        stop = _group_stop(pose, order, start)
        if stop - start > _LARGE_GROUP:
            _dedupe_bucketed(q, score, rev, tol, order[start:stop], keep)
            start = stop
            continue
        for a in range(start, stop):
            i = order[a]
            for b in range(start, stop):
                m = order[b]
                if b == a or not (score[m] < score[i] or (score[m] == score[i] and m < i)):
                    continue
                if _rows_within(q, i, m, rev, tol):
                    keep[i] = False
                    break
        start = stop


@inlined
def _drop_worse(q, score, rev, tol, a, b, keep):  # pragma: no cover
    """Of rows ``a`` and ``b`` when equal (``_rows_within``), the worse one dropped (a tie: the later row)."""
    if _rows_within(q, a, b, rev, tol):
        if score[b] < score[a] or (score[b] == score[a] and b < a):
            keep[a] = False
        else:
            keep[b] = False


@internal
def _bucket_rows(q, rev, tol, rows, j, key, bucket):  # pragma: no cover
    """Rows ``rows`` of ``q`` in ``rows.shape[0]`` buckets along joint ``j`` (its value modulo 2 pi for a revolute
    one, into ``key``), each at least the joint's tolerance wide (into ``bucket``); returns the number of pairs
    the buckets leave to compare (same or neighbouring bucket, the first and last for a revolute joint)."""
    m = rows.shape[0]
    lo, hi = math.inf, -math.inf
    for x in range(m):
        key[x] = wrap_pi(q[rows[x], j]) if rev[j] else q[rows[x], j]
        lo, hi = min(lo, key[x]), max(hi, key[x])
    width = max(tol[j] * (1.0 + 1e-9), (hi - lo) / m)
    count = np.zeros(m, dtype=np.int64)
    for x in range(m):
        bucket[x] = min(int((key[x] - lo) / width), m - 1)
        count[bucket[x]] += 1
    pairs = 0
    for b in range(m):
        pairs += count[b] * count[b] + (count[b] * count[b + 1] if b + 1 < m else 0)
    if rev[j]:
        pairs += count[0] * (count[m - 1] + count[m - 2])
    return pairs


@internal
def _dedupe_bucketed(q, score, rev, tol, rows, keep):  # pragma: no cover
    """Step 3 for one pose's many candidates ``rows`` (a numerical continuum's: thousands), in about linear time:
    the rows put in as many buckets along the joint whose buckets leave fewest pairs (``_bucket_rows``), so that
    equal rows share a bucket or lie in neighbouring ones (the first and last ones too for a revolute joint);
    only those pairs compared."""
    m = rows.shape[0]
    key = np.empty(m)
    bucket = np.empty(m, dtype=np.int64)
    best, fewest = 0, -1
    for j in range(q.shape[1]):
        pairs = _bucket_rows(q, rev, tol, rows, j, key, bucket)
        if fewest < 0 or pairs < fewest:
            best, fewest = j, pairs
    _bucket_rows(q, rev, tol, rows, best, key, bucket)
    first = np.zeros(m + 1, dtype=np.int64)
    for x in range(m):
        first[bucket[x] + 1] += 1
    for b in range(m):
        first[b + 1] += first[b]
    fill = first[:m].copy()
    sorted_rows = np.empty(m, dtype=np.int64)
    for x in range(m):
        sorted_rows[fill[bucket[x]]] = rows[x]
        fill[bucket[x]] += 1
    last = bucket.max()
    for b in range(last + 1):
        for x in range(first[b], first[b + 1]):
            a = sorted_rows[x]
            for y in range(x + 1, first[b + 1]):
                _drop_worse(q, score, rev, tol, a, sorted_rows[y], keep)
            if b < last:
                for y in range(first[b + 1], first[b + 2]):
                    _drop_worse(q, score, rev, tol, a, sorted_rows[y], keep)
    if rev[best] and last > 1:  # (a row just below pi may lie one bucket short of the last)
        for x in range(first[0], first[1]):
            for y in range(first[last - 1], first[last + 1]):
                _drop_worse(q, score, rev, tol, sorted_rows[x], sorted_rows[y], keep)


#: ``_settle``'s arguments (``one_pose`` calls it by its address too).
_SETTLE_SIG = (
    (float64[:, ::1], float64[::1], float64[::1], int64[::1], int64[::1], float64[::1], boolean[::1])
    + (float64[::1],)
    + (float64[::1], float64[::1], boolean, float64[::1], float64[::1], float64, boolean[::1], int64[::1])
    + (float64[:, ::1], float64[::1], boolean[::1], boolean[::1], int64[::1], int64[::1], int64, int64)
)


@lazy_njit(_SETTLE_SIG, cache=True, nogil=True)
def _settle(
    q, eg, ep, pose, mult, thr, rev, lower, upper, ltol, beyond, reach, tol, scale,
    due, idx, w, score, inside, keep, parts, counts, start, stop,
):  # pragma: no cover  # fmt: skip
    """``settle``'s kernel for parts ``start .. stop - 1`` (rows ``parts[p] .. parts[p + 1] - 1``; a pose's rows
    lie in one part): marks the poses due the solver's rarer steps (``due``, one entry per pose, False on entry);
    of the other poses, the certified rows (``idx``, their wrapped configurations ``w``, ``score``, ``inside``,
    ``keep``), written from the part's first row on, ``counts[p]`` of them."""
    polish_below, polish_above, polish_paper_above, accept, polish_multiple = thr[0], thr[1], thr[2], thr[3], thr[4]
    n = q.shape[1]
    for part in range(start, stop):
        lo, hi = parts[part], parts[part + 1]
        c = lo
        for k in range(lo, hi):
            finite = True
            for j in range(n):
                if not math.isfinite(q[k, j]):
                    finite = False
                    break
            if not finite:
                continue
            e = eg[k]
            # (a simple root's candidate further than polish_below: the solver's steps polish it if its configuration
            # is nearly singular, ``settings.POLISH_SINGULAR_REL``)
            below = polish_multiple if mult[k] >= 2 else polish_below * _SINGULAR_OVER_BELOW
            if e <= below and (e > polish_above or ep[k] > polish_paper_above):
                due[pose[k]] = True  # a Newton polish (or, failing it, the fallback reduction)
                continue
            if not e <= accept:
                continue
            for j in range(n):
                w[c, j] = q[k, j]
            ok = wrap_inside_row(w[c], rev, lower, upper, ltol, beyond)
            if not ok:
                near = True  # within reach of the limits: tried at the limit
                for j in range(n):
                    over = max((lower[j] - ltol[j]) - w[c, j], (w[c, j] - upper[j]) - ltol[j])
                    if not over <= reach[j]:
                        near = False
                        break
                if near:
                    due[pose[k]] = True
                    continue
            idx[c], inside[c] = k, ok
            score[c] = e if ok else e + scale
            c += 1
        m = lo
        for a in range(lo, c):  # the rows of poses found due after them are dropped
            if due[pose[idx[a]]]:
                continue
            if m < a:
                idx[m], inside[m], score[m] = idx[a], inside[a], score[a]
                for j in range(n):
                    w[m, j] = w[a, j]
            m += 1
        _dedupe_rows(pose[idx[lo:m]], w[lo:m], score[lo:m], rev, tol, keep[lo:m])
        counts[part] = m - lo
