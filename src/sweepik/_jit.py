"""Compile options shared by the compiled kernels (a module of its own: the subproblems and the engine import it, and
it imports nothing of sweepik)."""

from __future__ import annotations

from typing import Any, Final

import numba
import numpy as np
from numba.core import cgutils, types
from numba.extending import intrinsic
from numpy.typing import ArrayLike, NDArray

_njit: Any = numba.njit  # (untyped: Numba's stubs do not list every option sweepik passes)

__all__ = ["internal", "inlined", "unowned", "alive", "function_at", "writable", "ERROR_MODEL"]

#: Numba's error model for every compiled function of sweepik: IEEE results for a division by zero (inf, NaN), as
#: NumPy gives them, rather than a ZeroDivisionError raised from deep inside a kernel (which would abort a whole
#: batch where a NaN sample or a candidate that fails certification is the right outcome).
ERROR_MODEL: Final = "numpy"
#: The options of ``internal`` and ``inlined``.
_INTERNAL = {"cache": True, "no_cpython_wrapper": True, "no_cfunc_wrapper": True, "error_model": ERROR_MODEL}


def internal(fn: Any) -> Any:
    """``numba.njit(cache=True, error_model=ERROR_MODEL)`` for a function that only compiled code calls: compiled
    without the wrappers that let Python and C call it (``no_cpython_wrapper``, ``no_cfunc_wrapper``), which cost
    ~0.05 s each on a fresh install. Calling it from Python fails. Its Python function must not be compiled by
    another dispatcher too (Numba's disk cache keys on the function and the signature, not on these options)."""
    return _njit(**_INTERNAL, forceinline=False)(fn)


def inlined(fn: Any) -> Any:
    """``internal``, and inlined into every compiled caller (``forceinline``: LLVM's ``alwaysinline``), for the small
    functions a kernel is built of (vector algebra, subproblems, the steps of a family) and the engine's helpers
    called per sample or candidate (root finding, probes, FK, errors). Numba compiles each function on its own and
    calls it with its own convention (results through memory, a status code, and the reference counts of the arrays
    passed counted up and down); LLVM inlines only the smallest. A generic family's residual made ~20 calls per
    evaluation: inlined, it takes 2.5 times less (330 -> 134 ns on CRX-10iA, docs/performance.md), with the same
    results bit for bit.

    Numba passes ``forceinline`` on to the functions first compiled while compiling an inlined one, unless they set
    it: ``internal`` sets it False, and so does a large subproblem (``sp5``, ``sp6``)."""
    return _njit(**_INTERNAL, forceinline=True)(fn)


@intrinsic
def unowned(typingctx: Any, a: Any) -> Any:
    """Compiled code only: ``a`` (an array) as a view that is not reference-counted (no meminfo), so that passing it
    or a view of it to a first-class function (a reduction's kernel) costs no atomic increment and decrement of
    its reference count (Numba brackets every such call with them: about a fifth of the engine's time). Only for
    an array that outlives every use of the view: an argument of the compiled function (its caller holds it)."""
    if not isinstance(a, types.Array):
        return None

    def codegen(context: Any, builder: Any, sig: Any, args: Any) -> Any:
        ary = context.make_array(sig.args[0])(context, builder, value=args[0])
        ary.meminfo = cgutils.get_null_value(ary.meminfo.type)
        return ary._getvalue()

    return a(a), codegen


@internal
def alive(*arrays: Any) -> int:
    """Nothing: a use of arrays a compiled function allocated, after the last use of their ``unowned`` views, so
    that they are freed after it."""
    return len(arrays)


def function_at(sig: Any) -> Any:
    """An intrinsic for compiled code: ``function_at(sig)(address)`` is the compiled function of signature ``sig``
    whose Numba entry point is at ``address`` (an int64, see ``reductions.kernels.address_of``), as a first-class
    function value that compiled code calls like any other.

    A kernel takes a reduction's function as its address rather than as a first-class function argument: Numba
    unboxes a first-class argument through two Python calls on every call of the kernel (~4 us each time), and calls
    it through its C wrapper; from the address it is called directly, with Numba's own calling convention. The address
    must be that of a compiled function of exactly this signature that outlives the call (the dispatcher holds it).
    """
    fnty = types.FunctionType(sig)

    @intrinsic
    def at(typingctx: Any, address: Any) -> Any:
        if not isinstance(address, types.Integer):
            return None

        def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
            fn = cgutils.create_struct_proxy(fnty)(context, builder)
            voidptr = context.get_value_type(types.voidptr)
            fn.c_addr = cgutils.get_null_value(voidptr)
            fn.py_addr = cgutils.get_null_value(voidptr)
            fn.jit_addr = builder.inttoptr(args[0], voidptr)
            return fn._getvalue()

        return fnty(address), codegen

    return at


def writable(a: ArrayLike) -> NDArray[np.float64]:
    """``a`` as a C-contiguous, writable float64 array (the compiled signatures' kind): copied only if needed."""
    a = np.asarray(a)
    return np.array(a, dtype=np.float64, order="C", copy=not a.flags.writeable or None)
