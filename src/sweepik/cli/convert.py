"""``sweepik convert``: write a robot (bundled, TOML or URDF) as a TOML robot file or as URDF."""

from __future__ import annotations

import argparse
from pathlib import Path

from sweepik.cli.common import (
    CliInputError,
    _add_json,
    _add_robot_options,
    _check_output_path,
    _load_robot,
    _locked_from_args,
    _print_json,
    _subparser,
    _SubParsers,
)
from sweepik.io.robot_file import robot_to_toml
from sweepik.model.origin_axis import hold_joints

__all__ = ["add_convert_parser", "cmd_convert"]

SUFFIXES = (".toml", ".urdf")


def add_convert_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "convert",
        help="write a robot as a TOML robot file or as URDF",
        description=(
            "Write ROBOT (a bundled robot, a TOML robot file or a URDF file) to FILE, as a TOML robot file "
            "(.toml: DH rows for a DH arm, origin + axis joints otherwise) or as URDF (.urdf: lengths in metres). "
            "The written robot has the same forward kinematics (URDF: scaled to metres). With --lock, the arm "
            "with those joints held is written."
        ),
    )
    p.add_argument("robot", metavar="ROBOT", help="robot name or file (TOML or URDF)")
    p.add_argument("-o", "--output", metavar="FILE", required=True, help="the file to write (.toml or .urdf)")
    p.add_argument("--rad", action="store_true", help="--lock values of revolute joints in radians")
    _add_robot_options(p, lock=True)
    _add_json(p, ": the file written")


def cmd_convert(args: argparse.Namespace) -> int:
    suffix = Path(args.output).suffix.lower()
    if suffix not in SUFFIXES:
        raise CliInputError(f"convert: the output file must end in .toml or .urdf, got {args.output!r}")
    _check_output_path(args.output, suffixes=SUFFIXES)
    robot = _load_robot(args.robot, args)
    locked = _locked_from_args(robot, args)
    if locked:
        robot = hold_joints(robot, locked, n_free=None).arm
    if suffix == ".urdf":
        from sweepik.io.urdf import urdf_text

        text = urdf_text(robot)
    else:
        text = robot_to_toml(robot)
    Path(args.output).write_text(text, encoding="utf-8")
    if args.json:
        _print_json({"robot": robot.name, "n_joints": robot.n_joints, "output": args.output})
    else:
        print(f"wrote {robot.name!r} ({robot.n_joints} joints) to {args.output}")
    return 0
