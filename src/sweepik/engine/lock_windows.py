"""The lock values at which a held arm is not the arm it is at other values (``held_pose``'s exceptions).

Holding joint ``k`` of a seven-joint arm turns the axes after it about its axis; the relations between an axis before
``k`` and one after it change with the value. At most values they are those of every other value, but near a few
they come close to holding (two axes nearly parallel, the neighbours of ``k`` nearly meeting: a near-structure, where
the automatic choice checks every plan and may join a companion) or hold exactly (another structure, another plan, or
none: two axes on one line). ``special_windows`` finds those values once per arm and joint:

1. a grid of one turn, ``NEAR_TOL / 4`` apart, flags each value where an axis before ``k`` and one after it are within
   twice ``NEAR_TOL`` of parallel (the sine of their angle changes at most as fast as the value), or the neighbours
   of ``k`` within twice ``NEAR_TOL`` (times the length scale) of meeting, unless the relation holds at every value
   (or, for the neighbours, nearly holds at every value by the same distance: ``SAME_DISTANCE_REL``);
2. at each flagged value the held arm's own checks (``structure.near_structure``, ``structure.structure_of``) decide:
   a near-structure or a structure other than at the reference value marks it (a held arm with a near-structure at
   every value, of joints on one side of ``k``, such as the Kinova Gen3's nearly spherical wrist: one that differs
   from it, or from the size it has there, ``held_joined``);
3. where an axis before ``k`` turns perpendicular to one after it (a blind spot of some plans), the plan the held
   arm chooses there (``plan_at``) must be the one of other values, else that value is marked;

and returns the marked values, widened by two grid steps, as windows ``(m, 2)`` (radians, within one turn).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.model.chain import Chain, rotation_about
from sweepik.model.robot import Robot
from sweepik.model.structure import (
    INTERSECT_TOL_REL,
    NEAR_TOL,
    PARALLEL_TOL,
    Structure,
    near_structure,
    structure_of,
)

__all__ = ["special_windows", "in_windows", "window_reference", "GRID_STEP", "REFERENCE_AT"]

Array = NDArray[np.float64]

#: The grid's step (radians): a quarter of the near-structure tolerance.
GRID_STEP = NEAR_TOL / 4.0
#: Neighbours of the held joint that nearly meet at every value where they are not parallel, at distances within this
#: fraction of one another, are one near-structure at every value and are not flagged (the Kinova Gen3 held at joint
#: 6: its axes 5 and 7 3.1e-4 of its size apart at every value; every value of the grid was checked, ~10 s).
SAME_DISTANCE_REL = 1e-3
#: A value marked for its plan alone (step 3) is taken within this of it.
EXACT_WINDOW = 1e-6
#: A window's reference value (``window_reference``) lies this fraction of its width from its start: off the special
#: value at its middle, where the held arm may be another arm.
REFERENCE_AT = 0.3


def _relations(structure: Structure) -> tuple[Any, ...]:
    return structure.pairs, structure.parallel, structure.spherical


def special_windows(
    robot: Robot, k: int, chain_at: Callable[[float], Chain], plan_at: Callable[[float], object], reference: float
) -> Array:
    """The windows ``(m, 2)`` of values of revolute joint ``k`` (one turn, ``[-pi, pi]``; an end at -inf or inf: the
    window goes round) where ``robot`` held at ``k`` is not the arm it is at ``reference`` (module docstring).
    ``chain_at(v)``: the held arm's chain at ``v``; ``plan_at(v)``: its plan there (anything comparable)."""
    ch = robot.chain
    H, pts = ch.H, ch.points
    n, hk, ok = ch.n_joints, ch.H[k], ch.points[k]
    scale = robot.length_scale
    grid = np.arange(-math.pi, math.pi, GRID_STEP)
    R = rotation_about(hk, grid)  # (N, 3, 3)
    after = list(range(k + 1, n))
    Ha = np.einsum("nij,mj->nmi", R, H[after])  # (N, len(after), 3)
    flag = np.zeros(grid.size, dtype=bool)
    for i in range(k):
        sines = np.linalg.norm(np.cross(H[i], Ha), axis=-1)  # (N, len(after))
        for col in range(len(after)):
            if sines[:, col].max() >= PARALLEL_TOL:  # (parallel at every value: the same structure at all)
                flag |= sines[:, col] < 2.0 * NEAR_TOL
    a, b = k - 1, k + 1
    rev = robot.is_revolute
    if a >= 0 and b < n and rev[a] and rev[b]:
        pb = R @ (pts[b] - ok) + ok  # (N, 3)
        nrm = np.cross(H[a], Ha[:, 0])
        sn = np.linalg.norm(nrm, axis=-1)
        with np.errstate(all="ignore"):
            d = np.abs(np.einsum("ij,ij->i", pb - pts[a], nrm)) / sn / scale
        d = np.where(sn < NEAR_TOL, 0.0, d)  # (nearly parallel: flagged above)
        apart = d[sn >= NEAR_TOL]
        same = apart.size > 0 and np.ptp(apart) <= SAME_DISTANCE_REL * np.max(apart) and np.max(apart) < NEAR_TOL
        if np.nanmax(d) >= INTERSECT_TOL_REL and not same:
            flag |= d < 2.0 * NEAR_TOL
    near = np.convolve(flag, np.ones(5), mode="same") > 0  # (and the two values either side)
    at_reference = chain_at(reference)
    generic, nearly = _relations(structure_of(at_reference, scale)), near_structure(at_reference, scale)
    plan = plan_at(reference)
    marked = np.zeros(grid.size, dtype=bool)
    for g in np.nonzero(near)[0]:
        held = chain_at(float(grid[g]))
        if near_structure(held, scale) != nearly or _relations(structure_of(held, scale)) != generic:
            marked[g] = True
    windows = _runs(grid, np.convolve(marked, np.ones(5), mode="same") > 0)
    for v in _perpendicular(H, hk, k, n):
        if plan_at(v) != plan:
            windows.append((v - EXACT_WINDOW, v + EXACT_WINDOW))
    merged: list[list[float]] = []
    for lo, hi in sorted(windows):
        if merged and lo <= merged[-1][1]:
            merged[-1][1] = max(merged[-1][1], hi)
        else:
            merged.append([lo, hi])
    return np.array(merged, dtype=np.float64).reshape(-1, 2)


def _runs(grid: Array, mask: NDArray[np.bool_]) -> list[tuple[float, float]]:
    """The runs of ``mask`` as intervals of ``grid`` (a run at either end reaches past it: the turn closes)."""
    out: list[tuple[float, float]] = []
    idx = np.nonzero(mask)[0]
    if idx.size == 0:
        return out
    breaks = np.nonzero(np.diff(idx) > 1)[0]
    for s, e in zip(np.r_[0, breaks + 1], np.r_[breaks, idx.size - 1], strict=True):
        lo, hi = float(grid[idx[s]]), float(grid[idx[e]])
        lo = -math.inf if idx[s] == 0 else lo
        hi = math.inf if idx[e] == grid.size - 1 else hi
        out.append((lo, hi))
    return out


def _perpendicular(H: Array, hk: Array, k: int, n: int) -> list[float]:
    """The values at which an axis before ``k`` is perpendicular to one after it (``H[i] . R(v) H[j] = 0``:
    ``A cos v + B sin v + C``), where that is not so at every value."""
    out = []
    for i in range(k):
        for j in range(k + 1, n):
            u = H[j]
            A = float(H[i] @ (u - (u @ hk) * hk))
            B = float(H[i] @ np.cross(hk, u))
            C = float((H[i] @ hk) * (u @ hk))
            r = math.hypot(A, B)
            if r < PARALLEL_TOL or abs(C) > r:
                continue
            phi, delta = math.atan2(B, A), math.acos(max(-1.0, min(1.0, -C / r)))
            out += [math.remainder(phi + delta, 2.0 * math.pi), math.remainder(phi - delta, 2.0 * math.pi)]
    return sorted(set(out))


def in_windows(value: float, windows: Array) -> bool:
    """Whether ``value`` (radians, any turn) lies in one of ``windows`` (``special_windows``)."""
    return _window_of(value, windows) is not None


def _window_of(value: float, windows: Array) -> int | None:
    """The row of ``windows`` that holds ``value`` (radians, any turn), None where none does."""
    if windows.shape[0] == 0:
        return None
    v = math.remainder(value, 2.0 * math.pi)
    i = int(np.searchsorted(windows[:, 0], v, side="right")) - 1
    return i if i >= 0 and v <= windows[i, 1] else None


def window_reference(value: float, windows: Array) -> float | None:
    """The reference value of the window of ``windows`` that holds ``value`` (radians, any turn), None where none
    does: a fixed value in it (``REFERENCE_AT`` of its width from its start, in ``[-pi, pi]``), the same for every
    value in the window, at which what the window's values share can be chosen once (``reductions``'
    ``automatic_for_held``: the companion of the plan vouched for). A window that goes round (ends at -inf and inf)
    is one window."""
    i = _window_of(value, windows)
    if i is None:
        return None
    lo, hi = float(windows[i, 0]), float(windows[i, 1])
    if lo == -math.inf:  # (its start is the last window's, a turn before)
        lo = float(windows[-1, 0]) - 2.0 * math.pi if windows[-1, 1] == math.inf else -math.pi
    if hi == math.inf:
        hi = float(windows[0, 1]) + 2.0 * math.pi if windows[0, 0] == -math.inf else math.pi
    return math.remainder(lo + REFERENCE_AT * (hi - lo), 2.0 * math.pi)
