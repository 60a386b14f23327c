"""The NumPy reference of the compiled sweep search (:mod:`sweepik.engine.search`), a test oracle: every zero of a
reduction's residual along theta*, by the same steps in vectorised NumPy (it was the engine's NumPy twin; the tests
compare the two candidate for candidate).

For N poses at once: sample theta* (uniform grid plus the reduction's hints) and evaluate every branch,
giving one residual sequence per (pose, branch). On each sequence:

* sign changes between consecutive valid samples -> bracketed roots (Chandrupatla, to full precision);
* local extrema of |residual| that do not cross zero at the samples -> the extremum is located precisely
  (as the root of a central difference of the residual); if it crosses zero there are two close roots
  (bracketed on either side), if it touches zero it is a double root (certified later by forward kinematics);
* samples at the edge of a branch's domain (next to NaN) and at the ends of the range -> candidates;
* an edge between a sample inside the domain and one outside it, not at the inside sample (no margin zero marked
  it) -> located by bisection, a candidate, and the stretch up to it resampled as an interval next to an edge;
* intervals where the curve bends enough to hide two roots between its samples (judged from second
  differences), or that touch a domain edge (square-root behaviour), are resampled more finely, recursively,
  and searched the same way;
* runs of samples where the residual vanishes identically -> self-motion families;
* samples within the residual's rounding noise -> candidates (a double root landing on a sample);
* roots in a stretch where the residual stays at rounding level (roots of high multiplicity) -> moved to the
  middle of the stretch; a stretch that ends at a domain edge, a jump or the search reach on both sides is a
  family (an analytic residual vanishing on an interval vanishes up to such an end), one that leaves the noise
  smoothly is a single root; roots joined by such stretches are merged;
* each root's multiplicity, from the growth of the residual away from it.

The result is a flat list of candidates ``(pose index, branch, theta*)``; ``solve`` turns them into
configurations, certifies each by forward kinematics and applies limits.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from oracles.rootfind import find_roots
from sweepik.engine.candidates import Candidates, Spans, grid_hints, unit_grid
from sweepik.engine.settings import (
    BEND,
    CLUSTER_FAMILY_REL,
    DIFF_LEVELS,
    DIFF_SHRINK,
    DIFF_STEP_REL,
    EDGE_LOW,
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
    MAX_LEVELS,
    MULT_LEVEL,
    MULT_MAX,
    N_SAMPLES,
    U_EDGE,
    U_UNIFORM,
    XTOL_REL,
)
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import Array, IntArray, Reduction
from sweepik.reductions.pose_error import PoseErrorResidual


def sample_grid(reduction: Reduction, poses: Array, lo: Array, hi: Array, n_samples: int) -> Array:
    """Sorted theta* samples ``(N, M)``: a uniform grid on [lo, hi] plus the reduction's hints inside it
    (``grid_hints``; :func:`sweepik.engine.search.sample_grid` is the compiled version, which adds no spare sample
    for a NaN hint)."""
    return merge_grid(lo, hi, n_samples, grid_hints(reduction, poses))


def merge_grid(lo: Array, hi: Array, n_samples: int, hints: Array | None) -> Array:
    """``sample_grid`` from the hints: the uniform grid, the hints inside [lo, hi], sorted, repeats spread."""
    s = unit_grid(n_samples)
    grid = lo[:, None] + (hi - lo)[:, None] * s[None, :]
    if hints is not None and hints.size:
        inside = np.isfinite(hints) & (hints >= lo[:, None]) & (hints <= hi[:, None])
        # a hint outside the range becomes a midpoint of the uniform grid (a distinct, harmless extra sample)
        spare = lo[:, None] + (hi - lo)[:, None] * ((np.arange(hints.shape[1]) + 0.5) / (n_samples - 1))[None, :]
        hints = np.where(inside, hints, spare)
        grid = np.concatenate([grid, hints], axis=1)
    grid = np.sort(grid, axis=1)
    # a sample repeated (a hint on the grid, hints outside the range all set to lo) would leave zero-width
    # intervals, where the three-sample extremum test cannot work (a double root exactly at that sample would go
    # unseen): each run of equal samples is spread evenly towards the next distinct sample
    new_run = np.ones(grid.shape, dtype=bool)
    new_run[:, 1:] = grid[:, 1:] > grid[:, :-1]
    if new_run.all():
        return grid
    M = grid.shape[1]
    idx = np.broadcast_to(np.arange(M), grid.shape)
    start = np.maximum.accumulate(np.where(new_run, idx, 0), axis=1)
    nxt = np.full(grid.shape, M)
    nxt[:, :-1] = np.minimum.accumulate(np.where(new_run, idx, M)[:, :0:-1], axis=1)[:, ::-1]
    r_i, r_j = np.nonzero(~new_run & (nxt < M))
    if r_i.size:
        s0, e0 = start[r_i, r_j], nxt[r_i, r_j]
        base = grid[r_i, s0]
        grid[r_i, r_j] = base + (grid[r_i, e0] - base) * (r_j - s0) / (e0 - s0)
    return grid


def _edge_coordinate(theta: Array, edge: Array) -> Array:
    """The coordinate in which an interval's curvature is judged: theta, or ``sqrt(|theta - edge|)`` where
    ``edge`` (broadcast against ``theta``) is finite. At a branch-domain edge the residual behaves like
    ``a + b sqrt(|theta - edge|) + ...`` (the square root of the branch's discriminant): analytic in that
    coordinate, unbounded in curvature in theta. Judged in theta, the intervals next to an edge always look bent
    and are resampled down to the last level; judged in the square root, only where a root can hide."""
    return np.where(np.isfinite(edge), np.sqrt(np.abs(theta - edge)), theta)


class _Search:
    """Candidate search over residual sequences ``theta, f (S, M)`` with pose/branch per sequence."""

    def __init__(self, reduction: Reduction, poses: Array, span: Array) -> None:
        self.red = reduction
        self.poses = poses
        self.span = span
        self.roots_p: list[IntArray] = []
        self.roots_b: list[IntArray] = []
        self.roots_t: list[Array] = []
        self.br: list[tuple[IntArray, IntArray, Array, Array, Array, Array]] = []
        self.spans = Spans.empty()
        #: |residual| above which a sample or extremum is no candidate (see ``FAR_NOISE``)
        self.far = FAR_NOISE * reduction.residual_noise
        #: a signed residual (analytic along a branch), not the pose error's norm (kinked where it vanishes)
        self.signed = not isinstance(reduction, PoseErrorResidual)

    def residual(self, pose: IntArray, branch: IntArray, theta: Array) -> Array:
        """Residual ``(K, M)`` of one branch per row."""
        r = self.red.residual_rows(self.poses, pose, theta, np.broadcast_to(branch[:, None], theta.shape))
        assert r is not None
        return r

    def _root(self, p: IntArray, b: IntArray, t: Array) -> None:
        self.roots_p.append(p)
        self.roots_b.append(b)
        self.roots_t.append(t)

    def scan(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        f: Array,
        valid: NDArray[np.bool_],
        level: int,
        edge_left: NDArray[np.bool_] | None = None,
        edge_right: NDArray[np.bool_] | None = None,
        ctx: tuple[Array, Array, Array, Array] | None = None,
        edge_x: Array | None = None,
        family: NDArray[np.bool_] | None = None,
    ) -> None:
        """Find candidates on sequences ``th, f (S, M)`` (``valid``: usable samples); recurse into bends.

        ``edge_left``/``edge_right`` ``(S,)``: the sequence's first/last sample borders a domain edge.
        ``ctx``: (theta, f) of the samples just left and right of a resampled interval (its parent's neighbours,
        NaN where there is none), so that its end samples get the extremum test with their nearest neighbours:
        a double root just beside a parent sample lies in the first or last sub-interval at every level.
        ``edge_x (S,)``: the domain edge whose neighbouring interval this sequence resamples (NaN if none): there
        curvature is judged in the coordinate sqrt(|theta - edge|) (see ``_edge_coordinate``).
        ``family (S, M)``: the samples masked as a family's (level 0 only; see ``FAR_NOISE``).
        """
        S = f.shape[0]
        if edge_left is None or edge_right is None:
            edge_left = edge_right = np.zeros(S, dtype=bool)
        if edge_x is None:
            edge_x = np.full(S, np.nan)
        absf = np.abs(f)
        fin = np.where(valid, f, np.nan)
        t0, t1 = th[:, :-1], th[:, 1:]
        v0, v1 = valid[:, :-1], valid[:, 1:]
        both = v0 & v1 & (t1 > t0)
        # samples on a root (within the residual's rounding noise): a sample that lands on a double root is
        # the root, whatever its neighbours do (the end samples of a resampled interval are its parent's)
        own = valid.copy()
        if level:
            own[:, 0] = own[:, -1] = False
        z_i, z_j = np.nonzero(own & (absf <= self.red.residual_noise))
        self._root(p[z_i], b[z_i], th[z_i, z_j])
        self._extrema_of(p, b, th, fin, ctx)
        self._edge_roots(p, b, th, absf, valid, level, family)
        # 5) intervals that may hide a pair of roots (besides a sign change they may have) are resampled;
        #    sign changes of the other intervals are bracketed
        prod = fin[:, :-1] * fin[:, 1:]
        if level < MAX_LEVELS:
            edges = (edge_left, edge_right, edge_x)
            refine, near_edge, open_l, open_r = self._to_refine(p, b, th, fin, absf, valid, both, level, *edges, family)
        else:
            refine = np.zeros_like(both)
        s_i, s_j = np.nonzero(both & ~refine & (prod < 0))
        if s_i.size:
            self.br.append((p[s_i], b[s_i], th[s_i, s_j], th[s_i, s_j + 1], f[s_i, s_j], f[s_i, s_j + 1]))
        r_i, r_j = np.nonzero(refine)
        if r_i.size:
            self._resample(p, b, th, f, fin, r_i, r_j, level, near_edge, open_l, open_r, ctx, edge_x)
        if level < MAX_LEVELS and self.signed:
            self._hidden_edges(p, b, th, fin, valid, level, edge_left, edge_right, ctx)

    def _hidden_edges(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        fin: Array,
        valid: NDArray[np.bool_],
        level: int,
        edge_left: NDArray[np.bool_],
        edge_right: NDArray[np.bool_],
        ctx: tuple[Array, Array, Array, Array] | None,
    ) -> None:
        """``scan``'s step 6 (``search._hidden_edge``): an interval with one sample in the branch's domain whose
        edge is not at that sample: the edge located by bisection (a candidate where the residual is near zero
        there and no larger than at the inside sample), the stretch from the inside sample to it resampled as an
        interval next to an edge."""
        S, M = th.shape
        h_i, h_j = np.nonzero((valid[:, :-1] != valid[:, 1:]) & (th[:, 1:] > th[:, :-1]))
        right = valid[h_i, h_j]
        inside = np.where(right, th[h_i, h_j], th[h_i, h_j + 1])
        outside = np.where(right, th[h_i, h_j + 1], th[h_i, h_j])
        span = self.span[p[h_i]]
        out = self.residual(p[h_i], b[h_i], outside[:, None])[:, 0]  # (a family's sample is masked, not outside)
        probe = self.residual(p[h_i], b[h_i], (inside + np.where(right, 1.0, -1.0) * EDGE_PROBE_REL * span)[:, None])
        hidden = ~np.isfinite(out) & np.isfinite(probe[:, 0])
        h_i, h_j, right, inside, outside, span = (a[hidden] for a in (h_i, h_j, right, inside, outside, span))
        if not h_i.size:
            return
        pp, bb = p[h_i], b[h_i]
        active = np.abs(outside - inside) > EDGE_PROBE_REL * span
        while active.any():
            k = np.nonzero(active)[0]
            mid = 0.5 * (inside[k] + outside[k])
            ok = np.isfinite(self.residual(pp[k], bb[k], mid[:, None])[:, 0])
            inside[k[ok]], outside[k[~ok]] = mid[ok], mid[~ok]
            active = np.abs(outside - inside) > EDGE_PROBE_REL * span
        fe = self.residual(pp, bb, inside[:, None])[:, 0]
        a = np.where(right, th[h_i, h_j], th[h_i, h_j + 1])
        fa = np.where(right, fin[h_i, h_j], fin[h_i, h_j + 1])
        near = (np.abs(fe) <= self.far) & (np.abs(fe) <= np.abs(fa))
        self._root(pp[near], bb[near], inside[near])
        lo, hi = np.where(right, a, inside), np.where(right, inside, a)
        sub = lo[:, None] + (hi - lo)[:, None] * U_EDGE[None, :]
        fs = self.residual(pp, bb, sub)
        fs[:, 0], fs[:, -1] = np.where(right, fa, fe), np.where(right, fe, fa)
        nan = np.full(h_i.size, np.nan)
        has_l, has_r = h_j >= 1, h_j + 2 <= M - 1
        jl, jr = np.maximum(h_j - 1, 0), np.minimum(h_j + 2, M - 1)
        prev_open = np.where(h_j == 0, edge_left[h_i], ~valid[h_i, jl])
        next_open = np.where(h_j + 1 == M - 1, edge_right[h_i], ~valid[h_i, jr])
        el = np.where(right, prev_open, True)
        er = np.where(right, True, next_open)
        c0 = (nan, nan, nan, nan) if ctx is None else (ctx[0][h_i], ctx[1][h_i], ctx[2][h_i], ctx[3][h_i])
        cl_t = np.where(right, np.where(has_l, th[h_i, jl], c0[0]), th[h_i, h_j])
        cl_f = np.where(right, np.where(has_l, fin[h_i, jl], c0[1]), fin[h_i, h_j])
        cr_t = np.where(right, th[h_i, h_j + 1], np.where(has_r, th[h_i, jr], c0[2]))
        cr_f = np.where(right, fin[h_i, h_j + 1], np.where(has_r, fin[h_i, jr], c0[3]))
        ex = np.where(el & er, np.nan, inside)
        self.scan(pp, bb, sub, fs, np.isfinite(fs), level + 1, el, er, (cl_t, cl_f, cr_t, cr_f), ex)

    def _extrema_of(
        self, p: IntArray, b: IntArray, th: Array, fin: Array, ctx: tuple[Array, Array, Array, Array] | None
    ) -> None:
        """``scan``'s step 3: extrema of |f| with no sign change around them (interior samples; with context, the
        ends too)."""
        if ctx is not None:
            th_x = np.concatenate([ctx[0][:, None], th, ctx[2][:, None]], axis=1)
            f_x = np.concatenate([ctx[1][:, None], fin, ctx[3][:, None]], axis=1)
        else:
            th_x, f_x = th, fin
        if th_x.shape[1] >= 3:
            fm, fc, fp = f_x[:, :-2], f_x[:, 1:-1], f_x[:, 2:]
            hl, hr = th_x[:, 1:-1] - th_x[:, :-2], th_x[:, 2:] - th_x[:, 1:-1]
            with np.errstate(invalid="ignore", divide="ignore"):
                dd = 2.0 * ((fp - fc) / hr - (fc - fm) / hl) / (hl + hr)
                # a parabola through the samples dips at most |f''| h^2 / 2 below the middle one
                may_touch = np.abs(fc) <= EXTREMUM_REACH * np.abs(dd) * np.maximum(hl, hr) ** 2
                ext = (
                    (np.abs(fc) <= np.abs(fm))
                    & (np.abs(fc) <= np.abs(fp))
                    & (fm * fc > 0)
                    & (fc * fp > 0)
                    & (hl > 0)
                    & (hr > 0)
                    & may_touch
                )
            e_i, e_j = np.nonzero(ext)
            if e_i.size:
                self._extrema(
                    p[e_i],
                    b[e_i],
                    th_x[e_i, e_j],
                    th_x[e_i, e_j + 1],
                    th_x[e_i, e_j + 2],
                    f_x[e_i, e_j + 1],
                    f_x[e_i, e_j],
                    f_x[e_i, e_j + 2],
                )

    def _edge_roots(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        absf: Array,
        valid: NDArray[np.bool_],
        level: int,
        family: NDArray[np.bool_] | None,
    ) -> None:
        """``scan``'s step 4: samples next to a domain edge (NaN) or at the range ends (level 0 only)."""
        S = th.shape[0]
        end = level == 0
        left_open = np.concatenate([np.full((S, 1), end), ~valid[:, :-1]], axis=1)
        right_open = np.concatenate([~valid[:, 1:], np.full((S, 1), end)], axis=1)
        nb_r = np.concatenate([absf[:, 1:], np.full((S, 1), np.inf)], axis=1)
        nb_l = np.concatenate([np.full((S, 1), np.inf), absf[:, :-1]], axis=1)
        nb_r = np.where(np.isfinite(nb_r), nb_r, np.inf)
        nb_l = np.where(np.isfinite(nb_l), nb_l, np.inf)
        edge_l, edge_r = left_open & (absf <= nb_r), right_open & (absf <= nb_l)
        near = absf <= self.far
        if family is not None:  # (next to a family's samples: whatever the residual)
            no = np.zeros((S, 1), dtype=bool)
            near |= edge_l & np.concatenate([no, family[:, :-1]], axis=1)
            near |= edge_r & np.concatenate([family[:, 1:], no], axis=1)
        edge = valid & (edge_l | edge_r) & near
        d_i, d_j = np.nonzero(edge)
        self._root(p[d_i], b[d_i], th[d_i, d_j])

    def _to_refine(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        fin: Array,
        absf: Array,
        valid: NDArray[np.bool_],
        both: NDArray[np.bool_],
        level: int,
        edge_left: NDArray[np.bool_],
        edge_right: NDArray[np.bool_],
        edge_x: Array,
        family: NDArray[np.bool_] | None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_], NDArray[np.bool_]]:
        """``scan``'s step 5: the intervals to resample (``(S, M - 1)``), whether each is next to a domain edge, and
        whether each sample borders one on its left / right (``(S, M)``)."""
        S, M = fin.shape
        t0, t1 = th[:, :-1], th[:, 1:]
        with np.errstate(invalid="ignore", divide="ignore"):
            # curvature in theta, or in sqrt(|theta - edge|) below an edge's interval
            x = _edge_coordinate(th, edge_x[:, None])
            dd = np.full((S, M), np.nan)  # second divided difference at interior samples
            if M >= 3:
                hl, hr = x[:, 1:-1] - x[:, :-2], x[:, 2:] - x[:, 1:-1]
                dd[:, 1:-1] = 2.0 * ((fin[:, 2:] - fin[:, 1:-1]) / hr - (fin[:, 1:-1] - fin[:, :-2]) / hl) / (hl + hr)
            curv = np.fmax(np.abs(dd[:, :-1]), np.abs(dd[:, 1:]))
            lowest = np.minimum(absf[:, :-1], absf[:, 1:])
            hx = x[:, 1:] - x[:, :-1]
            bend = lowest <= BEND * curv * hx * hx
            # sample j borders a domain edge on its left / right
            open_l = np.concatenate([edge_left[:, None], ~valid[:, :-1]], axis=1)
            open_r = np.concatenate([~valid[:, 1:], edge_right[:, None]], axis=1)
            near_edge = open_l[:, :-1] | open_r[:, 1:]
            # an interval next to an edge is resampled unconditionally, except next to the edge whose
            # coordinate judges the curvature (there the bend test in that coordinate decides)
            ex = edge_x[:, None]
            own_edge = (open_l[:, :-1] & (t0 == ex) & ~open_r[:, 1:]) | (open_r[:, 1:] & (t1 == ex) & ~open_l[:, :-1])
        nonzero = np.abs(fin[:, :-1]) + np.abs(fin[:, 1:]) > 0
        refine = bend | (near_edge & ~own_edge)
        if level == 0 and self.signed:  # (an edge at a sample: in its coordinate)
            judged, bent = self._edge_at_sample(p, b, th, fin, both, open_l, open_r, family)
            refine = np.where(judged, bent, refine)
        refine &= both & nonzero
        return refine, near_edge, open_l, open_r

    def _resample(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        f: Array,
        fin: Array,
        r_i: IntArray,
        r_j: IntArray,
        level: int,
        near_edge: NDArray[np.bool_],
        open_l: NDArray[np.bool_],
        open_r: NDArray[np.bool_],
        ctx: tuple[Array, Array, Array, Array] | None,
        edge_x: Array,
    ) -> None:
        """The intervals ``(r_i, r_j)`` resampled and scanned one level down."""
        M = th.shape[1]
        # uniform sub-samples; next to a domain edge (square-root behaviour) clustered towards both ends
        u = np.where(near_edge[r_i, r_j, None], U_EDGE[None, :], U_UNIFORM[None, :])
        sub = th[r_i, r_j, None] + (th[r_i, r_j + 1] - th[r_i, r_j])[:, None] * u
        pp, bb = p[r_i], b[r_i]
        fs = self.residual(pp, bb, sub)
        fs[:, 0], fs[:, -1] = f[r_i, r_j], f[r_i, r_j + 1]
        vs = np.isfinite(fs)
        # the parent already handled the interval's end samples as candidates: only interior ones are new;
        # its neighbours (or, at the sequence's ends, its own context) are the sub-sequence's context
        nan = np.full(r_i.size, np.nan)
        left = r_j >= 1
        right = r_j + 2 <= M - 1
        jl, jr = np.maximum(r_j - 1, 0), np.minimum(r_j + 2, M - 1)
        cl_t = np.where(left, th[r_i, jl], nan if ctx is None else ctx[0][r_i])
        cl_f = np.where(left, fin[r_i, jl], nan if ctx is None else ctx[1][r_i])
        cr_t = np.where(right, th[r_i, jr], nan if ctx is None else ctx[2][r_i])
        cr_f = np.where(right, fin[r_i, jr], nan if ctx is None else ctx[3][r_i])
        # an interval next to one edge: its sub-sequences judge curvature in that edge's coordinate; next to two
        # edges: in theta; next to none: as their parent
        el, er = open_l[r_i, r_j], open_r[r_i, r_j + 1]
        ex = np.where(el & ~er, th[r_i, r_j], np.where(er & ~el, th[r_i, r_j + 1], np.where(el, np.nan, edge_x[r_i])))
        self.scan(pp, bb, sub, fs, vs, level + 1, el, er, (cl_t, cl_f, cr_t, cr_f), ex)

    def _edge_at_sample(
        self,
        p: IntArray,
        b: IntArray,
        th: Array,
        fin: Array,
        both: NDArray[np.bool_],
        open_l: NDArray[np.bool_],
        open_r: NDArray[np.bool_],
        family: NDArray[np.bool_] | None,
    ) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """Level-0 intervals ``(S, M - 1)`` next to one domain edge that sits at their open-side sample (the residual
        just past it is not finite), and which of them bend in that edge's coordinate (judged from the interval and its
        other neighbour: the test the interval's sub-intervals get, ``_edge_coordinate``)."""
        S, M = th.shape
        judged = np.zeros((S, M - 1), dtype=bool)
        bent_out = np.zeros((S, M - 1), dtype=bool)
        if M < 3:
            return judged, bent_out
        o_l, o_r = open_l[:, :-1], open_r[:, 1:]
        if family is not None:  # (a family's masked samples are no domain edge)
            no = np.zeros((S, 1), dtype=bool)
            o_l = o_l & ~np.concatenate([no, family[:, :-2]], axis=1)
            o_r = o_r & ~np.concatenate([family[:, 2:], no], axis=1)
        right = both & o_r & ~open_l[:, :-1]  # interval j's sample j + 1 borders the edge
        left = both & o_l & ~open_r[:, 1:]
        right[:, 0] = False  # (the sample on the other side is needed)
        left[:, -1] = False
        i_r, j_r = np.nonzero(right)
        i_l, j_l = np.nonzero(left)
        i = np.concatenate([i_r, i_l])
        e = np.concatenate([j_r + 1, j_l])  # the sample at the edge
        n1 = np.concatenate([j_r, j_l + 1])  # its neighbour, then the next one
        n2 = np.concatenate([j_r - 1, j_l + 2])
        side = np.concatenate([np.ones(j_r.size), -np.ones(j_l.size)])  # the edge's side
        if i.size == 0:
            return judged, bent_out
        ok = np.isfinite(fin[i, n2])
        te = th[i, e]
        x1, x2 = np.sqrt(np.abs(th[i, n1] - te)), np.sqrt(np.abs(th[i, n2] - te))
        f0, f1, f2 = fin[i, e], fin[i, n1], fin[i, n2]
        with np.errstate(invalid="ignore", divide="ignore"):
            dd = 2.0 * ((f2 - f1) / (x2 - x1) - (f1 - f0) / x1) / x2
            low = np.minimum(np.abs(f0), np.abs(f1))
            bent = (low <= BEND * np.abs(dd) * x1 * x1) | (np.abs(f0) <= EDGE_LOW * np.abs(f1))
        step = EDGE_PROBE_REL * self.span[p[i]]
        past = self.residual(p[i], b[i], (te + side * step)[:, None])[:, 0]
        at = ok & np.isfinite(dd) & ~np.isfinite(past)
        # (a dip between the edge and its neighbour that the three samples do not show: halfway in its coordinate)
        mid = self.residual(p[i], b[i], (te - side * 0.25 * x1 * x1)[:, None])[:, 0]
        with np.errstate(invalid="ignore"):
            bent |= np.abs(mid) < low
        judged[i_r, j_r], judged[i_l, j_l] = at[: j_r.size], at[j_r.size :]
        bent_out[i_r, j_r], bent_out[i_l, j_l] = bent[: j_r.size], bent[j_r.size :]
        return judged, bent_out

    def _extrema(
        self, p: IntArray, b: IntArray, ta: Array, tc: Array, tb: Array, fc: Array, fa: Array, fb: Array
    ) -> None:
        """Locate the extremum between ta and tb, then classify (two roots / touching / nothing)."""
        span = self.span[p]
        idx = np.arange(p.size)

        def fe(x: Array, sel: IntArray) -> Array:
            return self.residual(p[sel], b[sel], x[:, None])[:, 0]

        xe = tc.copy()
        a, c = ta, tb
        far = np.zeros(p.size, dtype=bool)
        idx_ok = ~far
        # root of the central difference g(x) = f(x + h) - f(x - h), then again with h / DIFF_SHRINK around it:
        # the first step's truncation error (next to a domain edge f''' is large) shrinks by DIFF_SHRINK^2
        for level in range(DIFF_LEVELS):
            h = DIFF_STEP_REL * span / DIFF_SHRINK**level

            if level:
                a, c = xe - 2.0 * DIFF_SHRINK * h, xe + 2.0 * DIFF_SHRINK * h
            lo_, hi_ = a + h, c - h
            ga = fe(lo_ + h, idx) - fe(lo_ - h, idx)
            gc = fe(hi_ + h, idx) - fe(hi_ - h, idx)
            ok = (ga * gc < 0) & (lo_ < hi_) & idx_ok
            if not ok.any():
                break
            k = np.nonzero(ok)[0]
            hk = h[k]

            def g(x: Array, s: IntArray, k: IntArray = k, hk: Array = hk) -> Array:
                return fe(x + hk[s], k[s]) - fe(x - hk[s], k[s])

            xe[k] = find_roots(g, lo_[k], hi_[k], ga[k], gc[k], 1e-3 * float(hk.min()))
            if level == 0:  # an extremum located this far from zero (on fc's side) is neither root nor touching
                f0 = fe(xe, idx)
                far |= np.sign(fc) * f0 > self.far
                idx_ok = ~far
        fx = fe(xe, idx)
        # a dip below zero within the residual's rounding noise is a double root, not two roots: bracketing
        # it would return arbitrary points of the flat bottom (where |f| < noise) instead of the extremum
        cross = np.isfinite(fx) & (np.sign(fc) * fx < -self.red.residual_noise)
        k = np.nonzero(cross)[0]
        if k.size:
            self.br.append((p[k], b[k], ta[k], xe[k], fa[k], fx[k]))
            self.br.append((p[k], b[k], xe[k], tb[k], fx[k], fb[k]))
        k = np.nonzero(~cross & np.isfinite(fx) & ~far & (np.abs(fx) <= self.far))[0]
        self._root(p[k], b[k], xe[k])

    def finish(self) -> Candidates:
        if self.br:
            p, b, a, c, fa, fc = (np.concatenate(x) for x in zip(*self.br, strict=True))
            xtol = float(XTOL_REL * self.span.min())
            x = find_roots(lambda x, s: self.residual(p[s], b[s], x[:, None])[:, 0], a, c, fa, fc, xtol)
            self._root(p, b, x)
        p = np.concatenate(self.roots_p).astype(np.intp)
        b = np.concatenate(self.roots_b).astype(np.intp)
        t, lo, hi, family = self._center_flat(p, b, np.concatenate(self.roots_t))
        if family.any():
            self.spans = Spans(p[family], b[family], lo[family], hi[family])
        cand = self._merge_clusters(p[~family], b[~family], t[~family])
        return Candidates(cand.pose, cand.branch, cand.theta, self._multiplicity(cand.pose, cand.branch, cand.theta))

    def _small(self, p: IntArray, b: IntArray, x: Array) -> NDArray[np.bool_]:
        """|residual| within the noise (NaN, outside the branch's domain, counts as not small)."""
        return np.abs(self.residual(p, b, x[:, None])[:, 0]) <= self.red.residual_noise

    def _center_flat(self, p: IntArray, b: IntArray, t: Array) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
        """Move each root to the middle of the stretch around it where |residual| stays within the noise, and
        tell a self-motion family from a root of high multiplicity.

        A simple root's stretch is ~noise / |f'| wide: nothing moves. At a root of multiplicity k >= 3 (the
        residual ~ c x^k) the residual crosses zero at places decided by rounding anywhere in a stretch of
        width ~(noise / c)^(1/k); its middle is the root. Such a stretch ends *smoothly* on both sides (see
        ``JUMP_NOISE``); a stretch that ends at a domain edge, a jump or the search reach on both sides is a
        family. Returns the moved roots, the stretches' ends and the family mask."""
        family = np.zeros(t.size, dtype=bool)
        if t.size == 0:
            return t, t, t, family
        noise = self.red.residual_noise
        d0 = FLAT_PROBE_REL * self.span[p]
        flat = np.nonzero(self._small(p, b, t - d0) | self._small(p, b, t + d0))[0]
        if flat.size == 0:
            return t, t, t, family
        pf, bf, tf = p[flat], b[flat], t[flat]
        reach = np.empty((flat.size, 2))
        open_end = np.empty((flat.size, 2), dtype=bool)
        limit = FLAT_MAX_REL * self.span[pf]
        inners, outers = np.zeros((flat.size, 2)), np.zeros((flat.size, 2))
        for side, sgn in enumerate((-1.0, 1.0)):
            inner = np.zeros(flat.size)
            outer = d0[flat].copy()
            grow = self._small(pf, bf, tf + sgn * outer)
            for _ in range(64):  # double until the residual leaves the noise (or the reach limit)
                if not grow.any():
                    break
                inner = np.where(grow, outer, inner)
                outer = np.where(grow, np.minimum(2.0 * outer, limit), outer)
                grow = grow & (inner < limit) & self._small(pf, bf, tf + sgn * outer)
            inners[:, side], outers[:, side] = inner, outer
        # a stretch that cannot be a family (both sides within half of CLUSTER_FAMILY_REL) only gives the centre
        # of a multiple root: its ends are bisected to FLAT_SHORT_TOL of their reach
        short = np.all(outers <= 0.5 * CLUSTER_FAMILY_REL * self.span[pf][:, None], axis=1)
        for side, sgn in enumerate((-1.0, 1.0)):
            inner, outer = inners[:, side], outers[:, side]
            at_limit = inner >= limit
            for _ in range(FLAT_BISECT):  # boundary between inner (small) and outer (not small)
                go = ~short | (outer - inner > FLAT_SHORT_TOL * inner)
                mid = 0.5 * (inner + outer)
                sm = self._small(pf, bf, tf + sgn * mid)
                inner = np.where(go & sm, mid, inner)
                outer = np.where(go & ~sm, mid, outer)
            past = np.abs(self.residual(pf, bf, (tf + sgn * outer)[:, None])[:, 0])
            # ... and keeps growing (a rounding blip inside a continuum falls back into the noise)
            far = np.abs(self.residual(pf, bf, (tf + 2.0 * sgn * outer)[:, None])[:, 0])
            open_end[:, side] = at_limit | ~(past <= JUMP_NOISE * noise) | (far <= 2.0 * noise)  # NaN: domain edge
            reach[:, side] = inner
        lo, hi = t.copy(), t.copy()
        lo[flat] -= reach[:, 0]
        hi[flat] += reach[:, 1]
        wide = hi[flat] - lo[flat] > CLUSTER_FAMILY_REL * self.span[pf]
        family[flat] = wide & open_end[:, 0] & open_end[:, 1]
        return 0.5 * (lo + hi), lo, hi, family

    def _merge_clusters(self, p: IntArray, b: IntArray, t: Array) -> Candidates:
        """Merge neighbouring roots of one branch between which the residual stays within its rounding
        noise: at a root of high multiplicity the residual is flat at noise level over a short stretch and
        crosses zero there many times at random. Each such cluster becomes one candidate, its midpoint
        (families were set apart before, by ``_center_flat``)."""
        order = np.lexsort((t, b, p))
        p, b, t = p[order], b[order], t[order]
        empty = np.zeros(0, dtype=np.intp)
        if t.size < 2:
            return Candidates(p, b, t, empty)
        same = (p[1:] == p[:-1]) & (b[1:] == b[:-1])
        k = np.nonzero(same & (t[1:] > t[:-1]))[0]
        joined = np.zeros(t.size - 1, dtype=bool)
        if k.size:
            mid = 0.5 * (t[k] + t[k + 1])
            joined[k] = self._small(p[k], b[k], mid)
        joined |= same & (t[1:] == t[:-1])
        first = np.nonzero(np.concatenate([[True], ~joined]))[0]
        x = 0.5 * (np.minimum.reduceat(t, first) + np.maximum.reduceat(t, first))
        return Candidates(pose=p[first], branch=b[first], theta=x, mult=empty)

    def _multiplicity(self, p: IntArray, b: IntArray, t: Array) -> IntArray:
        """Order of each root (1 simple, 2 double, ...), from how fast |f| grows away from it: at the first
        distance d (doubling from ``FLAT_PROBE_REL``) where |f| exceeds ``MULT_LEVEL`` x noise, |f(2 d)| / |f(d)|
        is 2^m. Both sides are averaged; a side outside the branch's domain is left out (1 where neither)."""
        if t.size == 0:
            return np.zeros(0, dtype=np.intp)
        level = MULT_LEVEL * self.red.residual_noise
        limit = FLAT_MAX_REL * self.span[p]
        total, count = np.zeros(t.size), np.zeros(t.size)
        for sgn in (-1.0, 1.0):
            d = FLAT_PROBE_REL * self.span[p]
            f1 = np.abs(self.residual(p, b, (t + sgn * d)[:, None])[:, 0])
            for _ in range(64):
                low = (f1 < level) & (d < limit)
                if not low.any():
                    break
                d = np.where(low, 2.0 * d, d)
                k = np.nonzero(low)[0]
                f1[k] = np.abs(self.residual(p[k], b[k], (t[k] + sgn * d[k])[:, None])[:, 0])
            f2 = np.abs(self.residual(p, b, (t + 2.0 * sgn * d)[:, None])[:, 0])
            with np.errstate(divide="ignore", invalid="ignore"):
                m = np.log2(f2 / f1)
            ok = np.isfinite(m) & (f1 >= level)
            total += np.where(ok, m, 0.0)
            count += ok
        with np.errstate(invalid="ignore"):
            m = np.where(count > 0, total / np.maximum(count, 1), 1.0)
        return np.clip(np.rint(m), 1, MULT_MAX).astype(np.intp)


def _extend(reduction: Reduction, poses: Array, branch: IntArray, inside: Array, outside: Array) -> Array:
    """Bisect, for every family end at once, between a sample on the family (``inside``) and the next sample
    off it (``outside``) for where the family ends. ``poses (K, 4, 4)``, the rest ``(K,)``."""
    for _ in range(FAMILY_BISECT):
        mid = 0.5 * (inside + outside)
        r = reduction.residual(poses, mid[:, None], branch[:, None])
        on = np.isfinite(r[:, 0]) & (np.abs(r[:, 0]) <= FAMILY_TOL) if r is not None else np.zeros(mid.size, bool)
        inside = np.where(on, mid, inside)
        outside = np.where(on, outside, mid)
    return inside


def _families(
    reduction: Reduction, poses: Array, theta: Array, f: Array, valid: NDArray[np.bool_], span: Array
) -> tuple[Spans, NDArray[np.bool_]]:
    """Runs of vanishing samples ``(N, M, B)`` -> family spans (ends located by bisection towards the
    neighbouring samples), and the mask of samples they cover."""
    flat = valid & (np.abs(f) <= FAMILY_TOL)
    in_family = np.zeros_like(flat)
    if not flat.any():
        return Spans.empty(), in_family
    runs = []  # (pose, branch, first sample, last sample)
    for p, b in zip(*np.nonzero(flat.sum(axis=1) >= FAMILY_MIN_RUN), strict=True):
        col = flat[p, :, b]
        edges = np.diff(np.concatenate([[0], col.astype(np.int8), [0]]))
        for s0, e0 in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0], strict=True):
            # a run must also be long: coinciding samples (hints at one point) are one root, not a family
            if e0 - s0 >= FAMILY_MIN_RUN and theta[p, e0 - 1] - theta[p, s0] > CLUSTER_FAMILY_REL * span[p]:
                runs.append((int(p), int(b), int(s0), int(e0 - 1)))
                in_family[p, s0:e0, b] = True
    if not runs:
        return Spans.empty(), in_family
    P, Bb, S0, S1 = (np.array(x) for x in zip(*runs, strict=True))
    M = theta.shape[1]
    lo, hi = theta[P, S0], theta[P, S1]
    lo = np.where(S0 > 0, _extend(reduction, poses[P], Bb, lo, theta[P, np.maximum(S0 - 1, 0)]), lo)
    hi = np.where(S1 < M - 1, _extend(reduction, poses[P], Bb, hi, theta[P, np.minimum(S1 + 1, M - 1)]), hi)
    return Spans(P.astype(np.intp), Bb.astype(np.intp), lo, hi), in_family


def find_candidates(
    reduction: Reduction,
    poses: Array,
    lo: Array,
    hi: Array,
    n_samples: int = N_SAMPLES,
    masked: Spans | None = None,
) -> tuple[Candidates, Spans]:
    """Candidates for all N chain poses ``(N, 4, 4)`` with theta* ranges ``lo, hi (N,)``. ``masked``: stretches of
    theta* (pose, branch, ends) whose samples are left out of the search, as a family's are (a continuum traced
    already: :mod:`sweepik.engine.rough_continua`)."""
    theta = sample_grid(reduction, poses, lo, hi, n_samples)
    f = reduction.residual(poses, theta)
    if f is None:
        reduction = PoseErrorResidual(reduction, orientation_weight(reduction.robot.length_unit))
        f = reduction.residual(poses, theta)
    N, M, B = f.shape
    valid = np.isfinite(f)
    skip = sorted(set(range(B)) - set(reduction.search_branches))
    if skip:  # e.g. the other branches of a class of twins, which get their roots from its first (solver)
        valid[:, :, skip] = False
    spans, in_family = _families(reduction, poses, theta, f, valid, hi - lo)
    if masked is not None:
        for p, b, a, c in zip(masked.pose, masked.branch, masked.lo, masked.hi, strict=True):
            in_family[p, (theta[p] >= a) & (theta[p] <= c), b] = True
    valid &= ~in_family
    search = _Search(reduction, poses, hi - lo)
    p = np.repeat(np.arange(N), B)
    b = np.tile(np.arange(B), N)
    fs = f.transpose(0, 2, 1).reshape(N * B, M)
    vs = valid.transpose(0, 2, 1).reshape(N * B, M)
    fam = in_family.transpose(0, 2, 1).reshape(N * B, M)
    search.scan(p, b, theta[p], fs, vs, 0, family=fam if fam.any() else None)
    cand = search.finish()
    return cand, Spans.concat([spans, search.spans])
