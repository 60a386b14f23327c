"""The reference IK oracles of tests/oracles.py agree with forward kinematics and with each other.

Four oracles: a many-start numerical search (always available), EAIK, IK-Geo and ssik (skipped when the packages
``EAIK`` / ``ik-geo`` / ``ssik`` are not installed). On the PUMA 560 (both DH conventions) and a UR5, for random
joint values q: each oracle's solution set contains q (modulo 2 pi), every solution it returns reproduces the pose,
and they return the same set for at least 95% of the poses.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from oracles import (
    contains,
    eaik_solutions,
    ikgeo_solutions,
    numerical_solutions,
    pose_errors,
    same_solution_set,
    ssik_solutions,
)

from sweepik import Robot, load_robot, robot_from_dict

N_POSES = 20
ROBOTS = ["puma560", "puma560_std", "ur5"]
SET_TOL = 1e-6  # joint-space tolerance when comparing solution sets (rad; prismatic relative to length_scale)


def _dh_robot(name: str, a: list[float], alpha_deg: list[float], d: list[float], **extra: object) -> Robot:
    joints = [
        {"type": "revolute", "a": a[i], "alpha": alpha_deg[i], "d": d[i], "limits": [-360.0, 360.0]} for i in range(6)
    ]
    return robot_from_dict({"name": name, "dh_convention": "standard", "length_unit": "m", "joints": joints, **extra})


def _ur5() -> Robot:
    return _dh_robot(
        "ur5",
        a=[0.0, -0.425, -0.39225, 0.0, 0.0, 0.0],
        alpha_deg=[90.0, 0.0, 0.0, 90.0, -90.0, 0.0],
        d=[0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823],
    )


@cache
def _robot(name: str) -> Robot:
    return _ur5() if name == "ur5" else load_robot(name)


@cache
def _cases(name: str) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """(q, pose, numerical solutions) for N_POSES random configurations within the limits (seeded)."""
    robot = _robot(name)
    rng = np.random.default_rng(sum(map(ord, name)))
    out = []
    for k in range(N_POSES):
        q = robot.lower + (robot.upper - robot.lower) * rng.random(robot.n_joints)
        pose = robot.fk(q)
        out.append((q, pose, numerical_solutions(robot, pose, seed=k)))
    return out


def _check_solutions(robot: Robot, q: np.ndarray, pose: np.ndarray, sols: np.ndarray, fk_tol: float) -> None:
    assert sols.ndim == 2 and sols.shape[1] == robot.n_joints
    assert contains(sols, q, robot.is_revolute, robot.length_scale, SET_TOL), "q itself is not among the solutions"
    dp, ang = pose_errors(robot.fk(sols), pose, robot.length_scale)
    assert np.all(dp <= fk_tol) and np.all(ang <= fk_tol)
    wrapped = sols[:, robot.is_revolute]
    assert np.all((wrapped > -np.pi) & (wrapped <= np.pi))
    # Distinct (modulo 2 pi).
    for i in range(len(sols)):
        assert not contains(np.delete(sols, i, axis=0), sols[i], robot.is_revolute, robot.length_scale, 1e-6)


def test_chain_fk_equals_robot_fk() -> None:
    """The product-of-exponentials description handed to EAIK / IK-Geo reproduces ``robot.fk``."""
    from oracles import _poe_fk

    rng = np.random.default_rng(7)
    for name in ROBOTS:
        robot = _robot(name)
        c = robot.chain
        for q in rng.uniform(-np.pi, np.pi, (5, 6)):
            R, p = _poe_fk(np.array(c.H), np.array(c.P), q)
            T = robot.fk(q)
            assert np.allclose(R @ c.R_end, T[:3, :3], atol=1e-12)
            assert np.allclose(p, T[:3, 3], atol=1e-12 * robot.length_scale)


@pytest.mark.parametrize("name", ROBOTS)
def test_numerical_oracle(name: str) -> None:
    robot = _robot(name)
    for q, pose, sols in _cases(name):
        _check_solutions(robot, q, pose, sols, 1e-9)
        assert len(sols) <= 16


@pytest.mark.parametrize("name", ROBOTS)
def test_eaik_oracle(name: str) -> None:
    pytest.importorskip("eaik")
    robot = _robot(name)
    for q, pose, _ in _cases(name):
        info: dict[str, object] = {}
        sols = eaik_solutions(robot, pose, info=info)
        assert sols is not None, info
        _check_solutions(robot, q, pose, sols, 1e-6)


@pytest.mark.parametrize("name", ROBOTS)
def test_ikgeo_oracle(name: str) -> None:
    pytest.importorskip("ik_geo")
    robot = _robot(name)
    for q, pose, _ in _cases(name):
        info: dict[str, object] = {}
        sols = ikgeo_solutions(robot, pose, info=info)
        assert sols is not None, info
        assert info["kind"] == "closed"
        _check_solutions(robot, q, pose, sols, 1e-6)


@pytest.mark.parametrize("name", ROBOTS)
def test_ssik_oracle(name: str) -> None:
    """ssik (live, on the robot's own chain, limits off) recovers q, answers only FK-exact configurations, and
    returns the numerical search's set on at least 95% of the poses."""
    pytest.importorskip("ssik")
    robot = _robot(name)
    agree = 0
    for q, pose, num in _cases(name):
        info: dict[str, object] = {}
        sols = ssik_solutions(robot, pose, info=info)
        assert sols is not None, info
        assert info["rejected"] == 0, info  # everything ssik returned passed the FK check
        _check_solutions(robot, q, pose, sols, 1e-6)
        agree += same_solution_set(sols, num, robot.is_revolute, robot.length_scale, SET_TOL)
    assert agree >= 0.95 * N_POSES, f"{name}: ssik and the numerical search agree on only {agree} of {N_POSES} poses"


@pytest.mark.parametrize("name", ROBOTS)
def test_oracles_agree(name: str) -> None:
    pytest.importorskip("eaik")
    pytest.importorskip("ik_geo")
    robot = _robot(name)
    rev, L = robot.is_revolute, robot.length_scale
    agree = 0
    for _, pose, num in _cases(name):
        ea = eaik_solutions(robot, pose)
        ig = ikgeo_solutions(robot, pose)
        assert ea is not None and ig is not None
        agree += same_solution_set(num, ea, rev, L, SET_TOL) and same_solution_set(ea, ig, rev, L, SET_TOL)
    assert agree >= 0.95 * N_POSES, f"{name}: the oracles agree on only {agree} of {N_POSES} poses"


def test_structure_at_the_base_and_base_tool_transforms() -> None:
    """A spherical shoulder (joints 1-3 meet) with base and tool transforms: IK-Geo runs on the reversed chain."""
    pytest.importorskip("eaik")
    pytest.importorskip("ik_geo")
    robot = _dh_robot(
        "shoulder",
        a=[0.0, 0.0, 0.3, 0.2, 0.1, 0.05],
        alpha_deg=[90.0, -90.0, 40.0, 70.0, -60.0, 20.0],
        d=[0.2, 0.0, 0.1, 0.15, 0.09, 0.08],
        base={"xyz": [0.1, -0.2, 0.3], "zyz": [10.0, 20.0, 30.0]},
        tool={"xyz": [0.0, 0.01, 0.1], "zyz": [-15.0, 25.0, 5.0]},
    )
    rng = np.random.default_rng(3)
    for k in range(4):
        q = rng.uniform(-np.pi, np.pi, 6)
        pose = robot.fk(q)
        info: dict[str, object] = {}
        ig = ikgeo_solutions(robot, pose, info=info)
        ea = eaik_solutions(robot, pose)
        assert ig is not None and ea is not None
        assert info["reversed"] is True and info["decomposition"] == "spherical"
        num = numerical_solutions(robot, pose, seed=k)
        for sols in (ig, ea, num):
            _check_solutions(robot, q, pose, sols, 1e-6)
        assert same_solution_set(ig, ea, robot.is_revolute, robot.length_scale, SET_TOL)
        assert same_solution_set(ig, num, robot.is_revolute, robot.length_scale, SET_TOL)


def test_unsupported_arms_give_none_and_numerical_handles_prismatic() -> None:
    carm = load_robot("carm")  # prismatic rail: neither package handles it
    q = np.array([500.0, 0.3, -0.7, 1.1, 0.4, -2.0])
    pose = carm.fk(q)
    assert eaik_solutions(carm, pose) is None
    assert ikgeo_solutions(carm, pose) is None
    assert ssik_solutions(carm, pose) is None  # ssik has no prismatic solver (also None without ssik)
    stanford = load_robot("stanford")
    assert ssik_solutions(stanford, stanford.fk(np.array([0.1, 0.2, 0.5, 0.3, 0.4, 0.5]))) is None
    _check_solutions(carm, q, pose, numerical_solutions(carm, pose), 1e-9)

    general = _dh_robot(  # no two axes parallel or intersecting: no closed form in either package
        "general",
        a=[0.1, 0.3, 0.05, 0.2, 0.15, 0.07],
        alpha_deg=[80.0, -30.0, 60.0, -75.0, 45.0, 20.0],
        d=[0.2, 0.05, 0.1, 0.15, 0.09, 0.08],
    )
    pose = general.fk(np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6]))
    assert ikgeo_solutions(general, pose) is None
    assert eaik_solutions(general, pose) is None
    _check_solutions(general, np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6]), pose, numerical_solutions(general, pose), 1e-9)
