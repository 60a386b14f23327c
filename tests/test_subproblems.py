"""Subproblems against brute force: every returned solution solves its equation, every solution found by a dense
scan is returned, least-squares answers are the scan's minimum, degenerate cases are flagged."""

from __future__ import annotations

import numpy as np
import pytest

from sweepik.model.chain import rotation_about
from sweepik.subproblems import in_domain, lines2, lines3, lp1, lp3, lp4, sp1, sp2, sp3, sp4, sp5, sp6, trig2_roots

RNG = np.random.default_rng(20261123)
GRID = np.linspace(-np.pi, np.pi, 20001)


def _t(v):
    return tuple(float(x) for x in v)


def _unit(rng=RNG):
    v = rng.normal(size=3)
    return v / np.linalg.norm(v)


def _R(k, th):
    return rotation_about(np.asarray(k), th)


def _ang(a, b):
    return abs(np.angle(np.exp(1j * (a - b))))


def _scan_roots(f):
    """Angles where f (vectorised over GRID) changes sign or touches zero."""
    v = f(GRID)
    i = np.nonzero(np.sign(v[1:]) != np.sign(v[:-1]))[0]
    return GRID[i]


@pytest.mark.parametrize("seed", range(40))
def test_sp1_exact_and_least_squares(seed):
    rng = np.random.default_rng(seed)
    k, p1 = _unit(rng), rng.normal(size=3)
    th = rng.uniform(-np.pi, np.pi)
    p2 = _R(k, th) @ p1
    got, err = sp1(_t(p1), _t(p2), _t(k))
    assert _ang(got, th) < 1e-10 and err < 1e-12
    # least squares: the minimiser of |R p1 - p2| over a dense grid
    q = p2 + rng.normal(size=3)
    got, err = sp1(_t(p1), _t(q), _t(k))
    errs = np.linalg.norm(np.einsum("nij,j->ni", _R(k, GRID), p1) - q, axis=1)
    assert err <= errs.min() + 1e-9
    assert abs(err - np.linalg.norm(_R(k, got) @ p1 - q)) < 1e-12


@pytest.mark.parametrize("seed", range(40))
def test_sp4_matches_scan(seed):
    rng = np.random.default_rng(seed)
    h, p, k = rng.normal(size=3), rng.normal(size=3), _unit(rng)
    d = float(h @ _R(k, rng.uniform(-np.pi, np.pi)) @ p) if seed % 3 else float(rng.normal())

    def f(th):
        return np.einsum("j,nji,i->n", h, _R(k, th), p) - d

    a, b, c, _ = sp4(_t(h), _t(p), _t(k), d)
    roots = _scan_roots(f)
    if in_domain(c):
        for th in (a, b):
            assert abs(f(np.array([th]))[0]) < 1e-9 * (1 + np.linalg.norm(h) * np.linalg.norm(p))
        for r in roots:  # every root of the scan is returned
            assert min(_ang(r, a), _ang(r, b)) < 1e-3
    else:
        assert roots.size == 0
        assert a == b
        vals = np.abs(f(GRID))
        assert abs(f(np.array([a]))[0]) <= vals.min() + 1e-9


@pytest.mark.parametrize("seed", range(30))
def test_sp3_and_sp2_exact(seed):
    rng = np.random.default_rng(seed)
    k1, k2, p1, p2 = _unit(rng), _unit(rng), rng.normal(size=3), rng.normal(size=3)
    th = rng.uniform(-np.pi, np.pi)
    d = float(np.linalg.norm(_R(k1, th) @ p1 - p2))
    a, b, c, _ = sp3(_t(p1), _t(p2), _t(k1), d)
    assert in_domain(c)
    assert min(_ang(a, th), _ang(b, th)) < 1e-7
    for x in (a, b):
        assert abs(np.linalg.norm(_R(k1, x) @ p1 - p2) - d) < 1e-10
    # two circles: p2 chosen so that R(k1, t1) p1 = R(k2, t2) p2 has the solution (t1, t2)
    t1, t2 = rng.uniform(-np.pi, np.pi, size=2)
    q2 = _R(k2, -t2) @ _R(k1, t1) @ p1
    t1a, t2a, t1b, t2b, c, _ = sp2(_t(p1), _t(q2), _t(k1), _t(k2))
    assert in_domain(c)
    found = [(t1a, t2a), (t1b, t2b)]
    for x1, x2 in found:
        np.testing.assert_allclose(_R(k1, x1) @ p1, _R(k2, x2) @ q2, atol=1e-10)
    assert min(max(_ang(x1, t1), _ang(x2, t2)) for x1, x2 in found) < 1e-7


def test_degenerate_cases_are_flagged():
    z = (0.0, 0.0, 1.0)
    # a point on the axis: any angle (0), residual 0
    th, err = sp1((0.0, 0.0, 2.0), (0.0, 0.0, 2.0), z)
    assert th == 0.0 and err == 0.0
    # h parallel to the axis: h . R p does not depend on theta
    a, b, c, _ = sp4(z, (1.0, 0.0, 0.5), z, 0.5)
    assert np.isnan(c)
    # tangent: one double solution (both equal), at the domain edge
    a, b, c, _ = sp4((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), z, 1.0)
    assert in_domain(c) and abs(a - b) < 1e-12 and abs(c - 1.0) < 1e-15
    # just outside: no exact solution, the least-squares angle twice
    a, b, c, _ = sp4((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), z, 1.0 + 1e-6)
    assert not in_domain(c) and a == b == 0.0


@pytest.mark.parametrize("seed", range(30))
def test_line_subproblems(seed):
    rng = np.random.default_rng(seed)
    h, p1, p2 = _unit(rng), rng.normal(size=3), rng.normal(size=3)
    t = rng.normal()
    # line-point
    got, err = lp1(_t(p1), _t(p1 + t * h), _t(h))
    assert abs(got - t) < 1e-12 and err < 1e-12
    # line-sphere: both intersections, each at distance d
    d = float(np.linalg.norm(p1 + t * h - p2))
    a, b, disc = lp3(_t(p1), _t(p2), _t(h), d)
    assert disc >= 0.0 and min(abs(a - t), abs(b - t)) < 1e-9
    for x in (a, b):
        assert abs(np.linalg.norm(p1 + x * h - p2) - d) < 1e-9
    # line-sphere miss: the closest point, twice
    far = np.linalg.norm(np.cross(h, p1 - p2)) * 0.5
    a, b, disc = lp3(_t(p1), _t(p2), _t(h), float(far))
    assert disc < 0 and a == b
    ts = np.linspace(-20, 20, 400001)
    assert abs(a - ts[np.argmin(np.linalg.norm(p1 + ts[:, None] * h - p2, axis=1))]) < 1e-3
    # line-plane
    k = _unit(rng)
    dd = float(k @ (p1 + t * h))
    assert abs(lp4(_t(k), _t(p1), _t(h), dd) - t) < 1e-9 * (1 + 1 / abs(k @ h))
    assert np.isnan(lp4((0.0, 0.0, 1.0), _t(p1), (1.0, 0.0, 0.0), 1.0))
    # two and three lines
    h2, h3 = _unit(rng), _unit(rng)
    t1, t2, t3 = rng.normal(size=3)
    np.testing.assert_allclose(lines2(_t(h), _t(h2), _t(t1 * h + t2 * h2)), (t1, t2), atol=1e-9)
    np.testing.assert_allclose(lines3(_t(h), _t(h2), _t(h3), _t(t1 * h + t2 * h2 + t3 * h3)), (t1, t2, t3), atol=1e-8)
    assert np.isnan(lines2(_t(h), _t(h), _t(h))[0])


# ---------------------------------------------------------------------------------------------------------
# SP5 and SP6: a trigonometric polynomial of degree 2
# ---------------------------------------------------------------------------------------------------------


def _trig(c, t):
    a0, a1, b1, a2, b2 = c
    return a0 + a1 * np.cos(t) + b1 * np.sin(t) + a2 * np.cos(2 * t) + b2 * np.sin(2 * t)


@pytest.mark.parametrize("seed", range(60))
def test_trig2_roots_match_scan(seed):
    rng = np.random.default_rng(seed)
    c = rng.normal(size=5)
    if seed % 4 == 0:
        c[3:] = 0.0  # degree 1
    if seed % 5 == 0:  # a root at pi exactly
        c[0] -= _trig(c, np.pi)
    roots, n = trig2_roots(*c)
    assert n == np.count_nonzero(np.isfinite(roots))
    for t in roots[:n]:
        assert abs(_trig(c, t)) < 1e-10 * np.abs(c).max()
    scan = _scan_roots(lambda t: _trig(c, t))
    if seed % 5 != 0:  # (a root at the scan's end points is seen twice or not at all)
        assert n == len(scan)
    for t in scan:
        assert min(_ang(t, r) for r in roots[:n]) < 1e-3


def test_trig2_roots_double_root_and_degenerate():
    # (cos t - 0.3)^2 - 0: a double root pair at +-acos(0.3)
    c0, c1 = 0.3, 1.0
    # (cos t - c0)^2 = cos^2 - 2 c0 cos + c0^2 = 0.5 + 0.5 cos 2t - 2 c0 cos + c0^2
    roots, n = trig2_roots(0.5 + c0 * c0, -2 * c0, 0.0, 0.5 * c1, 0.0)
    assert n == 2 and np.allclose(np.sort(np.abs(roots[:2])), [np.arccos(0.3)] * 2, atol=1e-7)
    assert trig2_roots(0.0, 0.0, 0.0, 0.0, 0.0)[1] == -1
    # two distinct roots 6e-7 apart are two: (cos(t - 0.4) - cos(3e-7)) (cos(t + 2) - 0.3)
    d = 3e-7
    t = np.linspace(-np.pi, np.pi, 9)[:-1]
    vals = (np.cos(t - 0.4) - np.cos(d)) * (np.cos(t + 2) - 0.3)
    basis = np.stack([np.ones_like(t), np.cos(t), np.sin(t), np.cos(2 * t), np.sin(2 * t)], axis=1)
    coef = np.linalg.lstsq(basis, vals, rcond=None)[0]
    roots, n = trig2_roots(*coef)
    assert n == 4
    assert np.sum(np.abs(roots[:n] - (0.4 - d)) < 1e-8) == 1 and np.sum(np.abs(roots[:n] - (0.4 + d)) < 1e-8) == 1
    assert trig2_roots(1.0, 0.0, 0.0, 0.0, 0.0)[1] == 0


def test_companion_roots_are_numba_np_roots():
    """trig2_roots' eigenvalue step is Numba's np.roots without its general-purpose checks: the same companion matrix
    and LAPACK call, so the same roots to the bit (quadratics and quartics, some with zero inner coefficients)."""
    from numba import njit

    from sweepik.subproblems.trig import _companion_roots

    @njit
    def ours(c):
        return _companion_roots(c, c.shape[0])

    @njit
    def numba_roots(c):
        return np.roots(c)

    rng = np.random.default_rng(7)
    for trial in range(2000):
        c = rng.normal(size=5 if trial % 3 else 3) + 1j * rng.normal(size=5 if trial % 3 else 3)
        if trial % 7 == 0:
            c[1] = 0.0
        if trial % 11 == 0:
            c = np.round(c, 1) + (0.05 + 0.05j)  # (first and last coefficients stay nonzero)
        assert ours(c).tobytes() == numba_roots(c).tobytes(), c


def _sp6_data(rng):
    return [(rng.normal(size=3), _unit(rng), rng.normal(size=3)) for _ in range(4)]


def _sp6_residual(data, d, t1, t2):
    (h1, k1, p1), (h2, k2, p2), (h3, k3, p3), (h4, k4, p4) = data
    r1 = h1 @ _R(k1, t1) @ p1 + h2 @ _R(k2, t2) @ p2 - d[0]
    r2 = h3 @ _R(k3, t1) @ p3 + h4 @ _R(k4, t2) @ p4 - d[1]
    return r1, r2


def _sp6(data, d):
    args = [_t(v) for hkp in data for v in hkp]
    return sp6(*args, float(d[0]), float(d[1]))


@pytest.mark.parametrize("seed", range(40))
def test_sp6_recovers_constructed_solution(seed):
    rng = np.random.default_rng(seed)
    data = _sp6_data(rng)
    t1, t2 = rng.uniform(-np.pi, np.pi, 2)
    d = np.array(_sp6_residual(data, (0.0, 0.0), t1, t2))
    a, b, n = _sp6(data, d)
    assert 1 <= n <= 4
    for x, y in zip(a[:n], b[:n], strict=True):
        assert np.max(np.abs(_sp6_residual(data, d, x, y))) < 1e-9
    assert min(_ang(x, t1) + _ang(y, t2) for x, y in zip(a[:n], b[:n], strict=True)) < 1e-8


def _turned(v, k, p, t):
    """``v . Rot(k, t) p`` for angles ``t`` (array), by Rodrigues' formula (NumPy, independent of the subproblems)."""
    v, k, p = (np.asarray(x, dtype=float) for x in (v, k, p))
    return (v @ p - (v @ k) * (k @ p)) * np.cos(t) + (v @ np.cross(k, p)) * np.sin(t) + (v @ k) * (k @ p)


def _solve_turned(h, k, p, d):
    """Both ``t`` with ``h . Rot(k, t) p = d`` for each ``d`` (array; NaN where there is none), in NumPy."""
    h, k, p = (np.asarray(x, dtype=float) for x in (h, k, p))
    a, b = h @ p - (h @ k) * (k @ p), h @ np.cross(k, p)
    with np.errstate(invalid="ignore"):
        half = np.arccos((d - (h @ k) * (k @ p)) / np.hypot(a, b))
    phi = np.arctan2(b, a)
    return phi + half, phi - half


@pytest.mark.parametrize("seed", range(40))
def test_sp6_matches_scan(seed):
    """Brute force: theta2 from the first equation on a dense theta1 grid (both of its branches, in NumPy), the
    second's sign changes. Every root the scan finds is returned, and every returned pair solves both equations (the
    scan can miss a root where the first equation's two branches meet, so it bounds the count from below)."""
    rng = np.random.default_rng(100 + seed)
    data = _sp6_data(rng)
    d = rng.normal(size=2)
    a, b, n = _sp6(data, d)
    (h1, k1, p1), (h2, k2, p2), (h3, k3, p3), (h4, k4, p4) = data
    found = []
    for t2 in _solve_turned(h2, k2, p2, d[0] - _turned(h1, k1, p1, GRID)):
        g = _turned(h3, k3, p3, GRID) + _turned(h4, k4, p4, t2) - d[1]
        ok = np.isfinite(g[1:]) & np.isfinite(g[:-1])
        found += list(GRID[:-1][ok & (np.sign(g[1:]) != np.sign(g[:-1]))])
    assert len(found) <= n <= 4
    for t in found:
        assert min(_ang(x, t) for x in a[:n]) < 1e-3
    for x, y in zip(a[:n], b[:n], strict=True):
        assert np.max(np.abs(_sp6_residual(data, d, x, y))) < 1e-9


def test_sp6_degenerate():
    z = (0.0, 0.0, 1.0)
    # every p on its axis: no equation depends on an angle
    t1, t2, n = sp6(z, z, z, z, z, z, z, z, z, z, z, z, 1.0, 1.0)
    assert n == -1 and np.all(np.isnan(t1)) and np.all(np.isnan(t2))


@pytest.mark.parametrize("seed", range(40))
def test_sp5_recovers_constructed_solution(seed):
    rng = np.random.default_rng(seed)
    p1, p2, p3 = rng.normal(size=(3, 3))
    k1, k2, k3 = _unit(rng), _unit(rng), _unit(rng)
    t1, t2, t3 = rng.uniform(-np.pi, np.pi, 3)
    p0 = _R(k2, t2) @ (p2 + _R(k3, t3) @ p3) - _R(k1, t1) @ p1
    a, b, c, n = sp5(_t(p0), _t(p1), _t(p2), _t(p3), _t(k1), _t(k2), _t(k3))
    assert 1 <= n <= 4
    for x, y, w in zip(a[:n], b[:n], c[:n], strict=True):
        miss = p0 + _R(k1, x) @ p1 - _R(k2, y) @ (p2 + _R(k3, w) @ p3)
        assert np.linalg.norm(miss) < 1e-9
    assert min(_ang(x, t1) + _ang(y, t2) + _ang(w, t3) for x, y, w in zip(a[:n], b[:n], c[:n], strict=True)) < 1e-8
