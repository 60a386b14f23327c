"""The paper's verification (section 6) as plain functions returning JSON-able dicts.

* Table 2 / Table 3: the grid of 3 x 11 x 5 x 4 x 5 x 5 = 16,500 joint configurations, converted to poses by
  forward kinematics and solved; the paper's 15,900 "nonsingular" points leave out the 600 with
  theta2 = +-90 deg and theta3 = 0 (:func:`singular_mask`, docs/verification.md explains why).
* Figure 4: theta2 of every solution for the 11 poses d1 = 500 mm, theta3 = 60, theta4 = -60, theta5 = 60,
  theta6 = 0 deg, theta2 over its Table-2 values.
* Off-grid: seeded random in-limit configurations with continuous d1 (the honest test: the Table-2 d1
  values lie on the paper strategy's 10 mm sweep grid).
* Table 4 / Figure 5: a rectangle in the workspace at the zero-pose orientation, followed with
  :func:`sweepik.trajectory.follow_path`.

Units: d1 in mm, angles in radians in every array; the dicts state degrees where they use them
(``*_deg`` keys). J is the paper's error (eq. 6) in mm. All dict values are plain Python numbers, strings,
lists and dicts (NaN/inf become ``None``), so ``json.dumps`` works on every result.

Progress callbacks have the signature ``progress(stage: str, done: int, total: int) -> None``.
"""

from __future__ import annotations

import itertools
import math
import time
from collections import Counter
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import RobotDefinitionError, UnknownOptionError
from sweepik.model.pose import pose_error_paper
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.model.validate import check_configuration
from sweepik.reductions import Reduction
from sweepik.results import Solutions, joint_distance
from sweepik.solving import STRATEGIES, Progress, iter_solve, solve_many
from sweepik.trajectory import branch_switch_thresholds, follow_path, weighted_joint_distance

__all__ = [
    "TABLE2",
    "PAPER_TABLES",
    "RECALL_TOL",
    "RECALL_TOL_LOOSE",
    "TRAJECTORY_START",
    "TRAJECTORY_CORNERS",
    "TRAJECTORY_Q_REF",
    "POINTS_PER_EDGE",
    "FIGURE4_FIXED",
    "Progress",
    "grid_configurations",
    "singular_mask",
    "CONFIG_CLASSES",
    "configuration_classes",
    "random_configurations",
    "run_grid",
    "figure4_data",
    "trajectory_poses",
    "run_trajectory",
    "run_verify",
]

Array = NDArray[np.float64]
StrategyChoice = Literal["precise", "paper", "both"]

#: Table 2 of the paper: the values of each joint in the verification grid (d1 in mm, angles in degrees).
TABLE2: dict[str, tuple[float, ...]] = {
    "d1_mm": (500.0, 1000.0, 1500.0),
    "theta2_deg": tuple(float(v) for v in range(-150, 151, 30)),
    "theta3_deg": (-60.0, -30.0, 0.0, 30.0, 60.0),
    "theta4_deg": (-60.0, -30.0, 0.0, 30.0),
    "theta5_deg": (-120.0, -60.0, 0.0, 60.0, 120.0),
    "theta6_deg": (-60.0, -30.0, 0.0, 30.0, 60.0),
}

#: The paper's numbers: Table 3 (grid, 15,900 points, Matlab runtime) and Table 4 (trajectory). J in mm.
PAPER_TABLES: dict[str, dict[str, float | int]] = {
    "grid": {"points": 15900, "J_max": 3.49e-6, "J_mean": 9.51e-9, "J_99_6": 3.44e-9, "seconds_per_point": 0.098},
    "trajectory": {"J_max": 1.27e-13, "J_mean": 3.21e-14},
}

#: A generating configuration counts as found when a solution matches every joint within this (d1 in mm,
#: angles in radians modulo 2 pi): far below any physical resolution (the rail's is 0.01 mm), far above the
#: ~1e-12 to which simple roots are refined.
RECALL_TOL = 1e-6
#: Looser match, reported as ``recall_loose``: at a double root the residual grows with the square of the
#: distance, so a root is only determined to about sqrt(machine epsilon) x the arm's length scale
#: (1.5e-8 x 2752 mm = 4e-5 mm on the C-Arm). Found within this but not within RECALL_TOL means "found,
#: located to double-root accuracy only".
RECALL_TOL_LOOSE = 1e-4
#: Solutions whose d1 values differ by less than this (mm) count as one d1 value in ``distinct_d1_histogram``.
D1_DISTINCT_TOL = 1e-6
#: Poses per solve_many call (progress granularity; solve_many chunks memory by itself).
_CHUNK = 500
#: How many missed generating configurations a summary lists.
_MAX_MISSED = 20

#: Figure 4: every joint but theta2 fixed (d1 in mm, angles in degrees).
FIGURE4_FIXED = {"d1_mm": 500.0, "theta3_deg": 60.0, "theta4_deg": -60.0, "theta5_deg": 60.0, "theta6_deg": 0.0}

#: Trajectory (section 6.2): start and end point given by the paper (mm).
TRAJECTORY_START = (350.0, -250.0, 1250.0)
#: The rectangle's corners (mm), in path order, starting at TRAJECTORY_START. The paper does not give them.
#: Chosen once by a programmatic search over rectangles with a corner at the start point (edge directions in
#: 15 deg steps, edges 100-600 mm) at the zero-pose orientation, keeping the ones whose densely sampled path
#: (200 points per edge) has a solution everywhere and stays clear of trouble, then taking a large one with
#: round numbers. At this orientation theta2 = theta5 = 0 and the arm works as a planar two-link arm
#: (theta3, theta4) above the rail, so the xy-projection decides; along this path every point keeps
#: >= 14 deg from the theta3/theta4 limits, >= 20.6 deg from the stretched-elbow singularity theta4 = 0
#: (the start point itself is only 20.6 deg from it), and >= 30 deg from theta3 + theta4 = +-90 deg, where
#: a second solution branch (theta2 = +-theta5) crosses this one. (A rectangle reaching up to z = 1650 mm
#: with y up to +250 mm meets that crossing, and the nearest-solution rule then jumps branches at 10 points
#: per edge.) Each path point has exactly one solution inside the joint limits (4 to 8 without limits).
#: The plane is tilted (z changes along the second edge) so that Figure 5 is three-dimensional.
TRAJECTORY_CORNERS: tuple[tuple[float, float, float], ...] = (
    (350.0, -250.0, 1250.0),
    (350.0, 0.0, 1250.0),
    (250.0, 0.0, 1650.0),
    (250.0, -250.0, 1650.0),
)
#: Points per edge: each corner and 9 evenly spaced points after it (the paper: "ten points were calculated
#: between subsequent corner points"), plus the closing point: 4 x 10 + 1 = 41 points.
POINTS_PER_EDGE = 10
#: Reference configuration for the first trajectory point (d1 mm, angles rad): the zero pose moved along the
#: rail to the start height. The first point takes the solution nearest to it.
TRAJECTORY_Q_REF = (1250.0, 0.0, 0.0, 0.0, 0.0, 0.0)


# ------------------------------------------------------------------------------------------ helpers


def _num(x: float | np.floating[Any] | None) -> float | None:
    """A plain float, or None for NaN/inf/None (JSON has no NaN)."""
    if x is None:
        return None
    v = float(x)
    return v if math.isfinite(v) else None


def _check_carm_like(robot: Robot) -> None:
    if robot.n_joints != 6 or bool(robot.is_revolute[0]) or not bool(np.all(robot.is_revolute[1:])):
        raise RobotDefinitionError(
            f"the paper's verification is defined for the C-Arm (a prismatic joint then five revolute ones); "
            f"robot {robot.name!r} has joints {robot.joint_names} of types "
            f"{['revolute' if r else 'prismatic' for r in robot.is_revolute]}"
        )


def _check_strategy(strategy: str, allowed: Sequence[str]) -> None:
    if strategy not in allowed:
        raise UnknownOptionError(f"unknown strategy {strategy!r}; choose one of {', '.join(allowed)}")


def _config_deg(q: Array) -> list[float]:
    """A C-Arm configuration for display: d1 in mm, angles in degrees, rounded to 1e-9."""
    return [round(float(q[0]), 9)] + [round(float(v), 9) for v in np.degrees(q[1:])]


def _solve_chunked(
    robot: Robot,
    poses: Array,
    strategy: str,
    reduction: str | Reduction | None,
    progress: Progress | None,
    stage: str,
) -> tuple[list[Solutions], float]:
    """All solutions of ``poses`` (progress after each chunk) and the wall time of the solves (s)."""

    def report(_: str, done: int, total: int) -> None:
        if progress is not None:
            progress(stage, done, total)

    _warm_up(robot, poses, strategy, reduction)
    t0 = time.perf_counter()
    out = list(iter_solve(robot, poses, reduction=reduction, strategy=strategy, chunk_size=_CHUNK, progress=report))  # type: ignore[arg-type]
    return out, time.perf_counter() - t0


def _warm_up(robot: Robot, poses: Array, strategy: str, reduction: str | Reduction | None) -> None:
    """Solve the first pose once, untimed: the kernels are compiled (first run) or loaded from Numba's cache before
    the clock starts, so that the time per point is the solver's, not the compiler's."""
    if len(poses):
        list(iter_solve(robot, poses[:1], reduction=reduction, strategy=strategy))  # type: ignore[arg-type]


def _count_distinct(values: Array, tol: float) -> int:
    if values.size == 0:
        return 0
    v = np.sort(values)
    return 1 + int(np.count_nonzero(np.diff(v) > tol))


def _evaluate(robot: Robot, configs: Array, sols: Sequence[Solutions]) -> dict[str, NDArray[Any]]:
    """Per-pose arrays: generating configuration found (strict / loose), J of the solution closest to it,
    distance (max per joint) of the closest match, solution counts, distinct d1 values, families."""
    N = configs.shape[0]
    weight = orientation_weight(robot.length_unit)
    found = np.zeros(N, dtype=bool)
    found_loose = np.zeros(N, dtype=bool)
    J = np.full(N, np.nan)
    match = np.full(N, np.inf)  # smallest max-per-joint difference to the generating configuration
    n_sol = np.zeros(N, dtype=np.intp)
    n_d1 = np.zeros(N, dtype=np.intp)
    n_fam = np.zeros(N, dtype=np.intp)
    gen = robot.wrap(configs)
    for i, s in enumerate(sols):
        qg = gen[i]
        best_w = math.inf
        n_sol[i] = len(s)
        n_fam[i] = len(s.families)
        if len(s):
            per_joint = joint_distance(robot, s.q, qg).max(axis=-1)
            match[i] = float(per_joint.min())
            w = weighted_joint_distance(robot, s.q, qg)
            k = int(np.argmin(w))
            best_w, J[i] = float(w[k]), float(s.error[k])
            n_d1[i] = _count_distinct(s.q[:, 0], D1_DISTINCT_TOL)
        for fam in s.families:
            th = float(qg[fam.free_joint])
            lo, hi = fam.interval
            slack = 1e-9 * max(hi - lo, 1.0)
            if not lo - slack <= th <= hi + slack:
                continue
            member = fam.at(min(max(th, lo), hi))
            match[i] = min(match[i], float(joint_distance(robot, member, qg).max()))
            w_m = float(weighted_joint_distance(robot, member, qg))
            if w_m < best_w:
                best_w = w_m
                J[i] = float(pose_error_paper(robot.fk(member), s.pose, weight))
        found[i] = match[i] <= RECALL_TOL
        found_loose[i] = match[i] <= RECALL_TOL_LOOSE
        if not (len(s) or s.families):
            J[i] = np.nan
    return {
        "found": found,
        "found_loose": found_loose,
        "J": J,
        "match": match,
        "n_sol": n_sol,
        "n_d1": n_d1,
        "n_fam": n_fam,
    }


def _error_stats(J: Array) -> dict[str, float | None]:
    ok = J[np.isfinite(J)]
    if ok.size == 0:
        return {"J_max": None, "J_mean": None, "J_99_6": None}
    return {
        "J_max": _num(ok.max()),
        "J_mean": _num(ok.mean()),
        "J_99_6": _num(np.percentile(ok, 99.6)),
    }


def _histogram(values: Array) -> dict[str, int]:
    return {str(k): int(v) for k, v in sorted(Counter(int(x) for x in values).items())}


def _histogram_str(values: NDArray[np.str_]) -> dict[str, int]:
    return {str(k): int(v) for k, v in sorted(Counter(values.tolist()).items())}


def _summary(
    ev: dict[str, NDArray[Any]], configs: Array, sel: NDArray[np.bool_], seconds_per_point: float | None
) -> dict[str, Any]:
    found, loose, J = ev["found"][sel], ev["found_loose"][sel], ev["J"][sel]
    n = int(found.size)
    missed_idx = np.nonzero(np.logical_not(found))[0]
    cfg = configs[sel]
    match = ev["match"][sel]
    no_solution = (ev["n_sol"][sel] == 0) & (ev["n_fam"][sel] == 0)
    out: dict[str, Any] = {
        "points": n,
        "recall": _num(found.mean()) if n else None,
        "recall_loose": _num(loose.mean()) if n else None,
        **_error_stats(J),
        "seconds_per_point": _num(seconds_per_point),
        "no_solution": int(no_solution.sum()),
        "solutions_histogram": _histogram(ev["n_sol"][sel]),
        "distinct_d1_histogram": _histogram(ev["n_d1"][sel]),
        "family_poses": int(np.count_nonzero(ev["n_fam"][sel])),
        "missed_total": int(missed_idx.size),
        "missed": [cfg[i].tolist() for i in missed_idx[:_MAX_MISSED]],
        "missed_match": [_num(match[i]) for i in missed_idx[:_MAX_MISSED]],
        "missed_by_class": _histogram_str(configuration_classes(cfg[missed_idx])) if cfg.shape[1] == 6 else {},
    }
    return out


# ----------------------------------------------------------------------------------------------- grid


def grid_configurations(include_singular: bool = False) -> Array:
    """Table 2's grid as configurations ``(N, 6)`` (d1 in mm, angles in radians), d1 varying slowest.

    ``include_singular=True``: all 3 x 11 x 5 x 4 x 5 x 5 = 16,500 combinations; False: the paper's 15,900
    "nonsingular" ones, without the 600 of :func:`singular_mask` (theta2 = +-90 deg and theta3 = 0).
    """
    cols = [np.array(TABLE2["d1_mm"])] + [np.radians(TABLE2[k]) for k in list(TABLE2)[1:]]
    grid = np.array(list(itertools.product(*cols)), dtype=np.float64)
    if include_singular:
        return grid
    return grid[~singular_mask(grid)]


def singular_mask(configs: ArrayLike) -> NDArray[np.bool_]:
    """``(N,)`` True for configurations ``(N, 6)`` the paper leaves out: theta2 = +-90 deg and theta3 = 0.

    There link 1 is perpendicular to the rail while joints 3 and 4 turn in a plane that contains the rail;
    the residual along d1 touches zero without crossing (a double root), and with theta5 = 0 as well the
    rail and joints 3, 4 and 6 act in one plane, giving a self-motion family (docs/verification.md).
    """
    q = np.asarray(configs, dtype=np.float64)
    tol = 1e-9
    t2 = np.abs(np.abs(q[..., 1]) - np.pi / 2) <= tol
    t3 = np.abs(q[..., 2]) <= tol
    return np.asarray(t2 & t3)


#: Names of :func:`configuration_classes`, in the order they are tested.
CONFIG_CLASSES = ("self-motion", "excluded-singular", "branch-crossing", "regular")


def configuration_classes(configs: ArrayLike) -> NDArray[np.str_]:
    """``(N,)`` the C-Arm's special configuration sets a configuration ``(N, 6)`` belongs to (first match):

    * ``"self-motion"``: theta2 = +-90 deg and theta5 = 0 (rail and joints 3, 4, 6 act in one plane);
    * ``"excluded-singular"``: the rest of :func:`singular_mask` (theta2 = +-90 deg, theta3 = 0);
    * ``"branch-crossing"``: theta3 + theta4 = +-90 deg with theta2 = 0 or theta5 = 0, where the branch
      through the configuration meets a second one: a double root along d1;
    * ``"regular"``: everything else (all random configurations, with probability 1).
    """
    q = np.asarray(configs, dtype=np.float64).reshape(-1, 6)
    tol = 1e-9

    def zero(a: Array) -> NDArray[np.bool_]:
        return np.asarray(np.abs(np.pi - np.mod(np.pi - a, 2 * np.pi)) <= tol)

    t2_90 = zero(np.abs(q[:, 1]) - np.pi / 2)
    self_motion = t2_90 & zero(q[:, 4])
    crossing = zero(np.abs(q[:, 2] + q[:, 3]) - np.pi / 2) & (zero(q[:, 1]) | zero(q[:, 4]))
    out = np.full(q.shape[0], "regular", dtype="<U17")
    out[crossing] = "branch-crossing"
    out[singular_mask(q) & ~self_motion] = "excluded-singular"
    out[self_motion] = "self-motion"
    return out


def random_configurations(robot: Robot, n: int, rng: np.random.Generator | None = None) -> Array:
    """``(n, n_joints)`` configurations uniformly inside the joint limits (continuous d1: off the grid).

    ``rng``: a seeded generator for reproducible sets (a fresh unseeded one when None).
    """
    if n < 0:
        raise UnknownOptionError(f"the number of random configurations must be >= 0, got {n}")
    g = np.random.default_rng() if rng is None else rng
    lo, hi = robot.lower, robot.upper
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise RobotDefinitionError(f"robot {robot.name!r} needs finite joint limits to sample configurations")
    return g.uniform(lo, hi, size=(n, robot.n_joints))


def run_grid(
    robot: Robot,
    configs: ArrayLike,
    strategy: Literal["precise", "paper"] = "precise",
    progress: Progress | None = None,
    *,
    reduction: str | Reduction | None = None,
    stage: str = "grid",
) -> dict[str, Any]:
    """Solve the poses of ``configs (N, 6)`` (d1 mm, angles rad) and compare with the configurations.

    Returns a dict:

    * ``points``; ``recall``: share of poses whose generating configuration is among the solutions within
      ``RECALL_TOL`` (every joint; d1 mm, angles rad modulo 2 pi) or on a reported self-motion family;
      ``recall_loose``: the same within ``RECALL_TOL_LOOSE``;
    * ``J_max``, ``J_mean``, ``J_99_6`` (99.6th percentile): the paper's J (mm) of the solution closest to
      the generating configuration, over poses with at least one solution; ``no_solution``: poses without;
    * ``seconds_per_point``: wall time of the solves per pose;
    * ``solutions_histogram`` (isolated solutions per pose -> poses), ``distinct_d1_histogram`` (distinct d1
      values per pose -> poses), ``family_poses`` (poses with a self-motion family);
    * ``missed_total``, ``missed`` (up to 20 generating configurations not found, d1 mm and angles rad) and
      ``missed_match`` (for each, the largest joint difference of the closest solution), ``missed_by_class``
      (misses per :func:`configuration_classes` set).
    """
    _check_strategy(strategy, STRATEGIES)
    q = check_configuration(configs, robot.n_joints, "configs").reshape(-1, robot.n_joints)
    poses = robot.fk(q)
    sols, seconds = _solve_chunked(robot, poses, strategy, reduction, progress, stage)
    ev = _evaluate(robot, q, sols)
    spp = seconds / q.shape[0] if q.shape[0] else None
    return _summary(ev, q, np.ones(q.shape[0], dtype=bool), spp)


def figure4_data(robot: Robot, strategy: Literal["precise", "paper"] = "precise") -> dict[str, Any]:
    """Figure 4: theta2 (degrees) of every solution for the 11 poses of ``FIGURE4_FIXED`` x Table-2 theta2.

    Returns ``{"fixed": FIGURE4_FIXED, "theta2_desired_deg": [11], "theta2_solutions_deg": [11 lists],
    "multiplicity": [11 lists], "desired_found": [11 bools], "n_solutions": [11], "families": [11]}``:
    solutions sharing a theta2 value (within RECALL_TOL rad) are listed once with their multiplicity.
    """
    _check_carm_like(robot)
    _check_strategy(strategy, STRATEGIES)
    f = FIGURE4_FIXED
    th2 = np.radians(TABLE2["theta2_deg"])
    configs = np.zeros((th2.size, 6))
    configs[:, 0] = f["d1_mm"]
    configs[:, 1] = th2
    configs[:, 2:] = np.radians([f["theta3_deg"], f["theta4_deg"], f["theta5_deg"], f["theta6_deg"]])
    sols = solve_many(robot, robot.fk(configs), strategy=strategy)
    ev = _evaluate(robot, configs, sols)
    values: list[list[float]] = []
    mult: list[list[int]] = []
    for s in sols:
        groups: list[list[float]] = []
        for t in np.sort(np.pi - np.mod(np.pi - s.q[:, 1], 2 * np.pi)):
            if groups and abs(t - groups[-1][0]) <= RECALL_TOL:
                groups[-1].append(float(t))
            else:
                groups.append([float(t)])
        if len(groups) > 1 and abs(groups[-1][0] - groups[0][0] - 2 * np.pi) <= RECALL_TOL:
            groups[0].extend(groups.pop())  # -pi and pi are one angle
        values.append([round(math.degrees(g[0]), 9) for g in groups])
        mult.append([len(g) for g in groups])
    return {
        "fixed": dict(f),
        "theta2_desired_deg": [float(v) for v in TABLE2["theta2_deg"]],
        "theta2_solutions_deg": values,
        "multiplicity": mult,
        "desired_found": [bool(x) for x in ev["found"]],
        "n_solutions": [int(x) for x in ev["n_sol"]],
        "families": [int(x) for x in ev["n_fam"]],
    }


# ----------------------------------------------------------------------------------------- trajectory


def trajectory_poses(
    robot: Robot,
    corners: Sequence[Sequence[float]] = TRAJECTORY_CORNERS,
    per_edge: int = POINTS_PER_EDGE,
) -> Array:
    """Poses ``(4 * per_edge + 1, 4, 4)`` around the closed polygon ``corners`` (mm), back to the first.

    Orientation: the robot's zero-pose orientation (``robot.fk(zeros)``), as in the paper.
    """
    C = np.asarray(corners, dtype=np.float64)
    if C.ndim != 2 or C.shape[1] != 3 or C.shape[0] < 2 or per_edge < 1:
        raise UnknownOptionError(f"corners must be (K >= 2, 3) and per_edge >= 1, got {C.shape} and {per_edge}")
    t = np.arange(per_edge)[:, None] / per_edge
    pts = [a + (b - a) * t for a, b in zip(C, np.roll(C, -1, axis=0), strict=True)]
    xyz = np.concatenate([*pts, C[:1]])
    T = np.tile(robot.fk(np.zeros(robot.n_joints)), (xyz.shape[0], 1, 1))
    T[:, :3, 3] = xyz
    return T


def run_trajectory(
    robot: Robot,
    strategy: Literal["precise", "paper"] = "precise",
    *,
    corners: Sequence[Sequence[float]] = TRAJECTORY_CORNERS,
    per_edge: int = POINTS_PER_EDGE,
    q_ref: ArrayLike | None = TRAJECTORY_Q_REF,
    reduction: str | Reduction | None = None,
) -> dict[str, Any]:
    """Table 4 / Figure 5: follow the rectangle, nearest solution at every step (see ``follow_path``).

    Returns ``points``, ``recall`` (share of points with a solution), ``J_max``, ``J_mean``, ``J_99_6`` (mm,
    of the chosen solutions), ``seconds_per_point``, ``max_joint_step`` (the largest change of a revolute
    joint between consecutive points, degrees), ``max_joint_step_detail`` (``{"angle_deg", "length",
    "length_unit", "per_joint"}``: the same per joint, in degrees or the length unit), ``branch_switches``
    (steps over ``branch_switch_thresholds``: 30 deg, or 10 % of a prismatic joint's range),
    ``switch_steps``, ``solutions_per_point`` and, for plotting, ``corners``, ``xyz`` (desired positions),
    ``achieved_xyz`` (FK of the chosen configurations) and ``q`` (d1 mm, angles rad; None where a point has
    no solution).
    """
    _check_strategy(strategy, STRATEGIES)
    poses = trajectory_poses(robot, corners, per_edge)
    _warm_up(robot, poses, strategy, reduction)
    t0 = time.perf_counter()
    res = follow_path(robot, poses, q_ref, reduction=reduction, strategy=strategy)
    seconds = time.perf_counter() - t0
    names = robot.joint_names
    shown = np.where(robot.is_revolute, np.degrees(res.max_joint_step), res.max_joint_step)
    rev = robot.is_revolute
    achieved = np.full((poses.shape[0], 3), np.nan)
    if np.any(res.found):
        achieved[res.found] = robot.fk(res.q[res.found])[:, :3, 3]
    thresholds = branch_switch_thresholds(robot)

    def rows(a: Array) -> list[list[float | None]]:
        return [[_num(v) for v in r] for r in a]

    return {
        "points": int(poses.shape[0]),
        "recall": _num(res.recall),
        **_error_stats(res.error),
        "seconds_per_point": _num(seconds / poses.shape[0]),
        # a number, like the other metrics: the largest change of any revolute joint, in degrees
        "max_joint_step": _num(shown[rev].max()) if np.any(rev) else None,
        "max_joint_step_detail": {
            "angle_deg": _num(shown[rev].max()) if np.any(rev) else None,
            "length": _num(shown[~rev].max()) if np.any(~rev) else None,
            "length_unit": robot.length_unit,
            "per_joint": {nm: _num(v) for nm, v in zip(names, shown, strict=True)},
        },
        "branch_switches": int(res.branch_switches),
        "branch_switch_threshold": {
            nm: _num(math.degrees(t) if r else t) for nm, t, r in zip(names, thresholds, rev, strict=True)
        },
        "switch_steps": list(res.switch_steps),
        "solutions_per_point": [int(k) for k in res.n_solutions],
        "corners": [list(map(float, c)) for c in corners],
        "xyz": rows(poses[:, :3, 3]),
        "achieved_xyz": rows(achieved),
        "q": rows(res.q),
        "joint_names": names,
        "joint_revolute": [bool(r) for r in rev],
    }


# ----------------------------------------------------------------------------------------------- all


def _run_one(
    robot: Robot, strategy: Literal["precise", "paper"], offgrid: int, seed: int, progress: Progress | None
) -> dict[str, Any]:
    configs = grid_configurations(include_singular=True)
    poses = robot.fk(configs)
    sols, seconds = _solve_chunked(robot, poses, strategy, None, progress, f"{strategy}: grid")
    ev = _evaluate(robot, configs, sols)
    spp = seconds / configs.shape[0]
    nonsingular = ~singular_mask(configs)
    out: dict[str, Any] = {
        "strategy": strategy,
        "robot": robot.name,
        "grid": _summary(ev, configs, nonsingular, spp),
        "grid_all": _summary(ev, configs, np.ones(configs.shape[0], dtype=bool), spp),
    }
    rand = random_configurations(robot, offgrid, np.random.default_rng(seed))
    if offgrid:
        out["offgrid"] = run_grid(robot, rand, strategy, progress, stage=f"{strategy}: off-grid")
    else:
        out["offgrid"] = _summary(_evaluate(robot, rand, []), rand, np.zeros(0, dtype=bool), None)
    out["offgrid"]["seed"] = seed
    if progress is not None:
        progress(f"{strategy}: trajectory", 0, 1)
    out["trajectory"] = run_trajectory(robot, strategy)
    out["figure4"] = figure4_data(robot, strategy)
    if progress is not None:
        progress(f"{strategy}: trajectory", 1, 1)
    return out


def run_verify(
    robot: Robot,
    strategy: StrategyChoice = "precise",
    offgrid: int = 2000,
    seed: int = 0,
    progress: Progress | None = None,
) -> dict[str, Any]:
    """The paper's section 6 for one strategy or both; a JSON-able dict.

    One strategy: ``{"strategy", "robot", "grid" (15,900 nonsingular points), "grid_all" (16,500),
    "offgrid" (``offgrid`` random configurations, ``seed``), "trajectory", "figure4", "paper_reference"}``;
    ``grid``, ``grid_all`` and ``offgrid`` as :func:`run_grid`, ``trajectory`` as :func:`run_trajectory`.
    ``grid`` and ``grid_all`` come from one solve of the 16,500 poses (same ``seconds_per_point``).
    ``"both"``: ``{"paper": {...}, "precise": {...}, "paper_reference": PAPER_TABLES}``.

    The paper strategy takes several ms per pose: ``"both"`` with the defaults runs for a few minutes.
    """
    _check_carm_like(robot)
    _check_strategy(strategy, (*STRATEGIES, "both"))
    if offgrid < 0:
        raise UnknownOptionError(f"offgrid must be >= 0, got {offgrid}")
    if strategy == "both":
        return {
            "paper": _run_one(robot, "paper", offgrid, seed, progress),
            "precise": _run_one(robot, "precise", offgrid, seed, progress),
            "paper_reference": PAPER_TABLES,
        }
    out = _run_one(robot, strategy, offgrid, seed, progress)
    out["paper_reference"] = PAPER_TABLES
    return out
