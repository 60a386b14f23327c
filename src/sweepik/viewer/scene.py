"""What the viewer draws, as plain arrays (no viser here): an arm as line segments through its frames, in metres.

An arm is drawn as its kinematic skeleton: a segment from each frame's origin to the next one's (base, the joint
frames of ``Robot.frames``, the tool), a short segment along each joint's axis, and the tool's axes. Lengths are
turned into metres (viser's grid and camera are in metres) by ``metres_per_unit``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit

Array = NDArray[np.float64]

#: Colours (RGB 0-255): the chosen solution, the other solutions (ghosts), a solution outside the joint limits, a
#: multiple root (the arm singular there), a self-motion family's member, and the target.
SOLID = (0, 40, 150)
GHOST = (85, 95, 120)
OUTSIDE = (220, 60, 60)
MULTIPLE = (240, 150, 20)
FAMILY = (150, 70, 200)
TARGET = (20, 170, 90)


def metres_per_unit(robot: Robot) -> float:
    return mm_per_unit(robot.length_unit) / 1000.0


def size_m(robot: Robot) -> float:
    """A drawing scale: the arm's size in metres (``Robot.length_scale``), at least 5 cm."""
    return max(robot.length_scale * metres_per_unit(robot), 0.05)


@dataclass(frozen=True)
class Skeleton:
    """One configuration drawn: ``links (k, 2, 3)`` segments between frame origins, ``axes (n, 2, 3)`` a segment
    along each joint's axis (z of its frame for DH arms, the joint's axis for origin + axis arms), ``tool (4, 4)``
    the tool pose; all in metres."""

    links: Array
    axes: Array
    tool: Array


def skeleton(robot: Robot, q: Array) -> Skeleton:
    """The segments that draw ``robot`` at ``q (n,)``."""
    s = metres_per_unit(robot)
    F = robot.frames(np.asarray(q, dtype=np.float64))
    origins = F[:, :3, 3] * s
    keep = np.concatenate([[True], np.linalg.norm(np.diff(origins, axis=0), axis=1) > 1e-9])
    pts = origins[keep]
    links = np.stack([pts[:-1], pts[1:]], axis=1) if len(pts) > 1 else np.zeros((0, 2, 3))
    half = 0.06 * size_m(robot)
    axes = []
    for k, joint in enumerate(robot.joints):
        if robot.dh_convention == "none":  # joint k's frame after its motion: its axis is the same line
            frame, direction = F[k + 1], F[k + 1][:3, :3] @ np.asarray(joint.axis)
        else:  # the joint turns about z of frame k (modified DH: of frame k + 1)
            frame = F[k + 1] if robot.dh_convention == "modified" else F[k]
            direction = frame[:3, 2]
        centre = frame[:3, 3] * s
        axes.append([centre - half * direction, centre + half * direction])
    tool = F[-1].copy()
    tool[:3, 3] *= s
    return Skeleton(links=links, axes=np.array(axes), tool=tool)


def pose_in_metres(robot: Robot, T: Array) -> Array:
    """A pose of the robot's length unit with its translation in metres."""
    out = np.array(T, dtype=np.float64)
    out[:3, 3] *= metres_per_unit(robot)
    return out


def pose_from_metres(robot: Robot, T: Array) -> Array:
    """The inverse of :func:`pose_in_metres`."""
    out = np.array(T, dtype=np.float64)
    out[:3, 3] /= metres_per_unit(robot)
    return out


def colour(within_limits: bool, multiplicity: int, chosen: bool) -> tuple[int, int, int]:
    """The colour of a solution's skeleton."""
    if not within_limits:
        return OUTSIDE
    if multiplicity > 1:
        return MULTIPLE
    return SOLID if chosen else GHOST


def unit_cylinder(segments: int = 16) -> tuple[Array, NDArray[np.int32]]:
    """A closed cylinder of radius 1 and height 1 along z, centred at the origin: ``(vertices, faces)``."""
    a = np.linspace(0.0, 2.0 * np.pi, segments, endpoint=False)
    ring = np.stack([np.cos(a), np.sin(a)], axis=1)
    bottom = np.column_stack([ring, np.full(segments, -0.5)])
    top = np.column_stack([ring, np.full(segments, 0.5)])
    vertices = np.vstack([bottom, top, [[0.0, 0.0, -0.5], [0.0, 0.0, 0.5]]])
    i = np.arange(segments)
    j = (i + 1) % segments
    c0, c1 = 2 * segments, 2 * segments + 1
    faces = np.vstack([
        np.column_stack([i, j, segments + j]), np.column_stack([i, segments + j, segments + i]),  # the side
        np.column_stack([np.full(segments, c0), j, i]), np.column_stack([np.full(segments, c1), segments + i,
                                                                         segments + j]),
    ])  # fmt: skip
    return vertices, faces.astype(np.int32)


def cylinders(segments: Array, radius: float) -> tuple[Array, Array, Array]:
    """Instances of :func:`unit_cylinder` along ``segments (k, 2, 3)``: quaternions ``(k, 4)`` (w, x, y, z) turning
    z onto each segment, centres ``(k, 3)`` and scales ``(k, 3)`` (radius, radius, length)."""
    a, b = segments[:, 0], segments[:, 1]
    d = b - a
    length = np.linalg.norm(d, axis=1)
    u = d / np.maximum(length, 1e-12)[:, None]
    # the half-way quaternion between z and u: (1 + z.u, z x u), normalised; u = -z takes a turn about x
    w = 1.0 + u[:, 2]
    xyz = np.column_stack([-u[:, 1], u[:, 0], np.zeros(len(u))])
    q = np.column_stack([w, xyz])
    flip = w < 1e-9
    q[flip] = [0.0, 1.0, 0.0, 0.0]
    q /= np.linalg.norm(q, axis=1)[:, None]
    scales = np.column_stack([np.full(len(u), radius), np.full(len(u), radius), length])
    return q, 0.5 * (a + b), scales
