"""Poses that went a slow way (issue 39, eighth session): a seven-joint arm's lock values inside its lock windows,
and poses on a self-motion of two dimensions (three revolute axes on one line). Run from the repository root.

    python benchmarks/slow_singular.py [--seed 0]

Prints, for the Panda held at joint 6: values in the lock window round 0 and in the one round +-pi (a random
configuration each), the first value's time (the window's plan choice) and the median and largest of the rest; then,
for the Kuka iiwa held at A1 with A4 = A6 = 0 (axes 3, 5 and 7 on one line), one pose with the limits on and off (its
solutions and families) and 8 random such configurations. Benchmarks are not tests: timings vary by +-10-25 %.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import sweepik
from sweepik import solving


def _timed(robot: sweepik.Robot, T: np.ndarray, k: int, value: float, limits: bool = True) -> tuple[float, object]:
    start = time.perf_counter()
    sol = sweepik.solve(robot, T, locked={k: value}, limits=limits)
    return time.perf_counter() - start, sol


def windows(rng: np.random.Generator) -> None:
    """The Panda held at joint 6, values inside its lock windows."""
    arm, k = sweepik.load_robot("franka_panda"), 5
    fast = solving._held_pose(arm, k)
    assert fast is not None
    w = fast.windows
    q = rng.uniform(arm.lower, arm.upper)
    _timed(arm, arm.fk(q), k, float(q[k]))  # (kernels load)
    zero = next((a, b) for a, b in w if a < 0.0 < b)
    for name, (a, b) in (("round 0", zero), ("round pi", (w[-1, 0], w[0, 1] + 2 * np.pi))):
        values = [float(np.remainder(v + np.pi, 2 * np.pi) - np.pi) for v in rng.uniform(a, b, 25)]
        times = []
        for v in (v for v in values if arm.lower[k] <= v <= arm.upper[k]):
            q = rng.uniform(arm.lower, arm.upper)
            q[k] = v
            times.append(_timed(arm, arm.fk(q), k, v)[0] * 1e3)
        rest = times[1:]
        print(
            f"Panda joint 6, window {name}: {len(times)} values, first {times[0]:.0f} ms, "
            f"median of the rest {statistics.median(rest):.1f} ms, largest {max(rest):.0f} ms"
        )


def sheets(rng: np.random.Generator) -> None:
    """The Kuka iiwa held at A1 with A4 = A6 = 0: a self-motion of two dimensions."""
    arm = sweepik.load_robot("kuka_iiwa14")
    _timed(arm, arm.fk(np.full(7, 0.3)), 0, 0.3)  # (kernels load)
    q = np.array([0.2, 0.3, 0.4, 0.0, -0.5, 0.0, 1.0])
    for limits in (True, False):
        dt, sol = _timed(arm, arm.fk(q), 0, float(q[0]), limits)
        print(f"iiwa {q.tolist()}, limits {limits}: {len(sol)} solutions, {len(sol.families)} families, {dt:.2f} s")
    times = []
    for _ in range(8):
        q = rng.uniform(arm.lower, arm.upper) * 0.8
        q[3] = q[5] = 0.0
        times.append(_timed(arm, arm.fk(q), 0, float(q[0]))[0])
    print("iiwa, 8 random configurations with A4 = A6 = 0: " + ", ".join(f"{t:.2f}" for t in times) + " s")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    windows(np.random.default_rng(args.seed))
    sheets(np.random.default_rng(args.seed))


if __name__ == "__main__":
    main()
