"""Reductions ("given theta*, solve the rest") and their registry."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

from ..errors import UnknownOptionError
from ..robot import Robot
from .base import Reduction
from .carm import CArmD1, CArmTheta2
from .decompose import choose
from .generic import GeometricReduction, Plan

__all__ = [
    "Reduction",
    "CArmD1",
    "CArmTheta2",
    "GeometricReduction",
    "Plan",
    "REDUCTIONS",
    "get_reduction",
    "is_default",
    "AUTO",
]

#: Name of the reduction derived from the arm's geometry (``reductions.decompose``).
AUTO = "auto"

#: Registry: name -> factory(robot). Factories raise RobotDefinitionError for robots they do not fit.
REDUCTIONS: dict[str, Callable[[Robot], Reduction]] = {
    "carm-d1": CArmD1,
    "carm-theta2": CArmTheta2,
}
#: Short aliases accepted by ``solve(..., reduction=...)`` and the CLI.
_ALIASES = {"d1": "carm-d1", "theta2": "carm-theta2"}


def get_reduction(robot: Robot, reduction: str | Reduction | None, free_joint: int | None = None) -> Reduction:
    """Resolve ``reduction`` for ``robot``: an instance as is; a name (``"auto"``: derived from the arm's
    geometry); None: the robot's ``default_reduction`` if it names one, else ``"auto"``. ``free_joint`` (a joint
    index) asks the automatic decomposition for that theta*. NoReductionError when no decomposition applies."""
    if isinstance(reduction, Reduction):
        return reduction
    name = _name(robot, reduction, free_joint)
    if name == AUTO:
        return _automatic(robot, free_joint)
    if name not in REDUCTIONS:
        raise UnknownOptionError(
            f"unknown reduction {reduction!r}; choose one of {sorted(REDUCTIONS) + sorted(_ALIASES) + [AUTO]}"
        )
    return _cached(robot, name)


def _name(robot: Robot, reduction: str | None, free_joint: int | None) -> str:
    """The registry name (or ``AUTO``) that ``reduction`` resolves to (``get_reduction``)."""
    if reduction is None:
        reduction = AUTO if free_joint is not None else (robot.default_reduction or AUTO)
    return _ALIASES.get(reduction, reduction)


def is_default(robot: Robot, reduction: object) -> bool:
    """Whether ``reduction`` (None or a name) resolves to ``robot``'s default reduction, the one None gives."""
    return reduction is None or (type(reduction) is str and _name(robot, reduction, None) == _name(robot, None, None))


@lru_cache(maxsize=64)
def _cached(robot: Robot, name: str) -> Reduction:
    # Robots are values (equal and hashed by content): one reduction instance per (robot, name).
    return REDUCTIONS[name](robot)


@lru_cache(maxsize=64)
def _automatic(robot: Robot, free_joint: int | None) -> Reduction:
    return GeometricReduction(robot, choose(robot, free_joint))
