"""ssik 8.2's prebuilt catalogue of vendors' arms (``ssik.list_arms()``) as sweepik robots, for tests and
``scripts/ssik_catalogue.py`` (ssik is in the ``bench`` extra; callers skip without it).

Each arm is rebuilt in origin + axis form from the artifact's own per-joint constants (``T_left[i] @ Rot(axis_i, q_i)
@ T_right[i]``), lengths in metres."""

from __future__ import annotations

import importlib

import numpy as np

from sweepik.model.robot import Joint, Robot


def ssik_module(name: str):  # type: ignore[no-untyped-def]
    import ssik

    entry = next(a for a in ssik.list_arms() if a.name == name)
    return importlib.import_module(entry.import_path)


def _tuple(T: np.ndarray) -> tuple[tuple[float, ...], ...]:
    return tuple(tuple(float(v) for v in row) for row in T)


def robot_from_ssik(name: str) -> Robot:
    """The ssik artifact ``name`` as a sweepik robot (origin + axis, metres, limits from the artifact)."""
    m = ssik_module(name)
    joints = []
    carry = np.eye(4)
    for i, (ax, TL, TR, ty, lim) in enumerate(
        zip(m._JOINT_AXES, m._JOINT_T_LEFTS, m._JOINT_T_RIGHTS, m._JOINT_TYPES, m._JOINT_LIMITS, strict=True)
    ):
        typ = "revolute" if ty in ("revolute", "continuous") else "prismatic"
        joints.append(
            Joint(
                typ,
                origin=_tuple(carry @ np.asarray(TL)),
                axis=tuple(float(v) for v in ax),
                lower=-np.pi if lim is None else float(lim[0]),
                upper=np.pi if lim is None else float(lim[1]),
                name=str(m._JOINT_NAMES[i]),
            )
        )
        carry = np.asarray(TR, dtype=np.float64)
    return Robot(name.removesuffix("_ik"), tuple(joints), "none", T_flange_tool=carry, length_unit="m")


def check_fk(robot: Robot, name: str, rng: np.random.Generator) -> float:
    m = ssik_module(name)
    Q = rng.uniform(-np.pi, np.pi, (20, robot.n_joints))
    return max(float(np.abs(robot.fk(q) - m.fk(q)).max()) for q in Q)


def catalogue_configurations(
    name: str, n: int = 200, n_singular: int = 50, rng: np.random.Generator | None = None
) -> tuple[Robot, np.ndarray]:
    """ssik's arm ``name`` as a sweepik robot and the configurations ``scripts/ssik_catalogue.py --n n --singular
    n_singular`` draws for it (seed 0, or from ``rng``, which then goes on as the script's does, e.g. to its
    ``--rewrite``): ``n`` uniform over a turn, then ``n_singular`` on and next to its singular set."""
    from singular import singular_configurations

    robot = robot_from_ssik(name)
    rng = np.random.default_rng(0) if rng is None else rng
    rng.uniform(-np.pi, np.pi, (20, 6))  # (``check_fk``'s draw)
    Q = rng.uniform(-np.pi, np.pi, (n, 6))
    return robot, np.concatenate([Q, singular_configurations(robot, n_singular, rng)])
