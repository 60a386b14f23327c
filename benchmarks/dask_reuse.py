"""Throughput of ``solve_dask`` with its kept local cluster against ``solve_many`` (issue 38).

    python benchmarks/dask_reuse.py [--n 200000] [--robot carm]

Poses: ``--n`` random in-limit configurations' poses. Times, in one process: ``solve_many`` (after a warm-up
solve), then two ``solve_dask`` calls on the same poses (``client=None``: the first starts the local cluster, the
second reuses it). Prints poses per second of each and the two calls' combined throughput as a share of
``solve_many``'s.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import sweepik
from sweepik.distributed import close_local_cluster


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=200_000)
    ap.add_argument("--robot", default="carm")
    args = ap.parse_args()
    arm = sweepik.load_robot(args.robot)
    rng = np.random.default_rng(0)
    T = arm.fk(arm.lower + rng.random((args.n, arm.n_joints)) * (arm.upper - arm.lower))
    sweepik.solve_many(arm, T[:4096])  # (compiled kernels loaded)
    t = time.perf_counter()
    sweepik.solve_many(arm, T)
    base = time.perf_counter() - t
    calls = []
    for _ in range(2):
        t = time.perf_counter()
        sweepik.solve_dask(arm, T)
        calls.append(time.perf_counter() - t)
    close_local_cluster()
    n = args.n
    print(f"solve_many: {base:.2f} s ({n / base:,.0f} poses/s)")
    for k, c in enumerate(calls):
        print(f"solve_dask call {k + 1}: {c:.2f} s ({n / c:,.0f} poses/s, {base / c:.0%} of solve_many)")
    print(f"two calls together: {2 * n / sum(calls):,.0f} poses/s, {2 * base / sum(calls):.0%} of solve_many")


if __name__ == "__main__":
    main()
