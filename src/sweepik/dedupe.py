"""Certified configurations made final: revolute values wrapped into the limits, the limit check, duplicates dropped.

One algorithm, two implementations (the NumPy reference, and the compiled one the solver uses when Numba is
present: no per-call array overhead, one pass over the candidates):

1. **wrap**: each revolute value into (-pi, pi], then moved by +-2 pi where that brings it inside its limits (the
   shift only when some revolute limit lies beyond +-pi), as :meth:`Robot.wrap`;
2. **inside**: every joint within its limits with the robot's tolerance, as :meth:`Robot.within_limits`;
3. **duplicates**: per pose, a candidate is dropped when another one of the same pose equals it (every revolute
   joint within ``DEDUPE_ANGLE`` modulo 2 pi, every prismatic one within ``DEDUPE_LENGTH_REL`` x the length scale)
   and is better: a smaller error, where a candidate outside the limits counts one length scale worse (so of two
   twins the one inside the limits is kept), ties going to the earlier candidate.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .fastsweep import AVAILABLE

if TYPE_CHECKING:
    from .robot import Robot

Array = NDArray[np.float64]

__all__ = ["finish", "wrap_inside", "DEDUPE_ANGLE", "DEDUPE_LENGTH_REL"]

#: Two solutions are the same when every revolute joint agrees within this (radians, modulo 2 pi) ...
DEDUPE_ANGLE = 1e-6
#: ... and every prismatic joint within this times the arm's length scale.
DEDUPE_LENGTH_REL = 1e-8


def _tolerance(robot: Robot) -> Array:
    return np.where(robot.is_revolute, DEDUPE_ANGLE, DEDUPE_LENGTH_REL * robot.length_scale)


def wrap_inside(robot: Robot, q: Array) -> tuple[Array, NDArray[np.bool_]]:
    """``(wrapped q, inside)``: steps 1 and 2 of the module docstring (compiled when Numba is present)."""
    if not (AVAILABLE and q.shape[0]):
        return robot.wrapped_within_limits(q)
    w = np.array(q, dtype=np.float64, order="C")
    inside = np.empty(q.shape[0], dtype=np.bool_)
    _wrap_inside(
        w,
        np.array(robot.is_revolute),
        np.array(robot.lower),
        np.array(robot.upper),
        np.array(robot.limit_tol),
        bool(robot._limits_beyond_pi),
        inside,
    )
    return w, inside


def finish(
    robot: Robot, pose_idx: NDArray[np.intp], q: Array, err: Array
) -> tuple[Array, NDArray[np.bool_], NDArray[np.bool_]]:
    """``(wrapped q, inside, keep)`` for candidates ``q (K, n)`` of poses ``pose_idx (K,)`` with errors ``err (K,)``
    (see the module docstring); ``keep`` marks the candidates that are not a duplicate of a better one."""
    w, inside = wrap_inside(robot, q)
    score = np.where(inside, err, err + robot.length_scale)
    if not (AVAILABLE and q.shape[0]):
        return w, inside, _dedupe(robot, pose_idx, w, score)
    keep = np.empty(q.shape[0], dtype=np.bool_)
    _dedupe_compiled(pose_idx.astype(np.int64), w, score, np.array(robot.is_revolute), _tolerance(robot), keep)
    return w, inside, keep


def _dedupe(robot: Robot, pose_idx: NDArray[np.intp], q: Array, err: Array) -> NDArray[np.bool_]:
    """Keep-mask over candidates: per pose, drop any candidate equal (modulo 2 pi) to a better one (the reference).

    Candidates are sorted by pose and by their joint values rounded to 10x the tolerance; equal ones are
    then at most ``_DEDUPE_WINDOW`` places apart, so each is compared with its next neighbours only.
    """
    K = q.shape[0]
    keep = np.ones(K, dtype=bool)
    if K == 0:
        return keep
    tol = _tolerance(robot)
    if K <= _DEDUPE_PAIRWISE:  # small sets (a single pose): all pairs at once, fewer array operations
        d = q[:, None, :] - q[None, :, :]
        d = np.where(robot.is_revolute, np.abs(np.pi - np.mod(np.pi - d, 2.0 * np.pi)), np.abs(d))
        same = np.all(d <= tol, axis=-1) & (pose_idx[:, None] == pose_idx[None, :])
        idx = np.arange(K)
        better = (err[None, :] < err[:, None]) | ((err[None, :] == err[:, None]) & (idx[None, :] < idx[:, None]))
        return ~np.any(same & better, axis=1)
    keys = np.round(q / (10.0 * tol))
    order = np.lexsort((*keys.T[::-1], pose_idx))
    ps, qs, es = pose_idx[order], q[order], err[order]
    drop = np.zeros(K, dtype=bool)
    ks = keys[order, 0]
    for w in range(1, min(_DEDUPE_WINDOW, K - 1) + 1):
        # sorted by (pose, rounded first joint, ...): once no pair w apart shares pose and first key
        # (within one rounding step), no pair further apart does
        if not np.any((ps[w:] == ps[:-w]) & (ks[w:] - ks[:-w] <= 1)):
            break
        d = qs[w:] - qs[:-w]
        d = np.where(robot.is_revolute, np.abs(np.pi - np.mod(np.pi - d, 2.0 * np.pi)), np.abs(d))
        same = (ps[w:] == ps[:-w]) & np.all(d <= tol, axis=-1)
        i = np.nonzero(same)[0]
        worse_later = es[i + w] >= es[i]
        drop[np.where(worse_later, i + w, i)] = True
    keep[order] = ~drop
    return keep


#: Candidates compared by ``_dedupe`` on each side in sorted order (duplicates of one solution are few).
_DEDUPE_WINDOW = 16
#: Up to this many candidates, ``_dedupe`` compares all pairs directly.
_DEDUPE_PAIRWISE = 48


if AVAILABLE:
    import math

    from numba import boolean, float64, int64

    from .reductions.kernels import lazy_njit

    @lazy_njit(
        (float64[:, ::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean, boolean[::1]), cache=True
    )
    def _wrap_inside(q, rev, lower, upper, ltol, beyond, inside):  # pragma: no cover
        K, n = q.shape
        two_pi = 2.0 * math.pi
        for k in range(K):
            ok = True
            for j in range(n):
                x = q[k, j]
                if rev[j] and math.isfinite(x):
                    x = math.pi - ((math.pi - x) % two_pi)
                    if beyond and (x < lower[j] - ltol[j] or x > upper[j] + ltol[j]):
                        for shift in (two_pi, -two_pi):
                            c = x + shift
                            if lower[j] - ltol[j] <= c <= upper[j] + ltol[j]:
                                x = c
                                break
                    q[k, j] = x
                if not (lower[j] - ltol[j] <= x <= upper[j] + ltol[j]):
                    ok = False
            inside[k] = ok

    @lazy_njit((int64[::1], float64[:, ::1], float64[::1], boolean[::1], float64[::1], boolean[::1]), cache=True)
    def _dedupe_compiled(pose, q, score, rev, tol, keep):  # pragma: no cover
        K, n = q.shape
        two_pi = 2.0 * math.pi
        keep[:] = True
        order = np.argsort(pose, kind="mergesort")  # stable: within a pose, candidates keep their order
        start = 0
        while start < K:
            stop = start + 1
            while stop < K and pose[order[stop]] == pose[order[start]]:
                stop += 1
            for a in range(start, stop):
                i = order[a]
                for b in range(start, stop):
                    m = order[b]
                    if b == a or not (score[m] < score[i] or (score[m] == score[i] and m < i)):
                        continue
                    same = True
                    for j in range(n):
                        d = q[i, j] - q[m, j]
                        if rev[j]:
                            d = math.pi - ((math.pi - d) % two_pi)
                        if not abs(d) <= tol[j]:
                            same = False
                            break
                    if same:
                        keep[i] = False
                        break
            start = stop
