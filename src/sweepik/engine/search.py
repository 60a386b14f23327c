"""The precise sweep's candidate search, compiled (Numba): per pose and branch, sample theta*, bracket sign changes
(Chandrupatla), locate extrema, keep domain-edge samples, locate a domain edge hidden between two samples, resample
bending or edge-adjacent intervals recursively, detect families and merge noise-level clusters. Poses run in parallel
threads (:mod:`sweepik.engine.parallel`). The tests hold it against a NumPy reference of the same steps
(``tests/oracles/numpy_sweep.py``).

A kernel is ``residual(params, theta, branch) -> float`` compiled with ``numba.njit`` to the signature
``reductions.kernels.RESIDUAL_SIG``, where ``params`` is one row of ``Reduction.kernel_params(poses)``; the
engine takes it by the address of its compiled code (``Reduction.kernel[0]``, ``kernels.address_of``), so one
compiled engine serves every reduction. A reduction without a kernel (written in NumPy) is searched by the same
code, its residual called back (:mod:`sweepik.engine.callback`).

The constants (:mod:`sweepik.engine.settings`) are frozen into the compiled code, and Numba's on-disk cache is keyed
on this file's time stamp only: after changing one of them, touch this file (or delete its ``*.nbi`` cache).
"""

from __future__ import annotations

import math
import weakref
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numba import boolean, float64, int64, njit
from numba import void as _void
from numpy.typing import NDArray

from sweepik._jit import ERROR_MODEL, alive, function_at, inlined, internal, unowned, writable
from sweepik.engine import callback, candidates, parallel
from sweepik.engine.settings import (
    BEND,
    CLUSTER_FAMILY_REL,
    DIFF_LEVELS,
    DIFF_SHRINK,
    DIFF_STEP_REL,
    EDGE_LOW,
    EDGE_MARGIN,
    EDGE_NUDGES,
    EDGE_PROBE_REL,
    EXTREMUM_REACH,
    FAMILY_BISECT,
    FAMILY_MIN_RUN,
    FAMILY_TOL,
    FAR_NOISE,
    FLAT_BISECT,
    FLAT_MAX_REL,
    FLAT_PROBE_REL,
    FLAT_SHORT_TOL,
    JUMP_NOISE,
    MAX_CAND,
    MAX_FAM,
    MAX_LEVELS,
    MULT_LEVEL,
    MULT_MAX,
    N_SAMPLES,
    PARALLEL_MIN,
    REDO_GROW,
    REDO_MAX_CAND,
    STACK,
    SUB_SAMPLES,
    U_EDGE,
    U_UNIFORM,
    XTOL_REL,
)
from sweepik.errors import SearchOverflowError, UnknownOptionError
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import overridden_below_kernel
from sweepik.reductions.kernels import (
    HINTS_SIG,
    RESIDUAL_SIG,
    RESIDUALS_SIG,
    address_of,
    as_hints,
    as_residual,
    as_residuals,
    as_swing,
    lazy_njit,
    owned_kernel,
)
from sweepik.reductions.pose_error import PoseErrorResidual
from sweepik.subproblems.trig import wrap_pi

Array = NDArray[np.float64]


@inlined
def _root(res, p, b, a, c, fa, fc, xtol):
    """Chandrupatla's bracketed root finder (scalar), as the NumPy reference's find_roots."""
    eps = 2.220446049250313e-16
    x = a if abs(fa) < abs(fc) else c
    if fa == 0.0:
        return a
    if fc == 0.0:
        return c
    bb, fb = c, fc
    cc, fcc = a, fa
    t = 0.5
    for _ in range(100):
        xt = a + t * (bb - a)
        ft = res(p, xt, b)
        if math.isnan(ft):
            return x
        if (ft > 0) == (fa > 0):
            cc, fcc = a, fa
        else:
            cc, fcc = bb, fb
            bb, fb = a, fa
        a, fa = xt, ft
        if abs(fa) < abs(fb):
            xm, fm = a, fa
        else:
            xm, fm = bb, fb
        x = xm
        tol = 2.0 * eps * abs(xm) + 0.5 * xtol
        width = abs(bb - cc)
        if fm == 0.0 or width == 0.0:
            return x
        tlim = tol / width
        if tlim > 0.5:
            return x
        xi = (a - bb) / (cc - bb) if cc != bb else 0.0
        denom1 = fcc - fb
        phi = (fa - fb) / denom1 if denom1 != 0.0 else 0.0
        t = 0.5
        if phi * phi < xi and (1.0 - phi) ** 2 < 1.0 - xi and fb != fa and fb != fcc and fcc != fa:
            t = fa / (fb - fa) * fcc / (fb - fcc) + (cc - a) / (bb - a) * fa / (fcc - fa) * fb / (fcc - fb)
        if t != t:
            t = 0.5
        t = min(max(t, tlim), 1.0 - tlim)
    return x


@inlined
def _small(res, p, x, b, noise):
    f = res(p, x, b)
    return (not math.isnan(f)) and abs(f) <= noise


@inlined
def _center_flat(res, p, x, b, noise, span, probes):
    """As numpy_sweep._Search._center_flat, for one root: (centre, lo, hi, is a family). ``probes (2,)``: the residual
    at ``x -+ FLAT_PROBE_REL * span`` where the root is not in a flat stretch (the first probes of
    ``_multiplicity``), else NaN."""
    d0 = FLAT_PROBE_REL * span
    probes[0] = probes[1] = np.nan
    f0 = res(p, x - d0, b)
    if not ((not math.isnan(f0)) and abs(f0) <= noise):
        f1 = res(p, x + d0, b)
        if not ((not math.isnan(f1)) and abs(f1) <= noise):
            probes[0], probes[1] = f0, f1
            return x, x, x, False
    limit = FLAT_MAX_REL * span
    in0, out0 = _flat_grow(res, p, x, b, noise, d0, limit, -1.0)
    in1, out1 = _flat_grow(res, p, x, b, noise, d0, limit, 1.0)
    short = out0 <= 0.5 * CLUSTER_FAMILY_REL * span and out1 <= 0.5 * CLUSTER_FAMILY_REL * span
    r0, open0 = _flat_end(res, p, x, b, noise, in0, out0, limit, -1.0, short)
    r1, open1 = _flat_end(res, p, x, b, noise, in1, out1, limit, 1.0, short)
    lo, hi = x - r0, x + r1
    family = open0 and open1 and hi - lo > CLUSTER_FAMILY_REL * span
    return 0.5 * (lo + hi), lo, hi, family


@inlined
def _flat_grow(res, p, x, b, noise, d0, limit, sgn):
    """(inner, outer): the residual is within the noise at x + sgn inner, not at x + sgn outer (doubling)."""
    inner, outer = 0.0, d0
    if _small(res, p, x + sgn * outer, b, noise):
        for _ in range(64):
            inner = outer
            if inner >= limit:
                break
            outer = min(2.0 * outer, limit)
            if not _small(res, p, x + sgn * outer, b, noise):
                break
    return inner, outer


@inlined
def _flat_end(res, p, x, b, noise, inner, outer, limit, sgn, short):
    """(reach, the stretch ends openly) on one side, as in numpy_sweep._Search._center_flat."""
    at_limit = inner >= limit
    for _ in range(FLAT_BISECT if outer > inner else 0):  # (at the reach limit: nothing to bisect)
        if short and outer - inner <= FLAT_SHORT_TOL * inner:
            break
        mid = 0.5 * (inner + outer)
        if _small(res, p, x + sgn * mid, b, noise):
            inner = mid
        else:
            outer = mid
    past = abs(res(p, x + sgn * outer, b))
    far = abs(res(p, x + 2.0 * sgn * outer, b))
    return inner, at_limit or not (past <= JUMP_NOISE * noise) or far <= 2.0 * noise


@inlined
def _multiplicity(res, p, x, b, noise, span, f_lo, f_hi):
    """As numpy_sweep._Search._multiplicity, for one root; ``f_lo, f_hi``: the residual at its first probes if known
    (``_center_flat``'s, the same points), else NaN."""
    level = MULT_LEVEL * noise
    limit = FLAT_MAX_REL * span
    total, count = 0.0, 0
    for side in range(2):
        sgn = -1.0 if side == 0 else 1.0
        d = FLAT_PROBE_REL * span
        known = f_lo if side == 0 else f_hi
        f1 = abs(known if not math.isnan(known) else res(p, x + sgn * d, b))
        for _ in range(64):
            if not (f1 < level and d < limit):
                break
            d *= 2.0
            f1 = abs(res(p, x + sgn * d, b))
        f2 = abs(res(p, x + 2.0 * sgn * d, b))
        if f1 >= level and f2 > 0.0 and not math.isnan(f2) and not math.isinf(f2):
            total += math.log2(f2 / f1)
            count += 1
    m = total / count if count > 0 else 1.0
    return int(min(max(round(m), 1), MULT_MAX))


@inlined
def _extend(res, p, b, inside, outside):
    for _ in range(FAMILY_BISECT):
        mid = 0.5 * (inside + outside)
        f = res(p, mid, b)
        if (not math.isnan(f)) and abs(f) <= FAMILY_TOL:
            inside = mid
        else:
            outside = mid
    return inside


@inlined
def _push(out_t, out_b, cnt, x, b):
    if cnt[0] < out_t.shape[0]:
        out_t[cnt[0]] = x
        out_b[cnt[0]] = b
    cnt[0] += 1


@internal
def _extremum(res, p, b, ta, tc, tb, fa, fc, fb, span, noise, xtol, out_t, out_b, cnt):
    xe = tc
    lo, hi = ta, tb
    for level in range(DIFF_LEVELS):  # as numpy_sweep._Search._extrema
        h = DIFF_STEP_REL * span / DIFF_SHRINK**level
        if level > 0:
            lo, hi = xe - 2.0 * DIFF_SHRINK * h, xe + 2.0 * DIFF_SHRINK * h
        a, c = lo + h, hi - h
        if not a < c:
            break
        ga = res(p, a + h, b) - res(p, a - h, b)
        gc = res(p, c + h, b) - res(p, c - h, b)
        if not ga * gc < 0:
            break
        # root of the central difference g(x) = f(x + h) - f(x - h)
        xe = _root_diff(res, p, b, a, c, ga, gc, h)
        if level == 0 and (1.0 if fc > 0 else -1.0) * res(p, xe, b) > FAR_NOISE * noise:
            return  # located far from zero on fc's side: neither root nor touching (settings.FAR_NOISE)
    fx = res(p, xe, b)
    if math.isnan(fx):
        return
    s = 1.0 if fc > 0 else -1.0
    if s * fx < -noise:
        _push(out_t, out_b, cnt, _root(res, p, b, ta, xe, fa, fx, xtol), b)
        _push(out_t, out_b, cnt, _root(res, p, b, xe, tb, fx, fb, xtol), b)
    elif abs(fx) <= FAR_NOISE * noise:
        _push(out_t, out_b, cnt, xe, b)


@inlined
def _inside(res, p, x, b, reach):
    """A margin's zero ``x`` (branch ``b``) on the margin's non-negative side: itself if it is there, else moved by
    the least of ``reach 2^-k`` (k = EDGE_NUDGES - 1 ... 0) that gets there, up first (as ``inside_zeros``
    does for the staged search); ``x`` where neither side is (a domain narrower than that), and where its margin is
    below ``-EDGE_MARGIN`` (no zero: a sample next to the margin's own NaN, a range end)."""
    m = res(p, x, b)
    if not (m < 0.0 and m >= -EDGE_MARGIN):  # (inside, or no edge: a sample next to the margin's own NaN)
        return x
    d = reach * 2.0 ** (1 - EDGE_NUDGES)
    for _ in range(EDGE_NUDGES):
        if res(p, x + d, b) >= 0.0:
            return x + d
        if res(p, x - d, b) >= 0.0:
            return x - d
        d *= 2.0
    return x


@inlined
def _g(res, p, x, b, h):
    return res(p, x + h, b) - res(p, x - h, b)


@internal
def _root_diff(res, p, b, a, c, ga, gc, h):
    """Root of the central difference between a and c (Illinois-safeguarded bisection)."""
    xtol = 1e-3 * h
    fa, fc = ga, gc
    side = 0
    x = 0.5 * (a + c)
    for _ in range(100):
        if c - a <= xtol:
            break
        x = (a * fc - c * fa) / (fc - fa) if fc != fa else 0.5 * (a + c)
        if not (a < x < c):
            x = 0.5 * (a + c)
        fx = _g(res, p, x, b, h)
        if fx != fx:
            break
        if fx == 0.0:
            return x
        if (fx > 0) == (fa > 0):
            a, fa = x, fx
            if side == -1:
                fc *= 0.5
            side = -1
        else:
            c, fc = x, fx
            if side == 1:
                fa *= 0.5
            side = 1
    return x


@inlined
def _edge_bent(res, p, b, th, f, valid, fmask, j, right, span, otherwise):
    """Level 0: whether interval j, next to one domain edge (on its ``right`` or left), is resampled, as
    ``numpy_sweep._Search._edge_at_sample``: where the edge sits at its open-side sample (the residual just past it is
    not finite), by the bend test in that edge's coordinate; elsewhere ``otherwise``."""
    M = th.shape[0]
    if right:
        e, n1, n2, side = j + 1, j, j - 1, 1.0
        masked = j + 2 < M and fmask[j + 2]
    else:
        e, n1, n2, side = j, j + 1, j + 2, -1.0
        masked = j >= 1 and fmask[j - 1]
    if masked or n2 < 0 or n2 >= M or not valid[n2]:
        return otherwise
    te = th[e]
    x1 = math.sqrt(abs(th[n1] - te))
    x2 = math.sqrt(abs(th[n2] - te))
    dd = 2.0 * ((f[n2] - f[n1]) / (x2 - x1) - (f[n1] - f[e]) / x1) / x2
    if not math.isfinite(dd) or math.isfinite(res(p, te + side * EDGE_PROBE_REL * span, b)):
        return otherwise
    low = min(abs(f[e]), abs(f[n1]))
    if low <= BEND * abs(dd) * x1 * x1 or abs(f[e]) <= EDGE_LOW * abs(f[n1]):
        return True
    # (a dip between them that the three samples do not show: the residual halfway in the edge's coordinate)
    return abs(res(p, te - side * 0.25 * x1 * x1, b)) < low


@inlined
def _dd(fa, fb, fc, hl, hr):
    """The second divided difference of three samples ``hl`` and ``hr`` apart (the scan's curvature, as the
    reference's ``numpy_sweep._Search.scan`` works it out)."""
    return 2.0 * ((fc - fb) / hr - (fb - fa) / hl) / (hl + hr)


@inlined
def _bends_later(f_all, th, later, j):
    """Level 0: some branch of ``later`` bends in interval j, away from a domain edge: the first level's bend test
    (``BEND``, in theta) on the residuals ``f_all`` of every branch (a forecast: the branch's own scan decides)."""
    M = th.shape[0]
    h = th[j + 1] - th[j]
    for bi in range(later.shape[0]):
        b = later[bi]
        f0, f1 = f_all[j, b], f_all[j + 1, b]
        if math.isnan(f0) or math.isnan(f1):
            continue
        curv = 0.0
        if j >= 1:
            fm = f_all[j - 1, b]
            if math.isnan(fm):
                continue
            hl, hr = th[j] - th[j - 1], h
            curv = abs(_dd(fm, f0, f1, hl, hr))
        if j + 2 < M:
            fp = f_all[j + 2, b]
            if math.isnan(fp):
                continue
            hl, hr = h, th[j + 2] - th[j + 1]
            curv = max(curv, abs(_dd(f0, f1, fp, hl, hr)))
        if min(abs(f0), abs(f1)) <= BEND * curv * h * h:
            return True
    return False


@inlined
def _extrema(res, p, b, th, f, level, ctx, span, noise, xtol, out_t, out_b, cnt):
    """``_scan``'s local minima of ``|f|`` without a sign change (the ends with their context ``ctx``), each
    looked at (``_extremum``) where it may touch zero."""
    M = th.shape[0]
    j0, j1 = (0, M) if level > 0 else (1, M - 1)
    for j in range(j0, j1):
        tm, fm = (th[j - 1], f[j - 1]) if j > 0 else (ctx[0], ctx[1])
        tp, fp = (th[j + 1], f[j + 1]) if j < M - 1 else (ctx[2], ctx[3])
        fc = f[j]
        # (the cheap tests first: a local minimum of |f| without a sign change is rare, its curvature dearer; a
        # NaN among the three fails them)
        if not (abs(fc) <= abs(fm) and abs(fc) <= abs(fp) and fm * fc > 0 and fc * fp > 0):
            continue
        hl, hr = th[j] - tm, tp - th[j]
        if not (hl > 0 and hr > 0):
            continue
        ddj = _dd(fm, fc, fp, hl, hr)
        if abs(fc) <= EXTREMUM_REACH * abs(ddj) * max(hl, hr) ** 2:  # (it may touch zero)
            _extremum(res, p, b, tm, th[j], tp, fm, fc, fp, span, noise, xtol, out_t, out_b, cnt)


@inlined
def _edge_samples(b, th, f, valid, level, fmask, noise, out_t, out_b, cnt):
    """``_scan``'s samples next to a domain edge (or at the range ends, level 0) that are candidates: near zero,
    or next to a family's samples (``fmask``: ``settings.FAR_NOISE``)."""
    M = th.shape[0]
    for j in range(M):
        if not valid[j]:
            continue
        lo_open = (j == 0 and level == 0) or (j > 0 and not valid[j - 1])
        hi_open = (j == M - 1 and level == 0) or (j < M - 1 and not valid[j + 1])
        if not (lo_open or hi_open):
            continue
        nr = abs(f[j + 1]) if (j < M - 1 and valid[j + 1]) else np.inf
        nl = abs(f[j - 1]) if (j > 0 and valid[j - 1]) else np.inf
        at_l = lo_open and abs(f[j]) <= nr
        at_r = hi_open and abs(f[j]) <= nl
        if not (at_l or at_r):
            continue
        if (
            abs(f[j]) <= FAR_NOISE * noise
            or (at_l and level == 0 and j > 0 and fmask[j - 1])
            or (at_r and level == 0 and j < M - 1 and fmask[j + 1])
        ):
            _push(out_t, out_b, cnt, th[j], b)


@inlined
def _hidden_edge(
    res, p, b, th, f, valid, j, level, el, er, ctx, span, noise, out_t, out_b, cnt, stk_t, stk_f, stk_i, stk_c, top,
    signed,
):  # pragma: no cover  # fmt: skip
    """``_scan``, a signed residual, below the last level: interval j has one sample in the branch's domain and one
    outside it (else nothing: a sample masked as a family's is not outside). A domain edge at the inside sample
    (the residual just past it not finite: a margin's zero, sampled) is already the scan's. Elsewhere the edge is
    hidden between the samples (a margin's pair of close zeros that the margins' sweep missed): it is located by
    bisection, is a candidate where the residual there is near zero and no larger than at the inside sample (as
    ``_edge_samples``: a least value; the C-Arm's stretched elbow at the rail's end has its double root at the
    inside sample and an edge 8e-4 mm on, where the residual is still near zero: a second candidate there was merged
    with the root into one 5e-5 mm off it), and the stretch from the
    inside sample to it is resampled as an interval next to an edge (a root beside the edge, or a pair of close ones,
    would otherwise go unsearched)."""
    if not (level < MAX_LEVELS and signed and valid[j] != valid[j + 1] and th[j + 1] > th[j]):
        return
    M = th.shape[0]
    right = valid[j]  # (the edge on the interval's right)
    inside, outside = (th[j], th[j + 1]) if right else (th[j + 1], th[j])
    side = 1.0 if right else -1.0
    if not math.isfinite(res(p, inside + side * EDGE_PROBE_REL * span, b)) or math.isfinite(res(p, outside, b)):
        return  # (the edge at the inside sample, as mostly; or a sample masked as a family's, not outside)
    while abs(outside - inside) > EDGE_PROBE_REL * span:
        mid = 0.5 * (inside + outside)
        if math.isfinite(res(p, mid, b)):
            inside = mid
        else:
            outside = mid
    fe = res(p, inside, b)
    a, fa = (th[j], f[j]) if right else (th[j + 1], f[j + 1])
    if abs(fe) <= FAR_NOISE * noise and abs(fe) <= abs(fa):  # (not where |f| grows towards it: beside a root)
        _push(out_t, out_b, cnt, inside, b)
    if top[0] >= stk_t.shape[0]:
        cnt[0] += out_t.shape[0] + 1  # overflow: the caller redoes this pose with larger buffers
        return
    k0 = top[0]
    lo, hi = (a, inside) if right else (inside, a)
    for k in range(SUB_SAMPLES + 2):
        stk_t[k0, k] = lo + (hi - lo) * _U_EDGE_ARR[k]
    stk_f[k0, 0], stk_f[k0, SUB_SAMPLES + 1] = (fa, fe) if right else (fe, fa)
    for k in range(1, SUB_SAMPLES + 1):
        stk_f[k0, k] = res(p, stk_t[k0, k], b)
    open_l = True if not right else (el if j == 0 else not valid[j - 1])
    open_r = True if right else (er if j + 1 == M - 1 else not valid[j + 2])
    stk_i[k0, 0], stk_i[k0, 1], stk_i[k0, 2] = level + 1, 1 if open_l else 0, 1 if open_r else 0
    if right:
        stk_c[k0, 0], stk_c[k0, 1] = (th[j - 1], f[j - 1]) if j >= 1 else (ctx[0], ctx[1])
        stk_c[k0, 2], stk_c[k0, 3] = th[j + 1], f[j + 1]
    else:
        stk_c[k0, 0], stk_c[k0, 1] = th[j], f[j]
        stk_c[k0, 2], stk_c[k0, 3] = (th[j + 2], f[j + 2]) if j + 2 <= M - 1 else (ctx[2], ctx[3])
    stk_c[k0, 4] = np.nan if open_l and open_r else inside
    top[0] += 1


@internal
def _scan(
    res, p, b, th, f, level, el, er, ctx, xe, span, noise, xtol, out_t, out_b, cnt, stk_t, stk_f, stk_i, stk_c, top,
    wv, wx, res_all, n_all, edge_f, edge_ok, fmask, f_all, later, signed,
):  # fmt: skip
    """One sequence; intervals to resample go on the stack (Numba's cache holds no recursive function). ``ctx``: (theta,
    f) left and right of it, ``xe``: the edge whose coordinate judges curvature (NaN: theta), ``fmask``: samples masked
    as a family's (level 0); ``signed``: not the pose error's norm (``PoseErrorResidual``: an edge at a sample judged as
    any other). Level 0: ``f_all`` its residuals on every branch, ``later`` the branches searched after this one;
    ``edge_f``, ``edge_ok`` the all-branch sub-samples of its intervals (next to an edge, then not), which are known."""
    M = th.shape[0]
    valid = wv[:M]  # work arrays of the pose (no allocation per sequence)
    for j in range(M):  # (and the samples on a root: the ends of a resampled interval are its parent's)
        v = not math.isnan(f[j])
        valid[j] = v
        if v and abs(f[j]) <= noise and (level == 0 or 0 < j < M - 1):
            _push(out_t, out_b, cnt, th[j], b)
    _extrema(res, p, b, th, f, level, ctx, span, noise, xtol, out_t, out_b, cnt)
    _edge_samples(b, th, f, valid, level, fmask, noise, out_t, out_b, cnt)
    # second divided differences (dd), in theta or in sqrt(|theta - xe|) (numpy_sweep._edge_coordinate), worked out
    # as the intervals are walked: c1, c2 at the interval's samples (NaN at the ends and next to a NaN sample)
    x = th if math.isnan(xe) else wx[:M]
    if not math.isnan(xe):
        for j in range(M):
            x[j] = math.sqrt(abs(th[j] - xe))
    c2 = np.nan
    for j in range(M - 1):
        c1 = c2
        c2 = np.nan
        if j + 2 < M and valid[j] and valid[j + 1] and valid[j + 2]:
            hl = x[j + 1] - x[j]
            hr = x[j + 2] - x[j + 1]
            if hl != 0.0 and hr != 0.0:  # (decreasing where the edge is on the right: same dd)
                c2 = _dd(f[j], f[j + 1], f[j + 2], hl, hr)
        if not (valid[j] and valid[j + 1] and th[j + 1] > th[j]):
            _hidden_edge(res, p, b, th, f, valid, j, level, el, er, ctx, span, noise, out_t, out_b, cnt, stk_t, stk_f,
                         stk_i, stk_c, top, signed)  # fmt: skip
            continue
        prod = f[j] * f[j + 1]
        refine = False
        open_l = el if j == 0 else not valid[j - 1]
        open_r = er if j + 1 == M - 1 else not valid[j + 2]
        near_edge = open_l or open_r
        if level < MAX_LEVELS and abs(f[j]) + abs(f[j + 1]) > 0:
            curv = np.nan
            if not math.isnan(c1):
                curv = abs(c1)
            if not math.isnan(c2) and (math.isnan(curv) or abs(c2) > curv):
                curv = abs(c2)
            h = x[j + 1] - x[j]
            lowest = min(abs(f[j]), abs(f[j + 1]))
            bend = (not math.isnan(curv)) and lowest <= BEND * curv * h * h
            own_edge = (open_l and th[j] == xe and not open_r) or (open_r and th[j + 1] == xe and not open_l)
            refine = bend or (near_edge and not own_edge)
            if level == 0 and open_l != open_r and signed:  # (one edge: at a sample, judged in its coordinate)
                refine = _edge_bent(res, p, b, th, f, valid, fmask, j, open_r, span, refine)
        if refine:
            if top[0] >= stk_t.shape[0]:
                cnt[0] += out_t.shape[0] + 1  # overflow: the caller redoes this pose with larger buffers
                continue
            us = _U_EDGE_ARR if near_edge else _U_UNIFORM_ARR
            k0 = top[0]
            for k in range(SUB_SAMPLES + 2):
                stk_t[k0, k] = th[j] + (th[j + 1] - th[j]) * us[k]
            stk_f[k0, 0] = f[j]
            stk_f[k0, SUB_SAMPLES + 1] = f[j + 1]
            # the uniform grid is every branch's, and a domain edge is usually every branch's too: the sub-samples
            # of an interval next to one are evaluated for all branches at once (the same values); so are those of
            # an interval that a branch still to come bends in too (the all-branch kernel costs less than two)
            s = 0 if near_edge else 1
            if level == 0 and n_all > 0 and (near_edge or edge_ok[1, j] or _bends_later(f_all, th, later, j)):
                if not edge_ok[s, j]:
                    for k in range(1, SUB_SAMPLES + 1):
                        res_all(p, stk_t[k0, k], edge_f[s, j, k])
                    edge_ok[s, j] = True
                for k in range(1, SUB_SAMPLES + 1):
                    stk_f[k0, k] = edge_f[s, j, k, b]
            else:
                for k in range(1, SUB_SAMPLES + 1):
                    stk_f[k0, k] = res(p, stk_t[k0, k], b)
            stk_i[k0, 0] = level + 1
            stk_i[k0, 1] = 1 if open_l else 0
            stk_i[k0, 2] = 1 if open_r else 0
            if j >= 1:
                stk_c[k0, 0], stk_c[k0, 1] = th[j - 1], f[j - 1]
            else:
                stk_c[k0, 0], stk_c[k0, 1] = ctx[0], ctx[1]
            if j + 2 <= M - 1:
                stk_c[k0, 2], stk_c[k0, 3] = th[j + 2], f[j + 2]
            else:
                stk_c[k0, 2], stk_c[k0, 3] = ctx[2], ctx[3]
            if open_l and not open_r:
                stk_c[k0, 4] = th[j]
            elif open_r and not open_l:
                stk_c[k0, 4] = th[j + 1]
            else:
                stk_c[k0, 4] = np.nan if open_l else xe
            top[0] += 1
        elif prod < 0:
            _push(out_t, out_b, cnt, _root(res, p, b, th[j], th[j + 1], f[j], f[j + 1], xtol), b)


@inlined
def _sort_pairs(keys, values, carried, n):
    """The first ``n`` pairs ``(keys[k], values[k])`` sorted in place, by key, then by value, rows ``carried[k]``
    moving with them (insertion sort: a pose has a few dozen candidates at most; ``values`` are never NaN)."""
    for a in range(1, n):
        kk, vv = keys[a], values[a]
        c0, c1 = carried[a, 0], carried[a, 1]
        m = a - 1
        while m >= 0 and (keys[m] > kk or (keys[m] == kk and values[m] > vv)):
            keys[m + 1] = keys[m]
            values[m + 1] = values[m]
            carried[m + 1, 0] = carried[m, 0]
            carried[m + 1, 1] = carried[m, 1]
            m -= 1
        keys[m + 1] = kk
        values[m + 1] = vv
        carried[m + 1, 0] = c0
        carried[m + 1, 1] = c1


@inlined
def _all_branch_samples(res_all, p, th, n_all, known, known_at, row, f_all):
    """Every branch's residual ``f_all[j]`` at the samples ``th`` of a pose (row ``row`` of the part), from
    ``known`` where the caller has it (``_search``)."""
    for j in range(th.shape[0]):
        k = known_at[row, j] if known.shape[0] > 0 else -1
        if k >= 0:
            for b in range(n_all):
                f_all[j, b] = known[row, k, b]
        else:
            res_all(p, th[j], f_all[j])


@inlined
def _family_runs(res, p, b, th, f, fm, span, fam, fcnt, i):
    """Runs of vanishing samples ``f`` of branch ``b``: family spans of pose ``i`` (``fam[i]``, counted in
    ``fcnt[i]``, past the buffer's size too: an overflow), their samples made NaN in ``f`` and marked in ``fm``
    (a short run of coinciding samples is left to the scan: one root)."""
    M = th.shape[0]
    j = 0
    while j < M:
        if not math.isnan(f[j]) and abs(f[j]) <= FAMILY_TOL:
            k = j
            while k + 1 < M and not math.isnan(f[k + 1]) and abs(f[k + 1]) <= FAMILY_TOL:
                k += 1
            if k - j + 1 >= FAMILY_MIN_RUN and th[k] - th[j] > CLUSTER_FAMILY_REL * span:
                if fcnt[i] < fam.shape[1]:
                    lo, hi = th[j], th[k]
                    if j > 0:
                        lo = _extend(res, p, b, lo, th[j - 1])
                    if k + 1 < M:
                        hi = _extend(res, p, b, hi, th[k + 1])
                    fam[i, fcnt[i], 0] = lo
                    fam[i, fcnt[i], 1] = hi
                    fam[i, fcnt[i], 2] = b
                fcnt[i] += 1
                for m in range(j, k + 1):
                    f[m] = np.nan
                    fm[m] = True
            j = k + 1
        else:
            j += 1


@inlined
def _masked(th, f, fm, masks, b):
    """The samples ``th`` of branch ``b`` inside a stretch of ``masks (K, 3)`` (lo, hi, branch) made NaN in ``f``
    and marked in ``fm``, as a family's run is (``_family_runs``)."""
    for k in range(masks.shape[0]):
        if masks[k, 2] == b:
            for j in range(th.shape[0]):
                if masks[k, 0] <= th[j] <= masks[k, 1]:
                    f[j] = np.nan
                    fm[j] = True


@inlined
def _centred(res, p, ts, bs, n0, noise, span, probes, fam, fcnt, i):
    """The first ``n0`` candidates ``(ts, bs)`` of pose ``i`` centred on their flat stretch (``_center_flat``), or
    set apart as a family (``fam[i]``, ``fcnt[i]``); the others moved down. Returns how many stay (``probes[w]``:
    candidate w's probes, written whether or not it is kept)."""
    w0 = 0
    for k in range(n0):
        x, lo, hi, family = _center_flat(res, p, ts[k], bs[k], noise, span, probes[w0])
        if family:
            if fcnt[i] < fam.shape[1]:
                fam[i, fcnt[i], 0] = lo
                fam[i, fcnt[i], 1] = hi
                fam[i, fcnt[i], 2] = bs[k]
            fcnt[i] += 1
        else:
            ts[w0] = x
            bs[w0] = bs[k]
            w0 += 1
    return w0


@inlined
def _merged_clusters(res, p, ts, bs, n, noise, probes):
    """The first ``n`` candidates ``(ts, bs)`` sorted by branch, then theta, and each noise-level cluster of a
    branch merged into its centre (families were set apart: a cluster is one root), in place. Returns how many
    stay."""
    _sort_pairs(bs, ts, probes, n)
    w = 0  # (written in place: w <= s, and only entries from s on are read after a write)
    s = 0
    while s < n:
        e = s
        while (
            e + 1 < n
            and bs[e + 1] == bs[s]
            and (ts[e + 1] == ts[e] or abs(res(p, 0.5 * (ts[e] + ts[e + 1]), bs[s])) <= noise)
        ):
            e += 1
        ts[w] = 0.5 * (ts[s] + ts[e])
        bs[w] = bs[s]
        # (a cluster's centre is a new point: its probes are not known)
        probes[w, 0] = probes[s, 0] if e == s else np.nan
        probes[w, 1] = probes[s, 1] if e == s else np.nan
        w += 1
        s = e + 1
    return w


@inlined
def _scan_arrays(M, K):
    """``_search``'s work arrays for ``_scan`` (the most samples of a pose: ``M``; ``K`` candidates a pose): the
    candidate count, the stack of intervals to resample (theta, f, level and open ends, context; ``STACK`` deep,
    ``REDO_GROW`` times deeper with larger buffers: ``search``'s redo of a pose that overflowed), an empty
    context, the validity and edge coordinates of a sequence. Explicit loops rather than np.zeros, np.full, slice
    copies or np.argsort: each of those adds to the first compilation (docs/performance.md)."""
    c = np.empty(1, dtype=np.int64)
    depth = STACK * min(max(1, K // MAX_CAND), REDO_GROW)
    stk_t = np.empty((depth, SUB_SAMPLES + 2))
    stk_f = np.empty((depth, SUB_SAMPLES + 2))
    stk_i = np.empty((depth, 3), dtype=np.int64)
    stk_c = np.empty((depth, 5))
    no_ctx = np.empty(4)
    for k in range(4):
        no_ctx[k] = np.nan
    W = M if M > SUB_SAMPLES + 2 else SUB_SAMPLES + 2
    return c, stk_t, stk_f, stk_i, stk_c, no_ctx, np.empty(W, dtype=np.bool_), np.empty(W)


@inlined
def _pose_arrays(M, n_all, K):
    """``_search``'s work arrays for a pose (``M`` samples at most, ``n_all`` branches in the all-branch residual,
    ``K`` candidates): an interval popped from the stack (theta, f, context), the all-branch residuals of the
    samples and of the sub-samples of level-0 intervals (``_scan``) with which of those are known, one branch's
    residuals, the stack's top, the candidates' probes, the samples masked as a family's."""
    nb_all = n_all if n_all > 1 else 1
    buf_t, buf_f, buf_c = np.empty(SUB_SAMPLES + 2), np.empty(SUB_SAMPLES + 2), np.empty(4)
    f_all, edge_f = np.empty((M, nb_all)), np.empty((2, M, SUB_SAMPLES + 1, nb_all))
    edge_ok, f, top = np.empty((2, M), dtype=np.bool_), np.empty(M), np.empty(1, dtype=np.int64)
    return buf_t, buf_f, buf_c, f_all, edge_f, edge_ok, f, top, np.empty((K, 2)), np.empty(M, dtype=np.bool_)


@inlined
def _settled_candidates(res, p, i, c, noise, span, probes, out_t, out_b, out_m, cnt, fam, fcnt, multiplicity):
    """Pose ``i``'s ``c[0]`` candidates (none overflowed) centred on their flat stretches or set apart as families
    (``_centred``), noise-level clusters of a branch merged (``_merged_clusters``: sorted by branch, then theta),
    and each one's multiplicity (1 without ``multiplicity``); ``cnt[i]``: how many stay."""
    c[0] = _centred(res, p, out_t[i], out_b[i], c[0], noise, span, probes, fam, fcnt, i)
    cnt[i] = c[0]
    if c[0] > 1:
        cnt[i] = _merged_clusters(res, p, out_t[i], out_b[i], c[0], noise, probes)
    for k in range(cnt[i]):
        if multiplicity:
            out_m[i, k] = _multiplicity(res, p, out_t[i, k], out_b[i, k], noise, span, probes[k, 0], probes[k, 1])
        else:
            out_m[i, k] = 1


_U_UNIFORM_ARR = U_UNIFORM.copy()
_U_EDGE_ARR = U_EDGE.copy()

#: The engine's entry signature: the residual enters as the address of a compiled function
#: (``kernels.address_of``), so the engine is compiled once (and cached) for every reduction.
_SEARCH_SIG = (
    int64,
    int64,
    int64,
    float64[:, ::1],
    float64[:, ::1],
    int64[::1],
    int64[::1],
    float64[::1],
    float64,
    float64[:, ::1],
    int64[:, ::1],
    int64[:, ::1],
    int64[::1],
    float64[:, :, ::1],
    int64[::1],
    boolean,
    float64[:, :, ::1],
    int64[:, ::1],
    float64[:, :, ::1],
    int64[::1],
    boolean,
    int64,
    int64,
)


@lazy_njit(_SEARCH_SIG, cache=True, nogil=True)
def _search(
    res, res_all, n_all, params, grid, n_grid, branches, span, noise, out_t, out_b, out_m, cnt, fam, fcnt,
    multiplicity, known, known_at, masks, n_masks, signed, start, stop,
):  # fmt: skip
    """Poses ``start .. stop - 1`` (threads run parts of a batch side by side: :mod:`sweepik.engine.parallel`),
    pose i's samples the first ``n_grid[i]`` of ``grid[i]`` (``sample_grid``); ``multiplicity`` False: every
    candidate's is given as 1, not worked out (``search``).
    ``res_all``: every branch's residual at once (``Reduction.kernel_residuals``), used for the uniform samples
    when ``n_all`` (the number of branches it fills) is not 0. ``known (N, K, n_all)``: all-branch residuals the
    caller has already, sample j of pose i being ``known[i, known_at[i, j]]`` where that is not -1 (no rows:
    none). ``masks (N, K, 3)``: stretches ``(lo, hi, branch)`` of theta* whose samples pose i leaves out of its
    search as a family's (its first ``n_masks[i]``; no rows: none): the continua traced already
    (:mod:`sweepik.engine.rough_continua`). ``signed`` False: the residual is a pose error (``_scan``).

    One function, not a loop calling a function per pose: Numba re-optimises everything a compiled function calls
    when it compiles the caller, and each level costs seconds on a fresh install."""
    res, res_all = as_residual(res), as_residuals(res_all)
    # the arguments as views Numba does not reference-count: each kernel call would count them up and down
    params, grid, out_t, out_b, out_m = (
        unowned(params),
        unowned(grid),
        unowned(out_t),
        unowned(out_b),
        unowned(out_m),
    )
    cnt, fam, fcnt, span = unowned(cnt), unowned(fam), unowned(fcnt), unowned(span)
    # work arrays, shared by the poses (each pose sets what it reads)
    own_c, own_stk_t, own_stk_f, own_stk_i, own_stk_c, own_no_ctx, own_wv, own_wx = _scan_arrays(
        grid.shape[1], out_t.shape[1]
    )
    own_buf_t, own_buf_f, own_buf_c, own_f_all, own_edge_f, own_edge_ok, own_f, own_top, own_probes, own_fm = (
        _pose_arrays(grid.shape[1], n_all, out_t.shape[1])
    )
    # ... and the work arrays too (their owners are used at the end, ``alive``: they outlive the views)
    c, stk_t, stk_f, stk_i = unowned(own_c), unowned(own_stk_t), unowned(own_stk_f), unowned(own_stk_i)
    stk_c, no_ctx, wv, wx = unowned(own_stk_c), unowned(own_no_ctx), unowned(own_wv), unowned(own_wx)
    buf_t, buf_f, buf_c = unowned(own_buf_t), unowned(own_buf_f), unowned(own_buf_c)
    f_all, edge_f, edge_ok, f = unowned(own_f_all), unowned(own_edge_f), unowned(own_edge_ok), unowned(own_f)
    top, probes, fm = unowned(own_top), unowned(own_probes), unowned(own_fm)
    for i in range(start, stop):
        p = params[i]
        M = n_grid[i]
        th = grid[i, :M]
        xtol = XTOL_REL * span[i]
        c[0] = 0
        for j in range(M):
            edge_ok[0, j] = False
            edge_ok[1, j] = False
        if n_all > 0:
            _all_branch_samples(res_all, p, th, n_all, known, known_at, i, f_all)
        for bi in range(branches.shape[0]):
            if c[0] > out_t.shape[1] or fcnt[i] > fam.shape[1]:  # (overflowed: redone with larger buffers)
                break
            b = branches[bi]
            for j in range(M):
                f[j] = f_all[j, b] if n_all > 0 else res(p, th[j], b)
                fm[j] = False
            _family_runs(res, p, b, th, f, fm, span[i], fam, fcnt, i)
            if masks.shape[0] > 0:
                _masked(th, f, fm, masks[i, : n_masks[i]], b)
            top[0] = 0
            # the sequence itself, then the resampled intervals it (and they) push on the stack
            # level 0, not open at either end: read from ``top`` rather than written as constants (Numba would
            # compile _scan once more for the literal types of 0 and False)
            level = top[0]
            el = er = level > 0
            seq_t, seq_f, ctx, xe = th, f[:M], no_ctx, np.nan
            while True:
                _scan(res, p, b, seq_t, seq_f, level, el, er, ctx, xe, span[i], noise, xtol, out_t[i], out_b[i],
                      c, stk_t, stk_f, stk_i, stk_c, top, wv, wx, res_all, n_all, edge_f, edge_ok,
                      fm, f_all, branches[bi + 1 :], signed)  # fmt: skip
                if top[0] == 0 or c[0] > out_t.shape[1]:
                    break
                top[0] -= 1
                k0 = top[0]
                for k in range(SUB_SAMPLES + 2):  # copied: the scan pushes its own intervals from k0 on
                    buf_t[k] = stk_t[k0, k]
                    buf_f[k] = stk_f[k0, k]
                for k in range(4):
                    buf_c[k] = stk_c[k0, k]
                seq_t, seq_f, ctx, xe = buf_t, buf_f, buf_c, stk_c[k0, 4]
                level, el, er = stk_i[k0, 0], stk_i[k0, 1] == 1, stk_i[k0, 2] == 1
        cnt[i] = c[0]
        if c[0] <= out_t.shape[1] and fcnt[i] <= fam.shape[1]:
            _settled_candidates(res, p, i, c, noise, span[i], probes, out_t, out_b, out_m, cnt, fam, fcnt, multiplicity)
    alive(own_c, own_stk_t, own_stk_f, own_stk_i, own_stk_c, own_no_ctx, own_wv, own_wx)
    alive(own_buf_t, own_buf_f, own_buf_c, own_f_all, own_edge_f, own_edge_ok, own_f, own_top, own_probes, own_fm)


@lazy_njit(RESIDUALS_SIG, cache=True)
def _no_residuals(params, theta, out):  # pragma: no cover - never called (n_all = 0)
    pass


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _merge_grid(lo, hi, s, hints, out, count, start, stop):
    """``candidates.merge_grid`` for poses ``start .. stop - 1`` into ``out (N, n + H)`` and ``count (N,)``,
    element by element (the same arithmetic), but for the NaN hints: none of a pose's samples (see
    ``sample_grid``)."""
    for i in range(start, stop):
        count[i] = _merge_row(lo[i], hi[i], s, hints[i], out[i], True)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _hinted_grid(hints, params, ends, periodic, lo, hi, s, out, start, stop):
    """``sample_grid`` for poses ``start .. stop - 1`` of a reduction with a hints kernel (its address
    ``hints``): the pose's hints, then ``ends`` (theta*'s limits, for a non-periodic theta*), wrapped into
    [-pi, pi] for a periodic one, as ``candidates.grid_hints``; merged as ``candidates.merge_grid`` (a kernel
    writes as
    many hints for every pose: a NaN one is a spare sample, as in the reference)."""
    fn = as_hints(hints)
    H = out.shape[1] - s.shape[0]
    nh = H - ends.shape[0]
    row = np.empty(H)
    for i in range(start, stop):
        fn(params[i], row[:nh])
        for k in range(ends.shape[0]):
            row[nh + k] = ends[k]
        if periodic:
            for k in range(H):
                row[k] = wrap_pi(row[k])
        _merge_row(lo[i], hi[i], s, row, out[i], False)


@internal
def _merge_row(a, b, s, hints, g, drop_nan):
    """One pose's samples ``g (n + H,)`` on ``[a, b]``: the unit grid ``s (n,)`` and the hints ``(H,)`` inside
    it (else a spare midpoint; none for a NaN hint with ``drop_nan``), sorted, runs of equal samples spread.
    Returns their number; the row's entries past it are NaN. The hints are few, so an insertion sort of the
    row, whose uniform part is sorted already, costs little."""
    n, H = s.shape[0], hints.shape[0]
    w = b - a
    for k in range(n):
        g[k] = a + w * s[k]
    M = n
    for k in range(H):
        h = hints[k]
        if drop_nan and math.isnan(h):
            continue
        # (the spare's place from the hint's rank among the pose's own, as the reference's for the pose alone)
        g[M] = h if (math.isfinite(h) and h >= a and h <= b) else a + w * ((M - n + 0.5) / (n - 1))
        M += 1
    for m in range(M, n + H):
        g[m] = np.nan
    for m in range(n, M):
        v = g[m]
        j = m - 1
        while j >= 0 and g[j] > v:
            g[j + 1] = g[j]
            j -= 1
        g[j + 1] = v
    # runs of equal samples spread towards the next distinct one
    m = 1
    while m < M:
        if g[m] > g[m - 1]:
            m += 1
            continue
        s0 = m - 1
        e0 = m
        while e0 < M and not g[e0] > g[e0 - 1]:
            e0 += 1
        if e0 < M:
            base = g[s0]
            for j in range(m, e0):
                g[j] = base + (g[e0] - base) * (j - s0) / (e0 - s0)
        m = e0 + 1
    return M


#: ``_search`` called from compiled code, by its address (``kernels.address_of``: not linked in, so that the
#: one-pass kernels compile in a second rather than recompiling the search).
_SEARCH_FN_SIG = _void(*_SEARCH_SIG)
_as_search = function_at(_SEARCH_FN_SIG)
#: The one-pass kernels' plan: the addresses and counts they take as one array (a Python call costs per argument).
(_E_SEARCH, _E_RES, _E_RES_ALL, _E_N_ALL, _E_MARGIN, _E_MARGINS, _E_M_ALL, _E_SWING, _E_AMP, _E_AMPS, _E_N_SWING,
 _E_N, _E_PERIODIC, _E_MULT, _E_HINTS, _E_N_HINTS, _E_EVERY, _E_SIZE) = range(18)  # fmt: skip
#: ``(plan, branches, margin branches, steps, noise, params, hlo, hhi, lo, hi, unit grid, ends, twins, out_t,
#: out_b, out_m, cnt, fam, fcnt, redo, start, stop)``: both one-pass kernels' (each ignores what it does not use).
_ONE_PASS_SIG = (
    int64[::1],
    int64[::1],
    int64[::1],
    int64[::1],
    float64[::1],
    float64[:, ::1],
    float64[::1],
    float64[::1],
    float64[::1],
    float64[::1],
    float64[::1],
    float64[::1],
    int64[:, ::1],
    float64[:, ::1],
    int64[:, ::1],
    int64[:, ::1],
    int64[::1],
    float64[:, :, ::1],
    int64[::1],
    boolean[::1],
    int64,
    int64,
)


@inlined
def _pose_search(
    se, res, res_all, n_all, branches, noise, mult, params, grid, M, n_grid, span, width, out_t, out_b, out_m,
    cnt, fam, fcnt, i, known, known_at,
):  # fmt: skip
    """``_search`` of pose ``i`` alone (its rows of the arrays, as arrays of one row) on the first ``M`` samples
    of ``grid``, over a range ``width`` wide (``n_grid``, ``span``: the caller's work arrays of one; ``known``,
    ``known_at``: the pose's, as ``_search`` takes them)."""
    n_grid[0] = M
    span[0] = width
    fcnt[i] = 0
    se(res, res_all, n_all, params[i : i + 1], grid[:M].reshape((1, M)), n_grid, branches, span, noise,
       out_t[i : i + 1], out_b[i : i + 1], out_m[i : i + 1], cnt[i : i + 1], fam[i : i + 1], fcnt[i : i + 1], mult,
       known, known_at, np.empty((0, 0, 3)), np.empty(0, dtype=np.int64), True, 0, 1)  # fmt: skip


@inlined
def _known_at(grid, M, a, b, s, known_at):
    """``known_at[0, j]`` for the first ``M`` samples of ``grid``: k where sample j is the uniform grid's sample
    ``a + (b - a) s[k]`` (the same float: ``_merge_row``'s), else -1 (a hint, or a sample a run of equal ones
    moved). Both are sorted."""
    w = b - a
    k = 0
    for j in range(M):
        known_at[0, j] = -1
        while k < s.shape[0] and a + w * s[k] < grid[j]:
            k += 1
        if k < s.shape[0] and a + w * s[k] == grid[j]:
            known_at[0, j] = k
            k += 1


@inlined
def _add_swings(row, k, swings):
    """The swing samples ``swings[0]`` after the first ``k`` samples of ``row``, but the NaN ones (which add no
    sample, see ``sample_grid``): their new number."""
    for j in range(swings.shape[1]):
        if not math.isnan(swings[0, j]):
            row[k] = swings[0, j]
            k += 1
    return k


@inlined
def _with_ends(row, k, ends, periodic, start):
    """theta*'s ``ends`` after the first ``k`` samples of ``row``, and those from ``start`` on (the first: margins'
    zeros, wrapped already) wrapped into [-pi, pi] for a periodic theta*, as ``candidates.grid_hints`` gives
    them: their new number."""
    for j in range(ends.shape[0]):
        row[k] = ends[j]
        k += 1
    if periodic:
        for j in range(start, k):
            row[j] = wrap_pi(row[j])
    return k


@inlined
def _twin_copies(out_t, out_b, out_m, cnt, i, twins):
    """Pose ``i``'s candidates on the first branch of a class of twins, copied to the class's other branches
    after its own, class member by member (``twins``: ``candidates.twin_maps``), as ``candidates.twin_candidates``
    copies
    them; its count runs past the buffer if they do not fit (the pose is then redone)."""
    n0 = cnt[i]
    if n0 > out_t.shape[1]:
        return
    w = n0
    for d in range(twins.shape[0]):
        for k in range(n0):
            t = twins[d, out_b[i, k]]
            if t >= 0:
                if w < out_t.shape[1]:
                    out_t[i, w] = out_t[i, k]
                    out_b[i, w] = t
                    out_m[i, w] = out_m[i, k]
                w += 1
    cnt[i] = w


@lazy_njit(_ONE_PASS_SIG, cache=True, nogil=True)
def _edge_search(
    plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, out_t, out_b, out_m, cnt,
    fam, fcnt, redo, start, stop,
):  # fmt: skip
    """``search`` of poses ``start .. stop - 1`` for a reduction with an ``EdgeSearch``, each pose in one pass:
    its swing samples, the margins' search over ``[hlo, hhi]`` sampled with them, then its own search over
    ``[lo, hi]`` sampled with the margins' zeros and the swing samples, as ``sample_hints`` and ``sample_grid``
    give them (the same samples in the same order, so the same candidates bit for bit). With an
    ``EdgeSearch.every`` kernel, the uniform grid's samples, which the margins' search and (over the same range)
    its own search both take, are evaluated once for the two, by that kernel: the same values.
    ``plan``: the addresses and counts (``_E_*``); ``noise``: the search's residual noise and the margins';
    ``twins``: the candidates' copies to make (``_twin_copies``). A pose whose margins overflow the buffers is
    marked in ``redo`` (its count 0), for ``search`` to redo with larger buffers."""
    se, sw, margin = _as_search(plan[_E_SEARCH]), as_swing(plan[_E_SWING]), as_residual(plan[_E_MARGIN])
    n_swing, n, periodic = plan[_E_N_SWING], plan[_E_N], plan[_E_PERIODIC] != 0
    n_s, n_e, n_c = s.shape[0], ends.shape[0], out_t.shape[1]
    n_all = plan[_E_N_ALL]
    swings = np.empty((1, n_swing))
    row = np.empty(n_c + n_swing + n_e)
    grid = np.empty(n_s + n_c + n_swing + n_e)
    n_grid = np.empty(1, dtype=np.int64)
    span = np.empty(1)
    # the uniform samples' residuals and margins (``EdgeSearch.every``; none: P = 0)
    P = 1 if plan[_E_EVERY] != 0 else 0
    every = as_residuals(plan[_E_EVERY] if P else plan[_E_RES_ALL])
    shared = np.empty(n_all + 3)
    known_r = np.empty((P, n_s, n_all))
    known_m = np.empty((P, n_s, 3))
    known_at = np.empty((1, grid.shape[0]), dtype=np.int64)
    for i in range(start, stop):
        redo[i] = False
        for k in range(n_swing):
            swings[0, k] = np.nan
        sw(plan[_E_AMP], plan[_E_AMPS], params[i : i + 1], hlo[i : i + 1], hhi[i : i + 1], n, periodic, steps,
           swings, 0, 1)  # fmt: skip
        for k in range(n_s if P else 0):  # (the margins' uniform samples, as ``_merge_row`` places them)
            every(params[i], hlo[i] + (hhi[i] - hlo[i]) * s[k], shared)
            for b in range(n_all):
                known_r[0, k, b] = shared[b]
            for m in range(3):
                known_m[0, k, m] = shared[n_all + m]
        # the margins' samples: the swing samples and theta*'s ends (``grid_hints`` of the margins)
        k = _with_ends(row, _add_swings(row, 0, swings), ends, periodic, 0)
        M = _merge_row(hlo[i], hhi[i], s, row[:k], grid, True)
        if P:
            _known_at(grid, M, hlo[i], hhi[i], s, known_at)
        _pose_search(se, plan[_E_MARGIN], plan[_E_MARGINS], plan[_E_M_ALL], m_branches, noise[1], False, params,
                     grid, M, n_grid, span, hhi[i] - hlo[i], out_t, out_b, out_m, cnt, fam, fcnt, i, known_m,
                     known_at)  # fmt: skip
        if cnt[i] > n_c or fcnt[i] > fam.shape[1]:
            redo[i] = True
            cnt[i] = 0
            fcnt[i] = 0
            continue
        # its own samples: the margins' zeros (inside their domains), the swing samples, theta*'s ends
        # (``sample_hints``, ``grid_hints``)
        reach = EDGE_PROBE_REL * (hhi[i] - hlo[i])
        for j in range(cnt[i]):
            t = wrap_pi(out_t[i, j]) if periodic else out_t[i, j]
            row[j] = _inside(margin, params[i], t, out_b[i, j], reach)
        k = _with_ends(row, _add_swings(row, cnt[i], swings), ends, periodic, cnt[i])
        M = _merge_row(lo[i], hi[i], s, row[:k], grid, True)
        same = P != 0 and lo[i] == hlo[i] and hi[i] == hhi[i]  # (the uniform samples the margins' search had)
        if same:
            _known_at(grid, M, lo[i], hi[i], s, known_at)
        _pose_search(se, plan[_E_RES], plan[_E_RES_ALL], n_all, branches, noise[0], plan[_E_MULT] != 0,
                     params, grid, M, n_grid, span, hi[i] - lo[i], out_t, out_b, out_m, cnt, fam, fcnt, i,
                     known_r if same else known_r[:0], known_at)  # fmt: skip
        _twin_copies(out_t, out_b, out_m, cnt, i, twins)


@lazy_njit(_ONE_PASS_SIG, cache=True, nogil=True)
def _hinted_search(
    plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, out_t, out_b, out_m, cnt,
    fam, fcnt, redo, start, stop,
):  # fmt: skip
    """``search`` of poses ``start .. stop - 1`` for a reduction with a hints kernel (``Reduction.kernel_hints``),
    each pose in one pass: its samples as ``_hinted_grid`` gives them, then its search (``plan[_E_HINTS]``: the
    hints kernel's address, ``plan[_E_N_HINTS]`` the hints it writes; ``m_branches``, ``steps``, ``hlo``, ``hhi``
    unused; ``twins`` as for ``_edge_search``). Nothing overflows here that the engine could redo: ``redo`` is
    all False."""
    se, fn = _as_search(plan[_E_SEARCH]), as_hints(plan[_E_HINTS])
    nh, n_e, periodic = plan[_E_N_HINTS], ends.shape[0], plan[_E_PERIODIC] != 0
    row = np.empty(nh + n_e)
    grid = np.empty(s.shape[0] + nh + n_e)
    n_grid = np.empty(1, dtype=np.int64)
    span = np.empty(1)
    no_known, no_known_at = np.empty((0, 0, 1)), np.empty((0, 0), dtype=np.int64)
    for i in range(start, stop):
        redo[i] = False
        fn(params[i], row[:nh])
        _with_ends(row, nh, ends, periodic, 0)
        M = _merge_row(lo[i], hi[i], s, row, grid, False)
        _pose_search(se, plan[_E_RES], plan[_E_RES_ALL], plan[_E_N_ALL], branches, noise[0], plan[_E_MULT] != 0,
                     params, grid, M, n_grid, span, hi[i] - lo[i], out_t, out_b, out_m, cnt, fam, fcnt, i,
                     no_known, no_known_at)  # fmt: skip
        _twin_copies(out_t, out_b, out_m, cnt, i, twins)


def sample_grid(
    reduction, poses: Array, lo: Array, hi: Array, n_samples: int, params: Array | None = None
) -> tuple[Array, NDArray[np.int64]]:
    """Sorted theta* samples of each pose: a uniform grid on ``[lo, hi]`` plus the reduction's hints inside it
    (``candidates.grid_hints``), repeats spread, merged in compiled code (for a single pose NumPy steps cost ~80 us);
    the hints too where the reduction has a hints kernel (``Reduction.kernel_hints``; ``params``: its
    ``kernel_params(poses)``, if at hand). Returns ``(grid (N, M), count (N,))``: pose i's samples are the first
    ``count[i]`` of its row.

    A NaN hint of ``sample_hints`` adds no sample here, where the NumPy reference (tests) turns it into a spare
    midpoint of the uniform grid (its rows must be as long as the longest): the rows of a reduction whose hints
    differ in number between poses (the generic sweeps) then hold what the pose's own hints ask for, whatever the
    batch, and a batch costs no more samples per pose than a single pose (xArm 6: 64 + 12 instead of 64 + 78)."""
    plan = _plan(reduction)
    N = poses.shape[0]
    if plan.hints is not None:
        out = np.empty((N, n_samples + plan.n_hints + plan.ends.size))
        parallel.run(
            _hinted_grid,
            N,
            PARALLEL_MIN * 16,
            plan.hints,
            np.ascontiguousarray(reduction.kernel_params(poses) if params is None else params, dtype=np.float64),
            plan.ends,
            plan.periodic,
            np.ascontiguousarray(lo, dtype=np.float64),
            np.ascontiguousarray(hi, dtype=np.float64),
            candidates.unit_grid(n_samples),
            out,
        )
        return out, np.full(N, out.shape[1], dtype=np.int64)
    hints = candidates.grid_hints(reduction, poses)
    if hints is None:
        hints = np.empty((N, 0))
    out = np.empty((N, n_samples + hints.shape[1]))
    count = np.empty(N, dtype=np.int64)
    parallel.run(
        _merge_grid,
        N,
        PARALLEL_MIN * 16,
        np.ascontiguousarray(lo, dtype=np.float64),
        np.ascontiguousarray(hi, dtype=np.float64),
        candidates.unit_grid(n_samples),
        np.ascontiguousarray(hints, dtype=np.float64),
        out,
        count,
    )
    return out, count


class _Plan(NamedTuple):
    """What the engine passes for a reduction besides the poses' rows (``_plan``)."""

    residual: int  # the address of the residual kernel
    residuals: int  # ... of the all-branch one (``_no_residuals`` where there is none: ``n_all`` is 0)
    n_all: int
    branches: NDArray[np.int64]  # the branches searched (writable, as the kernels' signatures take them; unwritten)
    hints: int | None  # the address of the hints kernel, if any
    n_hints: int
    ends: Array  # theta*'s limits, sampled with the hints (none for a periodic theta*)
    periodic: bool
    one_pass: _OnePass | None  # its hints and search in one compiled pass per pose, if it can


class _OnePass(NamedTuple):
    """A one-pass kernel (``_edge_search``, ``_hinted_search``) and its arguments that do not change from call to
    call."""

    kernel: Any
    ints: tuple[NDArray[np.int64], NDArray[np.int64]]  # its ``plan``, without and with multiplicities
    margin_branches: NDArray[np.int64]
    steps: NDArray[np.int64]
    noise: Array  # the search's residual noise and the margins'
    n_samples: int | None  # the only sample count it takes (None: any)
    hint_range: Any  # ``EdgeSearch.hint_range``; None: the search's range
    twins: NDArray[np.int64]  # ``candidates.twin_maps`` of the reduction, one row each (none: no twins)


_PLANS: weakref.WeakKeyDictionary[object, _Plan] = weakref.WeakKeyDictionary()


def _plan(reduction) -> _Plan:
    """The reduction's ``_Plan``, worked out on its first search and kept while the reduction lives (a one-pose
    solve would spend ~10 us a call on it): a reduction's kernels, branches and limits are fixed once it is used."""
    # (a reduction made afresh for each call, as the generic sweeps' margins, names a lasting ``plan_key``)
    key = getattr(reduction, "plan_key", reduction)
    try:
        plan = _PLANS.get(key)
    except TypeError:  # (an unhashable reduction: worked out every time)
        return _make_plan(reduction)
    if plan is None:
        plan = _PLANS[key] = _make_plan(reduction)
    return plan


def _make_plan(red) -> _Plan:
    j = red.free_joint
    ends = np.zeros(0) if red.periodic else np.array([red.robot.lower[j], red.robot.upper[j]], dtype=np.float64)
    branches = np.asarray(red.search_branches, dtype=np.int64)
    if not red.uses_kernel:  # (its residual called back: :mod:`sweepik.engine.callback`)
        residual = address_of(callback.residual, RESIDUAL_SIG)
        residuals = address_of(callback.residuals, RESIDUALS_SIG)
        return _Plan(residual, residuals, int(red.n_branches), branches, None, 0, ends, bool(red.periodic), None)
    res_all = _kernel_residuals(red)
    hints = _hints_kernel(red)
    plan = _Plan(
        residual=address_of(red.kernel[0], RESIDUAL_SIG),
        residuals=address_of(_no_residuals if res_all is None else res_all, RESIDUALS_SIG),
        n_all=0 if res_all is None else int(red.n_branches),
        branches=branches,
        hints=None if hints is None else address_of(hints, HINTS_SIG),
        n_hints=0 if hints is None else int(red.n_kernel_hints),
        ends=ends,
        periodic=bool(red.periodic),
        one_pass=None,
    )
    return plan._replace(one_pass=_one_pass(red, plan))


def _one_pass(red, plan: _Plan) -> _OnePass | None:
    """The reduction's one-pass kernel and its fixed arguments: ``_hinted_search`` with a hints kernel,
    ``_edge_search`` with an ``EdgeSearch``, else None (the staged search)."""
    edges = None
    if plan.hints is None:
        edge_search = owned_kernel(red, "edge_search")
        if edge_search is None or overridden_below_kernel(red.__class__, ("sample_hints", "edge_reduction")):
            return None
        edges = edge_search(red)  # (read from the class: a function of the reduction)
        if edges is None:
            return None
    ints = np.zeros(_E_SIZE, dtype=np.int64)
    ints[_E_SEARCH] = address_of(_search, _SEARCH_FN_SIG)
    ints[_E_RES], ints[_E_RES_ALL], ints[_E_N_ALL] = plan.residual, plan.residuals, plan.n_all
    ints[_E_PERIODIC] = plan.periodic
    noise = np.array([red.residual_noise, 0.0], dtype=np.float64)
    maps = candidates.twin_maps(red)
    twins = np.array(maps, dtype=np.int64) if maps else np.zeros((0, max(int(red.n_branches), 1)), dtype=np.int64)
    if plan.hints is not None:
        ints[_E_HINTS], ints[_E_N_HINTS] = plan.hints, plan.n_hints
        none = np.zeros(0, dtype=np.int64)
        return _OnePass(_hinted_search, _with_mult(ints), none, none, noise, None, None, twins)
    assert edges is not None  # (no hints kernel: an EdgeSearch)
    margins = _plan(edges.margins)
    ints[_E_MARGIN], ints[_E_MARGINS], ints[_E_M_ALL] = margins.residual, margins.residuals, margins.n_all
    ints[_E_SWING], ints[_E_AMP], ints[_E_AMPS] = edges.swing, edges.amplitude, edges.amplitudes
    ints[_E_EVERY] = edges.every if margins.n_all == 3 and plan.n_all > 0 else 0  # (its layout: ``EdgeSearch``)
    ints[_E_N_SWING], ints[_E_N] = edges.n_swing, edges.n_samples
    noise[1] = edges.margins.residual_noise
    steps = np.ascontiguousarray(edges.steps, dtype=np.int64)
    return _OnePass(
        _edge_search, _with_mult(ints), margins.branches, steps, noise, edges.n_samples, edges.hint_range, twins
    )


def searches_margins(red) -> bool:
    """Whether ``red``'s compiled search is a generic sweep's one pass, its margins' search included (``EdgeSearch``):
    the costliest per pose (40-80 us on the swept 6R arms), where a batch's Python steps are a small part."""
    if red.closed_form or not red.uses_kernel:
        return False
    one = _plan(red).one_pass
    return one is not None and one.kernel is _edge_search


def _with_mult(ints: NDArray[np.int64]) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """A one-pass plan without and with multiplicities."""
    with_mult = ints.copy()
    with_mult[_E_MULT] = 1
    return ints, with_mult


def _hints_kernel(reduction):
    """``reduction.kernel_hints`` where it belongs to the reduction's ``kernel`` and no subclass below overrides
    ``sample_hints`` (the kernel would bypass it)."""
    kernel = owned_kernel(reduction, "kernel_hints")
    if kernel is None or overridden_below_kernel(type(reduction), ("sample_hints", "edge_reduction")):
        return None
    n = owned_kernel(reduction, "n_kernel_hints")
    if not (isinstance(n, int) and n >= 1):
        raise UnknownOptionError(
            f"reduction {reduction.name!r} sets kernel_hints but not n_kernel_hints (the number of hints it writes, "
            f"a positive int), got {n!r}"
        )
    return kernel


def _kernel_residuals(reduction):
    """``reduction.kernel_residuals`` where it belongs to the reduction's ``kernel`` (``kernels.owned_kernel``)."""
    return owned_kernel(reduction, "kernel_residuals")


def search(
    reduction,
    poses: Array,
    lo: Array,
    hi: Array,
    n_samples: int,
    params: Array | None = None,
    multiplicity: bool = True,
    one_pass: bool = True,
    before_redo: Callable[[NDArray[np.intp]], candidates.Spans] | None = None,
):
    """Candidates ``(pose, branch, theta*, multiplicity)`` and family spans of the chain poses ``poses (N, 4, 4)``
    over ``[lo, hi]`` (``(N,)`` each) with ``n_samples`` uniform samples plus the reduction's hints, by the compiled
    search; a reduction without a kernel through :mod:`sweepik.engine.callback` (``_called_back``). Poses whose
    candidate or family buffers overflow are searched again with larger buffers (``_redone``); ``before_redo(idx)``
    gives the stretches of those poses (``idx``) it leaves out (continua traced already). ``multiplicity`` False: the
    candidates' multiplicities are not wanted (each is given as 1; ~4 residuals a candidate less). The candidates
    and spans of the first branch of each class of ``reduction.twins`` are given to the others too
    (``candidates.twin_copies``). A reduction with a hints kernel or an ``EdgeSearch`` finds each pose's samples and
    candidates, twins' copies included, in one compiled pass, unless ``one_pass`` is False: then ``sample_grid``
    gives the samples of every pose first (the same samples: the tests compare the two)."""
    if not reduction.uses_kernel:
        return _called_back(reduction, poses, lo, hi, n_samples, multiplicity)
    params = np.ascontiguousarray(reduction.kernel_params(poses) if params is None else params, dtype=np.float64)
    N = poses.shape[0]
    out = _Out.empty(N)
    plan = _plan(reduction)
    one = plan.one_pass if one_pass else None
    if one is not None and one.n_samples is not None and one.n_samples != n_samples:
        one = None
    redo = None
    if one is not None:  # each pose's samples, then its candidates
        lo, hi = writable(lo), writable(hi)
        redo = _run_one_pass(reduction, plan, one, poses, params, lo, hi, n_samples, multiplicity, out)
    else:
        theta, n_theta = sample_grid(reduction, poses, lo, hi, n_samples, params)
        _run_search(reduction, plan, params, theta, n_theta, lo, hi, multiplicity, out)
    out_t, out_b, out_m, cnt, fcnt = out.t, out.b, out.m, out.cnt, out.fcnt
    if N == 1 and cnt[0] <= MAX_CAND and fcnt[0] == 0 and (redo is None or not redo[0]):
        # (a single pose: the general bookkeeping costs ~40 us)
        k0 = int(cnt[0])
        single = candidates.Candidates(
            pose=np.zeros(k0, dtype=np.intp),
            branch=out_b[0, :k0].astype(np.intp),
            theta=out_t[0, :k0].copy(),
            mult=out_m[0, :k0].astype(np.intp),
        )
        return (single if one is not None else candidates.twin_candidates(reduction, single)), candidates.Spans.empty()
    over = (cnt > MAX_CAND) | (fcnt > MAX_FAM)
    if redo is not None:
        over |= redo
    cand, spans = _gathered(out, over)
    redone = bool(over.any())
    if redone:
        idx = np.nonzero(over)[0]
        masked = None if before_redo is None else before_redo(idx)
        c2, s2 = _redone(reduction, plan, poses[idx], params[idx], lo[idx], hi[idx], n_samples, multiplicity, masked)
        if one is not None:  # (the one-pass kernels copied the others' candidates to their twins)
            c2 = candidates.twin_candidates(reduction, c2)
        cand = candidates.Candidates(
            np.concatenate([cand.pose, idx[c2.pose]]),
            np.concatenate([cand.branch, c2.branch]),
            np.concatenate([cand.theta, c2.theta]),
            np.concatenate([cand.mult, c2.mult]),
        )
        spans = candidates.Spans.concat(
            [spans, candidates.Spans(idx[s2.pose].astype(np.intp), s2.branch, s2.lo, s2.hi)]
        )
    cand = candidates.Candidates(
        pose=cand.pose.astype(np.intp),
        branch=cand.branch.astype(np.intp),
        theta=cand.theta,
        mult=cand.mult.astype(np.intp),
    )
    if one is None:
        return candidates.twin_copies(reduction, cand, spans)
    if redone and reduction.twins:  # the redone poses in their place, as ``candidates.twin_candidates`` puts them
        order = np.argsort(cand.pose, kind="stable")
        cand = candidates.Candidates(cand.pose[order], cand.branch[order], cand.theta[order], cand.mult[order])
    return cand, candidates.twin_spans(reduction, spans)


def _called_back(
    reduction, poses: Array, lo: Array, hi: Array, n_samples: int, multiplicity: bool
) -> tuple[candidates.Candidates, candidates.Spans]:
    """``search`` for a reduction without a compiled kernel (:mod:`sweepik.engine.callback`): its residual at every
    pose's samples in one vectorised call, the rest called back from the compiled search; a reduction without a
    residual (``residual`` gives None) is searched on its pose error (``PoseErrorResidual``). The twins' copies
    are made from its own candidates."""
    N = poses.shape[0]
    theta, n_theta = sample_grid(reduction, poses, lo, hi, n_samples)
    M = theta.shape[1]
    sampled = np.arange(M)[None, :] < n_theta[:, None]
    grid = np.where(sampled, theta, np.nan)
    searched, f = reduction, reduction.residual(poses, grid)
    if f is None:
        searched = PoseErrorResidual(reduction, orientation_weight(reduction.robot.length_unit))
        f = searched.residual(poses, grid)
    known = np.ascontiguousarray(np.asarray(f, dtype=np.float64).reshape(N, M, reduction.n_branches))
    known_at = np.where(sampled, np.arange(M)[None, :], -1).astype(np.int64)
    plan = _plan(searched)
    out = _Out.empty(N)
    with callback.registered(searched, poses) as params:
        _run_search(searched, plan, params, theta, n_theta, lo, hi, multiplicity, out, known=(known, known_at))
        over = (out.cnt > MAX_CAND) | (out.fcnt > MAX_FAM)
        cand, spans = _gathered(out, over)
        if over.any():
            idx = np.nonzero(over)[0]
            c2, s2 = _redone(searched, plan, poses[idx], params[idx], lo[idx], hi[idx], n_samples, multiplicity, None)
            cand = candidates.Candidates(
                np.concatenate([cand.pose, idx[c2.pose]]),
                np.concatenate([cand.branch, c2.branch]),
                np.concatenate([cand.theta, c2.theta]),
                np.concatenate([cand.mult, c2.mult]),
            )
            spans = candidates.Spans.concat([spans, candidates.Spans(idx[s2.pose], s2.branch, s2.lo, s2.hi)])
    cand = candidates.Candidates(
        cand.pose.astype(np.intp), cand.branch.astype(np.intp), cand.theta, cand.mult.astype(np.intp)
    )
    spans = candidates.Spans(spans.pose.astype(np.intp), spans.branch, spans.lo, spans.hi)
    return candidates.twin_copies(reduction, cand, spans)


#: Buffers of isolated candidates a pose may overflow before its search raises (``candidates_capped``); None: up to
#: ``REDO_MAX_CAND``.
_FOUND_CAP: ContextVar[int | None] = ContextVar("found_cap", default=None)


@contextmanager
def candidates_capped(cap: int) -> Iterator[None]:
    """Within the block, a pose whose isolated candidates overflow buffers of ``cap`` raises ``SearchOverflowError``
    at once (``_redone``) instead of searching again with larger ones (a fallback's search: ``chunk._answered``)."""
    token = _FOUND_CAP.set(cap)
    try:
        yield
    finally:
        _FOUND_CAP.reset(token)


def _redone(
    reduction, plan, poses, params, lo, hi, n_samples, multiplicity, masked
) -> tuple[candidates.Candidates, candidates.Spans]:
    """The poses that overflowed the search's buffers (their candidates, family spans or pending intervals) searched
    again by the staged search on the same samples, leaving out the stretches ``masked`` (``Spans`` of these poses:
    continua traced already), with buffers ``REDO_GROW`` times larger, then (for the poses that still overflow) large
    enough for twice the counts they reached, up to ``REDO_MAX_CAND`` candidates a pose; a pose whose candidates (not
    its families) overflow buffers of the cap ``candidates_capped`` sets (a fallback's search) raises
    ``SearchOverflowError``. Pose by pose in order."""
    N = poses.shape[0]
    theta, n_theta = sample_grid(reduction, poses, lo, hi, n_samples, params)
    n_masks = np.zeros(N, dtype=np.int64)
    masks = np.zeros((N, 0, 3))
    if masked is not None and len(masked):
        n_masks = np.bincount(masked.pose, minlength=N).astype(np.int64)
        masks = np.zeros((N, int(n_masks.max()), 3))
        order = np.argsort(masked.pose, kind="stable")
        p = masked.pose[order]
        slot = np.arange(p.size) - np.repeat(np.cumsum(n_masks) - n_masks, n_masks)
        masks[p, slot] = np.stack([masked.lo[order], masked.hi[order], masked.branch[order]], axis=1)
    todo, grow = np.arange(N), REDO_GROW
    found: list[tuple[candidates.Candidates, candidates.Spans]] = []
    while todo.size:
        K, F = MAX_CAND * grow, MAX_FAM * grow
        if K > REDO_MAX_CAND:
            raise SearchOverflowError(
                f"the search of {reduction.name!r} found more than {REDO_MAX_CAND} candidates or {F // REDO_GROW} "
                "families on a pose: its residual crosses zero that often along theta*"
            )
        out = _Out.empty(todo.size, K, F)
        rows = (params[todo], theta[todo], n_theta[todo], lo[todo], hi[todo])
        _run_search(reduction, plan, *rows, multiplicity, out, masks[todo], n_masks[todo])
        cap = _FOUND_CAP.get()
        if cap is not None and K >= cap and np.any(out.cnt > K):
            raise SearchOverflowError(
                f"the search of {reduction.name!r} found more than {K} isolated candidates on a pose: its residual "
                "crosses zero that often along theta* (a pose on a self-motion of two or more dimensions?)"
            )
        over = (out.cnt > K) | (out.fcnt > F)
        c, sp = _gathered(out, over)
        mine = candidates.Candidates(todo[c.pose], c.branch, c.theta, c.mult)
        found.append((mine, candidates.Spans(todo[sp.pose].astype(np.intp), sp.branch, sp.lo, sp.hi)))
        need = max(
            float(np.max(out.cnt[over], initial=0)) / MAX_CAND, float(np.max(out.fcnt[over], initial=0)) / MAX_FAM
        )
        todo, grow = todo[over], max(grow * REDO_GROW, 2 * int(np.ceil(need)))
    cand = candidates.Candidates(
        *(np.concatenate([getattr(c, k) for c, _ in found]) for k in ("pose", "branch", "theta", "mult"))
    )
    order = np.argsort(cand.pose, kind="stable")
    cand = candidates.Candidates(cand.pose[order], cand.branch[order], cand.theta[order], cand.mult[order])
    return cand, candidates.Spans.concat([s for _, s in found])


def edge_zeros(reduction, poses: Array, lo: Array, hi: Array) -> Array:
    """Zeros ``(N, K)`` (NaN-padded) of ``reduction``'s residual over ``[lo, hi]`` (``(N,)`` each), without their
    multiplicities: the domain edges a reduction's ``edge_reduction`` describes (``candidates.grid_hints``), wrapped
    into [-pi, pi] for a periodic theta* and each on its domain's side (``inside_zeros``)."""
    N = poses.shape[0]
    cand, _ = search(reduction, poses, lo, hi, N_SAMPLES, None, multiplicity=False)
    if reduction.periodic:  # (wrapped as samples are, then moved inside: wrapping can move a zero outside)
        cand = candidates.Candidates(cand.pose, cand.branch, candidates.wrapped(cand.theta), cand.mult)
    cand = inside_zeros(reduction, poses, cand, EDGE_PROBE_REL * (hi - lo))
    if N == 1:
        return cand.theta[None, :]
    counts = np.bincount(cand.pose, minlength=N)
    out = np.full((N, int(counts.max(initial=0))), np.nan)
    order = np.argsort(cand.pose, kind="stable")
    slot = np.arange(cand.pose.size) - np.repeat(np.cumsum(counts) - counts, counts)
    out[cand.pose[order], slot] = cand.theta[order]
    return out


def inside_zeros(reduction, poses: Array, cand: candidates.Candidates, reach: Array) -> candidates.Candidates:
    """The zeros ``cand`` of a margin ``reduction`` (``Reduction.edge_reduction``) each on its margin's
    non-negative side, as the compiled one-pass search places them (``_inside``; ``reach (N,)`` per pose): a domain
    edge's sample outside the domain is NaN for the branches it bounds, and the stretch from it to the next sample
    would go unsearched."""
    if not cand.theta.size:
        return cand
    t = cand.theta.copy()

    def margin(k: NDArray[np.intp], x: Array) -> Array:
        return np.asarray(reduction.residual_rows(poses, cand.pose[k], x[:, None], cand.branch[k, None]))[:, 0]

    k = np.arange(t.size)
    m = margin(k, t)
    k = k[(m < 0.0) & (m >= -EDGE_MARGIN)]  # the zeros still outside (``_inside``)
    d = reach[cand.pose[k]] * 2.0 ** (1 - EDGE_NUDGES)
    for _ in range(EDGE_NUDGES):
        for sign in (1.0, -1.0):
            if not k.size:
                return candidates.Candidates(cand.pose, cand.branch, t, cand.mult)
            x = t[k] + sign * d
            ok = margin(k, x) >= 0.0
            t[k[ok]] = x[ok]
            k, d = k[~ok], d[~ok]
        d = 2.0 * d
    return candidates.Candidates(cand.pose, cand.branch, t, cand.mult)


candidates.set_edge_zeros(edge_zeros)


@dataclass
class _Out:
    """The compiled search's output buffers for ``N`` poses: candidates (theta, branch, multiplicity; every slot
    below a pose's count is written) and their count, family spans ``(lo, hi, branch)`` and their count (counts past
    the buffers' sizes: an overflow)."""

    t: Array
    b: NDArray[np.int64]
    m: NDArray[np.int64]
    cnt: NDArray[np.int64]
    fam: Array
    fcnt: NDArray[np.int64]

    @classmethod
    def empty(cls, N: int, K: int | None = None, F: int | None = None) -> _Out:
        """Buffers of ``K`` candidates and ``F`` family spans a pose (``MAX_CAND``, ``MAX_FAM`` when not given)."""
        K = MAX_CAND if K is None else K
        F = MAX_FAM if F is None else F
        return cls(
            np.empty((N, K)),
            np.empty((N, K), dtype=np.int64),
            np.empty((N, K), dtype=np.int64),
            np.zeros(N, dtype=np.int64),
            np.empty((N, F, 3)),
            np.zeros(N, dtype=np.int64),
        )


def _run_one_pass(reduction, plan, one, poses, params, lo, hi, n_samples, multiplicity, out):
    """The one-pass kernel of ``plan`` (each pose's samples, then its candidates) over the poses, on threads for a
    batch (a single pose would wait for a worker thread to be scheduled). Returns which poses it leaves to redo."""
    N = poses.shape[0]
    redo = np.empty(N, dtype=np.bool_)
    hlo, hhi = lo, hi
    if one.hint_range is not None:
        hlo, hhi = (writable(a) for a in one.hint_range(reduction, poses))
    parallel.run(
        one.kernel,
        N,
        PARALLEL_MIN,
        one.ints[bool(multiplicity)],
        plan.branches,
        one.margin_branches,
        one.steps,
        one.noise,
        params,
        hlo,
        hhi,
        lo,
        hi,
        candidates.unit_grid(n_samples),
        plan.ends,
        one.twins,
        out.t,
        out.b,
        out.m,
        out.cnt,
        out.fam,
        out.fcnt,
        redo,
    )
    return redo


def _run_search(
    reduction, plan, params, theta, n_theta, lo, hi, multiplicity, out, masks=None, n_masks=None, known=None
):
    """``_search`` over the poses' samples ``theta (N, M)`` (the first ``n_theta[i]`` of row i), on threads for a
    batch, leaving out the stretches ``masks (N, K, 3)`` (the first ``n_masks[i]`` of pose i; None: none);
    ``known``: every branch's residual at the samples, ``(values (N, M, n_all), where (N, M))`` (``_search``'s
    ``known`` and ``known_at``; None: none)."""
    if masks is None or not masks.size:
        masks, n_masks = np.empty((0, 0, 3)), np.empty(0, dtype=np.int64)
    if known is None:
        known = (np.empty((0, 0, 1)), np.empty((0, 0), dtype=np.int64))
    parallel.run(
        _search,
        theta.shape[0],
        PARALLEL_MIN,
        plan.residual,
        plan.residuals,
        plan.n_all,
        params,
        np.ascontiguousarray(theta),
        n_theta,
        plan.branches,
        np.ascontiguousarray(hi - lo, dtype=np.float64),
        float(reduction.residual_noise),
        out.t,
        out.b,
        out.m,
        out.cnt,
        out.fam,
        out.fcnt,
        multiplicity,
        known[0],
        known[1],
        np.ascontiguousarray(masks, dtype=np.float64),
        np.ascontiguousarray(n_masks, dtype=np.int64),
        not isinstance(reduction, PoseErrorResidual),
    )


def _gathered(out: _Out, over: NDArray[np.bool_]) -> tuple[candidates.Candidates, candidates.Spans]:
    """The candidates and family spans of the poses that did not overflow (``over``), pose by pose."""
    counts = np.where(over, 0, out.cnt)
    pose_idx = np.repeat(np.arange(over.size), counts)
    slot = np.arange(pose_idx.size) - np.repeat(np.cumsum(counts) - counts, counts)
    cand = candidates.Candidates(pose_idx, out.b[pose_idx, slot], out.t[pose_idx, slot], out.m[pose_idx, slot])
    spans = candidates.Spans.empty()
    if out.fcnt.any():
        F = out.fam.shape[1]
        fp, fs = np.nonzero((np.arange(F)[None, :] < np.minimum(out.fcnt, F)[:, None]) & ~over[:, None])
        fam = out.fam
        spans = candidates.Spans(fp.astype(np.intp), fam[fp, fs, 2].astype(np.intp), fam[fp, fs, 0], fam[fp, fs, 1])
    return cand, spans
