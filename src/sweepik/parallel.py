"""Running a compiled kernel over a batch of independent items on several threads.

A batch kernel takes the range ``start, stop`` of the items it handles as its last two arguments and is compiled
with ``nogil=True``: Python threads then run it side by side on the parts of a batch, as Numba's ``prange`` would.
Numba's own parallel loops (``parallel=True``) cost far more to compile: the loop's index is unsigned, so every
compiled function called with it is compiled a second time for that type, and the loop body becomes one more
function whose module re-optimises everything it calls (about 10 s of the first C-Arm solve on a fresh install).

The number of threads is Numba's: ``NUMBA_NUM_THREADS`` (default: the number of cores), or what
``numba.set_num_threads`` set in the calling thread (a Dask task pins its kernels to one thread that way).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import Any

__all__ = ["run", "threads"]

#: Parts per thread a batch is split into: threads that finish early take the next part (the items of a batch
#: differ in cost), while each part stays large enough that handing it to a thread (~50 us) costs little.
PARTS_PER_THREAD = 4

_pool: ThreadPoolExecutor | None = None
_pool_size = 0
_pool_lock = threading.Lock()


def threads() -> int:
    """Threads a batch kernel may use in the calling thread (Numba's setting, see the module docstring)."""
    try:
        import numba
        from numba.np.ufunc import parallel
    except ImportError:  # pragma: no cover - without numba nothing releases the GIL
        return 1

    # numba.get_num_threads() starts Numba's own thread pool (~60 ms) to read a setting that only
    # numba.set_num_threads changes, and set_num_threads starts that pool itself
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
