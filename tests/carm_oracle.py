"""Independent, sweep-free inverse-kinematics oracle for the C-Arm (Friedman et al., Table 1).

Purpose
-------
A reference that finds *every* IK solution of one pose without sampling the rail, so that the production
solver (a sweep over d1) can be tested for completeness. It uses nothing from ``sweepik``: forward
kinematics are written out from the paper's eqs. 1b and 1c. Joint limits are not applied.

Conventions: ``q = [d1 (mm), theta2 .. theta6 (rad)]``, Craig's modified DH (Table 1), L1 = 350 mm (a_3),
L2 = 402 mm (d_5), tool frame = frame 6. Poses are 4x4 homogeneous transforms in the base frame {B}.

Derivation
----------
Write the desired pose as R_D (tool z axis ``z = R_D[:, 2]``) and P = (Px, Py, Pz), and let
``t = Pz - d1``. Pre-multiplying by (B_2T)^-1 (eq. 4) gives the wrist position in frame 2::

    (C2 Px + S2 t,  -S2 Px + C2 t,  -Py) = (S3 L1 + C34 L2,  0,  C3 L1 - S34 L2).

* Joint 2 (the {2,4} entry): -S2 Px + C2 t = 0, so with ``r = sqrt(Px^2 + t^2)``
  ``(C2, S2) = sigma (Px, t) / r`` (sigma = +-1) and the first entry becomes ``u = sigma r``.
* Joints 3, 4 (planar 2-link problem, w = -Py, rho^2 = u^2 + w^2 = Px^2 + t^2 + Py^2): with
  ``k = (rho^2 + L2^2 - L1^2) / (2 L2)`` and ``h = sqrt(rho^2 - k^2)`` (real iff
  |L1 - L2| <= rho <= L1 + L2)::

      C34 = (k u - eps h w) / rho^2,   S34 = -(k w + eps h u) / rho^2,   eps = +-1,
      S3 = (u - L2 C34) / L1,          C3 = (w + L2 S34) / L1.

* Joints 5, 6: the rotation of frame 4 is R_B4 = R_B2 R_24 with R_24 = [[S34, C34, 0], [0, 0, 1],
  [C34, -S34, 0]], and the wrist is N = R_B4^T R_D = RotY(theta5) RotZ(theta6) (joint 5 turns about y4).
  That needs N[1,2] = 0, i.e. the joint-5 axis y4 is perpendicular to z::

      N12 = C34 (C2 zx + S2 zz) + S34 zy = 0,

  after which theta5 = atan2(N02, N22) and theta6 = atan2(N10, N11) are unique (no wrist singularity in
  this split).
* Substituting the branches: rho^2 N12 = k A - (eps sigma) h G / r with ``A = Px zx + t zz + Py zy``,
  ``B = Px zx + t zz`` and ``G = w B + r^2 zy``. Multiplying by r gives, for ``e = eps sigma = +-1``,
  the unsquared residual ``F_e(t) = r k A - e h G``, and

      Q(t) = F_+(t) F_-(t) = r^2 k^2 A^2 - h^2 G^2,

  a polynomial in t (r^2, rho^2, h^2 are polynomials; only even powers of r and h remain). Degrees:
  r^2 k^2 A^2 is 2 + 4 + 2 = 8 and h^2 G^2 is 4 + 4 = 8; the t^8 coefficient is
  (zy^2 + zz^2) / (4 L2^2), so **Q has degree 8** unless the tool z axis is parallel to the base x axis
  (then degree <= 6, and Q vanishes identically if in addition Px = 0: see "Degenerate poses").

What the roots mean: each real root t of Q with h^2 >= 0 and r > 0 is a rail position d1 = Pz - t at
which F_e = 0 for e = +1 or -1, and then *two* configurations exist, (sigma, eps) = (+1, e) and (-1, -e)
(theta2 differs by pi between them: the "alternate solution 180 deg off" of the paper's Figure 4). Hence
at most 8 rail positions and at most 16 configurations per pose; generic poses have 0, 2, 4, ... Real
roots with h^2 < 0 are spurious (only possible where both sides of Q vanish) and are removed by the FK
check. Complex roots are not solutions.

Numerics
--------
Lengths are scaled by L1 + L2 so that Q's coefficients are O(1) and every valid root has |t| <= 1. Q is
built with ``numpy.polynomial.Polynomial`` arithmetic (exact coefficient algebra), leading coefficients
negligible relative to the largest are trimmed (they only carry roots at |t| >> 1, which cannot be
reached), and the roots come from ``np.roots`` (companion-matrix eigenvalues). Roots with a small
imaginary part are kept (a double root is returned by the eigensolver as two roots split by
~sqrt(eps), often as a complex pair), then each is polished by Newton's method on the unsquared F_e of
whichever branch vanishes. Roots that cluster after polishing are a multiple root; the root of the
(m-1)-th derivative of Q (a simple root) is then used as well, which locates a double root to full
precision. Every candidate is expanded into its branches, verified by FK (position < 1e-6 mm, rotation
< 1e-8 rad), and duplicates are merged (d1 within ``DEDUP_D1_MM``, angles within ``DEDUP_ANGLE``
modulo 2 pi). A double root of Q is therefore returned once.

Special case r = 0 (Px = 0 and d1 = Pz): the wrist centre lies on the joint-2 axis and theta2 is not
fixed by the {2,4} entry. Then u = 0 and theta2 solves C34 (C2 zx + S2 zz) = -S34 zy directly. For tiny
but non-zero |Px| these solutions sit at t = Px tan(theta2); they are used as Newton seeds, because the
eigenvalue roots of Q near t = 0 are too inaccurate there.

Degenerate poses (continua of solutions)
----------------------------------------
* Tool z axis = +-x_B and Px = 0 (e.g. theta2 = +-90 deg with theta5 = 0): joints 3, 4 and 6 are parallel
  and the rail moves in their common normal plane, so there is a one-parameter self-motion: every d1 with
  |L1 - L2| <= rho <= L1 + L2 works. Here Q vanishes identically (A = B = G = 0). The oracle returns no
  solutions and ``degenerate=True``.
* r = 0 with C34 = 0 and zy = 0 (wrist on the joint-2 axis at the workspace boundary): joints 2 and 5 are
  coaxial and theta2 is free at that d1. Isolated solutions are still returned; ``degenerate=True``.
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import Polynomial
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "carm_ik_oracle",
    "carm_ik_oracle_ex",
    "carm_fk",
    "carm_q_polynomial",
    "POS_TOL_MM",
    "ROT_TOL_RAD",
]

Array = NDArray[np.float64]

#: Acceptance of a candidate: FK position error (mm) and geodesic rotation error (rad).
POS_TOL_MM = 1e-6
ROT_TOL_RAD = 1e-8
#: Roots of Q (scaled t, |t| <= 1 for valid ones) with |imag| below this are treated as real candidates.
#: Generous on purpose: a double root splits by ~1e-8, a triple by ~1e-5; false candidates fail the FK check.
IMAG_TOL = 1e-3
#: Leading coefficients of Q below this fraction of the largest are dropped (their roots have |t| >> 1).
LEAD_TRIM = 1e-13
#: Polished roots closer than this (scaled t) form a cluster, i.e. a (numerically) multiple root:
#: ~100x the sqrt(machine eps) scatter that Newton leaves at a double root.
CLUSTER_TOL = 1e-7
#: Verified solutions closer than this are one solution (d1 in mm, angles in rad modulo 2 pi). Larger than
#: the scatter of a double root polished by Newton (~1e-8 * 752 mm in d1).
DEDUP_D1_MM = 1e-4
DEDUP_ANGLE = 1e-6
#: Below this |Px| (scaled) the r = 0 solutions are added as Newton seeds (see module docstring).
PX_SEED = 1e-3
#: r (scaled) below which theta2 is taken from the r = 0 formula instead of atan2(sigma t, sigma Px).
R_ZERO = 1e-13
#: Pose within these of a self-motion pose is reported as degenerate: Px (mm), angle of z from +-x_B (rad).
#: Both far below POS_TOL_MM / ROT_TOL_RAD, so the neighbouring continuum passes verification.
DEGEN_PX_MM = 1e-8
DEGEN_ANGLE = 1e-10
#: h^2 (scaled) slightly negative from rounding is clamped to 0 above this.
H2_CLAMP = 1e-10
NEWTON_ITERS = 40
#: Newton on F_e never moves farther than this (scaled t) from its start: a raw root of Q is far closer
#: than that to its true value (a quadruple root is off by ~eps^(1/4) ~ 1e-4).
NEWTON_MAX_MOVE = 1e-2
#: F_e is "zero to rounding" below F_NOISE times the size of its terms.
F_NOISE = 8.0 * np.finfo(float).eps
#: A derivative root t* is a multiple root of Q if |Q(t*)| <= Q_NOISE * (|T1| + |T2|)(|t*|), where
#: Q = T1 - T2 and |T| has the absolute values of T's coefficients: a generous multiple of the machine eps
#: times the size of what cancels in Q.
Q_NOISE = 1e-13


def _wrap(x: ArrayLike) -> Array:
    x = np.asarray(x, dtype=np.float64)
    return np.pi - np.mod(np.pi - x, 2.0 * np.pi)


def carm_fk(q: ArrayLike, L1: float = 350.0, L2: float = 402.0) -> Array:
    """C-Arm tool pose ``(..., 4, 4)`` from ``q (..., 6)`` = [d1 mm, theta2..theta6 rad] (paper eqs. 1b, 1c)."""
    q = np.asarray(q, dtype=np.float64)
    d1, t2, t3, t4, t5, t6 = np.moveaxis(q, -1, 0)
    C2, S2, C3, S3 = np.cos(t2), np.sin(t2), np.cos(t3), np.sin(t3)
    C34, S34, C5, S5, C6, S6 = (
        np.cos(t3 + t4),
        np.sin(t3 + t4),
        np.cos(t5),
        np.sin(t5),
        np.cos(t6),
        np.sin(t6),
    )
    z, o = np.zeros_like(d1), np.ones_like(d1)
    B2 = np.stack(
        [np.stack([C2, -S2, z, z], -1), np.stack([z, z, -o, z], -1),
         np.stack([S2, C2, z, d1], -1), np.stack([z, z, z, o], -1)], -2)  # fmt: skip
    W = np.stack(
        [np.stack([S34 * C5 * C6 + C34 * S6, C34 * C6 - S34 * C5 * S6, S34 * S5, S3 * L1 + C34 * L2], -1),
         np.stack([-S5 * C6, S5 * S6, C5, z], -1),
         np.stack([C34 * C5 * C6 - S34 * S6, -S34 * C6 - C34 * C5 * S6, C34 * S5, C3 * L1 - S34 * L2], -1),
         np.stack([z, z, z, o], -1)], -2)  # fmt: skip
    return B2 @ W


def _rotation_error(R: Array, Rd: Array) -> float:
    """Geodesic angle (rad) between two rotations, accurate for small angles."""
    return float(2.0 * np.arcsin(min(1.0, np.linalg.norm(R - Rd) / (2.0 * np.sqrt(2.0)))))


class _Pose:
    """Scaled quantities of one desired pose (lengths divided by s = L1 + L2)."""

    def __init__(self, T: Array, L1: float, L2: float) -> None:
        self.T = T
        self.L1, self.L2 = L1, L2
        self.s = s = L1 + L2
        self.l1, self.l2 = L1 / s, L2 / s
        self.Rd = T[:3, :3]
        self.zx, self.zy, self.zz = (float(v) for v in T[:3, 2])
        self.px, self.py, self.Pz = float(T[0, 3]) / s, float(T[1, 3]) / s, float(T[2, 3])
        self.w = -self.py
        self.c0 = self.l2**2 - self.l1**2  # k = (rho^2 + c0) / (2 l2)

    # ---------------------------------------------------------------- polynomial
    def polynomial(self) -> tuple[Polynomial, Polynomial, Polynomial]:
        """Q = r^2 k^2 A^2 - h^2 G^2 in scaled t, and its two terms."""
        t = Polynomial([0.0, 1.0])
        r2 = self.px**2 + t * t
        rho2 = r2 + self.py**2
        k = (rho2 + self.c0) / (2.0 * self.l2)
        h2 = rho2 - k * k
        A = self.px * self.zx + self.zz * t + self.py * self.zy
        B = self.px * self.zx + self.zz * t
        G = self.w * B + self.zy * r2
        T1 = r2 * k * k * A * A
        T2 = h2 * G * G
        return T1 - T2, T1, T2

    # ---------------------------------------------------------------- unsquared residual
    def F(self, t: float, e: float) -> tuple[float, float, float]:
        """F_e(t) = r k A - e h G, its derivative (nan where h or r vanish) and its rounding-noise level."""
        px, py, l2 = self.px, self.py, self.l2
        r = float(np.hypot(px, t))
        rho2 = r * r + py * py
        k = (rho2 + self.c0) / (2.0 * l2)
        h2 = rho2 - k * k
        h = np.sqrt(max(h2, 0.0))
        A = px * self.zx + t * self.zz + py * self.zy
        B = px * self.zx + t * self.zz
        G = self.w * B + r * r * self.zy
        F = r * k * A - e * h * G
        noise = F_NOISE * (abs(r * k) * (abs(px) + abs(t) + abs(py)) + h * (abs(self.w) * (abs(px) + abs(t)) + r * r))
        if r == 0.0 or h == 0.0:
            return F, np.nan, noise
        dr, dk, dh = t / r, t / l2, t * (1.0 - k / l2) / h
        dG = self.w * self.zz + 2.0 * t * self.zy
        dF = dr * k * A + r * dk * A + r * k * self.zz - e * (dh * G + h * dG)
        return F, dF, noise

    def newton_F(self, t0: float, e: float) -> tuple[float, float]:
        """Newton on F_e from t0; returns (t, |F_e| / noise level) at convergence or at the best iterate.

        Stops as soon as F_e is zero to rounding (so a double root, where F_e' ~ 0, is not left by a huge
        step) and never moves farther than NEWTON_MAX_MOVE from t0 (near r = 0, F_e is trivially small
        when Px ~ 0, which must not attract the iteration).
        """
        t = t0
        F, dF, noise = self.F(t, e)
        best_t, best_ratio = t, abs(F) / max(noise, 1e-300)
        for _ in range(NEWTON_ITERS):
            if abs(F) <= noise or not np.isfinite(dF) or dF == 0.0:
                break
            step = F / dF
            t_new = t - step
            if not np.isfinite(t_new) or abs(t_new - t0) > NEWTON_MAX_MOVE:
                break
            t = t_new
            F, dF, noise = self.F(t, e)
            ratio = abs(F) / max(noise, 1e-300)
            if ratio < best_ratio:
                best_t, best_ratio = t, ratio
            if abs(step) <= 1e-16 * (abs(t) + 1e-3):
                break
        return best_t, best_ratio

    # ---------------------------------------------------------------- configurations
    def _arm(self, C2: float, S2: float, u: float, eps: float, d1: float) -> Array | None:
        """Complete (d1, theta2) with the planar elbow branch eps and the wrist; None if unreachable."""
        w = self.w
        rho2 = u * u + w * w
        if rho2 == 0.0:
            return None
        k = (rho2 + self.c0) / (2.0 * self.l2)
        h2 = rho2 - k * k
        if h2 < -H2_CLAMP:
            return None
        h = np.sqrt(max(h2, 0.0))
        C34 = (k * u - eps * h * w) / rho2
        S34 = -(k * w + eps * h * u) / rho2
        return self._finish(d1, C2, S2, u, C34, S34)

    def _finish(self, d1: float, C2: float, S2: float, u: float, C34: float, S34: float) -> Array:
        S3 = (u - self.l2 * C34) / self.l1
        C3 = (self.w + self.l2 * S34) / self.l1
        th2 = np.arctan2(S2, C2)
        th3 = np.arctan2(S3, C3)
        th4 = np.arctan2(S34, C34) - th3
        R_B2 = np.array([[C2, -S2, 0.0], [0.0, 0.0, -1.0], [S2, C2, 0.0]])
        R_24 = np.array([[S34, C34, 0.0], [0.0, 0.0, 1.0], [C34, -S34, 0.0]])
        N = (R_B2 @ R_24).T @ self.Rd
        th5 = np.arctan2(N[0, 2], N[2, 2])
        th6 = np.arctan2(N[1, 0], N[1, 1])
        return np.array([d1, th2, th3, th4, th5, th6])

    def configs_at(self, t: float) -> tuple[list[Array], bool]:
        """All branch configurations at scaled t (unverified) and whether a theta2-continuum was met."""
        d1 = self.Pz - t * self.s
        r = float(np.hypot(self.px, t))
        out: list[Array] = []
        if r > R_ZERO:
            for sigma in (1.0, -1.0):
                C2, S2 = sigma * self.px / r, sigma * t / r
                for eps in (1.0, -1.0):
                    q = self._arm(C2, S2, sigma * r, eps, d1)
                    if q is not None:
                        out.append(q)
            return out, False
        return self.configs_r0(d1)

    def theta2_r0(self) -> tuple[list[tuple[float, float, float, float]], bool]:
        """r = 0: (theta2, eps, C34, S34) solving C34 (C2 zx + S2 zz) + S34 zy = 0 with u = 0."""
        w = self.w
        rho2 = w * w
        if rho2 == 0.0:
            return [], False
        k = (rho2 + self.c0) / (2.0 * self.l2)
        h2 = rho2 - k * k
        if h2 < -H2_CLAMP:
            return [], False
        h = np.sqrt(max(h2, 0.0))
        m = float(np.hypot(self.zx, self.zz))
        phi = float(np.arctan2(self.zz, self.zx))
        sols: list[tuple[float, float, float, float]] = []
        degenerate = False
        for eps in (1.0, -1.0) if h > 0.0 else (1.0,):
            C34, S34 = -eps * h * w / rho2, -k * w / rho2
            a, b = C34 * m, -S34 * self.zy  # a cos(theta2 - phi) = b
            if abs(a) < 1e-12:
                if abs(b) < 1e-12:
                    degenerate = True
                continue
            c = b / a
            if abs(c) > 1.0 + 1e-9:
                continue
            ac = float(np.arccos(np.clip(c, -1.0, 1.0)))
            for th2 in {phi + ac, phi - ac}:
                sols.append((th2, eps, C34, S34))
        return sols, degenerate

    def configs_r0(self, d1: float) -> tuple[list[Array], bool]:
        sols, degenerate = self.theta2_r0()
        out = [self._finish(d1, np.cos(th2), np.sin(th2), 0.0, C34, S34) for th2, _, C34, S34 in sols]
        return out, degenerate

    def r0_seeds(self) -> list[float]:
        """Newton seeds t = Px tan(theta2) from the r = 0 solutions, for small non-zero Px."""
        seeds = []
        for th2, _, _, _ in self.theta2_r0()[0]:
            c = np.cos(th2)
            if abs(c) > 1e-12:
                seeds.append(self.px * np.tan(th2))
        return seeds

    def verify(self, q: Array) -> float | None:
        """Combined error (pos mm / POS_TOL + rot / ROT_TOL) if within tolerance, else None."""
        Tq = carm_fk(q, self.L1, self.L2)
        pe = float(np.linalg.norm(Tq[:3, 3] - self.T[:3, 3]))
        re = _rotation_error(Tq[:3, :3], self.Rd)
        if pe < POS_TOL_MM and re < ROT_TOL_RAD:
            return pe / POS_TOL_MM + re / ROT_TOL_RAD
        return None


def carm_q_polynomial(T: ArrayLike, L1: float = 350.0, L2: float = 402.0) -> Polynomial:
    """The polynomial Q(t) of the module docstring for pose T, in scaled t = (Pz - d1) / (L1 + L2)."""
    return _Pose(np.asarray(T, dtype=np.float64), L1, L2).polynomial()[0]


def _dedupe(cands: list[tuple[int, float, Array]]) -> list[Array]:
    """Merge solutions equal within DEDUP tolerances; keep the lowest (priority, error) of each group."""
    cands = sorted(cands, key=lambda c: (c[0], c[1]))
    kept: list[Array] = []
    for _, _, q in cands:
        dup = False
        for p in kept:
            if abs(p[0] - q[0]) < DEDUP_D1_MM and np.all(np.abs(_wrap(p[1:] - q[1:])) < DEDUP_ANGLE):
                dup = True
                break
        if not dup:
            kept.append(q)
    return kept


def carm_ik_oracle_ex(T: ArrayLike, L1: float = 350.0, L2: float = 402.0) -> tuple[Array, bool]:
    """All real IK solutions of one pose, and whether the pose has a continuum of solutions.

    Parameters: ``T (4, 4)`` desired tool pose in the base frame (mm). Returns ``(q (k, 6), degenerate)``
    with rows [d1 mm, theta2..theta6 rad], angles in (-pi, pi], sorted by d1 then theta2; no joint limits.
    Every row reproduces T by FK within 1e-6 mm and 1e-8 rad. ``degenerate`` is True when the solution set
    contains a continuum (self-motion); then only isolated solutions are listed (none when Q == 0).
    """
    T = np.asarray(T, dtype=np.float64)
    if T.shape != (4, 4) or not np.all(np.isfinite(T)):
        raise ValueError(f"expected a finite 4x4 pose, got shape {T.shape}")
    P = _Pose(T, L1, L2)
    empty = np.zeros((0, 6))
    # rho >= hypot(Px, Py) and rho <= 1 (scaled) for any solution.
    if np.hypot(P.px, P.py) > 1.0 + 1e-9:
        return empty, False
    # Self-motion pose: Q vanishes identically.
    if abs(T[0, 3]) < DEGEN_PX_MM and np.hypot(P.zy, P.zz) < DEGEN_ANGLE:
        return empty, True

    Q, T1, T2 = P.polynomial()
    n = max(T1.coef.size, T2.coef.size)  # Q = T1 - T2: rounding error ~ eps * (|T1| + |T2|)
    noise_poly = Polynomial(np.abs(np.pad(T1.coef, (0, n - T1.coef.size))) + np.abs(np.pad(T2.coef, (0, n - T2.coef.size))))
    c = Q.coef.copy()
    big = np.max(np.abs(c)) if c.size else 0.0
    degenerate = False
    cands: list[tuple[int, float, Array]] = []  # (priority, error, q)

    def add_t(t: float, priority: int) -> None:
        nonlocal degenerate
        qs, deg = P.configs_at(t)
        degenerate |= deg
        for q in qs:
            err = P.verify(q)
            if err is not None:
                cands.append((priority, err, q))

    if big > 0.0:
        keep = np.nonzero(np.abs(c) > LEAD_TRIM * big)[0]
        c = c[: keep[-1] + 1]
        raw = np.roots(c[::-1]) if c.size > 1 else np.zeros(0, dtype=complex)
        raw = raw[(np.abs(raw.imag) < IMAG_TOL) & (np.abs(raw.real) < 1.0 + 1e-6)]
        best_polished: list[float] = []  # per raw root: the polished t of the branch that vanishes
        for t0 in raw.real:
            best = (np.inf, float(t0))
            for e in (1.0, -1.0):
                t1, f1 = P.newton_F(float(t0), e)
                best = min(best, (f1, t1))
                add_t(t1, 1)
            best_polished.append(best[1])
        # Multiple roots: distinct raw roots polish to (nearly) the same t. The simple root of the (m-1)-th
        # derivative of Q locates such a root to full precision; it is accepted only where Q itself vanishes
        # to rounding level (two close but distinct roots have a clearly non-zero Q between them).
        for tc, m in _clusters(sorted(best_polished)):
            for order in range(1, m):
                ts = _newton_poly(Q.deriv(order), tc)
                if ts is not None and abs(Q(ts)) <= Q_NOISE * noise_poly(abs(ts)):
                    # A higher order is the simple root when the multiplicity is m: most accurate first.
                    add_t(ts, -order)
    else:  # Q == 0 exactly but not caught above (e.g. zy = zz = 0 and Px = 0 to the bit)
        return empty, True

    # r = 0 family (wrist centre on the joint-2 axis).
    if abs(P.px) < PX_SEED:
        if P.px == 0.0:
            add_t(0.0, 0)
        else:
            for t0 in P.r0_seeds():
                sigma = 1.0  # F_e with e = eps * sigma; try both, the FK check decides
                for e in (1.0, -1.0):
                    t1, _ = P.newton_F(t0, e * sigma)
                    add_t(t1, 1)
            add_t(0.0, 3)

    sols = _dedupe(cands)
    if not sols:
        return empty, degenerate
    q = np.array(sols)
    q[:, 1:] = _wrap(q[:, 1:])
    order = np.lexsort((q[:, 1], q[:, 0]))
    return q[order], degenerate


def carm_ik_oracle(T: ArrayLike, L1: float = 350.0, L2: float = 402.0) -> Array:
    """All real IK solutions ``(k, 6)`` of pose ``T (4, 4)`` (see ``carm_ik_oracle_ex``; no continuum flag)."""
    return carm_ik_oracle_ex(T, L1, L2)[0]


def _clusters(ts: list[float]) -> list[tuple[float, int]]:
    """(centre, size) of groups (>= 2 members) of sorted values closer than CLUSTER_TOL to a neighbour."""
    out: list[tuple[float, int]] = []
    i = 0
    while i < len(ts):
        j = i
        while j + 1 < len(ts) and ts[j + 1] - ts[j] < CLUSTER_TOL:
            j += 1
        if j > i:
            out.append((float(np.mean(ts[i : j + 1])), j - i + 1))
        i = j + 1
    return out


def _newton_poly(p: Polynomial, t0: float) -> float | None:
    dp = p.deriv()
    t = t0
    for _ in range(NEWTON_ITERS):
        d = dp(t)
        if d == 0.0:
            break
        step = p(t) / d
        t -= step
        if not np.isfinite(t) or abs(t - t0) > 1e-3:
            return None
        if abs(step) <= 1e-16 * (abs(t) + 1e-3):
            break
    return float(t)
