"""A UR-type arm whose axes 1 and 2 meet (no shoulder offset along the parallel axes, as the Unitree Z1): with joint 6's
point W on axis 1, joint 1's step (``sp4`` on the height of W along the parallel axes) no longer involves joint 1, and
joint 1 turns freely along a continuum, the others following (issue 35: 6 of 30 Z1 configurations on its singular set
were missed). The parallel family flags such poses as degenerate; its fallback sweep reports the continua."""

from __future__ import annotations

import dataclasses

import numpy as np
from singular import families_certified, recovered, singular_configurations

import sweepik


def _ur5_without_shoulder_offset() -> sweepik.Robot:
    ur = sweepik.load_robot("ur5")
    joints = list(ur.joints)
    joints[3] = dataclasses.replace(joints[3], d=0.0)  # (UR's d4: the offset between the planes of joints 2 and 4)
    return sweepik.Robot("ur5_meeting_shoulder", tuple(joints), dh_convention="standard", length_unit="m")


def _on_axis_1(robot: sweepik.Robot, rng: np.random.Generator) -> np.ndarray:
    """A configuration with W on axis 1: joint 3 chosen so that W's distance from axis 1 vanishes."""
    from scipy.optimize import brentq

    def gap(q: np.ndarray) -> float:
        frames = robot.frames(q)
        w = frames[5][:3, 3]  # (joint 6's frame origin: W, standard DH)
        z0, p0 = frames[0][:3, 2], frames[0][:3, 3]
        d = w - p0
        return float(np.dot(d - np.dot(d, z0) * z0, np.cross(z0, frames[1][:3, 2])))

    while True:
        q = rng.uniform(-np.pi, np.pi, 6)
        xs = np.linspace(-np.pi, np.pi, 361)
        g = []
        for x in xs:
            q[2] = x
            g.append(gap(q))
        k = np.flatnonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)
        if k.size:
            i = int(rng.choice(k))

            def f(x: float, q: np.ndarray = q) -> float:
                q[2] = x
                return gap(q)

            q[2] = brentq(f, xs[i], xs[i + 1], xtol=1e-15)
            return q


def test_joint_6_point_on_axis_1_gives_the_joint_1_continuum() -> None:
    robot = _ur5_without_shoulder_offset()
    rng = np.random.default_rng(35)
    for _ in range(6):
        q = _on_axis_1(robot, rng)
        T = robot.fk(q)
        s = sweepik.solve(robot, T, limits=False)
        assert s.families and recovered(robot, s, q), q.tolist()
        families_certified(robot, s, T)
        # the continuum turns joint 1 whole turns: its members reach every value of it (no gap over 0.1 rad)
        a = np.sort(np.mod(np.concatenate([f.sample(1000)[:, 0] for f in s.families]), 2.0 * np.pi))
        assert np.max(np.diff(np.concatenate([a, [a[0] + 2.0 * np.pi]]))) < 0.1, q.tolist()


def test_singular_configurations_of_the_meeting_shoulder_arm_come_back() -> None:
    robot = _ur5_without_shoulder_offset()
    for q in singular_configurations(robot, 20, np.random.default_rng(7)):
        s = sweepik.solve(robot, robot.fk(q), limits=False)
        assert recovered(robot, s, q), q.tolist()
