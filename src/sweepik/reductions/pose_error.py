"""A reduction without a residual searched on its pose error (``Reduction.residual`` gives None): the engine's
sweep looks for the zeros of the pose error of each branch's configuration, as minima that touch zero."""

from __future__ import annotations

import numpy as np

from sweepik.model import kinematics
from sweepik.model.pose import pose_error_geodesic
from sweepik.reductions.base import Array, IntArray, Reduction

__all__ = ["PoseErrorResidual"]


class PoseErrorResidual(Reduction):
    """Wraps a reduction without a residual: its "residual" is the pose error (position + weight x angle,
    length unit) of each branch's configuration. Non-negative, so roots show up as local minima that touch
    zero; the engine's extremum search and the FK certification handle them (at some cost in speed).
    """

    def __init__(self, inner: Reduction, weight: float) -> None:
        super().__init__(inner.robot, inner.free_joint, inner.n_branches)
        self.inner = inner
        self.weight = weight
        self.name = inner.name
        self.residual_noise = 1e-14 * inner.robot.length_scale
        self._inv_base = np.linalg.inv(inner.robot.T_world_base)

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        return self.inner.solve_rest(poses, theta, branch)

    def residual(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        q = self.inner.solve_rest(poses, theta, branch)
        T = self._inv_base @ kinematics.chain_frames(self.robot, q)[..., -1, :, :]
        target = poses.reshape(poses.shape[0], *((1,) * (q.ndim - 2)), 4, 4)
        return pose_error_geodesic(T, target, self.weight)

    def sample_hints(self, poses: Array) -> Array | None:
        return self.inner.sample_hints(poses)

    def edge_reduction(self, poses: Array, hints: Array | None) -> tuple[Reduction, Array, Array] | None:
        return self.inner.edge_reduction(poses, hints)
