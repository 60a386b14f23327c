"""Helpers shared by the ``sweepik`` subcommands: robot and number parsing, units, tables, JSON."""

from __future__ import annotations

import argparse
import json
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import SweepikError
from .robot import Robot

PROG = "sweepik"
#: Robot used when a subcommand's optional ROBOT argument is left out.
DEFAULT_ROBOT = "carm"
#: Exit status for bad input (the same as argparse's usage errors).
EXIT_USAGE = 2
#: Exit status when a file cannot be read.
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


def _format_table(header: Sequence[str], rows: Sequence[Sequence[str]], indent: str = "  ") -> str:
    """Columns padded to equal width; columns holding only numbers are right-aligned."""
    table = [list(header), *(list(r) for r in rows)]
    widths = [max(len(r[i]) for r in table) for i in range(len(header))]
    right = [bool(rows) and all(_is_number(r[i]) for r in rows) for i in range(len(header))]
    lines = []
    for r in table:
        cells = [c.rjust(w) if rj else c.ljust(w) for c, w, rj in zip(r, widths, right, strict=True)]
        lines.append((indent + "  ".join(cells)).rstrip())
    return "\n".join(lines)


def _print_json(obj: Any) -> None:
    print(json.dumps(obj, indent=2, allow_nan=False))


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


# --------------------------------------------------------------------------------------------------
# fk
# --------------------------------------------------------------------------------------------------


def _nonnegative_int(text: str) -> int:
    """argparse type: an integer >= 0 (a seed, a count)."""
    try:
        v = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {text!r}") from None
    if v < 0:
        raise argparse.ArgumentTypeError(f"expected a non-negative integer, got {v}")
    return v


def _check_output_path(path: str, directory: bool = False) -> None:
    """Fail before any computation if ``path`` (a file, or a directory to create with ``directory``) cannot be
    written: its parent must be an existing writable directory; a file path must not be a directory."""
    p = Path(path)
    parent = p.parent if str(p.parent) else Path(".")
    if directory and p.is_dir():
        parent = p
    elif p.is_dir():
        raise CliInputError(f"{path}: is a directory, expected an output file")
    elif directory and p.exists():
        raise CliInputError(f"{path}: exists and is not a directory")
    if not parent.is_dir():
        raise CliInputError(f"{path}: cannot write there: directory {str(parent)!r} does not exist")
    if not os.access(parent, os.W_OK | os.X_OK):
        raise CliInputError(f"{path}: cannot write there: directory {str(parent)!r} is not writable")
