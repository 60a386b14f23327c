"""Compile sweepik's kernels once, in one process, before the test suite runs on two workers (``pytest -n 2``):
on a fresh install the Numba cache is empty, and two workers would each compile the same kernels. Not a test:
it solves a batch of every bundled arm (limits on and off, one pose alone, the paper's strategy on the C-Arm), a
7-joint arm with a joint held, and arms of the general method (6R, one slide), so that most kernels are in the cache
when the suite starts; whatever it misses, the suite compiles as it always did."""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

import sweepik  # noqa: E402


def batch(robot: sweepik.Robot, n: int = 64, **kw: object) -> None:
    rng = np.random.default_rng(0)
    q = robot.lower + (robot.upper - robot.lower) * rng.random((n, robot.n_joints))
    T = robot.fk(q)
    sweepik.solve_many(robot, T, **kw)
    sweepik.solve(robot, T[0], **kw)


def main() -> None:
    t0 = time.perf_counter()
    for name in sweepik.bundled_robots():
        robot = sweepik.load_robot(name)
        if robot.n_joints == 6:
            batch(robot)
            batch(robot, limits=False)
    carm = sweepik.load_robot("carm")
    batch(carm, 8, strategy="paper")
    panda = sweepik.load_robot("franka_panda")
    batch(sweepik.load_robot("kuka_iiwa14"), locked={"A3": 0.3})
    batch(panda, locked={"joint7": 0.3})
    batch(panda, locked={"joint1": 0.3})  # (a held sweep, its value an argument: engine.held_pose)
    from general_arms import random_arm

    for kind, k in (("6r", 0), ("5r1p", 0), ("4r2p", 1)):
        batch(random_arm(kind, k), 16, limits=False)
    print(f"kernels compiled in {time.perf_counter() - t0:.0f} s", flush=True)


if __name__ == "__main__":
    main()
