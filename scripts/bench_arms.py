"""Time per pose of sweepik and the other all-solutions solvers on every bundled arm, in one run.

Single: median over ``--single`` calls of one pose; batched: one call on ``--batch`` poses, divided by their
number (EAIK's ``IK_batched``; IK-Geo has no batch call: a loop). Peers are timed on their raw IK call (their
solutions are not FK-filtered here); "-" where a solver cannot solve the arm at all (EAIK: no known
decomposition or a prismatic joint; IK-Geo 1.0.3: only its closed forms are reliable, see tests/oracles.py).
For the C-Arm the automatic decomposition and the hand-written carm-d1 are timed side by side.

    pip install -e '.[bench]'; python scripts/bench_arms.py [--single 300] [--batch 2000] [--arms carm ur5 ...]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

import oracles  # noqa: E402

import sweepik  # noqa: E402
from sweepik.robot_file import bundled_robots  # noqa: E402


def _median_us(fn, items):
    fn(items[0])
    times = []
    for x in items:
        t0 = time.perf_counter()
        fn(x)
        times.append(time.perf_counter() - t0)
    return 1e6 * statistics.median(times)


def _batch_us(fn, items):
    fn(items[:8])
    t0 = time.perf_counter()
    fn(items)
    return 1e6 * (time.perf_counter() - t0) / len(items)


def _peers(robot):
    """{name: (single(T), batch(Ts))} for the peers that can solve ``robot``."""
    out = {}
    H, P, R_end, rev = oracles._chain_arrays(robot)
    if len(rev) != 6 or not rev.all():
        return out
    try:
        from eaik.IK_HP import HPRobot

        bot = HPRobot(H, P)
        if bot.hasKnownDecomposition():

            def _target(T):
                T = T.copy()
                T[:3, :3] = T[:3, :3] @ R_end.T
                return T

            out["EAIK"] = (lambda T: bot.IK(_target(T)), lambda Ts: bot.IK_batched([_target(T) for T in Ts], 1))
    except ImportError:
        pass
    try:
        import ik_geo

        setup = oracles._ikgeo_setup(ik_geo, H, P, R_end, {"closed"}, float(robot.length_scale))
        if setup is not None:
            gbot, _, _, reverse, Rc = setup

            def _geo(T):
                T = np.linalg.inv(T) if reverse else T
                return gbot.get_ik(np.ascontiguousarray((T[:3, :3] @ Rc.T).T), np.ascontiguousarray(T[:3, 3]))

            out["IK-Geo"] = (_geo, lambda Ts: [_geo(T) for T in Ts])
    except ImportError:
        pass
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--single", type=int, default=300)
    ap.add_argument("--batch", type=int, default=2000)
    ap.add_argument("--arms", nargs="*")
    args = ap.parse_args()
    rows = []
    for name in args.arms or bundled_robots():
        robot = sweepik.load_robot(name)
        rng = np.random.default_rng(1)
        T = robot.fk(oracles.in_limit_configurations(robot, max(args.single, args.batch), rng))
        variants = {"sweepik": {"reduction": "auto"}}
        if robot.default_reduction:
            variants[f"sweepik {robot.default_reduction}"] = {"reduction": robot.default_reduction}
        plan = sweepik.analyze(robot)["chosen"]
        how = "closed form" if plan["closed_form"] else f"sweep joint {plan['free_joint_number']}"
        cells = {}
        for label, kw in variants.items():
            cells[label] = (
                _median_us(lambda t, kw=kw, robot=robot: sweepik.solve(robot, t, **kw), list(T[: args.single])),
                _batch_us(lambda ts, kw=kw, robot=robot: sweepik.solve_many(robot, ts, **kw), T[: args.batch]),
            )
        for peer, (single, batch) in _peers(robot).items():
            cells[peer] = (_median_us(single, list(T[: args.single])), _batch_us(batch, list(T[: args.batch])))
        rows.append((name, how, cells))
        print(name, how, {k: (round(a, 1), round(b, 1)) for k, (a, b) in cells.items()}, flush=True)
    labels = ["sweepik", "sweepik carm-d1", "EAIK", "IK-Geo"]
    print()
    print("| arm | sweepik plan | " + " | ".join(f"{x} single / batched [us]" for x in labels) + " |")
    print("|---|---|" + "---|" * len(labels))
    for name, how, cells in rows:
        vals = [f"{cells[x][0]:.0f} / {cells[x][1]:.1f}" if x in cells else "-" for x in labels]
        print(f"| {name} | {how} | " + " | ".join(vals) + " |")


if __name__ == "__main__":
    main()
