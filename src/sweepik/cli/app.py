"""The ``sweepik`` command line.

Each subcommand is one pair of functions, ``_add_<name>_parser(sub)`` (creates its subparser with
``_subparser`` and declares its arguments) and ``_cmd_<name>(args) -> int`` (runs it and returns the exit
status), registered in ``_COMMANDS``. To add a subcommand, write the pair and add one line to
``_COMMANDS``; the helpers below (robot and number parsing, unit conversion, matrix and table formatting,
JSON output) are meant to be shared. Raise a :class:`SweepikError` (e.g. ``CliInputError``) for bad input:
``main`` turns it into the one-line error and exit status 2.

Exit status: 0 on success, 2 on bad input (usage errors, bad numbers or counts, a value too many after an
option, an unwritable output path, any :class:`SweepikError`), all detected before any computation; 1 on an
operating-system error while a file is read or written. Errors print one line ``sweepik: error: <message>`` on
stderr, never a traceback. Output paths are checked with ``cli_common._check_output_path`` before the work
starts; long runs report progress through ``cli_common._Progress`` (stderr, terminals only).

>>> main(["fk", "carm", "500", "0", "0", "0", "0", "0", "--json"])  # doctest: +ELLIPSIS
{
  "robot": "carm",
...
0
"""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Callable, Sequence
from typing import Any, NoReturn

import numpy as np
from numpy.typing import NDArray

from sweepik import __version__
from sweepik.errors import SweepikError
from sweepik.io.robot_file import bundled_robots
from sweepik.model.pose import GIMBAL_TOL, rpy_from_matrix, zyz_from_matrix
from sweepik.model.robot import Robot
from sweepik.reductions.analysis import analyze

__all__ = ["main", "build_parser"]

from sweepik.cli.analyze import add_analyze_parser, cmd_analyze, plan_line, print_locks
from sweepik.cli.batch import EXIT_INTERRUPTED, add_sample_parser, cmd_sample
from sweepik.cli.common import (
    DEFAULT_ROBOT,
    EXIT_IO,
    EXIT_USAGE,
    PROG,
    VERBOSE_HELP,
    _add_json,
    _add_precision,
    _add_robot_options,
    _clean,
    _config_from_cli,
    _format_matrix,
    _format_table,
    _is_number,
    _joint_units,
    _load_robot,
    _num,
    _print_json,
    _protect_negative_numbers,
    _split_robot,
    _subparser,
    _SubParsers,
)
from sweepik.cli.convert import add_convert_parser, cmd_convert
from sweepik.cli.design import add_design_parser, cmd_design
from sweepik.cli.solve import add_path_parser, add_solve_parser, cmd_path, cmd_solve
from sweepik.cli.verify import add_bench_parser, add_verify_parser, cmd_bench, cmd_verify
from sweepik.cli.view import add_view_parser, cmd_view


def _add_fk_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "fk",
        usage="%(prog)s [-h] [-v] [--rad] [--json] [--precision N] [ROBOT] Q1 ... Qn",
        help="forward kinematics: tool pose of a configuration",
        description=(
            "Print the tool pose (4x4 matrix, position, Z-Y-Z Euler angles) of a configuration. "
            f"ROBOT is a bundled robot name or a robot file (default: {DEFAULT_ROBOT}). Joint values are "
            "degrees for revolute joints (radians with --rad) and the robot's length unit for prismatic "
            "ones. Negative values need no quoting: sweepik fk carm 500 -30 0 0 0 0"
        ),
    )
    p.add_argument("values", nargs="+", metavar="[ROBOT] Q1 ... Qn", help="robot (optional), then one value per joint")
    p.add_argument("--rad", action="store_true", help="revolute joint values are in radians")
    _add_robot_options(p)
    _add_json(p, ": robot, joint_names, q (radians / length unit), pose, xyz, zyz_deg, ...")
    _add_precision(p)


def _cmd_fk(args: argparse.Namespace) -> int:
    name, tokens = _split_robot(args.values)
    robot = _load_robot(name, args)
    q = _config_from_cli(robot, tokens, args.rad)
    T = robot.fk(q)
    xyz = T[:3, 3]
    zyz_deg = np.degrees(zyz_from_matrix(T))
    inside = bool(robot.within_limits(q))
    if args.json:
        _print_json(
            {
                "robot": robot.name,
                "joint_names": robot.joint_names,
                "q": q.tolist(),
                "pose": T.tolist(),
                "xyz": xyz.tolist(),
                "zyz_deg": zyz_deg.tolist(),
                "length_unit": robot.length_unit,
                "within_limits": inside,
            }
        )
        return 0
    dec = args.precision
    unit = robot.length_unit
    shown = q if args.rad else np.where(robot.is_revolute, np.degrees(q), q)
    joints = ", ".join(
        f"{n} = {_num(v, dec)} {u}"
        for n, v, u in zip(robot.joint_names, shown, _joint_units(robot, args.rad), strict=True)
    )
    x, y, z = _clean(xyz, dec)
    a, b, g = _clean(zyz_deg, dec)
    print(f"robot: {robot.name} ({robot.dh_convention} DH, lengths in {unit})")
    print(f"joints: {joints}")
    if not inside:
        out = [n for n, ok in zip(robot.joint_names, _joints_inside(robot, q), strict=True) if not ok]
        print(f"note: outside joint limits: {', '.join(out)}")
    print(f"pose T_world_tool (rotation, translation in {unit}):")
    print(_format_matrix(T, dec))
    print(f"position [{unit}]: x = {x:.{dec}f}  y = {y:.{dec}f}  z = {z:.{dec}f}")
    print(f"ZYZ Euler [deg]: alpha = {a:.{dec}f}  beta = {b:.{dec}f}  gamma = {g:.{dec}f}")
    beta = np.radians(zyz_deg[1])
    if beta < GIMBAL_TOL or np.pi - beta < GIMBAL_TOL:
        which = "alpha + gamma" if beta < GIMBAL_TOL else "alpha - gamma"
        print(f"note: ZYZ gimbal case (beta = {b:.0f} deg): only {which} is defined; alpha = 0 chosen")
    if args.verbose:
        origins = robot.frames(q)[:, :3, 3]
        labels = ["base", *robot.joint_names, "tool"]
        rows = [[lab, *(f"{v:.{dec}f}" for v in _clean(o, dec))] for lab, o in zip(labels, origins, strict=True)]
        print(f"frame origins [{unit}]:")
        print(_format_table(["frame", "x", "y", "z"], rows))
    return 0


def _joints_inside(robot: Robot, q: NDArray[np.float64]) -> list[bool]:
    """Per joint: inside its limits (revolute values after ``Robot.wrap``), as ``Robot.within_limits``."""
    w = robot.wrap(q)
    return [
        bool(lo - t <= v <= hi + t) for v, lo, hi, t in zip(w, robot.lower, robot.upper, robot.limit_tol, strict=True)
    ]


# --------------------------------------------------------------------------------------------------
# robots
# --------------------------------------------------------------------------------------------------


def _add_robots_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "robots",
        help="list the bundled robots: DH tables, structure and decomposition",
        description="Show robots: the bundled ones, or the named robots / robot files.",
    )
    p.add_argument("robots", nargs="*", metavar="ROBOT", help="robot names or files (default: all bundled)")
    _add_robot_options(p)
    _add_json(p)
    _add_precision(p)


def _robot_summary(robot: Robot) -> dict[str, Any]:
    info = analyze(robot)
    return {
        "name": robot.name,
        "description": robot.description,
        "dh_convention": robot.dh_convention,
        "length_unit": robot.length_unit,
        "default_reduction": robot.default_reduction,
        "n_joints": robot.n_joints,
        "dh_table": robot.dh_table(),
        "T_world_base": robot.T_world_base.tolist(),
        "T_flange_tool": robot.T_flange_tool.tolist(),
        "structure": info["structure"],
        "decomposition": info["chosen"],
    }


def _cmd_robots(args: argparse.Namespace) -> int:
    robots = [_load_robot(name, args) for name in (args.robots or bundled_robots())]
    if args.json:
        _print_json([_robot_summary(r) for r in robots])
        return 0
    dec = args.precision
    for i, robot in enumerate(robots):
        if i:
            print()
        unit = robot.length_unit
        print(f"{robot.name}: {robot.description}" if robot.description else robot.name)
        extra = f", default reduction {robot.default_reduction}" if robot.default_reduction else ""
        form = "origin + axis joints" if robot.dh_convention == "none" else f"{robot.dh_convention} DH"
        print(f"  {robot.n_joints} joints, {form}, lengths in {unit}, angles in deg{extra}")
        info = analyze(robot)
        print(f"  structure {info['structure']}")
        chosen = info["chosen"]
        if "locks" in info:
            print("  decomposition: lock a joint first (--lock NAME=VALUE; the table below)")
        else:
            print(f"  decomposition: {plan_line(chosen) if chosen else 'none in the catalogue'}")
        header, rows = _joint_table(robot, dec)
        print(_format_table(header, rows))
        for label, T in (
            ("base T_world_base", robot.T_world_base),
            ("tool T_flange_tool", robot.T_flange_tool),
        ):
            if not np.array_equal(T, np.eye(4)):
                print(f"  {label}:")
                print(_format_matrix(T, dec, indent="    "))
        if "locks" in info:
            print_locks(robot, info["locks"])
    return 0


def _joint_table(robot: Robot, dec: int) -> tuple[list[str], list[list[str]]]:
    """The joints as a table: DH rows, or for an arm in origin + axis form (URDF, MJCF) each joint's origin
    (position, roll-pitch-yaw) in the previous joint's frame and its axis."""
    unit = robot.length_unit
    limits = [
        f"[{_num(float(np.degrees(lo) if rev else lo), dec)}, {_num(float(np.degrees(hi) if rev else hi), dec)}] "
        + ("deg" if rev else unit)
        for (lo, hi), rev in zip(robot.limits, robot.is_revolute, strict=True)
    ]
    if robot.dh_convention == "none":
        header = ["joint", "type", f"origin xyz [{unit}]", "origin rpy [deg]", "axis", "limits"]
        rows = []
        for j, lim in zip(robot.joints, limits, strict=True):
            T = np.array(j.origin, dtype=np.float64)
            xyz = " ".join(_num(float(v), dec) for v in T[:3, 3])
            rpy = " ".join(_num(float(v), dec) for v in np.degrees(rpy_from_matrix(T)))
            axis = " ".join(_num(float(v), dec) for v in j.axis)
            rows.append([str(j.name), j.type, xyz, rpy, axis, lim])
        return header, rows
    a_label = "a_{i-1}" if robot.dh_convention == "modified" else "a_i"
    al_label = "alpha_{i-1}" if robot.dh_convention == "modified" else "alpha_i"
    header = ["joint", "type", f"{a_label} [{unit}]", f"{al_label} [deg]", f"d_i [{unit}]", "theta_i [deg]", "limits"]
    rows = []
    for row, lim in zip(robot.dh_table(), limits, strict=True):
        num = [_num(float(row[k]), dec) for k in ("a", "alpha_deg", "d", "theta_deg")]
        rows.append([str(row["joint"]), str(row["type"]), *num, lim])
    return header, rows


# --------------------------------------------------------------------------------------------------
# Parser, dispatch, main
# --------------------------------------------------------------------------------------------------

_AddParser = Callable[[_SubParsers], None]
_Run = Callable[[argparse.Namespace], int]

#: Subcommand name -> (function adding its parser, function running it).
_COMMANDS: dict[str, tuple[_AddParser, _Run]] = {
    "fk": (_add_fk_parser, _cmd_fk),
    "robots": (_add_robots_parser, _cmd_robots),
    "analyze": (add_analyze_parser, cmd_analyze),
    "solve": (add_solve_parser, cmd_solve),
    "path": (add_path_parser, cmd_path),
    "verify": (add_verify_parser, cmd_verify),
    "bench": (add_bench_parser, cmd_bench),
    "convert": (add_convert_parser, cmd_convert),
    "sample": (add_sample_parser, cmd_sample),
    "design": (add_design_parser, cmd_design),
    "view": (add_view_parser, cmd_view),
}


#: Commands that run the compiled solver (their first run in a fresh install compiles its kernels).
_SOLVING = {"solve", "path", "verify", "bench", "design", "view"}


def _compile_notice(command: str) -> None:
    """On a terminal, before a solving command's first run in a fresh install (no compiled kernel in Numba's cache
    yet), say that the kernels are being compiled, once (a silent half minute looks like a hang)."""
    if command not in _SOLVING or not sys.stderr.isatty() or _kernels_cached():
        return
    print(
        f"{PROG}: compiling the solver's kernels for this machine (once: about 30 s, up to two minutes for an arm "
        "without structure; later runs load them from Numba's cache)",
        file=sys.stderr,
        flush=True,
    )


def _kernels_cached() -> bool:
    """Some compiled kernel of sweepik is in Numba's disk cache (``$NUMBA_CACHE_DIR``, the package's
    ``__pycache__`` folders, or Numba's per-user folder when the package's is not writable)."""
    from pathlib import Path

    import sweepik

    places = [Path(os.environ["NUMBA_CACHE_DIR"])] if os.environ.get("NUMBA_CACHE_DIR") else []
    places += [Path(sweepik.__file__).parent, Path.home() / ".cache" / "numba"]
    return any(next(p.rglob("*.nbi"), None) is not None for p in places if p.is_dir())


class _Parser(argparse.ArgumentParser):
    """argparse, but a usage error is one line (``sweepik: error: ...``, naming the command) and exit status 2."""

    def error(self, message: str) -> NoReturn:
        command = self.prog.split(" ", 1)[1] if " " in self.prog else ""
        where = f" {command}" if command else ""
        _error(f"{message} (see 'sweepik{where} --help')")
        raise SystemExit(EXIT_USAGE)


def build_parser() -> argparse.ArgumentParser:
    """The top-level parser with one subparser per entry of ``_COMMANDS``."""
    parser = _Parser(
        prog=PROG,
        description="All inverse-kinematics solutions of 6-DOF serial arms by a one-joint sweep.",
    )
    parser.add_argument("-v", "--verbose", action="store_true", help=VERBOSE_HELP)
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True, parser_class=_Parser)
    for add_parser, _ in _COMMANDS.values():
        add_parser(sub)
    return parser


def _unrecognized(parser: argparse.ArgumentParser, command: str, tokens: Sequence[str], extras: Sequence[str]) -> str:
    """The message for arguments no option took: a number right after an option's fixed count of values is named
    as a surplus of that option (``--zyz 0 0 0 0``: --zyz takes 3 angles)."""
    see = f"(see 'sweepik {command} --help')"
    sub = _subparsers(parser).get(command)
    fixed = {
        opt: action
        for action in (sub._actions if sub is not None else [])
        for opt in action.option_strings
        if isinstance(action.nargs, int) and action.nargs > 0
    }
    for i, tok in enumerate(tokens):
        action = fixed.get(tok)
        if action is None:
            continue
        n = int(action.nargs)  # type: ignore[arg-type]
        after = list(tokens[i + 1 : i + n + 2])
        if len(after) == n + 1 and all(_is_number(t) for t in after) and after[-1] in extras:
            names = f" ({' '.join(action.metavar)})" if isinstance(action.metavar, tuple) else ""
            return f"{tok} takes {n} values{names}, got one more: {after[-1].strip()!r} {see}"
    return f"unrecognized arguments: {' '.join(t.strip() for t in extras)} {see}"


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    """Subcommand name -> its parser."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _error(message: str) -> None:
    # One line, whatever the message holds.
    print(f"{PROG}: error: {' '.join(str(message).split())}", file=sys.stderr)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``sweepik`` command with ``argv`` (default: ``sys.argv[1:]``); return the exit status."""
    args_in = list(sys.argv[1:] if argv is None else argv)
    parser = build_parser()
    tokens = _protect_negative_numbers(args_in)
    try:
        args, extras = parser.parse_known_args(tokens)
    except SystemExit as exc:  # --help, --version, usage errors: argparse has printed its message
        return exc.code if isinstance(exc.code, int) else (0 if exc.code is None else EXIT_USAGE)
    if extras:
        _error(_unrecognized(parser, args.command, tokens, extras))
        return EXIT_USAGE
    if args.verbose:
        logging.basicConfig(level=logging.INFO, format=f"{PROG}: %(message)s")
    _, run = _COMMANDS[args.command]
    _compile_notice(args.command)
    try:
        return run(args)
    except SweepikError as exc:
        _error(str(exc))
        return EXIT_USAGE
    except BrokenPipeError:  # output piped into a command that stopped reading (e.g. `| head`)
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except (OSError, UnicodeError) as exc:  # a file that cannot be read, decoded or written after the checks
        if isinstance(exc, OSError) and exc.filename and exc.strerror:
            _error(f"{exc.filename}: {exc.strerror}")
        else:
            _error(str(exc))
        return EXIT_IO
    except KeyboardInterrupt:  # Ctrl-C: one line, not a traceback (what was printed so far stays printed)
        print(f"{PROG}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
