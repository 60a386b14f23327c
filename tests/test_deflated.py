"""The general method's compiled path on the deflated 16x16 eigenproblem (``reductions/deflated.py``) against the
elimination's full path (the 24x24 companion, ``GeneralIK.solve``), and its LAPACK eigenvalues against NumPy's."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from general_arms import poses_of, random_arm
from oracles import same_solution_set

from sweepik.reductions import lapack
from sweepik.reductions.deflated import deflation, solve_poses
from sweepik.reductions.general import MAX_SOLUTIONS, _fast_path, _setup


def test_lapack_eigenvalues_are_numpys() -> None:
    rng = np.random.default_rng(0)
    for n in (1, 5, 16):
        A = rng.normal(size=(n, n))
        wr, wi, info = lapack.eigenvalues(A.copy())
        assert info == 0
        got = np.sort_complex(wr + 1j * wi)
        assert np.allclose(got, np.sort_complex(np.linalg.eigvals(A)), atol=1e-12)


@pytest.mark.parametrize(("kind", "seed"), [("6r", 0), ("6r", 5), ("5r1p", 2)])
def test_compiled_path_equals_the_full_path(kind: str, seed: int) -> None:
    """Every pose the compiled path answers has the full path's solution set; on uniform configurations it answers
    nearly all (it hands a pose to the full path only where its checks question it: a near-real pair of eigenvalues
    that does not polish, ``elimination.PAIR_IMAG``, about 1 pose in 20 on random arms)."""
    robot = random_arm(kind, seed)
    path, ik = _fast_path(robot), _setup(robot)
    assert path is not None and not isinstance(ik, str)
    T = robot.fk(poses_of(robot, 60, 0, seed=seed))
    q, count = solve_poses(path, T, MAX_SOLUTIONS)
    assert np.sum(count < 0) <= 6
    for k in np.flatnonzero(count >= 0):
        assert np.all(np.isnan(q[k, count[k] :]))
        full = ik.solve(T[k]).q
        assert same_solution_set(q[k, : count[k]], full, robot.is_revolute, robot.length_scale), k


def test_the_spurious_roots_null_space_is_the_arms() -> None:
    """The left null space of S(i) is found at one pose and checked at another (a rank-8 S(i), the same space)."""
    ik = _setup(random_arm("6r", 1))
    assert not isinstance(ik, str)
    Ur, Ui, V = deflation(ik, ik.arrangements[0], np.random.default_rng(3))
    U = Ur + 1j * Ui
    assert np.allclose(U.conj().T @ U, np.eye(4), atol=1e-12)  # (orthonormal singular vectors)
    assert np.allclose(V.T @ V, np.eye(4), atol=1e-12)
    assert np.allclose(V.T @ np.concatenate([Ur, Ui], axis=1), 0.0, atol=1e-12)


@pytest.mark.parametrize(("kind", "seed"), [("6r", 1), ("5r1p", 3)])
def test_a_ranking_taken_over_gives_the_full_rankings_answers(kind: str, seed: int) -> None:
    """The elimination built with another build's ranking (``GeneralIK(..., prefer=)``, as an arm held at a new lock
    value takes the one found at a reference value) builds its first three arrangements alone, and gives the full
    build's solution set; a ranking whose first arrangement is unusable on the arm falls back to the full build."""
    from sweepik.reductions.elimination import ARRANGEMENTS, GeneralIK

    robot = random_arm(kind, seed)
    c = robot.chain
    full = GeneralIK(c.H, c.P, c.revolute, c.R_end)
    hinted = GeneralIK(c.H, c.P, c.revolute, c.R_end, prefer=full.ranking)
    assert hinted.hinted and not full.hinted
    assert hinted.ranking[0] == full.ranking[0][:3] and hinted.ranking[1] == full.ranking[1]
    T = robot.fk(poses_of(robot, 20, 0, seed=seed))  # (next to the singular set a double root is fixed to ~1e-6)
    for k in range(len(T)):
        a, b = hinted.solve(T[k]).q, full.solve(T[k]).q
        assert same_solution_set(a, b, robot.is_revolute, robot.length_scale), k
    fell = 0
    for k in (k for k in range(len(ARRANGEMENTS)) if k not in full.ranking[0]):  # (unusable in the full build)
        other = GeneralIK(c.H, c.P, c.revolute, c.R_end, prefer=((k,), None))
        assert other.ranking[0] == ((k,) if other.hinted else full.ranking[0])
        fell += not other.hinted
    assert fell or kind == "6r"  # (a prismatic joint makes some arrangements unusable whatever their numbers)


def test_a_held_arm_at_new_values_takes_the_reference_ranking() -> None:
    """A seven-joint arm without structure held at one joint: every value's held arm takes the general method, its
    setup the ranking found at the joint's reference value (``general.held_ranking``) where it passes the trial
    solves. Each value's solutions are those of the held arm solved on its own (a full build), the generating
    configuration among them."""
    from oracles import contains

    import sweepik
    from sweepik.io.robot_file import robot_from_dict
    from sweepik.model.origin_axis import hold_joints
    from sweepik.reductions import general

    rng = np.random.default_rng(39)
    joints = [
        {"name": f"j{i + 1}", "type": "revolute", "a": float(rng.uniform(0.05, 0.4)),
         "alpha": float(rng.uniform(-180, 180)), "d": float(rng.uniform(0.05, 0.3)),
         "theta": float(rng.uniform(-180, 180)), "limits": [-180.0, 180.0]}
        for i in range(7)
    ]  # fmt: skip
    arm = robot_from_dict({"name": "general_7r", "dh_convention": "standard", "length_unit": "m", "joints": joints})
    k = 3
    assert general.held_ranking(arm, k) is not None
    q = rng.uniform(-np.pi, np.pi, (6, 7))
    hinted = 0
    for qq in q:
        T = arm.fk(qq)
        s = sweepik.solve(arm, T, locked={"j4": float(qq[k])}, limits=False)
        assert contains(s.q, qq, arm.is_revolute, arm.length_scale, 1e-6)
        held = hold_joints(arm, {k: float(qq[k])}).arm
        setup = general._setup(held)
        assert not isinstance(setup, str)
        hinted += setup.hinted
        alone = dataclasses.replace(held, name="alone")  # (no hint: the full build)
        a = sweepik.solve(alone, T, limits=False)
        assert same_solution_set(np.delete(s.q, k, axis=1), a.q, alone.is_revolute, alone.length_scale)
    assert hinted >= 5


def test_the_compiled_path_takes_an_arrangement_that_answers_where_the_first_would_not() -> None:
    """ssik's xArm7 held at joint 2 (its rounding leaves near-structures: the general method) ranks first an
    arrangement that finds most random poses suspicious (a real root that does not polish): its compiled path handed
    nearly every pose to the full solve, which asked two more arrangements. The compiled path takes the arrangement
    found suspicious at the fewest trial poses instead, and answers as the full solve does."""
    pytest.importorskip("ssik")
    from catalogue import robot_from_ssik

    from sweepik.model.origin_axis import hold_joints
    from sweepik.reductions.elimination import _chain_fk

    arm = hold_joints(robot_from_ssik("xarm7_ik"), {1: 0.3}).arm
    path, ik = _fast_path(arm), _setup(arm)
    assert path is not None and not isinstance(ik, str)
    assert ik.fast is not ik.arrangements[0]
    rng = np.random.default_rng(5)
    world = np.empty((12, 4, 4))
    for k, q in enumerate(rng.uniform(-np.pi, np.pi, (12, 6))):
        R, p = _chain_fk(ik.H, ik.P, ik.rev, ik.R_end, q)
        world[k] = np.eye(4)
        world[k, :3, :3], world[k, :3, 3] = R, p * ik.scale
    q, count = solve_poses(path, world, MAX_SOLUTIONS)
    assert np.sum(count < 0) <= 2
    for k in np.flatnonzero(count >= 0):
        full = ik.solve(world[k]).q
        assert same_solution_set(q[k, : count[k]], full, arm.is_revolute, arm.length_scale), k
