"""Cold compilation: the first batch of each arm in a new process with an empty Numba cache; run from the repository
root (the sweepik on the path is timed).

    python benchmarks/cold_compile.py                              # carm,carm_swapped  carm_swapped  ur5  kinova_jaco2
    python benchmarks/cold_compile.py carm,carm_swapped ur5 --repeats 3 --json

Each argument is one process: its arms (comma-separated) are solved in that order, so an arm after the first shows
what it compiles beyond what the ones before it compiled. The batch is 200 random in-limit poses (seed 0); the
times are wall seconds of ``solve_many`` (import excluded), then of a first single ``solve``. Benchmarks are not
tests: on a busy machine, repeat and take medians.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile

CHILD = """
import json, sys, time
import numpy as np
import sweepik
out = []
for name in sys.argv[1].split(","):
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(0)
    q = robot.lower + (robot.upper - robot.lower) * rng.random((200, robot.n_joints))
    poses = robot.fk(q)
    t = time.perf_counter()
    sweepik.solve_many(robot, poses)
    batch = time.perf_counter() - t
    t = time.perf_counter()
    sweepik.solve(robot, poses[0])
    out.append({"arm": name, "first_batch_s": batch, "then_single_s": time.perf_counter() - t})
print(json.dumps(out))
"""

DEFAULT = ["carm,carm_swapped", "carm_swapped", "ur5", "kinova_jaco2"]


def run_once(arms: str) -> list[dict[str, float | str]]:
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        done = subprocess.run(
            [sys.executable, "-c", CHILD, arms], capture_output=True, text=True, env=env, check=True, timeout=3600
        )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("processes", nargs="*", default=DEFAULT, help="arms of one process, comma-separated")
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    rows = []
    for arms in args.processes:
        runs = [run_once(arms) for _ in range(args.repeats)]
        for k, name in enumerate(arms.split(",")):
            batch = [r[k]["first_batch_s"] for r in runs]
            single = [r[k]["then_single_s"] for r in runs]
            rows.append({"process": arms, "arm": name, "first_batch_s": batch, "then_single_s": single})
    if args.json:
        print(json.dumps(rows, indent=2))
        return
    print(f"{'process':<24} {'arm':<16} {'first batch (median) s':>24} {'then single s':>14}  runs")
    for r in rows:
        b, s = r["first_batch_s"], r["then_single_s"]
        runs_txt = ", ".join(f"{x:.1f}" for x in b)
        median_b, median_s = statistics.median(b), statistics.median(s)
        print(f"{r['process']:<24} {r['arm']:<16} {median_b:>24.1f} {median_s:>14.2f}  {runs_txt}")


if __name__ == "__main__":
    main()
