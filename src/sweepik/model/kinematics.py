"""Batched forward kinematics and the geometric Jacobian for DH chains.

All functions take joint values ``q (..., n)`` (radians for revolute joints, the robot's length unit for
prismatic ones) and loop only over the joints, never over configurations.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from sweepik.model.chain import rotation_about

Array = NDArray[np.float64]


class _Joint(Protocol):
    @property
    def origin(self) -> object: ...
    @property
    def axis(self) -> object: ...


class Arm(Protocol):
    """What these functions read of a :class:`sweepik.model.robot.Robot` (which imports this module)."""

    @property
    def joints(self) -> Sequence[_Joint]: ...
    @property
    def n_joints(self) -> int: ...
    @property
    def dh_convention(self) -> str: ...
    @property
    def dh_a(self) -> Array: ...
    @property
    def dh_alpha(self) -> Array: ...
    @property
    def dh_theta(self) -> Array: ...
    @property
    def dh_d(self) -> Array: ...
    @property
    def is_revolute(self) -> NDArray[np.bool_]: ...
    @property
    def T_world_base(self) -> Array: ...
    @property
    def T_flange_tool(self) -> Array: ...


def _origin_axis_transforms(robot: Arm, q: Array) -> Array:
    """``origin_i @ Rot(axis_i, q_i)`` or ``origin_i @ Trans(axis_i q_i)`` for ``dh_convention="none"``."""
    origins = np.array([j.origin for j in robot.joints], dtype=np.float64)
    axes = np.array([j.axis for j in robot.joints], dtype=np.float64)
    M = np.zeros((*q.shape, 4, 4))
    rev = robot.is_revolute
    M[..., :3, :3] = np.where(rev[:, None, None], rotation_about(axes, np.where(rev, q, 0.0)), np.eye(3))
    M[..., :3, 3] = np.where(rev[:, None], 0.0, axes * q[..., None])
    M[..., 3, 3] = 1.0
    return np.asarray(origins @ M, dtype=np.float64)


def link_transforms(robot: Arm, q: Array) -> Array:
    """Transforms ``(..., n, 4, 4)`` of each link frame relative to the previous one."""
    if robot.dh_convention == "none":
        return _origin_axis_transforms(robot, q)
    a = robot.dh_a
    alpha = robot.dh_alpha
    theta = robot.dh_theta + np.where(robot.is_revolute, q, 0.0)
    d = robot.dh_d + np.where(robot.is_revolute, 0.0, q)
    ct, st = np.cos(theta), np.sin(theta)
    ca, sa = np.cos(alpha), np.sin(alpha)
    shape = (*q.shape, 4, 4)
    T = np.zeros(shape)
    if robot.dh_convention == "modified":
        # Craig: RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i) TransZ(d_i)
        T[..., 0, 0] = ct
        T[..., 0, 1] = -st
        T[..., 0, 3] = a
        T[..., 1, 0] = st * ca
        T[..., 1, 1] = ct * ca
        T[..., 1, 2] = -sa
        T[..., 1, 3] = -sa * d
        T[..., 2, 0] = st * sa
        T[..., 2, 1] = ct * sa
        T[..., 2, 2] = ca
        T[..., 2, 3] = ca * d
    else:
        # standard: RotZ(theta_i) TransZ(d_i) TransX(a_i) RotX(alpha_i)
        T[..., 0, 0] = ct
        T[..., 0, 1] = -st * ca
        T[..., 0, 2] = st * sa
        T[..., 0, 3] = a * ct
        T[..., 1, 0] = st
        T[..., 1, 1] = ct * ca
        T[..., 1, 2] = -ct * sa
        T[..., 1, 3] = a * st
        T[..., 2, 1] = sa
        T[..., 2, 2] = ca
        T[..., 2, 3] = d
    T[..., 3, 3] = 1.0
    return T


def chain_frames(robot: Arm, q: Array) -> Array:
    """World poses ``(..., n + 1, 4, 4)`` of the base (index 0) and of link frames 1..n (tool not applied)."""
    links = link_transforms(robot, q)
    n = robot.n_joints
    out = np.empty((*q.shape[:-1], n + 1, 4, 4))
    out[..., 0, :, :] = robot.T_world_base
    for i in range(n):
        out[..., i + 1, :, :] = out[..., i, :, :] @ links[..., i, :, :]
    return out


def joint_axes(robot: Arm, frames: Array) -> tuple[Array, Array]:
    """Unit axes ``(..., n, 3)`` and points on them ``(..., n, 3)`` of each joint, in world coordinates.

    Modified DH: joint i moves along/about z of frame i. Standard DH: about z of frame i - 1. Origin + axis
    (``dh_convention="none"``): about its axis in frame i.
    """
    n = robot.n_joints
    sel = frames[..., 0:n, :, :] if robot.dh_convention == "standard" else frames[..., 1 : n + 1, :, :]
    if robot.dh_convention == "none":
        axes = np.array([j.axis for j in robot.joints], dtype=np.float64)
        return np.einsum("...ij,...j->...i", sel[..., :3, :3], axes), sel[..., :3, 3]
    return sel[..., :3, 2], sel[..., :3, 3]


def geometric_jacobian(robot: Arm, q: Array) -> Array:
    """Geometric Jacobian ``(..., 6, n)`` in world coordinates at the tool point.

    Rows 0-2: linear velocity of the tool origin; rows 3-5: angular velocity (rad per unit of q).
    """
    frames = chain_frames(robot, q)
    tool = frames[..., -1, :, :] @ robot.T_flange_tool
    z, o = joint_axes(robot, frames)
    p = tool[..., None, :3, 3]
    rev = robot.is_revolute[:, None]
    lin = np.where(rev, np.cross(z, p - o), z)
    ang = np.where(rev, z, 0.0)
    return np.swapaxes(np.concatenate([lin, ang], axis=-1), -1, -2)
