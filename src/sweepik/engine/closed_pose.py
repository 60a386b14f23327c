"""A closed form's single pose, from the target to its solutions, with the least Python around one compiled call.

``solve`` on one pose of an arm with a closed form spent ~16 us, of which ~5 us were the compiled work (every
branch, its forward-kinematics check, the settling) and the rest Python: the pose's checks in scalar arithmetic, the
parameter rows (a second compiled call), the settling's wrappers, ``Solutions``' dataclass init. Here one kernel
(``_closed_pose``) checks that the target is a rigid transform, builds its parameter row
(``geometric.pose_rows``) and runs ``one_pose.every_branch_settled``, the same compiled steps the one-call path
runs, so the answer is the same to the last bit. Whatever it cannot settle on its own (a singular pose, branches
that meet, a target that fails the scalar check) it hands back, and ``solve`` takes the general way.

A reduction qualifies (``ClosedPose.of``) when it is a closed form solved alone (no companion), with an all-branch
configuration kernel, a compiled check of its singular set (``Reduction.singular_kernel``), its parameter rows from
``geometric.pose_rows`` (``Reduction.pose_row_args``), and no blind spots or special solutions of its own.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import boolean, float64, int64
from numpy.typing import NDArray

from sweepik._jit import inlined, writable
from sweepik.engine.one_pose import _A_SING, OK, closed_fixed, every_branch_settled
from sweepik.engine.settings import MAX_ISOLATED_SOLUTIONS, MEET_REL
from sweepik.engine.settle import per_joint, settle_bounds, snap_reach
from sweepik.model.origin_axis import HeldJoints
from sweepik.model.robot import Robot
from sweepik.model.validate import check_poses, rigid_values
from sweepik.reductions import Reduction
from sweepik.reductions.geometric import N_PARAMS, pose_rows
from sweepik.reductions.kernels import defining_class, lazy_njit
from sweepik.results import Solutions, no_solution_reason

__all__ = ["ClosedPose", "NOT_RIGID"]

Array = NDArray[np.float64]

#: ``_closed_pose``'s status for a target that fails ``validate._one_pose_ok``'s scalar test (``check_poses`` then
#: says why, or accepts it: a sum that overflowed).
NOT_RIGID = -1


_rigid_values = inlined(rigid_values)


@inlined
def _rigid(T):  # pragma: no cover
    """``validate.rigid_values`` of ``T (4, 4)``."""
    return _rigid_values(
        T[0, 0], T[0, 1], T[0, 2], T[0, 3], T[1, 0], T[1, 1], T[1, 2], T[1, 3],
        T[2, 0], T[2, 1], T[2, 2], T[2, 3], T[3, 0], T[3, 1], T[3, 2], T[3, 3],
    )  # fmt: skip


@lazy_njit(
    (float64[:, ::1], float64[:, ::1], float64[:, ::1], float64[:, ::1], boolean, float64[:, ::1], float64[::1])
    + (float64[::1], int64[::1], int64, float64[:, ::1], float64[:, ::1], boolean[::1], float64[:, ::1], float64)
    + (float64[::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean, float64[::1], float64[::1])
    + (float64, float64[::1], float64[::1], boolean),
    cache=True,
    nogil=True,
)
def _closed_pose(
    world, chain, base, tool, reverse, r_end, w_tool, row, addr, nb, H, P, rev, R_end, weight, thr, lrev, lower,
    upper, ltol, beyond, reach, tol, scale, s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """The target ``world (4, 4)`` (its chain pose ``chain``) checked, its parameter row built (``pose_rows``'
    arguments ``base`` .. ``row``) and every branch settled (``every_branch_settled``'s arguments after them):
    ``(status, certified, reachable, q, error, error_geodesic, within_limits, multiplicity)``."""
    if not _rigid(world):  # (nothing settled: the status says why)
        n = rev.shape[0]
        none = np.empty(0)
        return NOT_RIGID, 0, 0, np.empty((0, n)), none, none, np.empty(0, np.bool_), np.empty(0, np.int64)
    params = np.empty((1, N_PARAMS))
    pose_rows(chain.reshape((1, 4, 4)), base, tool, reverse, r_end, w_tool, row, params)
    st, c, reachable, q, ep, eg, ins, mu, _ = every_branch_settled(
        addr, params, world.reshape((1, 4, 4)), nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond,
        reach, tol, scale, s_thr, meet, only_inside,
    )  # fmt: skip
    return st, c, reachable, q, ep, eg, ins, mu


class ClosedPose:
    """One arm's closed form, ready for single poses: its fixed arguments worked out once (``of``), then
    ``solve(pose, limits)`` per pose."""

    __slots__ = ("robot", "held", "_head", "_tail", "_base", "_tool")

    def __init__(self, arm: Robot, held: HeldJoints | None, head: tuple[Any, ...], tail: tuple[Any, ...]) -> None:
        self.robot = arm if held is None else held.robot  # (the solutions' arm)
        self.held = held
        self._head = head  # (pose_rows' arguments)
        self._tail = tail  # (every_branch_settled's, but the rows and target; then the meeting reach)
        # (``chunk.chain_poses``' transforms, None for the identity)
        self._base = None if arm.base_is_identity else arm.T_base_world
        self._tool = None if arm.tool_is_identity else arm.T_tool_flange

    @classmethod
    def of(cls, robot: Robot, red: Reduction, held: HeldJoints | None = None) -> ClosedPose | None:
        """``robot`` (with ``held``: the held arm, ``held.arm``) solved by ``red`` this way, or None where ``red``
        does not qualify (module docstring)."""
        rc = type(red)
        if not red.closed_form or getattr(red, "companion", None) is not None:
            return None
        if (
            defining_class(rc, "special_solutions") is not Reduction
            or defining_class(rc, "blind_spot") is not Reduction
        ):
            return None
        head = red.pose_row_args()
        bounds, reach = settle_bounds(robot), snap_reach(robot)
        fixed = closed_fixed(robot, red, bounds, reach)
        if head is None or fixed is None or fixed[0][_A_SING] == 0:
            return None  # (its singular set checked in Python: the general path)
        base, tool, reverse, r_end, w_tool, row = head
        head = (writable(base), writable(tool), bool(reverse), writable(r_end), writable(w_tool), writable(row))
        addr, nb, _, _, tail, s_thr = fixed
        return cls(robot, held, head, (addr, nb, *tail, s_thr, writable(per_joint(robot, MEET_REL))))

    def solve(self, pose: Array, limits: bool) -> tuple[int, Solutions | None]:
        """``(status, solutions)``: the solutions of ``pose`` (a C-contiguous, writable float64 ``(4, 4)``) as
        ``solve`` gives them (status ``OK``), or None where the general path must answer, with the status that says
        why (``one_pose``'s, or ``NOT_RIGID``; ``OK`` with more than ``MAX_ISOLATED_SOLUTIONS`` certified). Raises
        ``check_poses``' errors for a target that is not a rigid transform."""
        chain = pose
        if self._base is not None or self._tool is not None:  # (as ``chunk.chain_poses``: the same bits)
            with np.errstate(all="ignore"):  # (a target not finite: the kernel says so, ``check_poses`` raises)
                chain = pose[None] if self._base is None else self._base @ pose[None]
                chain = (chain if self._tool is None else chain @ self._tool)[0]
        status, c, reachable, q, ep, eg, ins, mu = _closed_pose(pose, chain, *self._head, *self._tail, limits)
        if status != OK or c > MAX_ISOLATED_SOLUTIONS:
            if status == NOT_RIGID:
                check_poses(pose)
            return status, None
        reason = None if q.shape[0] else no_solution_reason(reachable)
        if self.held is not None:
            q = self.held.expand(q)
        return status, Solutions.settled(q, ep, eg, ins, mu, reason, pose.copy(), self.robot)
