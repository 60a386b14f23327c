"""Families joined with isolated solutions (sweepik.engine.family_join): at poses on a self-motion, no isolated
solution reported lies on a reported family, and every family's members solve the pose."""

from __future__ import annotations

import numpy as np

from sweepik import load_robot, solve
from sweepik.engine.families import off_families
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.units import orientation_weight


def test_isolated_solutions_on_a_family_are_reported_by_the_family() -> None:
    """The C-Arm with theta2 = +-90 deg and theta5 = 0 is on its theta2 self-motion; UR5 with its wrist straight is
    on a wrist continuum: each pose has families, and its isolated solutions all lie off them (``with_families``
    drops those on a family), while the families' members solve the pose."""
    cases = [
        ("carm", [1000.0, np.pi / 2, 0.3, -0.4, 0.0, 0.7]),
        ("carm", [400.0, -np.pi / 2, -1.1, 0.2, 0.0, -2.0]),
        ("ur5", [0.4, -1.0, 1.2, 0.3, 0.0, -0.8]),
    ]
    for name, q in cases:
        robot = load_robot(name)
        T = robot.fk(np.array(q))
        sol = solve(robot, T, limits=False)
        assert sol.families, (name, q)
        off = off_families(robot, [(sol.q, tuple(sol.families))])[0]
        assert off.all(), (name, q, sol.q[~off])
        w = orientation_weight(robot.length_unit)
        for fam in sol.families:
            m = fam.sample(21)
            assert np.all(pose_error_geodesic(robot.fk(m), T, w) <= 1e-9 * robot.length_scale)
