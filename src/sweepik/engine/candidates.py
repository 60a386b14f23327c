"""The candidate set of a sweep, as arrays: ``Candidates`` (pose, branch, theta*, multiplicity) and ``Spans`` (family
runs of theta*), the copies a reduction's twin branches share, and the sample grid (a uniform grid plus the
reduction's hints) both search engines sample."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from sweepik.reductions.base import Array, IntArray, Reduction


@dataclass(frozen=True)
class Candidates:
    """Flat candidate list: pose index, branch, theta* value and the root's multiplicity (1 for a simple root,
    2 where two solutions merge, ...), for ``K`` candidates."""

    pose: IntArray
    branch: IntArray
    theta: Array
    mult: IntArray


@dataclass(frozen=True)
class Spans:
    """Runs of theta* along which a branch of a pose solves the pose identically (self-motion families): pose
    index, branch and the run's ends ``[lo, hi]``, for ``K`` runs (arrays: a batch has thousands of them)."""

    pose: IntArray
    branch: IntArray
    lo: Array
    hi: Array

    @staticmethod
    def empty() -> Spans:
        """No spans (one shared instance, its arrays read-only: most sweeps find none)."""
        return _NO_SPANS

    @staticmethod
    def concat(parts: list[Spans]) -> Spans:
        if len(parts) == 1:
            return parts[0]
        return Spans(
            np.concatenate([s.pose for s in parts]).astype(np.intp),
            np.concatenate([s.branch for s in parts]).astype(np.intp),
            np.concatenate([s.lo for s in parts]).astype(np.float64),
            np.concatenate([s.hi for s in parts]).astype(np.float64),
        )

    def __len__(self) -> int:
        return int(self.pose.size)


def _no_spans() -> Spans:
    arrays = (np.zeros(0, np.intp), np.zeros(0, np.intp), np.zeros(0), np.zeros(0))
    for a in arrays:
        a.flags.writeable = False
    return Spans(*arrays)


_NO_SPANS = _no_spans()


@lru_cache(maxsize=8)
def unit_grid(n: int) -> Array:
    return np.linspace(0.0, 1.0, n)


#: The engine's sweep for the zeros of a reduction's ``edge_reduction``: ``zeros(reduction, poses, lo, hi) -> (N, K)``
#: (NaN-padded), registered by :mod:`sweepik.engine.search` when it is imported (the search lives above this module).
_edge_zeros: Callable[[Reduction, Array, Array, Array], Array] | None = None


def set_edge_zeros(zeros: Callable[[Reduction, Array, Array, Array], Array]) -> None:
    """Register the engine's sweep for the domain edges' samples (``grid_hints``)."""
    global _edge_zeros
    _edge_zeros = zeros


def grid_hints(reduction: Reduction, poses: Array) -> Array | None:
    """The samples ``(N, H)`` that ``sample_grid`` adds to the uniform grid (NaN: none): the zeros of the reduction's
    ``edge_reduction`` (its domain edges, each on its domain's side: ``search.inside_zeros``), then its hints and,
    for a non-periodic theta*, its limits (a solution exactly at a limit, a rail end, is then a sample); for a
    periodic theta* wrapped into [-pi, pi] (the zeros before they are moved inside: ``edge_zeros``)."""
    hints = reduction.sample_hints(poses)
    edges = reduction.edge_reduction(poses, hints)
    if hints is not None and hints.size and reduction.periodic:
        hints = wrapped(hints)
    if edges is not None:  # the domain edges' samples first (the zeros of the reduction it gives)
        assert _edge_zeros is not None, "sweepik.engine.search registers the edge zeros when imported"
        zeros = _edge_zeros(edges[0], poses, edges[1], edges[2])
        theta = zeros if hints is None else np.concatenate([zeros, hints], axis=1)
        keep = np.any(np.isfinite(theta), axis=0)
        hints = theta[:, keep] if keep.any() else None
    if not reduction.periodic:
        j = reduction.free_joint
        ends = np.empty((poses.shape[0], 2))
        ends[:, 0], ends[:, 1] = reduction.robot.lower[j], reduction.robot.upper[j]
        hints = ends if hints is None else np.concatenate([hints, ends], axis=1)
    return hints


def wrapped(theta: Array) -> Array:
    """Angles wrapped into (-pi, pi], bit for bit as the compiled ``subproblems.trig.wrap_pi``."""
    return np.pi - np.mod(np.pi - theta, 2.0 * np.pi)


def twin_copies(red: Reduction, cand: Candidates, spans: Spans) -> tuple[Candidates, Spans]:
    """The roots (and family spans) found on the first branch of each class of ``red.twins``, given to the other
    branches of the class too: their residuals are the same, their configurations differ. A pose's copies follow
    its own candidates, poses stay in order."""
    return twin_candidates(red, cand), twin_spans(red, spans)


def twin_candidates(red: Reduction, cand: Candidates) -> Candidates:
    """``twin_copies``' candidates: each pose's own, then their copies (class member by member, in order), poses in
    order (``search``'s one-pass search makes the same copies pose by pose)."""
    if not red.twins:
        return cand
    c_rows, c_branch = _twin_rows(red, cand.branch)
    pose = np.concatenate([cand.pose, cand.pose[c_rows]])
    # in pose order again, as the search gave them (certification and settling run on parts of whole poses)
    order = np.argsort(pose, kind="stable") if pose.size > 1 and pose[0] != pose[-1] else slice(None)
    return Candidates(
        pose[order],
        np.concatenate([cand.branch, c_branch])[order],
        np.concatenate([cand.theta, cand.theta[c_rows]])[order],
        np.concatenate([cand.mult, cand.mult[c_rows]])[order],
    )


def twin_spans(red: Reduction, spans: Spans) -> Spans:
    """``twin_copies``' family spans: all of them, then their copies."""
    if not red.twins or not len(spans):  # (most sweeps find none)
        return spans
    s_rows, s_branch = _twin_rows(red, spans.branch)
    return Spans.concat([spans, Spans(spans.pose[s_rows], s_branch, spans.lo[s_rows], spans.hi[s_rows])])


def twin_maps(red: Reduction) -> tuple[IntArray, ...]:
    """``red.twins`` as maps: for the d-th other member of the classes (d = 1, 2, ...), each branch's twin in that
    place (-1: none); none without twins."""
    twins = red.twins
    if not twins:
        return ()
    try:  # (as the reductions give them: tuples of ints, the cache's key as it is)
        return _twin_maps(twins, red.n_branches)
    except TypeError:  # (unhashable classes: lists, arrays)
        return _twin_maps(tuple(tuple(int(b) for b in cls) for cls in twins), red.n_branches)


def _twin_rows(red: Reduction, branch: IntArray) -> tuple[IntArray, IntArray]:
    """The rows of ``branch`` on the first branch of a class of twins, once for each other branch of the class, and
    that branch: ``(rows, branches)``."""
    rows, branches = [], []
    for twin in twin_maps(red):
        t = twin[branch]
        k = np.nonzero(t >= 0)[0]
        rows.append(k)
        branches.append(t[k])
    if len(rows) == 1:  # (classes of two: one map)
        return rows[0], branches[0]
    return np.concatenate(rows).astype(np.intp), np.concatenate(branches)


@lru_cache(maxsize=64)
def _twin_maps(twins: tuple[tuple[int, ...], ...], n_branches: int) -> tuple[IntArray, ...]:
    """For the d-th other member of the classes of ``twins`` (d = 1, 2, ...): each branch's twin in that place (-1:
    none), read only."""
    maps = []
    for d in range(1, max(len(cls) for cls in twins)):
        twin = np.full(n_branches, -1, dtype=np.intp)
        for cls in twins:
            if len(cls) > d:
                twin[cls[0]] = cls[d]
        twin.flags.writeable = False
        maps.append(twin)
    return tuple(maps)
