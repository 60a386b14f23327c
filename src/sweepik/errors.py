"""Exception hierarchy: every error sweepik raises on bad input derives from :class:`SweepikError`.

Grouped by area:

- the model (robots, robot files, URDF, MJCF, catalogues): :class:`RobotDefinitionError`, :class:`RobotFileError`,
  :class:`UrdfError`, :class:`MjcfError`, :class:`UnknownRobotError`;
- the decomposition: :class:`NoReductionError`, :class:`SearchOverflowError`;
- input to a call (arrays, poses, options, files of poses, locked joints): :class:`ShapeError`,
  :class:`NonFiniteError`, :class:`InvalidPoseError`, :class:`UnknownOptionError`, :class:`LockedJointError`,
  :class:`PoseFileError`;
- the solution store: :class:`StoreError`.
"""

from __future__ import annotations

__all__ = [
    "SweepikError",
    "RobotDefinitionError",
    "RobotFileError",
    "UrdfError",
    "MjcfError",
    "UnknownRobotError",
    "ShapeError",
    "NonFiniteError",
    "InvalidPoseError",
    "UnknownOptionError",
    "PoseFileError",
    "NoReductionError",
    "SearchOverflowError",
    "LockedJointError",
    "StoreError",
]


class SweepikError(ValueError):
    """Root of all sweepik errors (a ``ValueError``, so callers may catch either)."""


# the model: robots, robot files, URDF


class RobotDefinitionError(SweepikError):
    """A robot or joint definition is inconsistent (unknown joint type, lower limit above upper, ...)."""


class RobotFileError(RobotDefinitionError):
    """A robot file is malformed, incomplete, unreadable (a directory, no permission, over 1 MiB, not UTF-8) or
    out of bounds; the message names the file, and the joint and field where there is one."""


class UrdfError(RobotFileError):
    """A URDF file or text is refused: not XML, a DTD or entity declaration (refused outright), over the size or
    joint bounds of :mod:`sweepik.io.urdf`, a broken tree (missing link, cycle, two roots, duplicate names), a bad
    number, or a chain sweepik cannot model (mimic, floating or planar joints on it); the message names the file,
    and the joint or link where there is one."""


class MjcfError(RobotFileError):
    """An MJCF file is refused: MuJoCo cannot read it, the ``mujoco`` package is missing, a name is not in it, or
    the chain has a joint sweepik cannot model (ball, free) or a slide without a range."""


class UnknownRobotError(SweepikError, LookupError):
    """No bundled robot of that name and no such file; the message lists the bundled robots."""


# input to a call: arrays, poses, options, pose files, locked joints


class ShapeError(SweepikError):
    """An array has the wrong shape (e.g. ``q`` with the wrong number of joints)."""


class NonFiniteError(SweepikError):
    """An input holds NaN or infinite values (or joint values beyond ``model.validate.MAX_JOINT_VALUE``, 1e30)."""


class InvalidPoseError(SweepikError):
    """A pose is not a rigid transform (rotation not orthonormal, bottom row not (0, 0, 0, 1)) or lies absurdly
    far (a translation coordinate beyond ``model.validate.MAX_TRANSLATION``, 1e30)."""


class UnknownOptionError(SweepikError):
    """An option got a value of the wrong type or outside its set or range (strategy, reduction, ``limits``,
    ``n_samples``, ``chunk_size``, the robot argument)."""


class PoseFileError(SweepikError):
    """A pose file cannot be read: missing, a directory, unreadable, too large, unknown extension, not UTF-8, or
    content not in a supported layout; the message names the file."""


class LockedJointError(UnknownOptionError):
    """A ``locked`` argument (``--lock``) names no joint of the arm, gives a value that is not a finite number or lies
    outside the joint's limits, or leaves other than six joints to solve for (a 7-joint arm without ``locked``)."""


# the decomposition


class NoReductionError(SweepikError):
    """No decomposition in sweepik's catalogue solves this arm (or not with the joint asked for as theta*); the
    message names the structure found and what a decomposition would need."""


class SearchOverflowError(SweepikError, RuntimeError):
    """A sweep's residual crosses zero more often along theta* on a pose than the search holds (millions of
    candidates): the decomposition cannot answer that pose (a continuum its tests do not see); the message names it.
    The automatic choice counts such a plan as failing its check."""


# the solution store


class StoreError(SweepikError):
    """A solution store cannot be used: missing, not a sweepik store, incomplete (an interrupted run: resume it),
    damaged, or (on resume) written for other poses, another robot or other options; the message names the store."""
