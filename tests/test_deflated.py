"""The general method's compiled path on the deflated 16x16 eigenproblem (``reductions/deflated.py``) against the
elimination's full path (the 24x24 companion, ``GeneralIK.solve``), and its LAPACK eigenvalues against NumPy's."""

from __future__ import annotations

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
