"""Configurations on and next to an arm's singular set, and what "recovered" means there (tests and scripts).

``singular_configurations``: from a random configuration, one joint is moved to where det J changes sign (the singular
set, found by a sign change on a grid and bisection), then left there or moved 1e-9 ... 1e-3 off it. Random arms meet
their singular set in its generic part and, by the joint chosen, in every component det J has.

``recovered``: a configuration is recovered by a solve when a solution (or a family member) lies within ``tol`` of it,
or when the straight segment between them solves the pose (its midpoint and quarter points within the certification
tolerance), or, within 1e-3, a short arc of solutions joins them (``_on_one_arc``): the two are then the same root to
the precision the pose fixes it (a double root is fixed only to about the square root of the rounding, and near a
continuum less).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.optimize import brentq

#: Offsets from the singular set along the moved joint (radians, or times the length scale for a slide).
OFFSETS = (0.0, 0.0, 1e-9, 1e-7, 1e-5, 1e-4, 1e-3)
#: The certification's tolerance on the geodesic pose error, relative to the length scale (``settings.ACCEPT_TOL_REL``
#: with the margin the solver's polish leaves).
SAME_ROOT_REL = 1e-12
#: Farthest apart (radians, or times the length scale) that two configurations joined by an arc of solutions
#: (``_on_one_arc``) count as one root: the close roots of issue 35 lie 1e-5 ... 1e-3 apart.
ARC_REACH = 1e-3
#: Points of the segment corrected onto the arc.
ARC_POINTS = 9
#: ... each solving the pose no worse than twice the worse end, or than this (relative to the length scale: rounding
#: of the forward kinematics; the solver's ``settings.MEET_ROUNDING_REL``): a valley rising above that between two
#: points (a PUMA 560 1e-7 rad short of its elbow fold: 6e-15 between two roots of 1e-16) makes them two roots.
ARC_ROUNDING_REL = 1e-15


def _range(robot: Any) -> tuple[np.ndarray, np.ndarray]:
    lo = np.where(np.isfinite(robot.lower), robot.lower, -robot.length_scale)
    hi = np.where(np.isfinite(robot.upper), robot.upper, robot.length_scale)
    lo = np.where(robot.is_revolute, -np.pi, lo)
    hi = np.where(robot.is_revolute, np.pi, hi)
    return lo, hi


def _brackets(f: Any, q: np.ndarray, joint: int, lo: float, hi: float, grid: int) -> tuple[np.ndarray, np.ndarray]:
    """Where ``f`` (configurations ``(..., n)`` to values ``(...)``) changes sign as ``joint`` of ``q`` moves over
    ``[lo, hi]`` on a grid: the grid ``xs`` and the indices ``i`` of the brackets ``[xs[i], xs[i + 1]]``."""
    xs = np.linspace(lo, hi, grid)
    Q = np.repeat(q[None], grid, axis=0)
    Q[:, joint] = xs
    s = np.sign(f(Q))
    # (a zero on the grid itself, as a wrist straight at exactly 0: the bracket that starts at it)
    return xs, np.flatnonzero((s[:-1] * s[1:] < 0) | ((s[:-1] == 0) & (s[1:] != 0)))


def _zero(f: Any, q: np.ndarray, joint: int, a: float, b: float) -> float:
    """The value of ``joint`` in ``[a, b]`` where ``f`` (as ``_brackets``) of ``q`` so moved vanishes."""
    return float(brentq(lambda x: float(f(np.r_[q[:joint], x, q[joint + 1 :]])), a, b, xtol=1e-15))


def _det(robot: Any) -> Any:
    return lambda Q: np.linalg.det(robot.jacobian(Q))


def singular_configurations(robot: Any, n: int, rng: np.random.Generator, grid: int = 721) -> np.ndarray:
    """``(n, n_joints)`` configurations on the singular set of ``robot`` (6 joints) and next to it."""
    lo, hi = _range(robot)
    out: list[np.ndarray] = []
    tries = 0
    while len(out) < n and tries < 50 * n:
        tries += 1
        q = rng.uniform(lo, hi)
        k = int(rng.integers(robot.n_joints))
        xs, idx = _brackets(_det(robot), q, k, lo[k], hi[k], grid)
        if idx.size == 0:
            continue
        i = int(rng.choice(idx))
        x = _zero(_det(robot), q, k, xs[i], xs[i + 1])
        step = float(rng.choice(OFFSETS)) * float(rng.choice([-1.0, 1.0]))
        qs = q.copy()
        qs[k] = x + (step if robot.is_revolute[k] else step * robot.length_scale)
        out.append(qs)
    return np.array(out).reshape(-1, robot.n_joints)  # (none found: (0, n), e.g. an arm whose det J never vanishes)


def _wrist_straight(robot: Any, q: np.ndarray, grid: int = 721) -> list[float]:
    """Values of joint 5 where, with the rest of ``q``, the axes of joints 4 and 6 are parallel (their cross product,
    along joint 5's axis, changes sign)."""

    def cross(Q: np.ndarray) -> np.ndarray:
        J = robot.jacobian(Q)
        return np.einsum("...i,...i->...", np.cross(J[..., 3:, 3], J[..., 3:, 5]), J[..., 3:, 4])

    xs, idx = _brackets(cross, q, 4, -np.pi, np.pi, grid)
    return [_zero(cross, q, 4, xs[i], xs[i + 1]) for i in idx]


def folds_with_a_straight_wrist(
    robot: Any, n: int, joint: int, rng: np.random.Generator, grid: int = 721
) -> np.ndarray:
    """``(n, 6)`` configurations of a 6R arm with a wrist (joints 4-6) where det J = 0 along ``joint`` with joint 5
    1e-7 ... 1e-4 rad from where the wrist is straight (axes 4 and 6 parallel): a double root whose neighbours the
    nearly singular wrist spreads far apart (a later step divides by the wrist's sine)."""
    out: list[np.ndarray] = []
    for _ in range(20 * n):
        if len(out) == n:
            break
        q = rng.uniform(-np.pi, np.pi, 6)
        straight = _wrist_straight(robot, q, grid)
        if not straight:
            continue
        q[4] = float(rng.choice(straight)) + float(rng.choice([-1.0, 1.0])) * 10.0 ** rng.uniform(-7.0, -4.0)
        xs, idx = _brackets(_det(robot), q, joint, -np.pi, np.pi, grid)
        if idx.size == 0:
            continue
        i = int(rng.choice(idx))
        q[joint] = _zero(_det(robot), q, joint, xs[i], xs[i + 1])
        out.append(q)
    return np.array(out)


def recovered(robot: Any, sols: Any, q: np.ndarray, tol: float = 1e-6, reach: float = ARC_REACH) -> bool:
    """``q`` is among ``sols`` (a ``sweepik.Solutions``) as the module docstring says (``reach``: the arc's)."""
    if not (len(sols) or sols.families):
        return False
    return same_root(robot, q, sols.nearest(q), tol, reach)


def same_root(robot: Any, q: np.ndarray, s: np.ndarray, tol: float = 1e-6, reach: float = ARC_REACH) -> bool:
    """``q`` and the solution ``s`` are the same root of ``FK(q)`` as the module docstring says (an arc of solutions
    joining them no longer than ``reach``)."""
    d = s - q
    d = np.where(robot.is_revolute, np.angle(np.exp(1j * d)), d / robot.length_scale)
    if np.max(np.abs(d)) < tol:
        return True
    T = robot.fk(q)
    s = q + np.where(robot.is_revolute, np.angle(np.exp(1j * (s - q))), s - q)  # (the same winding as q)
    between = q[None] + np.array([0.25, 0.5, 0.75])[:, None] * (s - q)[None]
    if np.all(_geodesic(robot, between, T) <= SAME_ROOT_REL * robot.length_scale):
        return True
    return bool(np.max(np.abs(d)) <= reach and _on_one_arc(robot, q, s, T))


def one_root(robot: Any, q: np.ndarray, s: np.ndarray) -> bool:
    """Two solutions ``q`` and ``s`` of ``FK(q)`` are one root to the precision the pose fixes it, strictly: their
    midpoint solves the pose no worse than a few times the worse of them (or than FK's rounding,
    ``ARC_ROUNDING_REL``), or an arc of solutions joins them (``_on_one_arc``). Two roots 1e-6 apart next to a fold
    (each solving the pose to 1e-16, their midpoint to 5e-13) are two; ``same_root`` takes them as one."""
    T = robot.fk(q)
    s = q + np.where(robot.is_revolute, np.angle(np.exp(1j * (s - q))), s - q)
    ends = float(np.max(_geodesic(robot, np.stack([q, s]), T)))
    mid = float(_geodesic(robot, (0.5 * (q + s))[None], T)[0])
    if mid <= max(4.0 * ends, ARC_ROUNDING_REL * robot.length_scale):
        return True
    d = np.abs(s - q) / np.where(robot.is_revolute, 1.0, robot.length_scale)
    return bool(np.max(d) <= ARC_REACH and _on_one_arc(robot, q, s, T))


def _on_one_arc(robot: Any, q: np.ndarray, s: np.ndarray, T: np.ndarray) -> bool:
    """``q`` and ``s`` lie on one arc of configurations that all solve ``T``: points of the segment between them, each
    corrected by Newton steps with the joint that moves most between them held, solve the pose as well as ``q`` and
    ``s`` do (``ARC_ROUNDING_REL``) and move off the segment by a small part of its length. (Where the solution set
    is a short curved valley at rounding level, an I2RT YAM pose on its singular set, two points 4e-5 rad apart both
    solve the pose to 1e-15, the straight segment between them misses it by 1e-11, and the corrected one by 6e-16
    everywhere: the pose fixes the configuration only to that arc, and either end is it.)"""
    from sweepik.engine.polish import polished
    from sweepik.model.units import orientation_weight

    d = s - q
    held = np.zeros((ARC_POINTS, robot.n_joints), dtype=bool)
    held[:, int(np.argmax(np.abs(d) / np.where(robot.is_revolute, 1.0, robot.length_scale)))] = True
    t = np.linspace(0.0, 1.0, ARC_POINTS + 2)[1:-1]
    start = q[None] + t[:, None] * d[None]
    weight = orientation_weight(robot.length_unit)
    moved, err = polished(robot, start, np.broadcast_to(T, (ARC_POINTS, 4, 4)).copy(), weight, 20, fixed=held)
    off = np.max(np.abs(moved - start)) <= 0.1 * np.max(np.abs(d))
    ends = float(np.max(_geodesic(robot, np.stack([q, s]), T)))
    return bool(off and np.all(err <= max(2.0 * ends, ARC_ROUNDING_REL * robot.length_scale)))


def _geodesic(robot: Any, Q: np.ndarray, T: np.ndarray) -> np.ndarray:
    from sweepik.model.pose import pose_error_geodesic
    from sweepik.model.units import orientation_weight

    F = robot.fk(Q)
    return pose_error_geodesic(F, np.broadcast_to(T, F.shape), orientation_weight(robot.length_unit))


def families_certified(robot: Any, sols: Any, T: np.ndarray, members: int = 9) -> None:
    """Every family of ``sols`` (a ``sweepik.Solutions`` of pose ``T``) has its members (``members`` along each)
    solve the pose to 1e-9 of the arm's size, and none lies on the others (``families.inner_off``)."""
    from sweepik.engine.families import inner_off

    for f in sols.families:
        m = f.at(np.linspace(f.interval[0], f.interval[1], members))
        assert np.all(_geodesic(robot, m, T) <= 1e-9 * robot.length_scale), f
    for i, f in enumerate(sols.families):
        others = tuple(g for j, g in enumerate(sols.families) if j != i)
        assert inner_off(robot, [f], others)[0], ("a family lies on the others", f)
