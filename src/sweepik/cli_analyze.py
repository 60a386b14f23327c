"""``sweepik analyze``: the structure of an arm, every decomposition that solves it, and the one chosen."""

from __future__ import annotations

import argparse
from typing import Any

from .analysis import analyze
from .cli_common import _add_json, _format_table, _print_json, _subparser, _SubParsers
from .robot_file import load_robot

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
    p.add_argument("robot", metavar="ROBOT", help="robot name or file")
    _add_json(p)


def plan_line(plan: dict[str, Any]) -> str:
    """One line describing a plan of ``analyze``, e.g. ``closed form, 8 branches`` or ``sweep joint 1 (d1), 4
    branches``."""
    if plan["closed_form"]:
        head = "closed form"
    else:
        head = f"sweep joint {plan['free_joint_number']} ({plan['free_joint_name']})"
    chain = ", reversed chain" if plan["chain"] == "reversed" else ""
    blind = ", blind spot" if plan["blind_spot"] else ""
    return f"{head}, {plan['branches']} branches{chain}{blind}"


def cmd_analyze(args: argparse.Namespace) -> int:
    info = analyze(load_robot(args.robot))
    if args.json:
        _print_json(info)
        return 0
    print(f"{info['robot']}: {info['structure']}")
    chosen = info["chosen"]
    if chosen is None:
        print(f"no decomposition: {info['reason']}")
        return 0
    print(f"chosen: {plan_line(chosen)}")
    for step in chosen["steps"]:
        print(f"  - {step}")
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
