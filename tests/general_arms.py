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


def _rodrigues(k: NDArray[np.float64], t: float) -> NDArray[np.float64]:
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * (K @ K)


def dh_chain(k: int) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """``(H (6, 3), P (7, 3), R_end)``: the k-th random 6R arm of the elimination's prototype bench (standard DH from
    ``default_rng(1000 + k)``: twists, ``a`` in [0.05, 0.4] m, ``d`` in [0.05, 0.3] m, offsets; no base or tool) as
    a product-of-exponentials chain, computed as the prototype did, digit for digit: ssik's derivations of these arms
    are cached on disk under their exact geometry (``scripts/general_arms.py ssik-refs``)."""
    rng = np.random.default_rng(1000 + k)
    alpha = rng.uniform(-np.pi, np.pi, 6)
    a = rng.uniform(0.05, 0.4, 6)
    d = rng.uniform(0.05, 0.3, 6)
    theta0 = rng.uniform(-np.pi, np.pi, 6)
    F = np.eye(4)
    H, pts = [], []
    for i in range(6):
        H.append(F[:3, 2].copy())
        pts.append(F[:3, 3].copy())
        A = np.eye(4)
        A[:3, :3] = _rodrigues(np.array([0.0, 0.0, 1.0]), theta0[i]) @ _rodrigues(np.array([1.0, 0.0, 0.0]), alpha[i])
        A[:3, 3] = [a[i] * np.cos(theta0[i]), a[i] * np.sin(theta0[i]), d[i]]
        F = F @ A
    P = np.diff(np.array([np.zeros(3), *pts, F[:3, 3]]), axis=0)
    return np.array(H), P, F[:3, :3].copy()


def robot_of_chain(H: NDArray[np.float64], P: NDArray[np.float64], R_end: NDArray[np.float64], name: str) -> Robot:
    """A 6R arm, metres, limits [-180, 180] deg, written joint by joint (origin + axis) from a product-of-exponentials
    chain at q = 0: joint i's origin is ``P[i]`` (frames parallel to the base), its axis ``H[i]``, the tool ``P[6]``
    and ``R_end``."""
    from sweepik.model.pose import zyz_from_matrix

    joints = [
        {"name": f"j{i + 1}", "type": "revolute", "origin": {"xyz": P[i].tolist()}, "axis": H[i].tolist(),
         "limits": [-180.0, 180.0]}
        for i in range(6)
    ]  # fmt: skip
    tool = {"xyz": P[6].tolist(), "zyz": np.degrees(zyz_from_matrix(R_end)).tolist()}
    return robot_from_dict({"name": name, "length_unit": "m", "joints": joints, "tool": tool})
