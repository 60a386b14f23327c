"""Running a compiled kernel over a batch of independent items on several threads.

A batch kernel takes the range ``start, stop`` of the items it handles as its last two arguments and is compiled
with ``nogil=True``: Python threads then run it side by side on the parts of a batch, as Numba's ``prange`` would.
Numba's own parallel loops (``parallel=True``) cost far more to compile: the loop's index is unsigned, so every
compiled function called with it is compiled a second time for that type, and the loop body becomes one more
function whose module re-optimises everything it calls (about 10 s of the first C-Arm solve on a fresh install).

The number of threads is Numba's: ``NUMBA_NUM_THREADS`` (default: the number of cores), or what
``numba.set_num_threads`` set in the calling thread (a Dask task pins its kernels to one thread that way).

A batch solved in chunks runs them two at a time (``in_order``): one chunk's Python steps (holding the GIL) then
overlap the other's compiled kernels, which would otherwise leave a core idle between kernels.
"""

from __future__ import annotations

import threading
from collections import deque
from collections.abc import Callable, Iterator, Sequence
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any, TypeVar

__all__ = ["in_order", "run", "threads"]

T = TypeVar("T")
R = TypeVar("R")

#: Parts per thread a batch is split into: threads that finish early take the next part (the items of a batch
#: differ in cost), while each part stays large enough that handing it to a thread (~50 us) costs little.
PARTS_PER_THREAD = 4

_pool: ThreadPoolExecutor | None = None
_pool_size = 0
_pool_lock = threading.Lock()
#: Chunks of a batch in flight at once (``in_order``): two keep both cores busy; each holds a chunk's work arrays.
IN_FLIGHT = 2
_chunk_pool: ThreadPoolExecutor | None = None
#: The caller's thread setting, seen by ``threads()`` in a chunk's thread (Numba's setting is per thread).
_local = threading.local()


def threads() -> int:
    """Threads a batch kernel may use in the calling thread (Numba's setting, see the module docstring; in a chunk's
    thread of ``in_order``, its caller's)."""
    import numba
    from numba.np.ufunc import parallel

    # numba.get_num_threads() starts Numba's own thread pool (~60 ms) to read a setting that only
    # numba.set_num_threads changes, and set_num_threads starts that pool itself
    inherited = getattr(_local, "threads", None)
    if inherited is not None:
        return int(inherited)
    if not getattr(parallel, "_is_initialized", True):
        return int(numba.config.NUMBA_NUM_THREADS)  # type: ignore[attr-defined]
    return int(numba.get_num_threads())


def _executor(n: int) -> ThreadPoolExecutor:
    global _pool, _pool_size
    with _pool_lock:
        if _pool is None or _pool_size < n:
            old = _pool
            _pool, _pool_size = ThreadPoolExecutor(max_workers=n, thread_name_prefix="sweepik"), n
            if old is not None:
                old.shutdown(wait=False)
        return _pool


def run(kernel: Callable[..., Any], n: int, min_parallel: int, *args: Any) -> None:
    """``kernel(*args, start, stop)`` over the items ``0 .. n - 1``: in the calling thread when ``n`` is below
    ``min_parallel`` (a thread hand-off would cost more than it saves) or one thread is allowed, else in parts on
    ``threads()`` threads. The items must be independent (each writes only its own outputs)."""
    nt = threads() if n >= min_parallel else 1
    if nt <= 1 or n < 2:
        kernel(*args, 0, n)
        return
    fn: Callable[..., Any] = getattr(kernel, "dispatcher", kernel)  # (a LazyKernel compiled here, not in threads)
    parts = min(n, nt * PARTS_PER_THREAD)
    bounds = [n * k // parts for k in range(parts + 1)]
    pool = _executor(nt)
    futures: list[Future[Any]] = [pool.submit(fn, *args, bounds[k], bounds[k + 1]) for k in range(parts)]
    for f in futures:
        f.result()  # (re-raises a kernel's exception)


def _chunk_executor() -> ThreadPoolExecutor:
    global _chunk_pool
    with _pool_lock:
        if _chunk_pool is None:  # (its own pool: a chunk waits on the kernel pool's threads, never on its own)
            _chunk_pool = ThreadPoolExecutor(max_workers=IN_FLIGHT, thread_name_prefix="sweepik-chunk")
        return _chunk_pool


def _with_threads(n: int, fn: Callable[[T], R], item: T) -> R:
    _local.threads = n
    try:
        return fn(item)
    finally:
        _local.threads = None


def in_order(fn: Callable[[T], R], items: Sequence[T], share: bool = False) -> Iterator[R]:
    """``fn(item)`` for each item, yielded in order. With two items or more and more than one thread allowed
    (``threads()``), ``IN_FLIGHT`` items are worked on at once in background threads, each seeing the caller's
    thread setting (``share``: its share of it, ``threads() // IN_FLIGHT``, for items that start together and take
    about as long, as a batch split evenly: no core is then oversubscribed, and none idles while the other item
    runs its Python steps), and the next one is queued while a result is awaited (called from one of those threads,
    it runs in that thread). ``fn`` must be safe to run in two threads at once. An exception of ``fn`` is raised
    where its item's result is due; items not started when the caller stops are dropped."""
    nt = threads()
    # (in the calling thread: nothing to overlap, or a chunk's own thread, which must not wait on its own pool)
    if nt <= 1 or len(items) < 2 or getattr(_local, "threads", None) is not None:
        yield from map(fn, items)
        return
    if share:
        nt = max(1, nt // IN_FLIGHT)
    pool = _chunk_executor()
    it = iter(items)
    pending: deque[Future[R]] = deque()
    try:
        for item in it:
            pending.append(pool.submit(_with_threads, nt, fn, item))
            if len(pending) >= IN_FLIGHT:
                break
        while pending:
            first = pending.popleft()
            for item in it:  # (the next item starts before this one's result is handed on)
                pending.append(pool.submit(_with_threads, nt, fn, item))
                break
            yield first.result()
    finally:
        for f in pending:
            f.cancel()
