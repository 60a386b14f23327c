"""The compiled wrap/limits/dedupe pass (``sweepik.engine.dedupe.finish``) equals its NumPy reference, and both keep one
of each set of equal candidates: the best, ties to the earliest, across the +-pi seam and beyond-pi limits."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import numpy_engine

import sweepik
from sweepik.engine import dedupe


def _candidates(robot: sweepik.Robot, rng: np.random.Generator, n_poses: int, per_pose: int):
    """Distinct base configurations per pose, each repeated with tiny offsets, copies shifted by 2 pi (the seam)
    and tied errors, in shuffled order."""
    lo = np.where(robot.is_revolute, np.maximum(robot.lower, -np.pi), robot.lower)
    hi = np.where(robot.is_revolute, np.minimum(robot.upper, np.pi), robot.upper)
    rows, poses, errs = [], [], []
    for p in range(n_poses):
        base = rng.uniform(lo, hi, size=(per_pose, robot.n_joints))
        base[0, robot.is_revolute] = np.pi - 1e-9  # on the seam
        for b in base:
            for _ in range(int(rng.integers(1, 4))):
                c = b + rng.normal(scale=1e-8, size=b.shape) * rng.integers(0, 2)
                c = np.where(robot.is_revolute & (rng.random(b.shape) < 0.3), c - 2 * np.pi * np.sign(c), c)
                rows.append(c)
                poses.append(p)
                errs.append(float(rng.choice([1e-12, 2e-12, 3e-12])))  # many ties
    order = rng.permutation(len(rows))
    return np.array(poses)[order], np.array(rows)[order], np.array(errs)[order]


@pytest.mark.parametrize("name", ["yaskawa_hc10", "carm", "ur5", "kinova_jaco2"])
@pytest.mark.parametrize("per_pose", [3, 20, 60])
def test_compiled_finish_equals_reference(name: str, per_pose: int) -> None:
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(per_pose)
    pose, q, err = _candidates(robot, rng, 7, per_pose)
    w_c, in_c, keep_c = dedupe.finish(robot, pose, q, err)
    w_r, in_r, keep_r = numpy_engine.finish(robot, pose, q, err)
    np.testing.assert_array_equal(w_c, w_r)
    np.testing.assert_array_equal(in_c, in_r)
    np.testing.assert_array_equal(keep_c, keep_r)
    # one kept per distinct base configuration (the copies are within the tolerance of each other), none equal
    kept = w_c[keep_c]
    for p in np.unique(pose):
        k = kept[pose[keep_c] == p]
        d = np.abs(k[:, None, :] - k[None, :, :])
        d = np.where(robot.is_revolute, np.minimum(d, 2 * np.pi - d), d)
        same = np.all(d <= 1e-6 * np.where(robot.is_revolute, 1.0, robot.length_scale * 1e-2), axis=-1)
        assert same.sum() == len(k), "two kept candidates are equal"


@pytest.mark.parametrize("joint", [0, 3, 5])
def test_a_continuum_across_the_seam_deduplicates_as_the_reference(joint: int) -> None:
    """Thousands of candidates of one pose along an arc of one joint that crosses +-pi (a numerical continuum's, the
    other joints constant or drifting by less than the tolerance), with near copies: the compiled pass (by buckets
    along the joint that spreads most) keeps exactly what the all-pairs reference keeps, seam pairs included."""
    robot = sweepik.load_robot("ur5")
    rng = np.random.default_rng(joint)
    K = 3000
    q = np.tile(rng.uniform(-np.pi, np.pi, 6), (K, 1))
    q[:, joint] = np.pi + rng.uniform(-0.2, 0.2, K)  # (wrapped: both sides of the seam)
    copies = rng.random(K) < 0.4
    q[copies] = q[rng.integers(0, K, int(copies.sum()))] + rng.normal(scale=3e-7, size=(int(copies.sum()), 6))
    q[:, (joint + 1) % 6] += rng.normal(scale=2e-7, size=K)
    q[:20, joint] = np.pi - rng.uniform(0, 4e-7, 20)  # just below pi, and copies of them just above -pi
    q[20:40] = q[:20]
    q[20:40, joint] += rng.uniform(4e-7, 6e-7, 20) - 2 * np.pi
    err = rng.choice([1e-12, 2e-12], K)
    pose = np.zeros(K, dtype=np.intp)
    w_c, _, keep_c = dedupe.finish(robot, pose, q, err)
    _, _, keep_r = numpy_engine.finish(robot, pose, q, err)
    np.testing.assert_array_equal(keep_c, keep_r)
    assert 0 < keep_c.sum() < K


def test_a_continuum_of_tens_of_thousands_of_points_collapses_in_bounded_memory() -> None:
    """40,000 certified points along one arc of a pose (a numerical continuum) and 5 isolated ones: the arc is
    reported by one medoid (before, the all-pairs comparison asked for (K, K, 6) floats: 77 GB)."""
    from sweepik.engine.families import collapse_continua

    robot = sweepik.load_robot("ur5")
    t = np.linspace(-1.0, 1.0, 40_000)
    q = np.zeros((t.size, 6))
    q[:, 0], q[:, 3] = t, -t
    q[-5:] = np.random.default_rng(0).uniform(-3, 3, (5, 6))
    keep = collapse_continua(robot, np.zeros(t.size, dtype=np.intp), q)
    assert keep.sum() == 6 and np.all(keep[-5:])


@pytest.mark.parametrize(
    ("name", "reduction"), [("ur5", None), ("puma560", None), ("carm", "carm-d1"), ("fanuc_crx10ia", None)]
)
def test_one_pass_settling_equals_the_solver_steps(
    name: str, reduction: str | None, monkeypatch: pytest.MonkeyPatch
) -> None:
    """``solve_many`` with the compiled settling pass (``dedupe.settle``: the poses due a polish, the fallback or a
    snap onto a limit left to the solver's steps, the others settled at once, in parts on the batch threads) gives
    bit for bit what the steps alone give: batches with singular wrists, solutions at a joint limit, random poses,
    with and without limits."""
    from sweepik.engine import chunk, parallel

    monkeypatch.setattr(parallel, "threads", lambda: 3)  # parts on threads, whatever the machine's cores
    monkeypatch.setattr(dedupe, "_PARALLEL_ROWS", 64)
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(2)
    q = rng.uniform(robot.lower, robot.upper, size=(700, robot.n_joints))
    q[:100, 4] = 0.0  # a singular wrist (polish, the fallback)
    q[100:200, 1] = robot.upper[1]  # at a limit (solutions just beyond it are snapped)
    q[200:250, 2] = robot.lower[2]
    poses = robot.fk(q)
    due = []
    real = dedupe.settle

    settled = []

    def counting(*args, **kwargs):
        out = real(*args, **kwargs)
        due.append(0 if out is None else int(out[0].sum()))
        settled.append(0 if out is None else out[1].size)
        return out

    monkeypatch.setattr(chunk, "settle", counting)
    got = [sweepik.solve_many(robot, poses, reduction=reduction, limits=lim) for lim in (True, False)]
    assert sum(due) > 0, "no pose was due the solver's steps: the mixed case is not exercised"
    assert sum(settled) > 0, "no candidate was settled in one pass"
    monkeypatch.setattr(chunk, "settle", lambda *args, **kwargs: None)
    ref = [sweepik.solve_many(robot, poses, reduction=reduction, limits=lim) for lim in (True, False)]
    for a, b in zip(got, ref, strict=True):
        for column in ("offsets", "q", "error", "error_geodesic", "within_limits", "multiplicity", "n_reachable"):
            np.testing.assert_array_equal(getattr(a, column), getattr(b, column), err_msg=column)
        assert a.families.keys() == b.families.keys()
        for i, fams in a.families.items():
            assert [(f.branch, f.interval) for f in fams] == [(f.branch, f.interval) for f in b.families[i]]
