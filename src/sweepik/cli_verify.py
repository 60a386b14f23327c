"""``sweepik verify`` (the paper's section 6) and ``sweepik bench`` (speed and memory)."""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from .cli_common import (
    DEFAULT_ROBOT,
    _add_json,
    _check_output_path,
    _nonnegative_int,
    _print_json,
    _subparser,
    _SubParsers,
)
from .robot_file import load_robot

#: Show progress only for runs longer than this (seconds), and only on a terminal.
PROGRESS_AFTER_S = 2.0


class _Progress:
    """A one-line progress indicator on stderr (terminals only), shown once a run exceeds a couple of seconds."""

    def __init__(self) -> None:
        self.start = time.monotonic()
        self.last = 0.0
        self.enabled = sys.stderr.isatty()

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if not self.enabled or now - self.start < PROGRESS_AFTER_S or (now - self.last < 0.2 and done < total):
            return
        self.last = now
        width = 30
        filled = int(width * done / max(total, 1))
        sys.stderr.write(f"\r{stage:<22} [{'#' * filled}{'.' * (width - filled)}] {done}/{total}")
        if done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()


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
        "--offgrid", type=_nonnegative_int, default=2000, metavar="N", help="random off-grid poses (default 2000)"
    )
    p.add_argument("--seed", type=_nonnegative_int, default=0, help="seed of the off-grid poses (default 0)")
    p.add_argument("--report", metavar="DIR", help="write a Markdown report with PNG figures into DIR")
    p.add_argument("--json", metavar="FILE", help="write the results as JSON to FILE ('-' for standard output)")


def cmd_verify(args: argparse.Namespace) -> int:
    from .verify import format_table, run_verify, write_report

    robot = load_robot(args.robot)
    if args.report:
        _check_output_path(args.report, directory=True)
    if args.json and args.json != "-":
        _check_output_path(args.json)
    result = run_verify(robot, args.strategy, offgrid=args.offgrid, seed=args.seed, progress=_Progress())
    if args.json == "-":
        _print_json(result)
    else:
        print(format_table(result))
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=2, allow_nan=False) + "\n")
            print(f"results written to {args.json}")
    if args.report:
        path = write_report(result, args.report)
        print(f"report written to {path}")
    return 0


def add_bench_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "bench",
        help="benchmarks: grid throughput, single-pose latency, paper strategy, peak memory",
        description="Measure sweepik on the bundled C-Arm (see docs/performance.md). Benchmarks are not tests.",
    )
    p.add_argument("--single", type=int, default=1000, metavar="N", help="poses for the latency test (0: skip)")
    p.add_argument("--paper", type=int, default=500, metavar="N", help="poses for the paper strategy (0: skip)")
    p.add_argument("--memory", type=int, default=100_000, metavar="N", help="poses for peak memory (0: skip)")
    p.add_argument("--repeats", type=int, default=3, metavar="N", help="repeats of the grid run (best is kept)")
    _add_json(p, "")


def cmd_bench(args: argparse.Namespace) -> int:
    from .bench import format_bench, run_bench

    result = run_bench(single=args.single, paper=args.paper, memory=args.memory, repeats=max(1, args.repeats))
    if args.json:
        _print_json(result)
    else:
        print(format_bench(result))
    return 0
