"""``sweepik solve`` and ``sweepik path``: all IK solutions of poses, and joint paths along pose lists."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.cli.batch import add_store_options, cmd_solve_store, wants_store
from sweepik.cli.common import (
    DEFAULT_ROBOT,
    CliInputError,
    _add_json,
    _add_precision,
    _add_robot_options,
    _check_output_path,
    _config_from_cli,
    _format_table,
    _is_number,
    _isatty,
    _joint_units,
    _load_robot,
    _locked_from_args,
    _parse_numbers,
    _print_json_stream,
    _Progress,
    _subparser,
    _SubParsers,
)
from sweepik.errors import UnknownOptionError
from sweepik.io.robot_file import bundled_robots
from sweepik.model.pose import pose_from_xyz_zyz
from sweepik.model.robot import Robot
from sweepik.reductions import REDUCTIONS
from sweepik.reductions.analysis import analyze, plan_line
from sweepik.results import METRICS, Solutions, check_tolerance
from sweepik.solving import STRATEGIES, iter_solve, solve

Array = NDArray[np.float64]


def _ik_kwargs(args: argparse.Namespace, robot: Robot) -> dict[str, Any]:
    """The solver's keyword arguments from the options of :func:`_add_ik_options`."""
    free = args.free_joint
    if free is not None and free.strip().isdecimal():
        number = int(free)
        if not 1 <= number <= robot.n_joints:
            raise UnknownOptionError(
                f"--free-joint takes a joint number from 1 to {robot.n_joints} (or a joint name), got {free}"
            )
        free = number - 1  # the API numbers joints from 0
    locked = _locked_from_args(robot, args)
    left = robot.n_joints - len(locked or {})
    if left > 6:
        raise CliInputError(
            f"robot {robot.name!r} has {robot.n_joints} joints; sweepik solves six: hold {left - 6} more with --lock "
            f"NAME=VALUE (e.g. --lock {robot.joint_names[-1]}=30, degrees or the length unit; 'sweepik analyze "
            f"{robot.name}' tells which lock gives a closed form or a sweep)"
        )
    return {
        "reduction": args.reduction,
        "free_joint": free,
        "strategy": args.strategy,
        "limits": not args.no_limits,
        "locked": locked,
    }


def _precise_finds_more(robot: Robot, sol: Solutions, kw: dict[str, Any], args: argparse.Namespace) -> int:
    """With ``--strategy paper``: how many solutions the precise strategy finds at the pose when that is more than
    the paper's (0 otherwise, and for the precise strategy itself)."""
    if args.strategy != "paper":
        return 0
    precise = solve(robot, sol.pose, windings=args.windings, **{**kw, "strategy": "precise"})
    return len(precise) if len(precise) > len(sol) else 0


def _decomposition_line(robot: Robot, kw: dict[str, Any]) -> str:
    """How ``solve`` decomposes the arm with these options, in words (``analyze``'s chosen plan)."""
    named = kw["reduction"] if kw["reduction"] is not None else robot.default_reduction
    if named not in (None, "auto"):
        return f"reduction {named}" + (" (the robot file's default)" if kw["reduction"] is None else "")
    if kw["free_joint"] is not None:
        free = kw["free_joint"]
        return f"sweep joint {free + 1 if isinstance(free, int) else free} (--free-joint)"
    info = analyze(robot, locked=kw["locked"])
    return plan_line(info["chosen"]) if info["chosen"] else "none (" + str(info["reason"]) + ")"


def _add_ik_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--strategy", choices=STRATEGIES, default="precise", help="search strategy (default: precise)")
    p.add_argument(
        "--reduction",
        metavar="NAME",
        help=(
            f"reduction (theta* joint): auto (derived from the arm's geometry) or one of "
            f"{', '.join(sorted(REDUCTIONS))}; default: the robot file's default_reduction, else auto"
        ),
    )
    p.add_argument(
        "--free-joint",
        metavar="J",
        help="with the automatic decomposition, sweep this joint (number from 1, or name); see 'sweepik analyze'",
    )
    p.add_argument("--no-limits", action="store_true", help="keep solutions outside the joint limits (flagged)")
    p.add_argument("--rad", action="store_true", help="angles in and out in radians instead of degrees")
    _add_robot_options(p, lock=True)


def _add_choice_options(p: argparse.ArgumentParser) -> None:
    """--metric and --tol: how the nearest solution is chosen (``Solutions.nearest``)."""
    p.add_argument(
        "--metric",
        choices=tuple(METRICS),
        default="weighted",
        help="joint distance for choosing the nearest solution: weighted (Euclidean, default) or linf (largest joint "
        "move); prismatic joints count 100 mm as 1 radian",
    )
    p.add_argument(
        "--tol",
        type=float,
        metavar="T",
        help="no solution is chosen farther than T from the reference (degrees, or radians with --rad)",
    )


def _choice_tol(args: argparse.Namespace) -> float | None:
    """``--tol`` in radians (the metric's unit), checked."""
    if args.tol is None:
        return None
    tol = float(check_tolerance(args.tol, "--tol") or 0.0)
    return tol if args.rad else float(np.radians(tol))


def add_solve_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "solve",
        help="inverse kinematics: every solution of a pose",
        description=(
            "Print every IK solution of a pose given as --xyz X Y Z --zyz A B G (Z-Y-Z Euler angles in "
            "degrees), as --matrix with 16 numbers (row-major 4x4), or of many poses in --poses FILE "
            f"(CSV, NPY or JSON). ROBOT is a bundled robot or a robot file (default: {DEFAULT_ROBOT})."
        ),
    )
    p.add_argument("robot", nargs="?", default=DEFAULT_ROBOT, help=f"robot name or file (default: {DEFAULT_ROBOT})")
    p.add_argument("--xyz", nargs=3, metavar=("X", "Y", "Z"), help="position, robot's length unit")
    p.add_argument("--zyz", nargs=3, metavar=("A", "B", "G"), help="Z-Y-Z Euler angles, degrees (default 0 0 0)")
    p.add_argument("--matrix", nargs=16, metavar="M", help="the pose as 16 numbers, row-major")
    p.add_argument("--poses", metavar="FILE", help="many poses: CSV, NPY or JSON (see docs/cli.md)")
    p.add_argument("--nearest", nargs="+", metavar="Q", help="also report the solution nearest this configuration")
    _add_choice_options(p)
    p.add_argument(
        "--windings",
        action="store_true",
        help="also list every 2 pi winding of each solution inside the joint limits (e.g. a UR's +-360 deg)",
    )
    _add_ik_options(p)
    _add_json(p, ": per pose, solutions q (radians / length unit), errors, families")
    _add_precision(p)
    add_store_options(p)  # --out STORE [--workers N | --scheduler ADDRESS] [--resume]: cli_batch


def _poses_from_args(args: argparse.Namespace) -> Array:
    given = [x for x in ("xyz", "matrix", "poses") if getattr(args, x) is not None]
    if len(given) != 1:
        raise CliInputError("give exactly one of --xyz (with --zyz), --matrix or --poses")
    if args.poses is not None:
        from sweepik.trajectory import load_poses

        return load_poses(args.poses)
    if args.matrix is not None:
        return _parse_numbers(args.matrix, [f"matrix[{i // 4},{i % 4}]" for i in range(16)]).reshape(1, 4, 4)
    xyz = _parse_numbers(args.xyz, ["x", "y", "z"])
    zyz = _parse_numbers(args.zyz or ["0", "0", "0"], ["alpha", "beta", "gamma"])
    return pose_from_xyz_zyz(xyz, zyz if args.rad else np.radians(zyz))[None]


def _display(robot: Robot, q: Array, rad: bool) -> Array:
    return q if rad else np.where(robot.is_revolute, np.degrees(q), q)


def _nearest_of(sol: Solutions, nearest: Array, args: argparse.Namespace) -> Array | None:
    return sol.nearest(nearest, metric=args.metric, tol=_choice_tol(args))


def _solution_json(
    robot: Robot, sol: Solutions, nearest: Array | None, args: argparse.Namespace | None = None, precise: int = 0
) -> dict[str, Any]:
    """One pose's JSON object (``args``: the command's options; None: no --windings, no --nearest; ``precise``: the
    precise strategy's count where the paper's found fewer)."""
    out: dict[str, Any] = {
        "q": sol.q.tolist(),
        "error_J": sol.error.tolist(),
        "error_geodesic": sol.error_geodesic.tolist(),
        "within_limits": sol.within_limits.tolist(),
        "multiplicity": sol.multiplicity.tolist(),
        "families": [
            {"free_joint": robot.joint_names[f.free_joint], "interval": list(f.interval)} for f in sol.families
        ],
        "reason": sol.reason,
    }
    if args is not None and args.windings:
        out["winding_of"] = sol.winding_of.tolist()
    if precise:
        out["precise_strategy_finds"] = precise
    if args is not None and nearest is not None:
        qn = _nearest_of(sol, nearest, args)
        out["nearest"] = None if qn is None else qn.tolist()
    return out


def _plural(count: int, one: str, many: str) -> str:
    return f"{count} {one if count == 1 else many}"


def _print_solutions(
    robot: Robot, sol: Solutions, args: argparse.Namespace, header: list[str], nearest: Array | None
) -> None:
    """The text block of one pose (without its ``pose k:`` line)."""
    dec = args.precision
    if not sol:
        print(f"  no solution: {sol.reason}")
        return
    show_mult = bool(np.any(sol.multiplicity > 1))  # a column only where some root is multiple (singular)
    rows = []
    for i, (q, e, ok, m) in enumerate(zip(sol.q, sol.error, sol.within_limits, sol.multiplicity, strict=True)):
        row = [str(i + 1), *(f"{v:.{dec}f}" for v in _display(robot, q, args.rad)), f"{e:.2e}"]
        if args.windings:
            row.append("" if sol.winding_of[i] == i else str(int(sol.winding_of[i]) + 1))
        if args.no_limits:
            row.append("yes" if ok else "no")
        if show_mult:
            row.append(str(int(m)))
        rows.append(row)
    if sol.families:
        count = _plural(len(sol), "isolated solution", "isolated solutions")
        fams = _plural(len(sol.families), "self-motion family", "self-motion families")
        print(f"  {count} and {fams} ({args.strategy} strategy):")
    else:
        print(f"  {len(sol)} solution(s) ({args.strategy} strategy):")
    if rows:
        # every column holds numbers but "in limits" (yes / no)
        numeric = [h != "in limits" for h in header] + ([True] if show_mult else [])
        print(_format_table([*header, "multiplicity"] if show_mult else header, rows, indent="  ", numeric=numeric))
    if sol.families:
        _print_families(robot, sol, args)
    if nearest is not None:
        qn = _nearest_of(sol, nearest, args)
        if qn is None:
            print(f"  nearest: none within --tol {args.tol:g} ({args.metric} metric)")
        else:
            print("  nearest: " + "  ".join(f"{v:.{dec}f}" for v in _display(robot, qn, args.rad)))


def _print_families(robot: Robot, sol: Solutions, args: argparse.Namespace) -> None:
    """Each self-motion family: its free joint and interval, then a table of its members at both ends."""
    dec = args.precision
    units = _joint_units(robot, args.rad)
    rows = []
    for k, f in enumerate(sol.families):
        j = f.free_joint
        ends = np.array(f.interval, dtype=np.float64)
        lo, hi = np.degrees(ends) if robot.is_revolute[j] and not args.rad else ends
        print(
            f"  self-motion family {k + 1}: every {robot.joint_names[j]} in [{lo:.{dec}f}, {hi:.{dec}f}] {units[j]} "
            "gives a solution"
        )
        for end, q in zip(("from", "to"), f.at(ends), strict=True):
            rows.append([f"{k + 1} {end}", *(f"{v:.{dec}f}" for v in _display(robot, q, args.rad))])
    header = ["family", *(f"{n} [{u}]" for n, u in zip(robot.joint_names, units, strict=True))]
    print("  members at both ends of the intervals:")
    print(_format_table(header, rows, indent="  "))


def cmd_solve(args: argparse.Namespace) -> int:
    if _is_number(args.robot):
        raise CliInputError(
            f"unexpected number {args.robot.strip()!r} where the robot goes: --xyz takes 3 numbers, --zyz 3 angles, "
            "--matrix 16 numbers"
        )
    robot = _load_robot(args.robot, args)
    if wants_store(args):  # many poses on Dask into a store: cli_batch
        return cmd_solve_store(args, robot, _ik_kwargs(args, robot))
    nearest = None if args.nearest is None else _config_from_cli(robot, args.nearest, args.rad)
    _choice_tol(args)  # (checked before solving)
    poses = _poses_from_args(args)
    # the output streaming to the terminal shows the progress by itself: no progress line mixed into it
    progress = _Progress(enabled=not _isatty(sys.stdout))
    kw = _ik_kwargs(args, robot)
    start = time.perf_counter()
    try:
        sols = iter_solve(robot, poses, progress=progress, windings=args.windings, **kw)
        how = _decomposition_line(robot, kw)
        if args.json:
            head = {
                "robot": robot.name,
                "joint_names": robot.joint_names,
                "units": "radians and " + robot.length_unit,
                "strategy": args.strategy,
                "decomposition": how,
            }
            items = (_solution_json(robot, s, nearest, args, _precise_finds_more(robot, s, kw, args)) for s in sols)
            _print_json_stream(head, "poses", items)
            return 0
        units = _joint_units(robot, args.rad)
        header = ["#", *(f"{n} [{u}]" for n, u in zip(robot.joint_names, units, strict=True))]
        header.append(f"J [{robot.length_unit}]")
        if args.windings:
            header.append("winds #")
        if args.no_limits:
            header.append("in limits")
        print(f"decomposition: {how}")
        count = 0
        for k, sol in enumerate(sols):
            if poses.shape[0] > 1:
                print(f"pose {k + 1}:")
            _print_solutions(robot, sol, args, header, nearest)
            count += len(sol)
            more = _precise_finds_more(robot, sol, kw, args)
            if more:
                print(
                    f"  note: the precise strategy finds {more} solution(s) at this pose (--strategy precise); the "
                    "paper's 10 mm sweep misses roots closer than its step and double roots (see docs/verification.md)"
                )
    finally:
        progress.close()
    if getattr(args, "verbose", False):
        spent = time.perf_counter() - start
        print(
            f"{poses.shape[0]} pose(s), {count} solution(s) in {spent:.3f} s ({1e6 * spent / poses.shape[0]:.0f} us "
            f"per pose, printing included; the first solve of an arm in a process compiles and loads its kernels)",
            file=sys.stderr,
        )
    return 0


def add_path_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "path",
        help="follow a Cartesian path: one configuration per pose, staying on one IK branch",
        description=(
            "Solve every pose of POSES_FILE (CSV, NPY or JSON) and pick, at each step, the solution nearest the "
            "previous configuration (the first: nearest --start, else the first solution). Writes the joint path "
            "as CSV or JSON (by the output file's extension; default: CSV on standard output)."
        ),
    )
    p.add_argument("args", nargs="+", metavar="[ROBOT] POSES_FILE", help="robot (optional), then the pose file")
    p.add_argument(
        "--start", nargs="+", metavar="Q", help="start configuration (degrees, or radians with --rad; length unit)"
    )
    p.add_argument("-o", "--output", metavar="FILE", help="write the joint path here (.csv or .json)")
    _add_choice_options(p)
    _add_ik_options(p)
    _add_json(p, ": summary (points, max joint step, branch switches, errors) and the path")


def cmd_path(args: argparse.Namespace) -> int:
    from sweepik.trajectory import follow_path, load_poses, write_joint_path

    if len(args.args) > 2:
        raise CliInputError(f"expected [ROBOT] POSES_FILE, got {len(args.args)} arguments")
    robot_name, path = (DEFAULT_ROBOT, args.args[0]) if len(args.args) == 1 else args.args
    if len(args.args) == 1 and (path in bundled_robots() or Path(path).suffix.lower() == ".toml"):
        raise CliInputError(
            f"path: {path!r} is a robot, the POSES_FILE is missing (usage: sweepik path [ROBOT] POSES_FILE)"
        )
    if args.output:
        _check_output_path(args.output, suffixes=(".csv", ".json"))
    robot = _load_robot(robot_name, args)
    start = None if args.start is None else _config_from_cli(robot, args.start, args.rad)
    poses = load_poses(path)
    progress = _Progress()
    try:
        res = follow_path(
            robot, poses, start, progress=progress, metric=args.metric, tol=_choice_tol(args), **_ik_kwargs(args, robot)
        )
    finally:
        progress.close()
    if args.output:
        write_joint_path(args.output, res.q, robot)
    summary = {
        "robot": robot.name,
        "points": int(len(res.q)),
        "found": int(np.sum(res.found)),
        "J_max": float(np.nanmax(res.error)) if np.any(res.found) else None,
        "max_joint_step": res.max_joint_step.tolist(),
        "branch_switches": res.branch_switches,
        "switch_steps": list(res.switch_steps),
    }
    if args.json:
        q_rows = ([float(v) if np.isfinite(v) else None for v in row] for row in res.q)
        _print_json_stream(summary, "q", q_rows)  # the rows are encoded one by one, never all held as text
    elif args.output:
        print(
            f"{summary['found']}/{summary['points']} poses solved, J_max = {summary['J_max']}, "
            f"branch switches: {res.branch_switches}; joint path written to {args.output}"
        )
    else:
        units = _joint_units(robot, args.rad)
        header = ["#", *(f"{n} [{u}]" for n, u in zip(robot.joint_names, units, strict=True)), "J"]
        rows = [
            [str(k + 1), *(f"{v:.6f}" for v in _display(robot, q, args.rad)), f"{e:.2e}"]
            for k, (q, e) in enumerate(zip(res.q, res.error, strict=True))
        ]
        print(_format_table(header, rows))
        print(f"{summary['found']}/{summary['points']} poses solved, branch switches: {res.branch_switches}")
    return 0
