"""Newton polish of near-solutions on the full pose (pseudo-inverse of the geometric Jacobian).

A reduction can be badly conditioned where theta* barely moves the pose (e.g. the C-Arm's d1 reduction
while theta2 swings through pi within |Pz - d1| ~ |Px|): there a root in theta* at full precision still
leaves ~1e-10 mm of pose error. One or two Newton steps on all six joints remove it.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from . import kinematics
from .pose import pose_error_geodesic
from .robot import Robot

Array = NDArray[np.float64]

#: Singular values below this fraction of the largest are dropped from the Newton step (pseudo-inverse):
#: keeps the step bounded at singular configurations, without effect at regular ones.
PINV_RCOND = 1e-10


def _pose_and_jacobian(robot: Robot, q: Array) -> tuple[Array, Array]:
    frames = kinematics.chain_frames(robot, q)
    T = frames[:, -1] @ robot.T_flange_tool
    return T, kinematics.geometric_jacobian(robot, q)


def polish(
    robot: Robot, q: Array, target: Array, weight: float, iterations: int = 2, fixed: NDArray[np.bool_] | None = None
) -> Array:
    """Improve configurations ``q (K, n)`` towards poses ``target (K, 4, 4)``; keeps a step only if the
    geodesic error (position + ``weight`` x angle) decreases. ``fixed (K, n)``: joints held where True."""
    if q.shape[0] == 0:
        return q
    q = q.copy()
    T = kinematics.chain_frames(robot, q)[:, -1] @ robot.T_flange_tool
    err = pose_error_geodesic(T, target, weight)
    scale = np.array([1.0, 1.0, 1.0, weight, weight, weight])
    for _ in range(iterations):
        T, J = _pose_and_jacobian(robot, q)
        dp = target[:, :3, 3] - T[:, :3, 3]
        dR = target[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2)
        w = 0.5 * np.stack([dR[:, 2, 1] - dR[:, 1, 2], dR[:, 0, 2] - dR[:, 2, 0], dR[:, 1, 0] - dR[:, 0, 1]], -1)
        e = np.concatenate([dp, w], axis=-1) * scale
        Js = J * scale[:, None]
        if fixed is not None:
            Js = np.where(fixed[:, None, :], 0.0, Js)
        # pseudo-inverse per candidate: singular Jacobians (rank-deficient arms poses) stay bounded
        q_new = q + np.einsum("kij,kj->ki", np.linalg.pinv(Js, rcond=PINV_RCOND), e)
        T_new = kinematics.chain_frames(robot, q_new)[:, -1] @ robot.T_flange_tool
        err_new = pose_error_geodesic(T_new, target, weight)
        better = np.isfinite(err_new) & (err_new < err)
        q[better] = q_new[better]
        err = np.where(better, err_new, err)
    return q
