"""Next to a fold of the solution set (issue 35, point 3: close roots): a solution's close partner on the far side,
and the bottom of a flat valley a solution stopped in (``valley_bottoms``, below).

A pose just inside a singular set's image has two solutions 1e-6 ... 1e-3 apart on either side of the fold, both
solving the pose to rounding. A sweep sees them as two roots a hair apart, often next to a branch-domain edge (a
FANUC CRX-10iA pose: 1.5e-8 rad apart in theta*, 6e-8 from the edge); a closed form sees them as one branch's value
split by rounding. Where only one of them came out (the Newton polish of a candidate between them converges to one),
the other lies on the far side of the fold, along the Jacobian's nearly null direction: Newton from points along it
converges to it.

Only solutions that needed the polish are probed (a candidate the closed form or the sweep gave to rounding already
is well conditioned, or was found with its partner), and only where the Jacobian is nearly singular
(``PARTNER_SINGULAR``).
A point found counts as a second solution when the midpoint between the two misses the pose (``PARTNER_MIDPOINT``)
and Newton from it goes over to one of them (``PARTNER_STAY``): along a continuum, or a numerical one (a pose a hair
off a self-motion), it stays where it is; between two roots whose pose error stays below the certification's
tolerance all the way, Newton ends anywhere between them (those two come from the closed form or the sweep as they
are: ``settings.MEET_NEAR``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import least_singular, scaled_singular
from sweepik.engine.families import golden_least
from sweepik.engine.polish import geodesic_errors, polished
from sweepik.engine.settings import (
    PARTNER_MIDPOINT,
    PARTNER_NEWTON,
    PARTNER_ROUNDING,
    PARTNER_SAME,
    PARTNER_SINGULAR,
    PARTNER_STAY,
    PARTNER_STEPS,
    VALLEY_REACH,
    VALLEY_RISE,
    VALLEY_SAMPLES,
    VALLEY_STEPS,
)
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import Array, IntArray
from sweepik.results import joint_distance


def nearly_singular(robot: Robot, q: Array) -> NDArray[np.bool_]:
    """``(K,)``: the configurations ``q (K, n)`` whose Jacobian's smallest singular value is at most
    ``PARTNER_SINGULAR`` of its largest (the only ones ``close_partners`` and ``valley_bottoms`` look at)."""
    return np.asarray(least_singular(robot, q) <= PARTNER_SINGULAR)


def close_partners(robot: Robot, q: Array, world: Array, tol: float) -> tuple[IntArray, Array, Array]:
    """Second solutions next to the certified solutions ``q (K, n)`` of poses ``world (K, 4, 4)`` across a fold:
    ``(row, q, error)``, ``row`` the solution each was found from (several may give the same one; none for most)."""
    n = robot.n_joints
    none = (np.zeros(0, dtype=np.intp), np.zeros((0, n)), np.zeros(0))
    if q.shape[0] == 0:
        return none
    s, vt = scaled_singular(robot, q)
    rows = np.nonzero(s[:, -1] <= PARTNER_SINGULAR * s[:, 0])[0]
    if rows.size == 0:
        return none
    steps = np.array(PARTNER_STEPS)
    signed = np.concatenate([steps, -steps])
    v = vt[rows, -1, :n] * np.where(robot.is_revolute, 1.0, robot.length_scale)  # (back to joint units)
    start = q[rows][:, None, :] + signed[None, :, None] * v[:, None, :]
    k = np.repeat(rows, signed.size)
    target = world[k]
    weight = orientation_weight(robot.length_unit)
    found, err = polished(robot, start.reshape(-1, n), target, weight, iterations=PARTNER_NEWTON, floor=1e-3 * tol)
    d = joint_distance(robot, found, q[k])
    same = np.all(d <= PARTNER_SAME * np.where(robot.is_revolute, 1.0, robot.length_scale), axis=-1)
    ok = np.nonzero((err <= PARTNER_ROUNDING * robot.length_scale) & ~same)[0]
    if ok.size == 0:
        return none
    # two roots: their midpoint misses the pose, and Newton from it goes over to one of them (or nowhere); along a
    # continuum it stays, and between two roots that close that the pose error stays below the tolerance between
    # them (a PUMA 560 1e-7 rad short of its elbow fold) Newton's end point is anywhere in the flat valley
    mid = 0.5 * (q[k[ok]] + found[ok])  # (Newton's steps from next to q: unwrapped, close to it)
    barrier = geodesic_errors(robot, mid, target[ok], weight) > PARTNER_MIDPOINT * tol
    ok, mid = ok[barrier], mid[barrier]
    m, m_err = polished(robot, mid, target[ok], weight, iterations=PARTNER_NEWTON, floor=1e-3 * tol)
    d = np.linalg.norm(found[ok] - q[k[ok]], axis=-1)
    near = np.minimum(np.linalg.norm(m - q[k[ok]], axis=-1), np.linalg.norm(m - found[ok], axis=-1))
    ok = ok[(m_err > tol) | (near <= PARTNER_STAY * d)]
    return k[ok].astype(np.intp), found[ok], err[ok]


def valley_bottoms(robot: Robot, q: Array, world: Array, tol: float) -> tuple[Array, NDArray[np.bool_]]:
    """Certified solutions ``q (K, n)`` of poses ``world (K, 4, 4)`` (``tol``: the certification's) moved to the lowest
    point of their valley where they lie in one (nearly singular, error above rounding): ``(q, moved)``, a row moved
    only where its error drops."""
    weight = orientation_weight(robot.length_unit)
    err = geodesic_errors(robot, q, world, weight)
    out, moved = q.copy(), np.zeros(q.shape[0], dtype=bool)
    floor = PARTNER_ROUNDING * robot.length_scale
    rows = np.nonzero((err > floor) & (err <= tol))[0]
    if rows.size == 0:
        return out, moved
    # a root the solver's polish left just above rounding (two PUMA 560 roots 1.8e-4 apart: 2e-15 of its size) gets
    # there with more steps: it is no valley point (whose bottom could be the other root)
    again, e_again = polished(robot, q[rows], world[rows], weight, iterations=PARTNER_NEWTON, floor=1e-3 * floor)
    rows = rows[e_again > floor]
    if rows.size == 0:
        return out, moved
    s, vt = scaled_singular(robot, q[rows])
    keep = s[:, -1] <= PARTNER_SINGULAR * s[:, 0]
    rows, vt = rows[keep], vt[keep]
    if rows.size == 0:
        return out, moved
    n = robot.n_joints
    v = vt[:, -1, :n] * np.where(robot.is_revolute, 1.0, robot.length_scale)
    held = np.zeros((rows.size, n), dtype=bool)
    held[np.arange(rows.size), np.argmax(np.abs(vt[:, -1, :n]), axis=1)] = True

    def corrected(t: Array) -> tuple[Array, Array]:  # (t (R, M): M points along each row's direction)
        M = t.shape[1]
        start = (q[rows][:, None, :] + t[..., None] * v[:, None, :]).reshape(-1, n)
        m, e = polished(robot, start, np.repeat(world[rows], M, axis=0), weight, iterations=PARTNER_NEWTON,
                        fixed=np.repeat(held, M, axis=0), floor=1e-3 * floor)  # fmt: skip
        return m.reshape(rows.size, M, n), e.reshape(rows.size, M)

    grid = np.broadcast_to(np.linspace(-VALLEY_REACH, VALLEY_REACH, VALLEY_SAMPLES), (rows.size, VALLEY_SAMPLES))
    _, e = corrected(grid)
    # a valley ends within the reach both ways: its ends do not solve the pose, or rise well above its lowest point
    # (a closed form's imprecise root just off a fold: a V at rounding level, ``VALLEY_ABOVE_REL``); along a
    # continuum, which holds solutions all the way, a point is where it is (the continuum is reported by its family)
    high = np.minimum(tol, VALLEY_RISE * np.maximum(e.min(axis=1), floor))
    bounded = (e[:, 0] > high) & (e[:, -1] > high)
    rows, grid, e, v, held = rows[bounded], grid[bounded], e[bounded], v[bounded], held[bounded]
    if rows.size == 0:
        return out, moved
    b = np.argmin(e, axis=1)
    idx = np.arange(rows.size)
    a_, c_ = grid[idx, np.maximum(b - 1, 0)], grid[idx, np.minimum(b + 1, VALLEY_SAMPLES - 1)]
    # (all its steps: near the bottom the error is at rounding level over a stretch, whose middle the search nears)
    x, _ = golden_least(lambda t: corrected(t[:, None])[1][:, 0], a_, c_, grid[idx, b], e[idx, b], steps=VALLEY_STEPS)
    m, e_m = corrected(x[:, None])
    better = e_m[:, 0] < err[rows]
    out[rows[better]], moved[rows[better]] = m[better, 0], True
    return out, moved
