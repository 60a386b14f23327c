"""``solve`` and ``solve_many``: all IK solutions of poses, certified by forward kinematics.

Pipeline (see DESIGN.md): chain poses -> strategy (precise sweep or the paper's) -> candidate
configurations -> FK check against the target -> joint limits -> duplicates removed -> ``Solutions``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping
from functools import lru_cache
from typing import Any, Literal, NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik._jit import writable
from sweepik.engine import parallel, search
from sweepik.engine.chunk import chain_poses, settled, solve_chunk, theta_range
from sweepik.engine.held_joined import HeldJoined
from sweepik.engine.held_pose import SPECIAL, HeldPose
from sweepik.engine.joined_pose import JoinedPose
from sweepik.engine.one_pose import DUE
from sweepik.engine.paper_sweep import COARSE_STEP_DEG, COARSE_STEP_MM
from sweepik.engine.settings import N_SAMPLES
from sweepik.engine.single_pose import NOT_RIGID, SinglePose
from sweepik.engine.turned_lock import TurnedLock, turned_at, turned_lock
from sweepik.engine.windings import wound_block, wound_solutions
from sweepik.errors import LockedJointError, NoReductionError, ShapeError, SweepikError, UnknownOptionError
from sweepik.model.origin_axis import HeldJoints, held_values, hold_joints, lock_runs, per_pose
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import as_float_array, check_bool, check_choice, check_int, check_poses, short_repr
from sweepik.reductions import (
    Reduction,
    automatic_for_held,
    first_held_reduction,
    get_reduction,
    held_pair,
    is_default,
)
from sweepik.reductions.decompose import not_sweepable
from sweepik.results import Block, SolutionBatch, Solutions, no_solution_reason

__all__ = ["solve", "solve_many", "iter_solve", "prepare", "Prepared", "held_joints", "STRATEGIES"]

#: A progress callback: ``progress(stage, done, total)``.
Progress = Callable[[str, int, int], None]

Array = NDArray[np.float64]
Strategy = Literal["precise", "paper"]
STRATEGIES = ("precise", "paper")

#: Poses per chunk of ``solve_many``: bounds memory at (chunk x samples x branches) residuals.
CHUNK = 2048


#: Largest ``n_samples`` accepted: a grid that fine costs seconds per pose and finds nothing the default misses.
MAX_SAMPLES = 100_000
#: A generic sweep's batch of at most ``parallel.IN_FLIGHT`` chunks (and at least IN_FLIGHT x SPLIT_MIN poses) is
#: split evenly into IN_FLIGHT chunks solved side by side, each on its share of the threads (``_chunking``).
SPLIT_MIN = 256
#: Largest ``chunk_size`` accepted (any larger value behaves like this one).
MAX_CHUNK = 2**31
#: Pose-samples per chunk (chunk x ``n_samples``): a larger ``n_samples`` runs in smaller chunks, so memory stays
#: that of the defaults (2048 poses x 64 samples). Chunking changes no solution (each pose's samples are its own).
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
    lo, hi = theta_range(robot, red, chain_poses(robot, P), paper_limits=limits)
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
    locked: Mapping[Any, float | ArrayLike] | None = None,
    windings: bool = False,
) -> SolutionBatch:
    """All IK solutions of each pose in ``poses (N, 4, 4)`` (world frame, robot's length unit).

    Vectorised over poses, samples and branches, in chunks of at most ``chunk_size`` poses (an integer in
    [1, ``MAX_CHUNK``]; a large ``n_samples`` or the paper's strategy on a long range use smaller chunks, so that
    memory stays bounded). Returns a :class:`~sweepik.results.SolutionBatch`: a sequence of one :class:`Solutions`
    per pose (the solutions :func:`solve` gives each pose, to rounding; built when indexed or iterated), whose columns
    (``offsets``, ``q``, ``error``, ...) hold every solution without a Python object per pose. An empty batch
    (``[]`` or an array ``(0, 4, 4)``) gives an empty one, after the other arguments are checked. Other arguments
    and errors: see :func:`solve`; :func:`iter_solve` yields the same results without holding them all.

    ``locked`` may give a joint one value per pose (a sequence of ``N``; docs/robots.md): each pose is solved with
    its own value held; with one pose ``(4, 4)`` and ``K`` values, that pose is solved for each (``K`` results: a
    self-motion sampled over a grid of lock values).
    """
    _check_strategy(strategy)
    check_bool(windings, "windings")
    P, runs = _pose_runs(robot, poses, locked)
    options: dict[str, Any] = dict(reduction=reduction, strategy=strategy, limits=limits, n_samples=n_samples)
    options.update(chunk_size=chunk_size, free_joint=free_joint)
    fast = _held_values(robot, P, runs, options, windings)
    blocks: list[Block] = []
    for s, e, lock in _segments(runs, fast is not None):
        if lock is _BY_VALUE:  # (short runs: the lock value an argument of one compiled call per pose)
            assert fast is not None
            blocks.extend(_held_blocks(robot, P, fast, options, s, e))
        else:
            blocks.extend(_held_run(robot, P[s:e], lock, options, windings))
    return SolutionBatch(robot, blocks)


#: Runs of at least this many consecutive poses with the same lock value are solved batched by their held arm; shorter
#: ones (a value per pose) pose by pose with the value an argument (``engine.held_pose``, ~15 us a pose either way
#: where the held arm is cached, ~2 ms more per run where it is built for a new value).
HELD_RUN_MIN = 64
#: ``_segments``' mark of the poses ``HeldPose`` takes.
_BY_VALUE = object()


def _segments(runs: list[tuple[int, int, object]], fast: bool) -> list[tuple[int, int, object]]:
    """``runs`` with consecutive ones shorter than ``HELD_RUN_MIN`` joined as ``(start, stop, _BY_VALUE)`` (with
    ``fast``: a ``HeldPose`` takes them)."""
    out: list[tuple[int, int, object]] = []
    for s, e, lock in runs:
        if not (fast and e - s < HELD_RUN_MIN):
            out.append((s, e, lock))
        elif out and out[-1][2] is _BY_VALUE:
            out[-1] = (out[-1][0], e, _BY_VALUE)
        else:
            out.append((s, e, _BY_VALUE))
    return out


def _held_blocks(
    robot: Robot, P: Array, fast: tuple[HeldPose | HeldJoined, Array], options: dict[str, Any], s: int, e: int
) -> list[Block]:
    """The blocks of poses ``s .. e - 1`` of ``P`` from ``fast``'s compiled call, each pose at its own lock value; a
    pose it does not settle by its held arm (``_held_run``)."""
    held, values = fast

    def general(i: int) -> Iterator[Block]:
        return _held_run(robot, P[s + i : s + i + 1], {held.joint: float(values[s + i])}, options)

    return held.blocks(writable(P[s:e]), values[s:e], options["limits"], general)


def _held_run(
    robot: Robot,
    P: Array,
    lock: object,
    options: dict[str, Any],
    windings: bool = False,
    first: Prepared | None = None,
    turned: bool = True,
) -> Iterator[Block]:
    """The blocks of poses ``P`` solved with ``lock``'s joints held (``options``: ``prepare``'s; ``first``: already
    prepared, at the reference value where the lock is ``turned``: ``_turned``)."""
    turn = _turned(robot, lock, options, windings) if turned else None
    if turn is not None:
        return _turned_run(robot, P, lock, turn, options, first)
    held = held_joints(robot, lock)
    arm = robot if held is None else held.arm
    prepared = first if first is not None else prepare(arm, P, **options, held=held)
    return (_finished(b, held, windings) for b in _solved_chunks(arm, P, prepared))


def _turned(robot: Robot, lock: object, options: Mapping[str, Any], windings: bool = False) -> TurnedLock | None:
    """``lock`` solved at its joint's reference value and turned (``engine.turned_lock``: the first or last joint of
    a seven-joint arm held) with the default options, else None."""
    reduction = options["reduction"]
    if not (
        (reduction is None or reduction == "auto")
        and windings is False
        and _defaults(robot, options["free_joint"], options["strategy"], options["limits"], options["n_samples"])
    ):
        return None
    return turned_lock(robot, lock)


def _turned_run(
    robot: Robot, P: Array, lock: object, turn: TurnedLock, options: dict[str, Any], first: Prepared | None
) -> Iterator[Block]:
    """``_held_run`` of a turned lock: the blocks of ``turn.poses(P)`` at the reference value turned back, a block
    ``turn.block`` cannot give back solved by the held arm at the value itself."""
    at = 0
    for b in _held_run(robot, turn.poses(P), turn.locked, options, False, first):
        part = P[at : at + b.n]
        back = turn.block(robot, b, part)
        if back is None:
            yield from _held_run(robot, part, lock, options, turned=False)
        else:
            yield back
        at += b.n


def _held_values(
    robot: Robot, P: Array, runs: list[tuple[int, int, object]], options: dict[str, Any], windings: bool
) -> tuple[HeldPose | HeldJoined, Array] | None:
    """With the default options and one joint of a seven-joint arm held, the ``HeldPose`` (or ``HeldJoined``) that
    takes its value as an argument and each pose's value; else None."""
    reduction = options["reduction"]
    if not (
        runs
        and isinstance(runs[0][2], Mapping)
        and len(runs[0][2]) == 1
        and (reduction is None or type(reduction) is str)
        and windings is False
        and _defaults(robot, options["free_joint"], options["strategy"], options["limits"], options["n_samples"])
    ):
        return None
    fast = _single_pose(robot, runs[0][2], reduction)
    if not isinstance(fast, HeldAt):
        return None
    values = np.empty(len(P))
    for s, e, lock in runs:
        values[s:e] = held_values(robot, lock)[0][1]  # type: ignore[arg-type]
    return fast.held, values


def _solved_chunks(arm: Robot, P: Array, prepared: Prepared) -> Iterator[Block]:
    """The blocks of ``P`` solved chunk by chunk (``_chunking``), in order."""
    red, strategy, limits, n_samples, chunk_size = prepared
    cs, share = _chunking(red, len(P), chunk_size)
    return parallel.in_order(
        lambda s: solve_chunk(arm, red, P[s : s + cs], strategy, limits, n_samples), range(0, len(P), cs), share
    )


def _pose_runs(robot: Robot, poses: ArrayLike, locked: object) -> tuple[Array, list[tuple[int, int, object]]]:
    """The batch's poses ``(N, 4, 4)`` and its runs of consecutive poses solved with the same joints held
    ``[(start, stop, locked), ...]``: one run of every pose, unless ``locked`` gives a value per pose (``lock_runs``;
    then a single pose ``(4, 4)`` or ``(1, 4, 4)`` is repeated for each value: a self-motion sampled over a grid of
    lock values)."""
    if not per_pose(locked):
        P = _pose_batch(poses)
        return P, [(0, len(P), locked)]
    _check_robot(robot)
    assert isinstance(locked, Mapping)
    arr = as_float_array(poses, "poses")
    if arr.shape in ((4, 4), (1, 4, 4)):  # (one pose for every lock value)
        n = max(len(v) for v in locked.values() if np.ndim(v) > 0)
        P = np.repeat(check_poses(arr.reshape(4, 4), "poses")[None], n, axis=0)
    else:
        P = _pose_batch(poses)
    return P, list(lock_runs(robot, locked, len(P)))


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
    locked: Mapping[Any, float | ArrayLike] | None = None,
    windings: bool = False,
) -> Iterator[Solutions]:
    """The solutions of each pose in ``poses (N, 4, 4)``, yielded one pose after the other as
    :func:`solve_many` computes them, a chunk of poses at a time: only a few chunks' results are alive at once
    (the one being yielded and the next ones being solved, see ``parallel.in_order``), so memory stays bounded
    whatever ``N`` (for streaming millions of poses to a file).

    Arguments are checked when it is called, before the first solution is asked for (``locked`` with a value per
    pose: every value; a decomposition of each value's held arm when its poses' turn comes). ``progress(stage, done,
    total)``, if given, is called with stage ``"solve"`` before the first chunk and after each one.
    """
    _check_strategy(strategy)
    check_bool(windings, "windings")
    if progress is not None and not callable(progress):
        raise UnknownOptionError(f"progress must be callable or None, got {type(progress).__name__}")
    P, runs = _pose_runs(robot, poses, locked)
    options: dict[str, Any] = dict(reduction=reduction, strategy=strategy, limits=limits, n_samples=n_samples)
    options.update(chunk_size=chunk_size, free_joint=free_joint)
    fast = _held_values(robot, P, runs, options, windings)
    first = None
    if runs and not (fast is not None and runs[0][1] - runs[0][0] < HELD_RUN_MIN):
        turn = _turned(robot, runs[0][2], options, windings)  # (then solved at the reference value)
        held = held_joints(robot, runs[0][2] if turn is None else turn.locked)
        first = prepare(robot if held is None else held.arm, P[: runs[0][1]], **options, held=held)
    return _iter_held(robot, P, runs, fast, first, options, progress, windings)


class Prepared(NamedTuple):
    """A solve's checked options (:func:`prepare`): the reduction and the strategy, limits, samples and chunk size."""

    reduction: Reduction
    strategy: str
    limits: bool
    n_samples: int
    chunk_size: int


def prepare(
    robot: Robot,
    P: Array,
    reduction: str | Reduction | None,
    strategy: str,
    limits: bool,
    n_samples: int,
    chunk_size: int = CHUNK,
    free_joint: int | str | None = None,
    held: HeldJoints | None = None,
) -> Prepared:
    """The solver's arguments checked (a :class:`~sweepik.errors.SweepikError` naming the one that is not right), and
    the reduction that solves ``robot`` with them: what ``solve``, ``solve_many``, ``iter_solve``, the solution store
    and ``solve_dask`` do before solving. ``P (N, 4, 4)``: the poses (the paper's strategy sizes its chunks by their
    sweep range).

    ``robot`` is the arm solved (with ``held``, the smaller arm of :func:`held_joints`; ``free_joint`` names a joint of
    the full one)."""
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
            values = tuple(v for _, v in held.held)
            red = automatic_for_held(held.robot, tuple(k for k, _ in held.held), robot, values)
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
    return Prepared(red, strategy, limits, n_samples, chunk_size)


def _check_robot(robot: object) -> None:
    if not isinstance(robot, Robot):
        hint = f"; load it with sweepik.load_robot({short_repr(robot, 40)})" if isinstance(robot, str) else ""
        raise UnknownOptionError(
            f"robot must be a sweepik.Robot (see load_robot), got {type(robot).__name__} {short_repr(robot, 40)}{hint}"
        )


def held_joints(robot: Robot, locked: object) -> HeldJoints | None:
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


def _finished(block: Block, held: HeldJoints | None, windings: bool) -> Block:
    """``block`` of the solved arm as the caller's: full length (``Block.expanded``), with the 2 pi windings of every
    solution when asked (``engine.windings``; held joints keep their values)."""
    out = block.expanded(held)
    return wound_block(out, _free_mask(out.robot, held)) if windings else out


def _free_mask(robot: Robot, held: HeldJoints | None) -> NDArray[np.bool_] | None:
    """Joints that may wind: all but the held ones."""
    if held is None:
        return None
    mask = np.zeros(robot.n_joints, dtype=bool)
    mask[list(held.free)] = True
    return mask


def _pose_batch(poses: ArrayLike) -> Array:
    """``poses`` checked as ``(N, 4, 4)``; an empty batch is ``[]`` or ``(0, 4, 4)`` (a ShapeError for another
    empty shape, such as ``(0, 3)``: positions are not poses)."""
    arr = as_float_array(poses, "poses")
    if arr.size == 0 and arr.shape not in ((0,), (0, 4, 4)):
        raise ShapeError(f"poses must have shape (N, 4, 4), got an empty array of shape {arr.shape}")
    P = np.zeros((0, 4, 4)) if arr.size == 0 else check_poses(arr, "poses")
    if P.ndim != 3:
        raise ShapeError(f"poses must have shape (N, 4, 4), got {P.shape}")
    return P


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


def _iter_held(
    robot: Robot,
    P: Array,
    runs: list[tuple[int, int, object]],
    fast: tuple[HeldPose | HeldJoined, Array] | None,
    first: Prepared | None,
    options: dict[str, Any],
    progress: Progress | None,
    windings: bool,
) -> Iterator[Solutions]:
    """``iter_solve``'s generator: ``_segments`` of ``runs``, long runs chunk by chunk by their held arms (the first
    run's options ``first`` prepared by the caller: the arguments' checks; the others' when their turn comes), short
    ones ``chunk_size`` poses at a time through ``fast``."""
    total, done, step = P.shape[0], 0, options["chunk_size"]
    if progress is not None:
        progress("solve", 0, total)
    for s, e, lock in _segments(runs, fast is not None):
        if lock is _BY_VALUE:
            assert fast is not None
            parts = (_held_blocks(robot, P, fast, options, a, min(a + step, e)) for a in range(s, e, step))
            blocks: Iterator[Block] = (b for part in parts for b in part)
        else:
            blocks = _held_run(robot, P[s:e], lock, options, windings, first if s == 0 else None)
        for block in blocks:
            yield from block
            done += block.n
            if progress is not None:
                progress("solve", done, total)


def _solve_one(
    robot: Robot,
    P: Array,
    reduction: str | Reduction | None,
    strategy: str,
    limits: bool,
    n_samples: int,
    free_joint: int | str | None = None,
    locked: object = None,
    one_call: bool = True,
    turned: bool = True,
) -> Solutions:
    """The solutions of the one pose ``P (1, 4, 4)`` (arguments checked here): its chunk, solved directly (with
    ``one_call``: by the one compiled call where it settles the pose); a turned lock (``_turned``, unless not
    ``turned``) at its reference value, turned back."""
    turn = None
    if turned and locked is not None:
        options = dict(reduction=reduction, strategy=strategy, limits=limits, n_samples=n_samples)
        turn = _turned(robot, locked, {**options, "free_joint": free_joint})
    if turn is not None:
        P0, lock0 = turn.poses(P), turn.locked
        ref = _solve_one(robot, P0, reduction, strategy, limits, n_samples, None, lock0, one_call, False)
        sol = turn.solutions(robot, ref, P[0])
        if sol is not None:
            return sol
    default = _defaults(robot, free_joint, strategy, limits, n_samples)
    held = held_joints(robot, locked)
    arm = robot if held is None else held.arm
    if default and is_default(arm, reduction):
        # (the default options, the default reduction named or not: their checks done once per arm)
        red = _default_reduction(arm, held)
        if red.uses_kernel and one_call:  # (its solutions straight from the one compiled call, where it settles)
            out = settled(arm, red, P, chain_poses(arm, P), limits, N_SAMPLES)
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
        red, strategy, limits, n_samples, _ = prepare(
            arm, P, reduction, strategy, limits, n_samples, 1, free_joint, held
        )
    block = solve_chunk(arm, red, P, strategy, limits, n_samples, one_call=one_call)
    return block.expanded(held).solutions(0, copy=False)


def _defaults(robot: object, free_joint: object, strategy: object, limits: object, n_samples: object) -> bool:
    """The options are the defaults (the automatic choice of theta*, precise, limits a bool, the default samples) and
    ``robot`` a Robot: checked here in ~0.3 us, where ``prepare`` takes ~6."""
    return (
        free_joint is None
        and (limits is True or limits is False)
        and type(strategy) is str
        and strategy == "precise"
        and type(n_samples) is int
        and n_samples == N_SAMPLES
        and isinstance(robot, Robot)
    )


@lru_cache(maxsize=16)
def _default_reduction(robot: Robot, held: HeldJoints | None = None) -> Reduction:
    """``prepare``'s reduction for ``robot`` solved with the default options (a solve would spend ~6 us a call
    checking them again; with ``held``, ``robot`` is the held arm, chosen as ``solve_many`` chooses it:
    ``reductions.automatic_for_held``); what ``prepare`` refuses is not kept, and raises again on the next call."""
    return prepare(robot, np.zeros((0, 4, 4)), None, "precise", True, N_SAMPLES, 1, None, held)[0]


def _single_pose(
    robot: Robot, locked: object, reduction: str | None = None, reused: bool = False
) -> SinglePose | JoinedPose | HeldAt | TurnedAt | None:
    """``robot``'s default reduction (``reduction``: None, or a name of it) ready for single poses with the default
    options and ``locked`` joints (None: it does not qualify, ``SinglePose.of``, or the arm, ``locked`` or
    ``reduction`` is refused: the general path then raises, after the pose's checks). One joint of a seven-joint arm
    held: its lock value an argument of the compiled call where the plan allows (``HeldPose``; the first or last
    joint: ``TurnedAt``; both plans' calls of a held arm with a near-structure: ``HeldJoined``). An arm solved with
    a companion: both plans' one calls (``JoinedPose``; a held arm's at a value asked for before, ``_asked_before``,
    or ``reused``: a value every pose asks for, a turned lock's reference)."""
    held = None
    if locked is not None:
        try:
            if isinstance(robot, Robot) and robot.n_joints == 7 and isinstance(locked, Mapping) and len(locked) == 1:
                ((k, v),) = held_values(robot, locked)
                fast = _held_pose(robot, k)
                if fast is not None and (reduction is None or is_default(fast.arm, reduction)):
                    return HeldAt(fast, v)
                turn = turned_at(robot, k, v) if reduction in (None, "auto") else None
                if turn is not None:  # (the held arm at the reference value, once for every value)
                    ref = _reference_pose(robot, turn.joint, turn.reference, reduction)
                    return None if ref is None else TurnedAt(ref, turn, robot)
                joined = _held_joined(robot, k)
                if joined is not None and (reduction is None or is_default(joined.arm, reduction)):
                    return HeldAt(joined, v)
            held = held_joints(robot, locked)
        except (SweepikError, TypeError):  # (an unhashable value: the general path says what is wrong)
            return None
    if reduction is not None and not is_default(robot if held is None else held.arm, reduction):
        return None
    single = _single_pose_of(robot, held)
    if single is None and (held is None or reused or _asked_before(held)):
        return _joined_pose_of(robot, held)
    return single


@lru_cache(maxsize=16)
def _reference_pose(
    robot: Robot, k: int, value: float, reduction: str | None
) -> SinglePose | JoinedPose | HeldAt | None:
    """``_single_pose`` of ``robot`` with joint ``k`` held at the reference ``value`` (kept: every value asks)."""
    fast = _single_pose(robot, {k: value}, reduction, reused=True)
    return None if isinstance(fast, TurnedAt) else fast


class TurnedAt(NamedTuple):
    """A turned lock (``engine.turned_lock``) solved as a ``SinglePose`` is: the pose turned, solved by the held arm
    at the reference value, its solutions turned back."""

    fast: SinglePose | JoinedPose | HeldAt
    turn: TurnedLock
    robot: Robot

    def solve(self, pose: Array, limits: bool) -> tuple[int, Solutions | None]:
        try:
            status, sol = self.fast.solve(self.turn.poses(pose), limits)
        except SweepikError:
            check_poses(pose)  # (the caller's pose named in the error)
            raise
        if sol is None:
            return status, None
        back = self.turn.solutions(self.robot, sol, pose)
        return (status, back) if back is not None else (DUE, None)


class HeldAt(NamedTuple):
    """A ``HeldPose`` (or ``HeldJoined``) at one lock value, solved as a ``SinglePose`` is."""

    held: HeldPose | HeldJoined
    value: float

    def solve(self, pose: Array, limits: bool) -> tuple[int, Solutions | None]:
        return self.held.solve(pose, self.value, limits)


@lru_cache(maxsize=16)
def _held_pose(robot: Robot, k: int) -> HeldPose | None:
    """``robot`` with joint ``k`` held, its lock value an argument (None: its plan changes with the value, or is not
    a closed form or sweep of ``SinglePose``: ``HeldPose.of``)."""
    return HeldPose.of(robot, k, first_held_reduction)


@lru_cache(maxsize=16)
def _held_joined(robot: Robot, k: int) -> HeldJoined | None:
    """``robot`` with joint ``k`` held, both plans' calls taking the value (None: no companion, or its plans change
    with the value: ``HeldJoined.of``). Built at the first value asked for (~0.2-0.4 s on the Kinova Gen3: every plan
    checked at one value, as the first value's own choice would, and the pair at four more), so that every value
    outside its windows is solved by the same pair, whatever was solved before."""
    return HeldJoined.of(robot, k, held_pair)


@lru_cache(maxsize=16)
def _single_pose_of(robot: Robot, held: HeldJoints | None) -> SinglePose | None:
    red = _solved_by(robot, held)
    return None if red is None else SinglePose.of(robot if held is None else held.arm, red, held)


@lru_cache(maxsize=16)
def _joined_pose_of(robot: Robot, held: HeldJoints | None) -> JoinedPose | None:
    red = _solved_by(robot, held)
    return None if red is None else JoinedPose.of(robot if held is None else held.arm, red, held)


def _solved_by(robot: Robot, held: HeldJoints | None) -> Reduction | None:
    """The default reduction of ``robot`` (the held arm with ``held``), None where it is refused."""
    try:
        return _default_reduction(robot if held is None else held.arm, held)
    except SweepikError:
        return None


#: The held arms ``_single_pose`` was asked for (bounded): an arm solved with a companion has its two plans' one
#: calls built (``JoinedPose.of``: 3-5 ms on the Kinova Gen3, its probes included) at a value asked for again, not
#: at each new lock value, where the general way answers sooner.
_HELD_ASKED: dict[HeldJoints, None] = {}


def _asked_before(held: HeldJoints) -> bool:
    """Whether ``held`` was asked for before (and note that it is now)."""
    if held in _HELD_ASKED:
        return True
    if len(_HELD_ASKED) > 256:
        _HELD_ASKED.clear()
    _HELD_ASKED[held] = None
    return False


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
    windings: bool = False,
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
        windings: also list every 2 pi winding of each solution inside the joint limits (an arm whose joints turn
            through more than a turn, such as a UR's +-360 degrees): one row each, after the base solutions,
            ``Solutions.winding_of`` naming the base row it winds. Held joints are not wound.

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
    one_call = True
    if (  # (the default options on an array: one compiled call answers most poses, ``single_pose``)
        type(pose) is np.ndarray
        and (reduction is None or type(reduction) is str)
        and windings is False
        and _defaults(robot, free_joint, strategy, limits, n_samples)
        and pose.dtype == np.float64
        and pose.shape == (4, 4)
    ):
        fast = _single_pose(robot, locked, reduction)
        flags = pose.flags
        if fast is not None and flags.c_contiguous and flags.writeable:
            status, sol = fast.solve(pose, limits)
            if sol is not None:
                return sol
            one_call = status in (NOT_RIGID, SPECIAL)  # (else the one call was made: the general path answers)
    P = check_poses(pose, "pose")
    if P.shape != (4, 4):
        raise ShapeError(f"pose must have shape (4, 4), got {P.shape}; use solve_many for batches")
    wind = check_bool(windings, "windings")
    sol = _solve_one(robot, P[None], reduction, strategy, limits, n_samples, free_joint, locked, one_call)
    return wound_solutions(sol, _free_mask(robot, held_joints(robot, locked))) if wind else sol
