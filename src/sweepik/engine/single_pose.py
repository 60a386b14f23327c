"""A single pose, from the target to its solutions, with the least Python around one compiled call.

``solve`` on one pose spent ~16 us of Python around the compiled work of a closed form (~5 us: every branch, its
forward-kinematics check, the settling), and ~30 us around a sweep's ~70: the pose's checks in scalar arithmetic, the
parameter rows (a second compiled call), theta*'s range, the settling's wrappers and checks, ``Solutions``'
dataclass init. Here one kernel checks that the target is a rigid transform (``validate.rigid_values``), builds its
parameter row (``geometric.pose_rows``) and runs the one-call path's compiled steps (``one_pose``'s
``every_branch_settled`` for a closed form, ``searched_settled`` and the close-pair check for a sweep), so the answer
is the one-call path's to the last bit. Whatever that path would not settle (a singular pose, branches that meet,
families, a polish due, a target that fails the scalar check) it hands back with its status, and ``solve`` takes the
general way.

A reduction qualifies (``SinglePose.of``) when it is solved alone (no companion), has no blind spots or special
solutions of its own and its parameter rows come from ``geometric.pose_rows`` (``Reduction.pose_row_args``); a closed
form when it has an all-branch configuration kernel and checks its singular set in compiled code
(``Reduction.singular_kernel``); a sweep when theta* is revolute (its range the circle), it has a one-pass search and
checks its continua in compiled code, and has no fallback.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import boolean, float64
from numpy.typing import NDArray

from sweepik._jit import inlined, writable
from sweepik.engine import search
from sweepik.engine.chain_pose import chain_into
from sweepik.engine.chunk import one_block, resumed
from sweepik.engine.one_pose import (
    _A_SING,
    DUE,
    OK,
    SETTLE_CLOSED_SIG,
    SETTLE_ONE_SIG,
    closed_fixed,
    every_branch_settled,
    searched_settled,
    sweep_fixed,
)
from sweepik.engine.settings import CLIP_REACH_REL, MAX_ISOLATED_SOLUTIONS, MEET_REL, N_SAMPLES, SEED_TOL_REL
from sweepik.engine.settle import per_joint, settle_bounds, snap_reach
from sweepik.model.origin_axis import HeldJoints
from sweepik.model.robot import Robot
from sweepik.model.validate import check_poses, rigid_values
from sweepik.reductions import GeometricReduction, Reduction
from sweepik.reductions.geometric import N_PARAMS, pose_rows
from sweepik.reductions.kernels import defining_class, lazy_njit
from sweepik.results import Block, Solutions, no_solution_reason

__all__ = ["SinglePose", "NOT_RIGID", "rigid_pose", "not_rigid", "pose_row", "answer", "settles", "swept_settled"]

Array = NDArray[np.float64]

#: The kernels' status for a target that fails ``validate.rigid_values`` (``check_poses`` then says why, or accepts
#: it: a sum that overflowed).
NOT_RIGID = -1

_rigid_values = inlined(rigid_values)


@inlined
def rigid_pose(T):  # pragma: no cover
    """``validate.rigid_values`` of ``T (4, 4)``."""
    return _rigid_values(
        T[0, 0], T[0, 1], T[0, 2], T[0, 3], T[1, 0], T[1, 1], T[1, 2], T[1, 3],
        T[2, 0], T[2, 1], T[2, 2], T[2, 3], T[3, 0], T[3, 1], T[3, 2], T[3, 3],
    )  # fmt: skip


@inlined
def not_rigid(n):  # pragma: no cover
    """The kernels' answer for a target that is not a rigid transform: nothing settled."""
    none = np.empty(0)
    return NOT_RIGID, 0, 0, np.empty((0, n)), none, none, np.empty(0, np.bool_), np.empty(0, np.int64)


@inlined
def pose_row(chain, base, tool, reverse, r_end, w_tool, row):  # pragma: no cover
    """The parameter row ``(1, N_PARAMS)`` of the chain pose ``chain (4, 4)`` (``pose_rows``)."""
    params = np.empty((1, N_PARAMS))
    pose_rows(chain.reshape((1, 4, 4)), base, tool, reverse, r_end, w_tool, row, params)
    return params


@inlined
def chained(world, frames, has_base, has_tool):  # pragma: no cover
    """The chain pose of ``world (4, 4)``, as ``chain_pose.chain_poses`` makes it (``frames (2, 4, 4)``: the arm's
    ``T_base_world`` and ``T_tool_flange``, each applied where its flag is set): ``world`` itself without either."""
    if not (has_base or has_tool):
        return world
    out = np.empty((4, 4))
    chain_into(world, frames[0], frames[1], has_base, has_tool, np.empty((4, 4)), out)
    return out


#: ``pose_rows``' arguments after the poses and before the output.
_ROW_SIG = (float64[:, ::1], float64[:, ::1], boolean, float64[:, ::1], float64[::1], float64[::1])
_TARGET_SIG = (float64[:, ::1], float64[:, :, ::1], boolean, boolean)


@lazy_njit(_TARGET_SIG + _ROW_SIG + SETTLE_CLOSED_SIG[:1] + SETTLE_CLOSED_SIG[3:], cache=True, nogil=True)
def _closed_pose(
    world, frames, has_base, has_tool, base, tool, reverse, r_end, w_tool, row, addr, nb, H, P, rev, R_end, weight,
    thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """A closed form's target ``world (4, 4)`` checked, its chain pose made (``chained``), its row built (``pose_rows``'
    arguments ``base`` .. ``row``) and every branch settled (``every_branch_settled``'s arguments after them):
    ``(status, certified, reachable, q, error, error_geodesic, within_limits, multiplicity)``."""
    if not rigid_pose(world):
        return not_rigid(rev.shape[0])
    params = pose_row(chained(world, frames, has_base, has_tool), base, tool, reverse, r_end, w_tool, row)
    st, c, reachable, q, ep, eg, ins, mu, _ = every_branch_settled(
        addr, params, world.reshape((1, 4, 4)), nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond,
        reach, tol, scale, s_thr, meet, only_inside,
    )  # fmt: skip
    return st, c, reachable, q, ep, eg, ins, mu


@lazy_njit(
    _TARGET_SIG + _ROW_SIG + SETTLE_ONE_SIG[:6] + SETTLE_ONE_SIG[11:18] + SETTLE_ONE_SIG[19:],
    cache=True,
    nogil=True,
)  # fmt: skip
def _swept_pose(
    world, frames, has_base, has_tool, base, tool, reverse, r_end, w_tool, row, addr, plan, branches, m_branches,
    steps, noise, s, ends, twins, max_cand, max_fam, limits, clip, H, P, rev, R_end, weight, thr, lrev, lower, upper,
    ltol, beyond, reach, tol, scale, c_joints, c_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """A sweep's target (as ``_closed_pose``) searched over the circle, certified and settled (``searched_settled``'s
    arguments)."""
    if not rigid_pose(world):
        return not_rigid(rev.shape[0])
    params = pose_row(chained(world, frames, has_base, has_tool), base, tool, reverse, r_end, w_tool, row)
    return swept_settled(
        world, params, addr, plan, branches, m_branches, steps, noise, s, ends, twins, max_cand, max_fam, limits, clip,
        H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, c_joints, c_thr, meet,
        only_inside,
    )  # fmt: skip


@inlined
def swept_settled(
    world, params, addr, plan, branches, m_branches, steps, noise, s, ends, twins, max_cand, max_fam, limits, clip, H,
    P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, c_joints, c_thr, meet,
    only_inside,
):  # pragma: no cover  # fmt: skip
    """``_swept_pose`` once the target is checked and its row ``params (1, N_PARAMS)`` built."""
    lo, hi = np.empty(1), np.empty(1)
    lo[0], hi[0] = -math.pi, math.pi
    return searched_settled(
        addr, plan, branches, m_branches, steps, noise, params, lo, hi, lo, hi, s, ends, twins, max_cand, max_fam,
        limits, clip, world.reshape((1, 4, 4)), H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach,
        tol, scale, c_joints, c_thr, meet, only_inside,
    )  # fmt: skip


class SinglePose:
    """One arm's reduction, ready for single poses: its fixed arguments worked out once (``of``), then
    ``solve(pose, limits)`` per pose."""

    __slots__ = ("robot", "held", "arm", "reduction", "_kernel", "_frames", "_head", "_tail", "_sweeps")

    def __init__(
        self, arm: Robot, red: Reduction, held: HeldJoints | None, kernel: Any, head: tuple[Any, ...],
        tail: tuple[Any, ...],
    ) -> None:  # fmt: skip
        self.robot = arm if held is None else held.robot  # (the solutions' arm)
        self.held = held
        self.arm = arm  # (the solved arm: the held arm with ``held``)
        self.reduction = red
        # (the compiled entry point itself: ``solve`` passes the signature's types, its pose checked by the caller)
        self._kernel = kernel.unchecked
        frames = np.stack([arm.T_base_world, arm.T_tool_flange])
        self._frames = (frames, not arm.base_is_identity, not arm.tool_is_identity)  # (``chained``'s)
        self._head = head  # (pose_rows' arguments)
        self._tail = tail  # (the settling's, but the rows, targets and buffers; then the meeting reach)
        self._sweeps = kernel is _swept_pose

    @classmethod
    def of(cls, robot: Robot, red: Reduction, held: HeldJoints | None = None, alone: bool = False) -> SinglePose | None:
        """``robot`` (with ``held``: the held arm, ``held.arm``) solved by ``red`` this way, or None where ``red``
        does not qualify (module docstring); ``alone``: ``red`` without its companion (``joined_pose`` joins
        them)."""
        rc = type(red)
        if not alone and getattr(red, "companion", None) is not None:
            return None
        for hook in ("special_solutions", "blind_spot"):
            if defining_class(rc, hook) is not Reduction:
                return None
        head = red.pose_row_args()
        if head is None:
            return None
        base, tool, reverse, r_end, w_tool, row = head
        head = (writable(base), writable(tool), bool(reverse), writable(r_end), writable(w_tool), writable(row))
        bounds, reach, meet = settle_bounds(robot), snap_reach(robot), writable(per_joint(robot, MEET_REL))
        if red.closed_form:
            closed = closed_fixed(robot, red, bounds, reach)
            if closed is None or closed[0][_A_SING] == 0:
                return None  # (its singular set checked in Python: the general path)
            addr, nb, _, _, tail, s_thr = closed
            return cls(robot, red, held, _closed_pose, head, (addr, nb, *tail, s_thr, meet))
        return cls._swept(robot, red, held, head, bounds, reach, meet)

    @classmethod
    def _swept(
        cls, robot: Robot, red: Reduction, held: HeldJoints | None, head: tuple[Any, ...], bounds: Any, reach: Any,
        meet: Array,
    ) -> SinglePose | None:  # fmt: skip
        """``of`` for a sweep."""
        if not red.periodic or red.fallback is not None:
            return None
        if defining_class(type(red), "continuum_poses") is not Reduction:
            return None
        fixed = sweep_fixed(robot, red, N_SAMPLES, bounds, reach, SEED_TOL_REL * robot.length_scale)
        if fixed is None or fixed.hint_range not in (None, GeometricReduction._range):  # (the circle either way)
            return None
        tail = (*fixed.middle, fixed.limits, float(CLIP_REACH_REL * 2.0 * math.pi), *fixed.tail, meet)
        return cls(robot, red, held, _swept_pose, head + fixed.head, tail)

    def solve(self, pose: Array, limits: bool) -> tuple[int, Solutions | None]:
        """``(status, solutions)``: the solutions of ``pose`` (a C-contiguous, writable float64 ``(4, 4)``) as
        ``solve`` gives them (status ``OK``), or None where the general path must answer, with the status that says
        why (``one_pose``'s, or ``NOT_RIGID``; ``OK`` with more than ``MAX_ISOLATED_SOLUTIONS`` certified). Raises
        ``check_poses``' errors for a target that is not a rigid transform. A sweep's pose with a candidate due a
        polish or a snap to a limit (``DUE``): the rest of the general way from the call's candidates."""
        out = self.call(pose, limits)
        if out[0] == DUE and self._sweeps:
            return OK, self._resumed(pose, out, limits).expanded(self.held).solutions(0, copy=False)
        return answer(out, pose, self.robot, None if self.held is None else self.held.expand)

    def block(self, pose: Array, out: tuple[Any, ...], limits: bool) -> Block | None:
        """The solved arm's block of ``pose`` from the call's answer ``out``: settled, or from a sweep's candidates
        (``DUE``); None where the general way answers. Raises as ``solve`` does."""
        if out[0] == DUE and self._sweeps:
            return self._resumed(pose, out, limits)
        if not settles(out, pose):
            return None
        _, _, reachable, q, ep, eg, ins, mu = out
        return one_block(self.arm, pose.reshape(1, 4, 4), q, ep, eg, ins, mu, reachable)

    def _resumed(self, pose: Array, out: tuple[Any, ...], limits: bool) -> Block:
        """``block`` from a sweep's candidates (``out``'s status ``DUE``: ``chunk.resumed``)."""
        _, _, _, q, ep, eg, _, mu = out
        return resumed(self.arm, self.reduction, pose.reshape(1, 4, 4), q, ep, eg, mu, limits)

    def call(self, pose: Array, limits: bool) -> tuple[Any, ...]:
        """The compiled call's answer for ``pose``: ``(status, certified, reachable, q, error, error_geodesic,
        within_limits, multiplicity)``, ``q`` the solved arm's (the held arm's, with ``held``)."""
        if self._sweeps:  # (the buffers read here: a test may cut them)
            head, tail = self._head, self._tail
            return self._kernel(
                pose, *self._frames, *head, *tail[:3], search.MAX_CAND, search.MAX_FAM, *tail[3:], limits
            )
        return self._kernel(pose, *self._frames, *self._head, *self._tail, limits)


def settles(out: tuple[Any, ...], pose: Array) -> bool:
    """Whether a one-pose kernel's ``out`` is the answer (status ``OK``, at most ``MAX_ISOLATED_SOLUTIONS``
    certified); raises ``check_poses``' errors where ``pose`` is not a rigid transform (``NOT_RIGID``)."""
    if out[0] == OK and out[1] <= MAX_ISOLATED_SOLUTIONS:
        return True
    if out[0] == NOT_RIGID:
        check_poses(pose)
    return False


def answer(out: tuple[Any, ...], pose: Array, robot: Robot, expand: Any = None) -> tuple[int, Solutions | None]:
    """A one-pose kernel's ``out`` as ``SinglePose.solve`` returns it (``expand``: the held arm's configurations
    made full length)."""
    status, c, reachable, q, ep, eg, ins, mu = out
    if not settles(out, pose):
        return status, None
    reason = None if q.shape[0] else no_solution_reason(reachable)
    if expand is not None:
        q = expand(q)
    return status, Solutions.settled(q, ep, eg, ins, mu, reason, pose.copy(), robot)
