"""Seven-joint arms with each lock that ``sweepik.analyze`` offers (issue 35): recall and refusals.

    python scripts/locked_arms.py [--n 20] [--arms kinova_gen3 franka_panda kuka_iiwa14 ...] [--ssik]
                                  [--only yumi kassow] [--numerical 3]

For every joint and every lock value ``analyze(robot)["locks"]`` lists, ``--n`` random configurations with that joint
at that value (the others uniform within their limits, or over one turn) are solved with the joint locked, limits
off; the configuration must come back (``tests/singular.recovered``). A lock ``analyze`` says nothing solves must be
refused by ``solve`` with NoReductionError (never answered wrongly). ``--ssik``: the 7-joint arms of ssik 8.2's
prebuilt catalogue too (``tests/catalogue.py``); ``--only``: the arms whose name contains one of these.
``--numerical K``: the solution sets of the first K configurations of each lock are compared with a many-start
numerical search's on the held arm (``oracles.numerical_solutions``, sets equal to 1e-4; both see the
joints over one turn).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from oracles import numerical_solutions, same_solution_set  # noqa: E402
from singular import recovered  # noqa: E402

import sweepik  # noqa: E402
from sweepik.solving import held_joints  # noqa: E402


def _same_as_numerical(robot: sweepik.Robot, k: int, v: float, s: sweepik.Solutions, q: np.ndarray) -> bool:
    """``s`` (the solutions of ``q``'s pose with joint ``k`` held at ``v``) equals a many-start search's set on the
    held arm."""
    held = held_joints(robot, {k: v})
    assert held is not None
    num = numerical_solutions(held.arm, robot.fk(q), n_starts=400, full_circle=True)
    ours = s.q[:, list(held.free)]
    same = bool(same_solution_set(ours, num, held.arm.is_revolute, held.arm.length_scale, tol=1e-4))
    if not same:  # (which side lacks what: a many-start search can miss a root, so can sweepik)
        print(f"    differs at q = {q.tolist()}: sweepik {len(ours)} solutions, numerical {len(num)}", flush=True)
    return same


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20)
    ap.add_argument("--arms", nargs="*", default=None)
    ap.add_argument("--ssik", action="store_true")
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--numerical", type=int, default=0)
    args = ap.parse_args()
    robots = [sweepik.load_robot(n) for n in (args.arms or sweepik.bundled_robots())]
    if args.ssik:
        import ssik
        from catalogue import robot_from_ssik

        robots += [robot_from_ssik(a.name) for a in ssik.list_arms() if a.dof == 7]
    if args.only:
        robots = [r for r in robots if any(o.lower() in r.name.lower() for o in args.only)]
    rng = np.random.default_rng(0)
    for robot in robots:
        if robot.n_joints != 7:
            continue
        lo, hi = np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi)
        for lock in sweepik.analyze(robot)["locks"]:
            k, name = lock["joint"], lock["joint_name"]
            for entry in lock["values"]:
                v = float(entry["value"])
                Q = rng.uniform(lo, hi, (args.n, 7))
                Q[:, k] = v
                rec = refused = same = compared = 0
                slow = 0.0
                for i, q in enumerate(Q):
                    t0 = time.perf_counter()
                    try:
                        s = sweepik.solve(robot, robot.fk(q), locked={name: v}, limits=False)
                    except sweepik.NoReductionError:
                        refused += 1
                        continue
                    slow = max(slow, time.perf_counter() - t0)
                    rec += recovered(robot, s, q)
                    if i < args.numerical:
                        compared += 1
                        same += _same_as_numerical(robot, k, v, s, q)
                said = "refused" if entry["chosen"] is None else "solved"
                print(
                    f"{robot.name:18s} lock {name:14s} = {v:+.4f}  analyze: {said:7s}  recall {rec}/{args.n - refused}"
                    f"  refused {refused}  slowest {slow * 1e3:.0f} ms"
                    + (f"  numerical same {same}/{compared}" if compared else ""),
                    flush=True,
                )


if __name__ == "__main__":
    main()
