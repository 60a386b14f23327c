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


# ------------------------------------------------------------------ choosing a solution: metrics, windings, filter


@pytest.mark.parametrize("metric", ["linf", "weighted"])
def test_nearest_with_a_tolerance_against_brute_force(metric: str) -> None:
    """``nearest(q_ref, metric, tol)`` on a UR (+-360 degrees, windings listed): the row a brute-force minimum over
    every winding picks (raw joint values: a winding a turn away is far), or None when that minimum exceeds tol."""
    robot = sweepik.load_robot("ur10")
    rng = np.random.default_rng(3)
    for _ in range(12):
        q = robot.lower + rng.random(6) * (robot.upper - robot.lower)
        sols = sweepik.solve(robot, robot.fk(q), windings=True)
        ref = q + rng.normal(0.0, 0.15, 6)
        d = np.abs(sols.q - ref)
        dist = d.max(axis=1) if metric == "linf" else np.linalg.norm(d, axis=1)
        best = int(np.argmin(dist))
        np.testing.assert_array_equal(sols.nearest(ref, metric=metric), sols.q[best])
        np.testing.assert_allclose(sols.distances(ref, metric=metric), dist, rtol=0, atol=1e-12)
        tol = float(dist[best])
        assert sols.nearest(ref, metric=metric, tol=tol * 1.001) is not None
        assert sols.nearest(ref, metric=metric, tol=tol * 0.999) is None


def test_linf_picks_the_small_step_where_the_sum_picks_a_flip() -> None:
    """The planner's case (ssik #330): from a reference, one solution moves every joint a little, another moves
    one joint a lot and the others not at all; L-infinity takes the first, the Euclidean norm may take the second.
    Checked as a property of the two metrics on every pair of a pose's solutions."""
    robot = sweepik.load_robot("ur5")
    q = np.array([0.3, -1.1, 1.4, -0.6, 1.2, 0.4])
    sols = sweepik.solve(robot, robot.fk(q))
    ref = q + 0.05
    linf = sols.distances(ref, metric="linf")
    assert np.isclose(linf.min(), 0.05)
    np.testing.assert_allclose(sols.nearest(ref, metric="linf"), q, atol=1e-9)
    assert np.all(sols.distances(ref) >= linf - 1e-15)  # the norm bounds the largest move


def test_filter_keeps_what_the_function_accepts() -> None:
    robot = sweepik.load_robot("ur5")
    q = np.array([0.3, -1.1, 1.4, -0.6, 1.2, 0.4])
    sols = sweepik.solve(robot, robot.fk(q), windings=True)
    kept = sols.filter(lambda c: c[1] < 0)  # e.g. the elbow above the table
    assert len(kept) == int(np.sum(sols.q[:, 1] < 0)) and np.all(kept.q[:, 1] < 0)
    assert np.max(joint_distance(robot, kept.q, kept.q[kept.winding_of])) <= 1e-12  # bases renumbered
    none = sols.filter(lambda c: False)
    assert len(none) == 0 and not none and "filter" in (none.reason or "")
    assert none.nearest(q) is None
    with pytest.raises(sweepik.SweepikError, match="function"):
        sols.filter("collision")  # type: ignore[arg-type]


def test_choice_options_are_checked() -> None:
    robot = sweepik.load_robot("ur5")
    sols = sweepik.solve(robot, robot.fk(np.full(6, 0.3)))
    for bad in ({"metric": "l1"}, {"metric": None}, {"tol": -1.0}, {"tol": float("nan")}, {"tol": "1"}):
        with pytest.raises(sweepik.SweepikError):
            sols.nearest(np.zeros(6), **bad)
    with pytest.raises(sweepik.SweepikError, match="windings"):
        sweepik.solve(robot, robot.fk(np.zeros(6)), windings="yes")  # type: ignore[arg-type]


def test_follow_path_with_a_linf_tolerance_never_steps_farther() -> None:
    """``follow_path(metric="linf", tol=...)``: every point taken lies within ``tol`` (largest joint move) of the
    point taken before it, the others are NaN rows; a tolerance no step reaches changes nothing. A path through the
    wrist singularity of a UR and back, coarse enough that some steps are large."""
    from sweepik.trajectory import follow_path

    robot = sweepik.load_robot("ur5")
    q = np.array([0.3, -1.1, 1.4, -0.6, 0.4, 0.4])
    s = np.concatenate([np.linspace(0.0, 1.0, 9), np.linspace(1.0, 0.0, 9)[1:]])
    path = q + s[:, None] * np.array([0.9, 0.4, -0.5, 0.7, -0.8, 1.9])
    free = follow_path(robot, robot.fk(path), q_start=q, metric="linf")
    assert free.found.all()
    same = follow_path(robot, robot.fk(path), q_start=q, metric="linf", tol=10.0)
    np.testing.assert_array_equal(same.q, free.q)
    tol = 0.3
    tight = follow_path(robot, robot.fk(path), q_start=q, metric="linf", tol=tol)
    assert tight.found[0] and not tight.found.all()
    taken = tight.q[tight.found]
    assert np.max(joint_distance(robot, taken[1:], taken[:-1])) <= tol + 1e-12
