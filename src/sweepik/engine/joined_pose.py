"""A single pose of an arm solved with a companion (a near-structure: ``engine.companion``), its plans' one calls first.

Such an arm is solved by its chosen plan and a companion plan, their answers joined. Every pose took the general way
for both (``chunk.solve_chunk``): ~330 us on the Kinova Gen3 lite and ~550 on the Doosan M0609, where ssik takes
~410 and a plan's compiled call 50-130. Here:

* the chosen plan's one call (``single_pose``) answers first, settled or from its candidates (a pose due a polish:
  ``chunk.resumed``); where it hands the pose on, the general way answers all of it, as before;
* where it answers, the companion's one call answers next, or else the general way for the companion alone;
* and the two are joined as ``solve_chunk`` joins them: the same answer to the bit, since each one call's answer is
  its plan's general answer (``tests/test_single_pose.py``).

A plan's one call is tried only where it answers at least half of the poses it is probed on (``PROBES``), and where
its plan qualifies (``SinglePose.of``: a general method's companion does not).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.chunk import solve_chunk
from sweepik.engine.one_pose import OK
from sweepik.engine.settings import N_SAMPLES
from sweepik.engine.single_pose import SinglePose
from sweepik.model.origin_axis import HeldJoints
from sweepik.model.robot import Robot
from sweepik.reductions import Reduction
from sweepik.results import Solutions

__all__ = ["JoinedPose", "PROBES", "SETTLES_OFTEN"]

Array = NDArray[np.float64]

#: How many poses of random configurations within the limits (a fixed seed) probe whether a plan's one call answers
#: often enough to be tried first (settled, or from its candidates: ``SinglePose.block``): ``SETTLES_OFTEN`` of them.
#: A call that hands most poses on (a search that needs the general path, families, roots that meet) would be paid on
#: top of the general way's answer. Every plan of the bundled and ssik's companion arms passes since a call's
#: candidates are taken on; before, the M0609's and the Piper's companions settled 0 and 1 of 40 poses, the I2RT
#: YAM's chosen plan 17.
PROBES = 16
SETTLES_OFTEN = 0.5


class JoinedPose:
    """An arm's reduction and its companion ready for single poses (``of``), then ``solve(pose, limits)`` per pose
    as ``SinglePose.solve``."""

    __slots__ = ("robot", "held", "arm", "reduction", "first", "second")

    def __init__(
        self, arm: Robot, red: Reduction, held: HeldJoints | None, first: SinglePose, second: SinglePose | None
    ) -> None:
        self.robot = arm if held is None else held.robot  # (the solutions' arm)
        self.held = held
        self.arm = arm  # (the solved arm: the held arm with ``held``)
        self.reduction = red
        self.first = first
        self.second = second

    @classmethod
    def of(cls, robot: Robot, red: Reduction, held: HeldJoints | None = None) -> JoinedPose | None:
        """``robot`` (the held arm with ``held``) solved by ``red`` and its companion this way; None where ``red``
        has no companion, does not qualify alone (``SinglePose.of``) or answers too few of the poses it is probed on
        (``PROBES``: each pose it hands on pays its one call on top of the general way's answer)."""
        comp = getattr(red, "companion", None)
        if comp is None:
            return None
        first = SinglePose.of(robot, red, held, alone=True)
        if first is None or not _settles_often(robot, first):
            return None
        second = SinglePose.of(robot, comp, held)
        return cls(robot, red, held, first, second if second is not None and _settles_often(robot, second) else None)

    def solve(self, pose: Array, limits: bool) -> tuple[int, Solutions | None]:
        """``SinglePose.solve``: the solutions, or None with the first plan's status where its call hands ``pose``
        on (the general way answers for both plans)."""
        out = self.first.call(pose, limits)
        first = self.first.block(pose, out, limits)
        if first is None:
            return out[0], None
        second = None  # (unless its one call answers the pose, the general way answers for the companion)
        if self.second is not None:
            second = self.second.block(pose, self.second.call(pose, limits), limits)
        poses = pose.reshape(1, 4, 4)
        block = solve_chunk(
            self.arm, self.reduction, poses, "precise", limits, N_SAMPLES, one_call=False, given=(first, second)
        )
        return OK, block.expanded(self.held).solutions(0, copy=False)


def _settles_often(arm: Robot, fast: SinglePose) -> bool:
    """Whether ``fast``'s one call answers at least ``SETTLES_OFTEN`` of ``PROBES`` poses of ``arm`` (the solved
    arm), settled or from its candidates (``SinglePose.block``)."""
    rng = np.random.default_rng(0)
    q = rng.uniform(np.maximum(arm.lower, -np.pi), np.minimum(arm.upper, np.pi), (PROBES, arm.n_joints))
    poses = np.ascontiguousarray(arm.fk(q))
    answered = sum(fast.block(pose, fast.call(pose, True), True) is not None for pose in poses)
    return answered >= SETTLES_OFTEN * PROBES
