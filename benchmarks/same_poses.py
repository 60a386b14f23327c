"""Time one reduction on a fixed set of random in-limit poses, in a form that runs on any version of sweepik, so
that two versions can be compared one after the other in one session (the machine's speed drifts by +-20 %
between runs: alternate them and keep the best of each).

    python benchmarks/same_poses.py REDUCTION [ROBOT]

Batched: ``solve_many`` of 2,000 poses, best of 5 (wall time, and process CPU time, both cores); single: median
of 300 ``solve`` calls. To compare with an older commit::

    git worktree add /tmp/old <commit>
    NUMBA_CACHE_DIR=/tmp/nc-old PYTHONPATH=/tmp/old/src python benchmarks/same_poses.py carm-d1
    python benchmarks/same_poses.py auto
"""

import sys
import time

import numpy as np

import sweepik


def main() -> None:
    reduction = sys.argv[1] if len(sys.argv) > 1 else "auto"
    robot = sweepik.load_robot(sys.argv[2] if len(sys.argv) > 2 else "carm")
    rng = np.random.default_rng(7)
    T = robot.fk(rng.uniform(robot.lower, robot.upper, size=(2000, robot.n_joints)))
    sweepik.solve_many(robot, T[:100], reduction=reduction)  # compile or load the kernels
    sweepik.solve(robot, T[0], reduction=reduction)
    wall = cpu = np.inf
    for _ in range(5):
        c, w = time.process_time(), time.perf_counter()
        sweepik.solve_many(robot, T, reduction=reduction)
        cpu, wall = min(cpu, time.process_time() - c), min(wall, time.perf_counter() - w)
    single = []
    for i in range(300):
        t = time.perf_counter()
        sweepik.solve(robot, T[i], reduction=reduction)
        single.append(time.perf_counter() - t)
    print(
        f"{robot.name} {reduction}: batched {wall / 2000 * 1e6:.1f} us/pose wall, {cpu / 2000 * 1e6:.1f} CPU "
        f"(best of 5); single median {np.median(single) * 1e6:.0f} us"
    )


if __name__ == "__main__":
    main()
