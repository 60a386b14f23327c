"""Recall of random arms of the decomposition's families (``tests/test_any_arm.py::FAMILIES``) on random and singular
configurations, limits off.

    python scripts/family_recall.py wrist_general,shoulder_general [--arms 10] [--n 100]

For each family, ``--arms`` random arms (seeds 7000 + k), ``--n`` configurations within limits and ``--n / 2`` on or
next to the singular set (``tests/singular.py``), solved in one batch: each generating configuration must come back
(``singular.recovered``). Prints the misses, then per family the recall, the median time per pose and the case of the
plan chosen.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from oracles import in_limit_configurations  # noqa: E402
from singular import recovered, singular_configurations  # noqa: E402
from test_any_arm import FAMILIES, _arm  # noqa: E402

import sweepik  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("families")
    ap.add_argument("--arms", type=int, default=10)
    ap.add_argument("--n", type=int, default=100)
    args = ap.parse_args()
    for fam in args.families.split(","):
        miss = tot = 0
        times = []
        case = None
        for a in range(args.arms):
            rng = np.random.default_rng(7000 + a)
            robot = _arm(FAMILIES[fam](rng), rng)
            case = sweepik.analyze(robot)["chosen"]["case"]
            Q = np.concatenate(
                [in_limit_configurations(robot, args.n, rng), singular_configurations(robot, args.n // 2, rng)]
            )
            T = robot.fk(Q)
            sweepik.solve(robot, T[0], limits=False)
            t = time.perf_counter()
            sols = sweepik.solve_many(robot, T, limits=False)
            times.append((time.perf_counter() - t) / len(Q))
            for q, s in zip(Q, sols, strict=True):
                tot += 1
                if not recovered(robot, s, q):
                    miss += 1
                    print(f"{fam} arm {a}: missed {np.round(q, 6).tolist()} ({len(s)} solutions)")
        print(f"{fam}: recall {tot - miss}/{tot}, median {1e6 * np.median(times):.0f} us a pose, case {case}")


if __name__ == "__main__":
    main()
