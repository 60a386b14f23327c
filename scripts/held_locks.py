"""Which locks of the seven-joint arms take their value as an argument of one compiled call (``engine.held_pose``;
or of two, a plan's and its companion's, where the held arm has a near-structure: ``engine.held_joined``), and
whether those calls give the held arm's own solutions (issue 39).

    python scripts/held_locks.py [--n 15] [--ssik] [--rewrite] [--only gen3 panda] [--turned]

For every seven-joint arm (the bundled ones; ``--ssik``: ssik 8.2's catalogue too, ``tests/catalogue.py``) and each
revolute joint: whether ``HeldPose`` takes it (a closed form or a sweep at every value; else ``HeldJoined``: "joined"),
then ``--n`` random poses at random values: the calls' solutions (where they settle the pose) against the held arm
built at the value and solved the general way (same count, configurations to 1e-8 of the arm's size), and the
generating configuration recovered by ``solve``. ``--rewrite``: each arm rewritten at random too (axis signs, zeros,
frames, units: ``tests/rewrites.py``). Prints a line per taken lock and the totals. ``--turned``: instead, the first
and last joints of every arm (``engine.turned_lock``: every value solved by the held arm at one reference value, the
pose turned): ``solve``'s solutions at random values against the held arm built at the value, and recovered.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from oracles import recovers  # noqa: E402
from rewrites import rewrite  # noqa: E402

import sweepik  # noqa: E402
from sweepik import solving  # noqa: E402


def _general(robot: sweepik.Robot, T: np.ndarray, k: int, value: float) -> sweepik.Solutions:
    return solving._solve_one(robot, T[None], None, "precise", True, solving.N_SAMPLES, None, {k: value}, False)


def _differs(a: sweepik.Solutions, b: sweepik.Solutions, robot: sweepik.Robot) -> float:
    """inf where the counts differ, else the largest difference of the sorted configurations."""
    if len(a) != len(b):
        return np.inf
    return float(np.abs(np.sort(a.q, axis=0) - np.sort(b.q, axis=0)).max(initial=0.0))


def check_arm(robot: sweepik.Robot, n: int, rng: np.random.Generator) -> tuple[int, int, int, int, int]:
    """``(locks, taken or joined, poses answered by the one call, differing, not recovered)`` of one arm."""
    locks = taken = answered = differ = missed = 0
    for k in range(7):
        if not robot.is_revolute[k]:
            continue
        locks += 1
        fast = solving._held_pose(robot, k)
        kind = "taken"
        if fast is None and k not in (0, 6):  # (the first and last: ``--turned``)
            fast, kind = solving._held_joined(robot, k), "joined"
        if fast is None:
            continue
        taken += 1
        q = _configurations(robot, n, rng)
        mine = 0
        for qq, T in zip(q, robot.fk(q), strict=True):
            v = float(qq[k])
            status, sol = fast.solve(np.ascontiguousarray(T), v, True)
            if sol is not None:
                mine += 1
                d = _differs(sol, _general(robot, T, k, v), robot)
                if not d <= 1e-8 * max(1.0, robot.length_scale):
                    differ += 1
                    print(f"    differs: joint {robot.joint_names[k]} at {v!r}, q = {qq.tolist()}: {d}")
            if not recovers(robot, sweepik.solve(robot, T, locked={k: v}), qq):
                missed += 1
                print(f"    not recovered: joint {robot.joint_names[k]} at {v!r}, q = {qq.tolist()}")
        answered += mine
        print(f"  {robot.name} {robot.joint_names[k]}: {kind}, {mine}/{n} answered by the one call", flush=True)
    return locks, taken, answered, differ, missed


_OPTIONS = dict(
    reduction=None, strategy="precise", limits=True, n_samples=solving.N_SAMPLES, chunk_size=1, free_joint=None
)


def _configurations(robot: sweepik.Robot, n: int, rng: np.random.Generator) -> np.ndarray:
    """Configurations uniform inside the limits (revolute joints within one turn of them where they allow)."""
    lo = np.where(robot.is_revolute, np.maximum(robot.lower, -np.pi), robot.lower)
    hi = np.where(robot.is_revolute, np.minimum(robot.upper, np.pi), robot.upper)
    lo, hi = np.where(hi > lo, lo, robot.lower), np.where(hi > lo, hi, robot.upper)
    return rng.uniform(lo, hi, size=(n, robot.n_joints))


def check_turned(robot: sweepik.Robot, n: int, rng: np.random.Generator) -> tuple[int, int, int, int, int]:
    """``check_arm``'s counts for the first and last joints, turned: ``(locks, turned, poses, differing, not
    recovered)``."""
    locks = turned = poses = differ = missed = 0
    for k in (0, robot.n_joints - 1):
        if not robot.is_revolute[k]:
            continue
        locks += 1
        q = _configurations(robot, n, rng)
        try:
            sols = [sweepik.solve(robot, T, locked={k: float(qq[k])}) for qq, T in zip(q, robot.fk(q), strict=True)]
        except sweepik.NoReductionError:
            print(f"  {robot.name} {robot.joint_names[k]}: refused")
            continue
        turned += 1
        for qq, T, sol in zip(q, robot.fk(q), sols, strict=True):
            poses += 1
            block = next(iter(solving._held_run(robot, T[None], {k: float(qq[k])}, _OPTIONS, turned=False)))
            d = _differs(sol, block.solutions(0), robot)
            if not d <= 1e-8 * max(1.0, robot.length_scale):
                differ += 1
                print(f"    differs: joint {robot.joint_names[k]} at {qq[k]!r}, q = {qq.tolist()}: {d}")
            if not recovers(robot, sol, qq):
                missed += 1
                print(f"    not recovered: joint {robot.joint_names[k]} at {qq[k]!r}, q = {qq.tolist()}")
        print(f"  {robot.name} {robot.joint_names[k]}: turned, {n} poses", flush=True)
    return locks, turned, poses, differ, missed


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=15)
    ap.add_argument("--ssik", action="store_true")
    ap.add_argument("--rewrite", action="store_true")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--turned", action="store_true")
    args = ap.parse_args()
    check = check_turned if args.turned else check_arm
    robots = [r for r in map(sweepik.load_robot, sweepik.bundled_robots()) if r.n_joints == 7]
    if args.ssik:
        import ssik
        from catalogue import robot_from_ssik

        robots += [robot_from_ssik(a.name) for a in ssik.list_arms() if a.dof == 7]
    if args.only:
        robots = [r for r in robots if any(s in r.name for s in args.only)]
    rng = np.random.default_rng(0)
    total = np.zeros(5, dtype=int)
    for robot in robots:
        total += check(robot, args.n, rng)
        if args.rewrite:
            total += check(rewrite(robot, rng).robot, args.n, rng)
    locks, taken, answered, differ, missed = total.tolist()
    what = "turned" if args.turned else "taken"
    print(f"locks {locks}, {what} {taken}; poses answered {answered}, differing {differ}; not recovered {missed}")


if __name__ == "__main__":
    main()
