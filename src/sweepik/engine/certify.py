"""Compiled (Numba) certification of candidate roots: configuration from the reduction's kernel, forward
kinematics of the robot's product-of-exponentials chain (:mod:`sweepik.model.chain`, any robot), the geodesic error
and the paper's J (eq. 6) in one pass per candidate. The same formulas as
``Reduction.solve_rest``, ``kinematics`` and ``pose`` (the references, used where a reduction has no kernel);
cheaper than their NumPy versions by the per-call overhead of some hundred small array operations per solve.
"""

from __future__ import annotations

import math
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np
from numba import float64, int64, types
from numpy.typing import NDArray

from sweepik._jit import alive, inlined, unowned, writable
from sweepik.engine import jacobi, parallel
from sweepik.engine.dedupe import limit_args, wrap_inside_row
from sweepik.engine.search import PARALLEL_MIN
from sweepik.engine.settings import J_CUTOFF_FACTOR, PINV_WIDEN
from sweepik.model.pose import GIMBAL_TOL
from sweepik.model.units import orientation_weight
from sweepik.reductions.kernels import (
    CONFIGURATION_SIG,
    CONFIGURATIONS_SIG,
    address_of,
    as_configuration,
    as_configurations,
    lazy_njit,
    owned_kernel,
)
from sweepik.subproblems.trig import wrap_pi

if TYPE_CHECKING:
    from sweepik.model.robot import Robot
    from sweepik.reductions.base import IntArray, Reduction

Array = NDArray[np.float64]
_EXACT_GIMBAL = 1e-12  # as pose._EXACT_GIMBAL
_MAX_FLOAT = float(np.finfo(np.float64).max)

#: A reduction's configuration kernel (all-branch kernel: ``_CFGS``) enters as its address (``address_of``).
_CFG = _CFGS = int64


@inlined
def _turn(r00, r01, r02, r10, r11, r12, r20, r21, r22, kx, ky, kz, angle):
    """The rotation ``r`` (row by row) followed by a turn of ``angle`` about the unit axis ``k`` (Rodrigues)."""
    c, s = math.cos(angle), math.sin(angle)
    v = 1.0 - c
    k00, k01, k02 = c + kx * kx * v, kx * ky * v - kz * s, kx * kz * v + ky * s
    k10, k11, k12 = ky * kx * v + kz * s, c + ky * ky * v, ky * kz * v - kx * s
    k20, k21, k22 = kz * kx * v - ky * s, kz * ky * v + kx * s, c + kz * kz * v
    return (
        r00 * k00 + r01 * k10 + r02 * k20,
        r00 * k01 + r01 * k11 + r02 * k21,
        r00 * k02 + r01 * k12 + r02 * k22,
        r10 * k00 + r11 * k10 + r12 * k20,
        r10 * k01 + r11 * k11 + r12 * k21,
        r10 * k02 + r11 * k12 + r12 * k22,
        r20 * k00 + r21 * k10 + r22 * k20,
        r20 * k01 + r21 * k11 + r22 * k21,
        r20 * k02 + r21 * k12 + r22 * k22,
    )


@inlined
def _poe_joint(r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, H, P, rev, q, i):
    """The chain's rotation (row by row) and position before joint ``i`` taken past it, at ``q[i]``."""
    kx, ky, kz = H[i, 0], H[i, 1], H[i, 2]
    if rev[i]:
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = _turn(
            r00, r01, r02, r10, r11, r12, r20, r21, r22, kx, ky, kz, q[i]
        )
    else:
        d = q[i]
        px += (r00 * kx + r01 * ky + r02 * kz) * d
        py += (r10 * kx + r11 * ky + r12 * kz) * d
        pz += (r20 * kx + r21 * ky + r22 * kz) * d
    ax, ay, az = P[i + 1, 0], P[i + 1, 1], P[i + 1, 2]
    px += r00 * ax + r01 * ay + r02 * az
    py += r10 * ax + r11 * ay + r12 * az
    pz += r20 * ax + r21 * ay + r22 * az
    return r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz


@inlined
def _poe_end(r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, e):
    """The tool pose (12 scalars, as ``_poe_fk``) of the chain's rotation and position after its last joint."""
    return (
        r00 * e[0, 0] + r01 * e[1, 0] + r02 * e[2, 0],
        r00 * e[0, 1] + r01 * e[1, 1] + r02 * e[2, 1],
        r00 * e[0, 2] + r01 * e[1, 2] + r02 * e[2, 2],
        r10 * e[0, 0] + r11 * e[1, 0] + r12 * e[2, 0],
        r10 * e[0, 1] + r11 * e[1, 1] + r12 * e[2, 1],
        r10 * e[0, 2] + r11 * e[1, 2] + r12 * e[2, 2],
        r20 * e[0, 0] + r21 * e[1, 0] + r22 * e[2, 0],
        r20 * e[0, 1] + r21 * e[1, 1] + r22 * e[2, 1],
        r20 * e[0, 2] + r21 * e[1, 2] + r22 * e[2, 2],
        px,
        py,
        pz,
    )


@inlined
def _poe_fk(H, P, rev, R_end, q):
    """World tool pose of configuration ``q (n,)`` of a product-of-exponentials chain as 12 scalars (rotation
    row by row, then position): scalar locals only, no array allocated (this runs once per candidate)."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    px, py, pz = P[0, 0], P[0, 1], P[0, 2]
    for i in range(H.shape[0]):
        r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = _poe_joint(
            r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, H, P, rev, q, i
        )
    return _poe_end(r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, R_end)


@inlined
def _poe_fk_after(H, P, rev, R_end, q, start, st):
    """``_poe_fk`` of ``q (n,)`` (the same bits) whose first ``start`` joints are those of the configuration last
    given: the chain before joint ``start`` read from ``st[start]`` (unless ``start`` is 0), and each joint's state
    after it written to ``st (n + 1, 12)``. A closed form's branches share their first joints in pairs and fours
    (a spherical wrist's flip turns the last three only): 34 joint turns instead of 48 for eight branches."""
    if start == 0:
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
        px, py, pz = P[0, 0], P[0, 1], P[0, 2]
    else:
        s = st[start]
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8]
        px, py, pz = s[9], s[10], s[11]
    for i in range(start, H.shape[0]):
        r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = _poe_joint(
            r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, H, P, rev, q, i
        )
        s = st[i + 1]
        s[0], s[1], s[2], s[3], s[4], s[5], s[6], s[7], s[8] = r00, r01, r02, r10, r11, r12, r20, r21, r22
        s[9], s[10], s[11] = px, py, pz
    return _poe_end(r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz, R_end)


@inlined
def _zyz(r00, r01, r02, r10, r11, r12, r20, r21, r22):
    """Z-Y-Z angles of a rotation given by its entries, as pose.zyz_from_matrix."""
    sb = math.hypot(r20, r21)
    beta = math.atan2(sb, r22)
    alpha = math.atan2(r12, r02)
    if sb <= _EXACT_GIMBAL:  # as pose.zyz_from_matrix: alpha = 0, beta keeps its value
        alpha = 0.0
        if r22 > 0:
            gamma = math.atan2(-r01, r00)
        else:
            gamma = math.atan2(r01, -r00)
    else:
        ca, sa = math.cos(alpha), math.sin(alpha)
        gamma = math.atan2(ca * r10 - sa * r00, ca * r11 - sa * r01)
    return wrap_pi(alpha), beta, wrap_pi(gamma)


@inlined
def _geodesic(T, Td, weight):
    """(geodesic error, position error) of the pose ``T`` (12 scalars, as ``_poe_fk``) against ``Td (4, 4)``."""
    r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = T
    dp = math.sqrt((px - Td[0, 3]) ** 2 + (py - Td[1, 3]) ** 2 + (pz - Td[2, 3]) ** 2)
    # geodesic: angle of M = Td^T R (only its trace and skew part are needed)
    m00 = Td[0, 0] * r00 + Td[1, 0] * r10 + Td[2, 0] * r20
    m11 = Td[0, 1] * r01 + Td[1, 1] * r11 + Td[2, 1] * r21
    m22 = Td[0, 2] * r02 + Td[1, 2] * r12 + Td[2, 2] * r22
    m21 = Td[0, 2] * r01 + Td[1, 2] * r11 + Td[2, 2] * r21
    m12 = Td[0, 1] * r02 + Td[1, 1] * r12 + Td[2, 1] * r22
    m02 = Td[0, 0] * r02 + Td[1, 0] * r12 + Td[2, 0] * r22
    m20 = Td[0, 2] * r00 + Td[1, 2] * r10 + Td[2, 2] * r20
    m10 = Td[0, 1] * r00 + Td[1, 1] * r10 + Td[2, 1] * r20
    m01 = Td[0, 0] * r01 + Td[1, 0] * r11 + Td[2, 0] * r21
    vx, vy, vz = m21 - m12, m02 - m20, m10 - m01
    ang = math.atan2(0.5 * math.sqrt(vx * vx + vy * vy + vz * vz), 0.5 * (m00 + m11 + m22 - 1.0))
    return dp + weight * ang, dp


@inlined
def _errors(T, Td, weight, zd):
    """(geodesic error, paper J) of the pose ``T`` (12 scalars, as ``_poe_fk``) against ``Td (4, 4)``. ``zd (4,)``:
    the Z-Y-Z angles of ``Td`` once computed (``zd[1:]``, when ``zd[0]`` is 1; set here when needed, so that
    candidates of one target compute them once: the caller sets ``zd[0] = 0`` for a new target)."""
    geo, dp = _geodesic(T, Td, weight)
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = T[0], T[1], T[2], T[3], T[4], T[5], T[6], T[7], T[8]
    if geo > J_CUTOFF_FACTOR * weight:  # far from a solution: the paper's J is not needed
        return geo, np.inf
    a, b, g = _zyz(r00, r01, r02, r10, r11, r12, r20, r21, r22)
    if zd[0] == 0.0:
        zd[1], zd[2], zd[3] = _zyz(
            Td[0, 0], Td[0, 1], Td[0, 2], Td[1, 0], Td[1, 1], Td[1, 2], Td[2, 0], Td[2, 1], Td[2, 2]
        )
        zd[0] = 1.0
    ad, bd, gd = zd[1], zd[2], zd[3]
    da, db, dg = wrap_pi(a - ad), b - bd, wrap_pi(g - gd)
    if b < GIMBAL_TOL or bd < GIMBAL_TOL:
        da, dg = 0.0, wrap_pi((a + g) - (ad + gd))
    elif math.pi - b < GIMBAL_TOL or math.pi - bd < GIMBAL_TOL:
        da, dg = 0.0, wrap_pi((a - g) - (ad - gd))
    jo = math.sqrt(da * da + db * db + dg * dg)
    return geo, math.sqrt(dp * dp + (weight * jo) ** 2)


_CERTIFY_SIG = (
    _CFG,
    float64[:, ::1],
    float64[:, :, ::1],
    int64[::1],
    float64[::1],
    int64[::1],
    types.boolean,
    float64[:, ::1],
    float64[:, ::1],
    types.boolean[::1],
    float64[:, ::1],
    float64,
    float64[:, ::1],
    float64[::1],
    float64[::1],
    int64,
    int64,
)


@inlined
def _views(params, world, q, err_geo, err_paper, H, P, rev, R_end):
    """A certification kernel's arrays as views Numba does not reference-count (``unowned``): each call on them in
    the kernel's loop would count every array up and down, atomically. Its caller holds the arrays."""
    return (
        unowned(params),
        unowned(world),
        unowned(q),
        unowned(err_geo),
        unowned(err_paper),
        unowned(H),
        unowned(P),
        unowned(rev),
        unowned(R_end),
    )


@lazy_njit(_CERTIFY_SIG, cache=True, nogil=True)
def _certify(
    cfg, params, world, pose, theta, branch, paper, H, P, rev, R_end, weight, q, err_geo, err_paper, start, stop
):
    """Candidates ``start .. stop - 1``: the configuration of candidate k (pose ``pose[k]``) into ``q[k]``, its
    geodesic error and paper J (inf where the branch does not exist; J inf too without ``paper``)."""
    cfg = as_configuration(cfg)
    params, world, q, err_geo, err_paper, H, P, rev, R_end = _views(
        params, world, q, err_geo, err_paper, H, P, rev, R_end
    )
    own_zd = np.empty(4)
    zd = unowned(own_zd)
    last = -1
    for k in range(start, stop):
        i = pose[k]
        if i != last:  # (a pose's candidates are mostly consecutive: the angles are redone when it changes)
            zd[0], last = 0.0, i
        cfg(params[i], theta[k], branch[k], q[k])
        if paper:
            _certify_row(H, P, rev, R_end, weight, q, world[i], zd, k, err_geo, err_paper)
        else:
            err_geo[k], err_paper[k] = _geodesic_row(H, P, rev, R_end, weight, q, world[i], k), np.inf
    alive(own_zd)


@inlined
def _certify_row(H, P, rev, R_end, weight, q, Td, zd, k, err_geo, err_paper):
    """Errors of candidate ``k`` (configuration ``q[k]``, target ``Td`` with its angles ``zd``, see ``_errors``):
    inf where the branch does not exist."""
    if not _finite_row(q, k):
        err_geo[k], err_paper[k] = np.inf, np.inf
        return
    err_geo[k], err_paper[k] = _errors(_poe_fk(H, P, rev, R_end, q[k]), Td, weight, zd)


@inlined
def _certify_after(H, P, rev, R_end, weight, q, Td, zd, k, err_geo, err_paper, start, st):
    """``_certify_row`` through ``_poe_fk_after`` (the same errors): whether the chain's states were written (the
    row is finite)."""
    if not _finite_row(q, k):
        err_geo[k], err_paper[k] = np.inf, np.inf
        return False
    err_geo[k], err_paper[k] = _errors(_poe_fk_after(H, P, rev, R_end, q[k], start, st), Td, weight, zd)
    return True


@inlined
def _shared_joints(q, a, b):
    """How many leading joints rows ``a`` and ``b`` of ``q`` have equal, bit for bit."""
    n = q.shape[1]
    for j in range(n):
        if q[a, j] != q[b, j]:
            return j
    return n


@inlined
def _geodesic_row(H, P, rev, R_end, weight, q, Td, k):
    """``_certify_row``'s geodesic error alone (where the paper's J is not wanted: its Z-Y-Z angles cost as much
    as the rest)."""
    if not _finite_row(q, k):
        return np.inf
    return _geodesic(_poe_fk(H, P, rev, R_end, q[k]), Td, weight)[0]


@inlined
def _finite_row(q, k):
    for j in range(q.shape[1]):
        if not math.isfinite(q[k, j]):
            return False
    return True


#: ``_certify_every_branch``'s arguments (``one_pose`` calls it by its address too).
_CERTIFY_EVERY_SIG = (
    (_CFGS, float64[:, ::1], float64[:, :, ::1], int64)
    + (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64)
    + (float64[:, ::1], float64[::1], float64[::1], int64, int64)
)


@lazy_njit(_CERTIFY_EVERY_SIG, cache=True, nogil=True)
def _certify_every_branch(cfgs, params, world, nb, H, P, rev, R_end, weight, q, err_geo, err_paper, start, stop):
    """Poses ``start .. stop - 1``: every branch's configuration at once (rows ``i nb .. i nb + nb - 1`` of
    ``q`` for pose i) and their errors."""
    cfgs = as_configurations(cfgs)
    params, world, q, err_geo, err_paper, H, P, rev, R_end = _views(
        params, world, q, err_geo, err_paper, H, P, rev, R_end
    )
    own_zd = np.empty(4)
    zd = unowned(own_zd)
    own_st = np.empty((H.shape[0] + 1, 12))
    st = unowned(own_st)
    for i in range(start, stop):
        cfgs(params[i], 0.0, q[i * nb : (i + 1) * nb])
        zd[0] = 0.0
        done = False  # (``st`` holds the previous branch's chain)
        for k in range(i * nb, (i + 1) * nb):
            shared = _shared_joints(q, k, k - 1) if done else 0
            done = _certify_after(H, P, rev, R_end, weight, q, world[i], zd, k, err_geo, err_paper, shared, st)
    alive(own_zd, own_st)


@lazy_njit(
    (_CFG, float64[:, ::1], float64[:, :, ::1], int64[::1], int64[::1], float64[::1], float64[::1], int64)
    + (types.boolean, float64, float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64)
    + (types.boolean[::1], float64[::1], float64[::1], float64[::1], types.boolean, int64, int64),
    cache=True,
    nogil=True,
)
def _locate_cuts(
    cfg,
    params,
    world,
    pose,
    branch,
    a,
    b,
    steps,
    limits,
    tol,
    H,
    P,
    rev,
    R_end,
    weight,
    jrev,
    lower,
    upper,
    ltol,
    beyond,
    start,
    stop,
):
    """Cuts ``start .. stop - 1``: ``families._locate_cuts`` step for step (``a`` a certified family member,
    ``b`` not), ``a`` and ``b`` updated in place."""
    cfg = as_configuration(cfg)
    n = H.shape[0]
    q = np.empty((1, n))
    ga, gb, gx = np.empty(n), np.empty(n), np.empty(n)  # each joint's limit excess at a, b and the new point
    for k in range(start, stop):
        i, br = pose[k], branch[k]
        ak, bk = a[k], b[k]
        target = math.ldexp(abs(bk - ak), -steps)
        for j in range(n):
            ga[j] = gb[j] = math.nan
        if limits:
            _member(cfg, params[i], ak, br, q, world[i], H, P, rev, R_end, weight, tol, limits,
                    jrev, lower, upper, ltol, beyond, ga)  # fmt: skip
            _member(cfg, params[i], bk, br, q, world[i], H, P, rev, R_end, weight, tol, limits,
                    jrev, lower, upper, ltol, beyond, gb)  # fmt: skip
        w1 = w2 = w3 = math.inf  # the bracket's widths 1, 2 and 3 steps ago
        side = 0
        for _ in range(3 * steps + 3):
            w = abs(bk - ak)
            if w <= target:
                break
            t = 0.5
            js = 0  # the joint furthest outside its limits at b (the first of equals)
            for j in range(1, n):
                if gb[j] > gb[js]:
                    js = j
            if ga[js] <= 0.0 and gb[js] > 0.0 and w <= 0.5 * w3:  # (NaN: no interpolation)
                tmin = 0.5 * target / w
                t = min(max(ga[js] / (ga[js] - gb[js]), tmin), 1.0 - tmin)
            x = ak + t * (bk - ak)
            on = _member(cfg, params[i], x, br, q, world[i], H, P, rev, R_end, weight, tol, limits,
                         jrev, lower, upper, ltol, beyond, gx)  # fmt: skip
            if on:
                ak = x
                for j in range(n):
                    ga[j] = gx[j]
                    if side == 1:
                        gb[j] = 0.5 * gb[j]
                side = 1
            else:
                bk = x
                for j in range(n):
                    gb[j] = gx[j]
                    if side == -1:
                        ga[j] = 0.5 * ga[j]
                side = -1
            w3, w2, w1 = w2, w1, w
        a[k], b[k] = ak, bk


@inlined
def _member(cfg, p, x, br, q, Td, H, P, rev, R_end, weight, tol, limits, jrev, lower, upper, ltol, beyond, ex):
    """Whether the family member at ``x`` is certified and, with ``limits``, inside them; each joint's limit
    excess into ``ex``, as ``families._members_excess`` (NaN where it is not certified or without
    limits)."""
    cfg(p, x, br, q[0])
    on = _geodesic_row(H, P, rev, R_end, weight, q, Td, 0) <= tol  # (inf where the member does not exist)
    for j in range(ex.shape[0]):
        ex[j] = math.nan
    if on and limits:
        on = wrap_inside_row(q[0], jrev, lower, upper, ltol, beyond)
        for j in range(ex.shape[0]):
            ex[j] = max((lower[j] - ltol[j]) - q[0, j], q[0, j] - (upper[j] + ltol[j]))
    return on


@inlined
def _limit_excess_row(q, jrev, lower, upper):
    """``families._limit_excess`` of one member ``q (n,)`` (changed in place), value for value: NaN becomes
    inf and +-inf the largest float (``np.nan_to_num``); an infinite revolute value wraps to NaN."""
    bad = False
    for j in range(q.shape[0]):
        x = q[j]
        if math.isnan(x):
            x = math.inf
        elif x == math.inf:
            x = _MAX_FLOAT
        elif x == -math.inf:
            x = -_MAX_FLOAT
        q[j] = x
        if x == math.inf:
            if jrev[j]:
                return math.nan
            bad = True
    if bad:
        return math.inf
    out = -math.inf
    for j in range(q.shape[0]):
        x = q[j]
        if jrev[j]:  # (from the middle of the limits modulo 2 pi, as ``Robot.limit_excess``)
            mid = 0.5 * (lower[j] + upper[j])
            x = mid + wrap_pi(x - mid)
        out = max(out, max(lower[j] - x, x - upper[j]))
    return out


@lazy_njit(
    (_CFG, float64[:, ::1], int64[::1], int64[::1], float64[::1], float64[::1], float64[::1], float64[::1])
    + (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[::1], float64[::1], float64[::1])
    + (types.boolean, int64, int64),
    cache=True,
    nogil=True,
)
def _dip_search(
    cfg, params, pose, branch, a, b, best_x, best_e, hist_x, hist_e, jrev, lower, upper, ltol, beyond, start, stop
):
    """Dips ``start .. stop - 1``: the golden-section search of ``families._limit_dips`` run for all its steps,
    the best point and excess after each step's update into ``hist_x``, ``hist_e``."""
    cfg = as_configuration(cfg)
    q = np.empty(jrev.shape[0])
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    for k in range(start, stop):
        i, br, lo, hi, bx, be = pose[k], branch[k], a[k], b[k], best_x[k], best_e[k]
        c, d = hi - g * (hi - lo), lo + g * (hi - lo)
        cfg(params[i], c, br, q)
        ec = _limit_excess_row(q, jrev, lower, upper)
        cfg(params[i], d, br, q)
        ed = _limit_excess_row(q, jrev, lower, upper)
        for t in range(hist_x.shape[1]):
            if ec < be:
                bx, be = c, ec
            if ed < be:
                bx, be = d, ed
            hist_x[k, t], hist_e[k, t] = bx, be
            left = ec < ed  # the least excess lies in [lo, d]: d becomes the new right end
            if left:
                hi = d
                new_c, new_d = hi - g * (hi - lo), c
                fresh = new_c
            else:
                lo = c
                new_c, new_d = d, lo + g * (hi - lo)
                fresh = new_d
            cfg(params[i], fresh, br, q)
            e_fresh = _limit_excess_row(q, jrev, lower, upper)
            if left:
                ec, ed = e_fresh, ec
            else:
                ec, ed = ed, e_fresh
            c, d = new_c, new_d


def dip_search(robot, red, chain: Array, pose, branch, a: Array, b: Array, best_x: Array, best_e: Array, steps: int):
    """``families._golden_dips`` compiled, value for value: ``(best_x, best_e)``."""
    K = a.shape[0]
    hist_x, hist_e = np.empty((K, steps)), np.empty((K, steps))
    parallel.run(
        _dip_search,
        K,
        PARALLEL_MIN,
        address_of(red.kernel[1], CONFIGURATION_SIG),
        np.ascontiguousarray(red.kernel_params(chain), dtype=np.float64),
        pose.astype(np.int64),
        branch.astype(np.int64),
        *(np.array(x, dtype=np.float64) for x in (a, b, best_x, best_e)),
        hist_x,
        hist_e,
        *limit_args(robot),
    )
    # each dip ran for every step; the NumPy steps stop for all dips once every one holds a point inside the limits
    hit = hist_e <= 0.0
    last = int(np.argmax(hit, axis=1).max()) if K and hit.any(axis=1).all() else steps - 1
    return hist_x[:, last], hist_e[:, last]


@inlined
def _put_pose(T, out):
    """``_poe_fk``'s 12 scalars as the 4x4 matrix ``out``."""
    for r in range(3):
        for c in range(3):
            out[r, c] = T[3 * r + c]
        out[r, 3] = T[9 + r]
        out[3, r] = 0.0
    out[3, 3] = 1.0


@lazy_njit(
    (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64[:, ::1], float64[:, :, ::1])
    + (float64, float64[:, :, ::1], float64[::1], int64, int64),
    cache=True,
    nogil=True,
)
def _tool_poses(H, P, rev, R_end, q, target, weight, out, err, start, stop):
    """Rows ``start .. stop - 1``: the world tool pose of ``q[k]`` into ``out[k]`` and (``target`` non-empty)
    its geodesic error to ``target[k]`` into ``err[k]``."""
    for k in range(start, stop):
        T = _poe_fk(H, P, rev, R_end, q[k])
        _put_pose(T, out[k])
        if target.shape[0]:
            err[k] = _geodesic(T, target[k], weight)[0]


@lazy_njit(
    (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64[:, ::1], float64[:, :, ::1])
    + (float64, float64[::1], float64[::1], int64, int64),
    cache=True,
    nogil=True,
)
def _pose_errors(H, P, rev, R_end, q, target, weight, err_geo, err_paper, start, stop):
    """Rows ``start .. stop - 1``: the geodesic error and the paper's J of configuration ``q[k]`` against
    ``target[k]``, as certification computes a candidate's (``_certify_row``: inf where ``q[k]`` is not
    finite, J inf far from a solution)."""
    own_zd = np.empty(4)
    zd = unowned(own_zd)
    for k in range(start, stop):
        zd[0] = 0.0  # (each row its own target)
        _certify_row(H, P, rev, R_end, weight, q, target[k], zd, k, err_geo, err_paper)
    alive(own_zd)


@lazy_njit(
    (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64[:, ::1], float64[:, :, ::1])
    + (float64[:, :, ::1], int64, int64),
    cache=True,
    nogil=True,
)
def _pose_jacobian(H, P, rev, R_end, q, T, J, start, stop):
    """Rows ``start .. stop - 1``: the world tool pose of ``q[k]`` into ``T[k]`` and the geometric Jacobian at
    the tool point into ``J[k] (6, n)`` (as ``kinematics.geometric_jacobian``), along ``_poe_fk``'s chain."""
    n = H.shape[0]
    z = np.empty((n, 3))
    o = np.empty((n, 3))
    for k in range(start, stop):
        Tk = _poe_fk(H, P, rev, R_end, q[k])
        _put_pose(Tk, T[k])
        _jacobian(H, P, rev, q[k], Tk, J[k], z, o)


@inlined
def _jacobian(H, P, rev, qk, Tk, J, z, o):
    """The geometric Jacobian ``J (6, n)`` at the tool point of configuration ``qk`` (tool pose ``Tk``, 12
    scalars as ``_poe_fk``); ``z``, ``o`` ``(n, 3)`` scratch: each joint's axis (world) and a point on it."""
    n = H.shape[0]
    r00, r01, r02, r10, r11, r12, r20, r21, r22 = 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0
    px, py, pz = P[0, 0], P[0, 1], P[0, 2]
    for i in range(n):
        kx, ky, kz = H[i, 0], H[i, 1], H[i, 2]
        z[i, 0] = r00 * kx + r01 * ky + r02 * kz
        z[i, 1] = r10 * kx + r11 * ky + r12 * kz
        z[i, 2] = r20 * kx + r21 * ky + r22 * kz
        o[i, 0], o[i, 1], o[i, 2] = px, py, pz
        if rev[i]:
            r00, r01, r02, r10, r11, r12, r20, r21, r22 = _turn(
                r00, r01, r02, r10, r11, r12, r20, r21, r22, kx, ky, kz, qk[i]
            )
        else:
            d = qk[i]
            px += z[i, 0] * d
            py += z[i, 1] * d
            pz += z[i, 2] * d
        ax, ay, az = P[i + 1, 0], P[i + 1, 1], P[i + 1, 2]
        px += r00 * ax + r01 * ay + r02 * az
        py += r10 * ax + r11 * ay + r12 * az
        pz += r20 * ax + r21 * ay + r22 * az
    tx, ty, tz = Tk[9], Tk[10], Tk[11]
    for i in range(n):
        zx, zy, zz = z[i, 0], z[i, 1], z[i, 2]
        if rev[i]:
            dx, dy, dz = tx - o[i, 0], ty - o[i, 1], tz - o[i, 2]
            J[0, i], J[1, i], J[2, i] = zy * dz - zz * dy, zz * dx - zx * dz, zx * dy - zy * dx
            J[3, i], J[4, i], J[5, i] = zx, zy, zz
        else:
            J[0, i], J[1, i], J[2, i] = zx, zy, zz
            J[3, i], J[4, i], J[5, i] = 0.0, 0.0, 0.0


@inlined
def nearly_singular_row(H, P, rev, R_end, qk, scale, ratio):
    """Whether the Jacobian at ``qk`` (lengths over ``scale``, a slide's column times it: as
    ``continuation.scaled_jacobians``) has its least singular value at most ``ratio`` of its largest: one row of
    ``partners.nearly_singular``, compiled (a few microseconds; its callers ask for the rare rows above rounding)."""
    n = H.shape[0]
    J, z, o = np.empty((6, n)), np.empty((n, 3)), np.empty((n, 3))
    _jacobian(H, P, rev, qk, _poe_fk(H, P, rev, R_end, qk), J, z, o)
    for j in range(n):
        for i in range(6):
            if i < 3:
                J[i, j] /= scale
            if not rev[j]:
                J[i, j] *= scale
    r = min(6, n)
    B, V, s = np.empty((6, n)), np.empty((n, n)), np.empty(r)
    jacobi.singular_values(J, B, V, s, False)
    return s[r - 1] <= ratio * s[0]


@inlined
def polish_row(H, P, rev, R_end, qk, Td, weight, held, iterations, backtrack, rcond, floor, work, settled=0.0):
    """``polish.polish`` of one configuration ``qk (n,)`` in place towards the pose ``Td (4, 4)``: its geodesic
    error after. Damped Newton steps on the full pose (pseudo-inverse of the Jacobian, singular values below
    ``rcond`` of the largest dropped; the joints where ``held (n,)`` is True held), a step kept only if it lowers
    the error, else halved up to ``backtrack`` times, then tried with more small directions dropped
    (``PINV_WIDEN``); it stops when no step improves it or (after one step) its error is at most ``floor``, and
    once a full step fails with the error at most ``settled`` (rounding level: no halving or narrower step is
    tried there). ``work``: :func:`polish_work`'s arrays."""
    z, o, J, e, trial, B, V, step = work
    n = H.shape[0]
    cur = _geodesic(_poe_fk(H, P, rev, R_end, qk), Td, weight)[0]
    for it in range(iterations):
        Tk = _poe_fk(H, P, rev, R_end, qk)
        _jacobian(H, P, rev, qk, Tk, J, z, o)
        r00, r01, r02, r10, r11, r12, r20, r21, r22, px, py, pz = Tk
        e[0], e[1], e[2] = Td[0, 3] - px, Td[1, 3] - py, Td[2, 3] - pz
        # dR = Rd R^T; its skew part, halved, scaled by the orientation weight
        d21 = Td[2, 0] * r10 + Td[2, 1] * r11 + Td[2, 2] * r12
        d12 = Td[1, 0] * r20 + Td[1, 1] * r21 + Td[1, 2] * r22
        d02 = Td[0, 0] * r20 + Td[0, 1] * r21 + Td[0, 2] * r22
        d20 = Td[2, 0] * r00 + Td[2, 1] * r01 + Td[2, 2] * r02
        d10 = Td[1, 0] * r00 + Td[1, 1] * r01 + Td[1, 2] * r02
        d01 = Td[0, 0] * r10 + Td[0, 1] * r11 + Td[0, 2] * r12
        e[3], e[4], e[5] = 0.5 * weight * (d21 - d12), 0.5 * weight * (d02 - d20), 0.5 * weight * (d10 - d01)
        for i in range(n):
            for r in range(6):
                J[r, i] = 0.0 if held[i] else (J[r, i] * weight if r >= 3 else J[r, i])
        improved = False
        jacobi.decompose(J, B, V, it > 0)  # (from the last step's: the Jacobian moved little)
        for widen in range(len(PINV_WIDEN)):  # (the step with more small directions dropped, if need be)
            jacobi.solve(B, V, e, rcond * PINV_WIDEN[widen], step)
            for i in range(n):  # (a held joint's zero column gives a step of rounding size: none at all)
                if held[i]:
                    step[i] = 0.0
            for _ in range(backtrack + 1):
                for i in range(n):
                    trial[i] = qk[i] + step[i]
                new = _geodesic(_poe_fk(H, P, rev, R_end, trial), Td, weight)[0]
                if new < cur:  # (False for NaN)
                    for i in range(n):
                        qk[i] = trial[i]
                    cur = new
                    improved = True
                    break
                if cur <= settled:
                    break
                for i in range(n):
                    step[i] *= 0.5
            if improved or cur <= settled:
                break
        if not improved or cur <= floor:
            break
    return cur


@inlined
def polish_work(n):
    """The work arrays of :func:`polish_row` for ``n`` joints."""
    return (
        np.empty((n, 3)),
        np.empty((n, 3)),
        np.empty((6, n)),
        np.empty(6),
        np.empty(n),
        np.empty((6, n)),
        np.empty((n, n)),
        np.empty(n),
    )


@lazy_njit(
    (float64[:, ::1], float64[:, ::1], types.boolean[::1], float64[:, ::1], float64[:, ::1], float64[:, :, ::1])
    + (float64, types.boolean[:, ::1], int64, int64, float64, float64, float64[::1], int64, int64),
    cache=True,
    nogil=True,
)
def _polish_rows(H, P, rev, R_end, q, target, weight, fixed, iterations, backtrack, rcond, floor, err, start, stop):
    """``polish.polish`` compiled, rows ``start .. stop - 1`` of ``q`` in place (``err``: their geodesic errors
    after; :func:`polish_row`)."""
    work = polish_work(H.shape[0])
    for k in range(start, stop):
        err[k] = polish_row(
            H, P, rev, R_end, q[k], target[k], weight, fixed[k], iterations, backtrack, rcond, floor, work
        )


@lru_cache(maxsize=64)
def chain_args(robot) -> tuple[Array, Array, NDArray[np.bool_], Array]:
    """The robot's chain ``(H, P, revolute, R_end)`` as the compiled kernels take it: writable copies (their
    signatures take writable arrays; nothing writes them), kept per robot (robots are values)."""
    ch = robot.chain
    return np.array(ch.H), np.array(ch.P), np.array(ch.revolute), np.array(ch.R_end)


def pose_and_jacobian(robot, q: Array) -> tuple[Array, Array]:
    """World tool poses ``(K, 4, 4)`` and geometric Jacobians ``(K, 6, n)`` at the tool point of configurations
    ``q (K, n)`` (``kinematics.geometric_jacobian``), compiled."""
    K, n = q.shape
    T, J = np.empty((K, 4, 4)), np.empty((K, 6, n))
    parallel.run(_pose_jacobian, K, 16 * PARALLEL_MIN, *chain_args(robot), writable(q), T, J)
    return T, J


def polish_rows(
    robot,
    q: Array,
    target: Array,
    weight: float,
    fixed: NDArray[np.bool_],
    iterations: int,
    backtrack: int,
    rcond: float,
    floor: float,
) -> tuple[Array, Array]:
    """``polish.polish`` compiled: ``(q (K, n) polished, geodesic errors (K,))``."""
    K = q.shape[0]
    out, err = np.array(q, dtype=np.float64), np.empty(K)
    parallel.run(
        _polish_rows,
        K,
        PARALLEL_MIN,
        *chain_args(robot),
        out,
        writable(target),
        float(weight),
        np.ascontiguousarray(fixed, dtype=np.bool_),
        int(iterations),
        int(backtrack),
        float(rcond),
        float(floor),
        err,
    )
    return out, err


def tool_poses(robot, q: Array, target: Array | None = None, weight: float = 1.0) -> tuple[Array, Array]:
    """World tool poses ``(K, 4, 4)`` of configurations ``q (K, n)`` (any joint types, product of exponentials)
    and, with ``target (K, 4, 4)``, their geodesic errors ``(K,)`` (position + ``weight`` x angle), compiled."""
    K = q.shape[0]
    out, err = np.empty((K, 4, 4)), np.empty(K if target is not None else 0)
    parallel.run(
        _tool_poses,
        K,
        16 * PARALLEL_MIN,
        *chain_args(robot),
        writable(q),
        np.zeros((0, 4, 4)) if target is None else writable(target),
        float(weight),
        out,
        err,
    )
    return out, err


def flange_poses(robot, q: Array) -> Array:
    """World poses of the last link frame ``(K, 4, 4)`` for configurations ``q (K, n)``: the tool poses
    (:func:`tool_poses`) with the tool transform taken off."""
    T, _ = tool_poses(robot, q)
    return T if robot.tool_is_identity else T @ robot.T_tool_flange


def pose_errors(robot, q: Array, target: Array, weight: float) -> tuple[Array, Array]:
    """Geodesic errors and the paper's J ``(K,)`` of configurations ``q (K, n)`` against ``target (K, 4, 4)``, as
    certification computes a candidate's (inf where a configuration is not finite, J inf where the geodesic error
    exceeds ``J_CUTOFF_FACTOR`` times ``weight``), compiled: NumPy takes ~170 us for a few rows."""
    K = q.shape[0]
    err_geo, err_paper = np.empty(K), np.empty(K)
    parallel.run(
        _pose_errors,
        K,
        16 * PARALLEL_MIN,
        *chain_args(robot),
        writable(q),
        writable(target),
        float(weight),
        err_geo,
        err_paper,
    )
    return err_geo, err_paper


def locate_cuts(robot, red, chain: Array, world: Array, pose, branch, a: Array, b: Array, steps: int, limits, tol):
    """``families._locate_cuts`` compiled, value for value: the last certified points ``a`` and the first others
    ``b`` (new arrays)."""
    a, b = np.array(a, dtype=np.float64), np.array(b, dtype=np.float64)
    args = (pose.astype(np.int64), branch.astype(np.int64), a, b, int(steps), bool(limits), float(tol))
    geometry = chain_args(robot)
    parallel.run(
        _locate_cuts,
        a.size,
        PARALLEL_MIN,
        address_of(red.kernel[1], CONFIGURATION_SIG),
        np.ascontiguousarray(red.kernel_params(chain), dtype=np.float64),
        writable(world),
        *args,
        *geometry,
        float(orientation_weight(robot.length_unit)),
        *limit_args(robot),
    )
    return a, b


def certify_every_branch(robot, red, chain: Array, world: Array, params: Array | None = None):
    """A closed form's candidates, every branch of every pose (pose-major, as ``chunk.every_branch``), certified
    with its all-branch configuration kernel (``owned_kernel(red, "kernel_configurations")``, which must exist):
    ``(q (N n_branches, n), geodesic errors, paper errors)``, as :func:`certify` gives them branch by branch."""
    N, nb = chain.shape[0], red.n_branches
    cfgs = address_of(owned_kernel(red, "kernel_configurations"), CONFIGURATIONS_SIG)
    return _run(_certify_every_branch, N, 2 * PARALLEL_MIN, N * nb, robot, red, chain, world, params, cfgs, int(nb))


def certify(
    robot,
    red,
    chain: Array,
    world: Array,
    pose,
    theta: Array,
    branch,
    params: Array | None = None,
    paper: bool = True,
):
    """Configurations ``(K, n)``, geodesic errors and paper errors ``(K,)`` of the candidates
    (inf errors where the branch does not exist; ``paper`` False: the paper errors are not wanted, inf)."""
    K = pose.shape[0]
    cfg = address_of(red.kernel[1], CONFIGURATION_SIG)
    ids = (pose.astype(np.int64), theta.astype(np.float64), branch.astype(np.int64), bool(paper))
    return _run(_certify, K, 16 * PARALLEL_MIN, K, robot, red, chain, world, params, cfg, *ids)


def _run(kernel, n, min_parallel, K, robot, red, chain, world, params, cfg, *middle):
    """``kernel(cfg, params, world, *middle, chain geometry, weight, q, err_geo, err_paper)`` over ``n`` items with
    ``K`` candidates: ``(q, err_geo, err_paper)``."""
    q = np.empty((K, robot.n_joints))
    eg = np.empty(K)
    ep = np.empty(K)
    parallel.run(
        kernel,
        n,
        min_parallel,
        cfg,
        np.ascontiguousarray(red.kernel_params(chain) if params is None else params, dtype=np.float64),
        writable(world),
        *middle,
        *chain_args(robot),
        float(orientation_weight(robot.length_unit)),
        q,
        eg,
        ep,
    )
    return q, eg, ep


@lazy_njit(
    (_CFG, float64[:, ::1], int64[::1], float64[::1], int64[::1], float64[:, ::1], int64, int64),
    cache=True,
    nogil=True,
)
def _configurations(cfg, params, pose, theta, branch, q, start, stop):
    cfg = as_configuration(cfg)
    for k in range(start, stop):
        cfg(params[pose[k]], theta[k], branch[k], q[k])


def configurations(robot: Robot, red: Reduction, chain: Array, pose: IntArray, theta: Array, branch: IntArray) -> Array:
    """Configurations ``(K, n)`` of branch ``branch`` at theta* ``theta`` of chain poses ``chain[pose]`` (compiled
    ``solve_rest`` for reductions with a kernel; NaN rows where the branch does not exist)."""
    q = np.empty((pose.shape[0], robot.n_joints))
    assert red.kernel is not None  # callers check red.uses_kernel
    parallel.run(
        _configurations,
        pose.shape[0],
        16 * PARALLEL_MIN,
        address_of(red.kernel[1], CONFIGURATION_SIG),
        np.ascontiguousarray(red.kernel_params(chain), dtype=np.float64),
        pose.astype(np.int64),
        theta.astype(np.float64),
        branch.astype(np.int64),
        q,
    )
    return q
