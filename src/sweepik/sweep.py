"""The one-joint sweep engine, precise strategy: every zero of a reduction's residual along theta*.

For N poses at once: sample theta* (uniform grid plus the reduction's hints), evaluate the residual of every
branch ``(N, M, B)``, then

* sign changes between consecutive valid samples -> bracketed roots (Chandrupatla, to full precision);
* local extrema of |residual| that do not cross zero at the samples -> the extremum is located precisely
  (as the root of a central difference of the residual); if it crosses zero there are two close roots
  (bracketed on either side), if it touches zero it is a double root (certified later by forward kinematics);
* extrema at the edge of a branch's domain (next to NaN) and at the ends of the range -> the edge sample;
* runs of samples where the residual vanishes identically -> self-motion families.

The result is a flat list of candidates ``(pose index, branch, theta*)``; ``solve`` turns them into
configurations, certifies each by forward kinematics and applies limits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .reductions.base import Array, IntArray, Reduction
from .rootfind import find_roots

#: Default number of uniform samples of theta* over its range (hints come on top). Checked against an
#: independent polynomial solver (tests/carm_oracle.py) and against 16x denser sampling.
N_SAMPLES = 96
#: |residual| at or below which a sample counts as lying on a self-motion family (residuals are computed to
#: ~1e-15; an isolated root makes three consecutive samples this small only with probability ~0).
FAMILY_TOL = 1e-10
#: Minimum number of consecutive vanishing samples that make a family.
FAMILY_MIN_RUN = 3
#: Root tolerance relative to the theta* range (2000 mm -> 2e-13 mm, 2 pi -> 6e-16 rad).
XTOL_REL = 1e-16
#: Half-step of the central difference used to locate extrema, relative to the theta* range.
#: Balances rounding (1e-16 / h) against truncation (h^2): the extremum lands within ~1e-8 of the range.
DIFF_STEP_REL = 1e-7


@dataclass(frozen=True)
class Candidates:
    """Flat candidate list: pose index, branch, theta* value, for ``K`` candidates."""

    pose: IntArray
    branch: IntArray
    theta: Array


@dataclass(frozen=True)
class FamilySpan:
    """A run of theta* along which branch ``branch`` of pose ``pose`` solves the pose identically."""

    pose: int
    branch: int
    lo: float
    hi: float


def sample_grid(reduction: Reduction, poses: Array, lo: Array, hi: Array, n_samples: int) -> Array:
    """Sorted theta* samples ``(N, M)``: a uniform grid on [lo, hi] plus the reduction's hints inside it."""
    s = np.linspace(0.0, 1.0, n_samples)
    grid = lo[:, None] + (hi - lo)[:, None] * s[None, :]
    hints = reduction.sample_hints(poses)
    if hints is not None and hints.size:
        if reduction.periodic:
            hints = np.pi - np.mod(np.pi - hints, 2.0 * np.pi)
        inside = np.isfinite(hints) & (hints >= lo[:, None]) & (hints <= hi[:, None])
        hints = np.where(inside, hints, lo[:, None])
        grid = np.concatenate([grid, hints], axis=1)
    return np.sort(grid, axis=1)


def _branch_eval(reduction: Reduction, poses: Array, pose_idx: IntArray, branch: IntArray):  # type: ignore[no-untyped-def]
    def f(x: Array, sel: IntArray) -> Array:
        r = reduction.residual(poses[pose_idx[sel]], x[:, None], branch[sel][:, None])
        assert r is not None
        return r[:, 0]

    return f


def find_candidates(
    reduction: Reduction,
    poses: Array,
    lo: Array,
    hi: Array,
    n_samples: int = N_SAMPLES,
) -> tuple[Candidates, list[FamilySpan]]:
    """Candidates for all N chain poses ``(N, 4, 4)`` with theta* ranges ``lo, hi (N,)``."""
    theta = sample_grid(reduction, poses, lo, hi, n_samples)
    f = reduction.residual(poses, theta)
    if f is None:
        raise NotImplementedError("reductions without a residual are handled by sweep_error_minima")
    N, M, B = f.shape
    span = hi - lo
    xtol = XTOL_REL * span
    valid = np.isfinite(f)
    absf = np.abs(f)

    # Self-motion families: runs of vanishing samples.
    flat = valid & (absf <= FAMILY_TOL)
    families: list[FamilySpan] = []
    in_family = np.zeros_like(flat)
    if flat.any():
        for p, b in zip(*np.nonzero(flat.sum(axis=1) >= FAMILY_MIN_RUN), strict=True):
            col = flat[p, :, b]
            edges = np.diff(np.concatenate([[0], col.astype(np.int8), [0]]))
            starts, ends = np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0]
            for s0, e0 in zip(starts, ends, strict=True):
                if e0 - s0 >= FAMILY_MIN_RUN and theta[p, e0 - 1] > theta[p, s0]:
                    families.append(FamilySpan(int(p), int(b), float(theta[p, s0]), float(theta[p, e0 - 1])))
                    in_family[p, s0:e0, b] = True
        valid = valid & ~in_family

    th0 = theta[:, :-1, None]
    th1 = theta[:, 1:, None]
    f0, f1 = f[:, :-1], f[:, 1:]
    v0, v1 = valid[:, :-1], valid[:, 1:]
    both = v0 & v1 & (th1 > th0)

    # 1) sign changes
    sc_p, sc_i, sc_b = np.nonzero(both & (f0 * f1 < 0))
    # 2) exact zeros at samples
    z_p, z_i, z_b = np.nonzero(valid & (f == 0))
    # 3) interior extrema of |f| with no sign change around them
    fm, fc, fp = f[:, :-2], f[:, 1:-1], f[:, 2:]
    vm, vc, vp = valid[:, :-2], valid[:, 1:-1], valid[:, 2:]
    ext = (
        vm & vc & vp
        & (absf[:, 1:-1] <= absf[:, :-2]) & (absf[:, 1:-1] <= absf[:, 2:])
        & (fm * fc > 0) & (fc * fp > 0)
        & (theta[:, 2:, None] > theta[:, :-2, None])
    )
    ex_p, ex_i, ex_b = np.nonzero(ext)
    ex_i = ex_i + 1
    # 4) edge samples (next to NaN or at the range ends) that are closer to zero than their neighbour
    left_open = np.concatenate([np.ones((N, 1, B), bool), ~valid[:, :-1]], axis=1)
    right_open = np.concatenate([~valid[:, 1:], np.ones((N, 1, B), bool)], axis=1)
    nb_left = np.concatenate([absf[:, 1:], np.full((N, 1, B), np.inf)], axis=1)
    nb_right = np.concatenate([np.full((N, 1, B), np.inf), absf[:, :-1]], axis=1)
    edge = valid & ((left_open & (absf <= np.where(np.isfinite(nb_left), nb_left, np.inf)))
                    | (right_open & (absf <= np.where(np.isfinite(nb_right), nb_right, np.inf))))
    ed_p, ed_i, ed_b = np.nonzero(edge)

    # Locate interior extrema precisely: root of the central difference g(x) = f(x + h) - f(x - h).
    roots_p: list[IntArray] = [z_p, ed_p]
    roots_b: list[IntArray] = [z_b, ed_b]
    roots_t: list[Array] = [theta[z_p, z_i], theta[ed_p, ed_i]]
    br_p, br_b = [sc_p], [sc_b]
    br_a, br_c = [theta[sc_p, sc_i]], [theta[sc_p, sc_i + 1]]
    br_fa, br_fc = [f[sc_p, sc_i, sc_b]], [f[sc_p, sc_i + 1, sc_b]]
    if ex_p.size:
        h = DIFF_STEP_REL * span[ex_p]
        a = theta[ex_p, ex_i - 1] + h
        c = theta[ex_p, ex_i + 1] - h
        fe = _branch_eval(reduction, poses, ex_p, ex_b)

        def g(x: Array, sel: IntArray) -> Array:
            return fe(x + h[sel], sel) - fe(x - h[sel], sel)

        idx = np.arange(ex_p.size)
        ga, gc = g(a, idx), g(c, idx)
        ok = (ga * gc < 0) & (a < c)
        xe = theta[ex_p, ex_i].copy()
        if ok.any():
            k = np.nonzero(ok)[0]
            xe[k] = find_roots(lambda x, s: g(x, k[s]), a[k], c[k], ga[k], gc[k], 1e-3 * h[k].min())
        fx = fe(xe, idx)
        sgn = np.sign(f[ex_p, ex_i, ex_b])
        cross = np.isfinite(fx) & (sgn * fx < 0)
        # two close roots: brackets on either side of the extremum
        kc = np.nonzero(cross)[0]
        for lo_t, hi_t, flo, fhi in (
            (theta[ex_p[kc], ex_i[kc] - 1], xe[kc], f[ex_p[kc], ex_i[kc] - 1, ex_b[kc]], fx[kc]),
            (xe[kc], theta[ex_p[kc], ex_i[kc] + 1], fx[kc], f[ex_p[kc], ex_i[kc] + 1, ex_b[kc]]),
        ):
            br_p.append(ex_p[kc])
            br_b.append(ex_b[kc])
            br_a.append(lo_t)
            br_c.append(hi_t)
            br_fa.append(flo)
            br_fc.append(fhi)
        # touching (or near-missing) extrema: double-root candidates, certified by FK later
        kt = np.nonzero(~cross & np.isfinite(fx))[0]
        roots_p.append(ex_p[kt])
        roots_b.append(ex_b[kt])
        roots_t.append(xe[kt])

    bp = np.concatenate(br_p)
    bb = np.concatenate(br_b)
    if bp.size:
        ba, bc = np.concatenate(br_a), np.concatenate(br_c)
        fa, fc = np.concatenate(br_fa), np.concatenate(br_fc)
        x = find_roots(_branch_eval(reduction, poses, bp, bb), ba, bc, fa, fc, float(np.min(xtol)))
        roots_p.append(bp)
        roots_b.append(bb)
        roots_t.append(x)
    cand = Candidates(
        pose=np.concatenate(roots_p).astype(np.intp),
        branch=np.concatenate(roots_b).astype(np.intp),
        theta=np.concatenate(roots_t),
    )
    return cand, families
