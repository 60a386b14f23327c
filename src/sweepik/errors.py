"""Exception hierarchy: every error sweepik raises on bad input derives from :class:`SweepikError`."""

from __future__ import annotations

__all__ = [
    "SweepikError",
    "RobotDefinitionError",
    "RobotFileError",
    "UnknownRobotError",
    "ShapeError",
    "NonFiniteError",
    "InvalidPoseError",
    "UnknownOptionError",
    "PoseFileError",
]


class SweepikError(ValueError):
    """Root of all sweepik errors (a ``ValueError``, so callers may catch either)."""


class RobotDefinitionError(SweepikError):
    """A robot or joint definition is inconsistent (unknown joint type, lower limit above upper, ...)."""


class RobotFileError(RobotDefinitionError):
    """A robot file is malformed or incomplete; the message names the file, the joint and the field."""


class UnknownRobotError(SweepikError, LookupError):
    """No bundled robot of that name and no such file; the message lists the bundled robots."""


class ShapeError(SweepikError):
    """An array has the wrong shape (e.g. ``q`` with the wrong number of joints)."""


class NonFiniteError(SweepikError):
    """An input holds NaN or infinite values."""


class InvalidPoseError(SweepikError):
    """A pose is not a rigid transform (rotation not orthonormal, bottom row not (0, 0, 0, 1))."""


class UnknownOptionError(SweepikError):
    """An option takes one of a fixed set of values (strategy, reduction, ...) and got another."""


class PoseFileError(SweepikError):
    """A pose file cannot be read: missing, unknown extension, or content not in a supported layout."""
