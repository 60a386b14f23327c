"""Time the C-Arm grid in parts, in a form that runs on any version of sweepik (alternate two versions in one
session, as with ``same_poses.py``: the machine's speed drifts between runs).

    python benchmarks/grid_parts.py [ROBOT ...]

Prints the grid's ``solve_many`` (15,900 poses, best of 3), its poses with self-motion families alone (best of 5),
and the compiled candidate search on one thread (2,000 random in-limit poses of each ROBOT, default carm and
fanuc_crx10ia, hints included, best of 5). To compare with an older commit::

    git worktree add /tmp/old <commit>
    NUMBA_CACHE_DIR=/tmp/nc-old PYTHONPATH=/tmp/old/src python benchmarks/grid_parts.py
    python benchmarks/grid_parts.py
"""

import sys
import time
from collections.abc import Callable

import numba
import numpy as np

import sweepik
from sweepik.engine import chunk, search
from sweepik.experiments.bench import grid_configurations


def best(fn: Callable[[], object], repeats: int) -> float:
    out = np.inf
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        out = min(out, time.perf_counter() - t)
    return float(out)


def main() -> None:
    carm = sweepik.load_robot("carm")
    P = carm.fk(grid_configurations(include_singular=False))
    batch = sweepik.solve_many(carm, P)
    fam = np.array([i for i in range(len(P)) if batch.families.get(i)], dtype=np.intp)
    grid = best(lambda: sweepik.solve_many(carm, P), 3)
    family = best(lambda: sweepik.solve_many(carm, P[fam]), 5)
    print(f"{sweepik.__file__}: grid {len(P)} poses {grid:.3f} s; its {fam.size} family poses {family:.3f} s")
    numba.set_num_threads(1)
    for name in sys.argv[1:] or ["carm", "fanuc_crx10ia"]:
        robot = sweepik.load_robot(name)
        red = sweepik.reductions.get_reduction(robot, None)
        rng = np.random.default_rng(0)
        chain = chunk.chain_poses(robot, robot.fk(rng.uniform(robot.lower, robot.upper, size=(2000, 6))))
        lo, hi = chunk.theta_range(robot, red, chain)
        search.search(red, chain[:10], lo[:10], hi[:10], 64)  # compile or load the kernels
        t = best(lambda: search.search(red, chain, lo, hi, 64), 5)  # noqa: B023 (called right here)
        print(f"  {name}: compiled search {t / len(chain) * 1e6:.1f} us/pose (one thread, {red.name})")


if __name__ == "__main__":
    main()
