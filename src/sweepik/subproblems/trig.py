"""Roots of a trigonometric polynomial of degree 2 in one angle (what SP5 and SP6 reduce to), and angle wrapping.

``f(theta) = a0 + a1 cos(theta) + b1 sin(theta) + a2 cos(2 theta) + b2 sin(2 theta)`` has at most 4 roots on the
circle. With ``z = exp(i theta)``, ``z^2 f`` is a polynomial of degree 4 in ``z`` whose roots on the unit circle are
the roots of ``f``: its companion matrix's eigenvalues (``numpy.roots``), those within ``UNIT_TOL`` of the circle
kept, each polished by Newton's method on ``f`` itself and accepted only where ``|f|`` is then at rounding level.
No tangent-half-angle substitution, so no angle is special (theta = pi included).

The eigenvalues come from LAPACK's ``zgeev`` through the binding Numba's ``np.roots`` uses, called directly
(``_companion_roots``: the same matrix and call, so the same roots to the bit): Numba's ``np.roots`` and
``np.linalg.eigvals`` carry general-purpose checks and conversions that took about 8 s to compile on a fresh
install.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, types
from numba.extending import overload

from sweepik._jit import ERROR_MODEL, inlined, internal

__all__ = ["trig2_roots", "trig2", "wrap_pi"]

#: Roots of ``z^2 f`` this far from the unit circle (in ``| |z| - 1 |``) are candidates: a double root (f tangent
#: to zero) splits into two roots ~sqrt(rounding) off the circle.
UNIT_TOL = 1e-4
#: Newton steps polishing each candidate on ``f``.
NEWTON_STEPS = 8
#: A candidate is a root when ``|f|`` ends below this times the size of ``f``'s coefficients.
ROOT_TOL = 1e-10
#: Two polished roots closer than this (radians) ...
SAME_ROOT = 1e-6
#: ... are one double root, at their midpoint, when ``|f|`` there is below this times the size of the coefficients
#: (a double root, f tangent to zero, comes out of the eigenvalues as two roots ~1e-8 apart with f at rounding
#: level between them; two distinct roots g apart have ``|f| ~ f'' g^2 / 8`` between them, so they stay two down to
#: g ~ 3e-7).
DOUBLE_FLAT = 1e-14


@njit(cache=True, error_model=ERROR_MODEL)
def trig2(a0, a1, b1, a2, b2, theta):
    """``f(theta)`` and ``f'(theta)``."""
    c, s = math.cos(theta), math.sin(theta)
    c2, s2 = c * c - s * s, 2.0 * s * c
    f = a0 + a1 * c + b1 * s + a2 * c2 + b2 * s2
    df = -a1 * s + b1 * c - 2.0 * a2 * s2 + 2.0 * b2 * c2
    return f, df


def _zgeev(a, w, vl, vr):
    """``info`` of LAPACK's ``zgeev`` (no eigenvectors) on ``a (n, n)`` (Fortran order), eigenvalues into ``w (n,)``
    (``vl``, ``vr``: one-element placeholders). Compiled code only (an overload)."""
    raise NotImplementedError("trig._zgeev is compiled code's")


@overload(_zgeev)
def _zgeev_compiled(a, w, vl, vr):
    # Numba's binding, the one its np.linalg.eigvals calls for complex matrices (a private name of numba.np.linalg),
    # looked up when a kernel using it is compiled: SciPy's LAPACK is then required, as for np.roots, and neither
    # numba.np.linalg nor SciPy is imported with sweepik (a cached kernel loads LAPACK when first called)
    from numba.np.linalg import _LAPACK, ensure_lapack

    ensure_lapack()
    zgeev = _LAPACK().numba_ez_cgeev(types.complex128)

    def impl(a, w, vl, vr):
        n = a.shape[0]
        # kind 'z', jobvl = jobvr = 'N' (the arrays stay alive: the caller holds them through this call)
        return zgeev(122, 78, 78, n, a.ctypes, n, w.ctypes, vl.ctypes, 1, vr.ctypes, 1)

    return impl


@internal
def _companion_roots(c, m):
    """The ``m - 1`` roots of the polynomial ``c[0] z^(m-1) + ... + c[m-1]`` (``c[0]`` and ``c[m-1]`` not 0), as
    Numba's ``np.roots(c[:m])``: the eigenvalues of the same companion matrix (first row ``-c[1:] / c[0]``, ones
    below the diagonal, Fortran order) by the same LAPACK call, with the same errors."""
    n = m - 1
    a = np.empty((n, n), dtype=np.complex128).T  # (Fortran order, as LAPACK takes it)
    for j in range(n):
        for i in range(n):
            a[i, j] = 0.0
    for k in range(n):
        a[0, k] = -c[k + 1] / c[0]
        if not (math.isfinite(a[0, k].real) and math.isfinite(a[0, k].imag)):
            raise np.linalg.LinAlgError("Array must not contain infs or NaNs.")
    for k in range(n - 1):
        a[k + 1, k] = 1.0
    w = np.empty(n, dtype=np.complex128)
    vl = np.empty(1, dtype=np.complex128)  # (not referenced: no eigenvectors)
    vr = np.empty(1, dtype=np.complex128)
    if _zgeev(a, w, vl, vr) != 0:
        raise ValueError("Internal algorithm failed to converge.")
    return w


@njit(cache=True, error_model=ERROR_MODEL)
def trig2_roots(a0, a1, b1, a2, b2):
    """Roots ``(4,)`` (NaN-padded, ascending) of ``a0 + a1 cos t + b1 sin t + a2 cos 2t + b2 sin 2t`` in (-pi, pi],
    and their count. An identically zero ``f`` (every angle a root) gives count -1."""
    out = np.empty(4)
    for k in range(4):
        out[k] = np.nan
    scale = max(abs(a0), abs(a1), abs(b1), abs(a2), abs(b2))
    if scale == 0.0:
        return out, -1
    # z^2 f = c4 z^4 + c3 z^3 + c2 z^2 + c1 z + c0, c4 = conj(c0), c3 = conj(c1)
    c4 = complex(0.5 * a2, -0.5 * b2)
    c3 = complex(0.5 * a1, -0.5 * b1)
    c2 = complex(a0, 0.0)
    c1 = complex(0.5 * a1, 0.5 * b1)
    c0 = complex(0.5 * a2, 0.5 * b2)
    small = 1e-13 * scale
    coef = np.empty(5, dtype=np.complex128)
    if abs(c4) > small:
        coef[0], coef[1], coef[2], coef[3], coef[4] = c4, c3, c2, c1, c0
        m = 5
    elif abs(c3) > small:  # degree 1 in the angle: z f = c3 z^2 + c2 z + c1
        coef[0], coef[1], coef[2] = c3, c2, c1
        m = 3
    else:  # constant and nonzero
        return out, 0
    z = _companion_roots(coef, m)  # (one call: with a constant m Numba would compile it once per value)
    n = 0
    for zi in z:
        if abs(abs(zi) - 1.0) > UNIT_TOL:
            continue
        t = math.atan2(zi.imag, zi.real)
        best, best_f = t, math.inf
        for _ in range(NEWTON_STEPS):
            f, df = trig2(a0, a1, b1, a2, b2, t)
            if abs(f) < best_f:
                best, best_f = t, abs(f)
            if df == 0.0:
                break
            step = f / df
            if abs(step) > 0.1:  # a near-double root: Newton would wander; keep the eigenvalue's angle
                break
            t -= step
        f, _ = trig2(a0, a1, b1, a2, b2, t)
        if abs(f) < best_f:
            best, best_f = t, abs(f)
        # (the angle where |f| is least: next to a double root that rounding turned into a complex pair, f has a
        # minimum at rounding level and no zero, and Newton steps from it lead away)
        t = best
        if best_f > ROOT_TOL * scale:
            continue
        t = math.atan2(math.sin(t), math.cos(t))
        dup = False
        for j in range(n):
            gap = math.atan2(math.sin(t - out[j]), math.cos(t - out[j]))
            mid = out[j] + 0.5 * gap
            if abs(gap) < SAME_ROOT and abs(trig2(a0, a1, b1, a2, b2, mid)[0]) <= DOUBLE_FLAT * scale:
                out[j] = math.atan2(math.sin(mid), math.cos(mid))
                dup = True
                break
        if not dup and n < 4:
            out[n] = t
            n += 1
    for a in range(1, n):  # ascending (insertion sort of at most 4 finite angles)
        t = out[a]
        j = a - 1
        while j >= 0 and out[j] > t:
            out[j + 1] = out[j]
            j -= 1
        out[j + 1] = t
    return out, n


@inlined
def wrap_pi(x: float) -> float:
    """``pi - ((pi - x) % 2 pi)``, the angle ``x`` wrapped into ``(-pi, pi]``, bit for bit as that expression gives it
    (Python's and NumPy's float modulo, as ``Robot.wrap``), without the modulo's library call when ``|pi - x| < 2 pi``:
    there ``fmod`` returns ``pi - x`` exactly and the modulo adds ``2 pi`` to a negative one (and gives +0 for 0, which
    ``pi -`` does not tell from -0). NaN (a branch that does not exist) is returned as it is: the modulo's call is
    slowest on it (~150 ns)."""
    y = math.pi - x
    two_pi = 2.0 * math.pi
    if 0.0 <= y < two_pi:
        return math.pi - y
    if -two_pi < y < 0.0:
        return math.pi - (y + two_pi)
    if y != y:
        return x
    return math.pi - (y % two_pi)
