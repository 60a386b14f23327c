"""Statics: the joint torques (and prismatic forces) that hold an arm still against gravity.

A point mass ``m`` at world position ``p(q)`` has potential energy ``V = -m g0 (ĝ · p)`` (``ĝ``: the robot's
``gravity`` direction, ``g0 = STANDARD_GRAVITY``). The generalised force an actuator must exert to hold the
configuration is ``tau = dV/dq``: positive ``tau_i`` pushes joint i towards larger values. For every joint, the
masses it carries (every link beyond it and the payload) act as their total mass at their common centre ``c``:

* revolute joint (axis ``z`` through ``o``): ``tau = m_tot g0 z · (ĝ × (c - o))`` in N·m;
* prismatic joint (direction ``z``): ``tau = -m_tot g0 (z · ĝ)`` in N.

Masses: the payload (``payload`` kg at ``payload_com``, in the tool frame, robot's length unit) and, with
``links=True``, each link's ``Joint.mass`` at ``Joint.com`` (in its link frame). Lengths are converted to metres,
so torques come out in N·m whatever the robot's length unit. Friction, dynamics and the base are out of scope.

>>> import numpy as np
>>> from sweepik import load_robot
>>> from sweepik.experiments.statics import gravity_torques
>>> tau = gravity_torques(load_robot("carm"), np.zeros(6), payload=12.0)
>>> round(float(tau[2]), 2)  # theta3 holds 12 kg 402 mm out, on the horizontal forearm
-47.31
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import UnknownOptionError
from sweepik.model import kinematics
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import MAX_LENGTH, check_configuration

__all__ = ["STANDARD_GRAVITY", "gravity_torques", "potential_energy", "torque_units"]

Array = NDArray[np.float64]

#: Standard acceleration of gravity (m/s²).
STANDARD_GRAVITY = 9.80665
#: Largest payload accepted (kg): beyond it the number is a typo, not a payload.
MAX_PAYLOAD = 1e6


def torque_units(robot: Robot) -> list[str]:
    """The unit of each joint's holding effort: ``"N·m"`` (revolute) or ``"N"`` (prismatic)."""
    return ["N·m" if r else "N" for r in robot.is_revolute]


def _check_payload(robot: Robot, payload: float, payload_com: ArrayLike) -> tuple[float, Array]:
    if isinstance(payload, bool) or not isinstance(payload, int | float | np.floating | np.integer):
        raise UnknownOptionError(f"payload must be a mass in kg (a number), got {type(payload).__name__}")
    m = float(payload)
    if not (np.isfinite(m) and 0.0 <= m <= MAX_PAYLOAD):
        raise UnknownOptionError(f"payload must be a mass in kg between 0 and {MAX_PAYLOAD:g}, got {payload!r}")
    try:
        c = np.array(payload_com, dtype=np.float64)
    except (TypeError, ValueError):
        c = np.zeros(0)
    if c.shape != (3,) or not np.all(np.isfinite(c)) or np.any(np.abs(c) > MAX_LENGTH):
        raise UnknownOptionError(
            f"payload_com must be 3 finite numbers of magnitude at most {MAX_LENGTH:g} (tool frame, "
            f"{robot.length_unit}), got {payload_com!r}"
        )
    return m, c


def _mass_points(
    robot: Robot, q: ArrayLike, payload: float, payload_com: ArrayLike, links: bool
) -> tuple[Array, Array, Array, Array]:
    """The arguments checked, then ``(masses (n + 1,), points (..., n + 1, 3), axes (..., n, 3), axis points
    (..., n, 3))``: point k < n is link k + 1's centre of mass, point n the payload (rides on the last link); world
    frame, length unit."""
    qa = check_configuration(q, robot.n_joints)
    mass, com = _check_payload(robot, payload, payload_com)
    frames = kinematics.chain_frames(robot, qa)
    tool = frames[..., -1, :, :] @ robot.T_flange_tool
    n = robot.n_joints
    masses = np.zeros(n + 1)
    if links:
        masses[:n] = [j.mass for j in robot.joints]
    masses[n] = mass
    coms = np.array([j.com for j in robot.joints] + [list(com)], dtype=np.float64)
    poses = np.concatenate([frames[..., 1:, :, :], tool[..., None, :, :]], axis=-3)
    points = np.einsum("...kij,kj->...ki", poses[..., :3, :3], coms) + poses[..., :3, 3]
    z, o = kinematics.joint_axes(robot, frames)
    return masses, points, z, o


def gravity_torques(
    robot: Robot,
    q: ArrayLike,
    *,
    payload: float = 0.0,
    payload_com: ArrayLike = (0.0, 0.0, 0.0),
    links: bool = True,
) -> Array:
    """Holding efforts ``(..., n)`` against gravity at configurations ``q (..., n)``: N·m for revolute joints, N
    for prismatic ones (see the module docstring for the sign and the masses counted)."""
    masses, points, z, o = _mass_points(robot, q, payload, payload_com, bool(links))
    n = robot.n_joints
    # masses beyond joint i: links i..n-1 (link k is moved by joint k) and the payload
    beyond = np.cumsum(masses[::-1])[::-1][:n]  # (n,)
    moment = np.cumsum((masses[:, None] * points)[..., ::-1, :], axis=-2)[..., ::-1, :][..., :n, :]
    g = np.array(robot.gravity)
    metres = mm_per_unit(robot.length_unit) / 1000.0
    # revolute: z · (ĝ × (sum m p - m_tot o)), in N·m
    arm = (moment - beyond[:, None] * o) * metres
    rev = np.einsum("...i,...i->...", z, np.cross(g, arm))
    pri = -beyond * np.einsum("...i,i->...", z, g)
    return np.asarray(STANDARD_GRAVITY * np.where(robot.is_revolute, rev, pri), dtype=np.float64)


def potential_energy(
    robot: Robot,
    q: ArrayLike,
    *,
    payload: float = 0.0,
    payload_com: ArrayLike = (0.0, 0.0, 0.0),
    links: bool = True,
) -> Array:
    """Gravitational potential energy ``(...)`` in J (zero at the world origin's height) of the masses that
    :func:`gravity_torques` counts; its derivative along q is those torques."""
    masses, points, _, _ = _mass_points(robot, q, payload, payload_com, bool(links))
    metres = mm_per_unit(robot.length_unit) / 1000.0
    height = -np.einsum("...ki,i->...k", points, np.array(robot.gravity)) * metres
    return np.asarray(STANDARD_GRAVITY * height @ masses, dtype=np.float64)
