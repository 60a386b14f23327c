"""A second decomposition's solutions joined to the first's (sweepik.engine.companion): the union of the two
answers pose by pose, without duplicates, the first answer's rows first."""

from __future__ import annotations

import dataclasses

import numpy as np

from sweepik import load_robot, solve, solve_many
from sweepik.engine.companion import joined
from sweepik.engine.families import off_families
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


def test_a_companion_adds_no_member_of_the_first_answers_families() -> None:
    """A companion's solution on one of the first answer's families is reported by the family, not as a row. The
    iiwa held at A5 = -170 deg, a pose with four self-motion families (A2 = A6 = 0): after a value near 0 (whose plan
    the next values take as their companion: ``reductions.automatic_for_held``) the companion's four isolated
    solutions, members of those families, were added as rows (6 rows where a fresh process gave 2)."""
    robot = load_robot("kuka_iiwa14")
    q = np.array([1.1835548360898351, 0.0, 0.11879735902081068, -1.7997463918365746, -2.9670597283903604, 0.0, 1.26])
    other = np.array([0.3, 0.5, -0.2, 0.8, 1e-9, 0.6, 0.1])
    solve(robot, robot.fk(other), locked={"A5": 1e-9})
    sol = solve(robot, robot.fk(q), locked={"A5": q[4]})
    assert len(sol.families) == 4 and len(sol) == 2
    assert off_families(robot, [(sol.q, sol.families)])[0].all()
    # the pose is reached: by the rows and by the families
    for s in sol.q:
        assert np.allclose(robot.fk(s), robot.fk(q), atol=1e-9)


def test_without_the_solved_arm_two_near_solutions_are_handed_on() -> None:
    """``meetings=False`` (blocks of another arm than the solved one, ``engine.held_joined``): a companion's solution
    within ``MEET_REL`` of one of the first's but not its duplicate may be the same root, which only the solved arm
    settles: None; a duplicate is left out as ever."""
    robot = load_robot("puma560")
    (block,) = solve_many(robot, robot.fk(np.array([[0.3, -0.4, 0.5, 0.6, 0.7, 0.8]])), limits=False).blocks
    near, same = block.q.copy(), block.q.copy()
    near[0, 0] += 1e-4  # (within MEET_REL, past the duplicate tolerance)
    same[:, 0] += 1e-8
    assert joined(block, dataclasses.replace(block, q=near), meetings=False) is None
    assert joined(block, dataclasses.replace(block, q=near)) is not None
    both = joined(block, dataclasses.replace(block, q=same), meetings=False)
    assert both is not None and both.q.shape == block.q.shape
