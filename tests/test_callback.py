"""A reduction without compiled kernels, searched by the compiled engine through callbacks (sweepik.engine.callback):
the same candidates as the NumPy reference search, its errors raised (never a silent wrong answer), nothing kept
after a search."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import numpy_sweep
from oracles.numpy_engine import numpy_reduction

import sweepik
from sweepik.engine import callback, candidates, chunk, search
from sweepik.reductions import CArmD1, get_reduction

CARM = sweepik.load_robot("carm")


def _chain(n: int, seed: int) -> np.ndarray:
    q = np.random.default_rng(seed).uniform(CARM.lower, CARM.upper, (n, 6))
    return chunk.chain_poses(CARM, CARM.fk(q))


@pytest.mark.parametrize("name", ["carm-d1", "carm-theta2"])
def test_called_back_search_finds_the_kernels_candidates(name: str) -> None:
    """The reduction's NumPy residual called back from the search gives the candidates its compiled kernel gives:
    the same (pose, branch, multiplicity) rows, theta* within 1e-9 of its range (the two residuals differ in
    rounding); on random poses and the C-Arm's singular set (theta5 = 0, theta2 = 90 deg)."""
    red = get_reduction(CARM, name)
    q = np.random.default_rng(1).uniform(CARM.lower, CARM.upper, (60, 6))
    q[:15, 4] = 0.0
    q[15:25, 1] = np.pi / 2
    chain = chunk.chain_poses(CARM, CARM.fk(q))
    lo, hi = chunk.theta_range(CARM, red, chain)
    a, _ = search.search(red, chain, lo, hi, 64)
    b, _ = search.search(numpy_reduction(red), chain, lo, hi, 64)
    assert a.theta.size >= 2 * len(chain)
    oa = np.lexsort((a.theta, a.branch, a.pose))
    ob = np.lexsort((b.theta, b.branch, b.pose))
    for x, y in ((a.pose, b.pose), (a.branch, b.branch), (a.mult, b.mult)):
        np.testing.assert_array_equal(x[oa], y[ob])
    assert np.all(np.abs(a.theta[oa] - b.theta[ob]) <= 1e-9 * (hi - lo)[a.pose[oa]])


def test_called_back_search_finds_the_reference_roots() -> None:
    """Against the NumPy reference search (tests/oracles/numpy_sweep.py) on carm-theta2 without its kernel: every
    root one finds (a candidate where the residual vanishes), the other finds on the same branch within 1e-6 rad (the
    two place a pair of close roots differently by up to ~1e-7)."""
    red = numpy_reduction(get_reduction(CARM, "carm-theta2"))
    q = np.random.default_rng(1).uniform(CARM.lower, CARM.upper, (60, 6))
    chain = chunk.chain_poses(CARM, CARM.fk(q))
    lo, hi = chunk.theta_range(CARM, red, chain)
    got, _ = search.search(red, chain, lo, hi, 64)
    ref, _ = candidates.twin_copies(red, *numpy_sweep.find_candidates(red, chain, lo, hi, 64))
    for a, b in ((got, ref), (ref, got)):
        f = red.residual_rows(chain, a.pose, a.theta[:, None], a.branch[:, None])[:, 0]
        for k in np.nonzero(np.abs(f) <= 1e-9)[0]:  # (the roots; not the samples at the range's ends)
            same = (b.pose == a.pose[k]) & (b.branch == a.branch[k])
            d = np.abs(b.theta[same] - a.theta[k])
            assert same.any() and np.minimum(d, 2.0 * np.pi - d).min() <= 1e-6, (a.pose[k], a.theta[k])


class _Failing(CArmD1):
    """carm-d1 in NumPy whose residual fails at a single theta* (the refinements' calls back), not on the grid."""

    name = "failing"

    def residual(self, poses, theta, branch=None):  # type: ignore[no-untyped-def]
        if np.size(theta) == 1:
            raise ZeroDivisionError("the reduction's own error")
        return super().residual(poses, theta, branch)


def test_an_error_in_a_called_back_residual_is_raised_by_solve() -> None:
    red = _Failing(CARM)
    assert not red.uses_kernel
    T = CARM.fk(np.array([[700.0, 0.4, 0.3, -0.5, 0.6, 0.2], [300.0, -0.2, 0.1, 0.5, -0.6, 1.0]]))
    with pytest.raises(ZeroDivisionError, match="own error"):
        sweepik.solve_many(CARM, T, reduction=red)
    assert not callback._SEARCHES  # (the registration is gone after the failure)
    sweepik.solve_many(CARM, T, reduction=numpy_reduction(get_reduction(CARM, "carm-d1")))
    assert not callback._SEARCHES
