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

import math
from collections import OrderedDict
from functools import lru_cache

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sweepik._jit import ERROR_MODEL
from sweepik.errors import NoReductionError
from sweepik.model.robot import Robot
from sweepik.reductions.base import Array, IntArray, Reduction
from sweepik.reductions.deflated import FastPath, fast_path, solve_poses
from sweepik.reductions.elimination import ArmNotSupportedError, GeneralIK

#: At most this many isolated solutions (6R, 5R1P: the degree of the elimination's polynomial).
MAX_SOLUTIONS = 16

#: A solution whose Jacobian's smallest to largest singular value is under this can be a double root.
DOUBLE_ROOT_RCOND = 1e-5
#: The roots of this many distinct poses are kept (the engine asks for rows of the same poses several times).
_ROOTS_KEPT = 4096

__all__ = ["GeneralReduction", "MAX_SOLUTIONS", "general_refusal"]


#: Held arms (a 7-joint arm with one joint locked) and the arm and joint they come from: their elimination's setup
#: tries the ranking found at a reference value of that joint first (``held_ranking``). Bounded, as the caches.
_HELD_FROM: OrderedDict[Robot, tuple[Robot, int]] = OrderedDict()
_HELD_KEPT = 256
#: Where in the held joint's range (cut to one turn) its reference value lies (the first of
#: ``engine.held_pose.REFERENCES``, where a held arm's plan is checked first).
REFERENCE = 0.0731


def held_arm(arm: Robot, full: Robot, joint: int) -> None:
    """Note that ``arm`` is ``full`` with ``joint`` held (at some value): its setup takes ``held_ranking``'s."""
    _HELD_FROM[arm] = (full, joint)
    _HELD_FROM.move_to_end(arm)
    while len(_HELD_FROM) > _HELD_KEPT:
        _HELD_FROM.popitem(last=False)


@lru_cache(maxsize=64)
def held_ranking(full: Robot, joint: int) -> tuple[tuple[int, ...], int | None] | None:
    """The ranking of the elimination's arrangements (``GeneralIK.ranking``) of ``full`` held at the reference value
    of revolute ``joint`` (``REFERENCE`` of its range cut to one turn), or None (a prismatic joint, no range, or the
    general method not well posed there). Every value of the joint tries it first: the same hint whatever was solved
    before."""
    from sweepik.model.origin_axis import hold_joints

    lo, hi = max(float(full.lower[joint]), -math.pi), min(float(full.upper[joint]), math.pi)
    if not full.is_revolute[joint] or not hi > lo:
        return None
    chain = hold_joints(full, {joint: lo + REFERENCE * (hi - lo)}).arm.chain
    try:
        return GeneralIK(chain.H, chain.P, chain.revolute, chain.R_end).ranking
    except ArmNotSupportedError:
        return None


@lru_cache(maxsize=64)
def _setup(robot: Robot) -> GeneralIK | str:
    """The elimination's per-arm setup for ``robot`` (cached per robot, by value), or why none is well posed. A held
    arm (``held_arm``) takes the ranking of its arrangements found at the reference value where the first of them
    passes the trial solves: 3 arrangements built and one checked instead of 12 built and ranked (a new lock value
    every pose: 24 ms of setup a value before)."""
    chain = robot.chain
    held = _HELD_FROM.get(robot)
    prefer = None if held is None else held_ranking(*held)
    try:
        return GeneralIK(chain.H, chain.P, chain.revolute, chain.R_end, prefer=prefer)
    except ArmNotSupportedError as e:
        return str(e)


@lru_cache(maxsize=64)
def _fast_path(robot: Robot) -> FastPath | None:
    """The compiled path of ``robot``'s elimination (:mod:`.deflated`; cached per robot), or None. A setup whose
    ranking was taken over checks its compiled path on fewer poses (``deflated.HINTED_CHECK_POSES``)."""
    setup = _setup(robot)
    return None if isinstance(setup, str) else fast_path(setup)


def general_refusal(robot: Robot) -> str | None:
    """Why the general method cannot solve ``robot`` (not six joints, or no elimination of its chain well posed),
    or None."""
    if robot.n_joints != 6:
        return f"the general method solves 6-joint arms, not {robot.n_joints}"
    setup = _setup(robot)
    return setup if isinstance(setup, str) else None


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _residual(p, x, branch):
    """``kernels.RESIDUAL_SIG``: nothing is swept (a closed form), NaN."""
    return math.nan


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _configuration(p, x, branch, out):
    """``kernels.CONFIGURATION_SIG``: root ``branch`` of the pose, as ``kernel_params`` laid it out (NaN where the
    pose has fewer)."""
    for i in range(out.shape[0]):
        out[i] = p[out.shape[0] * branch + i]


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _configurations(p, x, out):
    """``kernels.CONFIGURATIONS_SIG``: every root of the pose."""
    for b in range(out.shape[0]):
        _configuration(p, x, b, out[b])


class GeneralReduction(Reduction):
    """The general method as a closed-form reduction (see the module docstring).

    Its compiled kernels read the roots from the parameter row of a pose (``kernel_params``: the elimination runs
    there, each distinct pose once), so the engine certifies and settles them like any closed form's branches."""

    name = "general"
    closed_form = True
    blind_spots = (
        "none: every isolated solution is a root of the elimination; a continuum is traced from the members it finds "
        "(none where its pencil is singular in every arrangement)"
    )
    kernel = (_residual, _configuration)
    kernel_configurations = _configurations

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot, free_joint=0, n_branches=MAX_SOLUTIONS)
        why = general_refusal(robot)
        if why is not None:
            raise NoReductionError(f"robot {robot.name!r}: {why}")
        setup = _setup(robot)
        assert not isinstance(setup, str)
        self._elimination = setup
        self._fast = _fast_path(robot)
        self._last: tuple[Array, Array, Array] | None = None  # (a copy of the poses, the poses, their rows)
        self._kept: OrderedDict[bytes, Array] = OrderedDict()

    def kernel_params(self, poses: Array) -> Array:
        """``(N, MAX_SOLUTIONS * n + 1)`` per chain pose: its roots (row-major, NaN-padded), then 1.0 where it is
        a continuum (``continuum_poses``). Each distinct pose is solved once: the engine asks for rows of the same
        poses several times, so the rows of the last ``_ROOTS_KEPT`` distinct poses are kept by value until their
        chunk is done (``release``)."""
        if self._is_last(poses):
            assert self._last is not None
            return self._last[2]
        robot = self.robot
        flat, keys = self._keys(poses)
        n = robot.n_joints
        rows = np.empty((flat.shape[0], MAX_SOLUTIONS * n + 1))
        got = [self._kept.get(key) for key in keys]  # (read once: another thread's chunk may evict them)
        new: dict[bytes, int] = {}
        for i, (key, row) in enumerate(zip(keys, got, strict=True)):
            if row is None:
                new.setdefault(key, i)
        solved = dict(zip(new, self._solve_new(flat[list(new.values())], list(new)), strict=True)) if new else {}
        for i, (key, row) in enumerate(zip(keys, got, strict=True)):
            rows[i] = solved[key] if row is None else row
        self._last = (poses.copy(), poses, rows)
        return rows

    def _is_last(self, poses: Array) -> bool:
        last = self._last
        return last is not None and (
            last[1] is poses or (last[0].shape == poses.shape and np.array_equal(last[0], poses))
        )

    def release(self, poses: Array) -> None:
        if self._is_last(poses):
            self._last = None
        for key in self._keys(poses)[1]:
            self._kept.pop(key, None)

    def _keys(self, poses: Array) -> tuple[Array, list[bytes]]:
        """The chain poses ``poses`` in the world frame of the chain, flat ``(N, 16)``, and their keys."""
        world = poses
        if not self.robot.base_is_identity:
            world = self.robot.T_world_base @ world
        world = world @ self.robot.T_flange_tool
        flat = np.ascontiguousarray(world.reshape(world.shape[0], 16))
        return flat, [pose.tobytes() for pose in flat]

    def _solve_new(self, flat: Array, keys: list[bytes]) -> Array:
        """The rows of the distinct poses ``flat (U, 16)`` (the world frame of the chain), kept under ``keys`` too: by
        the compiled path (:mod:`.deflated`) where it answers, by the elimination's full solve elsewhere."""
        n = self.robot.n_joints
        width = MAX_SOLUTIONS * n + 1
        rows = np.full((flat.shape[0], width), np.nan)
        rows[:, -1] = 0.0
        todo = np.arange(flat.shape[0])
        if self._fast is not None:
            q, count = solve_poses(self._fast, flat.reshape(-1, 4, 4), MAX_SOLUTIONS)
            rows[:, :-1] = q.reshape(flat.shape[0], -1)
            todo = np.flatnonzero(count < 0)
        for i in todo:
            res = self._elimination.solve(flat[i].reshape(4, 4))
            q = self._double_root_twice(res.q, res.continuum)[:MAX_SOLUTIONS]
            rows[i, :-1] = np.nan
            rows[i, : q.size] = q.reshape(-1)
            rows[i, -1] = float(res.continuum)
        kept = self._kept
        for key, row in zip(keys, rows, strict=True):
            while len(kept) >= _ROOTS_KEPT:
                try:
                    kept.popitem(last=False)  # (one call: safe beside another thread's chunk)
                except KeyError:
                    break
            kept[key] = row
        return rows

    def _double_root_twice(self, q: Array, continuum: bool) -> Array:
        """The elimination's solutions ``q (k, n)`` of a pose, a double root given twice: where ``k`` is odd (the
        real roots of the elimination's polynomial come in an even number, counted with multiplicity) and not a
        continuum, the solution whose Jacobian is nearest singular is the double one. Its two rows are one branch
        meeting another to the engine, which reports one solution of multiplicity 2."""
        if continuum or q.shape[0] % 2 == 0:
            return q
        J = self.robot.jacobian(q)
        J[:, :3] /= self.robot.length_scale  # (rows: linear velocity first)
        sv = np.linalg.svd(J, compute_uv=False)
        ratio = sv[:, -1] / sv[:, 0]
        k = int(np.argmin(ratio))
        if not ratio[k] < DOUBLE_ROOT_RCOND:
            return q
        return np.concatenate([q[: k + 1], q[k:]])

    def _roots(self, poses: Array) -> Array:
        """``(N, MAX_SOLUTIONS, n)``: the roots of each chain pose (NaN-padded)."""
        n = self.robot.n_joints
        return self.kernel_params(poses)[:, :-1].reshape(-1, MAX_SOLUTIONS, n)

    def continuum_poses(self, poses: Array) -> NDArray[np.bool_]:
        """The chain poses the elimination finds to be a continuum (see ``continuum_joints``)."""
        return self.kernel_params(poses)[:, -1] > 0.5

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        per_pose = self._roots(poses)  # (N, B, n)
        N, M = np.asarray(theta).shape
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
        on = self.continuum_poses(poses)
        if not on.any():
            return None
        branch = np.asarray(branch)
        roots = self._roots(poses)[pose, branch]
        flagged = on[pose] & np.all(np.isfinite(roots), axis=-1)
        if error is not None:
            flagged &= error <= tol
        if not flagged.any():
            return None
        roots = roots[flagged]
        J = self.robot.jacobian(roots)
        J[:, :3] /= self.robot.length_scale  # (rows: linear velocity first)
        null = np.linalg.svd(J)[2][:, -1, :]
        out = np.full(pose.shape[0], -1, dtype=np.intp)
        out[np.flatnonzero(flagged)] = np.argmax(np.abs(null), axis=1)
        return out
