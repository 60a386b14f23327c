"""LAPACK's real eigenvalue solver (``dgeev``) for compiled code.

Numba's ``np.linalg.eigvals`` refuses a real matrix whose eigenvalues are complex ("domain change"), and computing
them as a complex matrix's costs four times the arithmetic. The general method (:mod:`.elimination`) needs the
complex eigenvalues of a real 16x16 matrix per pose, inside its compiled loop: this module hands compiled code
SciPy's ``dgeev`` (the LAPACK that Numba's own linear algebra uses, ``scipy.linalg.cython_lapack``) as an external
symbol, so the functions calling it are cached on disk like any other kernel.

``AVAILABLE`` is False where SciPy's LAPACK does not have the expected 32-bit integer interface; the caller then
takes ``numpy.linalg.eigvals`` from Python.
"""

from __future__ import annotations

import numpy as np
from numba import njit, types

from sweepik._jit import ERROR_MODEL

__all__ = ["AVAILABLE", "eigenvalues"]

_SYMBOL = "sweepik_lapack_dgeev"
#: ``dgeev(jobvl, jobvr, n, a, lda, wr, wi, vl, ldvl, vr, ldvr, work, lwork, info)``: every argument a pointer
_dgeev = types.ExternalFunction(_SYMBOL, types.void(*([types.voidptr] * 14)))


def _register() -> bool:
    """Make SciPy's ``dgeev`` the symbol ``_SYMBOL`` of compiled code; False where it is not there or not LP64."""
    try:
        import ctypes

        from llvmlite import binding
        from numba.extending import get_cython_function_address
        from scipy.linalg import cython_lapack

        capsule = cython_lapack.__pyx_capi__["dgeev"]
        name = ctypes.pythonapi.PyCapsule_GetName
        name.restype, name.argtypes = ctypes.c_char_p, [ctypes.py_object]
        signature = name(capsule).decode()
        if not signature.startswith("void (char *, char *, int *,"):  # (an ILP64 build: other integers)
            return False
        binding.add_symbol(_SYMBOL, get_cython_function_address("scipy.linalg.cython_lapack", "dgeev"))
    except (ImportError, KeyError, AttributeError, ValueError):  # pragma: no cover - SciPy missing or changed
        return False
    return True


AVAILABLE = _register()


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def eigenvalues(A):
    """``(wr, wi, info)``: the eigenvalues ``wr + i wi`` of the square C-ordered matrix ``A`` (overwritten: LAPACK
    reads it as its transpose, which has the same eigenvalues) and LAPACK's ``info`` (0: converged)."""
    n = A.shape[0]
    wr, wi, work = np.empty(n), np.empty(n), np.empty(34 * n)
    ints = np.empty(5, dtype=np.int32)  # n, lda, ldv, lwork, info
    ints[0], ints[1], ints[2], ints[3], ints[4] = n, n, 1, 34 * n, 0
    jobs = np.empty(1, dtype=np.uint8)
    jobs[0] = 78  # "N": no eigenvectors
    _dgeev(
        jobs.ctypes,
        jobs.ctypes,
        ints[0:].ctypes,
        A.ctypes,
        ints[1:].ctypes,
        wr.ctypes,
        wi.ctypes,
        work.ctypes,
        ints[2:].ctypes,
        work.ctypes,
        ints[2:].ctypes,
        work.ctypes,
        ints[3:].ctypes,
        ints[4:].ctypes,
    )
    return wr, wi, ints[4]
