"""A 7-joint arm held at a new lock value every pose against the same value every pose (issue 39's "a new lock
value for free"): ``solve`` per pose, and ``solve_many`` with one value per pose. Run from the repository root.

    python benchmarks/lock_values.py [--arm kuka_iiwa14] [--joint A3] [--n 40] [--parts]

Prints the mean time a pose of each, in milliseconds, and their ratio. The same value is timed on poses reached with
the joint at that value (configurations with it set there), as a user holding a lock solves them; and on the
new-value poses too (most of which the arm does not reach at the fixed value: a quicker answer, the comparison the
first rounds of issue 39 made); and the first new-value poses solved again at their own values (each value asked for
before: the same poses, ``AGAIN``). ``--parts``: where a new value's time goes, each step timed on its own in the
order a solve takes them (the held arm, its plan, the reduction, its one call's fixed arguments, the solve itself),
means over ``--n`` new values.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

import sweepik

#: How many of the new-value poses are solved again at their values (``--n`` at most; the held arms and reductions
#: of the last 64 values are cached): the same poses and values, each value asked for before. The same value's poses
#: are other poses, and how many of them need the general way's rarer steps depends on the value.
AGAIN = 40


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--arm", default="kuka_iiwa14")
    parser.add_argument("--joint", default="A3")
    parser.add_argument("--n", type=int, default=40)
    parser.add_argument("--parts", action="store_true")
    args = parser.parse_args()
    arm = sweepik.load_robot(args.arm)
    k = arm.joint_names.index(args.joint)
    n = args.n
    # fresh configurations (and lock values) for each measurement: held arms and their reductions are cached
    q = np.random.default_rng(2).uniform(arm.lower, arm.upper, (3 * n + 1, arm.n_joints))
    T = arm.fk(q)
    # (kernels loaded: the one call's, and the general path's that the poses it hands on take, ~30 ms once a process)
    sweepik.solve(arm, T[0], locked={args.joint: float(q[0, k])})
    warm = np.clip(q[1:, k] + 0.01, arm.lower[k], arm.upper[k])
    sweepik.solve_many(arm, T[1:], locked={args.joint: warm})
    if args.parts:
        parts(arm, args.joint, q[1 : n + 1], T[1 : n + 1])
        return
    t0 = time.perf_counter()
    for i in range(1, n + 1):
        sweepik.solve(arm, T[i], locked={args.joint: float(q[i, k])})
    new = (time.perf_counter() - t0) / n
    same_value = float(q[n + 1, k])
    at_value = q[n + 1 : 2 * n + 1].copy()
    at_value[:, k] = same_value
    T_at = arm.fk(at_value)
    for _ in range(2):  # (twice: an arm solved with a companion builds its one calls at a value asked for again)
        sweepik.solve(arm, T[n + 1], locked={args.joint: same_value})
    t0 = time.perf_counter()
    for i in range(n):
        sweepik.solve(arm, T_at[i], locked={args.joint: same_value})
    same = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    for i in range(n + 1, 2 * n + 1):
        sweepik.solve(arm, T[i], locked={args.joint: same_value})
    other = (time.perf_counter() - t0) / n
    m = min(n, AGAIN)
    t0 = time.perf_counter()
    for i in range(1, m + 1):
        sweepik.solve(arm, T[i], locked={args.joint: float(q[i, k])})
    again = (time.perf_counter() - t0) / m
    rows = slice(2 * n + 1, 3 * n + 1)
    t0 = time.perf_counter()
    sweepik.solve_many(arm, T[rows], locked={args.joint: q[rows, k]})
    batch = (time.perf_counter() - t0) / n
    print(
        f"{args.arm}, {args.joint} held: a new value every pose {new * 1e3:.2f} ms, the same value {same * 1e3:.3f} ms "
        f"(x{new / same:.2f}; on poses it mostly does not reach {other * 1e3:.3f} ms, x{new / other:.2f}); the first "
        f"{m} new-value poses again, each value asked for before: {again * 1e3:.3f} ms (x{new / again:.2f}); "
        f"solve_many with a new value per pose {batch * 1e3:.2f} ms a pose"
    )


def parts(arm: sweepik.Robot, joint: str, q: np.ndarray, T: np.ndarray) -> None:
    """``--parts``: each step of a solve at a new lock value timed on its own (later steps find the earlier ones'
    results cached, as a solve does): the held arm, its plan and reduction (``reductions.automatic_for_held``), the
    one call's fixed arguments, the solve."""
    from sweepik import solving

    k = arm.joint_names.index(joint)
    names = ("held arm", "plan and reduction", "one call's arguments", "solve")
    total = np.zeros(len(names))
    for qq, TT in zip(q, T, strict=True):
        locked = {joint: float(qq[k])}
        clock = [time.perf_counter()]
        held = solving.held_joints(arm, locked)
        assert held is not None
        clock.append(time.perf_counter())
        solving._default_reduction(held.arm, held)
        clock.append(time.perf_counter())
        solving._single_pose(arm, locked)
        clock.append(time.perf_counter())
        sweepik.solve(arm, TT, locked=locked)
        clock.append(time.perf_counter())
        total += np.diff(clock)
    each = ", ".join(f"{name} {t / len(q) * 1e3:.2f}" for name, t in zip(names, total, strict=True))
    print(f"{arm.name}, {joint} held at a new value, ms a pose: {each}")


if __name__ == "__main__":
    main()
