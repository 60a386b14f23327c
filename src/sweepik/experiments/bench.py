"""Benchmarks (``sweepik bench``): speed and memory of the solver.

On the bundled C-Arm (the default):
(a) ``solve_many`` on the paper's 15,900 grid poses, precise strategy: wall time and us per pose;
(b) single-pose ``solve`` latency, median and 95th percentile over random in-limit poses;
(c) the paper strategy, seconds per pose (on a subset of the grid);
(d) peak memory (resident set) of ``solve_many`` on 100,000 random poses, measured in a child process.

On every bundled arm (``sweepik bench --arms``, :func:`bench_arms`): single-pose median, batched time per pose and
peak memory, side by side with the other all-solutions solvers installed (:mod:`sweepik.experiments.peers`) on the same
poses,
timed in turn with them (``_side_by_side``), each row flagged against the speed targets (``ARM_TARGETS``).

Benchmarks are not tests: nothing here asserts a speed.
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.experiments.verify import grid_configurations, random_configurations
from sweepik.io.robot_file import load_robot
from sweepik.model.origin_axis import hold_joints
from sweepik.model.robot import Robot
from sweepik.solving import Progress, solve, solve_many

Array = NDArray[np.float64]

#: The paper's figure: 0.098 s per pose in Matlab.
PAPER_SECONDS_PER_POSE = 0.098

_MEMORY_SCRIPT = """
import resource, sys, json
import numpy as np


def peak_mib():
    # this process's own peak (VmHWM, Linux: the high-water mark of its memory since exec); ru_maxrss would also
    # count the parent's resident set at fork, which exec carries over into it
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


import sweepik
from sweepik.experiments.verify import random_configurations
robot = sweepik.load_robot({robot!r})
rng = np.random.default_rng(0)
# poses made a slice at a time: the forward kinematics of a million configurations at once would set the peak
sizes = [min(50_000, {n} - s) for s in range(0, {n}, 50_000)]
poses = np.concatenate([robot.fk(random_configurations(robot, k, rng)) for k in sizes])
base = peak_mib()
sols = sweepik.solve_many(robot, poses)
peak = peak_mib()
print(json.dumps({{"peak_rss_mib": peak, "before_solve_mib": base, "poses": len(sols)}}))
"""


_STARTUP_SCRIPT = """
import time
t0 = time.perf_counter()
import numpy as np
import sweepik
t1 = time.perf_counter()
robot = sweepik.load_robot({robot!r})
q = np.clip(np.zeros(robot.n_joints), robot.lower, robot.upper) + 0.3 * (robot.upper - robot.lower > 0.6)
sweepik.solve(robot, robot.fk(q))
t2 = time.perf_counter()
print(t1 - t0, t2 - t1)
"""


def bench_startup(robot: str = "carm", repeats: int = 3) -> dict[str, Any]:
    """(e) A new process: seconds to ``import sweepik`` and then to its first ``solve`` (compiled kernels loaded
    from the disk cache; the first run after installation compiles them instead: it is run once before timing),
    best of ``repeats`` child processes."""
    runs = []
    for _ in range(repeats + 1):
        out = subprocess.run(
            [sys.executable, "-c", _STARTUP_SCRIPT.format(robot=robot)], capture_output=True, text=True, check=True
        )
        runs.append([float(x) for x in out.stdout.split()])
    imp, first = min(runs[1:], key=sum)
    return {"robot": robot, "import_s": imp, "first_solve_s": first, "total_s": imp + first}


def _no_progress(stage: str, done: int, total: int) -> None:
    pass


def _latencies(fn: Any, poses: Array, progress: Progress = _no_progress, stage: str = "") -> Array:
    """Seconds of ``fn(T)`` for each pose (after one warm-up call); ``progress`` every 100 poses, outside the
    timed region."""
    fn(poses[0])
    lat = np.empty(len(poses))
    for i, T in enumerate(poses):
        t0 = time.perf_counter()
        fn(T)
        lat[i] = time.perf_counter() - t0
        if (i + 1) % 100 == 0 or i + 1 == len(poses):
            progress(stage, i + 1, len(poses))
    return lat


def _best_seconds(
    fn: Any, poses: Array, repeats: int, warm: int = 8, progress: Progress = _no_progress, stage: str = ""
) -> float:
    """Best of ``repeats`` wall times of ``fn(poses)`` (after a warm-up on ``warm`` poses: imports, caches)."""
    fn(poses[:warm])
    best = np.inf
    progress(stage, 0, repeats)
    for r in range(repeats):
        t0 = time.perf_counter()
        fn(poses)
        best = min(best, time.perf_counter() - t0)
        progress(stage, r + 1, repeats)
    return float(best)


def bench_grid(repeats: int = 3, progress: Progress = _no_progress) -> dict[str, Any]:
    """(a) Best of ``repeats`` wall times of ``solve_many`` on the 15,900 grid poses (precise)."""
    robot = load_robot("carm")
    poses = robot.fk(grid_configurations(include_singular=False))
    best = _best_seconds(lambda P: solve_many(robot, P), poses, repeats, 64, progress, "bench: grid")
    return {
        "poses": len(poses),
        "seconds": best,
        "us_per_pose": best / len(poses) * 1e6,
        "speedup_vs_paper": PAPER_SECONDS_PER_POSE * len(poses) / best,
    }


def bench_single(count: int = 1000, seed: int = 0, progress: Progress = _no_progress) -> dict[str, Any]:
    """(b) Latency of ``solve`` on ``count`` random in-limit poses: median and 95th percentile."""
    robot = load_robot("carm")
    poses = robot.fk(random_configurations(robot, count, np.random.default_rng(seed)))
    lat = _latencies(lambda T: solve(robot, T), poses, progress, "bench: single pose")
    return {"poses": count, "median_us": float(np.median(lat) * 1e6), "p95_us": float(np.percentile(lat, 95) * 1e6)}


def bench_paper(count: int = 500) -> dict[str, Any]:
    """(c) The paper strategy on ``count`` grid poses (every 31st): seconds per pose."""
    robot = load_robot("carm")
    q = grid_configurations(include_singular=False)
    poses = robot.fk(q[:: max(1, len(q) // count)][:count])
    t0 = time.perf_counter()
    solve_many(robot, poses, strategy="paper")
    dt = time.perf_counter() - t0
    return {"poses": len(poses), "seconds_per_pose": dt / len(poses), "paper_seconds_per_pose": PAPER_SECONDS_PER_POSE}


def bench_memory(count: int = 100_000, robot: str = "carm") -> dict[str, Any]:
    """(d) Peak resident memory of a child process running ``solve_many`` on ``count`` random poses of ``robot``
    (a bundled name or a robot file): the child's own high-water mark (``VmHWM`` on Linux), not ``ru_maxrss``,
    which after fork and exec also holds the parent's resident set at the fork (a parent that had grown to 2 GiB
    made every child report 2 GiB)."""
    out = subprocess.run(
        [sys.executable, "-c", _MEMORY_SCRIPT.format(n=count, robot=robot)], capture_output=True, text=True, check=True
    )
    return dict(json.loads(out.stdout.strip().splitlines()[-1]))


def run_bench(
    single: int = 1000,
    paper: int = 500,
    memory: int = 100_000,
    repeats: int = 3,
    progress: Progress | None = None,
    arms: bool = True,
    batch: int = 2000,
) -> dict[str, Any]:
    """The C-Arm's four benchmarks and the start-up of a new process (:func:`bench_startup`), then (``arms``)
    :func:`bench_arms` on every bundled arm with ``batch`` poses per batched run, ``min(single, 300)`` single poses
    and ``min(memory, 10,000)`` poses for peak memory. Sizes can be reduced for a quick look (0 skips a benchmark).
    ``progress(stage, done, total)`` is called as they advance (a memory benchmark, one child process, reports only
    its start and end).
    """
    report = progress or _no_progress
    result: dict[str, Any] = {"grid_precise": bench_grid(repeats, report)}
    if single:
        result["single_pose"] = bench_single(single, progress=report)
    if paper:
        report("bench: paper strategy", 0, 1)
        result["paper_strategy"] = bench_paper(paper)
        report("bench: paper strategy", 1, 1)
    if memory:
        report("bench: memory", 0, 1)
        result["memory"] = bench_memory(memory)
        report("bench: memory", 1, 1)
    report("bench: start-up", 0, 1)
    result["startup"] = bench_startup(repeats=repeats)
    report("bench: start-up", 1, 1)
    if arms:
        result.update(bench_arms(None, min(single, 300), batch, min(memory, 10_000), repeats, report))
    return result


def format_bench(result: dict[str, Any]) -> str:
    """Human-readable table of ``run_bench``'s result, with the issue's targets."""
    rows = []
    g = result["grid_precise"]
    rows.append(
        (
            "(a) 15,900 grid poses, precise",
            f"{g['seconds']:.3f} s ({g['us_per_pose']:.0f} us/pose, {g['speedup_vs_paper']:.0f}x the paper)",
            "<= 0.35 s",
        )
    )
    if "single_pose" in result:
        s = result["single_pose"]
        rows.append(
            ("(b) single-pose solve", f"median {s['median_us']:.0f} us, p95 {s['p95_us']:.0f} us", "median <= 150 us")
        )
    if "paper_strategy" in result:
        p = result["paper_strategy"]
        rows.append(("(c) paper strategy", f"{p['seconds_per_pose'] * 1e3:.2f} ms/pose (paper: 98 ms in Matlab)", ""))
    if "memory" in result:
        m = result["memory"]
        rows.append((f"(d) peak memory, {m['poses']:,} poses", f"{m['peak_rss_mib']:.0f} MiB resident", "<= 1024 MiB"))
    if "startup" in result:
        u = result["startup"]
        rows.append(
            (
                "(e) new process: import + first solve",
                f"{u['total_s']:.2f} s ({u['import_s']:.2f} s import, {u['first_solve_s']:.2f} s first solve)",
                "<= 1 s",
            )
        )
    w0 = max(len(r[0]) for r in rows)
    w1 = max(len(r[1]) for r in rows)
    lines = [f"{'benchmark':<{w0}}  {'measured':<{w1}}  target", "-" * (w0 + w1 + 20)]
    lines += [f"{a:<{w0}}  {b:<{w1}}  {c}" for a, b, c in rows]
    if "arms" in result:
        lines += ["", "every bundled arm:", format_arms(result)]
    return "\n".join(lines)


#: Targets of the speed issue per kind of arm: closed forms batched (us per pose); the C-Arm single and batched (us
#: per pose); every swept arm that ssik solves, against ssik's time on the same poses in the same run: single-pose
#: median <= 1/3 of ssik's, batched time per pose <= 1/10 of ssik's (ssik has no batch call: its batch is a loop of
#: single calls); an arm of the general method (issue 37): single <= ssik's, batched <= 1/3. ssik runs at its best
#: (``sweepik.experiments.peers.ssik_solver``: its prebuilt artifact of the arm when it ships one, else its C++
#: backend on the arm's chain with the per-arm precompute done once) and answers what sweepik's default answers
#: (joint limits applied, one configuration per branch, not every 2 pi winding). ssik solves 6R arms only: the C-Arm
#: and other arms with a prismatic joint are judged by their absolute targets alone.
ARM_TARGETS = {
    "closed_batched_us": 10.0,
    "general_single_ratio": 1.0,  # (the general method against ssik's general solver: issue 37)
    "general_batched_ratio": 1.0 / 3.0,
    "carm_single_us": 150.0,
    "carm_batched_us": 22.0,
    "ssik_single_ratio": 1.0 / 3.0,
    "ssik_batched_ratio": 1.0 / 10.0,
}


#: Poses a solver solves one by one before the next solver's turn (``_side_by_side``).
SINGLE_BLOCK = 25


def _side_by_side(
    solvers: dict[Any, tuple[Any, Any]], poses: Array, single: int, batch: int, repeats: int
) -> dict[Any, dict[str, Any]]:
    """``{label: {"single_us", "batched_us"}}`` of ``solvers`` (``{label: (one pose -> ..., poses -> ...)}``) on the
    same poses, timed in turn rather than one after the other: the latency test's poses in blocks of ``SINGLE_BLOCK``,
    each block by each solver in turn (median of ``single`` poses; None for 0), each batched run of ``batch`` poses
    likewise (best of ``repeats``). The machine's speed drifts over minutes (by up to ~1.8x on the development
    machine); interleaved, the ratio of two solvers' times is that of the same moments. (Pose by pose, each solver
    would evict the other's code and data from the caches between two calls: blocks keep single calls warm.)"""
    lat = {k: np.empty(single) for k in solvers}
    for one, _ in solvers.values():  # (warm-up: imports, compilation, caches)
        if single:
            one(poses[0])
    for s in range(0, single, SINGLE_BLOCK):
        block = poses[s : min(s + SINGLE_BLOCK, single)]
        for k, (one, _) in solvers.items():
            for i, T in enumerate(block, s):
                t0 = time.perf_counter()
                one(T)
                lat[k][i] = time.perf_counter() - t0
    for _, many in solvers.values():
        many(poses[:8])
    best = dict.fromkeys(solvers, np.inf)
    for _ in range(repeats):
        for k, (_, many) in solvers.items():
            t0 = time.perf_counter()
            many(poses[:batch])
            best[k] = min(best[k], time.perf_counter() - t0)
    return {
        k: {
            "single_us": float(np.median(lat[k]) * 1e6) if single else None,
            "batched_us": best[k] / batch * 1e6,
        }
        for k in solvers
    }


def _flags(
    name: str, kind: str, cell: dict[str, Any], peers: dict[str, dict[str, Any]], ssik: dict[str, Any]
) -> list[str]:
    """The targets a row misses (plain words); ``kind``: "closed", "sweep" or "general" (the general method); ``ssik``
    is ``sweepik.experiments.peers.ssik_status`` of the arm."""
    out = []
    if kind == "closed" and cell["batched_us"] > ARM_TARGETS["closed_batched_us"]:
        out.append(f"closed form batched > {ARM_TARGETS['closed_batched_us']:g} us")
    if name == "carm":
        if cell["single_us"] > ARM_TARGETS["carm_single_us"]:
            out.append(f"single > {ARM_TARGETS['carm_single_us']:g} us")
        if cell["batched_us"] > ARM_TARGETS["carm_batched_us"]:
            out.append(f"batched > {ARM_TARGETS['carm_batched_us']:g} us")
    for peer, t in peers.items():
        if peer == "ssik" and kind != "closed":
            continue  # a swept arm and the general method have ratio targets below
        if t["single_us"] < cell["single_us"] or t["batched_us"] < cell["batched_us"]:
            out.append(f"slower than {peer}")
    if kind != "closed":
        theirs = peers.get("ssik")
        if theirs is not None:
            single, batched = (
                (ARM_TARGETS["general_single_ratio"], ARM_TARGETS["general_batched_ratio"])
                if kind == "general"
                else (ARM_TARGETS["ssik_single_ratio"], ARM_TARGETS["ssik_batched_ratio"])
            )
            if cell["single_us"] > single * theirs["single_us"]:
                out.append("single > ssik" if single == 1.0 else f"single > 1/{1 / single:.0f} of ssik")
            if cell["batched_us"] > batched * theirs["batched_us"]:
                out.append(f"batched > 1/{1 / batched:.0f} of ssik")
        elif ssik.get("why") == "not installed":
            out.append("ssik not installed: its targets not measured")
    return out


def bench_arms(
    names: list[str | Robot] | None = None,
    single: int = 300,
    batch: int = 2000,
    memory: int = 10_000,
    repeats: int = 3,
    progress: Progress = _no_progress,
) -> dict[str, Any]:
    """Per arm (every bundled one by default; names, robot files or Robots): sweepik's plan, single-pose median (us),
    batched time per pose (best of ``repeats``, us), peak memory of ``solve_many`` on ``memory`` poses (a child
    process; 0 skips it), the installed peers on the same poses (raw calls: their answers are not FK-checked),
    whether and how ssik solves the arm (``"ssik"``: ``sweepik.experiments.peers.ssik_status``), and the targets missed.
    Random in-limit configurations, seed 1."""
    from sweepik.experiments.peers import peers_for, ssik_status
    from sweepik.io.robot_file import bundled_robots
    from sweepik.reductions.analysis import analyze

    rows: dict[str, Any] = {}
    arms = list(names) if names else list(bundled_robots())
    robots = [load_robot(n) for n in arms]  # bad names fail before anything is timed
    for k, (arm, robot) in enumerate(zip(arms, robots, strict=True)):
        name = arm if isinstance(arm, str) else robot.name
        progress("bench: arms", k, len(arms))
        q = random_configurations(robot, max(single, batch, 8), np.random.default_rng(1))
        locked = _bench_lock(robot)
        for j, v in (locked or {}).items():
            q[:, j] = v
        poses = robot.fk(q)
        plan = analyze(robot, locked=locked)["chosen"]
        if plan is None:
            rows[name] = {"plan": "none", "sweepik": None, "peers": {}}
            continue
        closed = bool(plan["closed_form"])
        general = plan["family"] == "general"
        label = "general method" if general else "closed form" if closed else f"sweep joint {plan['free_joint_number']}"
        row: dict[str, Any] = {"plan": label}
        if locked:
            row["plan"] += " (" + ", ".join(f"{robot.joint_names[j]} locked" for j in locked) + ")"
        variants: dict[str, dict[str, Any]] = {"sweepik": {"reduction": "auto", "locked": locked}}
        if robot.default_reduction:
            variants[f"sweepik {robot.default_reduction}"] = {"reduction": robot.default_reduction}
        solvers = {
            label: (
                lambda T, kw=kw, r=robot: solve(r, T, **kw),
                lambda Ts, kw=kw, r=robot: solve_many(r, Ts, **kw),
            )
            for label, kw in variants.items()
        }
        solved = hold_joints(robot, locked).arm if locked else robot
        row["ssik"] = ssik_status(solved)
        theirs = peers_for(solved)
        timed = _side_by_side({**solvers, **{("peer", p): f for p, f in theirs.items()}}, poses, single, batch, repeats)
        row.update({label: timed[label] for label in variants})
        fastest = min((row[v] for v in variants), key=lambda c: c["batched_us"])
        peers = {peer: timed[("peer", peer)] for peer in theirs}
        row["peers"] = peers
        if memory and not locked and isinstance(arm, str):  # (the child process loads the arm by name or path)
            row["peak_rss_mib"] = bench_memory(memory, arm)["peak_rss_mib"]
        if single:
            kind = "general" if general else "closed" if closed else "sweep"
            row["misses"] = _flags(name, kind, fastest, peers, row["ssik"])
        rows[name] = row
    progress("bench: arms", len(arms), len(arms))
    return {"arms": rows, "single_poses": single, "batch_poses": batch, "memory_poses": memory}


def _bench_lock(robot: Robot) -> dict[int, float] | None:
    """A seven-joint arm is timed with one joint locked: the first whose lock (at a generic value) gives a closed
    form, else the first that gives a sweep (see ``analysis.lock_options``); None for a six-joint arm."""
    from sweepik.reductions.analysis import lock_options

    options = [(lock["joint"], v) for lock in lock_options(robot) for v in lock["values"][-1:] if v["chosen"]]
    if not options:
        return None
    j, v = min(options, key=lambda o: not o[1]["chosen"]["closed_form"])
    return {j: float(v["value"])}


def format_arms(result: dict[str, Any]) -> str:
    """Human-readable table of ``bench_arms``'s result."""
    peers = sorted({p for r in result["arms"].values() for p in r["peers"]})
    if "ssik" not in peers and any("ssik" in r for r in result["arms"].values()):
        peers.append("ssik")  # the swept arms' yardstick: its column says why it is absent (not 6R, not installed)
    head = ["arm", "plan", "sweepik single/batched [us]"] + [f"{p} single/batched [us]" for p in peers]
    head += ["peak MiB", "misses"]
    lines = []

    def cell(c: dict[str, Any] | None) -> str:
        if c is None:
            return "-"
        single = "-" if c["single_us"] is None else f"{c['single_us']:.0f}"
        return f"{single} / {c['batched_us']:.1f}"

    for name, r in result["arms"].items():
        ours = cell(r["sweepik"])
        extra = [k for k in r if k.startswith("sweepik ")]
        if extra:
            ours += "; " + ", ".join(f"{k[8:]}: {cell(r[k])}" for k in extra)
        mem = f"{r['peak_rss_mib']:.0f}" if "peak_rss_mib" in r else "-"
        theirs = [cell(r["peers"].get(p)) for p in peers]
        if "ssik" in peers:
            status = r.get("ssik", {})
            k = peers.index("ssik")
            if status.get("solves") and "ssik" in r["peers"]:
                theirs[k] += f" ({status['source']})"
            elif status.get("why"):
                theirs[k] = f"- ({status['why']})"
        lines.append([name, r["plan"], ours, *theirs, mem, "; ".join(r.get("misses", []))])
    widths = [max(len(x) for x in col) for col in zip(head, *lines, strict=True)]
    out = ["  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True)).rstrip()]
    out.append("-" * (sum(widths) + 2 * (len(widths) - 1)))
    out += ["  ".join(v.ljust(w) for v, w in zip(line, widths, strict=True)).rstrip() for line in lines]
    return "\n".join(out)
