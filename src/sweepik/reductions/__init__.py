"""Reductions ("given theta*, solve the rest") and their registry."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

from ..errors import UnknownOptionError
from ..robot import Robot
from .base import Reduction
from .carm import CArmD1, CArmTheta2

__all__ = ["Reduction", "CArmD1", "CArmTheta2", "REDUCTIONS", "get_reduction"]

#: Registry: name -> factory(robot). Factories raise RobotDefinitionError for robots they do not fit.
REDUCTIONS: dict[str, Callable[[Robot], Reduction]] = {
    "carm-d1": CArmD1,
    "carm-theta2": CArmTheta2,
}
#: Short aliases accepted by ``solve(..., reduction=...)`` and the CLI.
_ALIASES = {"d1": "carm-d1", "theta2": "carm-theta2"}


def get_reduction(robot: Robot, reduction: str | Reduction | None) -> Reduction:
    """Resolve ``reduction`` (None: the robot's default; a name; or an instance) for ``robot``."""
    if isinstance(reduction, Reduction):
        return reduction
    if reduction is None:
        if robot.default_reduction is None:
            raise UnknownOptionError(
                f"robot {robot.name!r} names no default reduction; pass reduction= one of {sorted(REDUCTIONS)} "
                "or a Reduction instance"
            )
        reduction = robot.default_reduction
    name = _ALIASES.get(reduction, reduction)
    if name not in REDUCTIONS:
        raise UnknownOptionError(
            f"unknown reduction {reduction!r}; choose one of {sorted(REDUCTIONS) + sorted(_ALIASES)}"
        )
    return _cached(robot, name)


@lru_cache(maxsize=64)
def _cached(robot: Robot, name: str) -> Reduction:
    # Robots are immutable and hash by identity: one reduction instance per (robot, name).
    return REDUCTIONS[name](robot)
