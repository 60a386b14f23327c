"""Helpers of the tests of the one compiled call (``test_single_pose``, ``test_joined_pose``, ``test_held_pose``,
``test_held_joined``): configurations that probe singular sets, ``solve`` without the one call, the comparison bit for
bit or to rounding."""

from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np
import pytest

import sweepik
from sweepik import solving
from sweepik.engine import chunk
from sweepik.results import Solutions


def configurations(robot: sweepik.Robot, rng: np.random.Generator, n: int = 24) -> np.ndarray:
    """Random configurations, a quarter with the wrist straight (joint 5 at 0), a quarter with joint 3 at 0."""
    q = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), (n, robot.n_joints))
    q[: n // 4, 4] = 0.0
    q[n // 4 : n // 2, 2] = 0.0
    return q


def general_path(monkeypatch: pytest.MonkeyPatch, robot: sweepik.Robot, T: np.ndarray, **kw: Any) -> Solutions:
    """``solve`` without the one call (neither ``single_pose``'s, ``joined_pose``'s nor ``chunk.settled``)."""
    with monkeypatch.context() as m:
        m.setattr(solving, "_single_pose", lambda *args, **kwargs: None)
        m.setattr(solving, "settled", lambda *args: None)
        m.setattr(chunk, "settled", lambda *args: None)
        return sweepik.solve(robot, T, **kw)


def assert_same(a: Solutions, b: Solutions) -> None:
    """``a`` and ``b`` hold the same values, bit for bit (families: as many)."""
    for f in dataclasses.fields(Solutions):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype, f.name
            np.testing.assert_array_equal(x, y, err_msg=f.name)
        elif f.name == "families":
            assert len(x) == len(y)
        else:
            assert x == y, f.name


def answered_by_one_call(robot: sweepik.Robot, T: np.ndarray, limits: bool = True, locked: Any = None) -> bool:
    """Whether the one call (``solving._single_pose``'s) answers ``T``."""
    fast = solving._single_pose(robot, locked)
    return fast is not None and fast.solve(np.ascontiguousarray(T), limits)[1] is not None


def assert_reproduced(robot: sweepik.Robot, sol: Solutions, T: np.ndarray, qq: np.ndarray) -> None:
    """Every solution of ``sol`` reaches ``T``, and ``qq`` is among them (modulo 2 pi) or the pose has families."""
    scale = robot.length_scale
    for s in sol.q:
        F = robot.fk(s)
        assert np.max(np.abs(F[:3, 3] - T[:3, 3])) < 1e-9 * scale and np.max(np.abs(F[:3, :3] - T[:3, :3])) < 1e-9
    d = np.abs(sol.q - qq)
    d[:, robot.is_revolute] = np.abs(np.angle(np.exp(1j * d[:, robot.is_revolute])))
    assert sol.families or (len(sol) and np.min(np.max(d, axis=1)) < 1e-6)


def answered_as_the_general_path(
    monkeypatch: pytest.MonkeyPatch, robot: sweepik.Robot, q: np.ndarray, locked: Any = None
) -> int:
    """For each configuration of ``q``, its pose solved with limits on and off: the general path's solutions bit
    for bit, every solution reaching the pose and the configuration among them (``assert_reproduced``). Returns how
    many of the ``2 len(q)`` solves the one call answered."""
    answered = 0
    for qq, T in zip(q, robot.fk(q), strict=True):
        for limits in (True, False):
            sol = sweepik.solve(robot, T, limits=limits, locked=locked)
            assert_same(sol, general_path(monkeypatch, robot, T, limits=limits, locked=locked))
            answered += answered_by_one_call(robot, T, limits, locked)
        assert_reproduced(robot, sweepik.solve(robot, T, limits=False, locked=locked), T, qq)
    return answered


def held_general(robot: sweepik.Robot, T: np.ndarray, k: int, value: float) -> Solutions:
    """The held arm of ``robot`` with joint ``k`` at ``value`` solved the general way (its own plan, no one call)."""
    return solving._solve_one(robot, T[None], None, "precise", True, solving.N_SAMPLES, None, {k: value}, False)


def same_to_rounding(a: Solutions, b: Solutions, robot: sweepik.Robot) -> None:
    """``a`` and ``b`` hold as many solutions, the same configurations to rounding, and the same reason."""
    assert len(a) == len(b)
    if len(a):
        d = np.sort(a.q, axis=0) - np.sort(b.q, axis=0)
        assert np.abs(d).max() < 1e-8 * max(1.0, robot.length_scale)
    assert a.reason == b.reason


def fk_ok(robot: sweepik.Robot, sol: Solutions, T: np.ndarray) -> None:
    """Every solution of ``sol`` reaches ``T`` to 1e-9 (times the length scale)."""
    F = robot.fk(sol.q)
    assert np.abs(F[..., :3, 3] - T[:3, 3]).max(initial=0.0) < 1e-9 * robot.length_scale
    assert np.abs(F[..., :3, :3] - T[:3, :3]).max(initial=0.0) < 1e-9
