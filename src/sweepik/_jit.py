"""Compile options shared by the compiled kernels (a module of its own: the subproblems and the engine import it, and
it imports nothing of sweepik)."""

from __future__ import annotations

from typing import Any

_njit: Any
try:
    from numba import njit as _njit
except ImportError:  # pragma: no cover - without numba the NumPy engine is used
    _njit = None

__all__ = ["internal"]


def internal(fn: Any) -> Any:
    """``numba.njit(cache=True)`` for a function that only compiled code calls: compiled without the wrappers that
    let Python and C call it (``no_cpython_wrapper``, ``no_cfunc_wrapper``), which cost ~0.05 s each on a fresh
    install. Calling it from Python fails. Its Python function must not be compiled by another dispatcher too (Numba's
    disk cache keys on the function and the signature, not on these options)."""
    if _njit is None:  # pragma: no cover
        return fn
    return _njit(cache=True, no_cpython_wrapper=True, no_cfunc_wrapper=True)(fn)
