"""sweepik on random arms without structure (issue 37): recall, wrong answers, agreement with ssik and a numerical
search, speed.

    python scripts/general_arms.py refs  [--arms 20] [--n 200] [--singular 50] [--cache PATH]
    python scripts/general_arms.py check [--arms 20] [--prismatic 10] [--n 200] [--singular 50] [--cache PATH]
                                         [--numerical 20]

``refs`` derives ssik 8.2's general solver for each random 6R arm (``tests/general_arms.random_arm("6r", k)``; ssik
derives a Raghavan-Roth elimination with SymPy the first time it meets an arm, 1.5 to 3.5 minutes, kept in
``~/.cache/ssik``) and stores its solutions of every pose, with its time per pose (after the derivation), in
``--cache`` (a pickle; default ``~/.cache/sweepik/general_arms.pkl``). ``check`` solves the same poses with
``sweepik.solve`` (limits off) and reports per arm: recall (the generating configuration among the solutions,
``singular.recovered``), wrong solutions (pose error above 1e-9 of the arm's size), the share of poses whose set
equals ssik's (6R), the share equal to a many-start numerical search's on ``--numerical`` poses per arm (all arms),
and the median time per pose, single and batched, beside ssik's. Poses: ``--n`` uniform configurations and
``--singular`` on or next to the singular set (``general_arms.poses_of``).
"""

from __future__ import annotations

import argparse
import pickle
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from general_arms import poses_of, random_arm  # noqa: E402
from oracles import numerical_solutions, pose_errors, same_solution_set, ssik_solutions  # noqa: E402
from singular import recovered  # noqa: E402

import sweepik  # noqa: E402

DEFAULT_CACHE = Path.home() / ".cache" / "sweepik" / "general_arms.pkl"


def _load(path: Path) -> dict:
    if path.exists():
        with path.open("rb") as f:
            return pickle.load(f)
    return {}


def refs(args: argparse.Namespace) -> None:
    cache = _load(args.cache)
    for k in range(args.arms):
        robot = random_arm("6r", k)
        Q = poses_of(robot, args.n, args.singular, seed=k)
        key = ("6r", k, args.n, args.singular)
        if key in cache:
            continue
        t0 = time.perf_counter()
        ssik_solutions(robot, robot.fk(Q[0]))  # (derives the elimination)
        derive = time.perf_counter() - t0
        sols, times = [], []
        for q in Q:
            T = robot.fk(q)
            t = time.perf_counter()
            sols.append(ssik_solutions(robot, T))
            times.append(time.perf_counter() - t)
        cache[key] = {"Q": Q, "ssik": sols, "seconds": np.array(times), "derive": derive}
        args.cache.parent.mkdir(parents=True, exist_ok=True)
        with args.cache.open("wb") as f:
            pickle.dump(cache, f)
        counts = [0 if s is None else len(s) for s in sols]
        print(
            f"6r arm {k}: derived in {derive:.0f} s, {1e3 * np.median(times):.2f} ms a pose, "
            f"solutions {min(counts)}-{max(counts)} (mean {np.mean(counts):.1f})",
            flush=True,
        )


def _check_arm(robot: sweepik.Robot, Q: np.ndarray, ref: dict | None, n_numerical: int) -> dict:
    L = robot.length_scale
    T = robot.fk(Q)
    sweepik.solve(robot, T[0], limits=False)  # (compiles)
    single = []
    sols = []
    for Tk in T:
        t = time.perf_counter()
        sols.append(sweepik.solve(robot, Tk, limits=False))
        single.append(time.perf_counter() - t)
    t = time.perf_counter()
    sweepik.solve_many(robot, T, limits=False)
    batched = (time.perf_counter() - t) / len(T)
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
    out = {"recall": rec, "poses": len(Q), "wrong": wrong, "single_us": 1e6 * np.median(single),
           "batched_us": 1e6 * batched, "misses": misses}  # fmt: skip
    if ref is not None:
        rev = robot.is_revolute
        same = [r is not None and same_solution_set(s.q, r, rev, L) for s, r in zip(sols, ref["ssik"], strict=True)]
        out["ssik_same"] = int(np.sum(same))
        out["ssik_us"] = 1e6 * float(np.median(ref["seconds"]))
    if n_numerical:
        idx = np.linspace(0, len(Q) - 1, n_numerical).astype(int)
        same = [same_solution_set(sols[i].q, numerical_solutions(robot, T[i], n_starts=400, full_circle=True),
                                  robot.is_revolute, L) for i in idx]  # fmt: skip
        out["numerical_same"], out["numerical_poses"] = int(np.sum(same)), len(idx)
    return out


def check(args: argparse.Namespace) -> None:
    cache = _load(args.cache)
    arms = [("6r", k) for k in range(args.arms)]
    arms += [("5r1p" if k % 2 == 0 else "4r2p", k) for k in range(args.prismatic)]
    totals = {"recall": 0, "poses": 0, "wrong": 0}
    for kind, k in arms:
        robot = random_arm(kind, k)
        ref = cache.get((kind, k, args.n, args.singular))
        Q = ref["Q"] if ref is not None else poses_of(robot, args.n, args.singular, seed=k)
        r = _check_arm(robot, Q, ref, args.numerical)
        for key in totals:
            totals[key] += r[key]
        extra = ""
        if "ssik_same" in r:
            extra += f", ssik same {r['ssik_same']}/{r['poses']} (ssik {r['ssik_us']:.0f} us)"
        if "numerical_same" in r:
            extra += f", numerical same {r['numerical_same']}/{r['numerical_poses']}"
        print(
            f"{kind} arm {k}: recall {r['recall']}/{r['poses']}, wrong {r['wrong']}, single {r['single_us']:.0f} us, "
            f"batched {r['batched_us']:.0f} us{extra}",
            flush=True,
        )
        for q in r["misses"][:3]:
            print("   missed", np.round(q, 6).tolist())
    print(f"total: recall {totals['recall']}/{totals['poses']}, wrong {totals['wrong']}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("stage", choices=("refs", "check"))
    ap.add_argument("--arms", type=int, default=20)
    ap.add_argument("--prismatic", type=int, default=10)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--singular", type=int, default=50)
    ap.add_argument("--numerical", type=int, default=20)
    ap.add_argument("--cache", type=Path, default=DEFAULT_CACHE)
    args = ap.parse_args()
    refs(args) if args.stage == "refs" else check(args)


if __name__ == "__main__":
    main()
