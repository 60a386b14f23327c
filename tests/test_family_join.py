"""Families joined with isolated solutions (sweepik.engine.family_join): at poses on a self-motion, no isolated
solution reported lies on a reported family, and every family's members solve the pose."""

from __future__ import annotations

import sys
from pathlib import Path

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


def _repeats(robot, families) -> list[tuple[int, int]]:  # type: ignore[no-untyped-def]
    """Pairs ``(i, j)``: every member of family ``i`` (101 along it) is a member of family ``j``."""
    out = []
    for i, f in enumerate(families):
        members = f.sample(101)
        others = [(j, g) for j, g in enumerate(families) if j != i]
        for (j, _), off in zip(others, off_families(robot, [(members, (g,)) for _, g in others]), strict=True):
            if not off.any():
                out.append((i, j))
    return out


def test_a_continuum_is_reported_once() -> None:
    """Poses of ``benchmarks/same_solutions.py`` (the random arms of ``test_any_arm``) with several continua, some
    found twice before: along two joints (an RRP arm with a spherical wrist, its slide at zero: the q4/q6 continuum
    traced along joint 4 and along joint 6), or whole and in pieces. No family lies wholly on another
    (``family_join._not_repeated``), and the configuration each pose comes from is still found."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    from same_solutions import arms, configurations
    from singular import recovered

    by_name = dict(arms())
    poses = (("wrist_rrp[0]", 158), ("wrist_rrp[1]", 153), ("slide_parallel[0]", 129), ("three_parallel[1]", 204))
    for name, i in poses:
        robot = by_name[name]
        q = configurations(robot, 250)[i]
        sol = solve(robot, robot.fk(q), limits=False)
        assert len(sol.families) > 1, (name, i)
        assert _repeats(robot, sol.families) == [], (name, i)
        assert recovered(robot, sol, q), (name, i)
