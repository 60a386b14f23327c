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

What the roots mean: each real root t of Q (with r > 0) is a rail position d1 = Pz - t at which
F_e = 0 for e = +1 or -1, and then *two* configurations exist, (sigma, eps) = (+1, e) and (-1, -e):
(theta2 + pi, -theta3, -pi - theta4, theta5 + pi, theta6) is the partner of (theta2, ..., theta6), the
"alternate solution 180 deg off" of the paper's Figure 4. Where both F_+ and F_- vanish at the same t
there are four. Hence at most 8 rail positions and 16 configurations per pose. Measured over 40,000
random reachable poses: 2, 4 or 6 rail positions (4, 8 or 12 configurations; 71 %, 29 %, 0.75 %),
always exactly 2 x (number of real roots of Q). Within the paper's joint limits 5 or 6 distinct d1
values occur for about 1 pose in 750, although the paper reports at most four. Every real root of Q is
a solution: where h^2 < 0, Q = r^2 k^2 A^2 - h^2 G^2 is a sum of squares and vanishes only if both terms
do (those rare points fail the FK check). Complex roots are not solutions.

Numerics
--------
* Lengths are scaled by L1 + L2, so Q's coefficients are O(1) and every valid root has |t| <= 1. Q is
  built with ``numpy.polynomial.Polynomial`` arithmetic (exact coefficient algebra, no fitting); leading
  coefficients negligible next to the largest are trimmed (they only carry roots at |t| >> 1, which cannot
  be reached: the t^8 coefficient vanishes when the tool z axis is +-x_B), and the roots come from
  ``np.roots`` (companion-matrix eigenvalues). Roots with |imag| < ``IMAG_TOL`` are candidates: a root of
  multiplicity m comes back as m roots scattered by ~eps^(1/m), often as a complex pair.
* Each candidate is polished by Newton's method on the unsquared F_+ and on F_- (F is evaluated with a
  rounding-error bound, calibrated against long-double evaluation). It becomes a root of each branch
  where F_e then vanishes to rounding (and of the better branch at least).
* Per branch, polished roots closer than ``CLUSTER_TOL`` form a group. A group that agrees to rounding is
  one simple root. Otherwise the signs of F_e at and between the members and just outside the group
  decide: two or more sign changes are distinct close roots (each refined by bisection); none is a
  multiple root (a singular pose, where Newton stalls ~1e-8 away), located to full precision as the simple
  root of Q^(m-1) (m = raw roots in the cluster) or of F_e'; one is an odd-multiplicity root. A multiple
  root is returned once.
* Every root is expanded into its two configurations and verified by FK (paper eqs. 1b, 1c): position
  < ``POS_TOL_MM`` = 1e-6 mm and rotation < ``ROT_TOL_RAD`` = 1e-8 rad; if a root's best estimate fails,
  the next alternative of its group is tried. Solutions equal within ``DEDUP_D1_MM`` and ``DEDUP_ANGLE``
  (angles modulo 2 pi) are merged.

Special case r = 0 (Px = 0 and d1 = Pz): the wrist centre lies on the joint-2 axis and theta2 is not
fixed by the {2,4} entry (Q has a spurious double root at t = 0 from the r^2 factors). Then u = 0 and
theta2 solves C34 (C2 zx + S2 zz) = -S34 zy directly (up to 2 per elbow branch). For tiny non-zero |Px|
these solutions sit at t = Px tan(theta2) and are used as Newton seeds, because the eigenvalue roots of Q
near t = 0 are too inaccurate there.

Accuracy limits (inherent, not of the method): at and near singular poses (e.g. theta2 = +-90 deg with
theta3 = 0, where F_e has a double root) two solutions merge; a pose computed by FK in double precision
then has, exactly, two real solutions about 1e-5 mm from the generating q or none (a complex pair),
which was confirmed with long-double arithmetic. The oracle returns what the rounded pose admits, so a
"contains the generating q within 1e-6 mm" test can fail there by ~1e-5 mm.

Degenerate poses (continua of solutions)
----------------------------------------
* Tool z axis = +-x_B and Px = 0 (e.g. theta2 = +-90 deg with theta5 = 0): joints 3, 4 and 6 are parallel
  to x_B and the rail (z_B) lies in their common normal plane, so there is a one-parameter self-motion:
  every d1 with |L1 - L2| <= rho <= L1 + L2 works. Here Q vanishes identically (A = B = G = 0). The
  oracle returns no solutions and ``degenerate=True``, also for poses within half the verification
  tolerance of such a pose (|Px| < 5e-7 mm, angle(z, +-x_B) < 5e-9 rad), where a whole continuum of
  configurations passes the FK check. Slightly farther away (up to ~1e-6 rad) the pose is near-continuum:
  many verified near-solutions (up to ~28) are returned.
* r = 0 with C34 = 0 and zy = 0 (wrist centre on the joint-2 axis at the workspace boundary): joints 2
  and 5 are coaxial and theta2 is free at that d1. Isolated solutions are still returned, with
  ``degenerate=True``.
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
#: Roots of one branch F_e, polished to rounding level, closer than this (scaled t) form a group that is
#: tested for being one multiple root (``_branch_roots``). Newton leaves a double root scattered by ~1e-8;
#: distinct roots inside a group are recognised by the sign test.
CLUSTER_TOL = 1e-5
#: A polished t counts as a root of F_e when |F_e| <= CONVERGED * (its rounding-noise estimate).
CONVERGED = 4.0
#: A multiple-root estimate must lie within this (scaled t) of its group of polished roots.
MULTIPLE_WINDOW = 1e-6
#: Polished roots of one branch that agree to this relative precision are one simple root.
SAME_ROOT_TOL = 1e-12
#: Raw roots of Q closer than this (scaled t) are tested as one multiple root (a root of multiplicity m
#: is scattered by ~eps^(1/m): 1e-8 for m = 2, 1e-4 for m = 4).
RAW_CLUSTER_TOL = 1e-3
#: Verified solutions closer than this are one solution (d1 in mm, angles in rad modulo 2 pi): e.g. the
#: two elbow branches at h = 0 (angles there are only good to ~sqrt(eps)), or an r = 0 solution found both
#: from a seed and from Q. Distinct solutions are far apart except within ~1e-8 of a singular pose.
DEDUP_D1_MM = 1e-5
DEDUP_ANGLE = 1e-6
#: Below this |Px| (scaled) the r = 0 solutions are added as Newton seeds (see module docstring).
PX_SEED = 1e-3
#: r (scaled) below which theta2 is taken from the r = 0 formula instead of atan2(sigma t, sigma Px).
R_ZERO = 1e-13
#: A pose this close to a self-motion pose (|Px| in mm, angle of the tool z axis from +-x_B in rad) is
#: reported as degenerate: every configuration of the neighbouring continuum then reproduces it within
#: half the verification tolerance, so no finite list of solutions is meaningful.
DEGEN_PX_MM = 0.5 * POS_TOL_MM
DEGEN_ANGLE = 0.5 * ROT_TOL_RAD
#: h^2 (scaled) slightly negative from rounding is clamped to 0 above this.
H2_CLAMP = 1e-10
NEWTON_ITERS = 40
#: Newton on F_e never moves farther than this (scaled t) from its start: a raw root of Q is far closer
#: than that to its true value (a quadruple root is off by ~eps^(1/4) ~ 1e-4).
NEWTON_MAX_MOVE = 1e-2
#: F_e is "zero to rounding" below F_NOISE times the size of its terms (see ``_Pose.F``); calibrated against
#: long-double evaluation: the actual error stayed below 0.5 of this bound over 9,600 test evaluations.
F_NOISE = 2.0 * np.finfo(float).eps


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
        # Rounding-error bound: A and G from their summands, h from the cancellation in rho^2 - k^2
        # (absolute error ~eps (rho^2 + k^2), i.e. ~eps (rho^2 + k^2) / (2 h) in h), the products relative.
        sA = abs(px * self.zx) + abs(t * self.zz) + abs(py * self.zy)
        sG = abs(self.w) * (abs(px * self.zx) + abs(t * self.zz)) + r * r * abs(self.zy)
        dh_err = (rho2 + k * k) / (2.0 * h) if h > 0.0 else np.sqrt(rho2 + k * k)
        noise = F_NOISE * (abs(r * k) * sA + h * sG + abs(G) * dh_err + abs(r * k * A) + abs(h * G))
        if r == 0.0 or h == 0.0:
            return F, np.nan, noise
        dr, dk, dh = t / r, t / l2, t * (1.0 - k / l2) / h
        dG = self.w * self.zz + 2.0 * t * self.zy
        dF = dr * k * A + r * dk * A + r * k * self.zz - e * (dh * G + h * dG)
        return F, dF, noise

    def newton_F(self, t0: float, e: float) -> tuple[float, float]:
        """Newton on F_e from t0; returns (t, |F_e(t)| / its noise level) at the best iterate.

        Iterates until the step is at rounding level, or until F_e is zero to rounding and the steps
        stopped shrinking (at a double root, where F_e' ~ 0, further steps would be erratic and large);
        never moves farther than NEWTON_MAX_MOVE from t0 (near r = 0, F_e is trivially small when
        Px ~ 0, which must not attract the iteration).
        """
        t = t0
        F, dF, noise = self.F(t, e)
        best_t, best_F, best_noise = t, abs(F), noise
        prev = np.inf
        for _ in range(NEWTON_ITERS):
            if F == 0.0 or not np.isfinite(dF) or dF == 0.0:
                break
            step = F / dF
            if abs(F) <= noise and abs(step) > 2.0 * prev:
                break
            t_new = t - step
            if not np.isfinite(t_new) or abs(t_new - t0) > NEWTON_MAX_MOVE:
                break
            t = t_new
            F, dF, noise = self.F(t, e)
            if abs(F) < best_F:
                best_t, best_F, best_noise = t, abs(F), noise
            if abs(step) <= 1e-16 * (abs(t) + 1e-3) or (abs(F) <= noise and abs(step) > 0.5 * prev):
                break
            prev = abs(step)
        return best_t, best_F / max(best_noise, 1e-300)

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

    def configs_at(self, t: float, e: float | None = None) -> tuple[list[Array], bool]:
        """Configurations at scaled t (unverified) and whether a theta2-continuum was met.

        With ``e`` only the two branches of F_e, (sigma, eps) = (+1, e) and (-1, -e), are built; at r = 0
        the theta2 solutions of the r = 0 case are returned whatever ``e``.
        """
        d1 = self.Pz - t * self.s
        r = float(np.hypot(self.px, t))
        out: list[Array] = []
        if r > R_ZERO:
            for sigma in (1.0, -1.0):
                C2, S2 = sigma * self.px / r, sigma * t / r
                for eps in (1.0, -1.0) if e is None else (e * sigma,):
                    q = self._arm(C2, S2, sigma * r, eps, d1)
                    if q is not None:
                        out.append(q)
            return out, False
        return self.configs_r0(d1)

    def root_of_derivative(self, ta: float, tb: float, e: float) -> float | None:
        """The root of F_e' near [ta, tb] (secant method): where a double root of F_e sits."""
        t0, t1 = ta, tb if tb > ta else ta + 1e-9
        d0, d1 = self.F(t0, e)[1], self.F(t1, e)[1]
        for _ in range(NEWTON_ITERS):
            if not (np.isfinite(d0) and np.isfinite(d1)) or d1 == d0:
                break
            t2 = t1 - d1 * (t1 - t0) / (d1 - d0)
            if not np.isfinite(t2) or abs(t2 - 0.5 * (ta + tb)) > 1e-4:
                return None
            t0, d0, t1 = t1, d1, t2
            d1 = self.F(t1, e)[1]
            if abs(t1 - t0) <= 1e-16 * (abs(t1) + 1e-3):
                break
        return float(t1)

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

    Parameters: ``T (4, 4)`` desired tool pose in the base frame (mm); ``L1``, ``L2`` in mm. Returns
    ``(q (k, 6), degenerate)`` with rows [d1 mm, theta2..theta6 rad], angles wrapped to (-pi, pi], sorted
    by d1 then theta2, no joint limits, duplicates removed. Every row reproduces T by FK within
    ``POS_TOL_MM`` and ``ROT_TOL_RAD``. ``degenerate`` is True when the solutions form a continuum
    (self-motion): at (or within half the tolerance of) a pose with tool z = +-x_B and Px = 0, ``q`` is
    empty; in the rare coaxial r = 0 case the isolated solutions are still listed. Unreachable poses give
    ``(empty, False)``.

    >>> q = [500.0, 0.3, 0.2, -0.4, 1.0, 0.5]
    >>> sols = carm_ik_oracle(carm_fk(q))
    >>> sols.shape[1], bool(np.any(np.all(np.abs(sols - q) < 1e-9, axis=1)))
    (6, True)
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

    Q = P.polynomial()[0]
    c = Q.coef.copy()
    big = np.max(np.abs(c)) if c.size else 0.0
    if big == 0.0:  # Q == 0 exactly but not caught above (zy = zz = 0 and Px = 0 to the bit)
        return empty, True
    degenerate = False
    cands: list[tuple[int, float, Array]] = []  # (priority, error, q); lower priority wins in dedupe

    def add_t(t: float, e: float | None, priority: int) -> int:
        """Verify the configurations at t (branch e) and keep those that pass; returns how many did."""
        nonlocal degenerate
        qs, deg = P.configs_at(t, e)
        degenerate |= deg
        n_ok = 0
        for q in qs:
            err = P.verify(q)
            if err is not None:
                cands.append((priority, err, q))
                n_ok += 1
        return n_ok

    keep = np.nonzero(np.abs(c) > LEAD_TRIM * big)[0]
    c = c[: keep[-1] + 1]
    raw = np.roots(c[::-1]) if c.size > 1 else np.zeros(0, dtype=complex)
    raw = raw[(np.abs(raw.imag) < IMAG_TOL) & (np.abs(raw.real) < 1.0 + 1e-6)]

    # Every near-real root of Q is polished on both branches (a root of Q is a root of F_+ or of F_-). It
    # belongs to each branch where F_e then vanishes to rounding, and at least to the better one (at the
    # elbow boundary h = 0, where F_+ = F_-, the noise bound of F_e is pessimistic).
    members: dict[float, list[float]] = {1.0: [], -1.0: []}
    for t0 in raw.real:
        pol = {e: P.newton_F(float(t0), e) for e in (1.0, -1.0)}
        best_e = min(pol, key=lambda e: pol[e][1])
        for e, (t1, ratio) in pol.items():
            if ratio <= CONVERGED or e == best_e:
                members[e].append(t1)
    for e in (1.0, -1.0):
        for alternatives in _branch_roots(P, e, np.sort(members[e]), raw.real, Q):
            for t in alternatives:
                if add_t(t, e, 0):
                    break

    # r = 0 family (wrist centre on the joint-2 axis).
    if abs(P.px) < PX_SEED:
        if P.px == 0.0:
            add_t(0.0, None, 0)
        else:
            for t0 in P.r0_seeds():
                for e in (1.0, -1.0):
                    t1, _ = P.newton_F(t0, e)
                    add_t(t1, e, 1)
            add_t(0.0, None, 2)

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


def _branch_roots(P: _Pose, e: float, members: Array, raw: Array, Q: Polynomial) -> list[list[float]]:
    """The distinct roots of F_e, from its sorted polished roots ``members``, each as a list of
    alternatives (best first; the caller keeps the first that passes the FK check).

    Members closer than CLUSTER_TOL form a group. A group whose members agree to rounding is one simple
    root. Otherwise the signs of F_e at the members, at the midpoints between them and just outside the
    group (only values beyond rounding noise count) decide: two or more sign changes are distinct roots,
    each refined by bisection; no sign change is one multiple root (a singular pose), located by
    ``_multiple_root``; one sign change is an odd-multiplicity root (``_multiple_root``, else bisection).
    The group member with the smallest |F_e| is always the last alternative.
    """
    out: list[list[float]] = []
    for ta, tb, _ in _clusters(members, CLUSTER_TOL, singletons=True):
        group = members[(members >= ta) & (members <= tb)]
        best = float(min(group, key=lambda t: abs(P.F(float(t), e)[0])))
        if tb - ta <= SAME_ROOT_TOL * (1.0 + abs(ta)):
            out.append([best])
            continue
        D = max(tb - ta, 0.5 * CLUSTER_TOL)
        pts = [ta - D]
        for i, t in enumerate(group):
            if i:
                pts.append(0.5 * (group[i - 1] + t))
            pts.append(float(t))
        pts.append(tb + D)
        sig = []
        for t in pts:
            F, _, noise = P.F(t, e)
            if abs(F) > noise:
                sig.append((t, float(np.sign(F))))
        changes = [(a[0], b[0]) for a, b in zip(sig[:-1], sig[1:], strict=True) if a[1] != b[1]]
        if len(changes) >= 2:
            for lo, hi in changes:
                inside = group[(group >= lo) & (group <= hi)]
                near = [float(min(inside, key=lambda t: abs(P.F(float(t), e)[0])))] if inside.size else []
                out.append([_bisect(P, e, lo, hi), *near])
            continue
        outside = (P.F(pts[0], e)[0], P.F(pts[-1], e)[0])
        alternatives = []
        ts = _multiple_root(P, e, group, outside, len(changes) == 1, raw, Q)
        if ts is not None:
            alternatives.append(ts)
        if changes:
            alternatives.append(_bisect(P, e, *changes[0]))
        out.append([*alternatives, best])
    return out


def _multiple_root(
    P: _Pose,
    e: float,
    group: Array,
    outside: tuple[float, float],
    odd: bool,
    raw: Array,
    Q: Polynomial,
) -> float | None:
    """A multiple root of F_e at the group of polished roots ``group``, to full precision, or None.

    np.roots returns a root of multiplicity m as m roots scattered by ~eps^(1/m), and the root of Q^(m-1)
    is simple: it is tried for m = (raw roots nearby) down to 2, then the root of F_e'. A candidate must lie
    at the group and make F_e vanish to the rounding level seen across the group; for an even
    multiplicity (``odd`` False) it is also accepted if F_e there has the sign F_e has on both sides
    (``outside``: F_e just left and right of the group), i.e. touches zero without crossing (a near-double
    root).
    """
    ta, tb = float(group[0]), float(group[-1])
    at_members = [P.F(float(t), e) for t in group]
    # The rounding level across the group (the noise bound is relative to F's terms, which may all be
    # tiny at a single point, e.g. at t = 0).
    level = max(max(abs(F) for F, _, _ in at_members), CONVERGED * max(n for _, _, n in at_members))

    def acceptable(ts: float | None) -> bool:
        # Newton leaves the members of a double root up to ~sqrt(noise / F'') ~ 1e-8 away, possibly all
        # on one side; the |F_e| test below is what rejects a wrong derivative root.
        if ts is None or not (ta - MULTIPLE_WINDOW <= ts <= tb + MULTIPLE_WINDOW):
            return False
        Fs, _, noise = P.F(ts, e)
        if abs(Fs) <= max(CONVERGED * noise, level):
            return True
        return not odd and bool(np.sign(Fs) == np.sign(outside[0]) == np.sign(outside[1]))

    m = int(np.sum((raw >= ta - RAW_CLUSTER_TOL) & (raw <= tb + RAW_CLUSTER_TOL)))
    for order in range(m - 1, 0, -1):
        ts = _newton_poly(Q.deriv(order), 0.5 * (ta + tb), tb - ta)
        if acceptable(ts):
            return ts
    ts = P.root_of_derivative(ta, tb, e)
    return ts if acceptable(ts) else None


def _bisect(P: _Pose, e: float, lo: float, hi: float) -> float:
    """Bisection for the sign change of F_e in [lo, hi]."""
    flo = np.sign(P.F(lo, e)[0])
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid in (lo, hi):
            break
        fm = np.sign(P.F(mid, e)[0])
        if fm == 0.0:
            return mid
        if fm == flo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _clusters(ts: Array, tol: float, singletons: bool = False) -> list[tuple[float, float, int]]:
    """(first, last, size) of groups of sorted values closer than tol to a neighbour (size >= 2 unless
    ``singletons``)."""
    out: list[tuple[float, float, int]] = []
    i = 0
    while i < len(ts):
        j = i
        while j + 1 < len(ts) and ts[j + 1] - ts[j] < tol:
            j += 1
        if j > i or singletons:
            out.append((float(ts[i]), float(ts[j]), j - i + 1))
        i = j + 1
    return out


def _newton_poly(p: Polynomial, t0: float, span: float) -> float | None:
    """Newton on polynomial p from t0; None if it leaves t0 +- span (+ 1e-4) or does not settle."""
    dp = p.deriv()
    t = t0
    for _ in range(NEWTON_ITERS):
        d = dp(t)
        if d == 0.0:
            break
        step = p(t) / d
        t -= step
        if not np.isfinite(t) or abs(t - t0) > span + 1e-4:
            return None
        if abs(step) <= 1e-16 * (abs(t) + 1e-3):
            break
    return float(t)
