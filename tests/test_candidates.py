"""The candidate set and the sample grid (sweepik.engine.candidates): the grid holds the uniform samples and every
hint inside the range, sorted, without repeats; twin branches get the first branch's roots, pose by pose, in order;
spans concatenate."""

from __future__ import annotations

import numpy as np

from sweepik import load_robot
from sweepik.engine.candidates import Candidates, Spans, merge_grid, twin_candidates
from sweepik.reductions import CArmD1


def test_the_grid_holds_the_uniform_samples_and_the_hints_in_range() -> None:
    """Sorted rows, strictly increasing (a hint on the grid or repeated is spread, not duplicated), every uniform
    sample and every finite hint inside ``[lo, hi]`` present (to the spreading), the row as long as the uniform grid
    plus the hints."""
    rng = np.random.default_rng(0)
    N, n = 200, 17
    lo = rng.uniform(-3.0, 0.0, N)
    hi = lo + rng.uniform(0.5, 4.0, N)
    uniform = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n)[None, :]
    hints = np.where(rng.random((N, 6)) < 0.5, uniform[:, rng.integers(0, n, 6)], rng.uniform(-4.0, 5.0, (N, 6)))
    hints[:, 5] = hints[:, 4]  # a repeated hint
    hints[rng.random((N, 6)) < 0.2] = np.nan
    grid = merge_grid(lo, hi, n, hints)
    assert grid.shape == (N, n + 6)
    assert np.all(np.diff(grid, axis=1) > 0)
    assert np.all(grid >= lo[:, None]) and np.all(grid <= hi[:, None])
    step = ((hi - lo) / (n - 1))[:, None]
    for want in (uniform, np.where((hints >= lo[:, None]) & (hints <= hi[:, None]), hints, np.nan)):
        d = np.abs(grid[:, None, :] - want[:, :, None]).min(axis=2)
        assert np.all(d[np.isfinite(want)] <= 0.5 * step.repeat(want.shape[1], 1)[np.isfinite(want)])


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
