"""Result types: ``Solutions`` (all IK solutions of one pose), ``Family`` (a self-motion continuum) and
``SolutionBatch`` (the solutions of many poses, held in columns).

``solve_many`` of a million poses should not build a million Python objects unless asked: the solver keeps each
chunk's solutions as stacked arrays (``Block``), and a batch is a sequence of blocks. Indexing or iterating a
batch builds the :class:`~sweepik.results.Solutions` of the poses asked for; the column attributes
(``offsets``, ``q``, ``error``, ...) give every solution of every pose at once, pose ``i``'s solutions being the
rows ``offsets[i]:offsets[i + 1]``.
"""

from __future__ import annotations

import bisect
import dataclasses
import numbers
import operator
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, cast, overload

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import ShapeError, SweepikError, UnknownOptionError
from sweepik.model.validate import check_choice, check_configuration, check_int, short_repr

if TYPE_CHECKING:
    from sweepik.model.origin_axis import HeldJoints
    from sweepik.model.robot import Robot
    from sweepik.reductions.base import Reduction

Array = NDArray[np.float64]
#: How a :class:`Family` computes its members: ``(reduction, chain_pose, branch, theta, lo, hi) -> q``.
MemberFunction = Callable[["Reduction", Array, int, Array, float, float], Array]

#: Most members ``Family.sample`` gives in one call (a bigger grid is a loop over calls).
MAX_FAMILY_SAMPLES = 10_000_000
#: Tolerance when asking a family for a member just outside its interval (relative to the interval length).
_FAMILY_EDGE_TOL = 1e-9


def joint_distance(robot: Robot, q: ArrayLike, q_ref: ArrayLike, wrap: bool = True) -> Array:
    """Per-joint absolute differences ``(..., n)``: revolute ones wrapped modulo 2 pi (radians), unless ``wrap`` is
    False (2 pi windings then count as far apart as they are)."""
    d = np.asarray(q, dtype=np.float64) - np.asarray(q_ref, dtype=np.float64)
    if not wrap:
        return np.abs(d)
    wrapped = np.abs(np.pi - np.mod(np.pi - d, 2.0 * np.pi))
    return np.where(robot.is_revolute, wrapped, np.abs(d))


def weighted_joint_distance(robot: Robot, q: ArrayLike, q_ref: ArrayLike, wrap: bool = True) -> Array:
    """Distance ``(...)`` between configurations ``q (..., n)`` and ``q_ref (n,)``, dimensionless: the default
    metric of joint space in sweepik (``Solutions.nearest``, ``follow_path``; ``metric="weighted"``).

    Angles are compared modulo 2 pi (radians); prismatic differences are divided by the paper's weight
    (100 mm per radian, eq. 6c, in the robot's length unit), then the Euclidean norm is taken. ``wrap``: see
    :func:`joint_distance`.
    """
    return np.asarray(np.linalg.norm(_scaled_joint_distance(robot, q, q_ref, wrap), axis=-1))


def linf_joint_distance(robot: Robot, q: ArrayLike, q_ref: ArrayLike, wrap: bool = True) -> Array:
    """The largest joint move ``(...)`` from ``q_ref (n,)`` to ``q (..., n)`` (``metric="linf"``): angles modulo
    2 pi in radians, prismatic moves in units of the paper's weight (100 mm count as 1 radian). A planner's seed
    metric: a tolerance on it bounds every joint's step, where a summed metric lets one joint flip by pi while the
    others stay. ``wrap``: see :func:`joint_distance`."""
    return np.asarray(np.max(_scaled_joint_distance(robot, q, q_ref, wrap), axis=-1))


def _scaled_joint_distance(robot: Robot, q: ArrayLike, q_ref: ArrayLike, wrap: bool) -> Array:
    """``joint_distance`` with prismatic joints divided by the paper's weight (dimensionless)."""
    from sweepik.model.units import orientation_weight  # local import keeps this module's imports light

    scale = np.where(robot.is_revolute, 1.0, 1.0 / orientation_weight(robot.length_unit))
    return joint_distance(robot, q, q_ref, wrap) * scale


#: A joint-space distance: ``metric(robot, q (..., n), q_ref (n,), wrap) -> (...)``.
DistanceFunction = Callable[["Robot", ArrayLike, ArrayLike, bool], Array]
#: The joint-space metrics of ``Solutions.nearest``, ``Solutions.distances`` and ``follow_path``.
METRICS: dict[str, DistanceFunction] = {
    "weighted": weighted_joint_distance,
    "linf": linf_joint_distance,
}


def joint_metric(metric: object) -> DistanceFunction:
    """The distance function named ``metric`` (a key of ``METRICS``); UnknownOptionError for another value."""
    return METRICS[check_choice(metric, "metric", tuple(METRICS))]


def check_tolerance(tol: object, what: str = "tol") -> float | None:
    """``tol`` as a float >= 0 (None stays None); UnknownOptionError naming anything else."""
    if tol is None:
        return None
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real) or not np.isfinite(float(tol)) or tol < 0:
        raise UnknownOptionError(f"{what} must be a finite number >= 0, got {tol!r}")
    return float(tol)


#: Members sampled along a self-motion family before the nearest one is refined (golden section).
_FAMILY_SAMPLES = 721
#: Local minima of the sampled distance refined by ``_nearest_on_family`` (the lowest ones).
_NEAREST_MINIMA = 4
_GOLDEN_ITERS = 60


def _nearest_winding(robot: Robot, q: Array, ref: Array) -> Array:
    """``q (n,)`` with each revolute value turned by the whole turns that bring it nearest ``ref``'s while inside the
    joint's limits (with ``limit_tol``; a value outside them stays)."""
    two_pi = 2.0 * np.pi
    lo, hi = robot.lower - robot.limit_tol, robot.upper + robot.limit_tol
    k_lo, k_hi = np.ceil((lo - q) / two_pi), np.floor((hi - q) / two_pi)
    k = np.where(k_lo <= k_hi, np.clip(np.round((ref - q) / two_pi), k_lo, k_hi), 0.0)
    return np.where(robot.is_revolute, q + two_pi * k, q)


def _nearest_on_family(robot: Robot, fam: Family, ref: Array, metric: DistanceFunction) -> tuple[Array, float]:
    """Member of ``fam`` nearest ``ref`` by ``metric`` (modulo 2 pi: families are not wound): dense sampling, then a
    golden-section search around each local minimum of the samples (``_NEAREST_MINIMA`` at most, the lowest first),
    the best kept. Every local minimum, not only the lowest sample: the nearest member can lie next to another sample
    of the same distance, e.g. across the seam of a family that turns theta* through a whole circle (both ends are
    the same member)."""
    lo, hi = fam.interval
    grid = np.linspace(lo, hi, _FAMILY_SAMPLES)
    members = fam.at(grid)
    d = metric(robot, members, ref, True)
    d = np.where(np.all(np.isfinite(members), axis=-1), d, np.inf)
    left = np.concatenate([[np.inf], d[:-1]])
    right = np.concatenate([d[1:], [np.inf]])
    minima = np.nonzero(np.isfinite(d) & (d <= left) & (d <= right))[0]
    minima = minima[np.argsort(d[minima], kind="stable")][:_NEAREST_MINIMA]
    i0 = int(np.argmin(d))
    best, bd = members[i0], float(d[i0])

    def dist(t: float) -> float:
        return float(metric(robot, fam.at(t), ref, True))

    g = (np.sqrt(5.0) - 1.0) / 2.0
    for i in minima.tolist():
        a, b = grid[max(i - 1, 0)], grid[min(i + 1, grid.size - 1)]
        c, e = b - g * (b - a), a + g * (b - a)
        fc, fe = dist(c), dist(e)
        for _ in range(_GOLDEN_ITERS):
            if fc <= fe:
                b, e, fe = e, c, fc
                c = b - g * (b - a)
                fc = dist(c)
            else:
                a, c, fc = c, e, fe
                e = a + g * (b - a)
                fe = dist(e)
        t, dt = (c, fc) if fc <= fe else (e, fe)
        if dt < bd:
            best, bd = fam.at(t), dt
    return np.asarray(best, dtype=np.float64), bd


def thetas_inside(lo: Any, hi: Any, periodic: bool, theta: Array) -> Array:
    """theta* values ``theta`` of families with intervals ``[lo, hi]`` (broadcast against ``theta``) as their members
    are taken: a revolute joint's angle by whole turns onto the interval, then clipped to it (a value within
    ``_FAMILY_EDGE_TOL`` of the interval outside it is its end); SweepikError for a value outside."""
    tol = _FAMILY_EDGE_TOL * np.maximum(hi - lo, 1.0)
    th = theta
    if periodic:  # an angle by whole turns onto the interval (a joint's range can pass +-pi)
        th = lo - tol + np.mod(th - (lo - tol), 2.0 * np.pi)
    if np.any(~np.isfinite(th)) or np.any(th < lo - tol) or np.any(th > hi + tol):
        raise SweepikError(
            f"theta* = {th.tolist()} is outside the family's interval [{np.min(lo):.12g}, {np.max(hi):.12g}]"
        )
    return np.asarray(np.clip(th, lo, hi))


@dataclass(frozen=True, eq=False)
class Family:
    """A continuum of solutions (self-motion): every theta* in ``interval`` gives a solution.

    Attributes:
        free_joint: index of the joint that parametrises the family (theta* of the reduction).
        interval: ``(lo, hi)`` in that joint's unit (radians or length unit), inside the joint limits
            when the solve applied limits.
        held: for an arm solved with locked joints, how members of the smaller arm the reduction solves map
            back to full length (``free_joint`` is then an index of the full arm).
    """

    free_joint: int
    interval: tuple[float, float]
    reduction: Reduction = field(repr=False)
    chain_pose: Array = field(repr=False)
    branch: int = 0
    held: HeldJoints | None = field(default=None, repr=False)
    #: ``members(reduction, chain_pose, branch, theta (K,), lo, hi) -> (K, n)``: the members, each certified by FK
    #: (the engine's ``families.certified_members``, given by whoever builds the family: results need no engine).
    members: MemberFunction = field(kw_only=True, repr=False)

    def at(self, theta: ArrayLike) -> Array:
        """Member configuration(s) ``(n,)`` (or ``(..., n)``) at theta* value(s) inside ``interval`` (a revolute
        joint's angle modulo 2 pi: a configuration's own value of the joint will do, wherever its range puts it).
        Each is a solution of the pose: at an isolated theta* where the reduction's closed form breaks down (the
        C-Arm's wrist crossing joint 2's axis), the member ~1e-9 of the interval away is given, the solution there
        being its limit."""
        th = np.asarray(theta, dtype=np.float64)
        flat = self.theta_inside(th.reshape(-1))
        red = self.reduction
        q = red.robot.wrap(self.members(red, self.chain_pose, self.branch, flat, *self.interval))
        if self.held is not None:
            q = self.held.expand(q)
        return q.reshape(*th.shape, -1)

    def theta_inside(self, theta: ArrayLike) -> Array:
        """The theta* values inside ``interval`` at which :meth:`at` takes its members for ``theta``
        (:func:`thetas_inside`); SweepikError for a value outside."""
        lo, hi = self.interval
        return thetas_inside(np.float64(lo), np.float64(hi), self.reduction.periodic, np.asarray(theta, np.float64))

    def sample(self, count: int = 50) -> Array:
        """``(count, n)`` member configurations evenly spaced over the interval (``count`` an integer >= 1)."""
        k = check_int(count, "count", 1, MAX_FAMILY_SAMPLES)
        return self.at(np.linspace(self.interval[0], self.interval[1], k))


def _read_only(a: NDArray[np.intp]) -> NDArray[np.intp]:
    a.flags.writeable = False
    return a


#: ``own_rows(k)`` for the usual counts: one shared read-only array each.
_OWN_ROWS = tuple(_read_only(np.arange(k, dtype=np.intp)) for k in range(65))


def own_rows(k: int) -> NDArray[np.intp]:
    """``winding_of`` of ``k`` rows without windings, ``arange(k)``: read-only, one shared array for each ``k`` up to
    64 (a new ``np.arange`` each took ~0.2-0.4 us of a single closed-form solve's ~11)."""
    return _OWN_ROWS[k] if k < len(_OWN_ROWS) else _read_only(np.arange(k, dtype=np.intp))


@dataclass(frozen=True, eq=False)
class Solutions:
    """Every IK solution of one pose.

    Attributes:
        q: ``(k, n)`` configurations (radians / length unit), revolute values wrapped into their limits.
        error: ``(k,)`` the paper's error J (eq. 6) in the robot's length unit.
        error_geodesic: ``(k,)`` position error + weight x rotation angle (length unit).
        within_limits: ``(k,)`` bool; all True when solved with ``limits=True``.
        multiplicity: ``(k,)`` int, the order of each solution as a root of the sweep's residual: 1 for a
            regular solution, 2 where two solutions merge (the arm is singular there), 3 or more on
            intersections of singular sets. A solution of multiplicity m is pinned down by the pose only to
            about (rounding / c)^(1/m) along theta*: ~1e-8 of the range for m = 2, ~1e-5 for m = 3.
        families: self-motion continua (empty for almost every pose).
        reason: why there is no solution, when ``q`` and ``families`` are empty; else ``None``.
        pose: the target ``(4, 4)``.
        winding_of: ``(k,)`` int, for each row the row of the solution it is a 2 pi winding of (``solve(...,
            windings=True)`` adds a row for every other value of the revolute joints, modulo 2 pi, inside their
            limits); a row's own index when it is not a winding. The windings come after every base row. Without
            windings it is read-only, shared with other results of as many rows.
        wound: the windings were listed; distances (``nearest``) then compare revolute values as they are, not
            modulo 2 pi, so that the winding nearest a reference is chosen.
    """

    q: Array
    error: Array
    error_geodesic: Array
    within_limits: NDArray[np.bool_]
    multiplicity: NDArray[np.intp]
    families: tuple[Family, ...]
    reason: str | None
    pose: Array
    robot: Robot = field(repr=False)
    winding_of: NDArray[np.intp] = field(default=cast("NDArray[np.intp]", None), repr=False)  # (None: own rows)
    wound: bool = field(default=False, repr=False)

    def __post_init__(self) -> None:
        if self.winding_of is None:
            object.__setattr__(self, "winding_of", own_rows(self.q.shape[0]))

    @classmethod
    def settled(
        cls,
        q: Array,
        error: Array,
        error_geodesic: Array,
        within_limits: NDArray[np.bool_],
        multiplicity: NDArray[np.intp],
        reason: str | None,
        pose: Array,
        robot: Robot,
    ) -> Solutions:
        """The isolated solutions of one pose, without families or windings: the same object as the constructor's,
        built in a fifth of its time (a single closed-form solve's; a frozen dataclass sets each field through
        ``object.__setattr__``), ``winding_of`` shared (``own_rows``)."""
        self = object.__new__(cls)
        self.__dict__.update(
            q=q,
            error=error,
            error_geodesic=error_geodesic,
            within_limits=within_limits,
            multiplicity=multiplicity,
            families=(),
            reason=reason,
            pose=pose,
            robot=robot,
            winding_of=own_rows(q.shape[0]),
            wound=False,
        )
        return self

    def __len__(self) -> int:
        return int(self.q.shape[0])

    def __iter__(self) -> Iterator[Array]:
        return iter(self.q)

    def __getitem__(self, i: int) -> Array:
        return self.q[i]

    def __bool__(self) -> bool:
        return len(self) > 0 or bool(self.families)

    def distances(self, q_ref: ArrayLike, metric: str = "weighted") -> Array:
        """``(k,)`` distance of each solution to ``q_ref (n,)`` by ``metric``: ``"weighted"``
        (:func:`weighted_joint_distance`, the Euclidean norm) or ``"linf"`` (:func:`linf_joint_distance`, the
        largest joint move); angles modulo 2 pi in radians, prismatic joints in units of 100 mm per radian."""
        fn = joint_metric(metric)
        return fn(self.robot, self.q, self._reference(q_ref), not self.wound)

    def _reference(self, q_ref: ArrayLike) -> Array:
        ref = check_configuration(q_ref, self.robot.n_joints, "q_ref")
        if ref.ndim != 1:
            raise ShapeError(f"q_ref must have shape ({self.robot.n_joints},), got {ref.shape}")
        return ref

    def nearest(self, q_ref: ArrayLike, metric: str = "weighted", tol: float | None = None) -> Array | None:
        """The solution ``(n,)`` closest to ``q_ref`` by ``metric`` (see :meth:`distances`; ``follow_path`` uses
        the same), or None when no solution lies within ``tol`` of it (any distance when ``tol`` is None) or there
        is no solution. Family members count: the nearest member is searched along each family.

        >>> import numpy as np
        >>> from sweepik import load_robot, solve
        >>> arm = load_robot("ur5")
        >>> q = np.array([0.1, -1.2, 1.3, -0.4, 1.1, 0.3])
        >>> sols = solve(arm, arm.fk(q))
        >>> bool(np.allclose(sols.nearest(q + 0.01, metric="linf", tol=0.05), q))
        True
        >>> sols.nearest(q + 1.0, metric="linf", tol=0.05) is None
        True
        """
        fn = joint_metric(metric)
        limit = check_tolerance(tol)
        ref = self._reference(q_ref)
        best: Array | None = None
        best_d = np.inf
        if len(self):
            d = fn(self.robot, self.q, ref, not self.wound)
            i = int(np.argmin(d))
            best, best_d = self.q[i], float(d[i])
        for fam in self.families:
            member, dm = _nearest_on_family(self.robot, fam, ref, fn)
            if self.wound:  # (the rows are compared as they are: the member's winding nearest the reference too)
                member = _nearest_winding(self.robot, member, ref)
                dm = float(fn(self.robot, member[None], ref, False)[0])
            if dm < best_d:
                best, best_d = member, dm
        if best is None or (limit is not None and best_d > limit):
            return None
        return best.copy()

    def filter(self, keep: Callable[[Array], object]) -> Solutions:
        """The solutions for which ``keep(q)`` is true (``q (n,)``, e.g. a collision check), as a new
        :class:`Solutions` (rows in the same order; families kept as they are: ``keep`` sees isolated solutions
        only, sample a family with :meth:`Family.sample` to check its members). When every solution is dropped,
        ``reason`` says so."""
        if not callable(keep):
            raise UnknownOptionError(f"filter takes a function q -> bool, got {short_repr(keep)}")
        mask = np.array([bool(keep(q.copy())) for q in self.q], dtype=bool).reshape(len(self))
        if len(self) and not np.any(mask) and not self.families:
            return self.kept(mask, reason=f"filtered out: the filter rejected all {len(self)} solution(s)")
        return self.kept(mask)

    def kept(self, rows: NDArray[np.bool_] | NDArray[np.intp], **changes: object) -> Solutions:
        """A new :class:`Solutions` of the rows ``rows`` (a bool mask, or row indices: repeats allowed), each
        column taken alike; ``winding_of`` renumbered (a row whose base is not kept becomes its own base);
        ``changes``: other fields to replace (as ``dataclasses.replace``)."""
        index = np.nonzero(rows)[0] if np.asarray(rows).dtype == np.bool_ else np.asarray(rows, dtype=np.intp)
        fields: dict[str, Any] = {
            "q": self.q[index],
            "error": self.error[index],
            "error_geodesic": self.error_geodesic[index],
            "within_limits": self.within_limits[index],
            "multiplicity": self.multiplicity[index],
            "winding_of": _renumbered(self.winding_of, index),
        }
        return dataclasses.replace(self, **cast(dict[str, Any], {**fields, **changes}))

    def __repr__(self) -> str:
        parts = [f"{len(self)} solution(s)"]
        if self.families:
            parts.append(f"{len(self.families)} self-motion famil{'y' if len(self.families) == 1 else 'ies'}")
        if len(self) and np.any(self.multiplicity > 1):
            parts.append(f"{int(np.sum(self.multiplicity > 1))} multiple root(s)")
        if len(self) and not np.all(self.within_limits):
            parts.append(f"{int(np.sum(~self.within_limits))} outside the limits")
        if len(self) and np.any(self.winding_of != np.arange(len(self))):
            parts.append(f"{int(np.sum(self.winding_of != np.arange(len(self))))} winding(s)")
        head = f"Solutions({self.robot.name}: {', '.join(parts)}"
        if not self:
            return f"{head}; {self.reason})"
        if not len(self):
            return head + ")"
        worst = float(np.max(self.error))
        rows = np.array2string(self.q, precision=4, suppress_small=True, max_line_width=120, threshold=60)
        return f"{head}, J <= {worst:.1e} {self.robot.length_unit})\n{rows}"


def _renumbered(winding_of: NDArray[np.intp], index: NDArray[np.intp]) -> NDArray[np.intp]:
    """``winding_of`` of the rows ``index`` (in that order): each row's base as a new row number (its first place
    in ``index``), or the row itself when its base is not among them."""
    first = np.full(winding_of.shape[0], -1, dtype=np.intp)
    first[index[::-1]] = np.arange(index.size - 1, -1, -1)  # (the earliest place of each old row wins)
    base = first[winding_of[index]]
    return np.where(base >= 0, base, np.arange(index.size)).astype(np.intp)


UNREACHABLE = "unreachable: no configuration of the arm reaches this pose"


def no_solution_reason(n_reachable: int) -> str:
    """Why a pose has no solution (nor family), given how many solutions it has before the joint limits."""
    if n_reachable > 0:
        return f"out of joint limits: {n_reachable} solution(s) reach the pose but violate the limits"
    return UNREACHABLE


@dataclass(frozen=True, eq=False)
class Block:
    """The solutions of a chunk of ``n`` poses, rows sorted by pose: pose ``i`` owns rows
    ``bounds[i]:bounds[i + 1]``. ``families`` maps a pose to its self-motion families (most poses have none);
    ``n_reachable[i]`` counts its solutions before the joint limits were applied (for the no-solution reason);
    ``empty_reason``, if set, is the reason given to every pose without solutions (the paper's strategy)."""

    robot: Robot
    poses: Array
    bounds: NDArray[np.intp]
    q: Array
    error: Array
    error_geodesic: Array
    within_limits: NDArray[np.bool_]
    multiplicity: NDArray[np.intp]
    families: dict[int, tuple[Family, ...]]
    n_reachable: NDArray[np.intp]
    empty_reason: str | None = None
    #: per row, the row (within its pose's rows) of the solution it is a 2 pi winding of; None: no windings
    winding_of: NDArray[np.intp] | None = None

    @property
    def n(self) -> int:
        return int(self.poses.shape[0])

    @property
    def row_in_pose(self) -> NDArray[np.intp]:
        """``(K,)`` each row's index among its pose's rows (what ``winding_of`` is without windings)."""
        counts = np.diff(self.bounds)
        return (np.arange(self.q.shape[0]) - np.repeat(self.bounds[:-1], counts)).astype(np.intp)

    def reason(self, i: int) -> str | None:
        """Why pose ``i`` has no solution (None when it has some, or a family)."""
        if self.bounds[i + 1] > self.bounds[i] or self.families.get(i):
            return None
        if self.empty_reason is not None:
            return self.empty_reason
        return no_solution_reason(int(self.n_reachable[i]))

    def expanded(self, held: HeldJoints | None) -> Block:
        """This block of the held arm as a block of the full arm (``held``: how it was held; None: itself):
        configurations full length, families too."""
        if held is None:
            return self
        families = {
            i: tuple(dataclasses.replace(f, free_joint=held.free[f.free_joint], held=held) for f in fams)
            for i, fams in self.families.items()
        }
        return dataclasses.replace(self, robot=held.robot, q=held.expand(self.q), families=families)

    def solutions(self, i: int, copy: bool = True) -> Solutions:
        """The :class:`Solutions` of pose ``i``: arrays copied (the block stays as it is), or views of the block's
        (``copy=False``, for a block made for this one result)."""
        s, e = int(self.bounds[i]), int(self.bounds[i + 1])
        take = np.copy if copy else np.asarray
        return Solutions(
            q=take(self.q[s:e]),
            error=take(self.error[s:e]),
            error_geodesic=take(self.error_geodesic[s:e]),
            within_limits=take(self.within_limits[s:e]),
            multiplicity=take(self.multiplicity[s:e]),
            families=self.families.get(i, ()),
            reason=self.reason(i),
            pose=take(self.poses[i]),
            robot=self.robot,
            winding_of=cast("NDArray[np.intp]", None if self.winding_of is None else take(self.winding_of[s:e])),
            wound=self.winding_of is not None,
        )

    def __iter__(self) -> Iterator[Solutions]:
        return (self.solutions(i) for i in range(self.n))


class SolutionBatch(Sequence[Solutions]):
    """The solutions of a batch of ``N`` poses (what ``solve_many`` returns).

    A sequence of :class:`Solutions` (``len``, indexing, slicing, iteration; each built when asked for), and
    the same data in columns, every pose's solutions stacked (``K`` rows in all):

    * ``offsets (N + 1,)``: pose ``i``'s solutions are rows ``offsets[i]:offsets[i + 1]``; ``counts (N,)``;
    * ``pose_index (K,)``: the pose of each row;
    * ``q (K, n)``, ``error (K,)``, ``error_geodesic (K,)``, ``within_limits (K,)``, ``multiplicity (K,)``,
      ``winding_of (K,)``: as in :class:`Solutions`;
    * ``n_reachable (N,)``: each pose's solutions before the joint limits were applied;
    * ``families``: ``{pose index: families}`` for the few poses that have self-motion families;
    * ``reason(i)``: why pose ``i`` has no solution (None if it has some).
    """

    def __init__(self, robot: Robot, blocks: Sequence[Block]) -> None:
        self.robot = robot
        self._blocks = list(blocks)
        self._starts = np.concatenate([[0], np.cumsum([b.n for b in self._blocks])]).astype(np.intp)

    def __len__(self) -> int:
        return int(self._starts[-1])

    @property
    def blocks(self) -> list[Block]:
        """The solver's chunks, in order (each a :class:`Block` of consecutive poses)."""
        return list(self._blocks)

    def _locate(self, i: int) -> tuple[Block, int]:
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"pose index {i} out of range for a batch of {n} poses")
        i %= n
        k = bisect.bisect_right(self._starts, i) - 1
        return self._blocks[k], i - int(self._starts[k])

    @overload
    def __getitem__(self, i: int) -> Solutions: ...

    @overload
    def __getitem__(self, i: slice) -> list[Solutions]: ...

    def __getitem__(self, i: int | slice) -> Solutions | list[Solutions]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        block, j = self._locate(operator.index(i))
        return block.solutions(j)

    def __iter__(self) -> Iterator[Solutions]:
        for block in self._blocks:
            yield from block

    def __repr__(self) -> str:
        return f"SolutionBatch({len(self)} poses, {int(self.offsets[-1])} solutions)"

    def __eq__(self, other: object) -> bool:
        """Element by element with a list or tuple (an empty batch equals ``[]``). :class:`Solutions` compare by
        identity and a batch builds them anew on each access, so a non-empty batch equals no list, and two batches
        are equal only if they are the same object."""
        if isinstance(other, SolutionBatch):
            return other is self
        if isinstance(other, list | tuple):
            return len(other) == len(self) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # mutable-sequence semantics, as a list

    def reason(self, i: int) -> str | None:
        """Why pose ``i`` has no solution (None when it has some, or a family)."""
        block, j = self._locate(operator.index(i))
        return block.reason(j)

    def _stack(self, name: str, shape: tuple[int, ...], dtype: type) -> NDArray:
        parts = [getattr(b, name) for b in self._blocks]
        return np.concatenate(parts) if parts else np.zeros(shape, dtype=dtype)

    @cached_property
    def offsets(self) -> NDArray[np.intp]:
        counts = self.counts
        return np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)

    @cached_property
    def counts(self) -> NDArray[np.intp]:
        if not self._blocks:
            return np.zeros(0, dtype=np.intp)
        return np.concatenate([np.diff(b.bounds) for b in self._blocks]).astype(np.intp)

    @cached_property
    def pose_index(self) -> NDArray[np.intp]:
        return np.repeat(np.arange(len(self)), self.counts).astype(np.intp)

    @cached_property
    def q(self) -> Array:
        return self._stack("q", (0, self.robot.n_joints), np.float64)

    @cached_property
    def error(self) -> Array:
        return self._stack("error", (0,), np.float64)

    @cached_property
    def error_geodesic(self) -> Array:
        return self._stack("error_geodesic", (0,), np.float64)

    @cached_property
    def within_limits(self) -> NDArray[np.bool_]:
        return self._stack("within_limits", (0,), np.bool_)

    @cached_property
    def multiplicity(self) -> NDArray[np.intp]:
        return self._stack("multiplicity", (0,), np.intp)

    @cached_property
    def winding_of(self) -> NDArray[np.intp]:
        """``(K,)`` as :attr:`Solutions.winding_of`: the row, among its pose's rows, that each row winds."""
        parts = [b.row_in_pose if b.winding_of is None else b.winding_of for b in self._blocks]
        return np.concatenate(parts).astype(np.intp) if parts else np.zeros(0, dtype=np.intp)

    @cached_property
    def n_reachable(self) -> NDArray[np.intp]:
        """``(N,)`` each pose's solutions before the joint limits were applied (``counts`` is after)."""
        return self._stack("n_reachable", (0,), np.intp).astype(np.intp)

    @cached_property
    def families(self) -> dict[int, tuple[Family, ...]]:
        out: dict[int, tuple[Family, ...]] = {}
        for start, block in zip(self._starts, self._blocks, strict=False):
            out.update({int(start) + i: f for i, f in block.families.items() if f})
        return out
