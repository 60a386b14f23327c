"""Whether two versions of sweepik give the same solutions: solve a fixed set of poses, save the answers, and compare
another version's answers with them. A check for a change that should not move results (or should move them only at
rounding level), not a test: it takes minutes. Run from the repository root (it reads the random arms of
``tests/test_any_arm.py``).

    git worktree add /tmp/old <commit>
    PYTHONPATH=/tmp/old/src python benchmarks/same_solutions.py save /tmp/old.pkl
    python benchmarks/same_solutions.py compare /tmp/old.pkl

The poses: on every bundled six-joint arm and two random arms of every ``test_any_arm`` family, 250 random in-limit
configurations' poses, half of them with one to three joints set to 0, +-90 deg or 180 deg (slides to 0), mostly on
the singular set; solved batched with and without limits, and the first 40 one by one; then the C-Arm's 15,900 grid
poses. ``compare`` prints the
poses whose solution counts, multiplicities or families differ, and the largest difference of matched solutions,
simple and multiple roots apart (rounding-level differences are expected from any change of arithmetic; a multiple
root is pinned down only to its flat stretch, ~1e-5 of theta*'s range).
"""

from __future__ import annotations

import glob
import os
import pickle
import sys

import numpy as np

import sweepik
from sweepik.experiments.bench import grid_configurations

sys.path.insert(0, "tests")
from test_any_arm import FAMILIES, _arm  # noqa: E402

SPECIAL = (0.0, np.pi / 2, -np.pi / 2, np.pi)


def configurations(robot: sweepik.Robot, n: int) -> np.ndarray:
    rng = np.random.default_rng(11)
    q = rng.uniform(robot.lower, robot.upper, (n, robot.n_joints))
    for row in q[n // 2 :]:
        for j in rng.choice(robot.n_joints, rng.integers(1, 4), replace=False):
            row[j] = SPECIAL[rng.integers(4)] if robot.is_revolute[j] else 0.0
    return q


def arms() -> list[tuple[str, sweepik.Robot]]:
    out = []
    for path in sorted(glob.glob("src/sweepik/io/robots/*.toml")):
        robot = sweepik.load_robot(os.path.basename(path)[:-5])
        if robot.n_joints == 6:
            out.append((robot.name, robot))
    for family in sorted(FAMILIES):
        for seed in range(2):
            rng = np.random.default_rng(seed + 300)
            convention = "modified" if family == "rail_pair" else "standard"
            out.append((f"{family}[{seed}]", _arm(FAMILIES[family](rng), rng, convention)))
    return out


def record(solutions: sweepik.Solutions) -> tuple[np.ndarray, np.ndarray, list[tuple[float, float]]]:
    return solutions.q, solutions.multiplicity, [f.interval for f in solutions.families]


def solve_all() -> dict[tuple[str, object], object]:
    n = 250
    out: dict[tuple[str, object], object] = {}
    for name, robot in arms():
        T = robot.fk(configurations(robot, n))
        try:
            for limits in (True, False):
                out[(name, limits)] = [record(s) for s in sweepik.solve_many(robot, T, limits=limits)]
            out[(name, "single")] = [record(sweepik.solve(robot, t)) for t in T[:40]]
        except sweepik.SweepikError as e:
            out[(name, "error")] = repr(e)
        print(name, file=sys.stderr, flush=True)
    carm = sweepik.load_robot("carm")
    out[("grid", True)] = [record(s) for s in sweepik.solve_many(carm, carm.fk(grid_configurations(True)))]
    return out


def _matched(q0: np.ndarray, q1: np.ndarray) -> np.ndarray:
    """Each solution's largest joint difference (angles modulo 2 pi) from its nearest in the other set."""
    d = np.abs(q0[:, None, :] - q1[None, :, :])
    d = np.minimum(d, np.abs(2 * np.pi - d))  # (slides differ by far more than 2 pi where they differ)
    return d.max(axis=-1).min(axis=1)


def compare(old: dict[tuple[str, object], object], new: dict[tuple[str, object], object]) -> int:
    differing, worst = 0, {"simple": 0.0, "multiple": 0.0}
    for key, answers in new.items():
        before = old.get(key)
        if isinstance(answers, str) or isinstance(before, str) or before is None:
            if answers != before:
                differing += 1
                print(key, "before:", before if isinstance(before, str) else "solved", "now:", answers)
            continue
        for i, ((q1, m1, f1), (q0, m0, f0)) in enumerate(zip(answers, before, strict=True)):  # type: ignore[arg-type]
            if len(q0) != len(q1) or len(f0) != len(f1) or sorted(m0.tolist()) != sorted(m1.tolist()):
                differing += 1
                print(key, i, f"solutions {len(q0)} -> {len(q1)}, families {len(f0)} -> {len(f1)}, "
                      f"multiplicities {sorted(m0.tolist())} -> {sorted(m1.tolist())}")  # fmt: skip
            elif len(q0):
                for m, d in ((m0, _matched(q0, q1)), (m1, _matched(q1, q0))):
                    worst["simple"] = max(worst["simple"], float(d[m == 1].max(initial=0.0)))
                    worst["multiple"] = max(worst["multiple"], float(d[m > 1].max(initial=0.0)))
    # (a root of multiplicity >= 2 is pinned down only to its flat stretch: ~1e-5 of theta*'s range)
    print(f"poses differing in counts, multiplicities or families: {differing}; largest difference of matched "
          f"solutions: {worst['simple']:.1e} (simple roots), {worst['multiple']:.1e} (multiple roots)")  # fmt: skip
    return differing


def main() -> None:
    if len(sys.argv) != 3 or sys.argv[1] not in ("save", "compare"):
        sys.exit(__doc__)
    answers = solve_all()
    if sys.argv[1] == "save":
        with open(sys.argv[2], "wb") as f:
            pickle.dump(answers, f)
    else:
        with open(sys.argv[2], "rb") as f:
            compare(pickle.load(f), answers)


if __name__ == "__main__":
    main()
