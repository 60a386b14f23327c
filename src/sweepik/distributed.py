"""``solve_dask``: ``solve_many`` on a Dask cluster, chunk by chunk, optionally into an on-disk store.

The poses are cut into chunks of ``chunk_size`` poses (``chunk k`` = poses ``[k * chunk_size, (k + 1) *
chunk_size)``); each chunk is one Dask task running the solver's own chunk loop (:func:`_solve_task`: the same
steps as ``solve_many``, in sub-chunks of the solver's ``CHUNK`` poses), so the results are ``solve_many``'s, in
the same order. The robot travels by value (pickled with each task, ~1.5 kB); each worker process builds its
reductions and loads its compiled kernels once (they are cached per robot content).

The client collects the chunks as they finish and (with ``out``) writes each one to the store
(:mod:`sweepik.io.store`): one writer, so the store needs no locking and may live where only the client can write;
the workers need no shared file system. At most ``IN_FLIGHT_PER_THREAD`` chunks per worker thread are submitted at
once, so the client, the scheduler and the workers hold a bounded number of chunks whatever the number of poses.

Nothing is lost: Dask reruns the tasks of a worker that dies (a local cluster's nanny restarts the process; the
scheduler gives up on a task only after it has killed ``distributed.scheduler.allowed-failures`` workers, 3 by
default); the store is written chunk by chunk and marked complete last, and ``resume=True`` skips the chunks an
interrupted run stored (after checking that they hold the same poses, robot and options).

Dask is an optional dependency (``pip install 'sweepik[dask]'``), imported when ``solve_dask`` runs.
"""

from __future__ import annotations

import contextlib
import logging
import math
import os
import time
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.engine.settings import N_SAMPLES
from sweepik.errors import ShapeError, SweepikError, UnknownOptionError
from sweepik.io.store import (
    StoreError,
    StoreWriter,
    chunk_stats,
    load_solutions,
    merge_blocks,
    poses_digest,
    store_info,
)
from sweepik.model.robot import Robot
from sweepik.model.validate import as_float_array, check_int, check_poses, short_repr
from sweepik.reductions import Reduction
from sweepik.results import Block, SolutionBatch

__all__ = ["solve_dask", "close_local_cluster"]

#: A progress callback: ``progress(stage, done, total)`` (``stage`` is ``"solve"``, counts are poses).
Progress = Callable[[str, int, int], None]
Array = NDArray[np.float64]

#: Chunks submitted per worker thread at a time: one running, one queued (the worker never waits for the client).
IN_FLIGHT_PER_THREAD = 2
#: Automatic chunk size: about this many chunks per worker thread (tasks even out at the end of the run) ...
CHUNKS_PER_THREAD = 8
#: ... at least this many poses (smaller chunks cost more in scheduling than they solve) ...
MIN_AUTO_CHUNK = 64
#: ... at most this many (16,384 C-Arm poses: ~3 s on one core, ~10 MB of results), and above the solver's
#: CHUNK a multiple of it, so that the solver's sub-chunks fall where ``solve_many``'s do.
MAX_AUTO_CHUNK = 8 * 2048
#: Seconds to wait for a scheduler given by address.
CONNECT_TIMEOUT_S = 30


def _dask() -> Any:
    try:
        import distributed
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SweepikError("solve_dask needs Dask: pip install 'sweepik[dask]'") from exc
    return distributed


# --------------------------------------------------------------------------------------------------
# The task run by a worker
# --------------------------------------------------------------------------------------------------


def _solve_task(robot: Robot, poses: ArrayLike, options: Mapping[str, Any], start: int) -> Block:
    """The solutions of one chunk of poses ``(n, 4, 4)`` (poses ``start:start + n`` of the run), as one Block:
    ``solve_many`` on the chunk (a bad pose is named by its place in the run)."""
    import numba

    from sweepik.solving import solve_many

    numba.set_num_threads(1)  # (Dask runs a task per worker thread: the compiled kernels must not fan out too)
    arr = as_float_array(poses, "poses")
    P = check_poses(arr, f"poses[{start}:{start + arr.shape[0]}]" if arr.ndim == 3 else "poses")
    if P.ndim != 3:
        raise ShapeError(f"poses must have shape (N, 4, 4), got {P.shape}")
    o = options
    batch = solve_many(
        robot,
        P,
        reduction=o["reduction"],
        free_joint=o["free_joint"],
        strategy=o["strategy"],
        limits=o["limits"],
        n_samples=o["n_samples"],
        locked=o["locked"],
    )
    return merge_blocks(batch.blocks)


def _checked_options(
    robot: Robot,
    reduction: str | Reduction | None,
    free_joint: int | str | None,
    strategy: str,
    limits: bool,
    n_samples: int,
    locked: Mapping[Any, float] | None,
    stored: bool,
) -> dict[str, Any]:
    """The solver options, checked as ``solve_many`` checks them (before any cluster starts), normalised to plain
    Python values (the store keeps them as JSON)."""
    from sweepik.solving import held_joints, prepare

    held = held_joints(robot, locked)
    arm = robot if held is None else held.arm
    _, strategy, limits, n_samples, _ = prepare(
        arm, np.zeros((0, 4, 4)), reduction, strategy, limits, n_samples, 1, free_joint, held
    )
    if stored and isinstance(reduction, Reduction):
        raise UnknownOptionError(
            f"with out=, reduction must be a name or None, not a {type(reduction).__name__} instance: a store "
            "rebuilds its families' reduction by name"
        )
    if isinstance(free_joint, int | np.integer) and not isinstance(free_joint, bool):
        free_joint = int(free_joint)
    return {
        "reduction": reduction,
        "free_joint": free_joint,
        "strategy": strategy,
        "limits": limits,
        "n_samples": n_samples,
        "locked": None
        if not locked
        else {(int(k) if isinstance(k, int | np.integer) else k): float(v) for k, v in locked.items()},
    }


# --------------------------------------------------------------------------------------------------
# Pose sources: in-memory or memory-mapped arrays, .npy paths, Dask arrays
# --------------------------------------------------------------------------------------------------


@dataclass
class _Source:
    """The poses of a run: ``array`` (NumPy, possibly a memmap; sliced by the client) or ``dask`` (a Dask array,
    computed by the workers)."""

    n: int
    array: Any = None
    dask: Any = None

    def chunk(self, s: int, e: int) -> Array:
        return np.ascontiguousarray(self.array[s:e])


def _is_dask_array(x: object) -> bool:
    return type(x).__module__.startswith("dask.array") and hasattr(x, "to_delayed")


def _source(poses: Any) -> _Source:
    if _is_dask_array(poses):
        shape = tuple(poses.shape)
        if len(shape) != 3 or shape[1:] != (4, 4) or any(isinstance(s, float) and math.isnan(s) for s in shape):
            raise ShapeError(f"poses must have shape (N, 4, 4), got {shape}")
        return _Source(int(shape[0]), dask=poses)
    if isinstance(poses, str | os.PathLike):
        poses = _open_npy(Path(poses))
    arr = poses if isinstance(poses, np.ndarray) else as_float_array(poses, "poses")
    if arr.size == 0:
        return _Source(0, array=np.zeros((0, 4, 4)))
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise ShapeError(f"poses must have shape (N, 4, 4), got {arr.shape}")
    if arr.dtype.kind not in "fiu":
        raise ShapeError(f"poses must hold real numbers, got dtype {arr.dtype}")
    return _Source(int(arr.shape[0]), array=arr)


def _open_npy(path: Path) -> NDArray[Any]:
    """A ``.npy`` file of poses, memory-mapped (read a chunk at a time; never all in memory)."""
    from sweepik.errors import PoseFileError

    if path.suffix.lower() != ".npy":
        raise PoseFileError(f"{path}: poses by path must be a .npy file (load other formats with load_poses)")
    if not path.is_file():
        raise PoseFileError(f"{path}: no such file" if not path.exists() else f"{path}: not a file")
    try:
        arr = np.load(path, mmap_mode="r", allow_pickle=False)
    except (ValueError, OSError) as exc:
        raise PoseFileError(f"{path}: not a readable .npy array ({exc})") from None
    if arr.dtype.kind not in "fiu":
        raise PoseFileError(f"{path}: poses must be real numbers, got dtype {arr.dtype}")
    if arr.ndim == 2 and arr.shape == (4, 4):
        arr = arr.reshape(1, 4, 4)
    if arr.ndim != 3 or arr.shape[1:] != (4, 4):
        raise PoseFileError(f"{path}: poses must have shape (N, 4, 4), got {arr.shape}")
    return arr


# --------------------------------------------------------------------------------------------------
# Cluster
# --------------------------------------------------------------------------------------------------


@contextlib.contextmanager
def _client_at(distributed: Any, address: str) -> Iterator[Any]:
    """A client of the scheduler at ``address`` with a worker, or a SweepikError within ``CONNECT_TIMEOUT_S`` (x2):
    a malformed address, nothing listening, a port that accepts but is no scheduler (Dask's own timeout does not
    bound that handshake: the connection runs in a thread given a hard deadline), or a scheduler without workers."""
    import concurrent.futures

    from distributed.comm import parse_address

    try:
        parse_address(address)
        distributed.comm.get_address_host_port(address)
    except (ValueError, TypeError) as exc:
        raise SweepikError(f"not a Dask scheduler address {address!r}: {exc}") from None
    pool = concurrent.futures.ThreadPoolExecutor(max_workers=1)
    pending = pool.submit(distributed.Client, address, timeout=CONNECT_TIMEOUT_S)
    try:
        c = pending.result(timeout=CONNECT_TIMEOUT_S + 5.0)
    except concurrent.futures.TimeoutError:
        raise SweepikError(
            f"the Dask scheduler at {address!r} did not answer within {CONNECT_TIMEOUT_S:g} s (is it a scheduler?)"
        ) from None
    except (OSError, TimeoutError, ValueError) as exc:
        raise SweepikError(f"cannot reach the Dask scheduler at {address!r}: {exc}") from None
    finally:
        pool.shutdown(wait=False)
    with c:
        try:
            c.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
        except (TimeoutError, OSError):
            raise SweepikError(
                f"the Dask scheduler at {address!r} has no workers (none joined within {CONNECT_TIMEOUT_S:g} s)"
            ) from None
        yield c


#: The local cluster of ``solve_dask(client=None)`` calls, kept for the next call in this process (starting one costs
#: seconds): ``(n_workers, cluster, client)``, closed by :func:`close_local_cluster` or at the process's exit.
_LOCAL: list[tuple[int, Any, Any]] = []


def close_local_cluster() -> None:
    """Stop the local cluster that ``solve_dask(client=None)`` started and keeps for the next call (if any)."""
    while _LOCAL:
        _, cluster, c = _LOCAL.pop()
        with contextlib.suppress(Exception):  # (already closed, or its processes gone at exit)
            c.close()
            cluster.close()


def _local_client(distributed: Any, n: int) -> Any:
    """A client of the local cluster: one worker with ``n`` threads in this process (the compiled kernels release
    the GIL, so threads solve chunks side by side as ``solve_many``'s do; no worker process to start, no re-import
    of the caller's script, no copy of poses and results between processes). The one kept from an earlier call when
    it has ``n`` threads and still runs, else a new one (the old one closed), kept for later calls."""
    import atexit

    if _LOCAL and _LOCAL[0][0] == n and _LOCAL[0][2].status == "running":
        return _LOCAL[0][2]
    close_local_cluster()
    try:
        cluster = distributed.LocalCluster(
            n_workers=1, threads_per_worker=n, processes=False, dashboard_address=":0", silence_logs=logging.CRITICAL
        )
    except (RuntimeError, OSError) as exc:
        raise SweepikError(f"could not start a local Dask cluster of {n} threads: {exc}") from None
    c = distributed.Client(cluster)
    if not _LOCAL:
        atexit.register(close_local_cluster)
    _LOCAL.append((n, cluster, c))
    return c


@contextlib.contextmanager
def _connected(client: Any, n_workers: int | None) -> Iterator[Any]:
    """The client to use: ``client`` itself; a new one for a scheduler address (closed on exit); the kept local
    cluster's (threads in this process) when None."""
    distributed = _check_client(client, n_workers)
    if client is None:
        yield _local_client(distributed, cast(int, _local_threads(None, n_workers)))
    elif isinstance(client, str):
        with _client_at(distributed, client) as c:
            yield c
    else:
        yield client


def _check_client(client: Any, n_workers: int | None) -> Any:
    """Refuse a ``client`` that is not a Client, an address or None, or one given with ``n_workers`` (checked
    before the store is created, so that a refused call leaves nothing behind). Returns ``dask.distributed``."""
    distributed = _dask()
    if client is not None and n_workers is not None:
        raise UnknownOptionError("n_workers sizes the local cluster started when client is None; give one of them")
    if not (client is None or isinstance(client, str | distributed.Client)):
        raise UnknownOptionError(
            f"client must be a dask.distributed Client, a scheduler address or None, got {short_repr(client, 40)}"
        )
    return distributed


@contextlib.contextmanager
def _connected_or_discarded(client: Any, n_workers: int | None, fresh: StoreWriter | None) -> Iterator[Any]:
    """``_connected``; when no connection could be made (an unreachable scheduler, a local cluster that fails to
    start), the store ``fresh`` created for this run is removed first."""
    entered = False
    try:
        with _connected(client, n_workers) as c:
            entered = True
            yield c
    except BaseException:
        if not entered and fresh is not None:
            fresh.discard()
        raise


def auto_chunk_size(n_poses: int, threads: int) -> int:
    """Poses per chunk when ``chunk_size`` is not given: a multiple of the solver's ``CHUNK`` (2,048 poses), so that
    the solver's batches are ``solve_many``'s and so are the results, bit for bit (on arms whose sample hints depend
    on the batch, e.g. the generic sweeps, another chunking moves some solutions by rounding, ~1e-13);
    ``CHUNKS_PER_THREAD`` chunks per worker thread up to ``MAX_AUTO_CHUNK`` poses; up to ``CHUNK`` poses, one."""
    from sweepik.solving import CHUNK

    if n_poses <= CHUNK:  # one chunk, as solve_many solves it
        return max(1, n_poses)
    target = -(-max(MIN_AUTO_CHUNK, -(-n_poses // (CHUNKS_PER_THREAD * max(threads, 1)))) // CHUNK) * CHUNK
    return int(min(target, MAX_AUTO_CHUNK))


# --------------------------------------------------------------------------------------------------
# The run
# --------------------------------------------------------------------------------------------------


@dataclass
class RunSummary:
    """What a run did: ``totals`` (poses, solutions, unreachable, out_of_limits, families: over all chunks,
    resumed ones included), chunk counts, poses resumed from the store, wall time, worker threads."""

    totals: dict[str, int]
    n_chunks: int
    chunk_size: int
    resumed_chunks: int
    resumed_poses: int
    seconds: float
    threads: int


def run(
    robot: Robot,
    poses: object,
    *,
    client: Any = None,
    n_workers: int | None = None,
    out: str | os.PathLike[str] | None = None,
    chunk_size: int | None = None,
    resume: bool = False,
    progress: Progress | None = None,
    keep: bool = True,
    options: Mapping[str, Any],
) -> tuple[RunSummary, dict[int, Block]]:
    """The engine of :func:`solve_dask` and ``sweepik solve --out``: solves every chunk not yet stored, writes
    each to ``out`` as it comes, returns the summary and (``keep``) the blocks computed, by chunk index."""
    t0 = time.perf_counter()
    src = _source(poses)
    if chunk_size is not None:
        chunk_size = check_int(chunk_size, "chunk_size", 1, 2**31)
    if resume and out is None:
        raise UnknownOptionError("resume=True continues a store: give out=PATH too")
    stored_chunk = None
    if out is not None:
        path = Path(out)
        if path.exists() or path.is_symlink():
            if not resume:
                raise StoreError(f"{path}: already exists; resume it (resume=True, --resume) or give a new path")
            stored_chunk = int(store_info(path)["chunk_size"])
            if chunk_size is not None and chunk_size != stored_chunk:
                raise StoreError(
                    f"{path}: cannot resume with chunk_size {chunk_size}: the store has chunks of {stored_chunk}"
                )
        elif not path.parent.is_dir():
            raise StoreError(f"{path}: cannot create the store: directory {str(path.parent)!r} is missing")
    # the store is created (or opened and checked, with resume) before a local cluster starts whenever the chunk
    # size is known by then: a store that cannot be written or resumed costs no cluster start
    _check_client(client, n_workers)
    local = _local_threads(client, n_workers)
    cs = stored_chunk or chunk_size or (None if local is None else auto_chunk_size(src.n, local))
    writer = None if out is None or cs is None else _open_writer(out, robot, options, src, cs, resume)
    with _connected_or_discarded(client, n_workers, None if resume else writer) as c:
        threads = max(1, sum(c.nthreads().values()))
        if cs is None:
            cs = auto_chunk_size(src.n, threads)
            writer = None if out is None else _open_writer(out, robot, options, src, cs, resume, c)
        n_chunks = -(-src.n // cs)
        done: dict[int, dict[str, Any]] = {} if writer is None else writer.done()
        if writer is not None and done and src.dask is not None:
            _check_resumed(c, src, writer, done, cs)
        stats = [done[k]["stats"] for k in sorted(done)]
        resumed_poses = sum(int(s["poses"]) for s in stats)
        todo = [k for k in range(n_chunks) if k not in done]
        blocks: dict[int, Block] = {}
        solved = resumed_poses
        if progress is not None:
            progress("solve", solved, src.n)
        for k, block in _results(c, robot, src, options, cs, todo, threads):
            if writer is not None:
                stats.append(writer.write(k, block))
            else:
                stats.append(chunk_stats(block))
            if keep:
                blocks[k] = block
            solved += block.n
            if progress is not None:
                progress("solve", solved, src.n)
        totals = writer.finish() if writer is not None else _totals(stats)
    summary = RunSummary(totals, n_chunks, cs, len(done), resumed_poses, time.perf_counter() - t0, threads)
    return summary, blocks


def _local_threads(client: Any, n_workers: int | None) -> int | None:
    """Worker threads of the local cluster ``_connected`` starts for ``client`` None (its one worker's), else None
    (an existing cluster's are known once connected)."""
    if client is not None:
        return None
    return (os.cpu_count() or 1) if n_workers is None else check_int(n_workers, "n_workers", 1, 4096)


def _open_writer(
    out: str | os.PathLike[str],
    robot: Robot,
    options: Mapping[str, Any],
    src: _Source,
    cs: int,
    resume: bool,
    c: Any = None,
) -> StoreWriter:
    """The store's writer (created, or opened and checked with ``resume``: robot, options, sizes and, for poses
    the client holds, each stored chunk's poses; a Dask array's are checked on the cluster, by the caller)."""
    writer = StoreWriter(out, robot, options, src.n, cs, resume=resume)
    if resume and src.dask is None:
        done = writer.done()
        if done:
            _check_resumed(c, src, writer, done, cs)
    return writer


def _totals(stats: list[dict[str, int]]) -> dict[str, int]:
    keys = ("poses", "solutions", "unreachable", "out_of_limits", "families")
    return {key: int(sum(int(s[key]) for s in stats)) for key in keys}


def _task(c: Any, robot: Robot, src: _Source, options: Mapping[str, Any], cs: int, k: int) -> Any:
    s, e = k * cs, min((k + 1) * cs, src.n)
    if src.dask is None:
        return c.submit(_solve_task, robot, src.chunk(s, e), options, s, pure=False)
    import dask

    piece = src.dask[s:e]
    return c.compute(dask.delayed(_solve_task, pure=False)(robot, piece, options, s))


def _results(
    c: Any, robot: Robot, src: _Source, options: Mapping[str, Any], cs: int, todo: list[int], threads: int
) -> Iterator[tuple[int, Block]]:
    """(chunk index, block) of every chunk in ``todo``, as they finish; at most ``IN_FLIGHT_PER_THREAD`` chunks per
    worker thread submitted at once. A task's error is raised here; the futures left are cancelled on exit."""
    distributed = _dask()
    pending = iter(todo)
    live: dict[Any, tuple[int, Any]] = {}  # future key -> (chunk index, future)
    queue = distributed.as_completed()

    def submit() -> None:
        k = next(pending, None)
        if k is not None:
            fut = _task(c, robot, src, options, cs, k)
            live[fut.key] = (k, fut)
            queue.add(fut)

    try:
        for _ in range(IN_FLIGHT_PER_THREAD * threads):
            submit()
        for fut in queue:
            block = fut.result()
            k, _ = live.pop(fut.key)
            fut.release()
            submit()
            yield k, block
    finally:
        if live:
            c.cancel([f for _, f in live.values()])


def _check_resumed(c: Any, src: _Source, writer: StoreWriter, done: Mapping[int, Mapping[str, Any]], cs: int) -> None:
    """StoreError unless every stored chunk holds the poses given now (SHA-256 of the chunk's float64 poses)."""
    if src.dask is None:
        for k, attrs in done.items():
            s, e = writer.span(k)
            writer.check_poses(k, attrs, poses_digest(as_float_array(src.chunk(s, e), "poses")))
        return
    import dask

    keys = sorted(done)
    digests = c.gather([c.compute(dask.delayed(_digest)(src.dask[k * cs : min((k + 1) * cs, src.n)])) for k in keys])
    for k, digest in zip(keys, digests, strict=True):
        writer.check_poses(k, done[k], digest)


def _digest(poses: ArrayLike) -> str:
    return poses_digest(as_float_array(poses, "poses"))


# --------------------------------------------------------------------------------------------------
# Public entry point
# --------------------------------------------------------------------------------------------------


def solve_dask(
    robot: Robot,
    poses: ArrayLike | str | os.PathLike[str],
    client: Any = None,
    out: str | os.PathLike[str] | None = None,
    *,
    chunk_size: int | None = None,
    resume: bool = False,
    progress: Progress | None = None,
    n_workers: int | None = None,
    reduction: str | Reduction | None = None,
    free_joint: int | str | None = None,
    strategy: str = "precise",
    limits: bool = True,
    n_samples: int = N_SAMPLES,
    locked: Mapping[Any, float] | None = None,
) -> SolutionBatch:
    """All IK solutions of each pose in ``poses (N, 4, 4)``, solved on a Dask cluster: the same
    :class:`~sweepik.results.SolutionBatch` as ``solve_many(robot, poses, ...)`` (same solutions, same order).

    Args:
        robot: the arm (travels to the workers by value).
        poses: a NumPy array (or ``np.memmap``), the path of a ``.npy`` file (memory-mapped: the client reads one
            chunk at a time), or a Dask array ``(N, 4, 4)`` (each worker computes the chunks it solves).
        client: None: a local cluster in this process (one worker of ``n_workers`` threads, default one per
            core), started by the first such call and kept for the next ones (:func:`close_local_cluster` stops
            it, the process's exit too); a ``dask.distributed.Client``; or a scheduler address
            (``"tcp://host:8786"``). The workers need sweepik (and its version) installed.
        out: a directory to write the store to (Zarr, see :mod:`sweepik.io.store`), chunk by chunk as chunks finish,
            marked complete at the end; :func:`~sweepik.io.store.load_solutions` reads it back. It must not exist,
            unless ``resume``.
        chunk_size: poses per task (and per chunk of the store); default: :func:`auto_chunk_size` (a multiple of
            ``solve_many``'s 2,048-pose batches, so that the results are its results bit for bit; one chunk up to
            2,048 poses). With ``resume``, the store's.
        resume: continue the store at ``out``: only the chunks it lacks are solved (StoreError if it was written
            for other poses, another robot or other options).
        progress: ``progress("solve", done, total)`` (poses) after each chunk.
        n_workers: threads of the local cluster (only when ``client`` is None; default one per core).
        reduction, free_joint, strategy, limits, n_samples, locked: as :func:`~sweepik.solve_many` (with ``out``,
            ``reduction`` must be a name or None).

    Returns the batch of every pose; with ``out``, read back from the store (its content is what was written).

    Raises:
        SweepikError subclasses, as ``solve_many`` (options checked before any cluster starts; a pose that is not a
        rigid transform when its chunk is solved); StoreError for a store that exists (without ``resume``) or
        does not match (with it). Other exceptions of Dask (e.g. ``KilledWorker``, when a task killed
        ``allowed-failures`` workers) pass through. On any error or interruption the store stays incomplete.
    """
    opts = _checked_options(robot, reduction, free_joint, strategy, limits, n_samples, locked, stored=out is not None)
    if progress is not None and not callable(progress):
        raise UnknownOptionError(f"progress must be callable or None, got {type(progress).__name__}")
    resume = bool(resume)
    _, blocks = run(
        robot,
        poses,
        client=client,
        n_workers=n_workers,
        out=out,
        chunk_size=chunk_size,
        resume=resume,
        progress=progress,
        keep=out is None,
        options=opts,
    )
    if out is not None:
        return load_solutions(out)
    return SolutionBatch(robot, [blocks[k] for k in sorted(blocks)])
