"""Evaluate the automatic decomposition on every bundled arm (issue 9's acceptance measurement).

For each arm: N random in-limit configurations plus edge cases (each joint at each limit, joint 5 at 0);
``sweepik.solve_many(robot, robot.fk(Q))`` with no options (the C-Arm: reduction="auto"). Reports recall
(q among the solutions, or on a reported family), FK certification (<= 1e-9 x length scale), limits, and the
agreement of each pose's solution set (within limits) with an independent reference: IK-Geo where it has a
closed form for the arm, else ssik (all-solutions, Raghavan-Roth elimination; the bench extra) for 6R arms, else the
many-start numerical search of tests/oracles.py.

    python scripts/evaluate_arms.py [--n 2000] [--arms ur5 carm ...] [--numerical-max 2000]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from oracles import (  # noqa: E402
    edge_configurations,
    ikgeo_solutions,
    in_limit_configurations,
    numerical_solutions,
    recovers,
    same_solution_set,
    ssik_solutions,
)

import sweepik  # noqa: E402
from sweepik.io.robot_file import bundled_robots  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=2000)
    ap.add_argument("--arms", nargs="*", default=None)
    ap.add_argument("--numerical-max", type=int, default=2000, help="poses compared with the numerical search")
    args = ap.parse_args()
    for name in args.arms or bundled_robots():
        robot = sweepik.load_robot(name)
        if robot.n_joints != 6:  # (a 7-joint arm is solved with a joint locked: tests/test_locked.py)
            print(f"{name:15s} skipped: {robot.n_joints} joints", flush=True)
            continue
        rng = np.random.default_rng(2026)
        Q = in_limit_configurations(robot, args.n, rng)
        Q = np.concatenate([Q, edge_configurations(robot, Q[0])])
        T = robot.fk(Q)
        kw = {"reduction": "auto"} if robot.default_reduction else {}
        t0 = time.perf_counter()
        S = sweepik.solve_many(robot, T, **kw)
        dt = time.perf_counter() - t0
        rec = sum(recovers(robot, s, q) for s, q in zip(S, Q, strict=True))
        cert = all((s.error_geodesic <= 1e-9 * robot.length_scale).all() for s in S if len(s))
        lim = all(robot.within_limits(s.q).all() for s in S if len(s))
        same = compared = rechecked = by_alt = 0
        kinds: dict[str, int] = {}  # poses compared, by reference
        plans = sweepik.analyze(robot)["plans"]
        chosen = plans[0]
        alts = [p["free_joint"] for p in plans if not p["closed_form"] and not p["blind_spot"]]
        alt = next((j for j in alts if chosen["closed_form"] or j != chosen["free_joint"]), None)
        worst = []
        for i, (s, t) in enumerate(zip(S, T, strict=True)):
            ref = ikgeo_solutions(robot, t) if robot.is_revolute.all() else None
            kind = "ik-geo"
            if ref is None and robot.is_revolute.all():
                ref = ssik_solutions(robot, t)  # (a 6R arm IK-Geo has no closed form for: ssik, if installed)
                kind = "ssik"
            if ref is None:
                kind = "numerical"
                if compared >= args.numerical_max:
                    continue
                ref = numerical_solutions(robot, t, n_starts=300)
            ref = ref[robot.within_limits(ref)] if len(ref) else ref
            ok = same_solution_set(s.q, ref, robot.is_revolute, robot.length_scale)
            if not ok and kind == "numerical":
                # near singular poses a many-start search misses solutions: a second, larger search, and the
                # verdict of another decomposition (another theta*, another chain of subproblems)
                more = numerical_solutions(robot, t, n_starts=3000, seed=1, full_circle=True)
                more = more[robot.within_limits(more)] if len(more) else more
                ok = same_solution_set(s.q, more, robot.is_revolute, robot.length_scale)
                rechecked += ok
                if not ok and alt is not None:
                    other = sweepik.solve(robot, t, free_joint=alt)
                    ok = same_solution_set(s.q, other.q, robot.is_revolute, robot.length_scale)
                    by_alt += ok
            same += ok
            compared += 1
            kinds[kind] = kinds.get(kind, 0) + 1
            if not ok:
                worst.append((i, len(s), len(ref)))
        refs = "+".join(f"{k}:{n}" for k, n in kinds.items()) or "none"
        print(
            f"{name:15s} poses {len(Q)} recall {rec}/{len(Q)} certified {cert} in-limits {lim} "
            f"same-as-{refs} {same}/{compared} ({100 * same / max(compared, 1):.2f} %; {rechecked} after a second "
            f"search, {by_alt} by another decomposition) "
            f"solve {1e3 * dt / len(Q):.3f} ms/pose; differing (pose, ours, ref): {worst[:6]}",
            flush=True,
        )


if __name__ == "__main__":
    main()
