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

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import scaled_singular, second_singular
from sweepik.engine.families import members_at
from sweepik.engine.settings import (
    CROSS_RANK,
    CROSS_SAMPLES,
    CROSS_SINGULAR,
    CROSS_STEP,
    CROSS_STEPS,
    VERTEX_REL,
    VERTEX_WIDTH,
)
from sweepik.model.pose import wrap_angle
from sweepik.model.robot import Robot
from sweepik.results import Family

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]


def _second_singular(robot: Robot, family: Family, theta: Array) -> Array:
    """Second smallest singular value over the largest of the (scaled) Jacobian at the family's members ``theta``
    (infinite where a member is not finite)."""
    return _singular_of(robot, [_probe(family, theta)])[0]


def _singular_of(robot: Robot, probes: list[Array]) -> list[Array]:
    """``_second_singular`` of each family's members ``probes[k] (M_k, n)``, in one compiled call."""
    q = np.concatenate(probes) if len(probes) > 1 else probes[0]
    ok = np.all(np.isfinite(q), axis=-1)
    out = np.full(q.shape[0], np.inf)
    if ok.any():
        rows = np.nonzero(ok)[0]
        family = np.repeat(np.arange(len(probes)), [len(p) for p in probes])[rows]
        cold = np.concatenate([[True], family[1:] != family[:-1]])  # (each family's values as in a call of its own)
        out[rows] = second_singular(robot, np.ascontiguousarray(q[rows]), cold)
    return np.split(out, np.cumsum([len(p) for p in probes[:-1]]).astype(np.intp))


def _grid_probes(families: list[Family]) -> list[Array]:
    """``_probe`` of each family at its ``CROSS_SAMPLES`` grid (``_grid``); the families whose probes are their
    members (``Family.at``) at once (``members_at``): the same values."""
    out = [_probe(f, _grid(f)) if _traced(f) else np.zeros((0, 0)) for f in families]
    plain = [k for k, f in enumerate(families) if not _traced(f)]
    for k, q in zip(plain, members_at([families[k] for k in plain], [_grid(families[k]) for k in plain]), strict=True):
        out[k] = q
    return out


def _grid(f: Family) -> Array:
    """The ``CROSS_SAMPLES`` theta* values over the family's interval, ends included."""
    lo, hi = f.interval
    return np.linspace(lo, hi, CROSS_SAMPLES)


def _traced(family: Family) -> bool:
    """The family's members are probed where the Newton steps left them (``_probe``), not as ``Family.at`` gives."""
    return getattr(family.reduction, "corrected", None) is not None and family.held is None


def _probe(family: Family, theta: Array) -> Array:
    """The family's members at ``theta`` (inside its interval) to probe the Jacobian at: a traced family's as the
    Newton steps left them (``Traced.corrected``; next to a crossing they converge linearly and a member may miss the
    certification by a little, which ``Family.at`` would answer with one nudged away: the search wants it where it
    is), another's from ``Family.at``."""
    corrected = getattr(family.reduction, "corrected", None)
    if corrected is None or family.held is not None:
        return family.at(theta)
    lo, hi = family.interval
    th = np.clip(theta, lo, hi)
    q = corrected(family.chain_pose[None], th[None], np.full((1, th.size), family.branch, dtype=np.intp))[0][0]
    return np.asarray(family.reduction.robot.wrap(q))


def vertex_least(
    excess: Callable[[Array], Array], a: Array, m: Array, b: Array, ea: Array, em: Array, eb: Array
) -> tuple[Array, Array]:
    """The least ``excess`` in each bracket ``[a, b]`` about its least sample ``m`` (``ea >= em <= eb``), for an
    excess shaped like a V (the second singular value along a family about a crossing: the distance to it times a
    slope; rounded at the bottom where two families only nearly meet): ``(x, excess there)``, the least found.

    Each step samples where the V through the three points has its vertex (the steeper side's slope, mirrored
    through the sample of the other side: one step reaches the vertex of a V), and keeps the least sample with its
    neighbours. A bracket is settled once its least excess is at most 0 (a crossing), or once the excess cannot
    reach 0 in it: a convex function lies above each side's secant extended over the other side, whose lower end is
    then above 0. At most ``CROSS_STEPS`` steps (a golden-section search took ~20 where a V's takes 2 to 6)."""
    a, m, b = (np.array(v, dtype=np.float64) for v in (a, m, b))
    ea, em, eb = (np.array(v, dtype=np.float64) for v in (ea, em, eb))
    for _ in range(CROSS_STEPS):
        with np.errstate(divide="ignore", invalid="ignore"):
            sl, sr = (ea - em) / (m - a), (eb - em) / (b - m)  # (the two sides' slopes, as magnitudes)
        bound = np.minimum(em - sr * (m - a), em - sl * (b - m))
        todo = np.nonzero((em > 0.0) & ~(bound > 0.0) & (b - a > VERTEX_WIDTH * np.maximum(np.abs(m), 1.0)))[0]
        if todo.size == 0:
            break
        k_a, k_m, k_b, k_ea, k_em, k_eb, k_sl, k_sr = (v[todo] for v in (a, m, b, ea, em, eb, sl, sr))
        slope = np.maximum(k_sl, k_sr)
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.where(  # the vertex: right of m where the left side is the steeper, else left of it
                k_sl >= k_sr,
                (k_em - k_eb + slope * (k_m + k_b)) / (2.0 * slope),
                (k_ea - k_em + slope * (k_a + k_m)) / (2.0 * slope),
            )
        w = k_b - k_a
        x = np.where(np.isfinite(x), x, k_m + 0.25 * w * np.where(k_b - k_m > k_m - k_a, 1.0, -1.0))
        x = np.clip(x, k_a + 0.01 * w, k_b - 0.01 * w)
        close = np.abs(x - k_m) < 0.01 * w  # (not on the least sample itself: a little to its wider side)
        x = np.where(close, k_m + 0.01 * w * np.where(k_b - k_m > k_m - k_a, 1.0, -1.0), x)
        ex = excess(x)
        better, right = ex < k_em, x > k_m
        # the least three: x between its neighbours where it is the least, else it closes its side of the bracket
        a[todo] = np.where(better, np.where(right, k_m, k_a), np.where(right, k_a, x))
        ea[todo] = np.where(better, np.where(right, k_em, k_ea), np.where(right, k_ea, ex))
        b[todo] = np.where(better, np.where(right, k_b, k_m), np.where(right, x, k_b))
        eb[todo] = np.where(better, np.where(right, k_eb, k_em), np.where(right, ex, k_eb))
        m[todo], em[todo] = np.where(better, x, k_m), np.where(better, ex, k_em)
    return m, em


def crossing_grids(robot: Robot, families: list[Family]) -> list[Array | None]:
    """The second singular value (``_second_singular``) of each family at its ``CROSS_SAMPLES`` members over its
    interval, every family's in one pass (a batch's families: one compiled call for the members of each reduction's,
    one for the singular values, where a call per family spent ~0.3 ms in Python); None for a family of one point or
    one without a dip to search (``_dips``)."""
    ks = [k for k, f in enumerate(families) if f.interval[1] > f.interval[0]]
    out: list[Array | None] = [None] * len(families)
    if ks:
        grids = _singular_of(robot, _grid_probes([families[k] for k in ks]))
        searched: list[bool] = np.asarray(_dips(np.array(grids)).any(axis=1)).tolist()
        for k, s2, keep in zip(ks, grids, searched, strict=True):
            out[k] = s2 if keep else None
    return out


def _dips(S: Array) -> NDArray[np.bool_]:
    """``(F, M)``: the least samples of the families' second singular values ``S (F, M)`` worth searching for a
    crossing: a local least (finite, with finite neighbours) at a crossing already (at most ``CROSS_SINGULAR``: a
    crossing on a sample, e.g. at 0 or 90 deg, where the value is rounding) or whose V through its neighbours reaches
    down to ``VERTEX_REL`` of it (a crossing between the samples: a V, |theta - crossing| x slope; its vertex, from
    the steeper side's slope and the other side's sample, at zero; a smooth least value above zero: well above it),
    on a family whose median is above ``CROSS_RANK`` (else it loses a second rank all along)."""
    inf = np.full((S.shape[0], 1), np.inf)
    padded = np.concatenate([inf, S, inf], axis=1)
    left, right = padded[:, :-2], padded[:, 2:]
    with np.errstate(invalid="ignore"):
        least = (S <= left) & (S <= right) & np.isfinite(S) & np.isfinite(left + right)
        high, low = np.maximum(left, right), np.minimum(left, right)
        drop = np.maximum(high - S, 1e-300)  # (per sample step)
        vertex = S - 0.5 * (S - low + drop)
        reaches = (vertex <= VERTEX_REL * S) | (S <= CROSS_SINGULAR)
        return least & reaches & (np.median(S, axis=1) > CROSS_RANK)[:, None]


def crossing_seeds(
    robot: Robot, families: tuple[Family, ...], grids: list[Array | None] | None = None
) -> tuple[Array, IntArray]:
    """Seeds of the continua crossing ``families`` (one pose's): ``(q (K, n), joint (K,))``, two per crossing found
    (one each side), for ``continuum_families``. ``grids``: their ``crossing_grids``, if known."""
    seeds: list[Array] = []
    joints: list[int] = []
    scale = np.where(robot.is_revolute, 1.0, robot.length_scale)
    for f, s2 in zip(families, crossing_grids(robot, list(families)) if grids is None else grids, strict=True):
        lo, hi = f.interval
        if s2 is None:
            continue
        grid = _grid(f)
        dips = np.nonzero(_dips(s2[None])[0])[0]
        if dips.size == 0:
            continue

        def excess(t: Array, f: Family = f) -> Array:
            return _second_singular(robot, f, t) - CROSS_SINGULAR

        e_grid = s2 - CROSS_SINGULAR
        x, e = vertex_least(
            excess, grid[dips - 1], grid[dips], grid[dips + 1], e_grid[dips - 1], e_grid[dips], e_grid[dips + 1]
        )
        x = x[e <= 0.0]
        if x.size == 0:
            continue
        h = 1e-6 * (hi - lo)
        qc = f.at(x)
        step = f.at(np.minimum(x + h, hi)) - f.at(np.maximum(x - h, lo))
        rev = robot.is_revolute  # (members are wrapped: a joint at +-pi must not step by a turn)
        step[:, rev] = wrap_angle(step[:, rev])
        tangent = step / scale
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
