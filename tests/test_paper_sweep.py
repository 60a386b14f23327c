"""The paper's strategy (sweepik.engine.paper_sweep): on the C-Arm's 10 mm grid it finds the generating
configuration of a pose whose d1 lies on the grid, with J below the paper's threshold, and every solution it
returns meets that threshold."""

from __future__ import annotations

import numpy as np

from sweepik import load_robot, solve
from sweepik.engine.settings import PAPER_ACCEPT_MM


def test_grid_poses_are_found_below_the_papers_threshold() -> None:
    robot = load_robot("carm")
    rng = np.random.default_rng(8)
    for _ in range(6):
        q = rng.uniform(robot.lower, robot.upper)
        q[0] = 10.0 * round(q[0] / 10.0)  # d1 on the paper's 10 mm grid
        q[1] = np.clip(q[1], -1.3, 1.3)  # (off the theta2 = +-90 deg blind spot)
        sol = solve(robot, robot.fk(q), strategy="paper")
        assert len(sol) and np.all(sol.error < PAPER_ACCEPT_MM)
        d = np.abs(sol.q - q)
        d[:, 1:] = np.minimum(d[:, 1:] % (2 * np.pi), -d[:, 1:] % (2 * np.pi))
        assert np.min(np.max(d, axis=1)) < 1e-3
