"""Held arms that take the general method (ssik's xArm7 and Gen72 at joints 2 and 4-6, its RM75 at joints 2 and 6:
rounding-level near-structures that no plan passes), a new lock value every pose against one value. Run from the
repository root with ssik installed (``pip install -e '.[bench]'``).

    python benchmarks/held_general.py [--locks xarm7_ik:1 rm75_ik:5 ...] [--n 30]

Per lock (arm and 0-based joint): ``solve`` of ``--n`` poses, each with its own value of the joint, then ``--n``
poses reached with the joint at one value; the median milliseconds a pose of each (and the mean and the largest of
the first). The first solve of a process loads kernels and is not timed.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from catalogue import robot_from_ssik  # noqa: E402

import sweepik  # noqa: E402

LOCKS = ("xarm7_ik:1", "xarm7_ik:3", "xarm7_ik:4", "xarm7_ik:5", "gen72_ik:1", "gen72_ik:3", "gen72_ik:4",
         "gen72_ik:5", "rm75_ik:1", "rm75_ik:5")  # fmt: skip


def timed(arm: sweepik.Robot, poses: np.ndarray, name: str, values: np.ndarray) -> np.ndarray:
    out = []
    for T, v in zip(poses, values, strict=True):
        t = time.perf_counter()
        sweepik.solve(arm, T, locked={name: float(v)})
        out.append(time.perf_counter() - t)
    return np.array(out) * 1e3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--locks", nargs="*", default=list(LOCKS))
    parser.add_argument("--n", type=int, default=30)
    args = parser.parse_args()
    for lock in args.locks:
        arm_name, joint = lock.split(":")
        arm, k = robot_from_ssik(arm_name), int(joint)
        name = arm.joint_names[k]
        q = np.random.default_rng(0).uniform(np.maximum(arm.lower, -3), np.minimum(arm.upper, 3), (args.n + 1, 7))
        sweepik.solve(arm, arm.fk(q[0]), locked={name: float(q[0, k])})
        new = timed(arm, arm.fk(q[1:]), name, q[1:, k])
        at = q.copy()
        at[:, k] = q[0, k]
        fixed = timed(arm, arm.fk(at[1:]), name, at[1:, k])
        print(
            f"{arm_name} {name}: a new value median {np.median(new):.2f} ms (mean {new.mean():.1f}, largest "
            f"{new.max():.0f}); one value median {np.median(fixed):.2f} ms"
        )


if __name__ == "__main__":
    main()
