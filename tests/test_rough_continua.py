"""Continua that the swept closed form reproduces only roughly (issue 35, point 4: a UR5 with its wrist straight, 3-20 s
a pose): the sweep along joint 4 sits at a branch-domain edge along the whole continuum, its residual carries the
square root of rounding and crosses zero hundreds of times. ``sweepik.engine.rough_continua`` recognises such stretches
from
the samples, traces the continuum and masks them from the search; a pose a hair off the continuum must keep its
isolated solutions (nothing masked)."""

from __future__ import annotations

import numpy as np
import pytest
from singular import families_certified, recovered

import sweepik
from sweepik.engine.chunk import chain_poses as _chain_poses
from sweepik.engine.chunk import theta_range as _theta_range
from sweepik.engine.rough_continua import rough_continua
from sweepik.engine.settings import ACCEPT_TOL_REL, POLISH_BELOW_REL
from sweepik.reductions import get_reduction

#: The issue's two UR5 configurations (the second in the limits, solved with them on)
ISSUE = [
    [0.86056, 5.46006, -2.88415, -3.03775, np.pi, 2.59342],
    [2.2042858345559706, -0.9782962654771837, -0.9648341437830452, -2.7538323619714946, np.pi, -2.660267771237715],
]


@pytest.mark.parametrize("which", [0, 1])
def test_the_wrist_straight_continuum_of_the_issue_comes_back_whole(which: int) -> None:
    """Joints 1 and 6 do not change the planar loop of joints 2, 3, 4 and 6: every choice of them keeps the pose on
    the rough continuum."""
    robot = sweepik.load_robot("ur5")
    rng = np.random.default_rng(35 + which)
    for _ in range(3):
        q = np.array(ISSUE[which])
        q[[0, 5]] = rng.uniform(-np.pi, np.pi, 2)
        T = robot.fk(q)
        s = sweepik.solve(robot, T, limits=bool(which))
        assert s.families and recovered(robot, s, q), q.tolist()
        assert len(s) <= 8, "the continuum came back in pieces"
        families_certified(robot, s, T)


@pytest.mark.parametrize("off", [0.0, 1e-11, 1e-7, 1e-5])
def test_only_a_continuum_is_masked(off: float) -> None:
    """On the continuum (and within rounding of it) its stretches are traced and masked; 1e-7 and more off it, where
    the pose's solutions are isolated, nothing is masked, and the solve still finds the configuration."""
    robot = sweepik.load_robot("ur5")
    red = get_reduction(robot, get_reduction(robot, None).fallback)
    q = np.array(ISSUE[0])
    q[4] -= off
    T = robot.fk(q)[None]
    chain = _chain_poses(robot, T)
    lo, hi = _theta_range(robot, red, chain)
    scale = robot.length_scale
    fams, _, _, masked = rough_continua(
        robot, red, chain, T, lo, hi, 64, False, POLISH_BELOW_REL * scale, ACCEPT_TOL_REL * scale
    )
    if off < 1e-9:
        assert fams.get(0) and len(masked)
        for a, c in zip(masked.lo, masked.hi, strict=True):  # a masked stretch lies in a traced family's interval
            assert any(f.interval[0] - 1e-9 <= a and c <= f.interval[1] + 1e-9 for f in fams[0]), (a, c)
    else:
        assert not fams and not len(masked)
    s = sweepik.solve(robot, T[0], limits=False)
    assert recovered(robot, s, q)


def test_a_stretch_too_short_to_trace_is_searched_with_buffers_as_large_as_it_needs() -> None:
    """A random slide_parallel arm (tests/test_any_arm.py) at a pose on a continuum whose fallback sweep sees it only
    roughly: the traced continuum is masked, but one piece of it (0.05 rad of theta*, fewer samples than a run
    needs) is not, and its noisy residual makes ~10,000 flat stretches. The compiled search, redone with buffers
    sized to what the pose reached (not a fixed cap), reports the continuum and no isolated solution, with and without
    limits, as the NumPy reference engine did (benchmarks/same_solutions.py: it stopped with an error at a fixed
    cap)."""
    from test_any_arm import FAMILIES, _arm

    rng = np.random.default_rng(300)
    robot = _arm(FAMILIES["slide_parallel"](rng), rng, "standard")
    q = np.array([0.0, 2.576595021666786, -1.5707963267948966, 3.087291094769447, np.pi, 1.0189484723137578])
    T = robot.fk(q)
    for limits in (True, False):
        s = sweepik.solve(robot, T, limits=limits)
        assert len(s) == 0 and s.families
        assert recovered(robot, s, q)
        for f in s.families:  # (each family's members solve the pose)
            m = f.at(np.linspace(f.interval[0], f.interval[1], 9))
            assert np.abs(robot.fk(m) - T).max() <= 1e-9 * robot.length_scale
