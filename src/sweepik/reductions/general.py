"""The general method: every 6-joint arm that no structured decomposition covers (issue 37).

An arm whose axes neither meet nor stay parallel anywhere has no joint whose value leaves the other five to closed
forms, so nothing can be swept. It is solved by elimination (:mod:`.elimination`): the kinematic equations are
reduced to a matrix polynomial in one joint's half-angle tangent whose eigenvalues are that joint's values at every
isolated solution (Raghavan & Roth 1993, posed as an eigenproblem by Manocha & Canny 1994); the other joints follow
from the eigenvectors and closed forms. Every root is polished by Newton steps on the forward kinematics and the
engine certifies each one like any other candidate.

To the engine this is a closed form with ``MAX_SOLUTIONS`` branches: branch k of a pose is its k-th root (NaN
where it has fewer). ``solve_rest`` solves each distinct pose it is given once.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from numpy.typing import NDArray

from sweepik.errors import NoReductionError
from sweepik.model.robot import Robot
from sweepik.reductions.base import Array, IntArray, Reduction
from sweepik.reductions.elimination import ArmNotSupportedError, GeneralIK

#: At most this many isolated solutions (6R, 5R1P: the degree of the elimination's polynomial).
MAX_SOLUTIONS = 16

__all__ = ["GeneralReduction", "MAX_SOLUTIONS", "general_refusal"]


@lru_cache(maxsize=64)
def _setup(robot: Robot) -> GeneralIK | str:
    """The elimination's per-arm setup for ``robot`` (cached per robot, by value), or why none is well posed."""
    chain = robot.chain
    try:
        return GeneralIK(chain.H, chain.P, chain.revolute, chain.R_end)
    except ArmNotSupportedError as e:
        return str(e)


def general_refusal(robot: Robot) -> str | None:
    """Why the general method cannot solve ``robot`` (not six joints, or no elimination of its chain well posed),
    or None."""
    if robot.n_joints != 6:
        return f"the general method solves 6-joint arms, not {robot.n_joints}"
    setup = _setup(robot)
    return setup if isinstance(setup, str) else None


class GeneralReduction(Reduction):
    """The general method as a closed-form reduction (see the module docstring)."""

    name = "general"
    closed_form = True
    blind_spots = (
        "none: every isolated solution is a root of the elimination; a continuum is traced from the members it finds "
        "(none where its pencil is singular in every arrangement)"
    )

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot, free_joint=0, n_branches=MAX_SOLUTIONS)
        why = general_refusal(robot)
        if why is not None:
            raise NoReductionError(f"robot {robot.name!r}: {why}")
        setup = _setup(robot)
        assert not isinstance(setup, str)
        self._elimination = setup
        self._last: tuple[Array, Array, IntArray, NDArray[np.bool_]] | None = None

    def _roots(self, poses: Array) -> tuple[Array, IntArray]:
        """``(unique roots (U, MAX_SOLUTIONS, n) NaN-padded, index of each pose's row (N,))`` of chain poses."""
        last = self._last
        if last is not None and last[0] is poses:
            return last[1], last[2]
        robot = self.robot
        world = poses
        if not robot.base_is_identity:
            world = robot.T_world_base @ world
        world = world @ robot.T_flange_tool
        flat = np.ascontiguousarray(world.reshape(world.shape[0], 16))
        unique, inverse = np.unique(flat, axis=0, return_inverse=True)
        out = np.full((unique.shape[0], MAX_SOLUTIONS, robot.n_joints), np.nan)
        continuum = np.zeros(unique.shape[0], dtype=bool)
        for i, row in enumerate(unique):
            res = self._elimination.solve(row.reshape(4, 4))
            out[i, : res.q.shape[0]] = res.q[:MAX_SOLUTIONS]
            continuum[i] = res.continuum
        inverse = inverse.reshape(-1)
        self._last = (poses, out, inverse, continuum[inverse])
        return out, inverse

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        roots, index = self._roots(poses)
        N, M = np.asarray(theta).shape
        per_pose = roots[index]  # (N, B, n)
        if branch is None:
            return np.broadcast_to(per_pose[:, None], (N, M, *per_pose.shape[1:])).copy()
        b = np.broadcast_to(np.asarray(branch, dtype=np.intp), (N, M))
        return per_pose[np.arange(N)[:, None], b]

    def continuum_joints(
        self, poses: Array, pose: IntArray, theta: Array, branch: IntArray, error: Array | None = None, tol: float = 0.0
    ) -> IntArray | None:
        """At a pose the elimination finds to be a continuum (its matrix polynomial singular for every value, or a
        root on a curve of solutions): each candidate's joint that moves most along the continuum (the largest
        entry of the Jacobian's null vector there), for the engine to trace; -1 elsewhere. None: no such pose."""
        self._roots(poses)
        last = self._last
        assert last is not None
        flagged = last[3][pose] & np.all(np.isfinite(last[1][last[2][pose], np.asarray(branch)]), axis=-1)
        if error is not None:
            flagged &= error <= tol
        if not flagged.any():
            return None
        roots = last[1][last[2][pose[flagged]], np.asarray(branch)[flagged]]
        J = self.robot.jacobian(roots)
        J[:, :3] /= self.robot.length_scale  # (rows: linear velocity first)
        null = np.linalg.svd(J)[2][:, -1, :]
        out = np.full(pose.shape[0], -1, dtype=np.intp)
        out[np.flatnonzero(flagged)] = np.argmax(np.abs(null), axis=1)
        return out
