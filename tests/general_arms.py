"""Random arms without structure (issue 37) and their poses, for tests and ``scripts/general_arms.py`` (no tests).

``random_arm(kind, seed)``: a six-joint arm in standard DH, ``a`` in [0.05, 0.4] m, ``d`` in [0.05, 0.3] m, twists
uniform on the circle, joint offsets random, a random base and tool: ``kind`` "6r" (all revolute), "5r1p" or "4r2p"
(one or two prismatic joints at random places, travel in [-0.5, 0.5] m). No two axes meet or are parallel (to the
precision of random numbers), so no structured decomposition applies.

``poses_of(robot, n, n_singular, seed)``: ``n`` configurations uniform over a turn (travel over the limits) and
``n_singular`` on or next to the singular set (``singular.singular_configurations``).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from singular import singular_configurations

from sweepik.io.robot_file import robot_from_dict
from sweepik.model.robot import Robot

KINDS = ("6r", "5r1p", "4r2p")


def random_arm(kind: str, seed: int, around: NDArray[np.float64] | None = None, width: float = 5.0) -> Robot:
    """(See the module docstring.) ``around``: limits ``width`` degrees (or ``width`` cm of travel) either side of
    this configuration instead."""
    rng = np.random.default_rng(37_000 + 101 * KINDS.index(kind) + seed)
    n_pris = KINDS.index(kind)
    prismatic = set(rng.choice(6, n_pris, replace=False).tolist()) if n_pris else set()
    joints = []
    for i in range(6):
        kind_i = "prismatic" if i in prismatic else "revolute"
        joints.append(
            {
                "name": f"j{i + 1}",
                "type": kind_i,
                "a": float(rng.uniform(0.05, 0.4)),
                "alpha": float(rng.uniform(-180.0, 180.0)),
                "d": float(rng.uniform(0.05, 0.3)),
                "theta": float(rng.uniform(-180.0, 180.0)),
                "limits": [-0.5, 0.5] if kind_i == "prismatic" else [-180.0, 180.0],
            }
        )
    if around is not None:
        for j, q in zip(joints, around, strict=True):
            v = float(np.degrees(q)) if j["type"] == "revolute" else float(q)
            w = width if j["type"] == "revolute" else width / 100.0
            j["limits"] = [v - w, v + w]
    data = {
        "name": f"general_{kind}_{seed}",
        "dh_convention": "standard",
        "length_unit": "m",
        "joints": joints,
        "base": {"xyz": rng.normal(scale=0.2, size=3).tolist(), "zyz": rng.uniform(-180, 180, 3).tolist()},
        "tool": {"xyz": rng.normal(scale=0.05, size=3).tolist(), "zyz": rng.uniform(-180, 180, 3).tolist()},
    }
    return robot_from_dict(data)


def poses_of(robot: Robot, n: int, n_singular: int, seed: int) -> NDArray[np.float64]:
    """``(n + n_singular, 6)`` configurations (see the module docstring)."""
    rng = np.random.default_rng(seed)
    lo = np.where(robot.is_revolute, -np.pi, robot.lower)
    hi = np.where(robot.is_revolute, np.pi, robot.upper)
    Q = rng.uniform(lo, hi, (n, robot.n_joints))
    if n_singular:
        Q = np.concatenate([Q, singular_configurations(robot, n_singular, rng)])
    return Q
