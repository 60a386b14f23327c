"""The paper's strategy (sections 4-5), faithfully: sweep theta* in 10 mm steps over its whole range,
evaluate the error J (eq. 6) of every branch inside the joint limits, take the best branch per sample,
refine each local minimum with 1, 0.1, 0.01 and 0.001 mm steps (+-10 steps around the current best),
and report every branch with J below the threshold at the final value. For a revolute theta* the same
scheme runs in angle steps of 1 deg down to 0.0001 deg.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import certify
from sweepik.engine.dedupe import inside_limits
from sweepik.engine.settings import COARSE_STEP_DEG, COARSE_STEP_MM, HALF_WIDTH, LEVELS
from sweepik.model.pose import pose_error_paper
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit, orientation_weight
from sweepik.reductions.base import Reduction

Array = NDArray[np.float64]


def _best_error(robot: Robot, red: Reduction, chain: Array, theta: Array, limits: bool) -> tuple[Array, Array]:
    """J per branch ``(N, M, B)`` (inf outside limits / where a branch is missing) and configurations."""
    q = red.solve_rest(chain, theta)  # (N, M, B, n)
    ok = np.all(np.isfinite(q), axis=-1)
    qz = np.where(ok[..., None], q, 0.0)
    flange = certify.flange_poses(robot, qz.reshape(-1, qz.shape[-1])).reshape(*qz.shape[:-1], 4, 4)
    T = np.linalg.inv(robot.T_world_base) @ flange  # chain frame, like the target
    J = pose_error_paper(T, chain[:, None, None], orientation_weight(robot.length_unit))
    if limits:
        ok &= inside_limits(robot, qz)
    return np.where(ok, J, np.inf), q


def paper_candidates(
    robot: Robot, red: Reduction, chain: Array, lo: Array, hi: Array, limits: bool
) -> tuple[NDArray[np.intp], Array]:
    """Candidate configurations ``(K, n)`` with their pose indices, per the paper's strategy.

    ``chain`` are chain poses (base and tool removed), so J is measured on the flange; with identity base
    and tool (the C-Arm) that is the paper's J.
    """
    if red.periodic:
        step = np.radians(COARSE_STEP_DEG)
    else:
        step = COARSE_STEP_MM / mm_per_unit(robot.length_unit)
    N = chain.shape[0]
    if not limits and not red.periodic:  # keep the paper's lattice (multiples of the step) when unbounded
        lo = np.floor(lo / step) * step
    m = int(np.floor((hi - lo).max() / step + 1e-9)) + 1
    grid = lo[:, None] + step * np.arange(m)[None, :]
    grid = np.minimum(grid, hi[:, None])
    J, _ = _best_error(robot, red, chain, grid, limits)
    Jmin = J.min(axis=-1)  # best branch per sample (N, M)
    left = np.concatenate([np.full((N, 1), np.inf), Jmin[:, :-1]], axis=1)
    right = np.concatenate([Jmin[:, 1:], np.full((N, 1), np.inf)], axis=1)
    is_min = np.isfinite(Jmin) & (Jmin <= left) & (Jmin <= right)
    # plateaus of equal values: keep the first sample of each
    is_min &= ~(np.isfinite(left) & (Jmin == left))
    p, i = np.nonzero(is_min)
    center = grid[p, i]
    offsets = np.arange(-HALF_WIDTH, HALF_WIDTH + 1, dtype=np.float64)
    s = step
    for _ in range(LEVELS):
        s = s / 10.0
        pts = np.clip(center[:, None] + s * offsets[None, :], lo[p, None], hi[p, None])
        Jl, _ = _best_error(robot, red, chain[p], pts, limits)
        best = np.argmin(Jl.min(axis=-1), axis=-1)
        center = pts[np.arange(p.size), best]
    Jf, qf = _best_error(robot, red, chain[p], center[:, None], limits)
    Jf, qf = Jf[:, 0], qf[:, 0]  # (K, B), (K, B, n)
    kk, bb = np.nonzero(np.isfinite(Jf))
    return p[kk].astype(np.intp), qf[kk, bb]
