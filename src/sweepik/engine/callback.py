"""A reduction written in NumPy (no compiled kernel, ``Reduction.uses_kernel`` False) searched by the compiled
engine: its residual is called back from the compiled search, one theta* at a time.

The search takes a reduction's residual as the address of a compiled function of ``kernels.RESIDUAL_SIG``
(``residual(params, theta, branch)``, ``params`` a row of per-pose parameters). For a NumPy reduction that function
is :data:`residual`: its ``params`` row is ``(key, pose row)``, and it calls the reduction's ``residual_rows`` for that
one pose, theta* and branch through Numba's object mode (the GIL taken for the call). ``registered`` hands out the
keys for the duration of a search. The uniform samples, where most evaluations are, are computed beforehand in one
vectorised ``residual`` call (``search`` passes them as known values), so the callbacks are the refinements: tens of
microseconds each, a few milliseconds a pose, where a compiled kernel takes microseconds (docs/reductions.md).

An exception raised by the reduction's code is kept, NaN returned to the search (which cannot raise through a function
address), and raised again by ``registered`` when the search is done: a wrong residual is an error, never an answer.
"""

from __future__ import annotations

import itertools
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import objmode
from numpy.typing import NDArray

from sweepik.reductions.base import Reduction
from sweepik.reductions.kernels import RESIDUAL_SIG, RESIDUALS_SIG, LazyKernel

__all__ = ["registered", "residual", "residuals"]

Array = NDArray[np.float64]


@dataclass
class _Search:
    """A search in progress: the reduction, its chain poses, and the first exception its code raised."""

    reduction: Reduction
    poses: Array
    error: BaseException | None = None


_SEARCHES: dict[int, _Search] = {}
_KEYS = itertools.count(1)
_LOCK = threading.Lock()


@contextmanager
def registered(reduction: Reduction, poses: Array) -> Iterator[Array]:
    """The ``params (N, 2)`` rows that make :data:`residual` and :data:`residuals` call ``reduction`` on the chain
    poses ``poses (N, 4, 4)`` while the block runs; the first exception the reduction raised in a callback is raised
    when it ends."""
    with _LOCK:
        key = next(_KEYS)
        _SEARCHES[key] = entry = _Search(reduction, np.ascontiguousarray(poses, dtype=np.float64))
    try:
        params = np.empty((poses.shape[0], 2))
        params[:, 0] = key
        params[:, 1] = np.arange(poses.shape[0])
        yield params
    finally:
        with _LOCK:
            del _SEARCHES[key]
    if entry.error is not None:
        raise entry.error


def _one(key: float, row: float, theta: float, branch: float) -> float:
    entry = _SEARCHES[int(key)]
    if entry.error is not None:
        return np.nan
    try:
        rows = np.array([int(row)], dtype=np.intp)
        value = entry.reduction.residual_rows(entry.poses, rows, np.array([[theta]]), np.array([[int(branch)]]))
        return float(np.asarray(value).reshape(-1)[0])
    except BaseException as err:  # (kept and raised by ``registered``)
        entry.error = err
        return np.nan


def _every(key: float, row: float, theta: float) -> Array:
    entry = _SEARCHES[int(key)]
    n = entry.reduction.n_branches
    if entry.error is not None:
        return np.full(n, np.nan)
    try:
        r = int(row)
        value = entry.reduction.residual(entry.poses[r : r + 1], np.array([[theta]]))
        return np.ascontiguousarray(np.asarray(value, dtype=np.float64).reshape(n))
    except BaseException as err:
        entry.error = err
        return np.full(n, np.nan)


def _residual(p: Any, x: float, b: int) -> float:
    with objmode(r="float64"):
        r = _one(p[0], p[1], x, b)
    return r


def _residuals(p: Any, x: float, out: Any) -> None:
    with objmode(r="float64[::1]"):
        r = _every(p[0], p[1], x)
    for k in range(out.shape[0]):
        out[k] = r[k]


# (compiled on first use, ~0.3 s, not at import: not cached either, as Numba does not cache object-mode blocks)
#: The compiled residual of any NumPy reduction (``kernels.RESIDUAL_SIG``), its ``params`` from ``registered``.
residual = LazyKernel(_residual, RESIDUAL_SIG, cache=False)
#: ... and every branch's at once (``kernels.RESIDUALS_SIG``).
residuals = LazyKernel(_residuals, RESIDUALS_SIG, cache=False)
