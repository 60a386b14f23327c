"""Shared fixtures and helpers for the test suite.

Hypothesis profiles: ``dev`` (default) and ``ci`` (derandomized, so CI runs are reproducible). The ``ci``
profile is chosen when the environment variable ``CI`` is set (as .ci/run's caller does) or by
``HYPOTHESIS_PROFILE=ci``.
"""

from __future__ import annotations

import os

import numpy as np
import pytest
from hypothesis import HealthCheck, settings
from numpy.typing import NDArray

from sweepik import Joint, Robot, load_robot

settings.register_profile("dev", deadline=None, max_examples=50)
settings.register_profile(
    "ci",
    deadline=None,
    max_examples=50,
    derandomize=True,
    database=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))


@pytest.fixture
def rng() -> np.random.Generator:
    """A seeded generator: every test that uses it sees the same numbers on every run."""
    return np.random.default_rng(20240607)


@pytest.fixture(scope="session")
def carm() -> Robot:
    return load_robot("carm")


@pytest.fixture(scope="session")
def puma() -> Robot:
    return load_robot("puma560")


@pytest.fixture(scope="session")
def puma_std() -> Robot:
    return load_robot("puma560_std")


def random_configs(
    robot: Robot, rng: np.random.Generator, size: int | tuple[int, ...], spread: float = 1.0
) -> NDArray[np.float64]:
    """Uniform configurations ``(*size, n)`` over the joint ranges scaled by ``spread`` about their centres.

    ``spread = 3`` samples three times each range, so about two thirds of each joint's values lie outside
    its limits.
    """
    size = (size,) if isinstance(size, int) else size
    mid = 0.5 * (robot.lower + robot.upper)
    half = 0.5 * spread * (robot.upper - robot.lower)
    return rng.uniform(mid - half, mid + half, size=(*size, robot.n_joints))


def rot_x(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1]], dtype=np.float64)


def rot_z(a: float) -> NDArray[np.float64]:
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]], dtype=np.float64)


def trans(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


def random_rotation(rng: np.random.Generator) -> NDArray[np.float64]:
    """A uniformly distributed rotation (3, 3), from a normalised Gaussian quaternion."""
    q = rng.normal(size=4)
    w, x, y, z = q / np.linalg.norm(q)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def random_pose(rng: np.random.Generator, scale: float = 1.0) -> NDArray[np.float64]:
    T = np.eye(4)
    T[:3, :3] = random_rotation(rng)
    T[:3, 3] = rng.uniform(-scale, scale, 3)
    return T


def axis_angle(axis: NDArray[np.float64], angle: float) -> NDArray[np.float64]:
    """Rotation (3, 3) by ``angle`` about ``axis`` (Rodrigues' formula)."""
    k = np.asarray(axis, dtype=np.float64)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * (K @ K)


def random_dh_robot(
    rng: np.random.Generator,
    convention: str = "standard",
    n: int | None = None,
    tool: bool = True,
    base: bool = True,
) -> Robot:
    """A random arm (mixed joint types) with random base and tool transforms."""
    n = int(rng.integers(1, 8)) if n is None else n
    joints = []
    for i in range(n):
        prismatic = rng.random() < 0.3
        joints.append(
            Joint(
                "prismatic" if prismatic else "revolute",
                a=float(rng.uniform(-1, 1)),
                alpha=float(rng.uniform(-np.pi, np.pi)),
                d=float(rng.uniform(-1, 1)),
                theta=float(rng.uniform(-np.pi, np.pi)),
                lower=-1.0 if prismatic else -np.pi,
                upper=1.0 if prismatic else np.pi,
                name=f"j{i + 1}",
            )
        )
    return Robot(
        "random",
        tuple(joints),
        dh_convention=convention,  # type: ignore[arg-type]
        T_world_base=random_pose(rng) if base else np.eye(4),
        T_flange_tool=random_pose(rng) if tool else np.eye(4),
        length_unit="m",
    )


def carm_stress_configurations(n: int, seed: int) -> NDArray[np.float64]:
    """``(n, 6)`` in-limit C-Arm configurations, with stress subsets: theta5 near 0, theta2 near +-90 deg (1e-4 off),
    d1 at a rail end."""
    carm = load_robot("carm")
    rng = np.random.default_rng(seed)
    q = rng.uniform(carm.lower, carm.upper, (n, 6))
    k = n // 5
    q[:k, 4] = rng.normal(0.0, 1e-3, k)
    q[k : 2 * k, 1] = np.pi / 2 * rng.choice([-1, 1], k) + rng.normal(0.0, 1e-4, k)
    q[2 * k : 3 * k, 0] = rng.choice([0.0, 2000.0], k)
    return q
