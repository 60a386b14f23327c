"""``Solutions`` (sweepik.results): the nearest solution to a reference, on isolated solutions and on self-motion
families, including a family whose theta* turns through a whole circle (its two ends are the same member)."""

from __future__ import annotations

import tomllib
from importlib import resources

import numpy as np
import pytest

import sweepik
from sweepik.results import joint_distance


@pytest.mark.parametrize("name", ["puma560", "kuka_kr6_r900", "stanford"])
@pytest.mark.parametrize("theta4", [np.pi - 1e-3, -np.pi + 1e-3, np.pi - 4.3e-3, 3.1412, 0.5, -2.0])
def test_nearest_on_a_wrist_family_is_the_generating_configuration(name: str, theta4: float) -> None:
    """Wrist singular (joint 5 at 0): joints 4 and 6 turn together, a family over the whole circle of joint 4.
    ``nearest(q)`` is q itself wherever joint 4 lies on that circle, next to the seam at +-pi too (it was the
    member at the seam, 1e-3 rad away, when the nearest sample was an end of the interval)."""
    robot = sweepik.load_robot(name)
    q = np.array(robot.lower + 0.37 * (robot.upper - robot.lower))
    q[3], q[4] = theta4, 0.0
    sols = sweepik.solve(robot, robot.fk(q), limits=False)
    assert sols.families, "the singular wrist should give a family"
    assert np.max(joint_distance(robot, sols.nearest(q), q)) <= 1e-9


@pytest.mark.parametrize(("name", "lock", "singular"), [("kuka_iiwa14", "A3", 5), ("puma_narrow_wrist", None, 4)])
def test_families_with_limits_stay_inside_the_limits(name: str, lock: str | None, singular: int) -> None:
    """With limits, every member of a reported family lies inside the joint limits, also where another joint than
    theta* turns through +-pi (outside limits narrower than the circle) between two of the samples the family is
    cut on (the iiwa's A7, +-175 deg, over a tenth of A5's range: 97 of 400 such poses reported out-of-limit members
    before). Families sampled at 2,001 members."""
    if name == "puma_narrow_wrist":  # joint 6 kept off +-pi, as the iiwa's A7
        data = tomllib.loads(resources.files("sweepik.io.robots").joinpath("puma560.toml").read_text())
        data["joints"][5]["limits"] = [-172.0, 172.0]
        robot = sweepik.robot_from_dict(data)
    else:
        robot = sweepik.load_robot(name)
    rng = np.random.default_rng(0)
    checked = 0
    for _ in range(60):
        q = rng.uniform(robot.lower, robot.upper)
        q[singular] = 0.0
        locked = {lock: float(q[robot.joint_names.index(lock)])} if lock else None
        sols = sweepik.solve(robot, robot.fk(q), locked=locked)
        for fam in sols.families:
            members = fam.sample(2001)
            assert robot.within_limits(members).all(), (q.tolist(), fam.interval)
            checked += 1
    assert checked >= 30


def test_family_member_at_a_removable_singular_point_is_a_solution() -> None:
    """A C-Arm family along the rail can pass d1 = Pz with the wrist on joint 2's axis, where carm-d1's closed form
    breaks down (u = 0: theta2 undefined): ``Family.at`` there still gives a solution (the member next to the point,
    whose limit the solution there is), as everywhere else in the interval."""
    robot = sweepik.load_robot("carm")
    checked = 0
    for d1, t2, t6 in [(500.0, 90.0, -60.0), (500.0, 90.0, 0.0), (1500.0, -90.0, 30.0), (200.0, 90.0, 60.0)]:
        q = np.array([d1, np.radians(t2), 0.0, 0.0, 0.0, np.radians(t6)])
        T = robot.fk(q)
        for fam in sweepik.solve(robot, T).families:
            lo, hi = fam.interval
            pz = float(fam.chain_pose[2, 3])
            if not lo < pz < hi or abs(fam.chain_pose[0, 3]) > 1e-9:
                continue
            members = fam.at(np.array([pz, lo, 0.5 * (lo + hi), hi]))
            np.testing.assert_allclose(robot.fk(members), np.broadcast_to(T, (4, 4, 4)), atol=1e-9)
            checked += 1
    assert checked >= 2


def test_family_member_at_an_angle_past_pi() -> None:
    """IRB 140's joint 4 reaches +-200 deg: a configuration's own joint-4 value past pi names a member of the wrist
    family (whose interval is in [-pi, pi]) by whole turns. (A value off the interval modulo 2 pi is refused:
    test_continuation's limited family.)"""
    robot = sweepik.load_robot("abb_irb140")
    q = np.array(robot.lower + 0.37 * (robot.upper - robot.lower))
    q[3], q[4] = 3.4, 0.0
    sols = sweepik.solve(robot, robot.fk(q))
    on = [f for f in sols.families if f.free_joint == 3 and np.max(joint_distance(robot, f.at(q[3]), q)) <= 1e-9]
    assert on, "the generating configuration should be a member, named by its own joint 4"
    np.testing.assert_allclose(joint_distance(robot, on[0].at(q[3] - 2.0 * np.pi), q), 0.0, atol=1e-9)
