"""The robot model: joints from a Denavit-Hartenberg table, limits, base and tool transforms.

Conventions
-----------
* ``dh_convention="modified"`` (Craig 2005): row i holds ``a_{i-1}, alpha_{i-1}, d_i, theta_i`` and the link
  transform is ``RotX(alpha_{i-1}) TransX(a_{i-1}) RotZ(theta_i) TransZ(d_i)``; joint i moves frame i.
* ``dh_convention="standard"``: row i holds ``a_i, alpha_i, d_i, theta_i`` and the link transform is
  ``RotZ(theta_i) TransZ(d_i) TransX(a_i) RotX(alpha_i)``.
* A revolute joint's value q_i (radians) is added to the row's constant ``theta`` (its offset); a prismatic
  joint's value (length unit) is added to the row's constant ``d``.
* ``dh_convention="none"``: no DH table; each joint carries ``origin`` (the fixed transform from the previous
  joint's frame, or the base, to this joint's frame at q = 0) and ``axis`` (unit vector in that frame), as URDF
  writes a chain: the link transform is ``origin @ Rot(axis, q_i)`` or ``origin @ Trans(axis * q_i)``.
* ``fk(q) = T_world_base @ T_0_1(q_1) @ ... @ T_{n-1}_n(q_n) @ T_flange_tool``.
* Robots are values: two robots with the same content are equal, hash alike and pickle to equal robots.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field, replace
from functools import cached_property
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import RobotDefinitionError, SweepikError
from sweepik.model import kinematics
from sweepik.model.chain import Chain
from sweepik.model.structure import INTERSECT_TOL_REL, Structure, structure_of
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import check_configuration, check_poses

__all__ = ["Joint", "Robot", "JointType", "DHConvention"]

JointType = Literal["revolute", "prismatic"]
DHConvention = Literal["modified", "standard", "none"]
Array = NDArray[np.float64]

#: Joint values this far outside a limit still count as inside: 1e-9 rad for revolute joints and
#: LIMIT_TOL_REL times the arm's length scale for prismatic ones (C-Arm: 2.8e-6 mm). A solution exactly at a
#: limit comes out of the solver with a rounding error that can be larger than that of a generic solution
#: (the root is found to ~noise / slope, and the slope can be small), far below any mechanical meaning.
LIMIT_TOL = 1e-9
LIMIT_TOL_REL = 1e-9
#: ``Robot.length_scale`` counts a prismatic range at most this many times the sum of the link lengths.
SPAN_CAP = 10.0
#: A joint axis shorter than this (before normalisation) is refused as having no direction.
AXIS_MIN_NORM = 1e-9


@dataclass(frozen=True)
class Joint:
    """One joint: its type, its DH row (constants; the joint value adds to ``theta`` or ``d``) and limits.

    Angles in radians, lengths in the robot's length unit.
    """

    type: JointType
    a: float = 0.0
    alpha: float = 0.0
    d: float = 0.0
    theta: float = 0.0
    lower: float = -np.pi
    upper: float = np.pi
    name: str = ""
    #: Only for ``dh_convention="none"``: the fixed 4x4 transform from the previous frame to this joint's frame
    #: at q = 0 (rows, as nested tuples), and the joint axis in that frame (normalised on construction).
    origin: tuple[tuple[float, ...], ...] | None = None
    axis: tuple[float, float, float] = (0.0, 0.0, 1.0)
    #: Mass (kg) of the link this joint moves and its centre of mass in this joint's link frame (length unit; the
    #: frame ``Robot.frames(q)[i + 1]`` of joint i). Only the statics (:mod:`sweepik.experiments.statics`) use them.
    mass: float = 0.0
    com: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        label = self.name or "joint"
        if self.type not in ("revolute", "prismatic"):
            raise RobotDefinitionError(f"{label}: type must be 'revolute' or 'prismatic', got {self.type!r}")
        for f in ("a", "alpha", "d", "theta", "lower", "upper", "mass"):
            v = getattr(self, f)
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(float(v)):
                raise RobotDefinitionError(f"{label}: {f} must be a finite number, got {v!r}")
            object.__setattr__(self, f, float(v))
        if self.mass < 0.0:
            raise RobotDefinitionError(f"{label}: mass must be >= 0 kg, got {self.mass!r}")
        object.__setattr__(self, "com", _finite_triple(self.com, f"{label}: com"))
        if self.lower > self.upper:
            raise RobotDefinitionError(f"{label}: lower limit {self.lower:g} is above upper limit {self.upper:g}")
        try:
            axis = np.array(self.axis, dtype=np.float64)
        except (TypeError, ValueError):
            raise RobotDefinitionError(f"{label}: axis must be 3 numbers, got {self.axis!r}") from None
        norm = float(np.linalg.norm(axis)) if axis.shape == (3,) and np.all(np.isfinite(axis)) else 0.0
        if norm < AXIS_MIN_NORM:
            raise RobotDefinitionError(f"{label}: axis must be 3 finite numbers, not all zero, got {self.axis!r}")
        object.__setattr__(self, "axis", tuple(float(v) for v in axis / norm))
        if self.origin is not None:
            try:
                T = _frozen(self.origin, f"{label}: origin")
            except SweepikError as exc:
                raise RobotDefinitionError(str(exc)) from None
            object.__setattr__(self, "origin", tuple(tuple(float(v) for v in row) for row in T))

    @property
    def is_revolute(self) -> bool:
        return self.type == "revolute"

    def with_added_mass(self, mass: float, com: ArrayLike) -> Joint:
        """This joint with a point mass ``mass`` (kg) at ``com`` (its link frame) added to its link: the masses
        add, the centre of mass is their weighted mean (a link held rigidly to this one merges so)."""
        total = self.mass + float(mass)
        if total <= 0.0:
            return self
        c = (self.mass * np.array(self.com) + float(mass) * np.asarray(com, dtype=np.float64)) / total
        return replace(self, mass=total, com=(float(c[0]), float(c[1]), float(c[2])))

    @property
    def offset(self) -> float:
        """Constant added to the joint value: ``theta`` for a revolute joint, ``d`` for a prismatic one."""
        return self.theta if self.is_revolute else self.d


def _finite_triple(v: object, what: str) -> tuple[float, float, float]:
    try:
        arr = np.array(v, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.zeros(0)
    if arr.shape != (3,) or not np.all(np.isfinite(arr)):
        raise RobotDefinitionError(f"{what} must be 3 finite numbers, got {v!r}")
    return (float(arr[0]), float(arr[1]), float(arr[2]))


def _frozen(T: ArrayLike | None, what: str) -> Array:
    arr = np.eye(4) if T is None else check_poses(T, what).copy()
    if arr.shape != (4, 4):
        raise RobotDefinitionError(f"{what} must be a single 4x4 transform, got shape {arr.shape}")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Robot:
    """An immutable serial robot. See the module docstring for conventions.

    >>> r = Robot("slider", (Joint("prismatic", lower=0, upper=1), Joint("revolute", a=0.5)))
    >>> r.fk([0.2, 0.0])[:3, 3].tolist()
    [0.5, 0.0, 0.2]
    """

    name: str
    joints: tuple[Joint, ...]
    dh_convention: DHConvention = "modified"
    T_world_base: Array = field(default_factory=lambda: np.eye(4))
    T_flange_tool: Array = field(default_factory=lambda: np.eye(4))
    length_unit: str = "mm"
    default_reduction: str | None = None
    description: str = ""
    #: Direction of gravity in the world frame (a unit vector; normalised on construction): only the statics
    #: (:mod:`sweepik.experiments.statics`) use it. Default: -z of the world frame.
    gravity: tuple[float, float, float] = (0.0, 0.0, -1.0)

    def __post_init__(self) -> None:
        if self.dh_convention not in ("modified", "standard", "none"):
            raise RobotDefinitionError(
                f"{self.name}: dh_convention must be 'modified', 'standard' or 'none', got {self.dh_convention!r}"
            )
        joints = tuple(self.joints)
        if not joints or not all(isinstance(j, Joint) for j in joints):
            raise RobotDefinitionError(f"{self.name}: joints must be a non-empty sequence of Joint")
        for i, j in enumerate(joints):
            label = f"{self.name}: joint {i + 1} ({j.name or 'unnamed'})"
            if self.dh_convention == "none" and j.origin is None:
                raise RobotDefinitionError(f"{label}: dh_convention 'none' needs an origin transform on every joint")
            if self.dh_convention != "none" and (j.origin is not None or j.axis != (0.0, 0.0, 1.0)):
                raise RobotDefinitionError(
                    f"{label}: origin/axis describe a joint only with dh_convention 'none' (DH joints move about z)"
                )
            if self.dh_convention == "none" and (j.a, j.alpha, j.d, j.theta) != (0.0, 0.0, 0.0, 0.0):
                raise RobotDefinitionError(
                    f"{label}: DH parameters a/alpha/d/theta are not used with dh_convention 'none'"
                )
        names = [j.name or f"q{i + 1}" for i, j in enumerate(joints)]  # (as joint_names)
        repeated = sorted({n for n in names if names.count(n) > 1})
        if repeated:
            raise RobotDefinitionError(
                f"{self.name}: joint names must differ (solve's free_joint and locked name joints): "
                f"{', '.join(map(repr, repeated))} used more than once"
            )
        mm_per_unit(self.length_unit)  # (RobotDefinitionError naming the supported units)
        object.__setattr__(self, "joints", joints)
        g = np.array(_finite_triple(self.gravity, f"{self.name}: gravity"))
        if float(np.linalg.norm(g)) < AXIS_MIN_NORM:
            raise RobotDefinitionError(f"{self.name}: gravity must be a direction (not all zero), got {self.gravity!r}")
        norm = float(np.linalg.norm(g))
        if abs(norm - 1.0) > 4 * np.finfo(float).eps:  # a unit vector stays as it is: equal robots stay equal
            g = g / norm
        object.__setattr__(self, "gravity", _finite_triple(g, "gravity"))
        object.__setattr__(self, "T_world_base", _frozen(self.T_world_base, f"{self.name}: base transform"))
        object.__setattr__(self, "T_flange_tool", _frozen(self.T_flange_tool, f"{self.name}: tool transform"))
        for attr, values in (
            ("dh_a", [j.a for j in joints]),
            ("dh_alpha", [j.alpha for j in joints]),
            ("dh_d", [j.d for j in joints]),
            ("dh_theta", [j.theta for j in joints]),
            ("lower", [j.lower for j in joints]),
            ("upper", [j.upper for j in joints]),
        ):
            arr = np.array(values, dtype=np.float64)
            arr.setflags(write=False)
            object.__setattr__(self, attr, arr)
        rev = np.array([j.is_revolute for j in joints])
        rev.setflags(write=False)
        object.__setattr__(self, "is_revolute", rev)

    # Populated in __post_init__ (declared for type checkers).
    dh_a: Array = field(init=False, repr=False)
    dh_alpha: Array = field(init=False, repr=False)
    dh_d: Array = field(init=False, repr=False)
    dh_theta: Array = field(init=False, repr=False)
    lower: Array = field(init=False, repr=False)
    upper: Array = field(init=False, repr=False)
    is_revolute: NDArray[np.bool_] = field(init=False, repr=False)

    def _content(self) -> tuple[object, ...]:
        return (
            self.name,
            self.joints,
            self.dh_convention,
            self.T_world_base.tobytes(),
            self.T_flange_tool.tobytes(),
            self.length_unit,
            self.default_reduction,
            self.description,
            self.gravity,
        )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Robot):
            return NotImplemented
        return self is other or self._content() == other._content()

    def __hash__(self) -> int:
        return self._hash

    @cached_property
    def _hash(self) -> int:
        # (solve looks its reduction up by robot on every call: hashing the content each time cost ~40 us)
        return hash(self._content())

    def __reduce__(self) -> tuple[object, ...]:
        # Rebuild through the constructor (validation, read-only arrays); cached properties are not pickled.
        return (
            Robot,
            (
                self.name,
                self.joints,
                self.dh_convention,
                np.array(self.T_world_base),
                np.array(self.T_flange_tool),
                self.length_unit,
                self.default_reduction,
                self.description,
                self.gravity,
            ),
        )

    @cached_property
    def chain(self) -> Chain:
        """The arm in product-of-exponentials form (world frame, q = 0): see :mod:`sweepik.model.chain`."""
        zero = np.zeros(self.n_joints)
        frames = kinematics.chain_frames(self, zero)
        axes, points = kinematics.joint_axes(self, frames)
        return Chain.from_frames(axes, points, self.is_revolute, frames[-1] @ self.T_flange_tool)

    def structure(self, tol_rel: float | None = None) -> Structure:
        """Which joint axes intersect or stay parallel (see :mod:`sweepik.model.structure`); distances below
        ``tol_rel`` (default ``structure.INTERSECT_TOL_REL``) times ``length_scale`` count as zero."""
        tol = INTERSECT_TOL_REL if tol_rel is None else float(tol_rel)
        return structure_of(self.chain, self.length_scale, tol)

    @property
    def n_joints(self) -> int:
        return len(self.joints)

    @property
    def joint_names(self) -> list[str]:
        return [j.name or f"q{i + 1}" for i, j in enumerate(self.joints)]

    @property
    def limits(self) -> Array:
        """Joint limits ``(n, 2)``: radians for revolute joints, length unit for prismatic ones."""
        return np.stack([self.lower, self.upper], axis=-1)

    @cached_property
    def length_scale(self) -> float:
        """A characteristic length of the arm, for relative tolerances: the sum of |a| and |d| (or of the origin
        offsets, for ``dh_convention="none"``) plus the prismatic ranges, each range counted at most ``SPAN_CAP``
        times the links (a rail of 1e300 does not make the arm coarser: its tolerances would grow with it)."""
        links = float(np.sum(np.abs(self.dh_a)) + np.sum(np.abs(self.dh_d)))
        links += sum(float(np.linalg.norm(np.array(j.origin)[:3, 3])) for j in self.joints if j.origin is not None)
        span = np.where(self.is_revolute, 0.0, self.upper - self.lower)
        if links > 0.0:
            span = np.minimum(span, SPAN_CAP * links)
        return links + float(np.sum(span))

    def fk(self, q: ArrayLike) -> Array:
        """Tool pose ``(..., 4, 4)`` for joint values ``q (..., n)``.

        >>> from sweepik import load_robot
        >>> load_robot("carm").fk([500, 0, 0, 0, 0, 0])[:3, 3].round(6).tolist()
        [402.0, -350.0, 500.0]
        """
        qa = check_configuration(q, self.n_joints)
        frames = kinematics.chain_frames(self, qa)
        return frames[..., -1, :, :] @ self.T_flange_tool

    def frames(self, q: ArrayLike) -> Array:
        """World poses ``(..., n + 2, 4, 4)``: base, link frames 1..n, then the tool (for drawing the arm)."""
        qa = check_configuration(q, self.n_joints)
        frames = kinematics.chain_frames(self, qa)
        tool = frames[..., -1:, :, :] @ self.T_flange_tool
        return np.concatenate([frames, tool], axis=-3)

    def jacobian(self, q: ArrayLike) -> Array:
        """Geometric Jacobian ``(..., 6, n)`` in world coordinates at the tool point.

        Rows 0-2 map joint rates to the tool origin's linear velocity, rows 3-5 to the angular velocity.
        """
        qa = check_configuration(q, self.n_joints)
        return kinematics.geometric_jacobian(self, qa)

    def wrap(self, q: ArrayLike) -> Array:
        """Revolute joint values shifted by multiples of 2 pi into their limits where possible.

        Each revolute value is first wrapped into (-pi, pi], then, where that is outside the limits, moved by the
        multiple of 2 pi that brings it to the lowest value not below the lower limit, if that is inside them (limits
        of any number of turns from zero: [750, 850] deg takes two). Prismatic values are unchanged.
        """
        qa = check_configuration(q, self.n_joints, finite=False)
        two_pi = 2.0 * np.pi
        with np.errstate(invalid="ignore"):  # inf (a branch that does not exist) stays non-finite
            w = np.pi - np.mod(np.pi - qa, two_pi)
            if self._limits_beyond_pi:
                lo, hi = self.lower - self.limit_tol, self.upper + self.limit_tol
                cand = w + two_pi * np.ceil((lo - w) / two_pi)  # (the same bits as w +- 2 pi for one turn)
                w = np.where(((w < lo) | (w > hi)) & (cand >= lo) & (cand <= hi), cand, w)
        return np.where(self.is_revolute, w, qa)

    def limit_excess(self, q: ArrayLike) -> Array:
        """``(..., n)``: how far each joint value lies outside its limits (<= 0 inside; ``limit_tol`` not added),
        a revolute one measured from the middle of its limits modulo 2 pi: continuous along a motion whatever turn the
        limits lie in (a window 0.1 rad wide one turn from zero, or [750, 850] deg), where the value ``wrap`` gives
        jumps by a turn. NaN for a revolute value that is not finite."""
        qa = np.asarray(q, dtype=np.float64)
        mid = 0.5 * (self.lower + self.upper)
        with np.errstate(invalid="ignore"):
            near = mid + (np.pi - np.mod(np.pi - (qa - mid), 2.0 * np.pi))
        w = np.where(self.is_revolute, near, qa)
        return np.asarray(np.maximum(self.lower - w, w - self.upper))

    def within_limits(self, q: ArrayLike) -> NDArray[np.bool_]:
        """``(...)`` bool: all joint values inside their limits (revolute ones after ``wrap``), with ``limit_tol``."""
        return self.wrapped_within_limits(q)[1]

    def wrapped_within_limits(self, q: ArrayLike) -> tuple[Array, NDArray[np.bool_]]:
        """``wrap(q)`` and ``within_limits(q)`` in one pass."""
        w = self.wrap(q)
        return w, np.all((w >= self.lower - self.limit_tol) & (w <= self.upper + self.limit_tol), axis=-1)

    @cached_property
    def _limits_beyond_pi(self) -> bool:
        """Some revolute limit lies outside [-pi, pi]: only then can a shift by 2 pi bring a value inside."""
        rev = self.is_revolute
        return bool(np.any(rev & ((self.lower < -np.pi - LIMIT_TOL) | (self.upper > np.pi + LIMIT_TOL))))

    @cached_property
    def limit_tol(self) -> Array:
        """``(n,)`` tolerance of the limit checks (see ``LIMIT_TOL``)."""
        return np.where(self.is_revolute, LIMIT_TOL, LIMIT_TOL_REL * self.length_scale)

    @cached_property
    def base_is_identity(self) -> bool:
        return bool(np.array_equal(self.T_world_base, np.eye(4)))

    @cached_property
    def tool_is_identity(self) -> bool:
        return bool(np.array_equal(self.T_flange_tool, np.eye(4)))

    @cached_property
    def T_base_world(self) -> Array:
        """Inverse of ``T_world_base`` (cached)."""
        return np.asarray(np.linalg.inv(self.T_world_base), dtype=np.float64)

    @cached_property
    def T_tool_flange(self) -> Array:
        """Inverse of ``T_flange_tool`` (cached)."""
        return np.asarray(np.linalg.inv(self.T_flange_tool), dtype=np.float64)

    def dh_table(self) -> list[dict[str, float | str]]:
        """The DH table as rows of plain values (angles in degrees), for display."""
        rows: list[dict[str, float | str]] = []
        for name, j in zip(self.joint_names, self.joints, strict=True):
            rows.append(
                {
                    "joint": name,
                    "type": j.type,
                    "a": j.a,
                    "alpha_deg": float(np.degrees(j.alpha)),
                    "d": j.d,
                    "theta_deg": float(np.degrees(j.theta)),
                    "lower": float(np.degrees(j.lower)) if j.is_revolute else j.lower,
                    "upper": float(np.degrees(j.upper)) if j.is_revolute else j.upper,
                }
            )
        return rows
