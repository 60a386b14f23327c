"""``sweepik analyze``: the structure of an arm, every decomposition that solves it, and the one chosen."""

from __future__ import annotations

import argparse
from typing import Any

import numpy as np

from sweepik.cli.common import (
    _add_json,
    _add_robot_options,
    _format_table,
    _load_robot,
    _locked_from_args,
    _print_json,
    _subparser,
    _SubParsers,
)
from sweepik.reductions.analysis import analyze, plan_line

__all__ = ["add_analyze_parser", "cmd_analyze", "plan_line"]


def add_analyze_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "analyze",
        help="structure of an arm and the decompositions that solve it",
        description=(
            "Show which joint axes of ROBOT (a bundled robot or a robot file) intersect or stay parallel, every "
            "decomposition in sweepik's catalogue that solves it (the swept joint theta*, the subproblem chain, "
            "the number of branches), and the one 'sweepik solve' uses; or why none applies."
        ),
    )
    p.add_argument("robot", metavar="ROBOT", help="robot name or file (TOML or URDF)")
    p.add_argument("--rad", action="store_true", help="--lock values of revolute joints in radians")
    _add_robot_options(p, lock=True)
    _add_json(p)


def _no_plan(reason: str | None) -> str:
    """The decomposition column of a lock that leaves nothing to solve: why, in a few words."""
    if reason and "every pose is a continuum" in reason:
        return "none: every pose a continuum"
    return "none in the catalogue"


def print_locks(robot: Any, locks: list[dict[str, Any]]) -> None:
    """The table of a 7-joint arm: for each joint, what locking it (at 0 and at a generic value) leaves."""
    print(f"{robot.n_joints} joints: solve with one locked (--lock NAME=VALUE); what each lock leaves:")
    rows = []
    for lock in locks:
        k = lock["joint"]
        for v in lock["values"]:
            value = np.degrees(v["value"]) if robot.is_revolute[k] else v["value"]
            unit = "deg" if robot.is_revolute[k] else robot.length_unit
            chosen = v["chosen"]
            rows.append(
                [
                    f"{lock['joint_number']} ({lock['joint_name']})",
                    f"{value:.4g} {unit}",
                    v["structure"],
                    plan_line(chosen) if chosen else _no_plan(v["reason"]),
                ]
            )
    print(_format_table(["lock joint", "at", "structure of the other six", "decomposition"], rows))


def cmd_analyze(args: argparse.Namespace) -> int:
    robot = _load_robot(args.robot, args)
    info = analyze(robot, locked=_locked_from_args(robot, args))
    if args.json:
        _print_json(info)
        return 0
    print(f"{info['robot']}: {info['structure']}")
    if "arm_joints" in info:
        held = ", ".join(info["held"])
        print(
            f"  ({held} held: structure and steps number the other joints 1-{len(info['arm_joints'])}, i.e. "
            f"joints {', '.join(map(str, info['arm_joints']))} of the arm; theta* below by the arm's numbers)"
        )
    if "locks" in info:
        print_locks(robot, info["locks"])
        return 0
    if info.get("near_structure"):
        print(f"near-structure (holds nearly, not exactly: a general arm there): {', '.join(info['near_structure'])}")
    chosen = info["chosen"]
    if chosen is None:
        print(f"no decomposition: {info['reason']}")
        return 0
    print(f"chosen: {plan_line(chosen)}")
    print(f"  why: {info['why']}")
    for step in chosen["steps"]:
        print(f"  - {step}")
    if info.get("checks"):
        print("checked on the arm (configurations given back, solutions found):")
        for c in info["checks"]:
            print(f"  {plan_line(c)} ({c['case']}): {c['recovered']}/{c['checked']}, {c['solutions']}")
    rows = [
        [
            str(i + 1),
            "closed form" if p["closed_form"] else f"{p['free_joint_number']} ({p['free_joint_name']})",
            p["chain"],
            p["case"],
            str(p["branches"]),
            "yes" if p["blind_spot"] else "no",
        ]
        for i, p in enumerate(info["plans"])
    ]
    print(f"every decomposition ({len(rows)}), best first:")
    print(_format_table(["#", "theta*", "chain", "position case", "branches", "blind spot"], rows))
    return 0
