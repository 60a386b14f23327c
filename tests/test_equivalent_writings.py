"""Every equivalent way of writing an arm gives the same solutions (issue 35).

An arm written with axes reversed (q -> -q), joints' zeros moved, other base and tool frames, another length unit
(``rewrites.rewrite``) or through a URDF round trip is the same arm: its solutions, mapped back, must be the
original's, one for one, and each must contain the configuration the pose came from. (A UR5 written with joint 3's
axis reversed once lost every solution: the parallel family took the parallel axes to point the same way.)
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest
from oracles import recovers, same_solution_set
from rewrites import rewrite

from sweepik import load_robot, solve
from sweepik.io.robot_file import bundled_robots
from sweepik.io.urdf import read_urdf, urdf_text
from sweepik.model.units import mm_per_unit

ARMS = [name for name in bundled_robots() if load_robot(name).n_joints == 6]


def _configurations(robot, n: int, rng: np.random.Generator) -> np.ndarray:
    lo = np.where(np.isfinite(robot.lower), robot.lower, -robot.length_scale)
    hi = np.where(np.isfinite(robot.upper), robot.upper, robot.length_scale)
    return np.where(robot.is_revolute, rng.uniform(-np.pi, np.pi, (n, 6)), rng.uniform(lo, hi, (n, 6)))


def _same(robot, a, b_back) -> bool:
    return same_solution_set(a, b_back, robot.is_revolute, robot.length_scale)


@pytest.mark.parametrize("name", ARMS)
def test_a_rewritten_arm_has_the_same_solutions(name: str) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    for _ in range(3):
        rw = rewrite(robot, rng)
        for q in _configurations(robot, 3, rng):
            q2 = rw.forward(q)
            T2 = rw.robot.fk(q2)
            np.testing.assert_allclose(T2, rw.pose(robot.fk(q)), atol=1e-9 * rw.robot.length_scale)
            a = solve(robot, robot.fk(q), limits=False)
            b = solve(rw.robot, T2, limits=False)
            assert recovers(robot, a, q)
            assert recovers(rw.robot, b, q2), f"{name} rewritten (signs {rw.sign}, unit x{rw.scale}) lost q"
            assert len(a) == len(b) and len(a.families) == len(b.families)
            assert _same(robot, a.q, rw.back(b.q))


@pytest.mark.parametrize("name", ["ur5", "puma560", "kinova_jaco2", "stanford"])
def test_each_axis_reversed_alone(name: str) -> None:
    """Every single axis reversal (the way URDFs write ``axis="0 0 -1"``), one pose each."""
    robot = load_robot(name)
    rng = np.random.default_rng(3)
    q = _configurations(robot, 1, rng)[0]
    a = solve(robot, robot.fk(q), limits=False)
    for k in range(6):
        rw = rewrite_only(robot, k)
        b = solve(rw.robot, rw.robot.fk(rw.forward(q)), limits=False)
        assert len(b) == len(a) and _same(robot, a.q, rw.back(b.q)), f"{name}: joint {k + 1} reversed"


def rewrite_only(robot, k: int):
    """``robot`` with joint ``k``'s axis reversed and nothing else changed."""
    rng = np.random.default_rng(0)
    while True:  # (rewrite draws the reversals at random: take a draw that reverses exactly joint k)
        rw = rewrite(robot, rng, offsets=False, frames=False, units=False)
        if np.flatnonzero(rw.sign < 0).tolist() == [k]:
            return rw


@pytest.mark.parametrize("name", ARMS)
def test_a_urdf_round_trip_has_the_same_solutions(name: str, tmp_path) -> None:
    robot = load_robot(name)
    path = tmp_path / f"{name}.urdf"
    path.write_text(urdf_text(robot))
    back = read_urdf(path)
    scale = mm_per_unit(robot.length_unit) / mm_per_unit(back.length_unit)
    rng = np.random.default_rng(zlib.crc32(name.encode()) + 1)
    for q in _configurations(robot, 3, rng):
        q_back = np.where(robot.is_revolute, q, q * scale)
        a = solve(robot, robot.fk(q), limits=False)
        b = solve(back, back.fk(q_back), limits=False)
        assert recovers(back, b, q_back)
        b_q = np.where(robot.is_revolute, b.q, b.q / scale)
        assert len(a) == len(b) and _same(robot, a.q, b_q)
