"""Compiled (Numba) certification of candidate roots: configuration from the reduction's kernel, forward
kinematics of the robot's product-of-exponentials chain (:mod:`sweepik.chain`, any robot), the geodesic error
and the paper's J (eq. 6) in one pass per candidate. The same formulas as
``Reduction.solve_rest``, ``kinematics`` and ``pose`` (the references, used when Numba is missing or the
robot or reduction has no kernel); cheaper than their NumPy versions by the per-call overhead of some
hundred small array operations per solve.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .fastsweep import AVAILABLE, PARALLEL_MIN
from .pose import GIMBAL_TOL
from .reductions.kernels import first_class, lazy_njit
from .units import orientation_weight

if TYPE_CHECKING:
    from .reductions.base import IntArray, Reduction
    from .robot import Robot

Array = NDArray[np.float64]
_EXACT_GIMBAL = 1e-12  # as pose._EXACT_GIMBAL
#: Candidates whose geodesic error exceeds this times the orientation weight (1e-4 x 100 mm = 0.01 mm) are far
#: from any solution (accepted ones are below 1e-9 mm, polished ones below 3e-3 mm): their J is reported as inf.
J_CUTOFF_FACTOR = 1e-4

if AVAILABLE:
    from numba import float64, int64, njit, prange, types

    from .reductions.kernels import CONFIGURATION_SIG

    _CFG = types.FunctionType(CONFIGURATION_SIG)

    @njit(cache=True)
    def _poe_fk(H, P, rev, R_end, q, T):
        """World tool pose of configuration ``q (n,)`` of a product-of-exponentials chain into ``T (4, 4)``
        (explicit loops: no BLAS)."""
        R = np.eye(3)
        Rn = np.empty((3, 3))
        p = P[0].copy()
        for i in range(H.shape[0]):
            if rev[i]:
                kx, ky, kz = H[i, 0], H[i, 1], H[i, 2]
                c, s = math.cos(q[i]), math.sin(q[i])
                v = 1.0 - c
                k00, k01, k02 = c + kx * kx * v, kx * ky * v - kz * s, kx * kz * v + ky * s
                k10, k11, k12 = ky * kx * v + kz * s, c + ky * ky * v, ky * kz * v - kx * s
                k20, k21, k22 = kz * kx * v - ky * s, kz * ky * v + kx * s, c + kz * kz * v
                for r in range(3):
                    a0, a1, a2 = R[r, 0], R[r, 1], R[r, 2]
                    Rn[r, 0] = a0 * k00 + a1 * k10 + a2 * k20
                    Rn[r, 1] = a0 * k01 + a1 * k11 + a2 * k21
                    Rn[r, 2] = a0 * k02 + a1 * k12 + a2 * k22
                R[:, :] = Rn
            else:
                for r in range(3):
                    p[r] += (R[r, 0] * H[i, 0] + R[r, 1] * H[i, 1] + R[r, 2] * H[i, 2]) * q[i]
            for r in range(3):
                p[r] += R[r, 0] * P[i + 1, 0] + R[r, 1] * P[i + 1, 1] + R[r, 2] * P[i + 1, 2]
        for r in range(3):
            for c2 in range(3):
                T[r, c2] = R[r, 0] * R_end[0, c2] + R[r, 1] * R_end[1, c2] + R[r, 2] * R_end[2, c2]
            T[r, 3] = p[r]
            T[3, r] = 0.0
        T[3, 3] = 1.0

    @njit(cache=True)
    def _wrap(x):
        return math.pi - ((math.pi - x) % (2.0 * math.pi))

    @njit(cache=True)
    def _zyz(R):
        r13, r23, r33, r31, r32 = R[0, 2], R[1, 2], R[2, 2], R[2, 0], R[2, 1]
        sb = math.hypot(r31, r32)
        beta = math.atan2(sb, r33)
        alpha = math.atan2(r23, r13)
        if sb <= _EXACT_GIMBAL:  # as pose.zyz_from_matrix: alpha = 0, beta keeps its value
            alpha = 0.0
            if r33 > 0:
                gamma = math.atan2(-R[0, 1], R[0, 0])
            else:
                gamma = math.atan2(R[0, 1], -R[0, 0])
        else:
            ca, sa = math.cos(alpha), math.sin(alpha)
            gamma = math.atan2(ca * R[1, 0] - sa * R[0, 0], ca * R[1, 1] - sa * R[0, 1])
        return _wrap(alpha), beta, _wrap(gamma)

    @njit(cache=True)
    def _errors(T, Td, weight):
        dp = math.sqrt((T[0, 3] - Td[0, 3]) ** 2 + (T[1, 3] - Td[1, 3]) ** 2 + (T[2, 3] - Td[2, 3]) ** 2)
        # geodesic: angle of Td^T T
        M = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                M[i, j] = Td[0, i] * T[0, j] + Td[1, i] * T[1, j] + Td[2, i] * T[2, j]
        vx, vy, vz = M[2, 1] - M[1, 2], M[0, 2] - M[2, 0], M[1, 0] - M[0, 1]
        ang = math.atan2(0.5 * math.sqrt(vx * vx + vy * vy + vz * vz), 0.5 * (M[0, 0] + M[1, 1] + M[2, 2] - 1.0))
        geo = dp + weight * ang
        if geo > J_CUTOFF_FACTOR * weight:  # far from a solution: the paper's J is not needed
            return geo, np.inf
        a, b, g = _zyz(T)
        ad, bd, gd = _zyz(Td)
        da, db, dg = _wrap(a - ad), b - bd, _wrap(g - gd)
        if b < GIMBAL_TOL or bd < GIMBAL_TOL:
            da, dg = 0.0, _wrap((a + g) - (ad + gd))
        elif math.pi - b < GIMBAL_TOL or math.pi - bd < GIMBAL_TOL:
            da, dg = 0.0, _wrap((a - g) - (ad - gd))
        jo = math.sqrt(da * da + db * db + dg * dg)
        return geo, math.sqrt(dp * dp + (weight * jo) ** 2)

    @njit(cache=True)
    def _certify_one(cfg, params, world, theta, branch, H, P, rev, R_end, weight, q, i, k):
        """Configuration of candidate k (pose i) into q[k]; returns (geodesic error, paper J)."""
        cfg(params[i], theta[k], branch[k], q[k])
        if not np.all(np.isfinite(q[k])):
            return np.inf, np.inf
        T = np.empty((4, 4))
        _poe_fk(H, P, rev, R_end, q[k], T)
        return _errors(T, world[i], weight)

    _CERTIFY_SIG = (
        _CFG,
        float64[:, ::1],
        float64[:, :, ::1],
        int64[::1],
        float64[::1],
        int64[::1],
        float64[:, ::1],
        float64[:, ::1],
        types.boolean[::1],
        float64[:, ::1],
        float64,
        float64[:, ::1],
        float64[::1],
        float64[::1],
    )

    @lazy_njit(_CERTIFY_SIG, cache=True, parallel=True)
    def _certify_parallel(cfg, params, world, pose, theta, branch, H, P, rev, R_end, weight, q, err_geo, err_paper):
        for k in prange(pose.shape[0]):
            err_geo[k], err_paper[k] = _certify_one(
                cfg, params, world, theta, branch, H, P, rev, R_end, weight, q, pose[k], k
            )

    @lazy_njit(_CERTIFY_SIG, cache=True)
    def _certify_serial(cfg, params, world, pose, theta, branch, H, P, rev, R_end, weight, q, err_geo, err_paper):
        for k in range(pose.shape[0]):
            err_geo[k], err_paper[k] = _certify_one(
                cfg, params, world, theta, branch, H, P, rev, R_end, weight, q, pose[k], k
            )


def certify(robot, red, chain: Array, world: Array, pose, theta: Array, branch, params: Array | None = None):
    """Configurations ``(K, n)``, geodesic errors and paper errors ``(K,)`` of the candidates
    (inf errors where the branch does not exist)."""
    K = pose.shape[0]
    q = np.empty((K, robot.n_joints))
    eg = np.empty(K)
    ep = np.empty(K)
    run = _certify_parallel if K >= 16 * PARALLEL_MIN else _certify_serial
    ch = robot.chain
    run(
        first_class(red.kernel[1]),
        np.ascontiguousarray(red.kernel_params(chain) if params is None else params, dtype=np.float64),
        np.ascontiguousarray(world, dtype=np.float64),
        pose.astype(np.int64),
        theta.astype(np.float64),
        branch.astype(np.int64),
        np.array(ch.H),  # writable copies: the compiled signature takes writable arrays
        np.array(ch.P),
        np.array(ch.revolute),
        np.array(ch.R_end),
        float(orientation_weight(robot.length_unit)),
        q,
        eg,
        ep,
    )
    return q, eg, ep


if AVAILABLE:

    @lazy_njit((_CFG, float64[:, ::1], int64[::1], float64[::1], int64[::1], float64[:, ::1]), cache=True)
    def _configurations(cfg, params, pose, theta, branch, q):
        for k in range(pose.shape[0]):
            cfg(params[pose[k]], theta[k], branch[k], q[k])


def configurations(robot: Robot, red: Reduction, chain: Array, pose: IntArray, theta: Array, branch: IntArray) -> Array:
    """Configurations ``(K, n)`` of branch ``branch`` at theta* ``theta`` of chain poses ``chain[pose]`` (compiled
    ``solve_rest`` for reductions with a kernel; NaN rows where the branch does not exist)."""
    q = np.empty((pose.shape[0], robot.n_joints))
    assert red.kernel is not None  # callers check red.uses_kernel
    _configurations(
        first_class(red.kernel[1]),
        np.ascontiguousarray(red.kernel_params(chain), dtype=np.float64),
        pose.astype(np.int64),
        theta.astype(np.float64),
        branch.astype(np.int64),
        q,
    )
    return q
