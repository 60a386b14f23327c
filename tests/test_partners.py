"""Two close solutions across a fold (issue 35, point 3): next to a singular set a pose has two solutions a hair apart,
and the polish of a candidate between them converges to one. ``sweepik.engine.partners`` finds the other along the
Jacobian's nearly null direction; along a continuum it finds nothing (Newton from the midpoint stays there)."""

from __future__ import annotations

import zlib

import numpy as np
from singular import recovered, singular_configurations

import sweepik
from sweepik.engine.continuation import scaled_singular
from sweepik.engine.partners import close_partners, valley_bottoms
from sweepik.engine.polish import geodesic_errors, polished
from sweepik.engine.settings import ACCEPT_TOL_REL
from sweepik.model.units import orientation_weight
from sweepik.results import joint_distance

#: A CRX-10iA configuration 1e-5 off its singular set whose pose has a second solution 2e-5 rad away (1.5e-8 rad
#: apart in the sweep's joint 1, 6e-8 rad from the edge of its branch's domain); only that one came back.
CRX = [-1.5933782892473556, 0.4673310589856223, 1.5570722031919138, 3.0914731206139985, 2.6624706034453016,
       -2.1864988338850018]  # fmt: skip
CRX_PARTNER = [-1.5933783038, 0.4673210512, 1.5570524527, 3.0914740602, 2.6624608734, -2.1864977606]


def test_the_crx_pose_gives_both_close_solutions() -> None:
    robot = sweepik.load_robot("fanuc_crx10ia")
    q = np.array(CRX)
    s = sweepik.solve(robot, robot.fk(q), limits=False)
    assert recovered(robot, s, q)
    assert recovered(robot, s, np.array(CRX_PARTNER), tol=1e-8)


def test_the_partner_is_found_from_the_other_solution() -> None:
    robot = sweepik.load_robot("fanuc_crx10ia")
    q = np.array(CRX)
    T = robot.fk(q)
    tol = ACCEPT_TOL_REL * robot.length_scale
    a, err = polished(robot, np.array([CRX_PARTNER]), T[None], orientation_weight(robot.length_unit), iterations=30)
    assert err[0] <= tol
    row, found, _ = close_partners(robot, a, T[None], tol)
    assert row.size and np.all(np.max(joint_distance(robot, found, q[None]), axis=1) < 1e-9)


def test_no_partner_along_a_continuum() -> None:
    """Members of a UR5 wrist-straight continuum are singular too; Newton from next to them lands on the continuum,
    and the midpoint of two of its members stays on it: no partner."""
    robot = sweepik.load_robot("ur5")
    q = np.array([0.86056, 5.46006, -2.88415, -3.03775, np.pi, 2.59342])
    T = robot.fk(q)
    s = sweepik.solve(robot, T, limits=False)
    m = np.vstack([f.at(np.linspace(f.interval[0], f.interval[1], 5)[1:-1]) for f in s.families])
    row, _, _ = close_partners(robot, m, np.broadcast_to(T, (len(m), 4, 4)), ACCEPT_TOL_REL * robot.length_scale)
    assert row.size == 0


def test_configurations_next_to_the_crx_singular_sets_come_back() -> None:
    robot = sweepik.load_robot("fanuc_crx10ia")
    for q in singular_configurations(robot, 40, np.random.default_rng(zlib.crc32(b"partners"))):
        s = sweepik.solve(robot, robot.fk(q), limits=False)
        assert recovered(robot, s, q), q.tolist()


#: An I2RT YAM configuration on its singular set (axes 2-4 parallel to 3e-6 rad: a double root blurred into a flat
#: valley): the polish stopped 4.6e-4 rad from it, at 7e-2 of the certification's tolerance.
YAM = [-2.5969578377896116, -0.46585898160365735, -0.6487270256316182, -1.8713330559425263, -1.570714931440159,
       -2.5460932206476232]  # fmt: skip


def test_a_blurred_double_root_comes_back_at_the_bottom_of_its_valley() -> None:
    robot = sweepik.load_robot("i2rt_yam")
    q = np.array(YAM)
    s = sweepik.solve(robot, robot.fk(q), limits=False)
    assert recovered(robot, s, q)


def test_the_valley_bottom_is_lower_and_nearer_the_root() -> None:
    """From a point 3e-4 rad along the valley (polished with the joint the valley moves most held), the bottom found
    solves the pose better and lies nearer the configuration."""
    robot = sweepik.load_robot("i2rt_yam")
    q = np.array(YAM)
    T = robot.fk(q)
    weight = orientation_weight(robot.length_unit)
    tol = ACCEPT_TOL_REL * robot.length_scale
    _, vt = scaled_singular(robot, q[None])
    v = vt[0, -1]
    held = np.zeros((1, 6), dtype=bool)
    held[0, int(np.argmax(np.abs(v)))] = True
    x, e0 = polished(robot, (q + 3e-4 * v)[None], T[None], weight, iterations=30, fixed=held)
    assert tol * 1e-3 < e0[0] <= tol  # (a point of the valley: certified, above rounding)
    y, moved = valley_bottoms(robot, x, T[None], tol)
    assert moved[0]
    e1 = geodesic_errors(robot, y, T[None], weight)
    assert e1[0] < e0[0]
    assert np.max(joint_distance(robot, y, q[None])) < np.max(joint_distance(robot, x, q[None]))
