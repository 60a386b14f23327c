"""sweepik on random arms without structure (issue 37): recall, wrong answers, agreement with ssik and a numerical
search, speed.

    python scripts/general_arms.py check [--arms 20] [--prismatic 10] [--n 200] [--singular 50] [--numerical 4]
    python scripts/general_arms.py ssik  [--arms 11] [--n 200] [--singular 50] [--out tests/data/ssik_general.npz]

``check`` solves random arms (``tests/general_arms.random_arm``: 6R, then 5R1P and 4R2P alternately) with
``sweepik.solve`` (limits off) and reports per arm: recall (the generating configuration among the solutions,
``singular.recovered``), wrong solutions (pose error above 1e-9 of the arm's size), the share of poses whose set
equals a many-start numerical search's on ``--numerical`` poses per arm (sets compared to 1e-4: the search stops
~1e-5 short of a double root), and the median time per pose, single and batched (each on poses not solved before in
the process: the general method keeps the roots of the poses it has seen). Poses: ``--n`` uniform configurations and
``--singular`` on or next to the singular set (``general_arms.poses_of``).

``ssik`` compares with ssik 8.2's general solver (its native path, ``oracles.ssik_general_native``) on the random 6R
arms ``general_arms.dh_chain(k)``, k < ``--arms``, whose SymPy derivations ssik keeps in ``~/.cache/ssik`` (4-9
minutes an arm the first time): per arm, the share of poses with the same solution set (``oracles.
unmatched_solutions``: roots next to the singular set compared to 1e-4, others to 1e-6), solutions only one side
has (and whether they pass an FK check), and the median time per pose of ssik, of sweepik single and of sweepik
batched, in the same run. ``--out``: also write ssik's solutions, for ``tests/test_general.py`` (a compressed
``.npz``).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from general_arms import dh_chain, poses_of, random_arm, robot_of_chain  # noqa: E402
from oracles import (  # noqa: E402
    numerical_solutions,
    pose_errors,
    same_solution_set,
    ssik_general_native,
    unmatched_solutions,
)
from singular import recovered  # noqa: E402

import sweepik  # noqa: E402


def _timed(robot: sweepik.Robot, T: np.ndarray) -> tuple[list[sweepik.Solutions], float, float]:
    """The solutions of ``T`` one pose at a time and their median time per pose; the time per pose of solving poses
    of the same kind (the next configurations of the arm, not solved before) as one batch."""
    sweepik.solve(robot, robot.fk(np.zeros(6)), limits=False)  # (compiles)
    single, sols = [], []
    for Tk in T:
        t = time.perf_counter()
        sols.append(sweepik.solve(robot, Tk, limits=False))
        single.append(time.perf_counter() - t)
    other = robot.fk(poses_of(robot, len(T), 0, seed=len(T) + 12345))
    t = time.perf_counter()
    sweepik.solve_many(robot, other, limits=False)
    return sols, float(np.median(single)), (time.perf_counter() - t) / len(T)


def _check_arm(robot: sweepik.Robot, Q: np.ndarray, n_numerical: int) -> dict:
    L = robot.length_scale
    T = robot.fk(Q)
    sols, single, batched = _timed(robot, T)
    rec = wrong = 0
    misses = []
    for q, s in zip(Q, sols, strict=True):
        ok = recovered(robot, s, q)
        rec += ok
        if not ok:
            misses.append(q)
        if len(s):
            dp, ang = pose_errors(robot.fk(s.q), robot.fk(q), L)
            wrong += int(np.sum(np.maximum(dp, ang) > 1e-9))
    out = {"recall": rec, "poses": len(Q), "wrong": wrong, "single_us": 1e6 * single, "batched_us": 1e6 * batched,
           "misses": misses}  # fmt: skip
    if n_numerical:
        idx = np.linspace(0, len(Q) - 1, n_numerical).astype(int)
        same = [same_solution_set(sols[i].q, numerical_solutions(robot, T[i], n_starts=400, full_circle=True),
                                  robot.is_revolute, L, tol=1e-4) for i in idx]  # fmt: skip
        out["numerical_same"], out["numerical_poses"] = int(np.sum(same)), len(idx)
    return out


def check(args: argparse.Namespace) -> None:
    arms = [("6r", k) for k in range(args.arms)]
    arms += [("5r1p" if k % 2 == 0 else "4r2p", k) for k in range(args.prismatic)]
    totals = {"recall": 0, "poses": 0, "wrong": 0}
    for kind, k in arms:
        robot = random_arm(kind, k)
        Q = poses_of(robot, args.n, args.singular, seed=k)
        r = _check_arm(robot, Q, args.numerical)
        for key in totals:
            totals[key] += r[key]
        extra = f", numerical same {r['numerical_same']}/{r['numerical_poses']}" if "numerical_same" in r else ""
        print(
            f"{kind} arm {k}: recall {r['recall']}/{r['poses']}, wrong {r['wrong']}, single {r['single_us']:.0f} us, "
            f"batched {r['batched_us']:.0f} us{extra}",
            flush=True,
        )
        for q in r["misses"][:3]:
            print("   missed", np.round(q, 6).tolist())
    print(f"total: recall {totals['recall']}/{totals['poses']}, wrong {totals['wrong']}")


def _fk_ok(robot: sweepik.Robot, q: np.ndarray, T: np.ndarray) -> bool:
    dp, ang = pose_errors(robot.fk(q[None]), T, robot.length_scale)
    return bool(max(dp[0], ang[0]) <= 1e-9)


def ssik(args: argparse.Namespace) -> None:
    saved: dict[str, np.ndarray] = {}
    same_all = poses_all = 0
    for k in range(args.arms):
        H, P, R_end = dh_chain(k)
        robot = robot_of_chain(H, P, R_end, f"dh_chain_{k}")
        t0 = time.perf_counter()
        solve_ssik = ssik_general_native(H, P, R_end)
        if solve_ssik is None:
            print("ssik is not installed or dispatches another solver")
            return
        Q = poses_of(robot, args.n, args.singular, seed=k)
        T = robot.fk(Q)
        solve_ssik(T[0])  # (derives the elimination, or loads it)
        setup = time.perf_counter() - t0
        theirs, seconds = [], []
        for Tk in T:
            t = time.perf_counter()
            theirs.append(solve_ssik(Tk))
            seconds.append(time.perf_counter() - t)
        ours, single, batched = _timed(robot, T)
        same = only_ours = only_theirs = only_theirs_fk = 0
        for Tk, s, r in zip(T, ours, theirs, strict=True):
            extra_ours, extra_theirs = unmatched_solutions(s.q, s.multiplicity, r, robot)
            same += not (extra_ours or extra_theirs)
            only_ours += len(extra_ours)
            only_theirs += len(extra_theirs)
            only_theirs_fk += sum(_fk_ok(robot, q, Tk) for q in extra_theirs)
        same_all += same
        poses_all += len(T)
        print(
            f"dh_chain {k}: ssik set {setup:.1f} s, same sets {same}/{len(T)}, only sweepik {only_ours}, only ssik "
            f"{only_theirs} ({only_theirs_fk} pass FK); per pose: ssik {1e6 * np.median(seconds):.0f} us, sweepik "
            f"single {1e6 * single:.0f} us, batched {1e6 * batched:.0f} us",
            flush=True,
        )
        saved[f"Q{k}"] = Q
        saved[f"count{k}"] = np.array([len(r) for r in theirs])
        saved[f"sols{k}"] = np.concatenate(theirs)
    print(f"total: same sets {same_all}/{poses_all}")
    if args.out is not None:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(args.out, n_arms=args.arms, **saved)
        print("wrote", args.out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("stage", choices=("check", "ssik"))
    ap.add_argument("--arms", type=int, default=None)
    ap.add_argument("--prismatic", type=int, default=10)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--singular", type=int, default=50)
    ap.add_argument("--numerical", type=int, default=4)
    ap.add_argument("--out", type=Path, default=None)
    args = ap.parse_args()
    if args.stage == "check":
        args.arms = 20 if args.arms is None else args.arms
        check(args)
    else:
        args.arms = 11 if args.arms is None else args.arms
        ssik(args)


if __name__ == "__main__":
    main()
