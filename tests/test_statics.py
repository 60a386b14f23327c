"""Static holding torques (sweepik.experiments.statics): against finite differences of the gravity potential (virtual
work),
through every way an arm can be written (DH either convention, origin + axis, joints held), and the robot file's
gravity and link masses."""

from __future__ import annotations

import dataclasses
import zlib

import numpy as np
import pytest
from oracles import in_metres

from sweepik import load_robot
from sweepik.errors import LockedJointError, RobotDefinitionError, RobotFileError, UnknownOptionError
from sweepik.experiments.statics import STANDARD_GRAVITY, gravity_torques, potential_energy
from sweepik.experiments.verify import random_configurations
from sweepik.io.robot_file import robot_from_dict, robot_to_toml
from sweepik.io.store import robot_from_json, robot_to_json
from sweepik.model.origin_axis import hold_joints, origin_axis_form
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit

ARMS = ["carm", "carm_swapped", "ur5", "puma560_std", "kuka_kr6_r900", "stanford", "kuka_iiwa14"]


def _with_masses(robot: Robot, rng: np.random.Generator) -> Robot:
    """``robot`` with random link masses and centres and a random gravity direction."""
    scale = robot.length_scale / robot.n_joints
    joints = tuple(
        dataclasses.replace(j, mass=float(rng.uniform(0.0, 8.0)), com=tuple(rng.normal(size=3) * scale))
        for j in robot.joints
    )
    return dataclasses.replace(robot, joints=joints, gravity=tuple(rng.normal(size=3)))


def _virtual_work(robot: Robot, q: np.ndarray, **kw: object) -> np.ndarray:
    """dV/dq by central differences, per metre for prismatic joints (the torques' units: N·m and N)."""
    h = 1e-6
    out = np.empty(q.shape)
    for i in range(robot.n_joints):
        step = np.zeros(robot.n_joints)
        step[i] = h
        d = (potential_energy(robot, q + step, **kw) - potential_energy(robot, q - step, **kw)) / (2 * h)
        out[:, i] = d if robot.is_revolute[i] else d * 1000.0 / mm_per_unit(robot.length_unit)
    return out


@pytest.mark.parametrize("name", ARMS)
def test_torques_are_the_gradient_of_the_potential(name: str) -> None:
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    robot = _with_masses(load_robot(name), rng)
    q = random_configurations(robot, 40, rng)
    kw = {"payload": 7.5, "payload_com": rng.normal(size=3) * robot.length_scale / 20}
    tau = gravity_torques(robot, q, **kw)
    fd = _virtual_work(robot, q, **kw)
    scale = np.abs(tau).max()
    assert scale > 1.0  # masses, not zeros
    np.testing.assert_allclose(tau, fd, atol=1e-6 * scale)


def test_payload_alone_and_links_switch() -> None:
    rng = np.random.default_rng(3)
    robot = _with_masses(load_robot("ur5"), rng)
    q = random_configurations(robot, 20, rng)
    both = gravity_torques(robot, q, payload=2.0)
    links = gravity_torques(robot, q)
    payload = gravity_torques(robot, q, payload=2.0, links=False)
    np.testing.assert_allclose(both, links + payload, atol=1e-9 * np.abs(both).max())
    assert np.all(gravity_torques(robot, q, links=False) == 0.0)


def test_lever_arm_by_hand() -> None:
    """C-Arm at the zero pose: gravity along +y (robot file), forearm horizontal along x: theta3 and theta4 carry
    the payload 402 mm out; the rail (horizontal) and the wrist joints (axes through the payload) carry nothing."""
    carm = load_robot("carm")
    assert carm.gravity == (0.0, 1.0, 0.0)
    tau = gravity_torques(carm, np.zeros(6), payload=12.0)
    lever = -12.0 * STANDARD_GRAVITY * 0.402
    np.testing.assert_allclose(tau, [0, 0, lever, lever, 0, 0], atol=1e-9)
    # a payload hanging 100 mm out along the tool's x axis (world -y: straight up) adds no lever about z
    up = gravity_torques(carm, np.zeros(6), payload=12.0, payload_com=(100.0, 0.0, 0.0))
    np.testing.assert_allclose(up, tau, atol=1e-9)


def test_vertical_rail_carries_the_weight() -> None:
    """Gravity along the rail: the prismatic joint holds the whole mass (N), whatever the configuration."""
    carm = dataclasses.replace(load_robot("carm"), gravity=(0.0, 0.0, -1.0))
    q = random_configurations(carm, 10, np.random.default_rng(0))
    tau = gravity_torques(carm, q, payload=12.0)
    np.testing.assert_allclose(tau[:, 0], 12.0 * STANDARD_GRAVITY)


def test_same_arm_in_metres() -> None:
    mm = _with_masses(load_robot("carm"), np.random.default_rng(5))
    assert mm.length_unit == "mm"
    m = in_metres(mm, "carm_m")
    q = random_configurations(mm, 20, np.random.default_rng(6))
    qm = np.where(mm.is_revolute, q, q / 1000)
    a = gravity_torques(mm, q, payload=3.0, payload_com=(10.0, -20.0, 30.0))
    b = gravity_torques(m, qm, payload=3.0, payload_com=(0.010, -0.020, 0.030))
    np.testing.assert_allclose(a, b, atol=1e-9 * np.abs(a).max())


@pytest.mark.parametrize("name", ["puma560_std", "carm", "ur5"])
def test_origin_axis_form_keeps_the_masses(name: str) -> None:
    rng = np.random.default_rng(11)
    robot = _with_masses(load_robot(name), rng)
    oa = origin_axis_form(robot)
    q = random_configurations(robot, 20, rng)
    a = gravity_torques(robot, q, payload=1.0)
    np.testing.assert_allclose(gravity_torques(oa, q, payload=1.0), a, atol=1e-9 * np.abs(a).max())


def test_held_joints_keep_their_links_weight() -> None:
    """A held joint's link rides on the previous free link: the smaller arm's torques are the full arm's."""
    rng = np.random.default_rng(12)
    robot = _with_masses(load_robot("kuka_iiwa14"), rng)
    for k in (0, 2, 6):
        q = random_configurations(robot, 15, rng)
        held = hold_joints(robot, {k: float(q[0, k])})
        q[:, k] = q[0, k]
        free = [i for i in range(7) if i != k]
        full = gravity_torques(robot, q, payload=2.0)[:, free]
        small = gravity_torques(held.arm, q[:, free], payload=2.0)
        np.testing.assert_allclose(small, full, atol=1e-9 * np.abs(full).max())


def test_robot_file_round_trip() -> None:
    rng = np.random.default_rng(13)
    for name in ("carm", "ur5", "puma560_std"):
        robot = _with_masses(load_robot(name), rng)
        again = load_robot_text(robot_to_toml(robot))
        assert again.gravity == pytest.approx(robot.gravity)
        assert [j.mass for j in again.joints] == [j.mass for j in robot.joints]
        assert [j.com for j in again.joints] == [j.com for j in robot.joints]
        assert robot_from_json(robot_to_json(robot)) == robot


def load_robot_text(text: str) -> Robot:
    import tomllib

    return robot_from_dict(tomllib.loads(text))


BASE = {"name": "one", "joints": [{"type": "revolute", "a": 100.0, "limits": [-90, 90]}]}


@pytest.mark.parametrize(
    ("patch", "words"),
    [
        ({"gravity": [0, 0, 0]}, "gravity"),
        ({"gravity": [0, 1]}, "gravity"),
        ({"gravity": "down"}, "gravity"),
        ({"joints": [{"type": "revolute", "limits": [-90, 90], "mass": -1.0}]}, "mass"),
        ({"joints": [{"type": "revolute", "limits": [-90, 90], "mass": "heavy"}]}, "mass"),
        ({"joints": [{"type": "revolute", "limits": [-90, 90], "com": [0, 0]}]}, "com"),
        ({"joints": [{"type": "revolute", "limits": [-90, 90], "com": [0, 0, float("nan")]}]}, "com"),
    ],
)
def test_bad_gravity_or_mass_in_a_file(patch: dict[str, object], words: str) -> None:
    with pytest.raises(RobotFileError, match=words):
        robot_from_dict({**BASE, **patch})


def test_bad_arguments() -> None:
    robot = load_robot("ur5")
    q = np.zeros(6)
    for bad in (-1.0, float("nan"), float("inf"), "12", True):
        with pytest.raises(UnknownOptionError, match="payload"):
            gravity_torques(robot, q, payload=bad)  # type: ignore[arg-type]
    for com in ((0, 0), (0, 0, float("nan")), "abc"):
        with pytest.raises(UnknownOptionError, match="payload_com"):
            gravity_torques(robot, q, payload=1.0, payload_com=com)  # type: ignore[arg-type]
    with pytest.raises(RobotDefinitionError, match="gravity"):
        dataclasses.replace(robot, gravity=(0.0, 0.0, 0.0))
    with pytest.raises(LockedJointError):
        hold_joints(robot, dict.fromkeys(range(6), 0.0))


def test_urdf_masses_round_trip() -> None:
    """urdf_text writes each link's mass and centre; robot_from_urdf reads them back (same torques)."""
    from sweepik.io.urdf import robot_from_urdf, urdf_text

    rng = np.random.default_rng(21)
    for name in ("carm", "puma560_std"):
        robot = _with_masses(load_robot(name), rng)
        back = robot_from_urdf(urdf_text(robot))
        back = dataclasses.replace(back, gravity=robot.gravity)  # URDF has no gravity: -z by default
        q = random_configurations(robot, 10, rng)
        qb = np.where(robot.is_revolute, q, q * mm_per_unit(robot.length_unit) / 1000.0)
        a = gravity_torques(robot, q, payload=1.0)
        np.testing.assert_allclose(gravity_torques(back, qb, payload=1.0), a, atol=1e-9 * np.abs(a).max())


def test_urdf_inertials_of_fixed_links_merge() -> None:
    """A link on a fixed joint after the last moving one rides on it; a link before the first rides on the base."""
    from sweepik.io.urdf import robot_from_urdf

    text = """<robot name="r">
      <link name="base"><inertial><mass value="50"/></inertial></link>
      <link name="a"><inertial><origin xyz="0.1 0 0"/><mass value="2"/></inertial></link>
      <link name="b"><inertial><origin xyz="0 0 0.2"/><mass value="1"/></inertial></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 1 0"/>
        <limit lower="-1" upper="1"/></joint>
      <joint name="f" type="fixed"><parent link="a"/><child link="b"/><origin xyz="0.5 0 0"/></joint>
    </robot>"""
    r = robot_from_urdf(text)
    assert r.joints[0].mass == 3.0
    assert r.joints[0].com == pytest.approx(((2 * 0.1 + 1 * 0.5) / 3, 0.0, 0.2 / 3))
    # about +y with gravity along -z, turning +x downwards: the holding torque is -(weight x lever along x)
    tau = gravity_torques(r, [0.0])
    assert tau[0] == pytest.approx(-0.7 * STANDARD_GRAVITY)
