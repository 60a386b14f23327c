"""``sweepik.analyze``: what the automatic decomposition makes of an arm (structure, every plan, the choice)."""

from __future__ import annotations

from typing import Any

from .errors import UnknownOptionError
from .reductions.decompose import explain
from .robot import Robot
from .robot_file import load_robot

__all__ = ["analyze"]


def analyze(robot: Robot | str) -> dict[str, Any]:
    """The arm's structure, every decomposition in sweepik's catalogue that solves it, and the one the automatic
    decomposition (``solve(..., reduction="auto")``, the default unless the robot file names a reduction) uses, or
    why there is none, as plain values.

    Keys: ``robot``, ``structure`` (e.g. ``"RRRRRR: 1∩2, 2∥3, 4∩5∩6 (one point)"``, joints numbered from 1),
    ``plans`` (best first; each with ``family``, ``closed_form``, ``free_joint`` (index from 0, as ``solve``'s
    ``free_joint`` takes it; None for a closed form), ``free_joint_number`` (from 1), ``free_joint_name``,
    ``chain`` ('forward' or 'reversed'), ``case``, ``branches``, ``blind_spot`` and ``steps``, the subproblem
    chain in words, joints numbered from 1), ``chosen`` (a plan or None) and ``reason`` (why none, else None).
    ``robot``: a Robot, or a bundled name or robot file path.

    >>> from sweepik import analyze
    >>> info = analyze("puma560")
    >>> info["chosen"]["closed_form"], info["chosen"]["branches"]
    (True, 8)
    """
    if isinstance(robot, str):
        robot = load_robot(robot)
    if not isinstance(robot, Robot):
        raise UnknownOptionError(f"robot must be a sweepik.Robot or a name/path, got {type(robot).__name__}")
    return explain(robot)
