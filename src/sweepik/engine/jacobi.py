"""The least-squares step ``pinv(A) @ e`` of a small matrix (a 6 x n Jacobian) through its singular value
decomposition by one-sided Jacobi rotations (Hestenes), compiled, for the Newton steps of the polish and of traced
continua; and the singular values themselves (``singular_values``: the crossing search's second least one along a
family, ``engine.crossings``).

Why not ``np.linalg.pinv`` inside the kernels: for a 6 x 6 matrix its LAPACK call (``gesdd``, with Numba's copies
and work arrays) costs ~12 us on this machine, about ten times the arithmetic; a traced continuum's correction made
four to seven of them, and a singular pose's solve traced hundreds (docs/performance.md). The rotations need no
allocation and give the singular values to high relative accuracy (a one-sided Jacobi SVD is at least as accurate as
the QR-based one, Demmel & Veselic 1992), so that the cut-off ``rcond`` drops the same directions (but for a
singular value at the cut-off itself, where the two may decide apart).

The columns of ``B = A`` are rotated in pairs until every pair is orthogonal to ``ORTHOGONAL`` (relative), the same
rotations accumulated in ``V``: then ``A = B V^T`` with orthogonal columns ``b_k = sigma_k u_k`` and
``pinv(A) e = sum_k v_k (b_k . e) / sigma_k^2`` over the ``sigma_k`` above ``rcond`` times the largest.
"""

from __future__ import annotations

import math

from sweepik._jit import inlined

#: Two columns count as orthogonal when their inner product is at most this fraction of the product of their norms.
ORTHOGONAL = 1e-15
#: Sweeps over every pair at most (a 6 x 7 matrix needs 5 to 8; the cap only guards against a NaN).
MAX_SWEEPS = 40


@inlined
def _rotate_pairs(B, V):
    """One sweep of rotations over every pair of columns of ``B`` (and ``V``): whether any was rotated."""
    m, n = B.shape
    rotated = False
    for p in range(n - 1):
        for q in range(p + 1, n):
            alpha = beta = gamma = 0.0
            for i in range(m):
                alpha += B[i, p] * B[i, p]
                beta += B[i, q] * B[i, q]
                gamma += B[i, p] * B[i, q]
            if not abs(gamma) > ORTHOGONAL * math.sqrt(alpha * beta):  # (also for a zero column, and NaN)
                continue
            zeta = (beta - alpha) / (2.0 * gamma)
            t = math.copysign(1.0, zeta) / (abs(zeta) + math.sqrt(1.0 + zeta * zeta))
            if t == 0.0:  # (a rotation below rounding)
                continue
            c = 1.0 / math.sqrt(1.0 + t * t)
            s = c * t
            rotated = True
            for i in range(m):
                bp, bq = B[i, p], B[i, q]
                B[i, p], B[i, q] = c * bp - s * bq, s * bp + c * bq
            for i in range(n):
                vp, vq = V[i, p], V[i, q]
                V[i, p], V[i, q] = c * vp - s * vq, s * vp + c * vq
    return rotated


@inlined
def decompose(A, B, V, warm=False):
    """``A (m, n)`` as ``B V^T``: ``B (m, n)`` with orthogonal columns (``sigma_k u_k``), ``V (n, n)`` orthogonal
    (both overwritten). ``warm``: start from the ``V`` given (orthogonal: the last decomposition's), ``B = A V``:
    for a matrix close to the last one (a Newton step's next Jacobian) its columns are nearly orthogonal already,
    and one or two sweeps finish them."""
    m, n = A.shape
    if warm:
        for i in range(m):
            for k in range(n):
                s = 0.0
                for j in range(n):
                    s += A[i, j] * V[j, k]
                B[i, k] = s
    else:
        for i in range(m):
            for k in range(n):
                B[i, k] = A[i, k]
        for i in range(n):
            for k in range(n):
                V[i, k] = 1.0 if i == k else 0.0
    for _ in range(MAX_SWEEPS):
        if not _rotate_pairs(B, V):
            break


@inlined
def solve(B, V, e, rcond, out):
    """``out (n,) = pinv(A) @ e`` from ``A``'s :func:`decompose` ``(B, V)``: singular values at most ``rcond`` times
    the largest dropped (``np.linalg.pinv``'s rule); NaN where ``A`` holds a NaN."""
    m, n = B.shape
    largest = 0.0
    for k in range(n):
        s2 = 0.0
        for i in range(m):
            s2 += B[i, k] * B[i, k]
        if s2 != s2:  # (a NaN in A: no step)
            for i in range(n):
                out[i] = math.nan
            return
        largest = max(largest, s2)
    cut = rcond * rcond * largest  # (squared: sigma_k > rcond * sigma_max)
    for k in range(n):
        out[k] = 0.0
    for k in range(n):
        s2 = be = 0.0
        for i in range(m):
            s2 += B[i, k] * B[i, k]
            be += B[i, k] * e[i]
        if not s2 > cut or s2 == 0.0:
            continue
        coef = be / s2
        for i in range(n):
            out[i] += coef * V[i, k]


@inlined
def pinv_step(A, e, rcond, B, V, out):
    """``out (n,) = pinv(A) @ e`` for ``A (m, n)``, ``e (m,)`` (``B (m, n)``, ``V (n, n)``: work arrays)."""
    decompose(A, B, V)
    solve(B, V, e, rcond, out)


@inlined
def singular_values(A, B, V, out, warm=False):
    """``out (min(m, n),)``: the singular values of ``A (m, n)``, decreasing (``np.linalg.svd``'s), from
    :func:`decompose` (``B``, ``V``: work arrays; ``warm``: as there): the norms of ``B``'s columns, the largest
    ``min(m, n)``."""
    m, n = A.shape
    decompose(A, B, V, warm)
    r = min(m, n)
    for k in range(r):
        out[k] = -1.0
    for k in range(n):  # (an insertion into the largest r so far)
        s2 = 0.0
        for i in range(m):
            s2 += B[i, k] * B[i, k]
        x = math.sqrt(s2)
        if x != x:  # (a NaN in A: no values)
            for i in range(r):
                out[i] = math.nan
            return
        j = r - 1
        if not x > out[j]:
            continue
        while j > 0 and x > out[j - 1]:
            out[j] = out[j - 1]
            j -= 1
        out[j] = x
