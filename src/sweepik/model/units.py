"""Length units: the paper's constants are in millimetres; robots may use other units."""

from __future__ import annotations

from sweepik.errors import RobotDefinitionError

#: Millimetres per unit of each supported length unit.
MM_PER_UNIT = {"mm": 1.0, "cm": 10.0, "m": 1000.0, "in": 25.4}


def mm_per_unit(length_unit: str) -> float:
    """Millimetres in one ``length_unit``; RobotDefinitionError for an unknown unit."""
    try:
        return MM_PER_UNIT[length_unit]
    except KeyError:
        raise RobotDefinitionError(
            f"unknown length unit {length_unit!r}; supported: {', '.join(MM_PER_UNIT)}"
        ) from None


def orientation_weight(length_unit: str) -> float:
    """The paper's 100 mm orientation weight expressed in ``length_unit``."""
    return 100.0 / mm_per_unit(length_unit)
