"""Continua along theta* that a sweep's closed form reproduces only roughly.

Along some self-motions the swept reduction's closed form sits at a branch-domain edge all the way (two of its
branches meet along the continuum: a UR arm with its wrist straight, joints 2, 3, 4 and 6 parallel, swept along
joint 4). Its residual then carries the square root of rounding (1e-8 where rounding is 1e-16) instead of
vanishing, and crosses zero hundreds of times along the continuum: the compiled search runs out of room, and the
NumPy search finds tens of thousands of roots, each polished and certified on its own (seconds a pose), with the
continuum coming out in thousands of pieces. Its members between those roots miss the pose by ~1e-9 of the arm's
size: the closed form cannot give it as a family.

Such a pose's samples are recognised directly: a run of consecutive samples (``FAMILY_MIN_RUN``) of one branch whose
configurations miss the pose by less than ``POLISH_BELOW_REL`` of the arm's size and, corrected by Newton steps with
theta* held (:func:`sweepik.engine.continuation.correct`), solve it *at the sample's theta**. A pose a hair off a
self-motion has near-solutions along the whole former continuum too, but its exact solutions there are isolated:
with theta* held at a sample, no correction reaches the pose. The continuum is traced from the corrected samples
(:func:`sweepik.engine.continuation.continuum_families`: exact members), and the samples it covers are masked from the
search: on that branch, at those values of theta*, the continuum's member is the only configuration.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import search
from sweepik.engine.candidates import Spans
from sweepik.engine.continuation import continuum_families, correct
from sweepik.engine.dedupe import inside_limits
from sweepik.engine.families import off_families
from sweepik.engine.polish import geodesic_errors
from sweepik.engine.settings import FAMILY_MIN_RUN
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions.base import Array, IntArray, Reduction
from sweepik.results import Family


def rough_continua(
    robot: Robot,
    red: Reduction,
    chain: Array,
    world: Array,
    lo: Array,
    hi: Array,
    n_samples: int,
    limits: bool,
    near: float,
    tol: float,
) -> tuple[dict[int, list[Family]], IntArray, Array, Spans]:
    """The continua along ``red``'s theta* of the chain poses ``chain (N, 4, 4)`` (world poses ``world``) on their
    sample grids over ``[lo, hi]`` (``search.sample_grid``), traced: ``(families per pose, pose index, q, masked)``,
    the pose index and ``q`` of the isolated members ``continuum_families`` gives (pieces shrinking to a point at the
    limits) and ``masked``, the stretches of theta* (per pose and branch) where the branch's member is a traced
    family's member or a solution outside the limits: a search there finds nothing else. ``near``: the pose error
    below which a sample is corrected; ``tol``: the certification's."""
    out: dict[int, list[Family]] = {}
    n = robot.n_joints
    no_p, no_q = np.zeros(0, dtype=np.intp), np.zeros((0, n))
    grid, count = search.sample_grid(red, chain, lo, hi, n_samples)
    theta = np.where(np.arange(grid.shape[1])[None, :] < count[:, None], grid, np.nan)  # (N, M)
    N, M = theta.shape
    B = red.n_branches
    q = red.solve_rest(chain, theta)  # (N, M, B, n)
    flat = q.reshape(-1, n)
    rows = np.repeat(np.arange(N), M * B)
    finite = np.all(np.isfinite(flat), axis=1)
    err = np.full(flat.shape[0], np.inf)
    weight = orientation_weight(robot.length_unit)
    err[finite] = geodesic_errors(robot, flat[finite], world[rows[finite]], weight)
    # runs of near-solutions first (cheap), then the correction of their samples
    close = _runs(err.reshape(N, M, B) <= near, theta, lo, hi)
    k = np.nonzero(close.reshape(-1))[0]
    if k.size == 0:
        return out, no_p, no_q, Spans.empty()
    fixed, e = correct(robot, flat[k], world[rows[k]], red.free_joint, tol)
    solved = np.zeros(N * M * B, dtype=bool)
    solved[k] = e <= tol
    on = _runs(solved.reshape(N, M, B), theta, lo, hi)
    k_on = np.nonzero(on.reshape(-1)[k])[0]
    if k_on.size == 0:
        return out, no_p, no_q, Spans.empty()
    seed_p, seed_q = rows[k[k_on]], fixed[k_on]
    joint = np.full(seed_p.size, red.free_joint, dtype=np.intp)
    out, iso_p, iso_q = continuum_families(robot, chain, world, seed_p, seed_q, joint, limits, tol)
    # a corrected sample counts as covered on a traced family, or (with limits) outside them
    covered = np.zeros(seed_p.size, dtype=bool)
    for i in np.unique(seed_p).tolist():
        mine = np.nonzero(seed_p == i)[0]
        covered[mine] = ~off_families(robot, [(seed_q[mine], tuple(out.get(i, ())))])[0]
    if limits:
        covered |= ~inside_limits(robot, seed_q)
    mask = np.zeros(N * M * B, dtype=bool)
    mask[k[k_on[covered]]] = True
    return out, iso_p, iso_q, _stretches(_runs(mask.reshape(N, M, B), theta, lo, hi), theta)


def _runs(ok: NDArray[np.bool_], theta: Array, lo: Array, hi: Array) -> NDArray[np.bool_]:
    """``ok (N, M, B)`` kept only in runs of at least ``FAMILY_MIN_RUN`` consecutive samples of one branch spanning
    more than a millionth of the range (a run of coinciding hints is one point)."""
    N, M, B = ok.shape
    out = np.zeros_like(ok)
    for p, b in zip(*np.nonzero(ok.sum(axis=1) >= FAMILY_MIN_RUN), strict=True):
        edges = np.diff(np.concatenate([[0], ok[p, :, b].astype(np.int8), [0]]))
        for s, e in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0], strict=True):
            if e - s >= FAMILY_MIN_RUN and theta[p, e - 1] - theta[p, s] > 1e-6 * (hi[p] - lo[p]):
                out[p, s:e, b] = True
    return out


def _stretches(mask: NDArray[np.bool_], theta: Array) -> Spans:
    """The runs of ``mask (N, M, B)`` as spans from their first sample to their last."""
    parts: list[tuple[int, int, float, float]] = []
    for p, b in zip(*np.nonzero(mask.any(axis=1)), strict=True):
        edges = np.diff(np.concatenate([[0], mask[p, :, b].astype(np.int8), [0]]))
        for s, e in zip(np.nonzero(edges == 1)[0], np.nonzero(edges == -1)[0], strict=True):
            parts.append((int(p), int(b), float(theta[p, s]), float(theta[p, e - 1])))
    if not parts:
        return Spans.empty()
    p_, b_, lo_, hi_ = (np.array(c) for c in zip(*parts, strict=True))
    return Spans(p_.astype(np.intp), b_.astype(np.intp), lo_.astype(np.float64), hi_.astype(np.float64))


class RoughRedo:
    """``search.search``'s ``before_redo`` for a chunk of poses: the rough continua of the poses it redoes
    (``rough_continua`` on them), kept in the chunk's pose numbering (``families``, and ``pose``, ``q`` of the isolated
    members), their stretches returned for the search to leave out."""

    def __init__(
        self,
        robot: Robot,
        red: Reduction,
        chain: Array,
        world: Array,
        lo: Array,
        hi: Array,
        n_samples: int,
        limits: bool,
        near: float,
        tol: float,
    ) -> None:
        self.args = (robot, red, chain, world, lo, hi, n_samples, limits, near, tol)
        self.families: dict[int, list[Family]] = {}
        self.pose: IntArray = np.zeros(0, dtype=np.intp)
        self.q: Array = np.zeros((0, robot.n_joints))

    def __call__(self, idx: IntArray) -> Spans:
        robot, red, chain, world, lo, hi, n_samples, limits, near, tol = self.args
        fams, p, self.q, masked = rough_continua(
            robot, red, chain[idx], world[idx], lo[idx], hi[idx], n_samples, limits, near, tol
        )
        # (the families' chain pose is their own: only the pose numbering changes)
        self.families = {int(idx[i]): f for i, f in fams.items()}
        self.pose = idx[p].astype(np.intp)
        return masked
