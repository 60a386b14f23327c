"""Compiled (Numba) certification of candidate roots: configuration from the reduction's kernel, forward
kinematics, the geodesic error and the paper's J (eq. 6) in one pass per candidate. The same formulas as
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
from .reductions.kernels import configuration_by_id
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
    from numba import njit, prange

    from .fastsweep import _fk_one

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
    def _certify_one(kid, params, chain, world, theta, branch, a, alpha, d, th0, rev, base, tool, weight, q, i, k):
        """Configuration of candidate k (pose i) into q[k]; returns (geodesic error, paper J)."""
        configuration_by_id(kid, params[i], chain[i], theta[k], branch[k], q[k])
        if not np.all(np.isfinite(q[k])):
            return np.inf, np.inf
        F = np.empty((1, 4, 4))
        qq = np.empty((1, a.shape[0]))
        qq[0] = q[k]
        _fk_one(a, alpha, d, th0, rev, base, qq, F, 0)
        T = np.zeros((4, 4))  # flange @ tool, without BLAS
        for r in range(4):
            for c in range(4):
                T[r, c] = F[0, r, 0] * tool[0, c] + F[0, r, 1] * tool[1, c] + F[0, r, 2] * tool[2, c]
                T[r, c] += F[0, r, 3] * tool[3, c]
        return _errors(T, world[i], weight)

    @njit(cache=True, parallel=True)
    def _certify_parallel(
        kid, params, chain, world, pose, theta, branch, a, alpha, d, th0, rev, base, tool, weight, q, err_geo, err_paper
    ):
        for k in prange(pose.shape[0]):
            err_geo[k], err_paper[k] = _certify_one(
                kid, params, chain, world, theta, branch, a, alpha, d, th0, rev, base, tool, weight, q, pose[k], k
            )

    @njit(cache=True)
    def _certify_serial(
        kid, params, chain, world, pose, theta, branch, a, alpha, d, th0, rev, base, tool, weight, q, err_geo, err_paper
    ):
        for k in range(pose.shape[0]):
            err_geo[k], err_paper[k] = _certify_one(
                kid, params, chain, world, theta, branch, a, alpha, d, th0, rev, base, tool, weight, q, pose[k], k
            )


def certify(robot, red, chain: Array, world: Array, pose, theta: Array, branch, params: Array | None = None):
    """Configurations ``(K, n)``, geodesic errors and paper errors ``(K,)`` of the candidates
    (inf errors where the branch does not exist)."""
    K = pose.shape[0]
    q = np.empty((K, robot.n_joints))
    eg = np.empty(K)
    ep = np.empty(K)
    run = _certify_parallel if K >= 16 * PARALLEL_MIN else _certify_serial
    run(
        red.kernel_id,
        np.ascontiguousarray(red.kernel_params(chain) if params is None else params),
        np.ascontiguousarray(chain),
        np.ascontiguousarray(world),
        pose.astype(np.int64),
        theta.astype(np.float64),
        branch.astype(np.int64),
        robot.dh_a,
        robot.dh_alpha,
        robot.dh_d,
        robot.dh_theta,
        robot.is_revolute,
        np.ascontiguousarray(robot.T_world_base),
        np.ascontiguousarray(robot.T_flange_tool),
        orientation_weight(robot.length_unit),
        q,
        eg,
        ep,
    )
    return q, eg, ep


if AVAILABLE:

    @njit(cache=True)
    def _configurations(kid, params, chain, pose, theta, branch, q):
        for k in range(pose.shape[0]):
            configuration_by_id(kid, params[pose[k]], chain[pose[k]], theta[k], branch[k], q[k])


def configurations(robot: Robot, red: Reduction, chain: Array, pose: IntArray, theta: Array, branch: IntArray) -> Array:
    """Configurations ``(K, n)`` of branch ``branch`` at theta* ``theta`` of chain poses ``chain[pose]`` (compiled
    ``solve_rest`` for reductions with a kernel; NaN rows where the branch does not exist)."""
    q = np.empty((pose.shape[0], robot.n_joints))
    _configurations(
        red.kernel_id,
        np.ascontiguousarray(red.kernel_params(chain)),
        np.ascontiguousarray(chain),
        pose.astype(np.int64),
        theta.astype(np.float64),
        branch.astype(np.int64),
        q,
    )
    return q
