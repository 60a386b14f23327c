"""A seven-joint arm held at one joint whose held arm has a near-structure: both plans' calls take the lock value.

The Kinova Gen3 held at joint 2, 3, 4 or 6 leaves a six-joint arm with a nearly spherical wrist or shoulder at every
value: a near-structure of joints on one side of the held one, which the value does not change. Such an arm is solved
by a chosen plan and a companion, their answers joined (``engine.companion``). Each new lock value chose the plans
again (every plan checked at a value seen first, or the short check of the plan chosen before) and built both
reductions: 8-9 ms a value, where the same value again takes 0.2-0.5 ms.

Here the pair is chosen once, for every value:

* the automatic choice at the first of ``held_pose.REFERENCES`` (every plan checked), a plan and its companion; at
  the other four each of the two must pass the short check (``reductions.held_pair``) and be the same plan, built by
  ``held_pose``'s compiled call from the value (``HeldPose.from_references``, each plan on its own);
* the values near which the held arm is another arm are ``lock_windows``' windows, answered the general way: another
  structure, another near-structure or the same one of another size, and the values where axes turn perpendicular
  at which the pair does not pass the short check;
* at every other value the general way takes the same pair, unchecked (``reductions.vouch_held_plan``), so that a
  pose this module hands on is solved by the plans it would have been.

That a pair which passes at the references and where axes turn perpendicular holds at every other value is not
proven, as an exact structure's plan is (``held_pose``): a plan's blind spots near a near-structure are found by
sampling configurations, at each value as here. Measured instead (the Gen3 held at joints 2, 3, 4 and 6, 100 random
values each, 12 configurations at each, a third with the wrist near or at its singular set): the pair recovered every
configuration, as did the choice at each value; the chosen plan alone missed one.

A pose goes the general way where either call does not settle it, or where a companion's solution lies within
``MEET_REL`` of one of the first's without being its duplicate (whether they are one root is settled on the held arm,
``settle.one_root``, which is not built here).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.chunk import one_block, resumed
from sweepik.engine.companion import joined
from sweepik.engine.held_pose import SPECIAL, HeldPose, at_turn, references
from sweepik.engine.lock_windows import in_windows, special_windows, window_reference
from sweepik.engine.one_pose import DUE, OK
from sweepik.engine.single_pose import SinglePose, settles
from sweepik.model.origin_axis import HeldJoints, hold_joints
from sweepik.model.robot import Robot
from sweepik.reductions import (
    GeometricReduction,
    PlanSignature,
    Reduction,
    paired_reduction,
    plan_signature,
    vouch_held_plan,
)
from sweepik.results import Block, Solutions

__all__ = ["HeldJoined"]

Array = NDArray[np.float64]
#: ``reductions.held_pair``: the pair at a held arm, chosen (None) or checked.
PairOf = Callable[[Robot, "tuple[PlanSignature, PlanSignature] | None"], "Reduction | None"]


class HeldJoined:
    """A seven-joint arm with revolute joint ``k`` held, solved by a plan and its companion whose arguments the
    compiled calls build from the lock value (module docstring): ``of(robot, k, pair_of)``, then
    ``solve(pose, value, limits)`` per pose, as ``HeldPose``."""

    __slots__ = ("robot", "joint", "arm", "windows", "pair", "first", "second")

    def __init__(
        self, pair: tuple[PlanSignature, PlanSignature], first: HeldPose, second: HeldPose, windows: Array
    ) -> None:
        self.robot, self.joint, self.arm = first.robot, first.joint, first.arm
        #: the values the general way answers (``lock_windows.special_windows``)
        self.windows = windows
        self.pair = pair  # (the plans' and companion's signatures)
        self.first = first
        self.second = second

    @classmethod
    def of(cls, robot: Robot, k: int, pair_of: PairOf) -> HeldJoined | None:
        """``robot`` with joint ``k`` held, its pair chosen and checked at ``REFERENCES`` (``pair_of(arm, pair)``:
        ``reductions.held_pair``); None where it does not qualify (not seven joints, the first or last joint or a
        slide held, no companion, a plan that is not a sweep or closed form of ``SinglePose`` or not the same at
        every reference, a row that is not the full chain moved, a reference at a special value)."""
        values = references(robot, k)
        if values is None or k in (0, robot.n_joints - 1):  # (the first and last: ``turned_lock``, whatever the arm)
            return None
        found: tuple[list[tuple[float, Any, SinglePose]], list[tuple[float, Any, SinglePose]]] = ([], [])
        pair: tuple[PlanSignature, PlanSignature] | None = None
        for v in values:
            held = hold_joints(robot, {k: v})
            red = pair_of(held.arm, pair)
            comp = getattr(red, "companion", None)
            if not (isinstance(red, GeometricReduction) and isinstance(comp, GeometricReduction)):
                return None
            first, second = SinglePose.of(held.arm, red, held, alone=True), SinglePose.of(held.arm, comp, held)
            if first is None or second is None:
                return None
            found[0].append((v, red, first))
            found[1].append((v, comp, second))
            pair = pair or (plan_signature(red.plan), plan_signature(comp.plan))
        assert pair is not None
        made = [HeldPose.from_references(robot, k, f) for f in found]
        if made[0] is None or made[1] is None:
            return None
        chosen = pair

        def pair_at(arm: Robot) -> object:
            return chosen if pair_of(arm, chosen) is not None else None

        windows = special_windows(robot, k, made[0].chain_at, lambda v: at_turn(robot, k, v, pair_at), values[0])
        if any(in_windows(v, windows) for v in values):
            return None
        out = cls(pair, made[0], made[1], windows)
        vouch_held_plan(robot, (k,), pair[0], out.window_reference, companion=pair[1])
        return out

    def special(self, value: float) -> bool:
        """Whether ``value`` is in ``windows`` (the held arm there may be another arm)."""
        return in_windows(value, self.windows)

    def window_reference(self, value: float) -> float | None:
        """The reference value of the window of ``windows`` that holds ``value``, None outside them
        (``lock_windows.window_reference``)."""
        return window_reference(value, self.windows)

    def joined(self, pose: Array, value: float, limits: bool) -> Block | int:
        """The block of ``pose`` (checked, C-contiguous, writable) at ``value``: both calls' answers joined; else the
        status with which the general way answers (``SPECIAL`` at a value in ``windows``). Raises as
        ``SinglePose.solve`` for a pose that is not a rigid transform."""
        if in_windows(value, self.windows):
            return SPECIAL
        outs = []
        for part in (self.first, self.second):
            out = part.call(pose, value, limits)
            if not (out[0] == DUE and part.sweeps) and not settles(out, pose):
                return int(out[0])
            outs.append(out)
        poses = pose.reshape(1, 4, 4)
        if outs[0][0] != DUE and outs[1][0] != DUE:
            both = joined(self.first.block_of(poses, [outs[0]]), self.second.block_of(poses, [outs[1]]), False)
            if both is not None:
                return both
        # (a sweep's pose due a polish, or two solutions that may be one root: on the held arm at this value)
        held = hold_joints(self.robot, {self.joint: value})
        parts = zip((self.first, self.second), outs, strict=True)
        a, b = (_held_block(held, part, value, poses, out, limits) for part, out in parts)
        both = joined(a, b)
        assert both is not None
        return both.expanded(held)

    def solve(self, pose: Array, value: float, limits: bool) -> tuple[int, Solutions | None]:
        """``HeldPose.solve``: the solutions, or None with the status where the general way answers."""
        got = self.joined(pose, value, limits)
        if isinstance(got, Block):
            return OK, got.solutions(0, copy=False)
        return got, None

    def blocks(
        self, poses: Array, values: Array, limits: bool, general: Callable[[int], Iterable[Block]]
    ) -> list[Block]:  # fmt: skip
        """``HeldPose.blocks``: pose ``i`` at ``values[i]``, each in a block of its own or as ``general(i)`` gives
        it."""
        out: list[Block] = []
        for i in range(poses.shape[0]):
            got = self.joined(poses[i], float(values[i]), limits)
            if isinstance(got, Block):
                out.append(got)
            else:
                out.extend(general(i))
        return out


def _held_block(
    held: HeldJoints, part: HeldPose, value: float, poses: Array, out: tuple[Any, ...], limits: bool
) -> Block:  # fmt: skip
    """The held arm's block of ``poses (1, 4, 4)`` from ``part``'s answer ``out`` at ``value`` (full-length
    configurations): settled, or resumed from a sweep's candidates by its plan's reduction there (``DUE``:
    ``chunk.resumed``), as ``SinglePose.block``."""
    status, _, reachable, q, ep, eg, ins, mu = out
    q = np.ascontiguousarray(np.delete(q, held.held[0][0], axis=1))
    if status == DUE:  # (the plan alone: its companion is the other part's)
        red = paired_reduction(held.arm, part.plan_at(value), None)
        return resumed(held.arm, red, poses, q, ep, eg, mu, limits)
    return one_block(held.arm, poses, q, ep, eg, ins, mu, reachable)
