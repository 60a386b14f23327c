"""``solve`` and ``solve_many``: all IK solutions of poses, certified by forward kinematics.

Pipeline (see DESIGN.md): chain poses -> strategy (precise sweep or the paper's) -> candidate
configurations -> FK check against the target -> joint limits -> duplicates removed -> ``Solutions``.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable, Iterator, Mapping
from functools import lru_cache
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.engine import certify, one_pose, parallel, search
from sweepik.engine.companion import joined
from sweepik.engine.continuation import Traced, continuum_families, correct
from sweepik.engine.crossings import crossing_seeds
from sweepik.engine.dedupe import duplicate_tolerance, finish, merged_multiplicity, near_pairs, settle, wrap_inside
from sweepik.engine.families import (
    MAX_ISOLATED_SOLUTIONS,
    collapse_continua,
    families_of,
    inner_off,
    off_families,
    unique_families,
)
from sweepik.engine.paper_sweep import COARSE_STEP_DEG, COARSE_STEP_MM, paper_candidates
from sweepik.engine.partners import close_partners, nearly_singular, valley_bottoms
from sweepik.engine.polish import geodesic_errors, polish
from sweepik.engine.rough_continua import RoughRedo
from sweepik.engine.settings import ACCEPT_TOL_REL
from sweepik.engine.sweep import N_SAMPLES, Candidates, Spans, find_candidates, twin_copies
from sweepik.errors import LockedJointError, NoReductionError, ShapeError, UnknownOptionError
from sweepik.model.origin_axis import HeldJoints, hold_joints
from sweepik.model.pose import pose_error_geodesic, pose_error_paper
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit, orientation_weight
from sweepik.model.validate import as_float_array, check_bool, check_choice, check_int, check_poses, short_repr
from sweepik.reductions import Reduction, automatic_for_held, get_reduction, is_default
from sweepik.reductions.decompose import not_sweepable
from sweepik.reductions.kernels import owned_kernel
from sweepik.results import Block, Family, SolutionBatch, Solutions, joint_distance, no_solution_reason

__all__ = ["solve", "solve_many", "iter_solve", "STRATEGIES"]

#: A progress callback: ``progress(stage, done, total)``.
Progress = Callable[[str, int, int], None]

Array = NDArray[np.float64]
Strategy = Literal["precise", "paper"]
STRATEGIES = ("precise", "paper")

#: Candidates with a pose error below this times the length scale get a Newton polish on the full pose
#: (removes the ill-conditioning of a reduction; spurious candidates are far above it).
POLISH_BELOW_REL = 1e-6
#: ... and above this (already at rounding level: nothing to gain), ...
POLISH_ABOVE_REL = 1e-14
#: ... or with the paper's J above this: near a Z-Y-Z gimbal J magnifies a tiny rotation error by 1/sin(beta),
#: so there the pose is polished down to rounding level.
POLISH_PAPER_ABOVE_REL = 5e-14
#: Paper strategy: the paper's acceptance threshold J < 1e-5 mm (section 4).
PAPER_ACCEPT_MM = 1e-5
#: Candidates within this (relative to the arm's length scale) of their pose seed the continua that a reduction
#: cannot see (``Reduction.continuum_joints``): certified ones and those a polish would certify.
SEED_TOL_REL = 1e-6
#: Poses per chunk of ``solve_many``: bounds memory at (chunk x samples x branches) residuals.
CHUNK = 2048


def _chain_poses(robot: Robot, poses: Array) -> Array:
    out = poses
    if not robot.base_is_identity:
        out = robot.T_base_world @ out
    if not robot.tool_is_identity:
        out = out @ robot.T_tool_flange
    return out


def _theta_range(robot: Robot, red: Reduction, chain: Array, paper_limits: bool = False) -> tuple[Array, Array]:
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


#: A root of multiplicity >= 2 is pinned down along theta* only to its flat stretch (~1e-5 of the range for a
#: triple root): one this close outside theta*'s limits gets a copy clipped to the limit, certified like any
#: candidate, so that a solution exactly at a limit (a rail end) is not lost to its rounding.
CLIP_REACH_REL = 1e-4


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


#: A certified solution at most this far outside a joint limit (radians; prismatic joints: times the arm's length
#: scale) is tried at the limit: near a singular configuration the pose pins a solution down only to ~1e-8, so
#: one exactly at a limit comes out a little beyond it.
SNAP_REACH = 1e-4
#: Newton steps (other joints free, the clamped ones held) for a solution moved onto its limit.
SNAP_ITERATIONS = 4


def _settle_bounds(robot: Robot) -> tuple[float, float, float, float]:
    """The precise strategy's thresholds, absolute (times the arm's length scale): polish below, polish above, polish
    above on the paper's J, acceptance (``POLISH_BELOW_REL`` ... ``ACCEPT_TOL_REL``); the stepwise path and
    ``dedupe.settle`` take the same values."""
    ls = robot.length_scale
    return POLISH_BELOW_REL * ls, POLISH_ABOVE_REL * ls, POLISH_PAPER_ABOVE_REL * ls, ACCEPT_TOL_REL * ls


@lru_cache(maxsize=64)
def _per_joint(robot: Robot, value: float) -> Array:
    """``value`` per joint: as it is for a revolute one (radians), times the length scale for a prismatic one. Cached
    (robots are values; the solver asks for the same ones on every chunk; the compiled kernels take it, writable, and
    do not write it)."""
    return np.where(robot.is_revolute, value, value * robot.length_scale)


def _snap_reach(robot: Robot) -> Array:
    """``SNAP_REACH`` per joint."""
    return _per_joint(robot, SNAP_REACH)


def _snap_to_limits(
    robot: Robot, q: Array, err_geo: Array, err_paper: Array, poses: Array, pose_idx: NDArray[np.intp], weight: float
) -> tuple[Array, NDArray[np.bool_]]:
    """In place: certified configurations ``q (K, n)`` of poses ``poses[pose_idx]`` just outside the limits are
    clamped to them and polished with the clamped joints held; where that still certifies, it replaces them (with
    their errors). Returns ``wrap_inside(robot, q)`` of the result (what the deduplication starts from)."""
    w_all, inside = wrap_inside(robot, q)
    out = np.nonzero(~inside)[0]
    if out.size == 0:
        return w_all, inside
    w = w_all[out]
    over = np.maximum(robot.lower - robot.limit_tol - w, w - robot.upper - robot.limit_tol)
    near = np.all(over <= _snap_reach(robot), axis=-1)
    k, w, over = out[near], w[near], over[near]
    if k.size == 0:
        return w_all, inside
    held = over > 0
    start = np.clip(w, robot.lower, robot.upper)
    target = poses[pose_idx[k]]
    moved = polish(robot, start, target, weight, SNAP_ITERATIONS, fixed=held)
    eg, ep = _errors(robot, moved, target, weight)
    ok = (eg <= ACCEPT_TOL_REL * robot.length_scale) & robot.within_limits(moved)
    k = k[ok]
    q[k], err_geo[k], err_paper[k] = moved[ok], eg[ok], ep[ok]
    if k.size:
        w_all[k], inside[k] = wrap_inside(robot, q[k])
    return w_all, inside


@lru_cache(maxsize=16)
def _every_branch(n_poses: int, n_branches: int) -> Candidates:
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


def _solve_chunk(
    robot: Robot,
    red: Reduction,
    poses: Array,
    strategy: str,
    limits: bool,
    n_samples: int,
    use_fallback: bool = True,
    one_call: bool = True,
) -> Block:
    """The solutions of the chunk ``poses``; ``one_call``: a single pose may take the one compiled call (False: the
    caller found that it cannot). A reduction with a ``companion`` (an arm with a near-structure): both solve, and
    the companion's solutions that the first lacks are joined (:mod:`.companion`)."""
    block = _solve_chunk_by(robot, red, poses, strategy, limits, n_samples, use_fallback, one_call)
    comp = getattr(red, "companion", None)
    if comp is None or strategy != "precise":
        return block
    return joined(block, _solve_chunk_by(robot, comp, poses, strategy, limits, n_samples, use_fallback, False))


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
        """Rows appended (their errors worked out when the others' are known)."""
        if self.err_geo is not None and self.err_paper is not None:
            eg, ep = _errors(robot, q, poses[pose], orientation_weight(robot.length_unit))
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
) -> Block:
    """:func:`_solve_chunk` with ``red`` alone: the candidates, settled (certified, deduplicated, limits), the meeting
    branches of a closed form merged, the fallback reduction where this one cannot answer, the families."""
    chain = _chain_poses(robot, poses)  # (one array: the reduction keeps its parameters for it)
    if len(poses) == 1 and strategy == "precise" and use_fallback and one_call and red.uses_kernel:
        block = _settled_single(robot, red, poses, chain, limits, n_samples)
        if block is not None:
            return block
    if strategy == "precise" or red.closed_form:
        found = _precise_candidates(robot, red, poses, chain, strategy, limits, n_samples, use_fallback)
    else:  # the paper's strategy, swept
        lo, hi = _theta_range(robot, red, chain, paper_limits=limits)
        pose_idx, q = paper_candidates(robot, red, chain, lo, hi, limits)
        found = _Found(pose_idx, q, np.ones(pose_idx.size, dtype=np.intp), None, None, {})
    pose_idx, q, err_paper, err_geo, mult, inside, keep = _settled_rows(
        robot, red, poses, strategy, limits, n_samples, use_fallback, found
    )
    if red.closed_form:
        q, mult = _closed_form_meetings(robot, poses, pose_idx, q, err_geo, err_paper, inside, keep, mult)
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
        _add_crossing_families(robot, chain, poses, limits, fams, fallback)
    families: dict[int, tuple[Family, ...]] = {}
    if fams or fallback:
        families, pose_idx, q, err_paper, err_geo, inside, mult = _with_families(
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
        lo, hi = _theta_range(robot, red, chain, paper_limits=strategy == "paper" and limits)
    spans = Spans.empty()
    compiled = red.uses_kernel and search.AVAILABLE
    err_geo = err_paper = None
    redo: RoughRedo | None = None
    if closed:  # no sweep: every branch of the closed form is a candidate
        params = red.kernel_params(chain) if compiled else None
        cand = _every_branch(chain.shape[0], red.n_branches)
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
    else:
        cand, spans = twin_copies(red, *find_candidates(red, chain, lo, hi, n_samples))
        cand = _limit_copies(robot, red, cand, hi - lo)
        q = red.solve_rest(chain[cand.pose], cand.theta[:, None], cand.branch[:, None])[:, 0]
    found = _Found(cand.pose, q, cand.mult, err_geo, err_paper, {})
    special = red.special_solutions(chain)
    sp_mult = None
    if isinstance(special, tuple):
        special, sp_mult = special
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
        bounds = _settle_bounds(robot)
        settled = settle(robot, q, err_geo, err_paper, pose_idx, len(poses), bounds, _snap_reach(robot))
    if settled is None:
        return _settle_stepwise(
            robot, red, poses, strategy, limits, n_samples, use_fallback, pose_idx, q, mult, err_geo, err_paper
        )
    assert err_geo is not None and err_paper is not None
    due, rows, w, inside, keep = settled
    parts = [(pose_idx[rows], w, err_paper[rows], err_geo[rows], mult[rows], inside, keep)]
    if due.any():  # (these poses' rows, by the steps; the rows of a pose stay in order, and together)
        sub = np.nonzero(due[pose_idx])[0]
        rest = (pose_idx[sub], q[sub], mult[sub], err_geo[sub], err_paper[sub])
        parts.append(_settle_stepwise(robot, red, poses, strategy, limits, n_samples, use_fallback, *rest))
    if len(parts) == 1:
        return parts[0]
    pose_idx, q, err_paper, err_geo, mult, inside, keep = (np.concatenate(c) for c in zip(*parts, strict=True))
    return pose_idx, q, err_paper, err_geo, mult, inside, keep


def _closed_form_meetings(
    robot: Robot,
    poses: Array,
    pose_idx: NDArray[np.intp],
    q: Array,
    err_geo: Array,
    err_paper: Array,
    inside: NDArray[np.bool_],
    keep: NDArray[np.bool_],
    mult: NDArray[np.intp],
) -> tuple[Array, NDArray[np.intp]]:
    """A closed form's branches that meet: one solution, a multiple root, whether the deduplication found them one
    (``keep``) or the closed form's rounding split them in two (merged here, in place of ``err_*``, ``inside`` and
    ``keep``). Returns ``(q, mult)`` (copies where changed)."""
    if not keep.all():
        mult = merged_multiplicity(robot, pose_idx, q, keep, mult)
    pair = _meeting_pairs(robot, pose_idx, q, keep)
    if pair.size:
        q, mult = q.copy(), mult.copy()
        _merge_meeting(robot, poses, pair, q, err_geo, err_paper, inside, keep, mult, pose_idx)
    return q, mult


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
        idx = np.nonzero(deg)[0]
        alt_red = get_reduction(robot, by)
        alt = _solve_chunk(robot, alt_red, poses[idx], strategy, limits, n_samples, False)
        if red.closed_form:  # at or near its singular set a closed form loses digits: the sweep answers
            fallback.update({int(i): alt.solutions(k) for k, i in enumerate(idx)})
            _trace_cut_continua(robot, alt_red, chain, poses, idx, alt, limits, fams, fallback)
        else:  # the reduction's blind spot: the fallback's families
            fallback.update({int(i): alt.solutions(k) for k, i in enumerate(idx) if alt.families.get(k)})
    return fallback


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


#: Two certified solutions of a closed form this close (every joint, radians; relative to the length scale for a
#: slide) may be one double root that the closed form's rounding split in two: where two branches meet, a step's
#: cosine sits at +-1 up to rounding magnified by the arm's geometry (1e-12 gives two roots 1.6e-6 rad apart, each
#: certified, as the pose error grows only quadratically along them). Their midpoint is the root.
MEET_REL = 1e-3
#: ... but not when the polish of their midpoint moves it by more than this fraction of their distance: it went over
#: to one of them, and they are two roots (next to a singular set two roots 1e-5 ... 1e-3 apart each solve the pose,
#: and the polish from between them converges to one). With the wrist nearly singular (UR16e, A5 = 1.7e-4 at a
#: shoulder double root) the closed form's split pair lies 2.7e-4 apart: the rounding of joint 1 (1e-8) over A5.
MEET_STAY = 0.1
#: Beyond this (the former ``MEET_REL``), the midpoint must solve the pose no worse than twice the worse of the pair,
#: not merely below ``POLISH_ABOVE_REL``: a PUMA 560 1e-7 rad off its elbow fold has two roots 3e-4 apart whose polished
#: midpoint misses the pose by 6e-15 of the arm's size, 60 times more than they do (the UR16e's split root: 1.3e-16).
MEET_NEAR = 1e-4
#: ... or than this (relative to the length scale: a few roundings of the forward kinematics; a UR18's split root
#: 6e-4 apart, each 1e-16, midpoint 2.2e-16).
MEET_ROUNDING_REL = 1e-15


def _meeting_pairs(robot: Robot, pose_idx: NDArray[np.intp], w: Array, keep: NDArray[np.bool_]) -> NDArray[np.intp]:
    """``(P, 2)`` pairs of kept rows of one pose whose configurations ``w`` (wrapped) are within ``MEET_REL``."""
    return near_pairs(robot, pose_idx, w, keep, _per_joint(robot, MEET_REL))


def _merge_meeting(
    robot: Robot,
    poses: Array,
    pair: NDArray[np.intp],
    w: Array,
    err_geo: Array,
    err_paper: Array,
    inside: NDArray[np.bool_],
    keep: NDArray[np.bool_],
    mult: NDArray[np.intp],
    pose_idx: NDArray[np.intp],
) -> None:
    """In place: each pair of ``_meeting_pairs`` whose midpoint (polished) solves the pose as well as the better of
    them, or at rounding level (``POLISH_ABOVE_REL``), becomes that midpoint (its errors, its limit check, the pair's
    multiplicities summed), the second row dropped.
    Two distinct roots this close (a pose next to the singular set) keep apart: between them the pose error grows
    quadratically, far above theirs."""
    weight = orientation_weight(robot.length_unit)
    for a, b in pair.tolist():
        if not (keep[a] and keep[b]):
            continue
        d = w[b] - w[a]
        d = np.where(robot.is_revolute, np.mod(d + np.pi, 2.0 * np.pi) - np.pi, d)
        target = poses[pose_idx[a]][None]
        # (polished: the pair's other joints carry rounding of their own, which moves the pose linearly)
        half = (w[a] + 0.5 * d)[None]
        moved = polish(robot, half, target, weight, SNAP_ITERATIONS)
        # (the polish may not carry the midpoint over to one of the pair: two distinct roots are not one)
        step = np.where(robot.is_revolute, np.mod(moved - half + np.pi, 2.0 * np.pi) - np.pi, moved - half)
        unit = _per_joint(robot, 1.0)
        apart = float(np.max(np.abs(d) / unit))
        stays = np.max(np.abs(step[0]) / unit) <= MEET_STAY * apart
        mid, mid_inside = wrap_inside(robot, moved)
        eg, ep = _errors(robot, mid, target, weight)
        # (better than both, or at rounding level as they may be: ``POLISH_ABOVE_REL``; a pair farther apart than
        # ``MEET_NEAR``: no worse than twice the worse of them, or than ``MEET_ROUNDING_REL``)
        best = max(min(err_geo[a], err_geo[b]), POLISH_ABOVE_REL * robot.length_scale)
        if apart > MEET_NEAR:
            best = max(2.0 * max(err_geo[a], err_geo[b]), MEET_ROUNDING_REL * robot.length_scale)
        if stays and eg[0] <= best and (mid_inside[0] or not (inside[a] or inside[b])):
            w[a], err_geo[a], err_paper[a], inside[a] = mid[0], eg[0], ep[0], mid_inside[0]
            mult[a] += mult[b]
            keep[b] = False


def _settled_single(
    robot: Robot, red: Reduction, poses: Array, chain: Array, limits: bool, n_samples: int
) -> Block | None:
    """``_solve_chunk`` of one pose (``chain``: its chain pose) in one compiled call (``fastsolve``), the same values;
    None where the pose needs one of its rarer steps (``_settled``)."""
    out = _settled(robot, red, poses, chain, limits, n_samples)
    if out is None:
        return None
    return Block(
        robot=robot,
        poses=poses.copy(),
        bounds=np.array([0, out.q.shape[0]], dtype=np.intp),
        q=out.q,
        error=out.error,
        error_geodesic=out.error_geodesic,
        within_limits=out.within_limits,
        multiplicity=out.multiplicity,
        families={},
        n_reachable=np.array([out.reachable], dtype=np.intp),
        empty_reason=None,
    )


def _settled(
    robot: Robot, red: Reduction, poses: Array, chain: Array, limits: bool, n_samples: int
) -> one_pose.Settled | None:
    """One pose's solutions from the one compiled call (``fastsolve``); None where the pose needs one of its rarer
    steps (a polish, families, special solutions, a continuum along another joint, the fallback, branches of a
    closed form that meet) or a second reduction's solutions (a ``companion``)."""
    if getattr(red, "companion", None) is not None:
        return None
    params = red.kernel_params(chain)
    bounds, reach = _settle_bounds(robot), _snap_reach(robot)
    if red.closed_form:  # (branches that meet, ``MEET``: merged into one of higher multiplicity, the general way)
        out = one_pose.settle_closed(robot, red, poses, params, bounds, reach, _per_joint(robot, MEET_REL), limits)
    else:
        lo, hi = _theta_range(robot, red, chain)
        seed_tol = SEED_TOL_REL * robot.length_scale  # (its continua: checked in the call)
        out = one_pose.settle_one(
            robot, red, chain, poses, lo, hi, n_samples, params, bounds, reach, CLIP_REACH_REL, seed_tol, limits
        )
    if out is None or out.status != one_pose.OK or out.certified > MAX_ISOLATED_SOLUTIONS:
        return None
    special = red.special_solutions(chain)
    if special is not None and np.isfinite(special[0] if isinstance(special, tuple) else special).all(-1).any():
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


#: A family's end is at a joint limit when a joint of its member there is this close to it (radians; relative to
#: the length scale for a slide): the limits cut it there (``_cut_short``) ...
_AT_LIMIT = 1e-7
#: ... and elsewhere the continuum goes on past it when the member this far beyond it (relative to the joint's
#: range) is a near-solution (within ``POLISH_BELOW_REL``): the family's closed form lost digits there. Past a
#: fold or a branch-domain edge, where a continuum ends, the member misses the pose by ~this times the arm.
_PAST_END_REL = 1e-3


def _cut_short(robot: Robot, family: Family, target: Array, limits: bool) -> bool:
    """The family's continuum goes on past one of its ends (the sweep's closed form lost it there: its members stop
    being certified), where no joint limit cuts it."""
    j = family.free_joint
    ends = np.array(family.interval)
    span = (-np.pi, np.pi) if robot.is_revolute[j] else (float(robot.lower[j]), float(robot.upper[j]))
    inner = (np.abs(ends - span[0]) > _AT_LIMIT) & (np.abs(ends - span[1]) > _AT_LIMIT)
    if limits:
        m = robot.wrap(family.at(ends))
        slack = _per_joint(robot, _AT_LIMIT)
        inner &= ~np.any((np.abs(m - robot.lower) <= slack) | (np.abs(m - robot.upper) <= slack), axis=-1)
    if not inner.any():
        return False
    past = (ends + np.array([-1.0, 1.0]) * _PAST_END_REL * (span[1] - span[0]))[inner]
    red = family.reduction
    q = red.solve_rest(family.chain_pose[None], past[None, :], np.full((1, past.size), family.branch))[0]
    err = geodesic_errors(robot, q, np.broadcast_to(target, (past.size, 4, 4)), orientation_weight(robot.length_unit))
    return bool(np.any(err <= POLISH_BELOW_REL * robot.length_scale))


def _trace_cut_continua(
    robot: Robot,
    sweep: Reduction,
    chain: Array,
    poses: Array,
    idx: NDArray[np.intp],
    alt: Block,
    limits: bool,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
) -> None:
    """A closed form's degenerate poses ``idx``, answered by its fallback ``sweep`` (``alt``): where the sweep's closed
    form loses digits along a continuum (the C-Arm with joints 5 and 6 swapped, its elbow nearly straight), the
    continuum comes out as short pieces and isolated members. From those (each isolated solution, the middle of each
    piece) it is traced along the sweep's joint (:mod:`.continuation`: exact members, and only from a configuration
    where the arm is singular); the continua found go to ``fams``, and the fallback's families they cover are
    dropped from ``fallback``. The fallback's families traced already (:mod:`.rough_continua`) are whole: the
    isolated solutions on them are no seeds, and a continuum traced again along one of them is not added."""
    pose = [idx[np.repeat(np.arange(idx.size), np.diff(alt.bounds))]]
    seeds = [alt.q]
    whole: dict[int, tuple[Family, ...]] = {}  # (the fallback's traced families, per pose of the chunk)
    for k, pieces in alt.families.items():  # (few poses)
        whole[int(idx[k])] = tuple(f for f in pieces if isinstance(f.reduction, Traced))
        cut = [f for f in pieces if not isinstance(f.reduction, Traced) and _cut_short(robot, f, poses[idx[k]], limits)]
        if cut:
            pose.append(np.full(len(cut), idx[k], dtype=np.intp))
            seeds.append(np.array([f.at(0.5 * (f.interval[0] + f.interval[1])) for f in cut]))
    p, q = np.concatenate(pose), np.concatenate(seeds)
    if whole and p.size:
        off = np.ones(p.size, dtype=bool)
        for i, known in whole.items():
            rows = np.nonzero(p == i)[0]
            off[rows] = off_families(robot, [(q[rows], known)])[0]
        p, q = p[off], q[off]
    traced: dict[int, list[Family]] = {}
    if p.size:
        joint = np.full(p.size, sweep.free_joint, dtype=np.intp)
        tol = ACCEPT_TOL_REL * robot.length_scale
        # (the continua's pieces that shrink to a point at a limit are left out: the fallback has them as solutions)
        traced, _, _ = continuum_families(robot, chain, poses, p, q, joint, limits, tol)
    for i in sorted(set(traced) | set(whole)):
        found, known = traced.get(i, []), whole.get(i, ())
        sol = fallback[i]
        if found and known:  # a traced family's continuum again (from an isolated solution on it): not added ...
            new = inner_off(robot, found, known)
            again = tuple(f for f, o in zip(found, new, strict=True) if not o)
            found = [f for f, o in zip(found, new, strict=True) if o]
            if again and len(sol):  # ... and its seeds are members of it (at a fold, or where it meets itself)
                sol = _rows(sol, off_families(robot, [(sol.q, again)])[0])
        if found:
            fams.setdefault(i, []).extend(found)
        swept = [f for f in sol.families if not isinstance(f.reduction, Traced)]
        if swept and (found or known):  # the pieces: covered when their ends and middle are members of a continuum
            ends = [f.at(np.linspace(f.interval[0], f.interval[1], 3)) for f in swept]
            uncovered = off_families(robot, [(m, tuple(found) + known) for m in ends])
            sol = dataclasses.replace(
                sol, families=known + tuple(f for f, o in zip(swept, uncovered, strict=True) if o.any())
            )
        fallback[i] = sol


def _next_to_folds(
    robot: Robot,
    poses: Array,
    pose_idx: NDArray[np.intp],
    q: Array,
    mult: NDArray[np.intp],
    err_geo: Array,
    err_paper: Array,
    rows: NDArray[np.intp],
) -> tuple[NDArray[np.intp], Array, NDArray[np.intp], Array, Array]:
    """The certified solutions ``rows`` the polish gave, next to a fold of the solution set (:mod:`.partners`): one in
    a flat valley moved to its bottom (in place; never out of the limits, as the polish's drift), and a close partner
    on the far side of the fold added after the solution it was found from (a pose's rows stay together): the
    candidates ``(pose_idx, q, mult, err_geo, err_paper)``."""
    if rows.size:  # (only nearly singular ones: most polished solutions are not)
        rows = rows[nearly_singular(robot, q[rows])]
    if rows.size == 0:
        return pose_idx, q, mult, err_geo, err_paper
    accept = ACCEPT_TOL_REL * robot.length_scale
    weight = orientation_weight(robot.length_unit)
    q_v, moved = valley_bottoms(robot, q[rows], poses[pose_idx[rows]], accept)
    if moved.any():
        moved &= robot.within_limits(q_v) | ~robot.within_limits(q[rows])
        m = rows[moved]
        q[m] = q_v[moved]
        err_geo[m], err_paper[m] = _errors(robot, q[m], poses[pose_idx[m]], weight)
    # each distinct one once, and none of a pose with more of them than an arm has solutions (a numerical continuum,
    # along which no partner is taken)
    distinct = rows[finish(robot, pose_idx[rows], q[rows], err_geo[rows])[2]]
    count = np.bincount(pose_idx[distinct], minlength=len(poses))
    distinct = distinct[count[pose_idx[distinct]] <= MAX_ISOLATED_SOLUTIONS]
    row, q_p, _ = close_partners(robot, q[distinct], poses[pose_idx[distinct]], accept)
    if row.size:  # (each once, and none its pose has already: found again, it would add to a multiplicity)
        new = _new_rows(robot, pose_idx, q, distinct[row], q_p)
        row, q_p = row[new], q_p[new]
    if row.size == 0:
        return pose_idx, q, mult, err_geo, err_paper
    src = distinct[row]
    eg_p, ep_p = _errors(robot, q_p, poses[pose_idx[src]], weight)
    order = np.argsort(np.concatenate([np.arange(pose_idx.size), src]), kind="stable")
    return (
        np.concatenate([pose_idx, pose_idx[src]])[order],
        np.concatenate([q, q_p])[order],
        np.concatenate([mult, np.ones(src.size, dtype=mult.dtype)])[order],
        np.concatenate([err_geo, eg_p])[order],
        np.concatenate([err_paper, ep_p])[order],
    )


def _new_rows(
    robot: Robot, pose_idx: NDArray[np.intp], q: Array, src: NDArray[np.intp], q_new: Array
) -> NDArray[np.bool_]:
    """``(K,)``: the configurations ``q_new (K, n)`` of the poses of rows ``src`` that are neither one of their pose's
    rows of ``q`` nor an earlier one of ``q_new`` (within ``dedupe.duplicate_tolerance``)."""
    tol = duplicate_tolerance(robot)
    out = np.zeros(src.size, dtype=bool)
    for k in range(src.size):
        mine = pose_idx == pose_idx[src[k]]
        known = np.concatenate([q[mine], q_new[:k][out[:k] & (pose_idx[src[:k]] == pose_idx[src[k]])]])
        out[k] = not np.any(np.all(joint_distance(robot, known, q_new[k]) <= tol, axis=-1))
    return out


def _rows(sol: Solutions, keep: NDArray[np.bool_]) -> Solutions:
    """``sol`` with the solutions ``keep`` only."""
    return dataclasses.replace(
        sol,
        q=sol.q[keep],
        error=sol.error[keep],
        error_geodesic=sol.error_geodesic[keep],
        within_limits=sol.within_limits[keep],
        multiplicity=sol.multiplicity[keep],
    )


def _add_crossing_families(
    robot: Robot,
    chain: Array,
    poses: Array,
    limits: bool,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
) -> None:
    """The continua that cross the families found (``fams`` and the fallback's, per pose), traced from where they
    cross (:mod:`.crossings`) and added to ``fams`` when not on a family found already."""
    tol = ACCEPT_TOL_REL * robot.length_scale
    known: dict[int, tuple[Family, ...]] = {}
    seed_p, seed_q, seed_j = [], [], []
    for i in sorted(set(fams) | set(fallback)):
        known[i] = tuple(fams.get(i, ())) + (fallback[i].families if i in fallback else ())
        q, j = crossing_seeds(robot, known[i])
        if j.size:
            seed_p.append(np.full(j.size, i, dtype=np.intp))
            seed_q.append(q)
            seed_j.append(j)
    if not seed_p:
        return
    p, q, j = np.concatenate(seed_p), np.concatenate(seed_q), np.concatenate(seed_j)
    # onto the solution set; those that fall back onto a family found already are not traced (most crossings of a
    # family with another singular set branch into no other continuum)
    q, err = correct(robot, q, poses[p], j, tol)
    new = err <= tol
    for i in np.unique(p[new]).tolist():
        rows = np.nonzero(new & (p == i))[0]
        new[rows] = off_families(robot, [(q[rows], known[i])])[0]
    if not new.any():
        return
    traced, _, _ = continuum_families(robot, chain, poses, p[new], q[new], j[new], limits, tol)
    for i, found in traced.items():
        fams.setdefault(i, []).extend(f for f, o in zip(found, inner_off(robot, found, known[i]), strict=True) if o)


def _with_families(
    robot: Robot,
    red: Reduction,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
    pose_idx: NDArray[np.intp],
    q: Array,
    err_paper: Array,
    err_geo: Array,
    inside: NDArray[np.bool_],
    mult: NDArray[np.intp],
) -> tuple[dict[int, tuple[Family, ...]], NDArray[np.intp], Array, Array, Array, NDArray[np.bool_], NDArray[np.intp]]:
    """The families of the poses that have some (``fams``, and the fallback reduction's, ``fallback``), and the
    solutions with those on a family dropped and the fallback's added: ``(families, pose_idx, q, err_paper,
    err_geo, inside, mult)``."""
    families: dict[int, tuple[Family, ...]] = {}
    keep = np.ones(pose_idx.size, dtype=bool)
    extra: list[tuple[int, Solutions, NDArray[np.bool_]]] = []
    checks: list[tuple[Array, tuple[Family, ...]]] = []  # (configurations, families) of each pose, checked at once
    targets: list[tuple[int, Solutions | None, NDArray[np.intp]]] = []
    for i in sorted(set(fams) | set(fallback)):
        fam = tuple(fams.get(i, ()))
        other = fallback.get(i)
        if other is not None:
            fam = unique_families(fam + other.families)
        families[i] = fam
        rows = np.nonzero(pose_idx == i)[0]
        if other is not None and (rows.size == 0 or red.closed_form):
            keep[rows] = False
            checks.append((other.q, fam))
            targets.append((i, other, rows))
        else:
            checks.append((q[rows], fam))
            targets.append((i, None, rows))
    for (i, other, rows), off in zip(targets, off_families(robot, checks), strict=True):
        if other is None:
            keep[rows] = off
        else:
            extra.append((i, other, off))
    if extra or not keep.all():
        p_parts, q_parts, e_parts = [pose_idx[keep]], [q[keep]], [err_paper[keep]]
        g_parts, in_parts, m_parts = [err_geo[keep]], [inside[keep]], [mult[keep]]
        for i, other, k in extra:
            p_parts.append(np.full(int(k.sum()), i, dtype=pose_idx.dtype))
            q_parts.append(other.q[k])
            e_parts.append(other.error[k])
            g_parts.append(other.error_geodesic[k])
            in_parts.append(other.within_limits[k])
            m_parts.append(other.multiplicity[k])
        pose_idx, q, err_paper = np.concatenate(p_parts), np.concatenate(q_parts), np.concatenate(e_parts)
        err_geo, inside, mult = np.concatenate(g_parts), np.concatenate(in_parts), np.concatenate(m_parts)
    return families, pose_idx, q, err_paper, err_geo, inside, mult


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
    weight = orientation_weight(robot.length_unit)
    finite = np.isfinite(q).all(axis=-1)
    if not finite.all():
        pose_idx, q, mult = pose_idx[finite], q[finite], mult[finite]
        if err_geo is not None and err_paper is not None:
            err_geo, err_paper = err_geo[finite], err_paper[finite]
    if err_geo is None or err_paper is None:
        err_geo, err_paper = _errors(robot, q, poses[pose_idx], weight)
    below, above, paper_above, accept = _settle_bounds(robot)
    if strategy == "precise":
        near = np.nonzero((err_geo <= below) & ((err_geo > above) | (err_paper > paper_above)))[0]
        if near.size:
            target = poses[pose_idx[near]]
            polished = polish(robot, q[near], target, weight, floor=above)
            eg, ep = _errors(robot, polished, target, weight)
            # at a singular configuration the step can drift along the near-null space: never out of the limits
            # for a configuration that was inside them and already certified
            drift = (err_geo[near] <= accept) & robot.within_limits(q[near]) & ~robot.within_limits(polished)
            take = np.nonzero(~drift)[0]
            q[near[take]], err_geo[near[take]], err_paper[near[take]] = polished[take], eg[take], ep[take]
            # a sweep's solution next to a fold of the solution set: a valley's bottom, a close partner (a closed form
            # gives every branch's root, a pair split by rounding included: ``MEET_REL``)
            if not red.closed_form:
                polished_ok = near[take][eg[take] <= accept]
                pose_idx, q, mult, err_geo, err_paper = _next_to_folds(
                    robot, poses, pose_idx, q, mult, err_geo, err_paper, polished_ok
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
        wrapped = _snap_to_limits(robot, q, err_geo, err_paper, poses, pose_idx, weight)
    if rescue.size:
        wrapped = None
        rescued = _solve_chunk(
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


def _errors(robot: Robot, q: Array, target: Array, weight: float) -> tuple[Array, Array]:
    """Geodesic error and the paper's J ``(K,)`` of configurations ``q (K, n)`` against ``target (K, 4, 4)``:
    compiled as certification computes them (``fastcertify.pose_errors``), else in NumPy."""
    if certify.AVAILABLE:
        return certify.pose_errors(robot, q, target, weight)
    T = search.flange_poses(robot, q) @ robot.T_flange_tool
    return pose_error_geodesic(T, target, weight), pose_error_paper(T, target, weight)


#: Largest ``n_samples`` accepted: a grid that fine costs seconds per pose and finds nothing the default misses.
MAX_SAMPLES = 100_000
#: A generic sweep's batch of at most ``parallel.IN_FLIGHT`` chunks (and at least IN_FLIGHT x SPLIT_MIN poses) is
#: split evenly into IN_FLIGHT chunks solved side by side, each on its share of the threads (``_chunking``).
SPLIT_MIN = 256
#: Largest ``chunk_size`` accepted (any larger value behaves like this one).
MAX_CHUNK = 2**31
#: Pose-samples per chunk (chunk x ``n_samples``): a larger ``n_samples`` runs in smaller chunks, so memory stays
#: that of the defaults (2048 poses x 64 samples). Chunking changes no solution (without Numba, on arms whose
#: poses differ in their number of sample hints, e.g. the generic sweeps, some move by rounding, ~1e-13: the NumPy
#: engine's grid gives a pose a spare sample for each hint another pose of its batch has).
SAMPLE_BUDGET = CHUNK * N_SAMPLES
#: The paper's strategy sweeps theta* in 10 mm (or 1 degree) steps over its whole range: a range needing more
#: coarse samples than this (2 km of rail in mm) is refused, as its memory (~2 kB per pose-sample) and time grow
#: with the range. Chunks are kept to ``PAPER_SAMPLE_BUDGET`` pose-samples (the C-Arm's 201 samples x 2048).
MAX_PAPER_SAMPLES = 200_000
PAPER_SAMPLE_BUDGET = CHUNK * 256


def _check_strategy(strategy: object) -> str:
    return check_choice(strategy, "strategy", STRATEGIES)


def _paper_samples(robot: Robot, red: Reduction, P: Array, limits: bool) -> int:
    """Coarse samples per pose of the paper's strategy (the most over ``P``); refused above MAX_PAPER_SAMPLES."""
    if red.periodic or P.shape[0] == 0:
        return int(np.ceil(360.0 / COARSE_STEP_DEG)) + 1
    lo, hi = _theta_range(robot, red, _chain_poses(robot, P), paper_limits=limits)
    step = COARSE_STEP_MM / mm_per_unit(robot.length_unit)
    m = float(np.max(hi - lo)) / step + 1.0
    if m > MAX_PAPER_SAMPLES:
        name = robot.joint_names[red.free_joint]
        raise UnknownOptionError(
            f"strategy 'paper' would sweep {name} over {float(np.max(hi - lo)):.6g} {robot.length_unit} in "
            f"{COARSE_STEP_MM:g} mm steps ({m:.3g} samples per pose, at most {MAX_PAPER_SAMPLES}); "
            f"use strategy='precise'"
        )
    return int(m)


def solve_many(
    robot: Robot,
    poses: ArrayLike,
    *,
    reduction: str | Reduction | None = None,
    free_joint: int | str | None = None,
    strategy: Strategy = "precise",
    limits: bool = True,
    n_samples: int = N_SAMPLES,
    chunk_size: int = CHUNK,
    locked: Mapping[Any, float] | None = None,
) -> SolutionBatch:
    """All IK solutions of each pose in ``poses (N, 4, 4)`` (world frame, robot's length unit).

    Vectorised over poses, samples and branches, in chunks of at most ``chunk_size`` poses (an integer in
    [1, ``MAX_CHUNK``]; a large ``n_samples`` or the paper's strategy on a long range use smaller chunks, so that
    memory stays bounded). Returns a :class:`~sweepik.results.SolutionBatch`: a sequence of one :class:`Solutions`
    per pose (the solutions :func:`solve` gives each pose, to rounding; built when indexed or iterated), whose columns
    (``offsets``, ``q``, ``error``, ...) hold every solution without a Python object per pose. An empty batch
    (``[]`` or an array ``(0, 4, 4)``) gives an empty one, after the other arguments are checked. Other arguments
    and errors: see :func:`solve`; :func:`iter_solve` yields the same results without holding them all.
    """
    _check_strategy(strategy)
    arr = as_float_array(poses, "poses")
    P = np.zeros((0, 4, 4)) if arr.size == 0 else check_poses(arr, "poses")
    if P.ndim != 3:
        raise ShapeError(f"poses must have shape (N, 4, 4), got {P.shape}")
    held = _held(robot, locked)
    arm = robot if held is None else held.arm
    red, strat, lim, ns, cs = _prepare(arm, P, reduction, strategy, limits, n_samples, chunk_size, free_joint, held)
    cs, share = _chunking(red, len(P), cs)
    blocks = parallel.in_order(
        lambda s: _solve_chunk(arm, red, P[s : s + cs], strat, lim, ns), range(0, len(P), cs), share
    )
    return SolutionBatch(robot, [_expanded(b, held) for b in blocks])


def _chunking(red: Reduction, n: int, chunk_size: int) -> tuple[int, bool]:
    """The chunk size of a batch of ``n`` poses, and whether its chunks share the threads (``parallel.in_order``).
    A batch of fewer chunks than are solved at once leaves a core idle while a chunk runs its Python steps; a
    generic sweep's batch of up to ``IN_FLIGHT`` chunks is split evenly into IN_FLIGHT, each on its share of the
    threads, so that one chunk's Python steps overlap the other's compiled search (2,000 random poses: -4 to -8 %
    on the swept 6R arms). Not for a smaller batch (chunks under ``SPLIT_MIN`` poses lose more to their fixed costs),
    nor for a cheaper search (a closed form, a hints kernel: ~10 us a pose, where the split measured +4 to +7 %), nor
    for a larger batch (its chunks already overlap, and a share of the threads would leave the last one alone on
    one core)."""
    k = parallel.IN_FLIGHT
    if k * SPLIT_MIN <= n <= k * chunk_size and search.searches_margins(red) and parallel.threads() > 1:
        return -(-n // k), True
    return chunk_size, False


def iter_solve(
    robot: Robot,
    poses: ArrayLike,
    *,
    reduction: str | Reduction | None = None,
    free_joint: int | str | None = None,
    strategy: Strategy = "precise",
    limits: bool = True,
    n_samples: int = N_SAMPLES,
    chunk_size: int = CHUNK,
    progress: Progress | None = None,
    locked: Mapping[Any, float] | None = None,
) -> Iterator[Solutions]:
    """The solutions of each pose in ``poses (N, 4, 4)``, yielded one pose after the other as
    :func:`solve_many` computes them, a chunk of poses at a time: only a few chunks' results are alive at once
    (the one being yielded and the next ones being solved, see ``parallel.in_order``), so memory stays bounded
    whatever ``N`` (for streaming millions of poses to a file).

    Arguments are checked when it is called, before the first solution is asked for. ``progress(stage, done,
    total)``, if given, is called with stage ``"solve"`` before the first chunk and after each one.
    """
    _check_strategy(strategy)
    arr = as_float_array(poses, "poses")
    P = np.zeros((0, 4, 4)) if arr.size == 0 else check_poses(arr, "poses")
    if P.ndim != 3:
        raise ShapeError(f"poses must have shape (N, 4, 4), got {P.shape}")
    if progress is not None and not callable(progress):
        raise UnknownOptionError(f"progress must be callable or None, got {type(progress).__name__}")
    held = _held(robot, locked)
    arm = robot if held is None else held.arm
    prepared = _prepare(arm, P, reduction, strategy, limits, n_samples, chunk_size, free_joint, held)
    return _iter_checked(arm, P, *prepared, progress, held)


def _prepare(
    robot: Robot,
    P: Array,
    reduction: str | Reduction | None,
    strategy: str,
    limits: bool,
    n_samples: int,
    chunk_size: int = CHUNK,
    free_joint: int | str | None = None,
    held: HeldJoints | None = None,
) -> tuple[Reduction, str, bool, int, int]:
    """Check the solver's arguments; the reduction and the checked (strategy, limits, n_samples, chunk size).

    ``robot`` is the arm solved (with ``held``, the smaller arm; ``free_joint`` names a joint of the full one)."""
    _check_robot(robot)
    if held is None and robot.n_joints != 6:
        raise LockedJointError(
            f"robot {robot.name!r} has {robot.n_joints} joints; sweepik solves six: "
            + (
                f"hold {robot.n_joints - 6} of them with locked={{joint name: value}} (sweepik.analyze tells which "
                "joint to lock gives a closed form or a sweep)"
                if robot.n_joints > 6
                else "an arm with fewer joints is out of scope"
            )
        )
    if held is not None and free_joint is not None:
        free_joint = _held_free_joint(held, free_joint)
    n_samples = check_int(n_samples, "n_samples", 8, MAX_SAMPLES)
    chunk_size = check_int(chunk_size, "chunk_size", 1, MAX_CHUNK)
    limits = check_bool(limits, "limits")
    strategy = _check_strategy(strategy)
    if reduction is not None and not isinstance(reduction, str | Reduction):
        raise UnknownOptionError(
            f"reduction must be a name, a Reduction instance or None, got {type(reduction).__name__}"
        )
    fj = _free_joint_index(robot, free_joint, reduction)
    try:
        if held is not None and fj is None and is_default(robot, reduction) and robot.default_reduction is None:
            red = automatic_for_held(held.robot, tuple(k for k, _ in held.held), robot)
        else:
            red = get_reduction(robot, reduction, fj)
    except NoReductionError:
        if held is None or fj is None:
            raise
        raise NoReductionError(not_sweepable(robot, fj, held.robot, held.free)) from None
    if red.robot != robot:
        raise UnknownOptionError(
            f"the reduction {red.name!r} was built for robot {red.robot.name!r}, not for {robot.name!r}"
        )
    if strategy == "paper":
        chunk_size = min(chunk_size, max(1, PAPER_SAMPLE_BUDGET // _paper_samples(robot, red, P, limits)))
    else:
        chunk_size = min(chunk_size, max(1, SAMPLE_BUDGET // n_samples))
    return red, strategy, limits, n_samples, chunk_size


def _check_robot(robot: object) -> None:
    if not isinstance(robot, Robot):
        hint = f"; load it with sweepik.load_robot({short_repr(robot, 40)})" if isinstance(robot, str) else ""
        raise UnknownOptionError(
            f"robot must be a sweepik.Robot (see load_robot), got {type(robot).__name__} {short_repr(robot, 40)}{hint}"
        )


def _held(robot: Robot, locked: object) -> HeldJoints | None:
    """``locked`` (joint name or index -> value) as the held arm, None when nothing is locked."""
    _check_robot(robot)
    if locked is None or (isinstance(locked, Mapping) and not locked):
        return None
    return hold_joints(robot, locked)  # type: ignore[arg-type]


def _held_free_joint(held: HeldJoints, free_joint: object) -> int | str:
    """A free joint of the full arm (index or name) as a joint of the held arm."""
    full = held.robot
    if isinstance(free_joint, str):
        if free_joint in full.joint_names and full.joint_names.index(free_joint) not in held.free:
            raise UnknownOptionError(f"free_joint {free_joint!r} is locked; sweep one of the others")
        return free_joint  # names are kept by the held arm; an unknown one is refused there
    k = check_int(free_joint, "free_joint", 0, full.n_joints - 1)
    if k not in held.free:
        raise UnknownOptionError(f"free_joint {full.joint_names[k]!r} is locked; sweep one of the others")
    return held.free.index(k)


def _expanded(block: Block, held: HeldJoints | None) -> Block:
    """``block`` of the held arm as a block of the full arm: configurations full length, families too."""
    if held is None:
        return block
    families = {
        i: tuple(dataclasses.replace(f, free_joint=held.free[f.free_joint], held=held) for f in fams)
        for i, fams in block.families.items()
    }
    return dataclasses.replace(block, robot=held.robot, q=held.expand(block.q), families=families)


def _free_joint_index(robot: Robot, free_joint: object, reduction: object) -> int | None:
    """``free_joint`` (an index from 0, or a joint name) as an index; None if not given."""
    if free_joint is None:
        return None
    if reduction is not None and reduction != "auto":
        raise UnknownOptionError(
            f"free_joint chooses theta* of the automatic decomposition; reduction {short_repr(reduction, 40)} fixes "
            "its own theta* (give reduction='auto' or none)"
        )
    if isinstance(free_joint, str):
        if free_joint not in robot.joint_names:
            raise UnknownOptionError(f"free_joint {free_joint!r} is not a joint of {robot.name!r}: {robot.joint_names}")
        return robot.joint_names.index(free_joint)
    return check_int(free_joint, "free_joint", 0, robot.n_joints - 1)


def _iter_checked(
    robot: Robot,
    P: Array,
    red: Reduction,
    strategy: str,
    limits: bool,
    n_samples: int,
    chunk_size: int,
    progress: Progress | None = None,
    held: HeldJoints | None = None,
) -> Iterator[Solutions]:
    total = P.shape[0]
    if progress is not None:
        progress("solve", 0, total)
    chunk_size, share = _chunking(red, total, chunk_size)
    starts = range(0, total, chunk_size)
    blocks = parallel.in_order(
        lambda s: _solve_chunk(robot, red, P[s : s + chunk_size], strategy, limits, n_samples), starts, share
    )
    for s, block in zip(starts, blocks, strict=True):
        yield from _expanded(block, held)
        if progress is not None:
            progress("solve", min(s + chunk_size, total), total)


def _solve_one(
    robot: Robot,
    P: Array,
    reduction: str | Reduction | None,
    strategy: str,
    limits: bool,
    n_samples: int,
    free_joint: int | str | None = None,
    locked: object = None,
) -> Solutions:
    """The solutions of the one pose ``P (1, 4, 4)`` (arguments checked here): its chunk, solved directly."""
    one_call = True
    default = (
        free_joint is None
        and limits is True
        and type(strategy) is str
        and strategy == "precise"
        and type(n_samples) is int
        and n_samples == N_SAMPLES
        and isinstance(robot, Robot)
    )
    held = _held(robot, locked)
    arm = robot if held is None else held.arm
    if default and is_default(arm, reduction):
        # (the default options, the default reduction named or not: their checks done once per arm)
        red = _default_reduction(arm)
        if red.uses_kernel:  # (its solutions straight from the one compiled call, where it settles the pose)
            out = _settled(arm, red, P, _chain_poses(arm, P), True, N_SAMPLES)
            if out is not None:
                n = out.q.shape[0]
                return Solutions(
                    q=out.q if held is None else held.expand(out.q),
                    error=out.error,
                    error_geodesic=out.error_geodesic,
                    within_limits=out.within_limits,
                    multiplicity=out.multiplicity,
                    families=(),
                    reason=None if n else no_solution_reason(out.reachable),
                    pose=P[0].copy(),
                    robot=robot,
                )
            one_call = False
    else:
        red, strategy, limits, n_samples, _ = _prepare(
            arm, P, reduction, strategy, limits, n_samples, 1, free_joint, held
        )
    block = _solve_chunk(arm, red, P, strategy, limits, n_samples, one_call=one_call)
    return _expanded(block, held).solutions(0, copy=False)


@lru_cache(maxsize=16)
def _default_reduction(robot: Robot) -> Reduction:
    """``_prepare``'s reduction for ``robot`` solved with the default options (a solve would spend ~6 us a call
    checking them again); what ``_prepare`` refuses is not kept, and raises again on the next call."""
    return _prepare(robot, np.zeros((0, 4, 4)), None, "precise", True, N_SAMPLES, 1)[0]


def solve(
    robot: Robot,
    pose: ArrayLike,
    *,
    reduction: str | Reduction | None = None,
    free_joint: int | str | None = None,
    strategy: Strategy = "precise",
    limits: bool = True,
    n_samples: int = N_SAMPLES,
    locked: Mapping[Any, float] | None = None,
) -> Solutions:
    """All IK solutions of one pose ``(4, 4)`` (world frame, robot's length unit).

    Args:
        robot: the arm (e.g. ``load_robot("carm")``).
        pose: target tool pose.
        reduction: name (``"auto"``, ``"carm-d1"``, ``"carm-theta2"``), a Reduction instance, or None: the
            robot's ``default_reduction`` if its file names one, else ``"auto"``, the decomposition derived from
            the arm's geometry (``sweepik.analyze`` shows it).
        free_joint: with the automatic decomposition, the joint to sweep as theta* (index from 0, or name);
            NoReductionError if no decomposition sweeps it. Not together with ``reduction``.
        strategy: ``"precise"`` (every root to full precision, double roots and close roots included) or
            ``"paper"`` (the paper's 10 mm sweep refined to 0.001 mm, J < 1e-5 mm).
        limits: drop solutions outside the joint limits (True) or keep and flag them (False); a bool (or NumPy
            bool), not a string or a number.
        n_samples: uniform theta* samples before refinement, an integer in [8, ``MAX_SAMPLES``] (100,000;
            not a bool or a float). The paper's strategy ignores it, and refuses a theta* range needing more
            than ``MAX_PAPER_SAMPLES`` (200,000) of its 10 mm samples.
        locked: joints held at given values, ``{name or index: value}`` (radians / length unit, inside the
            joint's limits): an arm with more than six joints is solved with enough of them held that six remain
            (e.g. a 7-DOF arm with one locked). The solutions' configurations are full length, the held values
            in place; ``free_joint`` and families name joints of the full arm. ``sweepik.analyze`` tells which
            joint to lock gives a closed form or a sweep. LockedJointError for an unknown joint, a value outside
            its limits, or other than six joints left.

    Raises:
        SweepikError subclasses: a pose that is not a rigid transform or not real numbers (ShapeError,
        InvalidPoseError, NonFiniteError), ``robot`` not a :class:`~sweepik.model.robot.Robot`, an unknown or ill-typed
        option (UnknownOptionError), a reduction that does not fit, an arm outside the catalogue of
        decompositions (NoReductionError, naming the structure found).

    >>> import numpy as np
    >>> from sweepik import load_robot, solve
    >>> arm = load_robot("carm")
    >>> q = np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1])
    >>> sols = solve(arm, arm.fk(q))
    >>> bool(np.allclose(sols.nearest(q), q, atol=1e-9))
    True
    """
    P = check_poses(pose, "pose")
    if P.shape != (4, 4):
        raise ShapeError(f"pose must have shape (4, 4), got {P.shape}; use solve_many for batches")
    return _solve_one(robot, P[None], reduction, strategy, limits, n_samples, free_joint, locked)
