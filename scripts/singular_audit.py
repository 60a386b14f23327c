"""Configurations on and next to the singular sets of the bundled arms (issue 35): recall, certified family members,
time per solve.

    python scripts/singular_audit.py [--n 100] [--arms ur5 ...] [--seed 0] [--limits]

Each arm: ``--n`` configurations from ``tests/singular.py`` (det J = 0 along a random joint, and 1e-9 ... 1e-3 off it);
each pose solved (warm: the time of a second solve); reports how many configurations were recovered
(``singular.recovered``), members of reported families (5 along each) whose pose error exceeds 1e-9 of the length
scale, and solves over 50 ms.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from singular import recovered, singular_configurations  # noqa: E402

import sweepik  # noqa: E402
from sweepik.model.pose import pose_error_geodesic  # noqa: E402
from sweepik.model.units import orientation_weight  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=100)
    ap.add_argument("--arms", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--limits", action="store_true", help="solve with the joint limits on")
    args = ap.parse_args()
    names = args.arms or [n for n in sweepik.bundled_robots() if sweepik.load_robot(n).n_joints == 6]
    total = total_rec = 0
    for name in names:
        robot = sweepik.load_robot(name)
        rng = np.random.default_rng(args.seed)
        Q = singular_configurations(robot, args.n, rng)
        w = orientation_weight(robot.length_unit)
        rec = bad_members = slow = 0
        worst = 0.0
        misses = []
        for i, q in enumerate(Q):
            T = robot.fk(q)
            sweepik.solve(robot, T, limits=args.limits)
            t0 = time.perf_counter()
            s = sweepik.solve(robot, T, limits=args.limits)
            dt = time.perf_counter() - t0
            worst = max(worst, dt)
            slow += dt > 0.05
            inside = not args.limits or bool(robot.within_limits(q))
            if inside:
                ok = recovered(robot, s, q)
                rec += ok
                if not ok:
                    misses.append(i)
            for f in s.families:
                m = f.at(np.linspace(f.interval[0], f.interval[1], 5))
                err = pose_error_geodesic(robot.fk(m), np.broadcast_to(T, (len(m), 4, 4)), w)
                bad_members += int((err > 1e-9 * robot.length_scale).sum())
        n_in = len(Q) if not args.limits else int(sum(bool(robot.within_limits(q)) for q in Q))
        total += n_in
        total_rec += rec
        print(
            f"{name:18s} recall {rec:3d}/{n_in}  bad family members {bad_members}  over 50 ms {slow}  "
            f"slowest {worst * 1e3:6.1f} ms  misses {misses[:8]}",
            flush=True,
        )
    print(f"total recall {total_rec}/{total}")


if __name__ == "__main__":
    main()
