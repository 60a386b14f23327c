"""``sweepik.analyze``: what the automatic decomposition makes of an arm (structure, every plan, the choice)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np

from sweepik.errors import UnknownOptionError
from sweepik.io.robot_file import load_robot
from sweepik.model.origin_axis import HeldJoints, hold_joints
from sweepik.model.robot import Robot
from sweepik.reductions.decompose import explain

__all__ = ["analyze", "lock_options", "plan_line"]

#: Where in a joint's range the "generic value" of a lock lies (a fraction of the range from the lower limit, not
#: a simple ratio, so that it is no special angle such as 0 or 90 degrees).
GENERIC_LOCK_FRACTION = 0.381966


def _generic_value(robot: Robot, k: int) -> float:
    lo, hi = float(robot.lower[k]), float(robot.upper[k])
    if robot.is_revolute[k]:
        lo, hi = max(lo, -np.pi), min(hi, np.pi)
    elif hi - lo > 10.0 * robot.length_scale:  # a rail without a practical end: stay near its start
        hi = lo + robot.length_scale
    return lo + GENERIC_LOCK_FRACTION * (hi - lo)


def lock_options(robot: Robot) -> list[dict[str, Any]]:
    """For an arm with seven joints: for each joint, what locking it leaves (the six-joint arm's structure and the
    decomposition ``solve`` would use), at a generic value and at 0 (when 0 is inside its limits; the structure
    can differ there, e.g. two axes turn parallel). Arms with six joints or fewer (or more than seven) give [].

    Each entry: ``joint`` (index from 0), ``joint_number``, ``joint_name``, and ``values``: a list of
    ``{"value", "structure", "chosen", "reason"}`` (``chosen`` as in :func:`analyze`, None with a ``reason``).
    """
    if robot.n_joints != 7:
        return []
    out = []
    for k in range(robot.n_joints):
        values = [_generic_value(robot, k)]
        if robot.lower[k] - robot.limit_tol[k] <= 0.0 <= robot.upper[k] + robot.limit_tol[k]:
            values.insert(0, 0.0)
        rows = []
        for v in values:
            info = explain(hold_joints(robot, {k: v}).arm)
            rows.append(
                {"value": v, "structure": info["structure"], "chosen": info["chosen"], "reason": info["reason"]}
            )
        out.append({"joint": k, "joint_number": k + 1, "joint_name": robot.joint_names[k], "values": rows})
    return out


def analyze(robot: Robot | str, locked: Mapping[Any, float] | None = None) -> dict[str, Any]:
    """The arm's structure, every decomposition in sweepik's catalogue that solves it, and the one the automatic
    decomposition (``solve(..., reduction="auto")``, the default unless the robot file names a reduction) uses, or
    why there is none, as plain values.

    Keys: ``robot``, ``structure`` (e.g. ``"RRRRRR: 1∩2, 2∥3, 4∩5∩6 (one point)"``, joints numbered from 1),
    ``plans`` (best first; each with ``family``, ``closed_form``, ``free_joint`` (index from 0, as ``solve``'s
    ``free_joint`` takes it; None for a closed form), ``free_joint_number`` (from 1), ``free_joint_name``,
    ``chain`` ('forward' or 'reversed'), ``case``, ``branches``, ``blind_spot`` and ``steps``, the subproblem
    chain in words, joints numbered from 1), ``chosen`` (a plan or None) and ``reason`` (why none, else None).
    ``robot``: a Robot, or a bundled name or robot file path. ``locked`` (joint name or index -> value, as
    :func:`~sweepik.solve` takes it): analyse the arm with those joints held; ``free_joint`` and
    ``free_joint_number`` are then still the full arm's (what ``solve(..., locked=..., free_joint=...)`` takes),
    while ``structure`` and ``steps`` number the joints of the smaller arm: ``arm_joints`` gives their numbers in
    the full arm (from 1), ``held`` the held joints' values. A seven-joint arm without ``locked`` has no plans of
    its own; its ``locks`` key (see :func:`lock_options`) tells, joint by joint, which lock gives a closed form or a
    sweep.

    >>> from sweepik import analyze
    >>> info = analyze("puma560")
    >>> info["chosen"]["closed_form"], info["chosen"]["branches"]
    (True, 8)
    """
    if isinstance(robot, str):
        robot = load_robot(robot)
    if not isinstance(robot, Robot):
        raise UnknownOptionError(f"robot must be a sweepik.Robot or a name/path, got {type(robot).__name__}")
    if locked:
        held = hold_joints(robot, locked)
        return _numbered_in_full_arm(explain(held.arm), held)
    info = explain(robot)
    if robot.n_joints == 7:
        info["locks"] = lock_options(robot)
        info["reason"] = (
            f"robot {robot.name!r} has 7 joints: lock one (solve(..., locked={{name: value}}), --lock NAME=VALUE); "
            "'locks' tells which lock gives a closed form or a sweep"
        )
    return info


def _numbered_in_full_arm(info: dict[str, Any], held: HeldJoints) -> dict[str, Any]:
    """``explain`` of the smaller arm with each plan's ``free_joint`` (and number) those of the full arm, as
    ``solve(..., locked=..., free_joint=...)`` takes them; ``held`` and ``arm_joints`` keys added."""
    others = [p for p in (info["chosen"], info.get("companion")) if p]
    for plan in [*info["plans"], *info["checks"], *others]:
        if plan["free_joint"] is not None:
            plan["free_joint"] = held.free[plan["free_joint"]]
            plan["free_joint_number"] = plan["free_joint"] + 1
    info["held"] = {held.robot.joint_names[k]: v for k, v in held.held}
    info["arm_joints"] = [k + 1 for k in held.free]
    return info


def plan_line(plan: dict[str, Any]) -> str:
    """One line describing a plan of ``analyze``, e.g. ``closed form, 8 branches`` or ``sweep joint 1 (d1), 4
    branches``."""
    if plan["family"] == "general":
        return f"general method (elimination), up to {plan['branches']} solutions"
    if plan["closed_form"]:
        head = "closed form"
    else:
        head = f"sweep joint {plan['free_joint_number']} ({plan['free_joint_name']})"
    chain = ", reversed chain" if plan["chain"] == "reversed" else ""
    blind = ", blind spot" if plan["blind_spot"] else ""
    return f"{head}, {plan['branches']} branches{chain}{blind}"
