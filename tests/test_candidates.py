"""The candidate set and the sample grid (sweepik.engine.candidates): the grid holds the uniform samples and every
hint inside the range, sorted, without repeats; twin branches get the first branch's roots, pose by pose, in order;
spans concatenate."""

from __future__ import annotations

import numpy as np

from sweepik import load_robot
from sweepik.engine import search
from sweepik.engine.candidates import Candidates, Spans, twin_candidates
from sweepik.reductions import CArmD1


def test_the_grid_holds_the_uniform_samples_and_the_hints_in_range() -> None:
    """The engine's sample grid (``search.sample_grid`` over a reduction's ``sample_hints``): each pose's samples
    sorted, strictly increasing (a hint on the grid or repeated is spread, not duplicated), inside ``[lo, hi]``,
    every uniform sample and every finite hint inside the range present (to the spreading), no sample for a NaN
    hint, theta*'s own limits added, NaN past the pose's count."""
    rng = np.random.default_rng(0)
    N, n = 200, 17
    lo = rng.uniform(-3.0, 0.0, N)
    hi = lo + rng.uniform(0.5, 4.0, N)
    uniform = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    hints = np.where(rng.random((N, 6)) < 0.5, uniform[:, rng.integers(0, n, 6)], rng.uniform(-4.0, 5.0, (N, 6)))
    hints[:, 5] = hints[:, 4]  # a repeated hint
    hints[rng.random((N, 6)) < 0.2] = np.nan

    class Hinted(CArmD1):
        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return hints

    grid, count = search.sample_grid(Hinted(load_robot("carm")), np.broadcast_to(np.eye(4), (N, 4, 4)), lo, hi, n)
    np.testing.assert_array_equal(count, n + np.isfinite(hints).sum(axis=1) + 2)  # (+ the rail's two limits)
    step = (hi - lo) / (n - 1)
    inside = np.where((hints >= lo[:, None]) & (hints <= hi[:, None]), hints, np.nan)
    for i in range(N):
        row = grid[i, : count[i]]
        assert np.all(np.diff(row) > 0) and row[0] >= lo[i] and row[-1] <= hi[i]
        assert np.isnan(grid[i, count[i] :]).all()
        for want in (uniform[i], inside[i][np.isfinite(inside[i])]):
            assert np.all(np.abs(row[None, :] - want[:, None]).min(axis=1) <= 0.5 * step[i])


def test_twin_branches_get_the_first_branchs_roots_in_pose_order() -> None:
    """carm-d1's twin classes (0, 3) and (1, 2): a root found on branch 0 (1) is a root of branch 3 (2) too, each
    pose's copies follow its own candidates, and the poses stay in order."""
    red = CArmD1(load_robot("carm"))
    cand = Candidates(
        pose=np.array([0, 0, 1, 2, 2], dtype=np.intp),
        branch=np.array([0, 1, 1, 0, 0], dtype=np.intp),
        theta=np.array([10.0, 20.0, 30.0, 40.0, 50.0]),
        mult=np.array([1, 2, 1, 1, 1], dtype=np.intp),
    )
    out = twin_candidates(red, cand)
    assert out.pose.tolist() == [0, 0, 0, 0, 1, 1, 2, 2, 2, 2]
    assert np.all(np.diff(out.pose) >= 0)
    rows = sorted(zip(out.pose.tolist(), out.branch.tolist(), out.theta.tolist(), out.mult.tolist(), strict=True))
    want = sorted(
        [(0, 0, 10.0, 1), (0, 3, 10.0, 1), (0, 1, 20.0, 2), (0, 2, 20.0, 2), (1, 1, 30.0, 1), (1, 2, 30.0, 1)]
        + [(2, 0, 40.0, 1), (2, 3, 40.0, 1), (2, 0, 50.0, 1), (2, 3, 50.0, 1)]
    )
    assert rows == want


def test_spans_concatenate_and_the_empty_spans_are_shared() -> None:
    a = Spans(np.array([0], dtype=np.intp), np.array([1], dtype=np.intp), np.array([0.1]), np.array([0.2]))
    b = Spans(
        np.array([3, 4], dtype=np.intp), np.array([0, 2], dtype=np.intp), np.array([1.0, 2.0]), np.array([1.5, 2.5])
    )
    both = Spans.concat([a, Spans.empty(), b])
    assert len(both) == 3 and both.pose.tolist() == [0, 3, 4] and both.hi.tolist() == [0.2, 1.5, 2.5]
    assert Spans.concat([a]) is a
    assert Spans.empty() is Spans.empty() and len(Spans.empty()) == 0
