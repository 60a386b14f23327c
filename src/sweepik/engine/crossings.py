"""Continua that branch off a reported family where it crosses another one (double singularities).

A pose can hold two continua that meet: the KUKA KR 6 with its wrist centre on axis 1 has a continuum along joint 1
(the wrist turning to keep the tool still), and where that continuum passes A5 = 0 the wrist's own circle (A4 + A6
constant) crosses it. The sweep and the tracers find the first; the second meets it in one configuration only, a
measure-zero point no sweep sample lands on. Where two continua cross, the arm's Jacobian loses a second rank: along
a family its smallest singular value is zero (the family's tangent), and at a crossing the second smallest is too.

``crossing_seeds`` looks for such points along each family (samples, then a golden-section search of the least
second singular value where a sampled least value is the bottom of a V reaching zero) and, at each one found, gives
configurations a step off the crossing along the second null direction (the one across the family) with the joint
that direction moves most held:
:func:`sweepik.engine.continuation.continuum_families` corrects them onto the other continuum and traces it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import scaled_singular
from sweepik.engine.families import golden_least
from sweepik.engine.settings import CROSS_RANK, CROSS_SAMPLES, CROSS_SINGULAR, CROSS_STEP, CROSS_STEPS, VERTEX_REL
from sweepik.model.robot import Robot
from sweepik.results import Family

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]


def _second_singular(robot: Robot, family: Family, theta: Array) -> Array:
    """Second smallest singular value over the largest of the (scaled) Jacobian at the family's members ``theta``
    (infinite where a member is not finite)."""
    q = family.at(theta)
    out = np.full(theta.shape, np.inf)
    ok = np.all(np.isfinite(q), axis=-1)
    if ok.any():
        s, _ = scaled_singular(robot, q[ok])
        out[ok] = s[:, -2] / s[:, 0]
    return out


def crossing_seeds(robot: Robot, families: tuple[Family, ...]) -> tuple[Array, IntArray]:
    """Seeds of the continua crossing ``families`` (one pose's): ``(q (K, n), joint (K,))``, two per crossing found
    (one each side), for ``continuum_families``."""
    seeds: list[Array] = []
    joints: list[int] = []
    scale = np.where(robot.is_revolute, 1.0, robot.length_scale)
    for f in families:
        lo, hi = f.interval
        if not hi > lo:
            continue
        grid = np.linspace(lo, hi, CROSS_SAMPLES)
        s2 = _second_singular(robot, f, grid)
        if not np.median(s2) > CROSS_RANK:
            continue
        padded = np.concatenate([[np.inf], s2, [np.inf]])
        left, right = padded[:-2], padded[2:]
        dips = np.nonzero((s2 <= left) & (s2 <= right) & np.isfinite(s2) & np.isfinite(left + right))[0]
        # a crossing between the samples: a V, |theta - crossing| x slope; its vertex, from the steeper side's slope
        # and the other side's sample, at zero (a smooth least value above zero: well above it)
        high, low = np.maximum(left[dips], right[dips]), np.minimum(left[dips], right[dips])
        drop = np.maximum(high - s2[dips], 1e-300)  # (per sample step)
        vertex = s2[dips] - 0.5 * (s2[dips] - low + drop)
        dips = dips[vertex <= VERTEX_REL * s2[dips]]
        rise = np.maximum(left, right)
        if dips.size == 0:
            continue

        def excess(t: Array, f: Family = f) -> Array:
            return _second_singular(robot, f, t) - CROSS_SINGULAR

        a, b = grid[np.maximum(dips - 1, 0)], grid[np.minimum(dips + 1, grid.size - 1)]
        slope = 2.0 * rise[dips] / (grid[1] - grid[0])  # (a bound on the V's slope)
        x, e = golden_least(excess, a, b, grid[dips], s2[dips] - CROSS_SINGULAR, steps=CROSS_STEPS, slope=slope)
        x = x[e <= 0.0]
        if x.size == 0:
            continue
        h = 1e-6 * (hi - lo)
        qc = f.at(x)
        tangent = (f.at(np.minimum(x + h, hi)) - f.at(np.maximum(x - h, lo))) / scale
        tangent /= np.maximum(np.linalg.norm(tangent, axis=1, keepdims=True), 1e-300)
        _, vt = scaled_singular(robot, qc)
        for c in range(x.size):
            null = vt[c, -2:]  # (2, n): the null space at the crossing
            across = null - (null @ tangent[c])[:, None] * tangent[c][None]
            v = across[int(np.argmax(np.linalg.norm(across, axis=1)))]
            v = v / max(float(np.linalg.norm(v)), 1e-300)
            joint = int(np.argmax(np.abs(v)))
            for sign in (1.0, -1.0):
                seeds.append(qc[c] + sign * CROSS_STEP * v * scale)
                joints.append(joint)
    if not seeds:
        return np.zeros((0, robot.n_joints)), np.zeros(0, dtype=np.intp)
    return np.array(seeds), np.array(joints, dtype=np.intp)
