"""Every isolated inverse-kinematics solution of a general 6-joint chain (6R, 5R1P, 4R2P) by elimination.

Raghavan and Roth's 14 equations, eliminated as Manocha and Canny do into a 12x12 quadratic matrix polynomial (a
24x24 eigenproblem), with every coefficient obtained numerically by exact interpolation (no symbolic algebra). The
method, its arrangements and its failure modes: docs/decomposition.md, "The general method".

Input: a chain in product-of-exponentials form at q = 0 (``H (6, 3)`` joint axes, ``P (7, 3)`` link vectors,
``revolute (6,)``, ``R_end (3, 3)``: :class:`sweepik.model.chain.Chain`) and a target pose ``T (4, 4)`` in the same
frame. ``GeneralIK(H, P, revolute, R_end)`` is the per-arm setup: every arrangement built, the unusable dropped, the
rest ranked by trial solves, the compiled path's chosen (with ``prefer=``, another build's ``ranking``: its first
three alone where the first passes the trial solves). ``.solve(T) -> IKResult(q, continuum, info)``: the solutions,
revolute angles wrapped to (-pi, pi], each Newton-polished and checked by FK, and whether the pose is a continuum
(then ``q`` holds the members found). :class:`ArmNotSupportedError` at setup when no arrangement is well posed for the
arm. :mod:`sweepik.reductions.general` makes it a reduction.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from sweepik.errors import NoReductionError

__all__ = ["GeneralIK", "IKResult", "ArmNotSupportedError"]


class ArmNotSupportedError(NoReductionError):
    """The general elimination is not well posed for this arm (no usable arrangement of the joints)."""


# ------------------------------------------------------------------------------------------ small kernels
@njit(cache=True, error_model="numpy")
def _rotm(h, th):
    """Rotation matrix by angle th about unit axis h (Rodrigues)."""
    s = math.sin(th)
    c = math.cos(th)
    v = 1.0 - c
    x, y, z = h[0], h[1], h[2]
    R = np.empty((3, 3))
    R[0, 0] = c + x * x * v
    R[0, 1] = x * y * v - z * s
    R[0, 2] = x * z * v + y * s
    R[1, 0] = y * x * v + z * s
    R[1, 1] = c + y * y * v
    R[1, 2] = y * z * v - x * s
    R[2, 0] = z * x * v - y * s
    R[2, 1] = z * y * v + x * s
    R[2, 2] = c + z * z * v
    return R


@njit(cache=True, error_model="numpy")
def _mv(R, x):
    out = np.empty(3)
    for i in range(3):
        out[i] = R[i, 0] * x[0] + R[i, 1] * x[1] + R[i, 2] * x[2]
    return out


@njit(cache=True, error_model="numpy")
def _cross(a, b):
    out = np.empty(3)
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]
    return out


@njit(cache=True, error_model="numpy")
def _f14(p, u):
    """Raghavan-Roth's 14 quantities of a point p (relative to the reference point) and a unit direction u."""
    out = np.empty(14)
    pp = p[0] * p[0] + p[1] * p[1] + p[2] * p[2]
    pl = p[0] * u[0] + p[1] * u[1] + p[2] * u[2]
    c = _cross(p, u)
    for i in range(3):
        out[i] = u[i]
        out[3 + i] = p[i]
        out[6 + i] = c[i]
        out[11 + i] = pp * u[i] - 2.0 * pl * p[i]
    out[9] = pp
    out[10] = pl
    return out


@njit(cache=True, error_model="numpy")
def _apply_joint(kind, h, c, val, x, d, inverse):
    """Move point x and direction d by a joint's motion (revolute about the line (c, h) / prismatic along h)."""
    if kind == 1:  # revolute
        R = _rotm(h, -val if inverse else val)
        x2 = c + _mv(R, x - c)
        d2 = _mv(R, d)
        return x2, d2
    sgn = -1.0 if inverse else 1.0
    return x + sgn * val * h, d.copy()


@njit(cache=True, error_model="numpy")
def _v_moves(ops_kind, ops_h, ops_c, ops_slot, n_pre, Rt, pt, vals, start, stop, x, d):
    """The point ``x`` and direction ``d`` of the V side moved by its motions ``start .. stop - 1`` (the inverse
    motions, with the target T' applied before motion ``n_pre``)."""
    for j in range(start, stop):
        if j == n_pre:
            x = _mv(Rt, x) + pt
            d = _mv(Rt, d)
        x, d = _apply_joint(ops_kind[j], ops_h[j], ops_c[j], vals[ops_slot[j]], x, d, True)
    if stop == ops_kind.shape[0] and n_pre == stop:
        x = _mv(Rt, x) + pt
        d = _mv(Rt, d)
    return x, d


@njit(cache=True, error_model="numpy")
def _v_side(ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, vals):
    """The V side of the loop equation at joint values ``vals`` (3: slots e, a, b): the line of joint L moved
    by the inverse motions of the joints after L, the target T', then the inverse motions of the joints before
    e (e last), returned as its 14 Raghavan-Roth quantities relative to ``ref`` (a point of e's axis)."""
    n = ops_kind.shape[0]
    x, d = _v_moves(ops_kind, ops_h, ops_c, ops_slot, n_pre, Rt, pt, vals, 0, n, o.copy(), hl.copy())
    return _f14(x - ref, d)


@njit(cache=True, error_model="numpy")
def _slot_value(kind, off, x):
    """Joint value of a slot variable x: revolute theta = off + 2 atan(x); prismatic d = off + x."""
    if kind == 1:
        return off + 2.0 * math.atan(x)
    return off + x


@njit(cache=True, error_model="numpy")
def _pencil(ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, slot_kind, slot_off, G, q0, N):
    """Coefficients (C, B, A) of the 12x12 matrix polynomial S(x_e) = A x_e^2 + B x_e + C for one pose.

    The V side's 14 functions (minus the E side's constant part q0), multiplied by (1 + x^2) for each revolute
    slot, are polynomials of degree <= 2 in each slot variable: sampled at x in {-1, 0, 1}^3 and interpolated
    exactly (G = inverse Vandermonde with the (1 + x^2) weights); the eigen-joint's motion must be the V side's
    last (every arrangement's is). N (6 x 14) annihilates the E side; the 6
    resulting equations, also multiplied by x_a, form 12 equations in the 12 monomials x_a^i x_b^j
    (i <= 3, j <= 2)."""
    F = np.empty((3, 3, 3, 14))
    vals = np.zeros(3)
    n = ops_kind.shape[0]
    last = n - 1  # (the eigen-joint's motion is the V side's last: the others' are moved once per (a, b) node)
    for na in range(3):
        vals[1] = _slot_value(slot_kind[1], slot_off[1], na - 1.0)
        for nb in range(3):
            vals[2] = _slot_value(slot_kind[2], slot_off[2], nb - 1.0)
            x1, d1 = _v_moves(ops_kind, ops_h, ops_c, ops_slot, n_pre, Rt, pt, vals, 0, last, o.copy(), hl.copy())
            for ne in range(3):
                vals[0] = _slot_value(slot_kind[0], slot_off[0], ne - 1.0)
                x, d = _v_moves(ops_kind, ops_h, ops_c, ops_slot, n_pre, Rt, pt, vals, last, n, x1, d1)
                f = _f14(x - ref, d)
                for r in range(14):
                    F[ne, na, nb, r] = f[r] - q0[r]
    # project onto the 6 equations first (cheaper), then interpolate slot by slot
    Fp = np.zeros((3, 3, 3, 6))
    for ne in range(3):
        for na in range(3):
            for nb in range(3):
                for k in range(6):
                    s = 0.0
                    for r in range(14):
                        s += N[k, r] * F[ne, na, nb, r]
                    Fp[ne, na, nb, k] = s
    Cb = np.zeros((3, 3, 3, 6))
    for ne in range(3):
        for na in range(3):
            for ib in range(3):
                for k in range(6):
                    s = 0.0
                    for nb in range(3):
                        s += G[2, ib, nb] * Fp[ne, na, nb, k]
                    Cb[ne, na, ib, k] = s
    Ca = np.zeros((3, 3, 3, 6))
    for ne in range(3):
        for ia in range(3):
            for ib in range(3):
                for k in range(6):
                    s = 0.0
                    for na in range(3):
                        s += G[1, ia, na] * Cb[ne, na, ib, k]
                    Ca[ne, ia, ib, k] = s
    M = np.zeros((3, 12, 12))  # M[ie] is the coefficient of x_e^ie
    for ie in range(3):
        for ia in range(3):
            for ib in range(3):
                for k in range(6):
                    s = 0.0
                    for ne in range(3):
                        s += G[0, ie, ne] * Ca[ne, ia, ib, k]
                    M[ie, k, ia * 3 + ib] = s
                    M[ie, 6 + k, (ia + 1) * 3 + ib] = s
    return M


@njit(cache=True, error_model="numpy")
def _lu_solve_tolerant(S, b):
    """Solve S v = b by LU with partial pivoting; zero pivots replaced by a tiny number (inverse iteration)."""
    n = S.shape[0]
    A = S.copy()
    x = b.copy()
    scale = 0.0
    for i in range(n):
        for j in range(n):
            scale = max(scale, abs(A[i, j]))
    tiny = 1e-300 + 1e-17 * scale
    for k in range(n):
        p = k
        m = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > m:
                m = abs(A[i, k])
                p = i
        if p != k:
            for j in range(n):
                t = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = t
            t = x[k]
            x[k] = x[p]
            x[p] = t
        if abs(A[k, k]) < tiny:
            A[k, k] = tiny
        for i in range(k + 1, n):
            f = A[i, k] / A[k, k]
            A[i, k] = f
            for j in range(k + 1, n):
                A[i, j] -= f * A[k, j]
            x[i] -= f * x[k]
    for k in range(n - 1, -1, -1):
        s = x[k]
        for j in range(k + 1, n):
            s -= A[k, j] * x[j]
        x[k] = s / A[k, k]
    return x


@njit(cache=True, error_model="numpy")
def _null_vector(S, b0):
    """Unit vector v with S v ~ 0 (two steps of inverse iteration); also |S v| / |S| as a residual."""
    v = _lu_solve_tolerant(S, b0)
    nv = np.sqrt(np.sum(v * v))
    if not np.isfinite(nv) or nv == 0.0:
        return b0 / np.sqrt(np.sum(b0 * b0)), 1.0
    v = v / nv
    w = _lu_solve_tolerant(S, v)
    nw = np.sqrt(np.sum(w * w))
    if np.isfinite(nw) and nw > 0.0:
        v = w / nw
    r = S @ v
    return v, np.sqrt(np.sum(r * r)) / (np.sqrt(np.sum(S * S)) + 1e-300)


@njit(cache=True, error_model="numpy")
def _proj_ratio(u, w):
    """Homogeneous (alpha, beta) minimising |alpha u - beta w| (u ~ x w, x = beta / alpha); returned as the
    angle 2 atan2(beta, alpha) (= 2 atan x) and x itself (inf if alpha = 0)."""
    a = np.sum(u * u)
    b = -np.sum(u * w)
    c = np.sum(w * w)
    # smallest eigenvector of [[a, b], [b, c]]
    tr = 0.5 * (a + c)
    det = a * c - b * b
    disc = math.sqrt(max(tr * tr - det, 0.0))
    lam = tr - disc
    # (a - lam) al + b be = 0
    if abs(a - lam) + abs(b) >= abs(b) + abs(c - lam):
        al, be = -b, a - lam
    else:
        al, be = c - lam, -b
    if al == 0.0 and be == 0.0:
        al, be = 1.0, 0.0
    return 2.0 * math.atan2(be, al), (be / al if al != 0.0 else np.inf)


@njit(cache=True, error_model="numpy")
def _rot_into(h, th, out):
    s = math.sin(th)
    c = math.cos(th)
    v = 1.0 - c
    x, y, z = h[0], h[1], h[2]
    out[0, 0] = c + x * x * v
    out[0, 1] = x * y * v - z * s
    out[0, 2] = x * z * v + y * s
    out[1, 0] = y * x * v + z * s
    out[1, 1] = c + y * y * v
    out[1, 2] = y * z * v - x * s
    out[2, 0] = z * x * v - y * s
    out[2, 1] = z * y * v + x * s
    out[2, 2] = c + z * z * v


@njit(cache=True, error_model="numpy")
def _fk_core(H, P, rev, R_end, q, want_jac, J):
    """FK (R_tool, p_tool) and, if want_jac, the geometric Jacobian into J; allocation-light."""
    R = np.eye(3)
    Rr = np.empty((3, 3))
    tmp = np.empty((3, 3))
    p = np.empty(3)
    for k in range(3):
        p[k] = P[0, k]
    ax = np.empty((6, 3))
    pts = np.empty((6, 3))
    for i in range(6):
        for k in range(3):
            ax[i, k] = R[k, 0] * H[i, 0] + R[k, 1] * H[i, 1] + R[k, 2] * H[i, 2]
            pts[i, k] = p[k]
        if rev[i]:
            _rot_into(H[i], q[i], Rr)
            for a in range(3):
                for b in range(3):
                    tmp[a, b] = R[a, 0] * Rr[0, b] + R[a, 1] * Rr[1, b] + R[a, 2] * Rr[2, b]
            for a in range(3):
                for b in range(3):
                    R[a, b] = tmp[a, b]
        else:
            for k in range(3):
                p[k] += ax[i, k] * q[i]
        for k in range(3):
            p[k] += R[k, 0] * P[i + 1, 0] + R[k, 1] * P[i + 1, 1] + R[k, 2] * P[i + 1, 2]
    if want_jac:
        for i in range(6):
            if rev[i]:
                d0 = p[0] - pts[i, 0]
                d1 = p[1] - pts[i, 1]
                d2 = p[2] - pts[i, 2]
                J[0, i] = ax[i, 1] * d2 - ax[i, 2] * d1
                J[1, i] = ax[i, 2] * d0 - ax[i, 0] * d2
                J[2, i] = ax[i, 0] * d1 - ax[i, 1] * d0
                J[3, i] = ax[i, 0]
                J[4, i] = ax[i, 1]
                J[5, i] = ax[i, 2]
            else:
                J[0, i] = ax[i, 0]
                J[1, i] = ax[i, 1]
                J[2, i] = ax[i, 2]
                J[3, i] = 0.0
                J[4, i] = 0.0
                J[5, i] = 0.0
    Rt = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            Rt[a, b] = R[a, 0] * R_end[0, b] + R[a, 1] * R_end[1, b] + R[a, 2] * R_end[2, b]
    return Rt, p


@njit(cache=True, error_model="numpy")
def _chain_fk(H, P, rev, R_end, q):
    J = np.empty((6, 6))
    return _fk_core(H, P, rev, R_end, q, False, J)


@njit(cache=True, error_model="numpy")
def _ratios_std(M, x, b0):
    """Null vector of S(x) = A x^2 + B x + C (12x12, monomials x_a^i x_b^j, i <= 3, j <= 2) and the slot
    variables read from it: (theta-like 2 atan x_a, x_a, 2 atan x_b, x_b, null residual)."""
    S = M[2] * (x * x) + M[1] * x + M[0]
    v, res = _null_vector(S, b0)
    # x_a: rows i+1 ~ x_a rows i ; x_b: columns j+1 ~ x_b columns j
    ta, xa, tb, xb = _slot_ratios(v)
    return ta, xa, tb, xb, res


@njit(cache=True, error_model="numpy")
def _complete(
    vals,
    ops_kind,
    ops_h,
    ops_c,
    ops_slot,
    n_pre,
    o,
    hl,
    Rt,
    pt,
    ref,
    q0,
    pinvQ,
    E_kind,
    E_idx,
    slots_idx,
    L_idx,
    Ha,
    Pa,
    reva,
    Rend_a,
    RT,
):
    """Full configuration (arrangement joint order) from the three slot values (e, a, b): the E joints from
    the E side's monomials (least squares with Q: Q X = F_V - q0), joint L from the orientation."""
    q = np.zeros(6)
    for s in range(3):
        q[slots_idx[s]] = vals[s]
    f = _v_side(ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, vals) - q0
    X = pinvQ @ f  # monomials of the E side, without the constant: index m -> (b1, b2) = divmod(m + 1, 3)
    # E1 alone: (b1, 0) -> m = 3 * b1 - 1 ; E2 alone: (0, b2) -> m = b2 - 1
    if E_kind[0] == 1:
        q[E_idx[0]] = math.atan2(X[5], X[2])  # b1 = 1 cos, b1 = 2 sin
    else:
        q[E_idx[0]] = X[2]
    if E_kind[1] == 1:
        q[E_idx[1]] = math.atan2(X[1], X[0])
    else:
        q[E_idx[1]] = X[0]
    # joint L from the orientation: R_0..R_{L-1} R_L R_{L+1}..R_5 R_end = R_T
    Rpre = np.eye(3)
    for i in range(L_idx):
        if reva[i]:
            Rpre = Rpre @ _rotm(Ha[i], q[i])
    Rpost = Rend_a.copy()
    for i in range(5, L_idx, -1):
        if reva[i]:
            Rpost = _rotm(Ha[i], q[i]) @ Rpost
    RL = Rpre.T @ RT @ Rpost.T
    h = Ha[L_idx]
    w0 = 0.5 * (RL[2, 1] - RL[1, 2])
    w1 = 0.5 * (RL[0, 2] - RL[2, 0])
    w2 = 0.5 * (RL[1, 0] - RL[0, 1])
    q[L_idx] = math.atan2(h[0] * w0 + h[1] * w1 + h[2] * w2, 0.5 * (RL[0, 0] + RL[1, 1] + RL[2, 2] - 1.0))
    return q


@njit(cache=True, error_model="numpy")
def _res_from(R, p, RT, pT):
    r = np.empty(6)
    for i in range(3):
        r[i] = p[i] - pT[i]
    # world-frame rotation error E = R RT^T: its skew part, plus (3 - tr E) / 2 (0 only at E = I, so a
    # rotation error of pi is not mistaken for a match)
    E = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            E[a, b] = R[a, 0] * RT[b, 0] + R[a, 1] * RT[b, 1] + R[a, 2] * RT[b, 2]
    r[3] = 0.5 * (E[2, 1] - E[1, 2])
    r[4] = 0.5 * (E[0, 2] - E[2, 0])
    r[5] = 0.5 * (E[1, 0] - E[0, 1])
    return r, 0.5 * (3.0 - E[0, 0] - E[1, 1] - E[2, 2])


@njit(cache=True, error_model="numpy")
def _residual6(H, P, rev, R_end, q, RT, pT):
    R, p = _chain_fk(H, P, rev, R_end, q)
    r, dev = _res_from(R, p, RT, pT)
    return r, p, dev


@njit(cache=True, error_model="numpy")
def _jac6(H, P, rev, q):
    J = np.empty((6, 6))
    _fk_core(H, P, rev, np.eye(3), q, True, J)
    return J


@njit(cache=True, error_model="numpy")
def _solve6(J, r):
    """Newton step -J^-1 r by Gaussian elimination with partial pivoting; also min|pivot| / max|pivot|."""
    A = J.copy()
    x = -r.copy()
    n = 6
    pmin = np.inf
    pmax = 0.0
    for k in range(n):
        p = k
        m = abs(A[k, k])
        for i in range(k + 1, n):
            if abs(A[i, k]) > m:
                m = abs(A[i, k])
                p = i
        if p != k:
            for j in range(n):
                t = A[k, j]
                A[k, j] = A[p, j]
                A[p, j] = t
            t = x[k]
            x[k] = x[p]
            x[p] = t
        pmin = min(pmin, m)
        pmax = max(pmax, m)
        if m == 0.0:
            return x, 0.0
        for i in range(k + 1, n):
            f = A[i, k] / A[k, k]
            for j in range(k + 1, n):
                A[i, j] -= f * A[k, j]
            x[i] -= f * x[k]
    for k in range(n - 1, -1, -1):
        s = x[k]
        for j in range(k + 1, n):
            s -= A[k, j] * x[j]
        x[k] = s / A[k, k]
    return x, pmin / pmax


#: The longest Newton step along a valley of near solutions that ``_polish`` re-projects onto it (radians; a slide's
#: over the arm's scale).
VALLEY_STEP = 0.05


@njit(cache=True, error_model="numpy")
def _onto_valley(H, P, rev, R_end, q, RT, pT):
    """``q`` moved onto the valley of near solutions beside it: two Newton steps in the five well-conditioned
    directions of the Jacobian only (``_polish``)."""
    for _k in range(2):
        r, p, dev = _residual6(H, P, rev, R_end, q, RT, pT)
        J = _jac6(H, P, rev, q)
        if not (np.all(np.isfinite(J)) and np.all(np.isfinite(r))):
            break
        U, S, Vt = np.linalg.svd(J)
        ur = U.T @ r
        for i in range(5):
            q = q - (ur[i] / S[i]) * Vt[i]
    return q


@njit(cache=True, error_model="numpy")
def _polish(H, P, rev, R_end, q0, RT, pT, max_iter, tol):
    """Newton on the full FK system, run until the residual stops decreasing (machine precision). Plain
    Newton (LU) while the Jacobian is well conditioned; otherwise an SVD pseudo-inverse step, Levenberg-
    Marquardt damping when a step fails to decrease the residual, and the doubled step, which restores fast
    convergence at a double root (singular Jacobian: Newton alone only halves the distance per step).
    Returns (q, |r|, ok, pivot ratio of the last Jacobian)."""
    q = q0.copy()
    r, p, dev = _residual6(H, P, rev, R_end, q, RT, pT)
    nr = math.sqrt(np.sum(r * r)) + dev
    pr = 1.0
    for it in range(max_iter):
        if not np.isfinite(nr):
            break
        J = _jac6(H, P, rev, q)
        if not np.all(np.isfinite(J)):
            nr = np.inf
            break
        step, pr = _solve6(J, r)
        if nr < tol:
            break
        # no real root near this start (e.g. a complex candidate): give up (from a complex pair's real part a double
        # root is still ~1e-5 away after 6 steps)
        if it >= 6 and nr > 1e-4:
            break
        improved = False
        smallstep = False
        if pr > 1e-7 and np.all(np.isfinite(step)):
            qn = q + step
            rn, pn, devn = _residual6(H, P, rev, R_end, qn, RT, pT)
            nn = math.sqrt(np.sum(rn * rn)) + devn
            if nn < nr:
                q = qn
                r = rn
                smallstep = math.sqrt(np.sum(step * step)) < 1e-16
                nr = nn
                if smallstep:
                    break
                continue
            if nr < 2e-15:  # a well-conditioned Newton step no longer helps: at the rounding floor
                break
        U, S, Vt = np.linalg.svd(J)
        ur = U.T @ r
        if S[5] < 1e-6 * S[0]:
            # near a double root: the pseudo-inverse Newton step, and the doubled step re-projected onto the
            # solution valley by steps in the well-conditioned directions only (a straight step leaves the
            # curved valley, so its residual alone does not show the progress); keep the better
            step = np.zeros(6)
            for i in range(6):
                if S[i] > 1e-15 * S[0]:
                    step -= (ur[i] / S[i]) * Vt[i]
            qn = q + step
            rn, pn, devn = _residual6(H, P, rev, R_end, qn, RT, pT)
            nn = math.sqrt(np.sum(rn * rn)) + devn
            for times in (2.0, 1.0):
                # (the step itself re-projected only where neither gains and it is short: along a valley of near
                # solutions, its Jacobian nearly singular all along it, the I2RT big YAM rewritten stalled 1e-2 rad
                # from its root at 1e-10; tried first, or a longer one, it carried candidates along such valleys
                # over to another root, 0.5 rad on)
                if times == 1.0 and (nn < 0.9 * nr or np.max(np.abs(step)) > VALLEY_STEP):
                    break
                q2 = _onto_valley(H, P, rev, R_end, q + times * step, RT, pT)
                r2, p2, dev2 = _residual6(H, P, rev, R_end, q2, RT, pT)
                n2 = math.sqrt(np.sum(r2 * r2)) + dev2
                if n2 < nn:
                    qn, rn, nn = q2, r2, n2
            if nn < 0.9 * nr:
                q, r, nr = qn, rn, nn
                continue
            if nn < nr:
                q, r, nr = qn, rn, nn
            break
        lam = 0.0
        for _ in range(8):
            step = np.zeros(6)
            for i in range(6):
                den = S[i] * S[i] + lam
                if S[i] > 1e-15 * S[0] and den > 0.0:
                    step -= (S[i] * ur[i] / den) * Vt[i]
            qn = q + step
            rn, pn, devn = _residual6(H, P, rev, R_end, qn, RT, pT)
            nn = math.sqrt(np.sum(rn * rn)) + devn
            if nn < nr:
                q = qn
                r = rn
                improved = True
                smallstep = math.sqrt(np.sum(step * step)) < 1e-16
                nr = nn
                break
            lam = max(lam * 10.0, 1e-10 * S[0] * S[0] + 1e-300)
        if not improved or smallstep:
            break
    return q, nr, np.isfinite(nr) and nr < 1e-11, pr


@njit(cache=True, error_model="numpy")
def _poses_err(H, P, rev, R_end, q, RT, pT):
    """(position error, rotation error (rad)) of FK(q) against the target, accurate near 0."""
    R, p = _chain_fk(H, P, rev, R_end, q)
    dp = math.sqrt((p[0] - pT[0]) ** 2 + (p[1] - pT[1]) ** 2 + (p[2] - pT[2]) ** 2)
    E = R.T @ RT
    w0 = 0.5 * (E[2, 1] - E[1, 2])
    w1 = 0.5 * (E[0, 2] - E[2, 0])
    w2 = 0.5 * (E[1, 0] - E[0, 1])
    s = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    c = 0.5 * (E[0, 0] + E[1, 1] + E[2, 2] - 1.0)
    return dp, math.atan2(s, c)


@njit(cache=True, error_model="numpy")
def _candidates_std(
    M,
    xs,
    ims,
    phi,
    b0,
    ops_kind,
    ops_h,
    ops_c,
    ops_slot,
    n_pre,
    o,
    hl,
    Rt,
    pt,
    ref,
    slot_kind,
    slot_off,
    q0,
    pinvQ,
    E_kind,
    E_idx,
    slots_idx,
    L_idx,
    Ha,
    Pa,
    reva,
    Rend_a,
    RTa,
    reversed_,
    H,
    P,
    rev,
    R_end,
    RT,
    pT,
    fk_tol,
):
    """Back-substitute and polish every candidate root (std construction) in one compiled loop. Returns
    (solutions (k, 6), pivot ratio of J at each, number of essentially-real candidates that failed).

    A candidate that does not polish and is real or nearly (``|Im x| < PAIR_IMAG``) may be one of two roots with
    nearly the same eigen-joint value (a near-double eigenvalue, often a complex pair by rounding) but different
    other joints: ``S(x)`` then has a two-dimensional null space, whose one vector from inverse iteration mixes the
    two roots. It is tried again from the two monomial vectors of that space (``_pair_vectors``)."""
    n = xs.shape[0]
    out = np.empty((2 * n, 6))
    prs = np.empty(2 * n)
    k = 0
    nfail = 0
    args = (ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, q0, pinvQ, E_kind, E_idx, slots_idx, L_idx)
    chain = (Ha, Pa, reva, Rend_a, RTa, reversed_, H, P, rev, R_end, RT, pT, fk_tol)
    for i in range(n):
        x = xs[i]
        if slot_kind[0] == 0 and abs(x) > 1e6:  # a prismatic length of 1e6 arm sizes: a root at infinity
            continue
        ta, xa, tb, xb, res = _ratios_std(M, x, b0)
        found = False
        pair = (np.zeros(0), np.zeros(0))
        for attempt in range(3):  # (one call site of _root_at: it is large, and compiled code inlines it)
            if attempt > 0:
                if not ims[i] < PAIR_IMAG:
                    break
                if attempt == 1:
                    pair = _pair_vectors(M[2] * (x * x) + M[1] * x + M[0])
                v = pair[attempt - 1]
                if v.shape[0] == 0:
                    continue
                ta, xa, tb, xb = _slot_ratios(v)
            qp, ok, pr = _root_at(x, ta, xa, tb, xb, phi, slot_kind, slot_off, args, chain)
            if ok:
                out[k], prs[k] = qp, pr
                k += 1
                found = True
                if attempt == 0:
                    break
        if not found and ims[i] < PAIR_IMAG:
            nfail += 1
    return out[:k].copy(), prs[:k].copy(), nfail


#: A candidate eigenvalue with ``|Im x| / (1 + |x|^2)`` below this that does not polish is tried as one of a close
#: pair of roots (``_candidates_std``), and counted as a failure if that fails too (the pose is then asked of another
#: arrangement). (1e-6 lost a pair 3e-5 rad apart next to the singular set whose eigenvalues a 1-ulp rounding of the
#: pose turned complex: ``dh_chain(16)``; 1e-4 lost the I2RT big YAM's, rewritten, on its singular set: two roots
#: whose eigenvalues came out as a pair 3.5e-3 off the real axis, each null vector mixing the two, while the first
#: arrangement gave the other two, regular, and no sign of a loss.)
PAIR_IMAG = 1e-2


@njit(cache=True, error_model="numpy")
def _slot_ratios(v):
    """The slot variables read from a monomial vector ``v`` (12: ``x_a^i x_b^j``, i <= 3, j <= 2): ``(2 atan x_a,
    x_a, 2 atan x_b, x_b)``."""
    V = v.reshape(4, 3)
    ta, xa = _proj_ratio(V[1:4, :].copy().ravel(), V[0:3, :].copy().ravel())
    tb, xb = _proj_ratio(V[:, 1:3].copy().ravel(), V[:, 0:2].copy().ravel())
    return ta, xa, tb, xb


@njit(cache=True, error_model="numpy")
def _pair_vectors(S):
    """The two monomial vectors in the two-dimensional near-null space of ``S`` (12x12): the combinations
    ``alpha A + beta B`` of its two last right singular vectors whose 4x3 reshape has rank one. Every 2x2 minor of
    that reshape is a quadratic form in ``(alpha, beta)`` vanishing at both; their common factor is the dominant
    singular vector of the minors' coefficients. Two vectors (an empty one where the factor has complex roots)."""
    _, _, Vt = np.linalg.svd(S)
    A = Vt[11].copy().reshape(4, 3)
    B = Vt[10].copy().reshape(4, 3)
    C = np.empty((18, 3))
    r = 0
    for i0 in range(4):
        for i1 in range(i0 + 1, 4):
            for j0 in range(3):
                for j1 in range(j0 + 1, 3):
                    if r < 18:
                        # det [[A00 + t B00, A01 + t B01], [A10 + t B10, A11 + t B11]] in (alpha, beta) = (1, t)
                        a00, a01, a10, a11 = A[i0, j0], A[i0, j1], A[i1, j0], A[i1, j1]
                        b00, b01, b10, b11 = B[i0, j0], B[i0, j1], B[i1, j0], B[i1, j1]
                        C[r, 0] = a00 * a11 - a01 * a10
                        C[r, 1] = a00 * b11 + b00 * a11 - a01 * b10 - b01 * a10
                        C[r, 2] = b00 * b11 - b01 * b10
                        r += 1
    _, _, W = np.linalg.svd(C)
    c0, c1, c2 = W[0, 0], W[0, 1], W[0, 2]  # c0 + c1 t + c2 t^2 (t = beta / alpha)
    empty = np.zeros(0)
    disc = c1 * c1 - 4.0 * c0 * c2
    if disc < 0.0:
        return empty, empty
    sq = math.sqrt(disc)
    # homogeneous roots (alpha, beta), stable for either coefficient small
    if abs(c2) >= abs(c0):
        q = -0.5 * (c1 + math.copysign(sq, c1))
        r1 = (c2, q) if q != 0.0 else (1.0, 0.0)  # t = q / c2
        r2 = (q, c0) if q != 0.0 else (0.0, 1.0)  # t = c0 / q
    else:
        q = -0.5 * (c1 + math.copysign(sq, c1))
        r1 = (q, c0) if q != 0.0 else (0.0, 1.0)
        r2 = (c2, q) if q != 0.0 else (1.0, 0.0)
    v1 = (r1[0] * A + r1[1] * B).ravel()
    v2 = (r2[0] * A + r2[1] * B).ravel()
    return v1 / np.sqrt(np.sum(v1 * v1)), v2 / np.sqrt(np.sum(v2 * v2))


@njit(cache=True, error_model="numpy")
def _root_at(x, ta, xa, tb, xb, phi, slot_kind, slot_off, args, chain):
    """The configuration of the eigen-joint's value ``x`` and the other slots' ``(2 atan x_a, x_a, 2 atan x_b, x_b)``:
    completed, polished on the full chain and FK-checked: ``(q, ok, pivot ratio of J)``."""
    ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, q0, pinvQ, E_kind, E_idx, slots_idx, L_idx = args
    Ha, Pa, reva, Rend_a, RTa, reversed_, H, P, rev, R_end, RT, pT, fk_tol = chain
    vals = np.empty(3)
    vals[0] = phi + 2.0 * math.atan(x) if slot_kind[0] == 1 else x
    if slot_kind[1] == 1:
        vals[1] = slot_off[1] + ta
    else:
        vals[1] = slot_off[1] + (xa if np.isfinite(xa) else 1e6)
    if slot_kind[2] == 1:
        vals[2] = slot_off[2] + tb
    else:
        vals[2] = slot_off[2] + (xb if np.isfinite(xb) else 1e6)
    q = _complete(
        vals, ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, q0, pinvQ, E_kind, E_idx, slots_idx, L_idx,
        Ha, Pa, reva, Rend_a, RTa,
    )  # fmt: skip
    if reversed_:
        q = q[::-1].copy()
    qp, nr, ok, pr = _polish(H, P, rev, R_end, q, RT, pT, 60, 1e-17)
    if ok:
        dp, dr = _poses_err(H, P, rev, R_end, qp, RT, pT)
        ok = dp < fk_tol and dr < fk_tol
    if ok:
        for j in range(6):
            if rev[j]:
                qp[j] = math.pi - ((math.pi - qp[j]) % (2.0 * math.pi))
    return qp, ok, pr


@njit(cache=True, error_model="numpy")
def _inv_rc(A):
    """Inverse by Gauss-Jordan with partial pivoting and the reciprocal 1-norm condition number (0 when a
    pivot vanishes)."""
    n = A.shape[0]
    W = A.copy()
    X = np.eye(n)
    for k in range(n):
        p = k
        m = abs(W[k, k])
        for i in range(k + 1, n):
            if abs(W[i, k]) > m:
                m = abs(W[i, k])
                p = i
        if m == 0.0:
            return X, 0.0
        if p != k:
            for j in range(n):
                t = W[k, j]
                W[k, j] = W[p, j]
                W[p, j] = t
                t = X[k, j]
                X[k, j] = X[p, j]
                X[p, j] = t
        piv = W[k, k]
        for j in range(n):
            W[k, j] /= piv
            X[k, j] /= piv
        for i in range(n):
            if i != k:
                f = W[i, k]
                if f != 0.0:
                    for j in range(n):
                        W[i, j] -= f * W[k, j]
                        X[i, j] -= f * X[k, j]
    na = 0.0
    nx = 0.0
    for j in range(n):
        sa = 0.0
        sx = 0.0
        for i in range(n):
            sa += abs(A[i, j])
            sx += abs(X[i, j])
        na = max(na, sa)
        nx = max(nx, sx)
    return X, 1.0 / (na * nx)


@njit(cache=True, error_model="numpy")
def _std_front(Rt, pt, phis, ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, ref, slot_kind, slot_off, G, q0, N):
    """Per-pose front end of the std construction with a revolute eigen-joint: the matrix polynomial for a
    few shifts phi of the half-angle variable until the leading matrix is well conditioned, and the 24x24
    companion matrix."""
    best_rc = -1.0
    best_phi = 0.0
    bestM = np.zeros((3, 12, 12))
    bestAinv = np.zeros((12, 12))
    so = slot_off.copy()
    for k in range(phis.shape[0]):
        so[0] = phis[k]
        M = _pencil(ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, slot_kind, so, G, q0, N)
        Ainv, rc = _inv_rc(M[2])
        if rc > best_rc:
            best_rc = rc
            best_phi = phis[k]
            bestM = M
            bestAinv = Ainv
        if rc > 1e-6:
            break
    Cm = np.zeros((24, 24))
    for i in range(12):
        Cm[i, 12 + i] = 1.0
    Cm[12:, :12] = -(bestAinv @ bestM[0])
    Cm[12:, 12:] = -(bestAinv @ bestM[1])
    return Cm, bestM, best_phi, best_rc


@njit(cache=True, error_model="numpy")
def _pose_in_nb(RT, pT, reversed_, M0R, M0p):
    """The target in an arrangement's chain: (RTa, pTa) (inverted for a reversed chain) and T' = T M0^-1."""
    if reversed_:
        RTa = RT.T.copy()
        pTa = -(RT.T @ pT)
    else:
        RTa = RT.copy()
        pTa = pT.copy()
    Rt = RTa @ M0R.T
    pt = pTa - Rt @ M0p
    return RTa, pTa, Rt, pt


@njit(cache=True, error_model="numpy")
def _filter_candidates(ev, imag_tol):
    """Real parts and the imaginary-part measure |Im x| / (1 + |x|^2) of the eigenvalues kept as candidates."""
    n = ev.shape[0]
    xs = np.empty(n)
    ims = np.empty(n)
    k = 0
    for i in range(n):
        x = ev[i].real
        im = abs(ev[i].imag) / (1.0 + abs(ev[i]) ** 2)
        if np.isfinite(x) and im < imag_tol:
            xs[k] = x
            ims[k] = im
            k += 1
    return xs[:k].copy(), ims[:k].copy()


@njit(cache=True, error_model="numpy")
def _merge_nb(S, rev, tol):
    n = S.shape[0]
    keep = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        dup = False
        for j in range(i):
            if keep[j]:
                dmax = 0.0
                for c in range(6):
                    d = S[i, c] - S[j, c]
                    if rev[c]:
                        d = (d + math.pi) % (2.0 * math.pi) - math.pi
                    dmax = max(dmax, abs(d))
                if dmax < tol:
                    dup = True
                    break
        keep[i] = not dup
    return keep


# ------------------------------------------------------------------------------------------- per-arm setup
_XN = np.array([-1.0, 0.0, 1.0])
_VAND = np.vander(_XN, 3, increasing=True)  # rows: node, cols: power
_G_REV = np.linalg.inv(_VAND) @ np.diag(1.0 + _XN**2)  # node values of f -> coefficients of (1+x^2) f
_G_PRI = np.linalg.inv(_VAND)
_TH_E = np.array([0.0, 2.0 * np.pi / 3.0, 4.0 * np.pi / 3.0])
_EV_REV = np.stack([np.ones(3), np.cos(_TH_E), np.sin(_TH_E)], axis=1)  # node -> (1, cos, sin)
_EV_PRI = np.vander(_XN, 3, increasing=True)  # node -> (1, d, d^2)


def _reverse_chain(H, P, rev, R_end):
    Rt = R_end.T
    return -(H[::-1] @ Rt.T), -(P[::-1] @ Rt.T), rev[::-1].copy(), Rt.copy()


#: Every arrangement tried, ``(reversed, L, swapped)``: the chain or its reverse, the joint whose line is used, the
#: family of splits (``_make_arrangement``, ``_make_swapped``).
ARRANGEMENTS = tuple((r, L, sw) for r in (False, True) for L in (5, 4, 3) for sw in (False, True))
#: Arrangements after the first that ``GeneralIK.solve`` asks for a second opinion on a suspicious pose.
SECOND_OPINIONS = 2


@dataclass
class _Arrangement:
    """One way of splitting the loop (docs/decomposition.md): chain (maybe reversed), L = joint whose line is used,
    E = the two joints eliminated with the per-arm matrix Q, e = the eigenvalue joint, a, b = the two joints
    recovered from the eigenvector."""

    reversed: bool
    L: int
    E: tuple[int, int]
    e: int
    ab: tuple[int, int]
    H: np.ndarray
    P: np.ndarray
    rev: np.ndarray
    R_end: np.ndarray
    M0: np.ndarray  # (4, 4) FK at q = 0 of this chain
    ops_kind: np.ndarray
    ops_h: np.ndarray
    ops_c: np.ndarray
    ops_slot: np.ndarray
    n_pre: int
    o: np.ndarray
    hl: np.ndarray
    ref: np.ndarray
    slot_kind: np.ndarray
    slot_off: np.ndarray
    slots_idx: np.ndarray
    E_kind: np.ndarray
    E_idx: np.ndarray
    q0: np.ndarray
    N: np.ndarray
    pinvQ: np.ndarray
    q_cond: float  # sigma_8 / sigma_1 of Q
    name: str = ""
    kind: str = "std"  # "std": 6 equations x (1, x_a) -> 12x12 ; "lowp": see _lowp_system
    p_slot: int = 0
    top_rank: int = 0
    Zp: np.ndarray | None = None
    swapped: bool = False
    b_ops: tuple | None = None
    b_nodes: np.ndarray | None = None
    b_inv: np.ndarray | None = None
    score: float = 0.0
    G: np.ndarray | None = None  # (3, 3, 3): per slot, node values -> monomial coefficients
    key: int = -1  # (its index in ARRANGEMENTS)
    trial_rcond: float = math.inf  # (the worst leading matrix's conditioning on the trial poses)
    trial_suspicious: int = 0  # (trial poses ``GeneralIK.solve`` would ask another arrangement about)
    trial_misses: int = 0  # (trial configurations it did not recover)

    def __post_init__(self):
        assert self.ops_slot[-1] == 0, "the eigen-joint's motion must be the V side's last (_pencil)"
        self.M0R = np.ascontiguousarray(self.M0[:3, :3])
        self.M0p = np.ascontiguousarray(self.M0[:3, 3])


def _make_arrangement(H, P, rev, R_end, reversed_, L, rng):
    """Arrangement with line joint L (0-based, in {5, 4, 3}) of the given (possibly reversed) chain, or None
    when it is structurally unusable."""
    e = L - 3
    E = (L - 2, L - 1)
    pre = list(range(L + 1, 6))  # inverse motions before T'
    post = list(range(0, e + 1))  # inverse motions after T' (e last)
    ab = tuple(j for j in pre + post if j != e)
    if not rev[L]:
        return None
    if (not rev[E[0]]) and (not rev[E[1]]):
        return None
    if (not rev[ab[0]]) and (not rev[ab[1]]):
        return None
    pts = np.cumsum(P[:6], axis=0)  # point of each joint's axis at q = 0
    M0 = np.eye(4)
    M0[:3, :3] = R_end
    M0[:3, 3] = P.sum(axis=0)
    slot = {e: 0, ab[0]: 1, ab[1]: 2}
    order = pre + post
    ops_kind = np.array([1 if rev[j] else 0 for j in order], dtype=np.int64)
    ops_h = np.array([H[j] for j in order], dtype=np.float64)
    ops_c = np.array([pts[j] for j in order], dtype=np.float64)
    ops_slot = np.array([slot[j] for j in order], dtype=np.int64)
    o = pts[L].copy()
    hl = H[L].copy()
    ref = pts[e].copy()
    slot_kind = np.array([1 if rev[j] else 0 for j in (e, ab[0], ab[1])], dtype=np.int64)
    slot_off = np.array(
        [0.0, rng.uniform(-np.pi, np.pi) if rev[ab[0]] else 0.0, rng.uniform(-np.pi, np.pi) if rev[ab[1]] else 0.0]
    )
    # E side: g_E1 g_E2 applied to L's line, 14 quantities relative to ref, interpolated on a 3x3 grid
    E_kind = np.array([1 if rev[j] else 0 for j in E], dtype=np.int64)
    nodes = [(_TH_E if rev[j] else _XN) for j in E]
    Fe = np.empty((3, 3, 14))
    for n1 in range(3):
        for n2 in range(3):
            x, d = o.copy(), hl.copy()
            x, d = _apply_joint(E_kind[1], H[E[1]], pts[E[1]], nodes[1][n2], x, d, False)
            x, d = _apply_joint(E_kind[0], H[E[0]], pts[E[0]], nodes[0][n1], x, d, False)
            Fe[n1, n2] = _f14(x - ref, d)
    inv1 = np.linalg.inv(_EV_REV if rev[E[0]] else _EV_PRI)
    inv2 = np.linalg.inv(_EV_REV if rev[E[1]] else _EV_PRI)
    Qfull = np.einsum("an,bm,nmr->rab", inv1, inv2, Fe).reshape(14, 9)
    q0 = Qfull[:, 0].copy()
    Q = Qfull[:, 1:]
    U, sv, Vt = np.linalg.svd(Q)
    q_cond = sv[7] / sv[0]
    N = U[:, 8:].T.copy()
    pinvQ = (Vt.T / sv) @ U[:, :8].T
    G = np.stack([_G_REV if k == 1 else _G_PRI for k in slot_kind])
    return _Arrangement(
        reversed=reversed_,
        L=L,
        E=E,
        e=e,
        ab=ab,
        H=H,
        P=P,
        rev=rev,
        R_end=R_end,
        M0=M0,
        ops_kind=ops_kind,
        ops_h=ops_h,
        ops_c=ops_c,
        ops_slot=ops_slot,
        n_pre=len(pre),
        o=o,
        hl=hl,
        ref=ref,
        slot_kind=slot_kind,
        slot_off=slot_off,
        slots_idx=np.array([e, ab[0], ab[1]], dtype=np.int64),
        E_kind=E_kind,
        E_idx=np.array(E, dtype=np.int64),
        q0=q0,
        N=N,
        pinvQ=pinvQ,
        q_cond=float(q_cond),
        name=f"{'rev' if reversed_ else 'fwd'}-L{L}",
        G=G,
    )


def _make_swapped(H, P, rev, R_end, reversed_, L, rng):
    """The other family of splits (Raghavan-Roth's and ssik's): the pose-free side g_e g_E1 g_E2 (line L) is
    the one kept (e, E1 = L-2, E2 = L-1 are the eigenvalue joint and the two joints read from the
    eigenvector) and the pair on the target's side is eliminated with a matrix Q(T) that depends on the pose
    (its null space and pseudo-inverse are then computed per pose, by an SVD of a 14 x 8 matrix). The kept
    side is evaluated by the same kernel as the V side: forward motions are inverse motions about the negated
    axis, and T' is the identity."""
    e = L - 3
    E1, E2 = L - 2, L - 1
    pre = list(range(L + 1, 6))
    post = list(range(0, e))
    B = pre + post  # the eliminated pair, in the order of its motions
    if not rev[L] or len(B) != 2:
        return None
    if (not rev[B[0]]) and (not rev[B[1]]):
        return None
    if (not rev[E1]) and (not rev[E2]):
        return None
    pts = np.cumsum(P[:6], axis=0)
    M0 = np.eye(4)
    M0[:3, :3] = R_end
    M0[:3, 3] = P.sum(axis=0)
    order = [E2, E1, e]  # g_e g_E1 g_E2: E2 moves the line first
    slot = {e: 0, E1: 1, E2: 2}
    ops_kind = np.array([1 if rev[j] else 0 for j in order], dtype=np.int64)
    ops_h = np.array([-H[j] for j in order], dtype=np.float64)
    ops_c = np.array([pts[j] for j in order], dtype=np.float64)
    ops_slot = np.array([slot[j] for j in order], dtype=np.int64)
    slot_kind = np.array([1 if rev[j] else 0 for j in (e, E1, E2)], dtype=np.int64)
    slot_off = np.array(
        [0.0, rng.uniform(-np.pi, np.pi) if rev[E1] else 0.0, rng.uniform(-np.pi, np.pi) if rev[E2] else 0.0]
    )
    bslot = {B[0]: 1, B[1]: 2}
    b_kind = np.array([1 if rev[j] else 0 for j in pre + post], dtype=np.int64)
    b_h = np.array([H[j] for j in pre + post], dtype=np.float64)
    b_c = np.array([pts[j] for j in pre + post], dtype=np.float64)
    b_slot = np.array([bslot[j] for j in pre + post], dtype=np.int64)
    b_nodes = np.stack([(_TH_E if rev[j] else _XN) for j in B])
    b_inv = np.stack([np.linalg.inv(_EV_REV if rev[j] else _EV_PRI) for j in B])
    G = np.stack([_G_REV if k == 1 else _G_PRI for k in slot_kind])
    a = _Arrangement(
        reversed=reversed_,
        L=L,
        E=tuple(B),
        e=e,
        ab=(E1, E2),
        H=H,
        P=P,
        rev=rev,
        R_end=R_end,
        M0=M0,
        ops_kind=ops_kind,
        ops_h=ops_h,
        ops_c=ops_c,
        ops_slot=ops_slot,
        n_pre=0,
        o=pts[L].copy(),
        hl=H[L].copy(),
        ref=pts[e].copy(),
        slot_kind=slot_kind,
        slot_off=slot_off,
        slots_idx=np.array([e, E1, E2], dtype=np.int64),
        E_kind=b_kind[np.argsort(b_slot)].copy(),
        E_idx=np.array(B, dtype=np.int64)[np.argsort(b_slot)].copy(),
        q0=None,
        N=None,
        pinvQ=None,
        q_cond=1.0,
        name=f"{'rev' if reversed_ else 'fwd'}-L{L}-sw",
        G=G,
    )
    a.swapped = True
    a.b_ops = (b_kind, b_h, b_c, b_slot, len(pre))
    a.b_nodes, a.b_inv = b_nodes, b_inv
    return a


@njit(cache=True, error_model="numpy")
def _sw_pose_Q(b_kind, b_h, b_c, b_slot, n_pre, o, hl, Rt, pt, ref, b_nodes, b_inv):
    """Per pose, for a swapped arrangement: the eliminated side's 14 functions of its two joints, interpolated
    on a 3x3 grid -> q0 (14), N (6 x 14, left null space of Q), pinv(Q) (8 x 14), sigma_8 / sigma_1."""
    F = np.empty((3, 3, 14))
    vals = np.zeros(3)
    for n1 in range(3):
        vals[1] = b_nodes[0, n1]
        for n2 in range(3):
            vals[2] = b_nodes[1, n2]
            F[n1, n2] = _v_side(b_kind, b_h, b_c, b_slot, n_pre, o, hl, Rt, pt, ref, vals)
    Qf = np.zeros((14, 9))
    for r in range(14):
        for a in range(3):
            for b in range(3):
                acc = 0.0
                for n1 in range(3):
                    for n2 in range(3):
                        acc += b_inv[0, a, n1] * b_inv[1, b, n2] * F[n1, n2, r]
                Qf[r, a * 3 + b] = acc
    q0 = Qf[:, 0].copy()
    Q = Qf[:, 1:].copy()
    U, sv, Vt = np.linalg.svd(Q)
    N = U[:, 8:].T.copy()
    pinvQ = np.zeros((8, 14))
    for i in range(8):
        if sv[i] > 1e-14 * sv[0]:
            for r in range(8):
                for c in range(14):
                    pinvQ[r, c] += Vt[i, r] * U[c, i] / sv[i]
    return q0, N, pinvQ, sv[7] / sv[0]


@dataclass
class IKResult:
    q: np.ndarray  # (k, 6) solutions
    continuum: bool  # the pose has a continuum of solutions (q then holds what was found, may be empty)
    info: dict


# candidate filter: |Im theta_e| (approx.) under this is tried (Newton decides). Next to a singular set a double root
# of the eigen-joint comes out as a complex pair: 0.008 ... 0.02 apart on the I2RT big YAM (joints 2-4 parallel to
# 3e-6 rad), whose roots there were lost at 5e-3.
IMAG_TOL = 5e-2
# two configurations closer than this (max-norm; angles mod 2 pi, lengths / arm size) are one solution
MERGE_TOL = 1e-6
# FK acceptance (relative to arm size for positions, radians for rotations)
FK_TOL = 1e-9


class GeneralIK:
    """Per-arm setup (arrangements of the elimination, cached matrices) and the per-pose solve."""

    def __init__(self, H, P, revolute, R_end, *, seed=12345, n_trial=6, prefer=None):
        H = np.asarray(H, dtype=np.float64).reshape(6, 3)
        P = np.asarray(P, dtype=np.float64).reshape(7, 3)
        rev = np.asarray(revolute, dtype=bool).reshape(6)
        R_end = np.asarray(R_end, dtype=np.float64).reshape(3, 3)
        H = H / np.linalg.norm(H, axis=1, keepdims=True)
        self.scale = float(np.sum(np.linalg.norm(P, axis=1))) or 1.0
        self.H, self.P, self.rev, self.R_end = H, P / self.scale, rev, R_end
        self.n_prismatic = int((~rev).sum())
        rng = np.random.default_rng(seed)
        self._rng_b0 = rng.normal(size=12)
        self._phis = rng.uniform(-np.pi, np.pi, 8)
        chains = {False: (self.H, self.P, rev, R_end), True: _reverse_chain(self.H, self.P, rev, R_end)}
        self.hinted = False
        if prefer:
            # the ranking found for the same arm held at a reference value: its first arrangements alone (each from
            # its own random stream), taken when the first of them answers every trial pose, as the best of the full
            # ranking must
            trial = np.random.default_rng((seed, len(ARRANGEMENTS)))
            qs = trial.uniform(-np.pi, np.pi, (n_trial, 6))
            qs[:, ~rev] = trial.uniform(-0.5, 0.5, (n_trial, int((~rev).sum())))
            ranking, fast = prefer
            arrs = [a for a in (self._keyed(k, chains, seed) for k in ranking[: 1 + SECOND_OPINIONS]) if a is not None]
            if arrs and self._misses(arrs[0], qs) == 0:
                self.arrangements, self.hinted = arrs, True
                mine = next((a for a in arrs if a.key == fast), None)
                if mine is None and fast is not None:  # (built alone, it must recover the trial configurations too)
                    mine = self._keyed(fast, chains, seed)
                    if mine is not None and self._misses(mine, qs) != 0:
                        mine = None
                self.fast = mine if mine is not None and _compiled(mine) else None
                return
        arrs = []
        for k, (reversed_, L, swapped) in enumerate(ARRANGEMENTS):
            h, p, r, re = (np.ascontiguousarray(x) for x in chains[reversed_])
            a = (_make_swapped if swapped else _make_arrangement)(h, p, r.copy(), re, reversed_, L, rng)
            if a is not None and (swapped or a.q_cond > 1e-9):
                a.key = k
                arrs.append(a)
        arrs = [a for a in arrs if self._choose_kind(a, rng)]
        if not arrs:
            raise ArmNotSupportedError("no arrangement of the elimination is usable for this arm")
        # rank arrangements: trial solves of random reachable poses; score = worst conditioning seen
        qs = rng.uniform(-np.pi, np.pi, (n_trial, 6))
        qs[:, ~rev] = rng.uniform(-0.5, 0.5, (n_trial, int((~rev).sum())))
        for a in arrs:
            misses = self._misses(a, qs)
            worst = min(a.q_cond, a.trial_rcond)
            # fewest misses first, then the best-conditioned leading matrix; the swapped family (per-pose SVD
            # of Q) is slightly slower, so it gives way to a pose-free one conditioned within a factor of 10
            a.score = -misses + 1e-3 * math.log10(max(worst, 1e-300)) - (1e-3 if a.swapped else 0.0)
            a.trial_misses = misses
        arrs.sort(key=lambda a: -a.score)
        self.arrangements = arrs
        # the compiled path's arrangement (``deflated.fast_path``): the first; where that one finds most trial poses
        # suspicious, the one found suspicious at the fewest of those that recover every trial configuration (the
        # first of equals). ssik's xArm7
        # held at joint 2 ranks first an arrangement suspicious at 5 of 6 trial poses, 3e-4 better conditioned than
        # one at none: the compiled path handed nearly every pose to the full solve, which asked two more
        # arrangements (1.2 ms a pose, 0.2 with the other). (The big YAM's first, suspicious at 2 of 6, stays: its
        # compiled path elsewhere lost 2 of 50 configurations next to the singular set.)
        first = arrs[0]
        self.fast = first if _compiled(first) else None
        if self.fast is not None and 2 * first.trial_suspicious > len(qs):
            sound = [a for a in arrs if a.trial_misses == 0 and _compiled(a)]
            self.fast = min(sound, key=lambda a: a.trial_suspicious) if sound else first

    @property
    def ranking(self) -> tuple[tuple[int, ...], int | None]:
        """``prefer``'s form: the arrangements in the order they are tried, and the compiled path's (``fast``), as
        indices of ``ARRANGEMENTS``."""
        return tuple(a.key for a in self.arrangements), None if self.fast is None else self.fast.key

    def _keyed(self, k, chains, seed):
        """Arrangement ``ARRANGEMENTS[k]`` of this arm with its matrix-polynomial construction chosen, from a random
        stream of its own (the same whatever else is built), or None where it is unusable."""
        reversed_, L, swapped = ARRANGEMENTS[k]
        rng = np.random.default_rng((seed, k))
        h, p, r, re = (np.ascontiguousarray(x) for x in chains[reversed_])
        a = (_make_swapped if swapped else _make_arrangement)(h, p, r.copy(), re, reversed_, L, rng)
        if a is None or (not swapped and a.q_cond <= 1e-9) or not self._choose_kind(a, rng):
            return None
        a.key = k
        return a

    def _misses(self, a, qs):
        """Of the configurations ``qs``, how many arrangement ``a`` does not recover (the worst leading matrix's
        conditioning seen: ``a.trial_rcond``; the poses ``solve`` would find suspicious: ``a.trial_suspicious``)."""
        misses, a.trial_rcond, a.trial_suspicious = 0, math.inf, 0
        for q in qs:
            RT, pT = _chain_fk(self.H, self.P, self.rev, self.R_end, q)
            sols, info = self._solve_with(a, RT, pT)
            a.trial_rcond = min(a.trial_rcond, info.get("a_rcond", 0.0))
            a.trial_suspicious += _suspicious(sols, info)
            if len(sols) == 0 or np.min(_dist(sols, q, self.rev)) > 1e-6:
                misses += 1
        return misses

    def _choose_kind(self, a, rng):
        """Pick the matrix-polynomial construction for arrangement a (checked on a random pose: the polynomial
        must be regular / of full column rank); False when none is."""
        q = rng.uniform(-np.pi, np.pi, 6)
        q[~self.rev] = rng.uniform(-0.5, 0.5, int((~self.rev).sum()))
        RT, pT = _chain_fk(self.H, self.P, self.rev, self.R_end, q)
        _, Rt, pt, q0, N, _, qc = self._pose_data(a, RT, pT)
        if qc < 1e-9:
            return False
        slot_off = a.slot_off.copy()
        slot_off[0] = 0.4

        def regular(C):
            worst = 1.0
            for xx in (0.37, -1.3):
                sv = np.linalg.svd(C[2] * xx * xx + C[1] * xx + C[0], compute_uv=False)
                worst = min(worst, sv[-1] / sv[0])
            return worst > 1e-9

        a.kind = "std"
        M, _, _ = self._coeffs(a, Rt, pt, slot_off, q0, N)
        if regular(M):
            return True
        if int(a.slot_kind[1] == 0) + int(a.slot_kind[2] == 0) != 1:
            return False
        a.kind = "lowp"
        a.p_slot = 1 if a.slot_kind[1] == 0 else 2
        Mc = np.stack([M[ie][:6, :9] for ie in range(3)], axis=1).reshape(6, 3, 3, 3)
        top = (Mc[:, :, 2, :] if a.p_slot == 1 else Mc[:, :, :, 2]).reshape(6, 9)
        sv = np.linalg.svd(top, compute_uv=False)
        a.top_rank = int(np.sum(sv > 1e-9 * sv[0]))
        if a.top_rank > 2:  # fewer than 4 low equations: 2(6 - r) rows < 8 columns
            return False
        a.Zp = np.linalg.qr(rng.normal(size=(2 * (6 - a.top_rank), 8)))[0]
        R = _lowp_system(M, a.p_slot, a.top_rank)
        return regular(R[:, :, :]) if R.shape[1] == R.shape[2] else _full_col_rank(R)

    # ---------------------------------------------------------------------------------------------- solve
    def _pose_in(self, a, RT, pT):
        """The target in arrangement a's chain: (RTa, pTa) and T' = T M0^-1 (inverted for a reversed chain)."""
        return _pose_in_nb(RT, pT, a.reversed, a.M0R, a.M0p)

    def _pose_data(self, a, RT, pT):
        """(RTa, Rt, pt, q0, N, pinvQ, q_cond): the target's rotation in a's chain, the T' that the kept side
        is evaluated with (the identity for a swapped arrangement, whose kept side is pose-free), and the
        elimination data (per arm, or per pose for a swapped arrangement)."""
        RTa, pTa, Rt, pt = self._pose_in(a, RT, pT)
        if not a.swapped:
            return RTa, Rt, pt, a.q0, a.N, a.pinvQ, a.q_cond
        bk, bh, bc, bs, bn = a.b_ops
        q0, N, pinvQ, qc = _sw_pose_Q(bk, bh, bc, bs, bn, a.o, a.hl, Rt, pt, a.ref, a.b_nodes, a.b_inv)
        return RTa, np.eye(3), np.zeros(3), q0, N, pinvQ, qc

    def _coeffs(self, a, Rt, pt, slot_off, q0, N):
        """Matrix-polynomial coefficients for one pose: (M (3, 12, 12) from _pencil, Rc (3, m, n) the system
        whose null vectors are monomial vectors, Pc (3, n, n) the square polynomial to take eigenvalues of)."""
        M = _pencil(
            a.ops_kind,
            a.ops_h,
            a.ops_c,
            a.ops_slot,
            a.n_pre,
            a.o,
            a.hl,
            Rt,
            pt,
            a.ref,
            a.slot_kind,
            slot_off,
            a.G,
            q0,
            N,
        )
        if a.kind == "std":
            return M, M, M
        Rc = _lowp_system(M, a.p_slot, a.top_rank)
        return M, Rc, np.einsum("mk,imn->ikn", a.Zp, Rc)

    def _solve_with(self, a, RT, pT):
        """Candidates from arrangement a, polished on the original chain. Returns (solutions (k, 6) in
        normalised units, info)."""
        info = {"arrangement": a.name}
        RTa, Rt, pt, q0, N, pinvQ, qc = self._pose_data(a, RT, pT)
        if qc < 1e-9:  # (swapped arrangement) the eliminated pair's Q is rank deficient at this pose
            info["singular_pencil"] = False
            info["rank_deficient_Q"] = True
            info["n_real_fail"] = 1  # counts as a failure: ask for a second opinion
            return np.zeros((0, 6)), info
        if a.kind == "std" and a.slot_kind[0] == 1:
            Cm, M, phi, rc = _std_front(
                Rt,
                pt,
                self._phis[:4],
                a.ops_kind,
                a.ops_h,
                a.ops_c,
                a.ops_slot,
                a.n_pre,
                a.o,
                a.hl,
                a.ref,
                a.slot_kind,
                a.slot_off,
                a.G,
                q0,
                N,
            )
            if rc > 1e-10:
                info["a_rcond"] = rc
                xs, ims = _filter_candidates(np.linalg.eigvals(Cm), IMAG_TOL)
                info["n_cand"] = len(xs)
                slot_off = a.slot_off.copy()
                slot_off[0] = phi
                return self._std_solutions(a, M, xs, ims, phi, slot_off, Rt, pt, q0, pinvQ, RTa, RT, pT, info)
        got = self._eigenvalues(a, Rt, pt, q0, N, info)
        if got is None:  # (a singular pencil)
            return np.zeros((0, 6)), info
        ev, phi, slot_off, M, Rc = got
        return self._back_substitute(a, ev, phi, slot_off, M, Rc, RTa, Rt, pt, q0, pinvQ, RT, pT, info)

    def _eigenvalues(self, a, Rt, pt, q0, N, info):
        """The eigen-joint's values at this pose (its half-angle tangents, or travels) by arrangement ``a``: the
        shift phi whose leading matrix is best conditioned, then the companion linearization (or QZ where the
        leading matrix is singular). Returns ``(eigenvalues, phi, slot offsets, M, Rc)``, or None where the
        pencil is singular (``info["singular_pencil"]``)."""
        best = None
        slot_off = a.slot_off.copy()
        phis = self._phis[:4] if a.slot_kind[0] == 1 else np.zeros(1)
        for phi in phis:
            slot_off[0] = phi
            M, Rc, Pc = self._coeffs(a, Rt, pt, slot_off, q0, N)
            A = Pc[2]
            try:
                Ainv = np.linalg.inv(A)
                rc = 1.0 / (np.linalg.norm(A, 1) * np.linalg.norm(Ainv, 1))
            except np.linalg.LinAlgError:
                rc, Ainv = 0.0, None
            if best is None or rc > best[0]:
                best = (rc, phi, M, Rc, Pc, Ainv)
            if rc > 1e-6:
                break
        rc, phi, M, Rc, Pc, Ainv = best
        info["a_rcond"] = rc
        slot_off[0] = phi
        n = Pc.shape[1]
        if rc < 1e-10 or a.slot_kind[0] == 0:
            # leading matrix (near) singular: is the whole pencil singular (continuum, or arm degenerate)?
            sing = []
            for xx in (0.3127, -1.731):
                sv = np.linalg.svd(Pc[2] * xx * xx + Pc[1] * xx + Pc[0], compute_uv=False)
                sing.append(sv[-1] / sv[0])
            if max(sing) < 1e-11:
                info["singular_pencil"] = True
                info["n_real_fail"] = 0
                return None
            ev = _qz_eigvals(Pc)
        else:
            Cm = np.zeros((2 * n, 2 * n))
            Cm[:n, n:] = np.eye(n)
            Cm[n:, :n] = -Ainv @ Pc[0]
            Cm[n:, n:] = -Ainv @ Pc[1]
            ev = np.linalg.eigvals(Cm)
        return ev, phi, slot_off, M, Rc

    def _back_substitute(self, a, ev, phi, slot_off, M, Rc, RTa, Rt, pt, q0, pinvQ, RT, pT, info):
        """The configurations of the eigenvalues ``ev`` (real, or nearly: near-double roots), each completed from
        the null vector of the matrix polynomial, polished on the chain and checked by FK; merged."""
        info["n_eig"] = len(ev)
        x = ev.real
        im = np.abs(ev.imag) / (1.0 + np.abs(ev) ** 2)
        cand = np.nonzero(np.isfinite(x) & (im < IMAG_TOL))[0]
        info["n_cand"] = len(cand)
        if a.kind == "std":
            xs, ims = x[cand].copy(), im[cand].copy()
            return self._std_solutions(a, M, xs, ims, phi, slot_off, Rt, pt, q0, pinvQ, RTa, RT, pT, info)
        return self._lowp_solutions(a, x, im, cand, phi, slot_off, Rc, RTa, Rt, pt, q0, pinvQ, RT, pT, info)

    def _lowp_solutions(self, a, x, im, cand, phi, slot_off, Rc, RTa, Rt, pt, q0, pinvQ, RT, pT, info):
        """``_back_substitute`` for a "lowp" arrangement (two slides opposite in the loop): each candidate's
        slide and revolute V joint read from the null vector of the rectangular 10x8 system."""
        sols = []
        singular = []  # indices of solutions with a near-singular Jacobian
        vals = np.empty(3)
        for i in cand:
            vals[0] = phi + 2.0 * math.atan(x[i]) if a.slot_kind[0] == 1 else x[i]
            S = Rc[2] * x[i] ** 2 + Rc[1] * x[i] + Rc[0]
            _, sv, Vt = np.linalg.svd(S)
            if sv[-1] > 1e-6 * sv[0] and im[i] > 0:  # not a root of the full rectangular system
                continue
            V = Vt[-1].reshape(2, 4)  # (prismatic power 0..1, revolute power 0..3)
            _, xp = _proj_ratio(V[1].copy(), V[0].copy())
            tr, _ = _proj_ratio(V[:, 1:].copy().ravel(), V[:, :3].copy().ravel())
            ps, rs = a.p_slot, 3 - a.p_slot
            vals[ps] = slot_off[ps] + _fin(xp)
            vals[rs] = slot_off[rs] + tr
            q = _complete(
                vals,
                a.ops_kind,
                a.ops_h,
                a.ops_c,
                a.ops_slot,
                a.n_pre,
                a.o,
                a.hl,
                Rt,
                pt,
                a.ref,
                q0,
                pinvQ,
                a.E_kind,
                a.E_idx,
                a.slots_idx,
                a.L,
                a.H,
                a.P,
                a.rev,
                a.R_end,
                RTa,
            )
            if a.reversed:
                q = q[::-1].copy()
            qp, nr, ok, pr = _polish(self.H, self.P, self.rev, self.R_end, q, RT, pT, 60, 1e-17)
            if ok:
                dp, dr = _poses_err(self.H, self.P, self.rev, self.R_end, qp, RT, pT)
                ok = dp < FK_TOL and dr < FK_TOL
            if ok:
                sols.append(_wrap(qp, self.rev))
                if pr < 1e-5:
                    singular.append(len(sols) - 1)
        info["n_real_fail"] = 0
        info["n_singular"] = len(singular)
        return np.array(_merge(sols, self.rev)).reshape(-1, 6), info

    def _std_solutions(self, a, M, xs, ims, phi, slot_off, Rt, pt, q0, pinvQ, RTa, RT, pT, info):
        """The configurations of the eigen-joint's candidate values ``xs`` (imaginary parts ``ims``) by a standard
        arrangement ``a`` (``_candidates_std``: completed, polished, FK-checked), merged."""
        args = (a.ops_kind, a.ops_h, a.ops_c, a.ops_slot, a.n_pre, a.o, a.hl, Rt, pt, a.ref, a.slot_kind, slot_off)
        chain = (a.L, a.H, a.P, a.rev, a.R_end, RTa, a.reversed, self.H, self.P, self.rev, self.R_end, RT, pT)
        elim = (q0, pinvQ, a.E_kind, a.E_idx, a.slots_idx)
        S_, prs, n_real_fail = _candidates_std(M, xs, ims, phi, self._rng_b0, *args, *elim, *chain, FK_TOL)
        keep = _merge_nb(S_, self.rev, MERGE_TOL)
        info["n_real_fail"] = n_real_fail
        info["n_singular"] = int(np.sum(prs[keep] < 1e-5))
        return S_[keep], info

    def _split_pairs(self, sols, RT, pT):
        """``sols`` with each root the polish left at the middle of two roots a hair apart replaced by those two
        (``_split_pair``): a root at a singular configuration (pivot ratio under ``SPLIT_PIVOT``) that misses the pose
        by more than ``SPLIT_ABOVE``. Two roots a few 1e-5 rad apart give one near-double eigenvalue, and Newton from
        its configuration stops between them, where the residual along the valley has its extremum (the I2RT big YAM
        on its singular set: 2.5e-13 of the arm, over the certification's 2e-13, so both were lost)."""
        out = []
        for q in sols:
            r, _, dev = _residual6(self.H, self.P, self.rev, self.R_end, q, RT, pT)
            nr = math.sqrt(float(np.sum(r * r))) + dev
            if nr > SPLIT_ABOVE:
                _, pr = _solve6(_jac6(self.H, self.P, self.rev, q), np.zeros(6))
                if pr < SPLIT_PIVOT:
                    pair, count = _split_pair(self.H, self.P, self.rev, self.R_end, q, nr, RT, pT)
                    if count == 2:
                        out.extend(pair)
                        continue
            out.append(q)
        return np.array(out, dtype=np.float64).reshape(-1, 6)

    def _merge_close(self, sols, RT, pT):
        """Second merging pass: two solutions closer than 1e-3 whose whole joining segment satisfies the FK to
        1e-12 (relative) are one solution known only that well (a double root along a flat direction, where
        the FK residual grows only like the distance squared), kept once."""
        out = []
        for q in sols:
            dup = False
            for k in out:
                d = q - k
                d[self.rev] = np.mod(d[self.rev] + np.pi, 2 * np.pi) - np.pi
                if np.max(np.abs(d)) < 1e-3:
                    worst = 0.0
                    for t in (0.25, 0.5, 0.75):
                        dp, dr = _poses_err(self.H, self.P, self.rev, self.R_end, k + t * d, RT, pT)
                        worst = max(worst, dp, dr)
                    if worst < 1e-12:
                        dup = True
                        break
            if not dup:
                out.append(q)
        return out

    def count(self, a, T) -> int:
        """How many solutions of the pose ``T`` arrangement ``a`` finds where it finds nothing suspicious
        (``_suspicious``), else how many ``solve`` gives: ``solve``'s count where ``a`` is the first."""
        T = np.asarray(T, dtype=np.float64)
        sols, info = self._solve_with(a, np.ascontiguousarray(T[:3, :3]), np.ascontiguousarray(T[:3, 3] / self.scale))
        return self.solve(T).q.shape[0] if _suspicious(sols, info) else len(sols)

    def solve(self, T) -> IKResult:
        T = np.asarray(T, dtype=np.float64)
        RT = np.ascontiguousarray(T[:3, :3])
        pT = np.ascontiguousarray(T[:3, 3] / self.scale)
        sols, info = self._solve_with(self.arrangements[0], RT, pT)
        infos = [info]
        # a suspicious answer asks another arrangement (``_suspicious``; none among them: a pose whose only roots are
        # a double one, on the singular set, can lose it as a complex pair: the big YAM exactly on its singular set
        # was answered unreachable)
        sing = info.get("singular_pencil", False)
        n_singular = info.get("n_singular", 0)
        continuum = False
        if _suspicious(sols, info):
            allsing = sing
            # up to two: a solution with a singular Jacobian (a double root) may have lost a near-double pair that
            # rounding made complex (an even count, every root polished: the I2RT big YAM's singular set)
            for a in self.arrangements[1 : 1 + SECOND_OPINIONS]:
                s2, i2 = self._solve_with(a, RT, pT)
                infos.append(i2)
                n_singular += i2.get("n_singular", 0)
                sols = np.concatenate([sols, s2])
                sols = sols[_merge_nb(sols, self.rev, MERGE_TOL)]
                s2sing = i2.get("singular_pencil", False)
                allsing = allsing and s2sing
                if not s2sing and i2["n_real_fail"] == 0 and len(s2) % 2 == 0 and not i2.get("n_singular", 0):
                    break
            continuum = allsing
        if n_singular:
            sols = self._split_pairs(sols, RT, pT)
            sols = np.array(self._merge_close(list(sols), RT, pT)).reshape(-1, 6)
            # continuum test at singular solutions: a solution on a curve of solutions
            if not continuum:
                for q in sols:
                    _, pr = _solve6(_jac6(self.H, self.P, self.rev, q), np.zeros(6))
                    if pr < 1e-5 and _on_continuum(self, q, RT, pT):
                        continuum = True
                        break
        out = np.array(sols, dtype=np.float64).reshape(-1, 6)
        out[:, ~self.rev] *= self.scale
        return IKResult(out, continuum, {"tries": infos})


def _compiled(a):
    """Whether arrangement ``a`` has a compiled path (:mod:`.deflated`): the standard construction, not swapped,
    a revolute eigen-joint."""
    return a.kind == "std" and not a.swapped and a.slot_kind[0] == 1


def _suspicious(sols, info):
    """Whether an arrangement's answer ``sols`` (its ``info``) asks another arrangement (``GeneralIK.solve``): a
    singular pencil, a real root that did not polish, an odd number of solutions (the real roots of a real
    polynomial come in an even number: odd means a double root or a lost one), a singular solution, or none."""
    return bool(
        info.get("singular_pencil", False)
        or info["n_real_fail"] > 0
        or len(sols) % 2 == 1
        or info.get("n_singular", 0) > 0
        or len(sols) == 0
    )


#: A root at a singular configuration (LU pivot ratio under ``SPLIT_PIVOT``) that the polish leaves missing the pose
#: by more than ``SPLIT_ABOVE`` (``_polish``'s measure, normalised lengths) is taken for the middle of two roots a
#: hair apart and split (``GeneralIK._split_pairs``), from these steps along the nearly null direction.
SPLIT_ABOVE = 1e-14
SPLIT_PIVOT = 1e-5
SPLIT_STEPS = (1e-6, 1e-5, 1e-4, 1e-3)


@njit(cache=True, error_model="numpy")
def _split_pair(H, P, rev, R_end, q, nr, RT, pT):
    """The two roots either side of ``q`` along the Jacobian's nearly null direction, where the polish stopped at
    ``q`` with the residual ``nr`` above rounding: from ``SPLIT_STEPS`` along that direction, each way, the first
    that polishes to a tenth of ``nr`` (wrapped). ``(roots (2, 6), count)``."""
    out = np.empty((2, 6))
    J = _jac6(H, P, rev, q)
    if not np.all(np.isfinite(J)):
        return out, 0
    _, _, Vt = np.linalg.svd(J)
    count = 0
    for sign in (1.0, -1.0):
        for h in SPLIT_STEPS:
            qp, n2, ok, _ = _polish(H, P, rev, R_end, q + (sign * h) * Vt[5], RT, pT, 30, 1e-17)
            if ok and n2 < 0.1 * nr:
                for j in range(6):
                    if rev[j]:
                        qp[j] = math.pi - ((math.pi - qp[j]) % (2.0 * math.pi))
                out[count] = qp
                count += 1
                break
    return out, count


def _fin(x):
    return x if np.isfinite(x) else 1e6


def _lowp_system(M, p_slot, top_rank):
    """For an arrangement whose V side has one prismatic slot (p_slot 1 or 2) whose square terms d^2 occur in
    only ``top_rank`` combinations of the 6 equations (this happens with a prismatic joint on each side, E
    and V): the other 6 - top_rank combinations (found per pose by an SVD) are of degree 1 in d; multiplied
    by (1, x_r) (x_r the revolute slot's half-angle variable) they give a 2(6 - top_rank) x 8 system in the
    monomials d^i x_r^j (i <= 1, j <= 3), quadratic in x_e."""
    Mc = np.stack([M[ie][:6, :9] for ie in range(3)], axis=1).reshape(6, 3, 3, 3)  # k, ie, ia, ib
    if p_slot == 2:
        Mc = Mc.transpose(0, 1, 3, 2)  # k, ie, ip, ir
    top = Mc[:, :, 2, :].reshape(6, 9)
    U, _, _ = np.linalg.svd(top)
    Z = U[:, top_rank:]
    low = np.einsum("kl,kepr->lepr", Z, Mc)[:, :, :2, :]  # l, ie, ip (<= 1), ir (<= 2)
    nl = low.shape[0]
    R = np.zeros((3, 2 * nl, 8))
    for s in range(2):
        for ip in range(2):
            for ir in range(3):
                R[:, s * nl : (s + 1) * nl, ip * 4 + ir + s] += low[:, :, ip, ir].T
    return R


def _qz_eigvals(M):
    import scipy.linalg as sl

    n = M.shape[1]
    Z = np.zeros((n, n))
    eye = np.eye(n)
    A = np.block([[Z, eye], [-M[0], -M[1]]])
    B = np.block([[eye, Z], [Z, M[2]]])
    w, b = sl.eigvals(A, B, homogeneous_eigvals=True, check_finite=False)
    with np.errstate(divide="ignore", invalid="ignore"):
        ev = w / b
    return ev[np.isfinite(ev)]


def _full_col_rank(R):
    worst = 1.0
    for xx in (0.37, -1.3):
        sv = np.linalg.svd(R[2] * xx * xx + R[1] * xx + R[0], compute_uv=False)
        worst = min(worst, sv[-1] / sv[0])
    return worst > 1e-9


def _wrap(q, rev):
    q = q.copy()
    q[rev] = np.pi - np.mod(np.pi - q[rev], 2 * np.pi)
    return q


def _dist(S, q, rev):
    d = np.asarray(S) - q
    d[..., rev] = np.mod(d[..., rev] + np.pi, 2 * np.pi) - np.pi
    return np.max(np.abs(d), axis=-1)


def _merge(sols, rev):
    out = []
    for q in sols:
        if not out or np.min(_dist(np.array(out), q, rev)) > MERGE_TOL:
            out.append(q)
    return out


def _on_continuum(ik, q, RT, pT):
    """Whether the solution q lies on a curve of solutions (see _on_continuum_nb)."""
    return _on_continuum_nb(ik.H, ik.P, ik.rev, ik.R_end, q, RT, pT)


@njit(cache=True, error_model="numpy")
def _on_continuum_nb(H, P, rev, R_end, q, RT, pT):
    """Whether the solution q lies on a curve of solutions. J(q) must be singular; then points at distances
    1e-3 and 1e-2 along J's null direction (both ways) are corrected back towards the solution set by
    Gauss-Newton moves orthogonal to that direction. On a curve of solutions the correction reaches the
    rounding level at every distance; at an isolated (double) root the residual left grows like the distance
    squared (it is at least ~1e-4 times the curvature at 1e-2), so a residual under 1e-11 at all four points
    means a continuum."""
    J = _jac6(H, P, rev, q)
    U, s, Vt = np.linalg.svd(J)
    if s[5] > 1e-6 * s[0]:
        return False
    n = Vt[5].copy()
    B = Vt[:5].T.copy()  # moves orthogonal to n
    for eps in (1e-3, 1e-2):
        for sgn in (1.0, -1.0):
            qq = q + sgn * eps * n
            for _ in range(12):
                r, p, dev = _residual6(H, P, rev, R_end, qq, RT, pT)
                Jr = _jac6(H, P, rev, qq) @ B
                step = np.linalg.lstsq(Jr, -r)[0]
                qq = qq + B @ step
                if math.sqrt(np.sum(step * step)) < 1e-15:
                    break
            r, p, dev = _residual6(H, P, rev, R_end, qq, RT, pT)
            if math.sqrt(np.sum(r * r)) + dev > 1e-11:
                return False
    return True
