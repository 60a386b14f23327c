"""A second decomposition's solutions joined to the first's, for arms whose near-structure can hide a root from one.

On an arm with a near-structure every plan was checked on the arm (:mod:`sweepik.plan_check`), and several pass: on
the Kinova Gen3 with joint 3 locked six plans gave back all 64 configurations of the check. Still, the one chosen
lost 4 of the 8 solutions of one pose in 200 (a configuration far from any singularity), which another plan found.
Two plans sweeping different joints lose a root together far more rarely than one alone, so an arm with a
near-structure is solved by its chosen plan and its **companion** (``decompose.companion_plan``: the best checked
plan sweeping another joint or the other chain), and the two answers are joined pose by pose: a solution of the
companion is added where the first answer has none within the duplicate tolerance (``dedupe.DEDUPE_ANGLE``,
``DEDUPE_LENGTH_REL``), nor one that is the same root to the precision the pose fixes it (``settle.one_root``).
Families are the first answer's, and a solution of the companion that is a member of one of them is not added (the
first's own are reported by their family too). Arms without a near-structure have no companion and pay nothing.
"""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.dedupe import DEDUPE_ANGLE, DEDUPE_LENGTH_REL
from sweepik.engine.families import off_families
from sweepik.engine.settings import MEET_REL
from sweepik.engine.settle import one_root, per_joint
from sweepik.results import Block, joint_distance

__all__ = ["joined"]


def joined(first: Block, second: Block, meetings: bool = True) -> Block | None:
    """``first`` with the solutions of ``second`` (the same poses) that it lacks added, pose by pose. ``meetings``
    False: None where a solution of ``second`` lies within ``MEET_REL`` of one of ``first`` but not within the
    duplicate tolerance (whether they are one root is settled on the solved arm, ``settle.one_root``: the caller's
    blocks are of another arm, the full arm of a held one, ``engine.held_joined``)."""
    robot = first.robot
    tol = np.where(robot.is_revolute, DEDUPE_ANGLE, DEDUPE_LENGTH_REL * robot.length_scale)
    near = per_joint(robot, MEET_REL)
    take: list[NDArray[np.intp]] = []
    counts = np.zeros(first.n, dtype=np.intp)
    mult = first.multiplicity
    for i in range(first.n):
        a = first.q[first.bounds[i] : first.bounds[i + 1]]
        b_rows = np.arange(second.bounds[i], second.bounds[i + 1])
        if b_rows.size == 0:
            continue
        b = second.q[b_rows]
        new = np.ones(b_rows.size, dtype=bool)
        if a.shape[0]:
            d = joint_distance(robot, b[:, None, :], a[None, :, :])
            new = ~np.any(np.all(d <= tol, axis=-1), axis=1)
            # (one within MEET_REL of the first's may be the same root, to the precision the pose fixes it)
            for k in np.flatnonzero(new & np.any(np.all(d <= near, axis=-1), axis=1)):
                if not meetings:
                    return None
                row = b_rows[k]
                for j in np.flatnonzero(np.all(d[k] <= near, axis=-1)):
                    at = first.bounds[i] + j
                    ea, eb = first.error_geodesic[at], second.error_geodesic[row]
                    if one_root(robot, first.poses[i], a[j], b[k], ea, eb) is not None:
                        new[k] = False
                        mult = mult.copy() if mult is first.multiplicity else mult
                        mult[at] = max(mult[at], second.multiplicity[row], 2)
                        break
        fams = first.families.get(i)
        if fams and new.any():  # (a member of the first's families is reported by its family, as the first's own)
            new[np.flatnonzero(new)[~off_families(robot, [(b[new], tuple(fams))])[0]]] = False
        if not new.all():
            b_rows = b_rows[new]
        take.append(b_rows)
        counts[i] = b_rows.size
    if not counts.any():
        return first if mult is first.multiplicity else dataclasses.replace(first, multiplicity=mult)
    extra = np.concatenate(take)
    pose_of = np.concatenate(
        [np.repeat(np.arange(first.n), np.diff(first.bounds)), np.repeat(np.arange(first.n), counts)]
    )
    order = np.argsort(pose_of, kind="stable")

    def both(x: np.ndarray, y: np.ndarray) -> np.ndarray:
        return np.concatenate([x, y[extra]])[order]

    return Block(
        robot=robot,
        poses=first.poses,
        bounds=np.searchsorted(pose_of[order], np.arange(first.n + 1)).astype(np.intp),
        q=both(first.q, second.q),
        error=both(first.error, second.error),
        error_geodesic=both(first.error_geodesic, second.error_geodesic),
        within_limits=both(first.within_limits, second.within_limits),
        multiplicity=both(mult, second.multiplicity),
        families=first.families,
        n_reachable=np.maximum(first.n_reachable, second.n_reachable),
        empty_reason=first.empty_reason,
    )
