"""The compiled least-squares step (``engine.jacobi``) against NumPy's pseudo-inverse: random, rank-deficient,
zero-column, wide and badly scaled matrices, every cut-off the polish uses."""

from __future__ import annotations

import numpy as np


def _step():  # type: ignore[no-untyped-def]
    import numba

    from sweepik.engine.jacobi import decompose, pinv_step, solve

    @numba.njit(cache=False)
    def step(A, e, rcond):  # type: ignore[no-untyped-def]
        m, n = A.shape
        out = np.empty(n)
        pinv_step(A, e, rcond, np.empty((m, n)), np.empty((n, n)), out)
        return out

    @numba.njit(cache=False)
    def singular_values(A):  # type: ignore[no-untyped-def]
        m, n = A.shape
        B, V = np.empty((m, n)), np.empty((n, n))
        decompose(A, B, V)
        out = np.empty(n)
        solve(B, V, np.zeros(m), 0.0, out)  # (compiles solve too)
        return np.sqrt(np.sum(B * B, axis=0)), V

    return step, singular_values


def _values():  # type: ignore[no-untyped-def]
    import numba

    from sweepik.engine.jacobi import singular_values

    @numba.njit(cache=False)
    def values(As, warm):  # type: ignore[no-untyped-def]
        K, m, n = As.shape
        B, V = np.empty((m, n)), np.empty((n, n))
        out = np.empty((K, min(m, n)))
        for k in range(K):
            singular_values(As[k], B, V, out[k], warm and k > 0)
        return out

    return values


def _matrices(rng: np.random.Generator, count: int) -> list[np.ndarray]:
    out = []
    for k in range(count):
        n = int(rng.choice([5, 6, 7]))
        A = rng.normal(size=(6, n)) * 10.0 ** rng.uniform(-3, 3, n)
        kind = k % 4
        if kind == 1:  # a held joint: its column zero
            A[:, rng.integers(n)] = 0.0
        elif kind == 2:  # a column nearly a combination of others
            A[:, 0] = 2.0 * A[:, 1] + A[:, 2] + rng.normal(size=6) * 10.0 ** rng.uniform(-14, -6)
        elif kind == 3:  # singular values spread over 14 decades
            U, _, Vt = np.linalg.svd(rng.normal(size=(6, n)), full_matrices=False)
            A = (U * 10.0 ** -np.sort(rng.uniform(0.0, 14.0, U.shape[1]))) @ Vt
        out.append(A)
    return out


def test_step_matches_numpy_pinv() -> None:
    step, _ = _step()
    rng = np.random.default_rng(7)
    checked = 0
    for A in _matrices(rng, 800):
        e = rng.normal(size=6)
        sv = np.linalg.svd(A, compute_uv=False)
        for rcond in (1e-10, 1e-6, 1e-3):
            if np.any(np.abs(sv / sv[0] - rcond) < 1e-3 * rcond):  # (a singular value at the cut-off: either is right)
                continue
            ref = np.linalg.pinv(A, rcond) @ e
            kept = sv[sv > rcond * sv[0]]
            bound = max(1e-13, 100 * np.finfo(float).eps * kept[0] / kept[-1])
            got = step(A, e, rcond)
            assert np.linalg.norm(got - ref) <= bound * max(np.linalg.norm(ref), 1e-300)
            checked += 1
    assert checked > 2000


def test_decomposition_is_orthogonal_with_the_singular_values() -> None:
    _, singular_values = _step()
    rng = np.random.default_rng(3)
    for A in _matrices(rng, 200):
        s, V = singular_values(A)
        assert np.allclose(V.T @ V, np.eye(V.shape[0]), atol=1e-13)
        ref = np.linalg.svd(A, compute_uv=False)
        got = np.sort(s)[::-1][: ref.size]
        assert np.allclose(got, ref, rtol=1e-12, atol=1e-15 * ref[0])


def test_zero_and_nan_matrices() -> None:
    step, _ = _step()
    assert np.all(step(np.zeros((6, 6)), np.ones(6), 1e-10) == 0.0)
    A = np.eye(6)
    A[2, 2] = np.nan
    assert not np.all(np.isfinite(step(A, np.ones(6), 1e-10)))  # (NaN in, not a silent finite answer)


def test_singular_values_decreasing_as_numpy_cold_and_warm() -> None:
    """``jacobi.singular_values``: NumPy's, decreasing, over 14 decades and for rank-deficient matrices; started from
    the last matrix's rotations (``warm``) along a path of neighbouring matrices, the same values; NaN in, NaN out."""
    values = _values()
    rng = np.random.default_rng(5)
    for A in _matrices(rng, 200):
        ref = np.linalg.svd(A, compute_uv=False)
        got = values(A[None], False)[0]
        assert np.all(np.diff(got) <= 0.0)
        assert np.allclose(got, ref, rtol=1e-12, atol=1e-15 * ref[0])
    A0, D = rng.normal(size=(6, 6)), rng.normal(size=(6, 6))
    path = np.array([A0 + t * D for t in np.linspace(0.0, 1e-2, 20)])
    path[:, :, 0] = path[:, :, 1] + path[:, :, 2]  # (rank 5: a continuum's Jacobian)
    cold, warm = values(path, False), values(path, True)
    ref = np.linalg.svd(path, compute_uv=False)
    assert np.allclose(warm, cold, rtol=1e-12, atol=1e-14 * ref[:, :1])
    assert np.allclose(warm, ref, rtol=1e-12, atol=1e-14 * ref[:, :1])
    bad = np.eye(6)
    bad[3, 3] = np.nan
    assert np.all(np.isnan(values(bad[None], False)))
