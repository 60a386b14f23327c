"""Two versions of sweepik timed in turn (A, B, A, B, ...), each in its own process: single-pose ``solve`` and batched
``solve_many`` per arm, the best of a few runs per process, then the best over the processes. For a change that
should not move speed (issue 36's "same speed"): alternating separate processes is fairer than two runs minutes
apart on this noisy 2-core machine, and a process can import one ``sweepik`` only.

    git worktree add /tmp/old <commit>
    python benchmarks/ab_speed.py /tmp/old/src src [--rounds 3] [--arms ur5 carm ...]

Prints per arm the best single-pose and batched time per pose of A and B and their ratio B / A.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys

ARMS = ["ur5", "carm", "kinova_jaco2", "doosan_m0609", "puma560", "kuka_kr6_r900"]

#: What each process runs: kernels loaded first (a few poses), then 3 runs of each kind, the best kept.
_CHILD = """
import json, sys, time
import numpy as np
import sweepik
out = {}
for name in sys.argv[1:]:
    robot = sweepik.load_robot(name)
    T = robot.fk(np.random.default_rng(0).uniform(robot.lower, robot.upper, (2000, robot.n_joints)))
    sweepik.solve_many(robot, T[:50])
    for t in T[:20]:
        sweepik.solve(robot, t)
    single = batched = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        sweepik.solve_many(robot, T)
        batched = min(batched, (time.perf_counter() - t0) / len(T))
        t0 = time.perf_counter()
        for t in T[:300]:
            sweepik.solve(robot, t)
        single = min(single, (time.perf_counter() - t0) / 300)
    out[name] = [single * 1e6, batched * 1e6]
print(json.dumps(out))
"""


def _run(src: str, arms: list[str]) -> dict[str, list[float]]:
    env = {**os.environ, "PYTHONPATH": os.path.abspath(src)}
    done = subprocess.run([sys.executable, "-c", _CHILD, *arms], env=env, capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("a", help="source directory of version A (holds sweepik/)")
    parser.add_argument("b", help="source directory of version B")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--arms", nargs="+", default=ARMS)
    args = parser.parse_args()
    best: dict[str, dict[str, list[float]]] = {"a": {}, "b": {}}
    for _ in range(args.rounds):
        for key, src in (("a", args.a), ("b", args.b)):
            for arm, times in _run(src, args.arms).items():
                old = best[key].get(arm, [float("inf")] * 2)
                best[key][arm] = [min(x, y) for x, y in zip(old, times, strict=True)]
    print(f"{'arm':16s} {'single A':>9s} {'B':>9s} {'B/A':>6s}  {'batched A':>9s} {'B':>8s} {'B/A':>6s}  (us per pose)")
    for arm in args.arms:
        (sa, ba), (sb, bb) = best["a"][arm], best["b"][arm]
        print(f"{arm:16s} {sa:9.1f} {sb:9.1f} {sb / sa:6.3f}  {ba:9.2f} {bb:8.2f} {bb / ba:6.3f}")


if __name__ == "__main__":
    main()
