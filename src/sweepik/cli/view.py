"""``sweepik view``: the browser viewer of every solution (``sweepik.viewer``; the ``view`` extra)."""

from __future__ import annotations

import argparse

from sweepik.cli.common import (
    CliInputError,
    _add_robot_options,
    _load_robot,
    _locked_from_args,
    _subparser,
    _SubParsers,
)

__all__ = ["add_view_parser", "cmd_view"]


def add_view_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "view",
        help="open a browser viewer: drag a target and see every IK solution (needs the 'view' extra)",
        description=(
            "Serve a page (viser) drawing ROBOT with a target gizmo: every solution of the target at once (the "
            "chosen one solid, the others as ghosts; out-of-limit ones red with the limits off, multiple roots "
            "orange), a slider along each self-motion family, joint sliders for forward kinematics, and with "
            "--poses FILE a slider stepping through the poses. Prints the URL; Ctrl-C stops it."
        ),
    )
    p.add_argument("robot", metavar="ROBOT", help="robot name or file (TOML, URDF, MJCF), or a catalogue name")
    p.add_argument("--poses", metavar="FILE", help="poses to step through (CSV, NPY or JSON, as for solve)")
    p.add_argument("--port", type=int, default=8080, help="port to serve on (default 8080; 0: any free port)")
    p.add_argument("--host", default="127.0.0.1", help="address to serve on (default 127.0.0.1: this machine only)")
    p.add_argument("--no-limits", action="store_true", help="show solutions outside the joint limits too (red)")
    p.add_argument("--rad", action="store_true", help="--lock values of revolute joints in radians")
    _add_robot_options(p, lock=True)


def cmd_view(args: argparse.Namespace) -> int:
    from sweepik.viewer.app import view

    robot = _load_robot(args.robot, args)
    locked = _locked_from_args(robot, args)
    if robot.n_joints - len(locked or {}) > 6:
        raise CliInputError(
            f"robot {robot.name!r} has {robot.n_joints} joints; the viewer solves six: hold one with --lock NAME=VALUE"
        )
    poses = None
    if args.poses is not None:
        from sweepik.trajectory import load_poses

        poses = load_poses(args.poses)
    urdf = args.robot if args.robot.lower().endswith(".urdf") else None  # (its meshes, where they resolve)
    view(robot, poses=poses, port=args.port, host=args.host, limits=not args.no_limits, locked=locked, urdf=urdf)
    return 0
