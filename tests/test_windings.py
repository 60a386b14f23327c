"""2 pi windings (:mod:`sweepik.engine.windings`): every value of the revolute joints, modulo 2 pi, within limits."""

from __future__ import annotations

import numpy as np
import pytest

import sweepik
from sweepik.engine.windings import MAX_WINDINGS, winding_rows
from sweepik.results import joint_distance


def _brute_windings(robot: sweepik.Robot, q: np.ndarray) -> np.ndarray:
    """Every configuration equal to ``q`` modulo 2 pi on the revolute joints and inside the limits: per joint, the
    values ``q_j + 2 pi t`` (t from -2 to 2, the arms tested turn at most +-360 degrees) inside its limits, then
    every combination of them."""
    import itertools

    per_joint = [
        [v for t in (range(-2, 3) if rev else (0,)) if lo - 1e-9 <= (v := qj + 2 * np.pi * t) <= hi + 1e-9]
        for qj, rev, lo, hi in zip(q, robot.is_revolute, robot.lower, robot.upper, strict=True)
    ]
    return np.array(list(itertools.product(*per_joint)))


@pytest.mark.parametrize("name", ["ur5", "doosan_m0609", "kinova_jaco2", "xarm6"])
def test_windings_are_every_turn_inside_the_limits(name: str) -> None:
    """``windings=True``: the rows are exactly the base solutions' windings found by brute force (every
    combination of whole turns inside the limits), each row's ``winding_of`` a base row equal to it modulo 2 pi,
    every row passing FK; solve_many gives the same rows."""
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(7)
    q = robot.lower + rng.random((4, 6)) * (robot.upper - robot.lower)
    T = robot.fk(q)
    batch = sweepik.solve_many(robot, T, windings=True)
    for k in range(len(q)):
        base = sweepik.solve(robot, T[k])
        wound = sweepik.solve(robot, T[k], windings=True)
        np.testing.assert_array_equal(wound.q[: len(base)], base.q)
        np.testing.assert_array_equal(batch[k].q, wound.q)
        np.testing.assert_array_equal(batch[k].winding_of, wound.winding_of)
        expect = np.concatenate([_brute_windings(robot, b) for b in base.q])
        gap = np.max(np.abs(wound.q[:, None, :] - expect[None, :, :]), axis=-1)
        assert len(wound) == len(expect) and np.all(gap.min(axis=0) <= 1e-9) and np.all(gap.min(axis=1) <= 1e-9)
        assert np.max(joint_distance(robot, wound.q, base.q[wound.winding_of])) <= 1e-12
        assert np.all(robot.within_limits(wound.q))
        assert np.max(np.abs(robot.fk(wound.q) - T[k])) <= 1e-9
        assert np.any(np.all(np.abs(wound.q - q[k]) <= 1e-8, axis=1))  # the generating q itself, not modulo 2 pi


def test_winding_rows_turn_only_the_joints_asked_and_never_a_value_outside_its_limits() -> None:
    """``winding_rows``: whole turns on the revolute joints of ``joints`` only; a value already outside its limits is
    not turned; no row repeats its base; a slide never turns."""
    robot = sweepik.load_robot("ur5")  # (every joint +-2 pi: three values of each inside the limits, or two)
    q = np.array([[0.3, -0.2, 0.1, 1.0, -1.2, 2.0], [0.3, -0.2, 0.1, 1.0, -1.2, 7.0]])  # (the second: q6 outside)
    mask = np.array([True, False, False, False, False, True])
    base, rows = winding_rows(robot, q, mask)
    assert set(base.tolist()) == {0, 1}
    for b, r in zip(base, rows, strict=True):
        turns = (r - q[b]) / (2 * np.pi)
        assert np.allclose(turns, np.round(turns), atol=1e-12) and np.any(np.round(turns) != 0)
        assert np.all(np.round(turns)[~mask] == 0)  # (only the joints asked)
        if b == 1:
            assert r[5] == q[b][5]  # (q6 = 7 is outside +-2 pi: never turned)
        inside = (r >= robot.lower - robot.limit_tol) & (r <= robot.upper + robot.limit_tol)
        assert np.all(inside[mask] | (r == q[b])[mask])
    # joint 1 at 0.3 has the windings 0.3 - 2 pi (and 0.3 + 2 pi is past +2 pi): 1 more; q6 = 2.0: 2.0 - 2 pi
    assert np.sum(base == 0) == 2 * 2 - 1 and np.sum(base == 1) == 2 - 1


def test_winding_rows_stop_at_the_cap() -> None:
    """An arm whose every joint turns through many turns: at most ``MAX_WINDINGS`` rows per solution."""
    import dataclasses

    robot = sweepik.load_robot("ur5")
    wide = dataclasses.replace(
        robot, joints=tuple(dataclasses.replace(j, lower=-40.0, upper=40.0) for j in robot.joints)
    )
    base, rows = winding_rows(wide, np.zeros((1, 6)))
    assert base.size == MAX_WINDINGS and rows.shape == (MAX_WINDINGS, 6)
