"""``solve_many`` returns a columnar ``SolutionBatch``: its columns and its per-pose ``Solutions`` say the same,
and both agree with ``solve`` pose by pose (regular poses, unreachable ones, out-of-limit ones, self-motion
families, several chunks)."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import in_limit_configurations

import sweepik
from sweepik.results import SolutionBatch


def _poses(robot, rng, n):
    Q = in_limit_configurations(robot, n, rng)
    T = robot.fk(Q)
    far = np.eye(4)
    far[:3, 3] = 10.0 * robot.length_scale  # unreachable
    return np.concatenate([T, far[None]])


@pytest.mark.parametrize("name", ["ur5", "carm", "fanuc_crx10ia"])
def test_columns_match_per_pose_solutions(name):
    robot = sweepik.load_robot(name)
    T = _poses(robot, np.random.default_rng(3), 40)
    batch = sweepik.solve_many(robot, T, chunk_size=16)  # several blocks
    assert isinstance(batch, SolutionBatch) and len(batch) == len(T)
    assert batch.offsets[0] == 0 and batch.offsets[-1] == batch.q.shape[0] == batch.pose_index.size
    assert np.array_equal(np.diff(batch.offsets), batch.counts)
    for i, t in enumerate(T):
        one = sweepik.solve(robot, t)
        s, e = batch.offsets[i], batch.offsets[i + 1]
        got = batch[i]
        assert np.array_equal(got.q, batch.q[s:e])
        # the same solutions as one pose alone (to rounding: batches run the parallel kernels)
        assert one.q.shape == got.q.shape and np.allclose(one.q, got.q, rtol=0, atol=1e-9)
        assert np.array_equal(got.error, batch.error[s:e]) and np.array_equal(
            got.error_geodesic, batch.error_geodesic[s:e]
        )
        assert np.array_equal(got.within_limits, batch.within_limits[s:e])
        assert np.array_equal(got.multiplicity, batch.multiplicity[s:e])
        assert np.all(batch.pose_index[s:e] == i)
        assert got.reason == one.reason == batch.reason(i)
        assert np.array_equal(got.pose, t)
    assert batch.reason(len(T) - 1).startswith("unreachable")
    # sequence behaviour: negative indices, slices, iteration, bounds
    assert np.array_equal(batch[-1].q, batch[len(T) - 1].q)
    assert [len(s) for s in batch[2:5]] == list(batch.counts[2:5])
    assert [len(s) for s in batch] == list(batch.counts)
    with pytest.raises(IndexError):
        batch[len(T)]


def test_per_pose_solutions_are_copies():
    robot = sweepik.load_robot("ur5")
    batch = sweepik.solve_many(robot, _poses(robot, np.random.default_rng(4), 3))
    before = batch.q.copy()
    batch[0].q[:] = 0.0
    assert np.array_equal(batch.q, before) and np.array_equal(batch[0].q, before[: batch.counts[0]])


def test_families_and_limits_in_columns():
    carm = sweepik.load_robot("carm")
    # wrist on joint 2's axis, elbow straight: a self-motion family along theta2 (docs/carm.md)
    q = np.array([900.0, 0.4, 0.0, -np.pi / 2, 0.3, 0.2])
    T = np.stack([carm.fk(q), carm.fk(np.array([900.0, 0.4, 0.3, -0.2, 0.3, 0.2]))])
    batch = sweepik.solve_many(carm, T, reduction="carm-theta2")
    assert set(batch.families) == {0} and batch.families[0] == batch[0].families
    assert not batch[1].families
    free = sweepik.solve_many(carm, T, limits=False)
    assert np.all(batch.within_limits) and free.q.shape[0] >= batch.q.shape[0]


def test_empty_batch():
    robot = sweepik.load_robot("ur5")
    batch = sweepik.solve_many(robot, np.zeros((0, 4, 4)))
    assert batch == [] and len(batch) == 0 and list(batch) == []
    assert batch.q.shape == (0, 6) and batch.offsets.tolist() == [0] and batch.families == {}


@pytest.mark.parametrize("name", ["ur5", "carm", "fanuc_crx10ia"])
def test_read_only_poses(name: str, tmp_path) -> None:
    """Poses in a read-only array (a memory-mapped .npy file) solve like writable ones."""
    robot = sweepik.load_robot(name)
    from sweepik.experiments.verify import random_configurations

    poses = robot.fk(random_configurations(robot, 12, np.random.default_rng(4)))
    np.save(tmp_path / "p.npy", poses)
    mapped = np.load(tmp_path / "p.npy", mmap_mode="r")
    assert not mapped.flags.writeable
    a, b = sweepik.solve_many(robot, mapped), sweepik.solve_many(robot, poses)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(sweepik.solve(robot, mapped[0]).q, b[0].q)


@pytest.mark.parametrize("name", ["carm", "ur5", "xarm6"])
def test_chunks_solved_side_by_side_change_nothing(name):
    """Several chunks are solved two at a time on threads (parallel.in_order): the same columns as one chunk, and
    iter_solve yields the same solutions in the same order. xArm 6 (a generic sweep whose poses differ in their
    number of sample hints): a pose's samples do not depend on its batch (``search.sample_grid``)."""
    robot = sweepik.load_robot(name)
    T = _poses(robot, np.random.default_rng(11), 150)
    one = sweepik.solve_many(robot, T)
    many = sweepik.solve_many(robot, T, chunk_size=7)
    for col in ("offsets", "q", "error", "multiplicity", "within_limits"):
        assert np.array_equal(getattr(one, col), getattr(many, col)), col
    streamed = list(sweepik.iter_solve(robot, T, chunk_size=7))
    assert len(streamed) == len(T)
    assert all(np.array_equal(s.q, one[i].q) for i, s in enumerate(streamed))
