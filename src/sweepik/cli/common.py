"""Helpers shared by the ``sweepik`` subcommands: robot and number parsing, units, tables, JSON."""

from __future__ import annotations

import argparse
import importlib.util
import json
import math
import os
import sys
import time
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import SweepikError
from sweepik.io.robot_file import load_robot
from sweepik.model.robot import Robot

PROG = "sweepik"
#: Robot used when a subcommand's optional ROBOT argument is left out.
DEFAULT_ROBOT = "carm"
#: Exit status for bad input (the same as argparse's usage errors).
EXIT_USAGE = 2
#: Exit status for an operating-system error while a file is read or written after the checks (a full disk).
EXIT_IO = 1
#: Largest --precision (float64 carries 15-17 significant digits).
MAX_PRECISION = 17
VERBOSE_HELP = "print more detail (and log at INFO level)"

_SubParsers = Any  # argparse's _SubParsersAction (a private type)


class CliInputError(SweepikError):
    """A command-line value is malformed (not a number, wrong count, ...)."""


# --------------------------------------------------------------------------------------------------
# Shared helpers for subcommands
# --------------------------------------------------------------------------------------------------


def _is_number(token: str) -> bool:
    try:
        float(token)
    except ValueError:
        return False
    return True


def _protect_negative_numbers(argv: Sequence[str]) -> list[str]:
    """Make every number-looking token that starts with '-' a positional for argparse.

    argparse takes ``-30`` and ``-0.5`` as positionals (no option of ours looks like a number) but
    ``-1e3``, ``-inf`` or ``-nan`` as unknown options. A leading space makes argparse treat a token as a
    positional; ``float`` ignores it.
    """
    return [f" {tok}" if tok.startswith("-") and len(tok) > 1 and _is_number(tok) else tok for tok in argv]


def _parse_numbers(tokens: Sequence[str], names: Sequence[str]) -> NDArray[np.float64]:
    """Floats from command-line tokens; ``names`` label each value in error messages. Rejects NaN/inf."""
    values = []
    for tok, name in zip(tokens, names, strict=True):
        text = tok.strip()
        try:
            v = float(text)
        except ValueError:
            raise CliInputError(f"value for {name} must be a number, got {text!r}") from None
        if not math.isfinite(v):
            raise CliInputError(f"value for {name} must be finite, got {text!r}")
        values.append(v)
    return np.array(values, dtype=np.float64)


def _split_robot(tokens: Sequence[str]) -> tuple[str, list[str]]:
    """Split ``[ROBOT] X1 ... Xk`` into the robot (``DEFAULT_ROBOT`` if the first token is a number)."""
    if tokens and not _is_number(tokens[0]):
        return tokens[0], list(tokens[1:])
    return DEFAULT_ROBOT, list(tokens)


def _add_robot_options(p: argparse.ArgumentParser, lock: bool = False) -> None:
    """``--base-link``/``--tip-link`` (URDF robots) and, with ``lock``, ``--lock NAME=VALUE``."""
    p.add_argument("--base-link", metavar="LINK", help="URDF robot: base link of the chain (default: the root link)")
    p.add_argument(
        "--tip-link",
        metavar="LINK",
        help="URDF robot: tip link of the chain (default: after the last moving joint, up to where the tree branches)",
    )
    if lock:
        p.add_argument(
            "--lock",
            action="append",
            metavar="NAME=VALUE",
            help=(
                "hold a joint at a value (degrees for revolute joints, radians with --rad; length unit for "
                "prismatic ones), the joint by name (first) or number from 1; repeatable. A 7-joint arm is solved "
                "with one joint locked ('sweepik analyze' tells which lock gives a closed form or a sweep)"
            ),
        )


def _load_robot(name: str, args: argparse.Namespace) -> Robot:
    """The robot ``name`` with the ``--base-link``/``--tip-link`` options of :func:`_add_robot_options`."""
    return load_robot(name, base_link=getattr(args, "base_link", None), tip_link=getattr(args, "tip_link", None))


def _locked_from_args(robot: Robot, args: argparse.Namespace) -> dict[int, float] | None:
    """``--lock NAME=VALUE`` options as ``solve``'s ``locked`` (joint index -> radians / length unit)."""
    items = getattr(args, "lock", None)
    if not items:
        return None
    rad = bool(getattr(args, "rad", False))
    out: dict[int, float] = {}
    for item in items:
        name, sep, text = item.rpartition("=")  # the value holds no '=', a joint name may
        if not sep or not name.strip():
            raise CliInputError(
                f"--lock takes NAME=VALUE (a joint name or number from 1, then its value), got {item!r}"
            )
        if name not in robot.joint_names:
            name = name.strip()
        if name in robot.joint_names:  # a joint's name before a joint number
            k = robot.joint_names.index(name)
        elif name.isascii() and name.isdecimal() and 1 <= int(name) <= robot.n_joints:
            k = int(name) - 1
        else:
            raise CliInputError(
                f"--lock {item!r}: {robot.name!r} has no joint {name!r} (joints: {', '.join(robot.joint_names)}, "
                f"or numbers 1 to {robot.n_joints})"
            )
        if k in out:
            raise CliInputError(f"--lock: joint {robot.joint_names[k]!r} is locked twice")
        value = float(_parse_numbers([text], [f"--lock {robot.joint_names[k]}"])[0])
        out[k] = float(np.radians(value)) if robot.is_revolute[k] and not rad else value
    return out


def _joint_units(robot: Robot, rad: bool) -> list[str]:
    """Display unit of each joint: 'deg' (or 'rad') for revolute joints, the length unit for prismatic."""
    ang = "rad" if rad else "deg"
    return [ang if rev else robot.length_unit for rev in robot.is_revolute]


def _config_from_cli(robot: Robot, tokens: Sequence[str], rad: bool) -> NDArray[np.float64]:
    """Configuration ``(n,)`` (radians, length unit) from joint values typed in display units."""
    units = _joint_units(robot, rad)
    labels = [f"{name} [{u}]" for name, u in zip(robot.joint_names, units, strict=True)]
    if len(tokens) != robot.n_joints:
        raise CliInputError(
            f"robot {robot.name!r} needs {robot.n_joints} joint values ({', '.join(labels)}), got {len(tokens)}"
        )
    values = _parse_numbers(tokens, labels)
    if rad:
        return values
    return np.asarray(np.where(robot.is_revolute, np.radians(values), values), dtype=np.float64)


def _num(v: float, decimals: int) -> str:
    """A number with at most ``decimals`` decimals, trailing zeros dropped (500.000000 -> 500)."""
    text = f"{float(_clean(v, decimals)):.{decimals}f}"
    return text.rstrip("0").rstrip(".") if "." in text else text


def _clean(x: ArrayLike, decimals: int) -> NDArray[np.float64]:
    """Round for display, turning -0.0 into 0.0."""
    return np.asarray(np.round(np.asarray(x, dtype=np.float64), decimals) + 0.0, dtype=np.float64)


def _format_matrix(M: NDArray[np.float64], decimals: int, indent: str = "  ") -> str:
    C = _clean(M, decimals)
    cells = [[f"{v:.{decimals}f}" for v in row] for row in C]
    width = max(len(c) for row in cells for c in row)
    return "\n".join(indent + "  ".join(c.rjust(width) for c in row) for row in cells)


def _format_table(
    header: Sequence[str],
    rows: Sequence[Sequence[str]],
    indent: str = "  ",
    numeric: Sequence[bool] | None = None,
) -> str:
    """Columns padded to equal width; columns holding only numbers are right-aligned. ``numeric`` (one bool per
    column) says which columns hold only numbers, when the caller knows (it saves parsing every cell)."""
    table = [list(header), *(list(r) for r in rows)]
    widths = [max(len(r[i]) for r in table) for i in range(len(header))]
    if numeric is None:
        right = [bool(rows) and all(_is_number(r[i]) for r in rows) for i in range(len(header))]
    else:
        right = [bool(rows) and bool(v) for v in numeric]
    lines = []
    for r in table:
        cells = [c.rjust(w) if rj else c.ljust(w) for c, w, rj in zip(r, widths, right, strict=True)]
        lines.append((indent + "  ".join(cells)).rstrip())
    return "\n".join(lines)


def _print_json(obj: Any) -> None:
    print(json.dumps(obj, indent=2, allow_nan=False))


#: ``json.dumps(..., indent=2)`` of a dict whose last value is an empty list ends with this.
_EMPTY_LIST_END = "[]\n}"


def _print_json_stream(head: dict[str, Any], key: str, items: Iterable[Any]) -> None:
    """Print ``{**head, key: list(items)}`` byte for byte as :func:`_print_json` would, but one item at a time:
    the items are encoded and written as they come and never held together, so memory does not grow with
    their number. ``key`` must not be in ``head`` (it comes last)."""
    if key in head:
        raise ValueError(f"{key!r} is already in the JSON header")
    text = json.dumps({**head, key: []}, indent=2, allow_nan=False)
    out = sys.stdout
    out.write(text[: -len(_EMPTY_LIST_END)])
    first = True
    for item in items:
        out.write("[\n" if first else ",\n")
        # an item sits at depth 2 of the document: json.dumps(indent=2) indents each of its lines by 4 more spaces
        # (strings are escaped, so every line break is one of the encoder's, and no line is blank)
        out.write("    " + json.dumps(item, indent=2, allow_nan=False).replace("\n", "\n    "))
        first = False
    out.write(_EMPTY_LIST_END + "\n" if first else "\n  ]\n}\n")


def _precision(text: str) -> int:
    try:
        n = int(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"must be a whole number, got {text.strip()!r}") from None
    if not 0 <= n <= MAX_PRECISION:
        raise argparse.ArgumentTypeError(f"must be between 0 and {MAX_PRECISION}, got {n}")
    return n


def _add_precision(p: argparse.ArgumentParser) -> None:
    p.add_argument(
        "--precision",
        type=_precision,
        default=6,
        metavar="N",
        help="decimals shown in tables and matrices (default: 6)",
    )


def _add_json(p: argparse.ArgumentParser, what: str = "") -> None:
    p.add_argument("--json", action="store_true", help=f"print JSON instead of text{what}")


def _subparser(sub: _SubParsers, name: str, **kwargs: Any) -> argparse.ArgumentParser:
    """A subparser that also accepts the common options (``-v``); ``kwargs`` go to ``add_parser``."""
    parser: argparse.ArgumentParser = sub.add_parser(name, parents=[_verbose_parent()], **kwargs)
    return parser


def _verbose_parent() -> argparse.ArgumentParser:
    """``-v`` for the subcommands: SUPPRESS keeps a subparser from resetting a ``-v`` given before it."""
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument("-v", "--verbose", action="store_true", default=argparse.SUPPRESS, help=VERBOSE_HELP)
    return common


def _nonnegative_int(text: str) -> int:
    """argparse type: an integer >= 0 (a seed)."""
    return _bounded_int(text, 0, None)


def _bounded_int(text: str, lo: int, hi: int | None) -> int:
    """An integer in ``[lo, hi]`` (no upper bound when ``hi`` is None) from a command-line token, for argparse."""
    try:
        v = int(text.strip())
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a whole number, got {text.strip()!r}") from None
    if v < lo or (hi is not None and v > hi):
        want = f"a whole number >= {lo}" if hi is None else f"a whole number from {lo:,} to {hi:,}"
        raise argparse.ArgumentTypeError(f"expected {want}, got {v}")
    return v


def _count(lo: int, hi: int) -> Callable[[str], int]:
    """argparse type of a count in ``[lo, hi]``: a negative or absurd count fails at parse time (exit status 2)."""

    def parse(text: str) -> int:
        return _bounded_int(text, lo, hi)

    parse.__name__ = "count"  # argparse names the type in some messages
    return parse


# --------------------------------------------------------------------------------------------------
# Output files: checked before any computation
# --------------------------------------------------------------------------------------------------


def _check_output_path(path: str, directory: bool = False, suffixes: Sequence[str] = ()) -> None:
    """Fail (CliInputError, exit status 2) before any computation if ``path`` cannot be written.

    A file path must not be a directory, an existing file must be writable, and its directory must exist and be
    writable; with ``suffixes`` its extension must be one of them. A ``directory`` (created when missing, as
    ``verify --report`` does) must not be a file and must be writable, or its parent must be an existing writable
    directory: a mistyped path does not create a tree of directories.
    """
    p = Path(path)
    if suffixes and p.suffix.lower() not in suffixes:
        raise CliInputError(f"{path}: unknown output file extension {p.suffix!r}; use {' or '.join(suffixes)}")
    if directory:
        if p.exists() and not p.is_dir():
            raise CliInputError(f"{path}: exists and is not a directory")
        parent = p if p.is_dir() else p.parent
    elif p.is_dir():
        raise CliInputError(f"{path}: is a directory, expected an output file")
    else:
        parent = p.parent
    if not parent.is_dir():
        why = "does not exist" if not parent.exists() else "is not a directory"
        raise CliInputError(f"{path}: cannot write there: directory {str(parent)!r} {why}")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CliInputError(f"{path}: cannot write there: directory {str(parent)!r} is not writable")
    if not directory and p.exists() and not os.access(p, os.W_OK):
        raise CliInputError(f"{path}: file exists and is not writable")


def _emit_results(
    args: argparse.Namespace, result: dict[str, Any], text: str, write_report: Callable[[str], Path]
) -> None:
    """``--json -``: ``result`` alone on stdout; else ``text``, and ``--json FILE`` written. Then ``--report DIR``
    by ``write_report(DIR)`` (its status line on stderr when stdout holds the JSON)."""
    if args.json == "-":
        _print_json(result)
    else:
        print(text)
        if args.json:
            Path(args.json).write_text(json.dumps(result, indent=2, allow_nan=False) + "\n", encoding="utf-8")
            print(f"results written to {args.json}")
    if args.report:
        path = write_report(args.report)
        print(f"report written to {path}", file=sys.stderr if args.json == "-" else sys.stdout)


def _check_report_and_json(args: argparse.Namespace) -> None:
    """Before any work: ``--report DIR`` must be writable and matplotlib installed (the directory is created now,
    so that ``--json DIR/file.json`` may go into it); ``--json FILE`` writable."""
    if args.report:
        _check_output_path(args.report, directory=True)
        if importlib.util.find_spec("matplotlib") is None:
            raise CliInputError(f"--report {args.report}: the figures need matplotlib: pip install 'sweepik[plot]'")
        try:
            Path(args.report).mkdir(exist_ok=True)
        except OSError as exc:
            raise CliInputError(f"--report {args.report}: cannot create the directory: {exc.strerror}") from None
    if args.json and args.json != "-":
        _check_output_path(args.json)


# --------------------------------------------------------------------------------------------------
# Progress on stderr
# --------------------------------------------------------------------------------------------------

#: Show progress only for runs longer than this (seconds), and only on a terminal.
PROGRESS_AFTER_S = 2.0
#: Least time between two redraws of the progress line (seconds).
PROGRESS_EVERY_S = 0.2


class _Progress:
    """A one-line progress indicator on stderr, shown only when stderr is a terminal and once a run exceeds
    ``PROGRESS_AFTER_S``; a callable ``progress(stage, done, total)`` as :mod:`sweepik.experiments.verify` expects.

    ``enabled=False`` turns it off whatever stderr is (e.g. when the output itself streams to the terminal).
    :meth:`close` ends a line left unfinished (an error or an interruption mid-run).
    """

    def __init__(self, enabled: bool = True) -> None:
        self.start = time.monotonic()
        self.last = 0.0
        self.stream = sys.stderr
        self.enabled = enabled and _isatty(self.stream)
        self.open = False  # a progress line is on screen without its newline

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if not self.enabled or now - self.start < PROGRESS_AFTER_S:
            return
        if now - self.last < PROGRESS_EVERY_S and done < total:
            return
        self.last = now
        width = 30
        filled = int(width * min(done, total) / max(total, 1))
        self.stream.write(f"\r{stage:<22} [{'#' * filled}{'.' * (width - filled)}] {done:,}/{total:,}")
        self.open = done < total
        if not self.open:
            self.stream.write("\n")
        self.stream.flush()

    def close(self) -> None:
        if self.open:
            self.stream.write("\n")
            self.stream.flush()
            self.open = False


def _isatty(stream: Any) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or a closed stream
        return False
