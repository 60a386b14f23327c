"""Vectorised bracketed root finding (Chandrupatla's method) over many independent brackets at once: the NumPy
reference sweep's (:mod:`oracles.numpy_sweep`; the compiled search has its scalar twin, ``search._root``).

Why not ``scipy.optimize.elementwise.find_root``: it implements the same method, but its per-call overhead
(~1.5 ms measured on this machine for a handful of brackets) alone exceeds the single-pose latency budget
of the whole solve (300 us). This loop costs one residual evaluation of the still-active brackets per
iteration and nothing else.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Iteration cap; Chandrupatla converges superlinearly and falls back to bisection, so 2000 mm to 1e-13 mm
#: needs at most ~55 bisections. The cap only guards against pathological residuals.
MAX_ITER = 100


def find_roots(
    func: Callable[[Array, IntArray], Array],
    a: Array,
    b: Array,
    fa: Array,
    fb: Array,
    xtol: float,
) -> Array:
    """Roots ``(K,)`` of ``func`` in the brackets ``[a, b]`` (``fa * fb <= 0`` required).

    ``func(x, idx)`` evaluates the residual of brackets ``idx`` at ``x`` (both ``(k,)``). Converges until the
    bracket is below ``xtol + 4 eps |x|`` or the residual is exactly zero.
    """
    a = a.astype(np.float64, copy=True)
    b = b.astype(np.float64, copy=True)
    fa = fa.astype(np.float64, copy=True)
    fb = fb.astype(np.float64, copy=True)
    x = np.where(np.abs(fa) < np.abs(fb), a, b)
    c, fc = a.copy(), fa.copy()
    t = np.full(a.shape, 0.5)
    active = np.nonzero((fa != 0) & (fb != 0))[0]
    eps = np.finfo(np.float64).eps
    for _ in range(MAX_ITER):
        if active.size == 0:
            break
        A, B, C = a[active], b[active], c[active]
        FA, FB, FC = fa[active], fb[active], fc[active]
        T = t[active]
        xt = A + T * (B - A)
        ft = func(xt, active)
        same = np.sign(ft) == np.sign(FA)
        C = np.where(same, A, B)
        FC = np.where(same, FA, FB)
        B = np.where(same, B, A)
        FB = np.where(same, FB, FA)
        A, FA = xt, ft
        use_a = np.abs(FA) < np.abs(FB)
        xm = np.where(use_a, A, B)
        fm = np.where(use_a, FA, FB)
        tol = 2.0 * eps * np.abs(xm) + 0.5 * xtol
        width = np.abs(B - C)
        with np.errstate(divide="ignore", invalid="ignore"):
            tlim = tol / width
            done = (fm == 0) | (tlim > 0.5) | ~np.isfinite(ft)
            xi = (A - B) / (C - B)
            phi = (FA - FB) / (FC - FB)
            iqi = (phi**2 < xi) & ((1.0 - phi) ** 2 < 1.0 - xi)
            t_iqi = FA / (FB - FA) * FC / (FB - FC) + (C - A) / (B - A) * FA / (FC - FA) * FB / (FC - FB)
        T = np.where(iqi, t_iqi, 0.5)
        T = np.clip(np.nan_to_num(T, nan=0.5), tlim, 1.0 - tlim)
        a[active], b[active], c[active] = A, B, C
        fa[active], fb[active], fc[active] = FA, FB, FC
        t[active] = T
        x[active] = xm
        active = active[~done]
    return x
