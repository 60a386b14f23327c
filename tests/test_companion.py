"""A second decomposition's solutions joined to the first's (sweepik.engine.companion): the union of the two
answers pose by pose, without duplicates, the first answer's rows first."""

from __future__ import annotations

import dataclasses

import numpy as np

from sweepik import load_robot, solve_many
from sweepik.engine.companion import joined
from sweepik.reductions import GeometricReduction
from sweepik.reductions.plan import plans
from sweepik.results import Block


def _without_last(block: Block) -> Block:
    """``block`` with each pose's last solution left out."""
    keep = np.ones(block.q.shape[0], dtype=bool)
    ends = block.bounds[1:][np.diff(block.bounds) > 0]
    keep[ends - 1] = False
    counts = np.add.reduceat(keep, block.bounds[:-1]) if keep.size else np.zeros(block.n, dtype=np.intp)
    counts = np.where(np.diff(block.bounds) > 0, counts, 0)
    return dataclasses.replace(
        block,
        bounds=np.concatenate([[0], np.cumsum(counts)]).astype(np.intp),
        q=block.q[keep],
        error=block.error[keep],
        error_geodesic=block.error_geodesic[keep],
        within_limits=block.within_limits[keep],
        multiplicity=block.multiplicity[keep],
    )


def test_joined_is_the_union_without_duplicates() -> None:
    """The PUMA 560's closed form and one of its sweeps solve the same poses. The closed form's answer with each
    pose's last solution left out, joined with the sweep's, gives every solution back once (the first answer's rows
    first); an answer joined with itself is itself."""
    robot = load_robot("puma560")
    sweep = next(p for p in plans(robot) if not p.closed_form)
    rng = np.random.default_rng(1)
    poses = robot.fk(rng.uniform(robot.lower, robot.upper, (12, 6)))
    a = solve_many(robot, poses, limits=False)
    b = solve_many(robot, poses, limits=False, reduction=GeometricReduction(robot, sweep))
    (block_a,), (block_b,) = a.blocks, b.blocks
    assert joined(block_a, block_a) is block_a
    short = _without_last(block_a)
    both = joined(short, block_b)
    for i in range(len(poses)):
        mine = both.solutions(i)
        assert len(a[i]) == len(b[i]) == len(mine) > 0
        np.testing.assert_array_equal(mine.q[:-1], short.solutions(i).q)
        for q in a[i].q:  # every solution once
            d = np.abs(mine.q - q)
            d = np.minimum(d % (2 * np.pi), -d % (2 * np.pi))
            assert np.sum(np.max(d, axis=1) < 1e-6) == 1
