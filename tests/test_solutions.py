"""``Solutions`` (sweepik.solutions): the nearest solution to a reference, on isolated solutions and on self-motion
families, including a family whose theta* turns through a whole circle (its two ends are the same member)."""

from __future__ import annotations

import numpy as np
import pytest

import sweepik
from sweepik.solutions import joint_distance


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
