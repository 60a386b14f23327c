"""Chain geometry (product of exponentials), origin + axis robots, robots as values, and structure detection."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import sweepik
from sweepik.errors import RobotDefinitionError
from sweepik.model import kinematics
from sweepik.model.chain import rotation_about
from sweepik.model.robot import Joint, Robot

BUNDLED = sweepik.bundled_robots()


def _random_rotation(rng: np.random.Generator) -> np.ndarray:
    Q = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    if np.linalg.det(Q) < 0:
        Q[:, 0] *= -1
    return Q


def _random_robot(rng: np.random.Generator, types: str, convention: str = "modified") -> Robot:
    joints = []
    for t in types:
        joints.append(
            Joint(
                "revolute" if t == "R" else "prismatic",
                a=float(rng.uniform(-1, 1)),
                alpha=float(rng.uniform(-np.pi, np.pi)),
                d=float(rng.uniform(-1, 1)),
                theta=float(rng.uniform(-np.pi, np.pi)),
                lower=-3.0,
                upper=3.0,
            )
        )
    base = np.eye(4)
    base[:3, :3] = _random_rotation(rng)
    base[:3, 3] = rng.normal(size=3)
    tool = np.eye(4)
    tool[:3, :3] = rotation_about(np.array([0.0, 0.6, 0.8]), 1.1)
    tool[:3, 3] = rng.normal(size=3)
    return Robot("rand", tuple(joints), dh_convention=convention, T_world_base=base, T_flange_tool=tool)  # type: ignore[arg-type]


@pytest.mark.parametrize("name", BUNDLED)
def test_chain_fk_matches_robot_fk(name: str) -> None:
    robot = sweepik.load_robot(name)
    q = np.random.default_rng(1).uniform(-2.0, 2.0, (40, robot.n_joints))
    tol = 1e-12 * max(robot.length_scale, 1.0)
    np.testing.assert_allclose(robot.chain.fk(q), robot.fk(q), atol=tol)


@pytest.mark.parametrize("types", ["RRRRRR", "PRRRRR", "RRPRRR", "RPRPRP"])
@pytest.mark.parametrize("convention", ["modified", "standard"])
def test_chain_of_random_arms_and_reversed_chain(types: str, convention: str) -> None:
    rng = np.random.default_rng(len(types) + 7 * len(convention) + types.count("P"))
    robot = _random_robot(rng, types, convention)
    q = rng.uniform(-3.0, 3.0, (30, robot.n_joints))
    np.testing.assert_allclose(robot.chain.fk(q), robot.fk(q), atol=1e-12)
    inv = np.linalg.inv(robot.fk(q))
    np.testing.assert_allclose(robot.chain.reversed().fk(q[:, ::-1]), inv, atol=1e-11)
    np.testing.assert_allclose(robot.chain.reversed().reversed().fk(q), robot.fk(q), atol=1e-11)


def _origin_axis_copy(robot: Robot, rng: np.random.Generator) -> Robot:
    """The same arm written with origin + axis joints whose axes are not z (each joint frame randomly rotated)."""
    frames = kinematics.chain_frames(robot, np.zeros(robot.n_joints))
    n = robot.n_joints
    # the frame each joint moves in, at q = 0: modified DH frame i, standard DH frame i - 1
    moving = frames[:n] if robot.dh_convention == "standard" else frames[1:]
    joints, parent = [], robot.T_world_base
    for j, J in zip(robot.joints, moving, strict=True):
        F = np.eye(4)
        F[:3, :3] = _random_rotation(rng)
        child = J @ F
        origin = np.linalg.inv(parent) @ child
        # (DH joints move about z of their frame; origin + axis joints about their own axis, not always z)
        axis = F[:3, :3].T @ (np.array(j.axis) if robot.dh_convention == "none" else np.array([0.0, 0.0, 1.0]))
        joints.append(
            Joint(j.type, lower=j.lower, upper=j.upper, name=j.name, origin=tuple(map(tuple, origin)), axis=tuple(axis))  # type: ignore[arg-type]
        )
        parent = child
    tool = np.linalg.inv(parent) @ frames[n] @ robot.T_flange_tool
    return Robot(
        robot.name + "-oa", tuple(joints), dh_convention="none", T_world_base=robot.T_world_base, T_flange_tool=tool
    )


@pytest.mark.parametrize("name", BUNDLED)
def test_origin_axis_robot_equals_dh_robot(name: str) -> None:
    rng = np.random.default_rng(3)
    robot = sweepik.load_robot(name)
    oa = _origin_axis_copy(robot, rng)
    q = rng.uniform(-2.0, 2.0, (25, robot.n_joints))
    tol = 1e-11 * max(robot.length_scale, 1.0)
    np.testing.assert_allclose(oa.fk(q), robot.fk(q), atol=tol)
    np.testing.assert_allclose(oa.jacobian(q), robot.jacobian(q), atol=tol)
    np.testing.assert_allclose(oa.chain.fk(q), robot.fk(q), atol=tol)
    assert oa.structure().describe() == robot.structure().describe()


def test_origin_axis_joint_validation() -> None:
    with pytest.raises(RobotDefinitionError, match="axis"):
        Joint("revolute", origin=tuple(map(tuple, np.eye(4))), axis=(0.0, 0.0, 0.0))
    with pytest.raises(RobotDefinitionError, match="origin"):
        Joint("revolute", origin=((1.0, 2.0), (3.0, 4.0)))
    with pytest.raises(RobotDefinitionError, match="needs an origin"):
        Robot("x", (Joint("revolute"),), dh_convention="none")
    with pytest.raises(RobotDefinitionError, match="only with dh_convention 'none'"):
        Robot("x", (Joint("revolute", axis=(1.0, 0.0, 0.0)),))


@pytest.mark.parametrize("name", BUNDLED)
def test_robots_are_values(name: str) -> None:
    a, b = sweepik.load_robot(name), sweepik.load_robot(name)
    c = pickle.loads(pickle.dumps(a))
    assert a == b == c and hash(a) == hash(b) == hash(c)
    assert len({a, b, c}) == 1
    tool = np.array(a.T_flange_tool)
    tool[0, 3] += 1e-3
    assert Robot(a.name, a.joints, a.dh_convention, a.T_world_base, tool) != a
    q = np.zeros(a.n_joints)
    assert np.array_equal(c.fk(q), a.fk(q))


def test_unpickled_robot_solves() -> None:
    arm = sweepik.load_robot("carm")
    clone = pickle.loads(pickle.dumps(arm))
    q = np.array([700.0, 0.3, 0.2, -0.4, 0.5, 0.1])
    sols = sweepik.solve(clone, arm.fk(q))
    assert np.min(np.abs(sols.q - q).max(axis=1)) < 1e-6
    red = sweepik.reductions.CArmD1(arm)  # built for the original, used with its unpickled copy
    assert sweepik.solve(clone, arm.fk(q), reduction=red).q.shape == sols.q.shape


def test_structure_of_bundled_arms() -> None:
    carm = sweepik.load_robot("carm").structure()
    assert carm.types == "PRRRRR"
    assert carm.intersecting(1, 2) and carm.is_parallel(2, 3) and carm.intersecting(3, 4) and carm.intersecting(4, 5)
    assert not carm.intersecting(2, 3) and not carm.common_point((3, 4, 5))
    puma = sweepik.load_robot("puma560").structure()
    assert puma.intersecting(0, 1) and puma.is_parallel(1, 2) and puma.common_point((3, 4, 5))
    assert puma.as_dict()["spherical"][-1] == [4, 5, 6]


def test_structure_tolerance_is_relative_to_the_arm() -> None:
    base = sweepik.load_robot("puma560")
    joints = list(base.joints)
    # move the wrist's axis 5 off axis 4 by 1e-6 of the arm's size: no longer one point at the default tolerance
    j = joints[4]
    joints[4] = Joint(j.type, a=j.a, alpha=j.alpha, d=j.d + 1e-6 * base.length_scale, theta=j.theta, name=j.name)
    off = Robot("off", tuple(joints), base.dh_convention)
    assert not off.structure().common_point((3, 4, 5))
    assert off.structure(tol_rel=1e-5).common_point((3, 4, 5))
