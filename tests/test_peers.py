"""The ssik adapter of sweepik.experiments.peers (skipped without ``ssik``): the chain handed to ssik reproduces the
arm's FK,
a prebuilt artifact is found only for the same geometry (base and tool transforms fitted), and ssik's solve under
the options the benchmark uses returns the set sweepik's default returns (joint limits applied, one configuration
per geometric branch: no second 2 pi winding of a joint whose limits span more than 2 pi). Arms chosen so that no
Raghavan-Roth derivation runs: a prebuilt artifact (CRX-10iA) and closed forms in ssik (UR5, PUMA)."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from oracles import in_limit_configurations, same_solution_set

import sweepik
from sweepik.experiments.peers import metres_per_unit, ssik_manipulator, ssik_prebuilt, ssik_solver, ssik_status

pytest.importorskip("ssik")


def _in_metres(robot: sweepik.Robot, T: np.ndarray) -> np.ndarray:
    out = np.array(T, dtype=np.float64)
    out[..., :3, 3] *= metres_per_unit(robot)
    return out


def _transform(zyz_deg: tuple[float, float, float], xyz: tuple[float, float, float]) -> np.ndarray:
    from scipy.spatial.transform import Rotation

    T = np.eye(4)
    T[:3, :3] = Rotation.from_euler("ZYZ", zyz_deg, degrees=True).as_matrix()
    T[:3, 3] = xyz
    return T


@pytest.mark.parametrize("name", ["xarm6", "puma560"])
def test_manipulator_reproduces_the_fk_in_metres(name: str) -> None:
    robot = sweepik.load_robot(name)  # the xArm6 is in millimetres
    arm = ssik_manipulator(robot)
    for q in np.random.default_rng(3).uniform(-np.pi, np.pi, (5, 6)):
        np.testing.assert_allclose(arm.fk(q), _in_metres(robot, robot.fk(q)), atol=1e-12)
    assert [tuple(b) for b in arm.joint_limits] == [tuple(b) for b in robot.limits]
    assert all(b is None for b in ssik_manipulator(robot, limits=False).joint_limits)


def test_prebuilt_found_with_other_base_and_tool() -> None:
    crx = sweepik.load_robot("fanuc_crx10ia")
    pre = ssik_prebuilt(crx)
    assert pre is not None and pre.name == "fanuc_crx10ia_ik" and pre.same_limits
    # the same arm on another base, with a tool: the artifact still fits, through other A and B
    moved = dataclasses.replace(
        crx,
        T_world_base=_transform((30.0, 20.0, -50.0), (0.2, -0.1, 0.4)),
        T_flange_tool=_transform((-10.0, 70.0, 15.0), (0.01, 0.02, 0.15)),
    )
    other = ssik_prebuilt(moved)
    assert other is not None and other.name == pre.name and not np.allclose(other.A, pre.A)
    for q in np.random.default_rng(5).uniform(-np.pi, np.pi, (5, 6)):
        np.testing.assert_allclose(other.A @ other.module.fk(q) @ other.B, moved.fk(q), atol=1e-12)
        np.testing.assert_allclose(other.target(moved.fk(q), 1.0), other.module.fk(q), atol=1e-12)
    # rounded published parameters (~1e-5 off ssik's URDF) and another joint convention are no match
    assert ssik_prebuilt(sweepik.load_robot("xarm6")) is None
    assert ssik_prebuilt(sweepik.load_robot("puma560")) is None


@pytest.mark.parametrize(
    ("name", "sources"),
    [
        ("fanuc_crx10ia", ("prebuilt",)),  # its joint 6 spans 450 degrees: sometimes two windings
        ("ur5", ("native",)),  # every joint +-360 degrees: 64 windings per branch
        ("ur5", ("live",)),
    ],
)
def test_solver_returns_sweepiks_default_set(name: str, sources: tuple[str, ...]) -> None:
    robot = sweepik.load_robot(name)
    solve, about = ssik_solver(robot, sources=sources)
    assert about["source"] == sources[0]
    for q in in_limit_configurations(robot, 8, np.random.default_rng(11)):
        T = robot.fk(q)
        ours = sweepik.solve(robot, T)
        theirs = np.array([s.q for s in solve(T)]).reshape(-1, 6)
        assert np.all(robot.within_limits(theirs))
        assert same_solution_set(ours.q, theirs, robot.is_revolute, robot.length_scale)
        # compared modulo 2 pi above; as many on both sides: neither lists a second winding of a branch
        assert len(ours.q) == len(theirs) == len(np.unique(np.round(np.mod(theirs, 2 * np.pi), 6), axis=0))


def test_status() -> None:
    carm = sweepik.load_robot("carm")
    status = ssik_status(carm)
    assert status["solves"] is False and status["why"] == "not 6R" and "PRRRRR" in status["reason"]
    crx = ssik_status(sweepik.load_robot("fanuc_crx10ia"))
    assert crx == {"solves": True, "source": "prebuilt", "artifact": "fanuc_crx10ia_ik", "solver": "ikgeo.general_6r"}
    with pytest.raises(ValueError, match="unknown ssik source"):
        ssik_solver(sweepik.load_robot("ur5"), sources=("nosuch",))
