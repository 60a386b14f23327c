"""Newton polish of near-solutions on the full pose (pseudo-inverse of the geometric Jacobian).

A reduction can be badly conditioned where theta* barely moves the pose (e.g. the C-Arm's d1 reduction
while theta2 swings through pi within |Pz - d1| ~ |Px|): there a root in theta* at full precision still
leaves ~1e-10 mm of pose error. One or two Newton steps on all six joints remove it. Next to a singular
configuration (an elbow almost straight) the step is damped: halved until it lowers the error.

The steps run compiled (``certify.polish_rows``): the continuation of a traced family corrects a few hundred
configurations one by one, ~1.5 ms each in NumPy (a shoulder-singular pose of a spherical-wrist arm, four families
along joint 1: 250-450 ms, compiled ~55 ms). The tests hold them against a NumPy reference
(``tests/oracles/numpy_engine.py``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.settings import BACKTRACK, ITERATIONS, PINV_RCOND
from sweepik.model.robot import Robot

Array = NDArray[np.float64]


def pose_and_jacobian(robot: Robot, q: Array) -> tuple[Array, Array]:
    """World tool poses and geometric Jacobians at the tool point of configurations ``q (K, n)`` (compiled)."""
    from sweepik.engine import certify

    return certify.pose_and_jacobian(robot, q)


def geodesic_errors(robot: Robot, q: Array, target: Array, weight: float) -> Array:
    """Geodesic errors of configurations ``q (K, n)`` to ``target (K, 4, 4)`` (compiled: a polish of a few
    configurations is mostly these evaluations, ~70 us each in NumPy)."""
    from sweepik.engine.certify import tool_poses

    return tool_poses(robot, q, target, weight)[1]


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
    from sweepik.engine.certify import polish_rows

    held = np.zeros(q.shape, dtype=np.bool_) if fixed is None else fixed
    return polish_rows(robot, q, target, weight, held, iterations, BACKTRACK, PINV_RCOND, floor)
