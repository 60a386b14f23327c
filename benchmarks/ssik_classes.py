"""sweepik against ssik 8.2's prebuilt catalogue, class by class (issue 39's table): single solves, median per arm,
then the median of the arms' medians per class. Run from the repository root (``pip install -e '.[bench]'``).

    python benchmarks/ssik_classes.py [--n 50] [--arms irb120_ik ...] [--seed 0]

Every six-joint arm of ``ssik.list_arms()`` is rebuilt in sweepik (``tests/catalogue.robot_from_ssik``, metres, the
artifact's limits) and classed by the plan sweepik chooses (``sweepik.analyze``): a closed form with a spherical
wrist, the UR type (three parallel axes), another closed form, a sweep, the general method. Per arm, ``--n`` fresh
configurations uniform within the limits; each pose is solved once by ``sweepik.solve`` (the defaults: limits on),
by the artifact's ``solve`` (limits on, no 2 pi windings: as sweepik's defaults) and by EAIK and IK-Geo where they
apply (closed forms); the first five poses of each solver are not timed (kernels load). Prints one line per arm,
then the class medians. Benchmarks are not tests: timings on a shared machine vary by +-10-25 %.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from catalogue import robot_from_ssik, ssik_module  # noqa: E402

import sweepik  # noqa: E402
from sweepik.experiments.peers import peers_for  # noqa: E402

WARM = 5
#: The closed-form solvers timed beside them where they apply (``peers.peers_for``).
PEERS = ("EAIK", "IK-Geo")


def arm_class(robot: sweepik.Robot) -> str:
    """The class of the plan sweepik chooses for ``robot``."""
    chosen = sweepik.analyze(robot)["chosen"]
    if chosen is None:
        return "refused"
    if chosen["family"] == "general":
        return "general"
    if not chosen["closed_form"]:
        return "swept"
    return {"wrist": "spherical wrist", "parallel": "UR type"}.get(chosen["family"], "other closed form")


def median_us(solve: Any, poses: np.ndarray) -> float:
    """The median time of ``solve(T)`` over ``poses`` after the first ``WARM``, in microseconds."""
    times = []
    for i, T in enumerate(poses):
        t0 = time.perf_counter()
        solve(T)
        if i >= WARM:
            times.append(time.perf_counter() - t0)
    return 1e6 * statistics.median(times)


def main() -> None:
    import ssik

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--arms", nargs="*", default=None)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    names = [a.name for a in ssik.list_arms() if a.dof == 6 and (args.arms is None or a.name in args.arms)]
    by_class: dict[str, list[tuple[float, float, float | None]]] = {}
    for name in names:
        robot = robot_from_ssik(name)
        if not robot.is_revolute.all():
            continue
        try:
            kind = arm_class(robot)
        except sweepik.SweepikError:
            kind = "refused"
        if kind == "refused":
            continue
        m = ssik_module(name)
        lo, hi = np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi)
        poses = robot.fk(rng.uniform(lo, hi, (args.n + WARM, 6)))
        ours = median_us(lambda T: sweepik.solve(robot, T), poses)  # noqa: B023
        theirs = median_us(lambda T: m.solve(T, enumerate_windings=False), poses)  # noqa: B023
        peers = peers_for(robot)
        others = {p: median_us(peers[p][0], poses) for p in PEERS if p in peers}
        by_class.setdefault(kind, []).append((ours, theirs, others))
        extra = "".join(f", {p} {t:.1f}" for p, t in others.items())
        print(f"{name:28s} {kind:18s} sweepik {ours:8.1f} us, ssik {theirs:8.1f} us (x{theirs / ours:.2f}){extra}")
        sys.stdout.flush()
    print()
    for kind, rows in sorted(by_class.items()):
        ours = statistics.median(r[0] for r in rows)
        theirs = statistics.median(r[1] for r in rows)
        extra = ""
        for p in PEERS:
            ts = [r[2][p] for r in rows if p in r[2]]
            extra += f", {p} {statistics.median(ts):.1f} us ({len(ts)} arms)" if ts else ""
        print(f"{kind} ({len(rows)} arms): sweepik {ours:.1f} us, ssik {theirs:.1f} us: 1/{theirs / ours:.2f}{extra}")


if __name__ == "__main__":
    main()
