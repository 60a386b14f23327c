"""World tool poses to chain poses: ``T_base_world @ pose @ T_tool_flange``, the pose the reductions solve.

One compiled product (``chain_into``) for a batch (``chain_poses``) and inside the one-pose kernels
(``single_pose``), so that both give the same bits; NumPy's ``@`` on a (4, 4) goes through BLAS, which may sum in
another order. The sums run in a fixed order (no fast-math: LLVM does not reassociate them).
"""

from __future__ import annotations

import numpy as np
from numba import boolean, float64, njit
from numpy.typing import NDArray

from sweepik._jit import ERROR_MODEL, inlined, writable
from sweepik.model.robot import Robot

__all__ = ["chain_poses", "chain_into"]

Array = NDArray[np.float64]


@inlined
def chain_into(T, base, tool, has_base, has_tool, tmp, out):  # pragma: no cover
    """``out (4, 4)``: ``base @ T @ tool``, each factor only where its flag is set (``tmp (4, 4)``: scratch)."""
    src = T
    if has_base:
        for a in range(4):
            for c in range(4):
                tmp[a, c] = base[a, 0] * T[0, c] + base[a, 1] * T[1, c] + base[a, 2] * T[2, c] + base[a, 3] * T[3, c]
        src = tmp
    if has_tool:
        for a in range(4):
            for c in range(4):
                out[a, c] = (
                    src[a, 0] * tool[0, c] + src[a, 1] * tool[1, c] + src[a, 2] * tool[2, c] + src[a, 3] * tool[3, c]
                )
    else:
        for a in range(4):
            for c in range(4):
                out[a, c] = src[a, c]


@njit(
    (float64[:, :, ::1], float64[:, ::1], float64[:, ::1], boolean, boolean, float64[:, :, ::1]),
    cache=True,
    nogil=True,
    error_model=ERROR_MODEL,
)
def _chain_all(poses, base, tool, has_base, has_tool, out):  # pragma: no cover
    tmp = np.empty((4, 4))
    for i in range(poses.shape[0]):
        chain_into(poses[i], base, tool, has_base, has_tool, tmp, out[i])


def chain_poses(robot: Robot, poses: Array) -> Array:
    """The chain poses ``(N, 4, 4)`` of world tool poses ``(N, 4, 4)`` (``poses`` itself when the arm has neither a
    base nor a tool frame)."""
    if robot.base_is_identity and robot.tool_is_identity:
        return poses
    out = np.empty(poses.shape)
    _chain_all(
        writable(poses),
        robot.T_base_world,
        robot.T_tool_flange,
        not robot.base_is_identity,
        not robot.tool_is_identity,
        out,
    )
    return out
