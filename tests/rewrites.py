"""The same arm written otherwise (an independent helper for the tests and scripts/ssik_catalogue.py).

``rewrite(robot, rng)`` returns an arm with the same motion written with axes reversed (q -> -q), joints' zeros moved
(q -> q - offset), other base and tool frames and, at random, another length unit (m <-> mm), and the map between
their configurations: ``Rewritten.forward(q)`` is the rewritten arm's configuration of the original's ``q`` (same tool
pose up to the base and tool transforms), ``Rewritten.back`` the inverse; ``Rewritten.pose(T)`` maps a pose of the
original to the rewritten arm's pose of the same configuration.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from sweepik import Joint, Robot
from sweepik.model.origin_axis import origin_axis_form

Array = np.ndarray


def rotation(axis: Array, angle: float) -> Array:
    """Rodrigues' rotation matrix about ``axis`` (any length) by ``angle`` (rad)."""
    k = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * (K @ K)


def random_transform(rng: np.random.Generator, length: float) -> Array:
    T = np.eye(4)
    T[:3, :3] = rotation(rng.normal(size=3), rng.uniform(-np.pi, np.pi))
    T[:3, 3] = rng.uniform(-length, length, 3)
    return T


def _rows(T: Array) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in T)


@dataclass(frozen=True)
class Rewritten:
    robot: Robot
    sign: Array  # (n,) +-1: the joint's axis reversed
    offset: Array  # (n,) rad: the joint's zero moved (revolute joints)
    scale: float  # length unit factor (new per old)
    A: Array  # new world from old world (4, 4), lengths in the new unit
    B: Array  # old tool to new tool (4, 4), lengths in the new unit
    revolute: Array

    def forward(self, q: Any) -> Array:
        q = np.asarray(q, dtype=float)
        return np.where(self.revolute, self.sign * q - self.offset, self.sign * q * self.scale)

    def back(self, q2: Any) -> Array:
        q2 = np.asarray(q2, dtype=float)
        return np.where(self.revolute, self.sign * (q2 + self.offset), self.sign * q2 / self.scale)

    def pose(self, T: Any) -> Array:
        S = np.array(T, dtype=float)
        S[..., :3, 3] *= self.scale
        return self.A @ S @ self.B


def rewrite(
    robot: Robot,
    rng: np.random.Generator,
    *,
    reverse: bool = True,
    offsets: bool = True,
    frames: bool = True,
    units: bool = True,
) -> Rewritten:
    """``robot`` written otherwise, at random (each kind of change may be switched off)."""
    r = origin_axis_form(robot)
    n = r.n_joints
    rev = np.array(r.is_revolute)
    scale = (1000.0 if r.length_unit == "m" else 0.001) if units and rng.random() < 0.5 else 1.0
    unit = {1000.0: "mm", 0.001: "m"}.get(scale, r.length_unit)
    sign = np.where(rng.random(n) < 0.5, -1.0, 1.0) if reverse else np.ones(n)
    offset = np.where(rev & (rng.random(n) < 0.5), rng.uniform(-np.pi, np.pi, n), 0.0) if offsets else np.zeros(n)
    joints = []
    for j, s, o in zip(r.joints, sign, offset, strict=True):
        org = np.array(j.origin)
        org[:3, 3] *= scale
        axis = np.array(j.axis)
        if o != 0.0:  # q_old = s (q_new + o): the joint's frame turned by s o about its axis at q_new = 0
            org[:3, :3] = org[:3, :3] @ rotation(axis, s * o)
        lo, hi = (j.lower, j.upper) if s > 0 else (-j.upper, -j.lower)
        lo, hi = (lo - o, hi - o) if j.is_revolute else (lo * scale, hi * scale)
        joints.append(
            Joint(j.type, origin=_rows(org), axis=tuple(float(v) for v in s * axis), lower=lo, upper=hi, name=j.name)
        )
    size = robot.length_scale * scale
    A = random_transform(rng, size) if frames else np.eye(4)
    B = random_transform(rng, 0.2 * size) if frames else np.eye(4)
    base, tool = np.array(r.T_world_base), np.array(r.T_flange_tool)
    base[:3, 3] *= scale
    tool[:3, 3] *= scale
    new = Robot(
        f"{r.name}_rewritten", tuple(joints), "none", T_world_base=A @ base, T_flange_tool=tool @ B, length_unit=unit
    )
    return Rewritten(new, sign, offset, scale, A, B, rev)
