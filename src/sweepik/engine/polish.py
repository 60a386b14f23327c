"""Newton polish of near-solutions on the full pose (pseudo-inverse of the geometric Jacobian).

A reduction can be badly conditioned where theta* barely moves the pose (e.g. the C-Arm's d1 reduction
while theta2 swings through pi within |Pz - d1| ~ |Px|): there a root in theta* at full precision still
leaves ~1e-10 mm of pose error. One or two Newton steps on all six joints remove it. Next to a singular
configuration (an elbow almost straight) the step is damped: halved until it lowers the error.

With Numba the same steps run compiled (``certify.polish_rows``): the continuation of a traced family corrects a
few hundred configurations one by one, ~1.5 ms each in NumPy (a shoulder-singular pose of a spherical-wrist arm, four
families along joint 1: 250-450 ms, now ~55 ms). This NumPy loop is what runs without Numba.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.settings import BACKTRACK, ITERATIONS, PINV_RCOND, PINV_WIDEN
from sweepik.model import kinematics
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.robot import Robot

Array = NDArray[np.float64]


def pose_and_jacobian(robot: Robot, q: Array) -> tuple[Array, Array]:
    """World tool poses and geometric Jacobians at the tool point of configurations ``q (K, n)``: compiled when Numba
    is present, else :func:`sweepik.model.kinematics.geometric_jacobian`."""
    from sweepik.engine import certify

    if certify.AVAILABLE:
        return certify.pose_and_jacobian(robot, q)
    return _pose(robot, q), kinematics.geometric_jacobian(robot, q)


def geodesic_errors(robot: Robot, q: Array, target: Array, weight: float) -> Array:
    """Geodesic errors of configurations ``q (K, n)`` to ``target (K, 4, 4)`` (compiled when Numba is present: a
    polish of a few configurations is mostly these evaluations, ~70 us each in NumPy)."""
    from sweepik.engine.certify import AVAILABLE, tool_poses

    if AVAILABLE:
        return tool_poses(robot, q, target, weight)[1]
    return pose_error_geodesic(_pose(robot, q), target, weight)


def polish(
    robot: Robot,
    q: Array,
    target: Array,
    weight: float,
    iterations: int = ITERATIONS,
    fixed: NDArray[np.bool_] | None = None,
    floor: float = 0.0,
) -> Array:
    """:func:`polished`'s configurations alone."""
    return polished(robot, q, target, weight, iterations, fixed, floor)[0]


def polished(
    robot: Robot,
    q: Array,
    target: Array,
    weight: float,
    iterations: int = ITERATIONS,
    fixed: NDArray[np.bool_] | None = None,
    floor: float = 0.0,
) -> tuple[Array, Array]:
    """Improve configurations ``q (K, n)`` towards poses ``target (K, 4, 4)`` by damped Newton steps on the full
    pose; a step is kept only if the geodesic error (position + ``weight`` x angle) decreases, else it is halved
    (up to ``BACKTRACK`` times), then tried with more small singular directions dropped (``PINV_WIDEN``), and a
    configuration no step improves is left as it is. A configuration stops
    once its error is at most ``floor`` (after one step at least). ``fixed (K, n)``: joints held where True.
    Returns ``(q, geodesic errors (K,))``."""
    if q.shape[0] == 0:
        return q, np.zeros(0)
    from sweepik.engine.certify import AVAILABLE, polish_rows

    if AVAILABLE:  # (the same steps, compiled: a single configuration's polish took ~1.5 ms in NumPy, continuation
        # corrects hundreds along a traced family)
        held = np.zeros(q.shape, dtype=np.bool_) if fixed is None else fixed
        return polish_rows(robot, q, target, weight, held, iterations, BACKTRACK, PINV_RCOND, floor)
    q = q.copy()
    err = geodesic_errors(robot, q, target, weight)
    scale = np.array([1.0, 1.0, 1.0, weight, weight, weight])
    active = np.arange(q.shape[0])
    for _ in range(iterations):
        qa, ta = q[active], target[active]
        T, J = pose_and_jacobian(robot, qa)
        dp = ta[:, :3, 3] - T[:, :3, 3]
        dR = ta[:, :3, :3] @ np.swapaxes(T[:, :3, :3], -1, -2)
        w = 0.5 * np.stack([dR[:, 2, 1] - dR[:, 1, 2], dR[:, 0, 2] - dR[:, 2, 0], dR[:, 1, 0] - dR[:, 0, 1]], -1)
        e = np.concatenate([dp, w], axis=-1) * scale
        Js = J * scale[:, None]
        if fixed is not None:
            Js = np.where(fixed[active][:, None, :], 0.0, Js)
        improved = np.zeros(active.size, dtype=bool)
        todo = np.arange(active.size)
        for widen in PINV_WIDEN:
            # pseudo-inverse per candidate: singular Jacobians (rank-deficient arms poses) stay bounded
            step = np.einsum("kij,kj->ki", np.linalg.pinv(Js, rcond=PINV_RCOND * widen), e)
            if fixed is not None:  # (a held joint's zero column gives a step of rounding size: none at all)
                step = np.where(fixed[active], 0.0, step)
            for _ in range(BACKTRACK + 1):
                q_new = qa[todo] + step[todo]
                err_new = geodesic_errors(robot, q_new, ta[todo], weight)
                better = np.isfinite(err_new) & (err_new < err[active[todo]])
                rows = active[todo[better]]
                q[rows], err[rows] = q_new[better], err_new[better]
                improved[todo[better]] = True
                todo = todo[~better]
                if todo.size == 0:
                    break
                step[todo] *= 0.5
            if todo.size == 0:
                break
        active = active[improved & (err[active] > floor)]
        if active.size == 0:
            break
    return q, err


def _pose(robot: Robot, q: Array) -> Array:
    """World tool poses (the NumPy path: with Numba the compiled ``certify`` kernels are used instead)."""
    return kinematics.chain_frames(robot, q)[:, -1] @ robot.T_flange_tool
