"""One chunk of poses solved by one reduction: the candidates (the search, a closed form's branches, special
solutions, families), settled (certified, deduplicated, limits), the fallback reduction where this one cannot
answer, and the block of results; a single pose in one compiled call where it can (``one_pose``)."""

from __future__ import annotations

import contextlib
import dataclasses
import math
from collections.abc import Iterator
from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import certify, one_pose, search
from sweepik.engine.candidates import Candidates, Spans
from sweepik.engine.chain_pose import chain_poses
from sweepik.engine.companion import joined
from sweepik.engine.continuation import continuum_families
from sweepik.engine.dedupe import finish, inside_limits, settle
from sweepik.engine.families import (
    MAX_ISOLATED_SOLUTIONS,
    collapse_continua,
    families_of,
)
from sweepik.engine.family_join import add_crossing_families, trace_cut_continua, with_families
from sweepik.engine.paper_sweep import paper_candidates
from sweepik.engine.partners import nearly_singular
from sweepik.engine.polish import polish
from sweepik.engine.rough_continua import RoughRedo
from sweepik.engine.settings import (
    ACCEPT_TOL_REL,
    CLIP_REACH_REL,
    MEET_REL,
    N_SAMPLES,
    PAPER_ACCEPT_MM,
    POLISH_BELOW_REL,
    POLISH_SINGULAR_REL,
    REDO_MAX_FOUND,
    SEED_TOL_REL,
)
from sweepik.engine.settle import (
    errors_of,
    meetings,
    next_to_folds,
    per_joint,
    settle_bounds,
    snap_reach,
    snap_to_limits,
)
from sweepik.errors import SearchOverflowError, ShapeError
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit, orientation_weight
from sweepik.reductions import Reduction, get_reduction
from sweepik.reductions.base import IntArray
from sweepik.reductions.kernels import owned_kernel
from sweepik.results import Block, Family, Solutions

Array = NDArray[np.float64]


def theta_range(robot: Robot, red: Reduction, chain: Array, paper_limits: bool = False) -> tuple[Array, Array]:
    """theta* range of each chain pose: the circle for a revolute theta*; for a prismatic one the interval the
    reduction says holds every solution, else the joint's limits. The same with and without joint limits, so
    that ``limits=True`` is exactly ``limits=False`` filtered by the limits (the sweep sees the same samples).
    ``paper_limits``: the paper's strategy with limits sweeps the joint's range on its own grid (section 5)."""
    n = chain.shape[0]
    j = red.free_joint
    if red.periodic:
        return np.full(n, -np.pi), np.full(n, np.pi)
    rng = None if paper_limits else red.search_range(chain)
    if rng is not None:
        lo, hi = rng[:, 0], rng[:, 1]
    else:
        lo, hi = np.full(n, robot.lower[j]), np.full(n, robot.upper[j])
    if n == 1:  # (Python floats: no NumPy error state to set for one pose)
        finite = math.isfinite(float(hi[0]) - float(lo[0]))
    else:
        with np.errstate(invalid="ignore", over="ignore"):
            finite = bool(np.isfinite(hi - lo).all())  # (lo and hi finite, and their difference too)
    if not finite:
        raise ShapeError(f"joint {robot.joint_names[j]} (theta*) needs finite limits to be swept")
    return lo, hi


def _limit_copies(robot: Robot, red: Reduction, cand: Candidates, span: Array) -> Candidates:
    """``cand`` plus, for each multiple root within ``CLIP_REACH_REL`` of the range outside theta*'s limits, a copy
    at the limit (same branch). Added with and without ``limits``: both see the same candidates."""
    if not (cand.mult >= 2).any():
        return cand
    j = red.free_joint
    lo, hi = robot.lower[j], robot.upper[j]
    reach = CLIP_REACH_REL * span[cand.pose]
    t = cand.theta
    near = (cand.mult >= 2) & (((t < lo) & (t >= lo - reach)) | ((t > hi) & (t <= hi + reach)))
    if not near.any():
        return cand
    k = np.nonzero(near)[0]
    return Candidates(
        np.concatenate([cand.pose, cand.pose[k]]),
        np.concatenate([cand.branch, cand.branch[k]]),
        np.concatenate([t, np.clip(t[k], lo, hi)]),
        np.concatenate([cand.mult, cand.mult[k]]),
    )


@lru_cache(maxsize=16)
def every_branch(n_poses: int, n_branches: int) -> Candidates:
    """Candidates of a closed form: every branch of every pose (theta* unused: 0). Cached (a chunk's size and a
    closed form's branches repeat): the arrays are read-only."""
    cand = Candidates(
        pose=np.repeat(np.arange(n_poses), n_branches).astype(np.intp),
        branch=np.tile(np.arange(n_branches), n_poses).astype(np.intp),
        theta=np.zeros(n_poses * n_branches),
        mult=np.ones(n_poses * n_branches, dtype=np.intp),
    )
    for a in (cand.pose, cand.branch, cand.theta, cand.mult):
        a.flags.writeable = False
    return cand


def solve_chunk(
    robot: Robot,
    red: Reduction,
    poses: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool = True,
    one_call: bool = True,
    given: tuple[Block | None, Block | None] = (None, None),
) -> Block:
    """The solutions of the chunk ``poses``; ``one_call``: a single pose may take the one compiled call (False: the
    caller found that it cannot). A reduction with a ``companion`` (an arm with a near-structure): both solve, and
    the companion's solutions that the first lacks are joined (:mod:`.companion`). ``given``: the blocks of ``red``
    and of its companion that the caller's one call settled already (``joined_pose``), None for each to solve here."""
    comp = getattr(red, "companion", None)
    first, second = given
    try:
        if first is None:
            first = _solve_chunk_by(robot, red, poses, strategy, limits, n_samples, use_fallback, one_call)
        if comp is None or strategy != "precise":
            return first
        if second is None:
            second = _solve_chunk_by(robot, comp, poses, strategy, limits, n_samples, use_fallback, False)
        both = joined(first, second)
        assert both is not None  # (settled on the solved arm: every pair of near solutions)
        return both
    finally:  # (what the reductions kept for these poses: dropped; most keep nothing, and pay nothing)
        keeping = [r for r in (red, comp) if r is not None and type(r).release is not Reduction.release]
        if keeping:
            chain = chain_poses(robot, poses)
            for r in keeping:
                r.release(chain)


@dataclasses.dataclass
class _Found:
    """A chunk's candidate solutions before settling: row ``i`` is configuration ``q[i]`` (multiplicity ``mult[i]``)
    of pose ``pose[i]``; the pose errors where the compiled certification gave them already (else None); the
    self-motion families found so far, by pose."""

    pose: NDArray[np.intp]
    q: Array
    mult: NDArray[np.intp]
    err_geo: Array | None
    err_paper: Array | None
    families: dict[int, list[Family]]

    def add(self, robot: Robot, poses: Array, pose: NDArray[np.intp], q: Array, mult: NDArray[np.intp]) -> None:
        """_Rows appended (their errors worked out when the others' are known)."""
        if self.err_geo is not None and self.err_paper is not None:
            eg, ep = errors_of(robot, q, poses[pose], orientation_weight(robot.length_unit))
            self.err_geo, self.err_paper = np.concatenate([self.err_geo, eg]), np.concatenate([self.err_paper, ep])
        self.q = np.concatenate([self.q, q])
        self.pose = np.concatenate([self.pose, pose])
        self.mult = np.concatenate([self.mult, mult])


#: A chunk's settled rows: ``(pose, q, err_paper, err_geo, mult, inside, keep)`` (``_settle_stepwise``'s).
_Rows = tuple[NDArray[np.intp], Array, Array, Array, NDArray[np.intp], NDArray[np.bool_], NDArray[np.bool_]]


def _solve_chunk_by(
    robot: Robot,
    red: Reduction,
    poses: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool = True,
    one_call: bool = True,
    found: _Found | None = None,
) -> Block:
    """:func:`solve_chunk` with ``red`` alone: the candidates, settled (certified, deduplicated, limits), the meeting
    branches of a closed form merged, the fallback reduction where this one cannot answer, the families; ``found``:
    the candidates found already (``resumed``)."""
    chain = chain_poses(robot, poses)  # (one array: the reduction keeps its parameters for it)
    if found is None:
        if len(poses) == 1 and strategy == "precise" and use_fallback and one_call and red.uses_kernel:
            block = _settled_single(robot, red, poses, chain, limits, n_samples)
            if block is not None:
                return block
        if strategy == "precise" or red.closed_form:
            found = _precise_candidates(robot, red, poses, chain, strategy, limits, n_samples, use_fallback)
        else:  # the paper's strategy, swept
            lo, hi = theta_range(robot, red, chain, paper_limits=limits)
            pose_idx, q = paper_candidates(robot, red, chain, lo, hi, limits)
            found = _Found(pose_idx, q, np.ones(pose_idx.size, dtype=np.intp), None, None, {})
    pose_idx, q, err_paper, err_geo, mult, inside, keep = _settled_rows(
        robot, red, poses, strategy, limits, n_samples, use_fallback, found
    )
    if red.closed_form or strategy == "precise":
        q, mult = meetings(robot, poses, pose_idx, q, err_geo, err_paper, inside, keep, mult, red.closed_form)
    if strategy == "precise" and pose_idx.size > MAX_ISOLATED_SOLUTIONS:  # (fewer: no pose can hold a continuum)
        # a numerical continuum of certified solutions is reported once
        keep[keep] = collapse_continua(robot, pose_idx[keep], q[keep])
    n_reachable = np.bincount(pose_idx[keep], minlength=len(poses))
    if limits:
        keep &= inside
    if not keep.all():  # (often all of them: a single pose's candidates are then used as they are)
        pose_idx, q, err_paper, err_geo, inside = pose_idx[keep], q[keep], err_paper[keep], err_geo[keep], inside[keep]
        mult = mult[keep]
    fams = found.families
    fallback = _fallback_solutions(robot, red, poses, chain, strategy, limits, n_samples, use_fallback, fams)
    # poses with families (few): their isolated solutions lying on a family are reported by the family; the
    # reduction's blind spot: the fallback reduction's families are added, and its isolated solutions when this
    # reduction has none (a closed form: always)
    if strategy == "precise" and use_fallback and (fams or fallback):
        add_crossing_families(robot, chain, poses, limits, fams, fallback)
    families: dict[int, tuple[Family, ...]] = {}
    if fams or fallback:
        families, pose_idx, q, err_paper, err_geo, inside, mult = with_families(
            robot, red, fams, fallback, pose_idx, q, err_paper, err_geo, inside, mult
        )
    empty_reason = None
    if strategy == "paper" and not red.closed_form:  # its final resolution decides nothing about reachability
        step = "0.0001 deg" if red.periodic else f"0.001 mm ({robot.joint_names[red.free_joint]})"
        empty_reason = (
            f"no solution with J < 1e-5 mm found by the paper's strategy (its final {step} step "
            "misses roots off its grid); strategy='precise' finds every solution"
        )
    rows = (pose_idx, q, err_paper, err_geo, mult, inside, keep)
    return _block(robot, poses, rows, families, n_reachable, empty_reason)


def _precise_candidates(
    robot: Robot,
    red: Reduction,
    poses: Array,
    chain: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool,
) -> _Found:
    """The candidates of the precise strategy (or of a closed form's): every branch of a closed form, or the sweep's
    roots (compiled: certified already), the reduction's special solutions, and the isolated members of the
    families found along theta*, along another joint (traced) or from a rough sweep."""
    closed = red.closed_form
    if not closed:  # (a closed form sweeps nothing)
        lo, hi = theta_range(robot, red, chain, paper_limits=strategy == "paper" and limits)
    spans = Spans.empty()
    compiled = red.uses_kernel
    err_geo = err_paper = None
    redo: RoughRedo | None = None
    if closed:  # no sweep: every branch of the closed form is a candidate
        params = red.kernel_params(chain) if compiled else None
        cand = every_branch(chain.shape[0], red.n_branches)
        if compiled and owned_kernel(red, "kernel_configurations") is not None:
            q, err_geo, err_paper = certify.certify_every_branch(robot, red, chain, poses, params)
        elif compiled:
            q, err_geo, err_paper = certify.certify(
                robot, red, chain, poses, cand.pose, cand.theta, cand.branch, params
            )
        else:  # (writable copies of the cached candidates: a reduction's code may want to write them)
            q = red.solve_rest(chain[cand.pose], np.array(cand.theta)[:, None], np.array(cand.branch)[:, None])
            q = q[:, 0]
    elif compiled:
        params = red.kernel_params(chain)
        if strategy == "precise":
            scale = robot.length_scale
            tols = (POLISH_BELOW_REL * scale, ACCEPT_TOL_REL * scale)
            redo = RoughRedo(robot, red, chain, poses, lo, hi, n_samples, limits, *tols)
        # (twins' copies included)
        cand, spans = search.search(red, chain, lo, hi, n_samples, params, before_redo=redo)
        cand = _limit_copies(robot, red, cand, hi - lo)
        q, err_geo, err_paper = certify.certify(robot, red, chain, poses, cand.pose, cand.theta, cand.branch, params)
    else:  # (a reduction without a compiled kernel: its residual called back, twins' copies included)
        cand, spans = search.search(red, chain, lo, hi, n_samples)
        cand = _limit_copies(robot, red, cand, hi - lo)
        q = red.solve_rest(chain[cand.pose], cand.theta[:, None], cand.branch[:, None])[:, 0]
    found = _Found(cand.pose, q, cand.mult, err_geo, err_paper, {})
    special, sp_mult = special_solutions(red, chain)
    if special is not None:
        sp_p, sp_k = np.nonzero(np.all(np.isfinite(special), axis=-1))
        ones = np.ones(sp_p.size, dtype=np.intp)
        found.add(robot, poses, sp_p, special[sp_p, sp_k], ones if sp_mult is None else sp_mult[sp_p, sp_k])
    tol = ACCEPT_TOL_REL * robot.length_scale
    members: list[tuple[NDArray[np.intp], Array]] = []  # (isolated members of families: pose index, q)
    if len(spans):  # (most sweeps find none)
        # a flat stretch followed past the sweep's range (past +-pi for a revolute theta*) is cut to the range
        s_lo, s_hi = np.maximum(spans.lo, lo[spans.pose]), np.minimum(spans.hi, hi[spans.pose])
        keep_span = s_hi > s_lo
        spans = Spans(spans.pose[keep_span], spans.branch[keep_span], s_lo[keep_span], s_hi[keep_span])
        fams, fam_p, fam_q = families_of(robot, red, chain, poses, spans, limits, tol)
        found.families = fams
        members.append((fam_p, fam_q))
    # a continuum along a joint other than theta*: its candidates (certified ones, when their errors are known
    # already: fewer to look at) where the reduction leaves such a joint free are traced (few poses)
    free = None
    if use_fallback and type(red).continuum_joints is not Reduction.continuum_joints:  # (else: None)
        n, seed_tol = cand.pose.size, SEED_TOL_REL * robot.length_scale
        e = None if err_geo is None else err_geo[:n]
        free = red.continuum_joints(chain, cand.pose, cand.theta, cand.branch, e, seed_tol)
    if redo is not None and redo.families:
        for i, f in redo.families.items():
            found.families.setdefault(i, []).extend(f)
        members.append((redo.pose, redo.q))
    if free is not None:
        seeds = np.nonzero(free >= 0)[0]
        seed_p, seed_q, free = cand.pose[seeds], q[seeds], free[seeds]
        traced, fam_p, fam_q = continuum_families(robot, chain, poses, seed_p, seed_q, free, limits, tol)
        for i, f in traced.items():
            found.families.setdefault(i, []).extend(f)
        members.append((fam_p, fam_q))
    for fam_p, fam_q in members:
        if fam_p.size:
            found.add(robot, poses, fam_p, fam_q, np.ones(fam_p.size, dtype=np.intp))
    return found


def special_solutions(red: Reduction, chain: Array) -> tuple[Array | None, IntArray | None]:
    """The candidates of the reduction's blind spots, ``(q (N, K, n) NaN-padded, multiplicities (N, K) or None)``:
    its ``special_solutions``, then the configurations the reduction of its ``blind_spot`` finds on the poses it
    names (swept here, twins' copies included) that ``blind_spot_kept`` keeps; ``(None, None)`` without either."""
    special = red.special_solutions(chain)
    own, own_mult = special if isinstance(special, tuple) else (special, None)
    blind = _blind_spot_solutions(red, chain)
    if blind is None:
        return own, own_mult
    if own is None:
        return blind
    if own_mult is None:
        own_mult = np.ones(own.shape[:2], dtype=np.intp)
    return np.concatenate([own, blind[0]], axis=1), np.concatenate([own_mult, blind[1]], axis=1)


def _blind_spot_solutions(red: Reduction, chain: Array) -> tuple[Array, IntArray] | None:
    """``special_solutions``' part from the reduction's ``blind_spot`` (None: no blind spot, or nothing kept)."""
    blind = red.blind_spot(chain)
    if blind is None:
        return None
    idx, other, rng = blind
    cand, _ = search.search(other, chain[idx], rng[:, 0], rng[:, 1], N_SAMPLES)  # (twins' copies included)
    q = other.solve_rest(chain[idx][cand.pose], cand.theta[:, None], cand.branch[:, None])[:, 0]
    keep = np.all(np.isfinite(q), axis=-1) & red.blind_spot_kept(q)
    pose, q, mult = cand.pose[keep], q[keep], cand.mult[keep]
    if pose.size == 0:
        return None
    counts = np.bincount(pose, minlength=idx.size)
    width = max(8, int(counts.max()))
    out = np.full((chain.shape[0], width, q.shape[1]), np.nan)
    out_m = np.ones((chain.shape[0], width), dtype=np.intp)
    order = np.argsort(pose, kind="stable")
    pose, q, mult = pose[order], q[order], mult[order]
    slot = np.arange(pose.size) - np.concatenate([[0], np.cumsum(counts)[:-1]])[pose]
    out[idx[pose], slot] = q
    out_m[idx[pose], slot] = mult
    return out, out_m


def _settled_rows(
    robot: Robot,
    red: Reduction,
    poses: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool,
    found: _Found,
) -> _Rows:
    """The candidates settled: in one compiled pass (``dedupe.settle``) but for the poses due a polish, the fallback
    or a limit snap (few), which go step by step (``_settle_stepwise``: all of them without the compiled errors)."""
    pose_idx, q, mult, err_geo, err_paper = found.pose, found.q, found.mult, found.err_geo, found.err_paper
    settled = None
    if strategy == "precise" and err_geo is not None and err_paper is not None:
        bounds = settle_bounds(robot)
        settled = settle(robot, q, err_geo, err_paper, pose_idx, mult, len(poses), bounds, snap_reach(robot))
    if settled is None:
        return _settle_stepwise(
            robot, red, poses, strategy, limits, n_samples, use_fallback, pose_idx, q, mult, err_geo, err_paper
        )
    assert err_geo is not None and err_paper is not None
    due, rows, w, inside, keep = settled
    slope = rows[err_geo[rows] > bounds[5]]  # (a certified one on a valley's slope: ``settings.VALLEY_ABOVE_REL``)
    if slope.size:
        slope = slope[nearly_singular(robot, q[slope])]
    if slope.size:
        due[pose_idx[slope]] = True
        kept = np.flatnonzero(~due[pose_idx[rows]])
        rows, w, inside, keep = rows[kept], w[kept], inside[kept], keep[kept]
    parts = [(pose_idx[rows], w, err_paper[rows], err_geo[rows], mult[rows], inside, keep)]
    if due.any():  # (these poses' rows, by the steps; the rows of a pose stay in order, and together)
        sub = np.nonzero(due[pose_idx])[0]
        rest = (pose_idx[sub], q[sub], mult[sub], err_geo[sub], err_paper[sub])
        parts.append(_settle_stepwise(robot, red, poses, strategy, limits, n_samples, use_fallback, *rest))
    if len(parts) == 1:
        return parts[0]
    pose_idx, q, err_paper, err_geo, mult, inside, keep = (np.concatenate(c) for c in zip(*parts, strict=True))
    return pose_idx, q, err_paper, err_geo, mult, inside, keep


def _fallback_solutions(
    robot: Robot,
    red: Reduction,
    poses: Array,
    chain: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool,
    fams: dict[int, list[Family]],
) -> dict[int, Solutions]:
    """The fallback reduction's solutions of the poses where ``red`` cannot answer (``degenerate_fallbacks``): all of
    them near a closed form's singular set (and the continua it cut, traced whole into ``fams``), the families at a
    sweep's blind spot."""
    fallback: dict[int, Solutions] = {}
    if strategy != "precise" or not use_fallback or red.fallback is None:
        return fallback
    for by, deg in red.degenerate_fallbacks(chain):
        alt_red = get_reduction(robot, by)
        for idx, alt in _answered(robot, alt_red, poses, np.nonzero(deg)[0], strategy, limits, n_samples):
            if red.closed_form:  # at or near its singular set a closed form loses digits: the sweep answers
                fallback.update({int(i): alt.solutions(k) for k, i in enumerate(idx)})
                trace_cut_continua(robot, alt_red, chain, poses, idx, alt, limits, fams, fallback)
            else:  # the reduction's blind spot: the fallback's families
                fallback.update({int(i): alt.solutions(k) for k, i in enumerate(idx) if alt.families.get(k)})
    return fallback


def _answered(
    robot: Robot, red: Reduction, poses: Array, idx: IntArray, strategy: str, limits: bool, n_samples: int
) -> Iterator[tuple[IntArray, Block]]:
    """``(idx, block)``: the poses ``idx`` solved by the fallback ``red``, in one chunk, or one by one where its search
    overflows (``SearchOverflowError``), without those that overflow alone: such a pose's candidates cross the
    fallback's residual more than ``settings.REDO_MAX_FOUND`` times (a self-motion of two dimensions, whose slices
    make it zero along stretches; ``search.candidates_capped``: a reduction's own search is not capped so), and the
    answer of the reduction that handed it over stands there."""
    block = _capped(robot, red, poses[idx], strategy, limits, n_samples)
    if block is not None:
        yield idx, block
        return
    for i in idx.tolist() if idx.size > 1 else ():
        one = np.array([i], dtype=np.intp)
        block = _capped(robot, red, poses[one], strategy, limits, n_samples)
        if block is not None:
            yield one, block


def _capped(robot: Robot, red: Reduction, poses: Array, strategy: str, limits: bool, n_samples: int) -> Block | None:
    """The fallback ``red``'s block of ``poses``, its search capped at ``REDO_MAX_FOUND`` candidates (the cap lifted
    before the caller goes on); None where it overflows."""
    try:
        with search.candidates_capped(REDO_MAX_FOUND):
            return solve_chunk(robot, red, poses, strategy, limits, n_samples, False)
    except SearchOverflowError:
        return None


def _block(
    robot: Robot,
    poses: Array,
    rows: _Rows,
    families: dict[int, tuple[Family, ...]],
    n_reachable: NDArray[np.intp],
    empty_reason: str | None,
) -> Block:
    """The chunk's block, its rows in pose order (mostly they are already, as a closed form's candidates and most
    sweeps' are, unless some poses went through the stepwise path: their rows come last; one pose's always: no
    reordering copies)."""
    pose_idx, q, err_paper, err_geo, mult, inside, _ = rows
    in_order = len(poses) == 1 or bool(np.all(pose_idx[1:] >= pose_idx[:-1]))
    order = slice(None) if in_order else np.argsort(pose_idx, kind="stable")
    return Block(
        robot=robot,
        poses=poses.copy(),
        bounds=(
            np.array([0, pose_idx.size], dtype=np.intp)
            if len(poses) == 1
            else np.searchsorted(pose_idx[order], np.arange(len(poses) + 1)).astype(np.intp)
        ),
        q=q[order],
        error=err_paper[order],
        error_geodesic=err_geo[order],
        within_limits=inside[order],
        multiplicity=mult[order].astype(np.intp),
        families=families,
        n_reachable=n_reachable.astype(np.intp),
        empty_reason=empty_reason,
    )


def _settled_single(
    robot: Robot, red: Reduction, poses: Array, chain: Array, limits: bool, n_samples: int
) -> Block | None:
    """``solve_chunk`` of one pose (``chain``: its chain pose) in one compiled call (``one_pose``), the same values;
    None where the pose needs one of its rarer steps (``settled``)."""
    out = settled(robot, red, poses, chain, limits, n_samples)
    if out is None:
        return None
    return one_block(
        robot, poses, out.q, out.error, out.error_geodesic, out.within_limits, out.multiplicity, out.reachable
    )


def resumed(
    robot: Robot, red: Reduction, poses: Array, q: Array, error: Array, error_geodesic: Array,
    multiplicity: NDArray[np.int64], limits: bool,
) -> Block:  # fmt: skip
    """``solve_chunk``'s block of the one pose ``poses (1, 4, 4)`` for ``red`` alone (default options), from the
    candidates its one call found (``single_pose``'s, for a sweep: status ``DUE``, one of them due a polish or a snap
    to a limit) without searching again: what ``_precise_candidates`` gives for such a reduction and pose (no special
    solutions, no families along theta*, no continuum along another joint through a certified candidate: the call
    checked those), then the rest of the general way. The same values as ``solve_chunk``'s."""
    pose = np.zeros(q.shape[0], dtype=np.intp)
    found = _Found(pose, q, multiplicity.astype(np.intp), error_geodesic, error, {})
    return _solve_chunk_by(robot, red, poses, "precise", limits, N_SAMPLES, found=found)


def one_block(
    robot: Robot, poses: Array, q: Array, error: Array, error_geodesic: Array, within_limits: NDArray[np.bool_],
    multiplicity: NDArray[np.intp], reachable: int,
) -> Block:  # fmt: skip
    """The block of the one pose ``poses (1, 4, 4)`` (copied) that the one compiled call settled: its solutions and
    how many certified configurations it reached."""
    return Block(
        robot=robot,
        poses=poses.copy(),
        bounds=np.array([0, q.shape[0]], dtype=np.intp),
        q=q,
        error=error,
        error_geodesic=error_geodesic,
        within_limits=within_limits,
        multiplicity=multiplicity,
        families={},
        n_reachable=np.array([reachable], dtype=np.intp),
        empty_reason=None,
    )


def settled(
    robot: Robot, red: Reduction, poses: Array, chain: Array, limits: bool, n_samples: int
) -> one_pose.Settled | None:
    """One pose's solutions from the one compiled call (``one_pose``); None where the pose needs one of its rarer
    steps (a polish, families, special solutions, a continuum along another joint, the fallback, branches of a
    closed form that meet) or a second reduction's solutions (a ``companion``: ``joined_pose`` tries both one
    calls where they settle the arm's poses often)."""
    if getattr(red, "companion", None) is not None:
        return None
    params = red.kernel_params(chain)
    bounds, reach = settle_bounds(robot), snap_reach(robot)
    if red.closed_form:  # (branches that meet, ``MEET``: merged into one of higher multiplicity, the general way)
        out = one_pose.settle_closed(robot, red, poses, params, bounds, reach, per_joint(robot, MEET_REL), limits)
    else:
        lo, hi = theta_range(robot, red, chain)
        seed_tol = SEED_TOL_REL * robot.length_scale  # (its continua: checked in the call)
        meet = per_joint(robot, MEET_REL)  # (two solutions that may be one root: merged stepwise, ``settle.meetings``)
        out = one_pose.settle_one(
            robot, red, chain, poses, lo, hi, n_samples, params, bounds, reach, CLIP_REACH_REL, seed_tol, meet, limits
        )
    if out is None or out.status != one_pose.OK or out.certified > MAX_ISOLATED_SOLUTIONS:
        return None
    special, _ = special_solutions(red, chain)
    if special is not None and np.isfinite(special).all(-1).any():
        return None
    if out.checked:  # (its singular set, checked in the call: ``Reduction.singular_kernel``)
        return out
    near = red.continuum_poses(chain)  # (a continuum the call does not look for)
    if near is not None and bool(near.any()):
        return None
    if red.closed_form and type(red).continuum_joints is not Reduction.continuum_joints:
        pose = np.zeros(out.theta.size, dtype=np.intp)
        free = red.continuum_joints(chain, pose, out.theta, out.branch, out.err_all, SEED_TOL_REL * robot.length_scale)
        if free is not None and bool((free >= 0).any()):
            return None
    if red.fallback is not None:
        deg = red.degenerate(chain)
        if deg is not None and bool(deg.any()):
            return None
    return out


#: While :func:`counting_stepwise` is active, the count of poses settled step by step (``_settle_stepwise``: their
#: candidates needed a polish, the fallback reduction or a snap to the limits): the cost a plan check weighs.
_stepwise_poses: list[int] | None = None


@contextlib.contextmanager
def counting_stepwise() -> Iterator[list[int]]:
    """``[n]``: the poses settled step by step while the block runs (one thread: the check's batch is one chunk)."""
    global _stepwise_poses
    outer, _stepwise_poses = _stepwise_poses, [0]
    try:
        yield _stepwise_poses
    finally:
        _stepwise_poses = outer


def _settle_stepwise(
    robot: Robot,
    red: Reduction,
    poses: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool,
    pose_idx: NDArray[np.intp],
    q: Array,
    mult: NDArray[np.intp],
    err_geo: Array | None,
    err_paper: Array | None,
) -> tuple[NDArray[np.intp], Array, Array, Array, NDArray[np.intp], NDArray[np.bool_], NDArray[np.bool_]]:
    """Candidates to certified, wrapped ones with ``finish``'s limit check and duplicate mask, step by step: the
    polish of near misses, the certification, the fallback reduction for poses it could not certify, the snap of
    solutions just outside the limits (``dedupe.settle`` does the same in one compiled pass when none of these is
    due). Returns ``(pose_idx, q, err_paper, err_geo, mult, inside, keep)``."""
    if _stepwise_poses is not None:
        _stepwise_poses[0] += int(np.unique(pose_idx).size)
    weight = orientation_weight(robot.length_unit)
    finite = np.isfinite(q).all(axis=-1)
    if not finite.all():
        pose_idx, q, mult = pose_idx[finite], q[finite], mult[finite]
        if err_geo is not None and err_paper is not None:
            err_geo, err_paper = err_geo[finite], err_paper[finite]
    if err_geo is None or err_paper is None:
        err_geo, err_paper = errors_of(robot, q, poses[pose_idx], weight)
    below, above, paper_above, accept, multiple, valley_above = settle_bounds(robot)
    if strategy == "precise":
        # (a multiple root's candidate: further, POLISH_MULTIPLE_REL; a nearly singular one's: POLISH_SINGULAR_REL)
        reach = np.where(mult >= 2, multiple, below)
        band = np.flatnonzero((err_geo > below) & (err_geo <= POLISH_SINGULAR_REL * robot.length_scale) & (mult < 2))
        if band.size:
            reach[band[nearly_singular(robot, q[band])]] = multiple
        near = np.nonzero((err_geo <= reach) & ((err_geo > above) | (err_paper > paper_above)))[0]
        probed = np.zeros(0, dtype=np.intp)
        if near.size:
            target = poses[pose_idx[near]]
            polished = polish(robot, q[near], target, weight, floor=above)
            eg, ep = errors_of(robot, polished, target, weight)
            # at a singular configuration the step can drift along the near-null space: never out of the limits
            # for a configuration that was inside them and already certified
            drift = (err_geo[near] <= accept) & inside_limits(robot, q[near]) & ~inside_limits(robot, polished)
            take = np.nonzero(~drift)[0]
            q[near[take]], err_geo[near[take]], err_paper[near[take]] = polished[take], eg[take], ep[take]
            if not red.closed_form:  # (a closed form gives every branch's root, a pair split by rounding too: MEET_REL)
                probed = near[take][eg[take] <= accept]
        # next to a fold of the solution set: a certified solution above rounding on a valley's slope moved to its
        # bottom (a closed form's root just off a fold, imprecise; a sweep's polish stopping in a valley); a sweep's
        # polished solution's close partner across the fold
        valley = (err_geo > valley_above) & (err_geo <= accept)
        valley[probed] = True
        if valley.any():
            probed_mask = np.zeros(q.shape[0], dtype=bool)
            probed_mask[probed] = True
            pose_idx, q, mult, err_geo, err_paper = next_to_folds(
                robot, poses, pose_idx, q, mult, err_geo, err_paper, np.flatnonzero(valley), probed_mask
            )
    if strategy == "precise":
        certified = err_geo <= accept
    else:
        certified = err_paper < PAPER_ACCEPT_MM / mm_per_unit(robot.length_unit)
    rescue = np.zeros(0, dtype=np.intp)
    if strategy == "precise" and use_fallback and red.fallback is not None:
        # a candidate that polishing could not certify (error between rounding level and 1e-6 of the arm):
        # the reduction's closed form is ill-conditioned there; the fallback reduction solves the pose too
        miss = ~certified & (err_geo <= below)
        if miss.any():
            rescue = np.unique(pose_idx[miss])
    pose_idx, q, err_paper, err_geo = pose_idx[certified], q[certified], err_paper[certified], err_geo[certified]
    mult = mult[certified]
    wrapped = None
    if strategy == "precise":
        wrapped = snap_to_limits(robot, q, err_geo, err_paper, poses, pose_idx, weight)
    if rescue.size:
        wrapped = None
        rescued = solve_chunk(
            robot, get_reduction(robot, red.fallback), poses[rescue], strategy, limits, n_samples, False
        )
        for r_pose, r_sol in zip(rescue, rescued, strict=True):  # (a block iterates its poses' Solutions)
            if len(r_sol):
                pose_idx = np.concatenate([pose_idx, np.full(len(r_sol), r_pose, dtype=pose_idx.dtype)])
                q = np.concatenate([q, r_sol.q])
                err_paper = np.concatenate([err_paper, r_sol.error])
                err_geo = np.concatenate([err_geo, r_sol.error_geodesic])
                mult = np.concatenate([mult, r_sol.multiplicity])
    # duplicates first (of twins, the one inside the limits is kept), so that limits=True is exactly
    # limits=False filtered by the limits
    q, inside, keep = finish(robot, pose_idx, q, err_geo, wrapped)
    return pose_idx, q, err_paper, err_geo, mult, inside, keep
