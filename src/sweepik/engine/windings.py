"""2 pi windings: every value of the revolute joints, modulo 2 pi, inside their limits (``solve(..., windings=True)``).

A solution is reported once, its revolute values wrapped into the limits (``Robot.wrap``). An arm whose joints turn
through more than a turn (a UR's +-360 degrees) reaches the same pose with a joint a whole turn further: the same
tool pose, another configuration, which a planner may need (the one that does not unwind a cable). Each winding is
a row of its own after the base solutions of its pose, with the index of the base row it winds (``winding_of``);
its errors, limit flag and multiplicity are the base row's (the forward kinematics is the same).
"""

from __future__ import annotations

import dataclasses
import itertools

import numpy as np
from numpy.typing import NDArray

from sweepik.model.robot import Robot
from sweepik.results import Block, Solutions

Array = NDArray[np.float64]

#: Windings listed per solution at most (a joint range of a few turns on every joint would give thousands).
MAX_WINDINGS = 4096


def winding_rows(robot: Robot, q: Array, joints: NDArray[np.bool_] | None = None) -> tuple[NDArray[np.intp], Array]:
    """The windings of the configurations ``q (K, n)``: ``(base (M,), q (M, n))``, each row a configuration that
    differs from ``q[base]`` by whole turns on some revolute joints (among ``joints``, all by default), every turned
    value inside its limits (with ``robot.limit_tol``). A value already outside its limits is not turned. Rows in
    the order of their base row; the base rows themselves are not repeated."""
    rev = robot.is_revolute if joints is None else robot.is_revolute & joints
    two_pi = 2.0 * np.pi
    lo, hi = robot.lower - robot.limit_tol, robot.upper + robot.limit_tol
    inside = (q >= lo) & (q <= hi) & rev
    with np.errstate(invalid="ignore"):
        k_lo = np.where(inside, np.ceil((lo - q) / two_pi), 0.0).astype(np.int64)
        k_hi = np.where(inside, np.floor((hi - q) / two_pi), 0.0).astype(np.int64)
    k_hi = np.maximum(k_hi, k_lo)
    count = np.prod(k_hi - k_lo + 1, axis=1)
    base: list[int] = []
    rows: list[Array] = []
    for i in np.nonzero(count > 1)[0].tolist():
        ranges = [range(int(a), int(b) + 1) for a, b in zip(k_lo[i], k_hi[i], strict=True)]
        turns = np.array([t for t in itertools.islice(itertools.product(*ranges), MAX_WINDINGS + 1) if any(t)])
        turns = turns[:MAX_WINDINGS]
        rows.append(q[i] + two_pi * turns)
        base.extend([i] * len(turns))
    if not rows:
        return np.zeros(0, dtype=np.intp), np.zeros((0, q.shape[1]))
    return np.array(base, dtype=np.intp), np.concatenate(rows)


def wound_block(block: Block, joints: NDArray[np.bool_] | None = None) -> Block:
    """``block`` with the windings of every solution (``winding_rows``) after the base rows of its pose."""
    base, extra = winding_rows(block.robot, block.q, joints)
    local = block.row_in_pose
    if base.size == 0:
        return dataclasses.replace(block, winding_of=local)
    pose_of_row = np.repeat(np.arange(block.n), np.diff(block.bounds))
    pose = np.concatenate([pose_of_row, pose_of_row[base]])
    order = np.argsort(2 * pose + np.concatenate([np.zeros(pose_of_row.size), np.ones(base.size)]), kind="stable")
    take = np.concatenate([np.arange(block.q.shape[0]), base])[order]
    added = np.bincount(pose_of_row[base], minlength=block.n)
    return dataclasses.replace(
        block,
        bounds=(block.bounds + np.concatenate([[0], np.cumsum(added)])).astype(np.intp),
        q=np.concatenate([block.q, extra])[order],
        error=block.error[take],
        error_geodesic=block.error_geodesic[take],
        within_limits=block.within_limits[take],
        multiplicity=block.multiplicity[take],
        winding_of=np.concatenate([local, local[base]])[order].astype(np.intp),
    )


def wound_solutions(sol: Solutions, joints: NDArray[np.bool_] | None = None) -> Solutions:
    """``sol`` with the windings of every solution after the base rows (``winding_rows``)."""
    base, extra = winding_rows(sol.robot, sol.q, joints)
    if base.size == 0:
        return dataclasses.replace(sol, wound=True)
    take = np.concatenate([np.arange(len(sol)), base])
    winding_of = np.concatenate([sol.winding_of, sol.winding_of[base]]).astype(np.intp)
    return sol.kept(take, q=np.concatenate([sol.q, extra]), winding_of=winding_of, wound=True)
