"""``sweepik design``: compare candidate mechanisms (IK, workspace, holding torques, manipulability)."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from sweepik.cli.common import (
    CliInputError,
    _add_robot_options,
    _check_report_and_json,
    _count,
    _emit_results,
    _load_robot,
    _nonnegative_int,
    _parse_numbers,
    _Progress,
    _subparser,
    _SubParsers,
)

__all__ = ["add_design_parser", "cmd_design"]


def add_design_parser(sub: _SubParsers) -> None:
    from sweepik.experiments.design import MAX_DESIGN_SAMPLES, MAX_WORKSPACE_SAMPLES

    p = _subparser(
        sub,
        "design",
        help="compare candidate arms: IK, workspace, holding torques with a payload, manipulability",
        description=(
            "Measure each candidate arm over one task (by default poses of random in-limit configurations, an "
            "equal share from each candidate): its IK decomposition and speed, solutions per pose, reachable "
            "volume, the static torques holding a payload at the tool, and the distance to singularities; print "
            "the side-by-side table and which design wins on what. Lengths (--payload-com, --region, --poses) "
            "are in the first candidate's length unit. See docs/design.md."
        ),
    )
    p.add_argument("robots", nargs="+", metavar="ROBOT", help="candidate arms: bundled names or robot files")
    p.add_argument("--payload", type=float, default=0.0, metavar="KG", help="payload held at the tool, kg (default 0)")
    p.add_argument(
        "--payload-com",
        nargs=3,
        metavar=("X", "Y", "Z"),
        help="payload's centre of mass in the tool frame (default: the tool origin)",
    )
    p.add_argument("--no-link-masses", action="store_true", help="ignore the link masses of the robot files")
    p.add_argument(
        "--samples",
        type=_count(1, MAX_DESIGN_SAMPLES),
        default=2000,
        metavar="N",
        help="task poses drawn from random in-limit configurations (default 2000)",
    )
    p.add_argument(
        "--workspace-samples",
        type=_count(1000, MAX_WORKSPACE_SAMPLES),
        default=200_000,
        metavar="N",
        help="random configurations per candidate for the volume estimate (default 200000)",
    )
    p.add_argument("--poses", metavar="FILE", help="the task's poses instead (CSV, NPY or JSON; see docs/cli.md)")
    p.add_argument(
        "--region",
        nargs=6,
        metavar=("XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"),
        help="keep only task poses whose position lies in this box (world frame)",
    )
    p.add_argument("--seed", type=_nonnegative_int, default=0, help="random seed (default 0)")
    p.add_argument("--report", metavar="DIR", help="write report.md with PNG figures into DIR")
    p.add_argument("--json", metavar="FILE", help="write every number as JSON to FILE ('-' for standard output)")
    _add_robot_options(p)


def cmd_design(args: argparse.Namespace) -> int:
    from sweepik.experiments.design import compare_designs
    from sweepik.experiments.design_report import format_table, write_design_report

    _check_report_and_json(args)
    robots = [_load_robot(name, args) for name in args.robots]
    kwargs: dict[str, Any] = {}
    if args.payload_com is not None:
        kwargs["payload_com"] = _parse_numbers(args.payload_com, ["--payload-com X", "Y", "Z"])
    if args.region is not None:
        kwargs["region"] = _parse_numbers(args.region, ["XMIN", "XMAX", "YMIN", "YMAX", "ZMIN", "ZMAX"]).reshape(3, 2)
    if args.poses is not None:
        from sweepik.trajectory import load_poses

        kwargs["poses"] = load_poses(args.poses)
    if not np.isfinite(args.payload) or args.payload < 0:
        raise CliInputError(f"--payload must be a mass in kg, >= 0, got {args.payload:g}")
    progress = _Progress()
    try:
        cmp = compare_designs(
            robots,
            payload=args.payload,
            links=not args.no_link_masses,
            samples=args.samples,
            workspace_samples=args.workspace_samples,
            seed=args.seed,
            progress=progress,
            **kwargs,
        )
    finally:
        progress.close()
    verdicts = [f"{v['criterion']}: {v['winner'] or 'no clear winner'}" for v in cmp.verdicts]
    text = "\n".join([format_table(cmp), "", *verdicts])
    _emit_results(args, cmp.to_dict(), text, lambda d: write_design_report(cmp, d))
    return 0
