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
from numba import float64, int64
from numpy.typing import NDArray

from sweepik.engine.continuation import scaled_jacobians, scaled_singular, second_singular
from sweepik.engine.families import members_at
from sweepik.engine.settings import (
    CROSS_RANK,
    CROSS_SAMPLES,
    CROSS_SCREEN,
    CROSS_SINGULAR,
    CROSS_STEP,
    CROSS_STEPS,
    SCREEN_JUMP,
    SCREEN_ZERO,
    VERTEX_REL,
    VERTEX_WIDTH,
)
from sweepik.engine.settle import per_joint
from sweepik.model.pose import wrap_angle
from sweepik.model.robot import Robot
from sweepik.reductions.kernels import lazy_njit
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


#: The samples of the ``CROSS_SAMPLES`` grid the screen takes: every ``CROSS_SCREEN``-th, and all of the first and
#: last stretch (a family's end is often a zero of the cofactors: where it folds back, or its closed form breaks down).
_SCREEN = np.unique(
    np.concatenate(
        [
            np.arange(0, CROSS_SAMPLES, CROSS_SCREEN),
            np.arange(CROSS_SCREEN),
            CROSS_SAMPLES - 1 - np.arange(CROSS_SCREEN),
        ]
    )
)


def screened(robot: Robot, families: list[Family]) -> list[bool]:
    """Whether each family shows no sign of crossing another continuum (``CROSS_SCREEN``; checked against the whole
    grid's search on the bundled and random arms' singular sets, docs/decomposition.md): at its screen's members
    the cofactor vectors of the arm's Jacobian without the family's joint (``_cofactors``) keep their sign from one to
    the next
    (their inner product positive), none inside is zero (``SCREEN_ZERO``) and every member is finite. Along a family
    the Jacobian has rank five, its null vector the family's tangent, which moves the family's joint: the other five
    columns span what the Jacobian spans, so the cofactors (a vector normal to that span, of the size of its volume)
    vanish where the arm loses a second rank, at a crossing, and change sign through it, however narrow the dip of
    the second singular value there. (The ends may be zeros: an end sample's sign is not compared.) Nor may a joint
    move by more than ``SCREEN_JUMP`` from one to the next: where a spherical wrist's family crosses A5 = 0 its members
    go over to the wrist turned by pi one sample after (the closed form's branch keeps the sign of A5), which turns
    the cofactors over a second time. Six-joint arms; False (probe it) for others and for families of held arms."""
    out = [False] * len(families)
    ks = [k for k, f in enumerate(families) if f.held is None]
    if robot.n_joints != 6 or not ks:
        return out
    probes = _grid_probes([families[k] for k in ks], _SCREEN)
    q = np.concatenate(probes)
    joint = np.repeat(np.array([families[k].free_joint for k in ks], dtype=np.intp), _SCREEN.size)
    finite = np.all(np.isfinite(q), axis=-1)
    flat = np.full((q.shape[0], 6), np.nan)
    if finite.any():
        rows = np.nonzero(finite)[0]
        flat[rows] = _cofactors(robot, np.ascontiguousarray(q[rows]), joint[rows])
    w = flat.reshape(len(ks), _SCREEN.size, 6)
    size = np.linalg.norm(w, axis=-1)
    step = np.diff(q.reshape(len(ks), _SCREEN.size, 6), axis=1)
    step[..., robot.is_revolute] = wrap_angle(step[..., robot.is_revolute])
    with np.errstate(invalid="ignore"):
        zero = size <= SCREEN_ZERO * np.max(size, axis=1, keepdims=True)
        same = np.sum(w[:, 1:] * w[:, :-1], axis=-1) > 0.0
        jump = np.any(np.abs(step) > per_joint(robot, SCREEN_JUMP), axis=-1)
    compared = ~zero[:, 1:] & ~zero[:, :-1]
    passed = np.isfinite(size).all(axis=1) & ~zero[:, 1:-1].any(axis=1) & np.all(same | ~compared, axis=1)
    passed &= ~jump.any(axis=1)
    for k, p in zip(ks, passed.tolist(), strict=True):
        out[k] = p
    return out


def _cofactors(robot: Robot, q: Array, joint: NDArray[np.intp]) -> Array:
    """``(K, 6)``: the cofactor vector of the scaled Jacobian at ``q (K, 6)`` without column ``joint (K,)``: ``w`` with
    ``w . x = det`` of the Jacobian with that column replaced by ``x`` (compiled)."""
    out = np.empty((q.shape[0], 6))
    _cofactor_rows(scaled_jacobians(robot, q), np.ascontiguousarray(joint, dtype=np.int64), out)
    return out


@lazy_njit((float64[:, :, ::1], int64[::1], float64[:, ::1]), cache=True, nogil=True)
def _cofactor_rows(J, joint, out):  # pragma: no cover
    """``_cofactors``' kernel. With ``A`` the 6 x 5 matrix left and ``P A = L U`` (partial pivoting),
    ``det [A | x] = det(P) prod(diag U) (L^-1 P x)_5``: ``w = det(P) prod(diag U) P^T z`` with ``L^T z = e_5``, and
    the column put back in place of the joint's (``(-1)^(5 - joint)``)."""
    A = np.empty((6, 5))
    perm = np.empty(6, np.int64)
    z = np.empty(6)
    for k in range(J.shape[0]):
        j = joint[k]
        for r in range(6):
            perm[r] = r
            c = 0
            for cc in range(6):
                if cc != j:
                    A[r, c] = J[k, r, cc]
                    c += 1
        det = 1.0 if (5 - j) % 2 == 0 else -1.0
        for col in range(5):
            piv = col
            for i in range(col + 1, 6):
                if abs(A[i, col]) > abs(A[piv, col]):
                    piv = i
            if piv != col:
                for c in range(5):
                    A[col, c], A[piv, c] = A[piv, c], A[col, c]
                perm[col], perm[piv] = perm[piv], perm[col]
                det = -det
            det *= A[col, col]
            if A[col, col] != 0.0:
                for i in range(col + 1, 6):
                    A[i, col] /= A[col, col]  # (L below the diagonal)
                    for c in range(col + 1, 5):
                        A[i, c] -= A[i, col] * A[col, c]
            else:
                for i in range(col + 1, 6):
                    A[i, col] = 0.0
        # L^T z = e_5 (L unit lower triangular, its last column e_5)
        z[5] = 1.0
        for i in range(4, -1, -1):
            s = 0.0
            for m in range(i + 1, 6):
                s += A[m, i] * z[m]
            z[i] = -s
        for i in range(6):
            out[k, perm[i]] = det * z[i]


def _grid_probes(families: list[Family], index: NDArray[np.intp] | None = None) -> list[Array]:
    """``_probe`` of each family at its ``CROSS_SAMPLES`` grid (``_grid``; the samples ``index`` of it, if given);
    the families whose probes are their members (``Family.at``) at once (``members_at``): the same values."""
    if not families:
        return []
    lo, hi = np.array([f.interval for f in families], dtype=np.float64).T
    grids = np.linspace(lo, hi, CROSS_SAMPLES, axis=1)  # (each row ``_grid``'s, bit for bit)
    if index is not None:
        grids = grids[:, index]
    out = [_probe(f, g) if _traced(f) else np.zeros((0, 0)) for f, g in zip(families, grids, strict=True)]
    plain = [k for k, f in enumerate(families) if not _traced(f)]
    for k, q in zip(plain, members_at([families[k] for k in plain], list(grids[plain])), strict=True):
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
    one for the singular values, where a call per family spent ~0.3 ms in Python); None for a family of one point,
    one the screen passes (``screened``: no crossing) or one without a dip to search (``_dips``)."""
    ks = [k for k, f in enumerate(families) if f.interval[1] > f.interval[0]]
    ks = [k for k, passed in zip(ks, screened(robot, [families[k] for k in ks]), strict=True) if not passed]
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
