"""Chain geometry in product-of-exponentials form: each joint's axis line and type at the zero configuration.

This is the description the geometric subproblems and the automatic decomposition work on (IK-Geo's
``(H, P)``), computed once per robot from whatever the robot is written in (DH of either convention, or a
fixed origin transform + an axis per joint as URDF has). Everything is in the **world** frame at ``q = 0``,
base transform included:

* ``H (n, 3)``: unit axis of each joint (rotation axis, or the direction a prismatic joint slides along);
* ``P (n + 1, 3)``: ``P[0]`` from the world origin to a point of joint 1's axis, ``P[i]`` from the point of
  joint i to the point of joint i + 1, ``P[n]`` from the point of joint n to the tool origin;
* ``R_end (3, 3)``: the tool orientation at ``q = 0``.

Forward kinematics (``Chain.fk``)::

    R = I; p = P[0]
    for joint i:  revolute: R = R @ rot(H[i], q[i])     prismatic: p += R @ H[i] * q[i]
                  p += R @ P[i + 1]
    T = [[R @ R_end, p], [0, 1]]

``Chain.reversed()`` is the chain of the inverse pose (joints in reverse order, seen from the tool): a
structure at the base of a chain is the same structure at the tool of its reversed chain.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from numpy.typing import ArrayLike, NDArray

Array = NDArray[np.float64]

__all__ = ["Chain", "rotation_about"]


def rotation_about(k: ArrayLike, theta: ArrayLike) -> Array:
    """Rotation matrices ``(..., 3, 3)`` by ``theta (...)`` radians about unit axes ``k (..., 3)`` (Rodrigues)."""
    ka = np.asarray(k, dtype=np.float64)
    t = np.asarray(theta, dtype=np.float64)[..., None, None]
    K = np.zeros((*ka.shape[:-1], 3, 3))
    K[..., 0, 1], K[..., 0, 2] = -ka[..., 2], ka[..., 1]
    K[..., 1, 0], K[..., 1, 2] = ka[..., 2], -ka[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -ka[..., 1], ka[..., 0]
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * (K @ K)


def _frozen(a: ArrayLike) -> Array:
    arr = np.array(a, dtype=np.float64)
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Chain:
    """A serial chain in product-of-exponentials form (see the module docstring). Lengths in the robot's unit."""

    H: Array
    P: Array
    revolute: NDArray[np.bool_]
    R_end: Array

    def __post_init__(self) -> None:
        for name in ("H", "P", "R_end"):
            object.__setattr__(self, name, _frozen(getattr(self, name)))
        rev = np.array(self.revolute, dtype=bool)
        rev.setflags(write=False)
        object.__setattr__(self, "revolute", rev)

    @classmethod
    def from_frames(cls, axes: ArrayLike, points: ArrayLike, revolute: ArrayLike, T_world_tool: ArrayLike) -> Chain:
        """Chain from the joints' world axes ``(n, 3)``, points on them ``(n, 3)`` and the tool pose, all at q = 0."""
        h = np.asarray(axes, dtype=np.float64)
        o = np.asarray(points, dtype=np.float64)
        T = np.asarray(T_world_tool, dtype=np.float64)
        h = h / np.linalg.norm(h, axis=-1, keepdims=True)
        pts = np.concatenate([np.zeros((1, 3)), o, T[None, :3, 3]])
        return cls(h, np.diff(pts, axis=0), np.asarray(revolute, dtype=bool), T[:3, :3])

    @property
    def n_joints(self) -> int:
        return int(self.H.shape[0])

    @cached_property
    def points(self) -> Array:
        """``(n, 3)``: the point of each joint's axis (world, q = 0) that ``P`` is built from."""
        return np.asarray(np.cumsum(self.P[:-1], axis=0), dtype=np.float64)

    def fk(self, q: ArrayLike) -> Array:
        """Tool poses ``(..., 4, 4)`` for ``q (..., n)`` (radians / length unit)."""
        qa = np.asarray(q, dtype=np.float64)
        R = np.broadcast_to(np.eye(3), (*qa.shape[:-1], 3, 3)).copy()
        p = np.broadcast_to(self.P[0], (*qa.shape[:-1], 3)).copy()
        for i in range(self.n_joints):
            if self.revolute[i]:
                R = R @ rotation_about(self.H[i], qa[..., i])
            else:
                p = p + (R @ self.H[i]) * qa[..., i, None]
            p = p + R @ self.P[i + 1]
        T = np.zeros((*qa.shape[:-1], 4, 4))
        T[..., :3, :3] = R @ self.R_end
        T[..., :3, 3] = p
        T[..., 3, 3] = 1.0
        return T

    def reversed(self) -> Chain:
        """The chain of the inverse pose: ``reversed().fk(q[..., ::-1]) == inv(fk(q))``, in the tool frame at q = 0.

        Joint j of the reversed chain is joint n - 1 - j of this one, with the same value.
        """
        Rt = self.R_end.T
        return Chain(-(self.H[::-1] @ Rt.T), -(self.P[::-1] @ Rt.T), self.revolute[::-1], Rt)

    def key(self) -> bytes:
        """Content key (for caches): the chain's numbers and joint types as bytes."""
        return b"".join(a.tobytes() for a in (self.H, self.P, self.revolute, self.R_end))
