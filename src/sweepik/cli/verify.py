"""``sweepik verify`` (the paper's section 6) and ``sweepik bench`` (speed and memory)."""

from __future__ import annotations

import argparse
from typing import Any

from sweepik.cli.common import (
    DEFAULT_ROBOT,
    _add_json,
    _add_robot_options,
    _check_report_and_json,
    _count,
    _emit_results,
    _load_robot,
    _nonnegative_int,
    _print_json,
    _Progress,
    _subparser,
    _SubParsers,
)

#: Largest --offgrid: every off-grid pose's solutions are kept for the statistics (~8 kB each).
MAX_OFFGRID = 1_000_000
#: Largest pose counts of ``sweepik bench`` (latency, paper strategy, memory) and grid repeats.
MAX_BENCH_SINGLE = 1_000_000
MAX_BENCH_PAPER = 100_000
MAX_BENCH_MEMORY = 1_000_000
MAX_BENCH_REPEATS = 100


def add_verify_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "verify",
        help="reproduce the paper's verification (Tables 3 and 4, Figures 4 and 5)",
        description=(
            "Solve the paper's 15,900 grid poses (and all 16,500 with the singular ones), seeded off-grid poses "
            "and the rectangular trajectory; print the paper's figures beside sweepik's with the paper's strategy "
            "and the precise one."
        ),
    )
    p.add_argument("robot", nargs="?", default=DEFAULT_ROBOT, help=f"C-Arm-like robot (default: {DEFAULT_ROBOT})")
    p.add_argument("--strategy", choices=("paper", "precise", "both"), default="both", help="default: both")
    p.add_argument(
        "--offgrid",
        type=_count(0, MAX_OFFGRID),
        default=2000,
        metavar="N",
        help=f"random off-grid poses, 0 to {MAX_OFFGRID:,} (default 2000)",
    )
    p.add_argument("--seed", type=_nonnegative_int, default=0, help="seed of the off-grid poses (default 0)")
    p.add_argument("--report", metavar="DIR", help="write a Markdown report with PNG figures into DIR")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON to FILE ('-' for standard output)")
    _add_robot_options(p)


def cmd_verify(args: argparse.Namespace) -> int:
    from sweepik.experiments.verify import run_verify
    from sweepik.experiments.verify_report import format_table, write_report

    _check_report_and_json(args)
    robot = _load_robot(args.robot, args)
    progress = _Progress()
    try:
        result = run_verify(robot, args.strategy, offgrid=args.offgrid, seed=args.seed, progress=progress)
    finally:
        progress.close()
    _emit_results(args, result, format_table(result), lambda d: write_report(result, d))
    return 0


def add_bench_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "bench",
        help="benchmarks: grid throughput, single-pose latency, paper strategy, peak memory; --arms: every arm",
        description="Measure sweepik on the bundled C-Arm (grid, single pose, paper strategy, memory), then on every "
        "bundled arm side by side with the other all-solutions solvers installed (pip install 'sweepik[bench]'); "
        "--arms runs the per-arm part alone. See docs/performance.md. Benchmarks are not tests.",
    )
    p.add_argument(
        "--arms",
        nargs="*",
        metavar="ROBOT",
        default=None,
        help="only the per-arm benchmark, on these arms (bundled names or robot files; none given: every bundled "
        "arm); without --arms, the C-Arm's four benchmarks run first, then every bundled arm",
    )
    p.add_argument(
        "--batch",
        type=_count(8, MAX_BENCH_MEMORY),
        default=2000,
        metavar="N",
        help="poses of the batched run per arm (default 2000)",
    )
    p.add_argument(
        "--single",
        type=_count(0, MAX_BENCH_SINGLE),
        default=None,
        metavar="N",
        help=f"poses for the latency test, up to {MAX_BENCH_SINGLE:,} (0: skip; default 1000, with --arms 300)",
    )
    p.add_argument(
        "--paper",
        type=_count(0, MAX_BENCH_PAPER),
        default=500,
        metavar="N",
        help=f"poses for the paper strategy, up to {MAX_BENCH_PAPER:,} (0: skip; default 500)",
    )
    p.add_argument(
        "--memory",
        type=_count(0, MAX_BENCH_MEMORY),
        default=None,
        metavar="N",
        help=f"poses for peak memory, up to {MAX_BENCH_MEMORY:,} (0: skip; default 100,000; with --arms 10,000 per "
        "arm)",
    )
    p.add_argument(
        "--repeats",
        type=_count(1, MAX_BENCH_REPEATS),
        default=3,
        metavar="N",
        help=f"repeats of the grid run, 1 to {MAX_BENCH_REPEATS} (best is kept; default 3)",
    )
    _add_robot_options(p)
    _add_json(p, "")


def cmd_bench(args: argparse.Namespace) -> int:
    from sweepik.experiments.bench import bench_arms, format_arms, format_bench, run_bench

    progress = _Progress()
    arms = args.arms is not None
    single = args.single if args.single is not None else (300 if arms else 1000)
    memory = args.memory if args.memory is not None else (10_000 if arms else 100_000)
    try:
        if arms:
            names: list[Any] = list(args.arms)
            if args.base_link or args.tip_link:  # URDF files with a chosen chain: loaded here, timed as Robots
                names = [_load_robot(n, args) for n in names]
            result = bench_arms(names, single, args.batch, memory, args.repeats, progress)
        else:
            result = run_bench(single, args.paper, memory, args.repeats, progress, batch=args.batch)
    finally:
        progress.close()
    if args.json:
        _print_json(result)
    else:
        print(format_arms(result) if arms else format_bench(result))
    return 0
