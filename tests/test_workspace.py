"""Workspace volume (:mod:`sweepik.experiments.workspace`) against arms whose reachable workspace is known in closed
form.

Properties tested (each can fail):
* five arms with analytic volumes (a Cartesian gantry: a box; the gantry with a tool offset: the box dilated by
  the offset, Steiner's formula; a 2R arm on a vertical slide: annulus x height; the same with the first joint
  limited to a quarter turn: an annular-sector-like region computed by quadrature; a 3R arm: a spherical shell),
  all with a spherical wrist: the true volume lies within ``volume +- uncertainty`` and within ``[lower, upper]``,
  the relative error is below 1 % and the uncertainty below 3 % (an uncertainty that says something);
* with 1e3 and 2e4 configurations (coarse voxels) the truth is still within ``+- uncertainty``;
* units: the same arm in metres and millimetres gives volumes 1e9 apart and the same m^3 in ``to_dict``;
* zero-volume workspaces (planar 2R, a sphere's surface, a locked arm): ``lower == 0``, a volume that is a tiny
  share of ``upper`` and zero within the uncertainty;
* the same seed gives the same result (int or Generator), another seed a different one within the uncertainties,
  and the chunk size changes nothing beyond them;
* bad arguments raise UnknownOptionError, an unbounded prismatic travel RobotDefinitionError;
* the position and Jacobian kernels agree with ``Robot.fk`` and ``Robot.jacobian`` on bundled arms.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import sweepik
from sweepik.errors import RobotDefinitionError, UnknownOptionError
from sweepik.experiments.workspace import (
    MAX_CONFIGURATIONS,
    MIN_CONFIGURATIONS,
    WorkspaceVolume,
    _positions_and_jacobians,
    _tool_positions,
    workspace_volume,
)
from sweepik.io.robot_file import robot_from_dict
from sweepik.model.robot import Joint, Robot

PI = math.pi


def _origin(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> tuple[tuple[float, ...], ...]:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return tuple(tuple(float(v) for v in row) for row in T)


def _wrist(at: tuple[tuple[float, ...], ...] | None = None) -> list[Joint]:
    """Three revolute joints about z, y, x meeting at one point, full turns: every orientation."""
    return [
        Joint("revolute", origin=at or _origin(), axis=(0.0, 0.0, 1.0), lower=-PI, upper=PI, name="w1"),
        Joint("revolute", origin=_origin(), axis=(0.0, 1.0, 0.0), lower=-PI, upper=PI, name="w2"),
        Joint("revolute", origin=_origin(), axis=(1.0, 0.0, 0.0), lower=-PI, upper=PI, name="w3"),
    ]


def gantry(a: float = 400.0, b: float = 300.0, c: float = 200.0, tool: float = 0.0) -> tuple[Robot, float]:
    """Prismatic x, y, z (travels a, b, c) and a spherical wrist; the tool ``tool`` mm along the wrist's x.

    Workspace: the travel box dilated by ``tool`` (every point within ``tool`` of the box is at distance exactly
    ``tool`` from some wrist centre, the box being thicker than ``2 tool``); Steiner's formula for a box.
    """
    joints = [
        Joint("prismatic", origin=_origin(), axis=(1.0, 0.0, 0.0), lower=0.0, upper=a, name="x"),
        Joint("prismatic", origin=_origin(), axis=(0.0, 1.0, 0.0), lower=0.0, upper=b, name="y"),
        Joint("prismatic", origin=_origin(), axis=(0.0, 0.0, 1.0), lower=0.0, upper=c, name="z"),
        *_wrist(),
    ]
    T_tool = np.eye(4)
    T_tool[0, 3] = tool
    volume = a * b * c + 2 * (a * b + b * c + c * a) * tool + PI * (a + b + c) * tool**2 + 4 / 3 * PI * tool**3
    return Robot("gantry", tuple(joints), dh_convention="none", T_flange_tool=T_tool), volume


def sector_area(L1: float, L2: float, phi: float) -> float:
    """Area swept by a 2R arm (links L1 > L2, second joint a full turn, first joint over [0, phi]).

    At radius r the elbow angle that reaches r sits ``alpha(r)`` off the tool's bearing, so the bearings reached
    form two arcs of length phi whose starts are 2 alpha apart: their union, integrated over r.
    """
    if phi >= 2 * PI:
        return 4 * PI * L1 * L2
    r = np.linspace(L1 - L2, L1 + L2, 400_001)
    alpha = np.arccos(np.clip((r**2 + L1**2 - L2**2) / (2 * r * L1), -1.0, 1.0))
    gap = np.minimum(2 * alpha, 2 * PI - 2 * alpha)
    f = np.minimum(2 * PI, phi + np.minimum(phi, gap)) * r
    return float(np.sum((f[1:] + f[:-1]) / 2 * np.diff(r)))


def slide_2r(L1: float = 400.0, L2: float = 250.0, H: float = 300.0, phi: float = 2 * PI) -> tuple[Robot, float]:
    """A vertical slide (travel H), two parallel revolute joints (links L1, L2) and a spherical wrist at the tip."""
    first = (-PI, PI) if phi >= 2 * PI else (0.0, phi)
    joints = [
        Joint("prismatic", origin=_origin(), axis=(0.0, 0.0, 1.0), lower=0.0, upper=H, name="slide"),
        Joint("revolute", origin=_origin(), axis=(0.0, 0.0, 1.0), lower=first[0], upper=first[1], name="shoulder"),
        Joint("revolute", origin=_origin(L1), axis=(0.0, 0.0, 1.0), lower=-PI, upper=PI, name="elbow"),
        *_wrist(_origin(L2)),
    ]
    return Robot("slide-2r", tuple(joints), dh_convention="none"), sector_area(L1, L2, phi) * H


def elbow_3r(L1: float = 400.0, L2: float = 300.0) -> tuple[Robot, float]:
    """Base yaw, shoulder and elbow pitch (full turns) and a spherical wrist: a spherical shell."""
    joints = [
        Joint("revolute", origin=_origin(), axis=(0.0, 0.0, 1.0), name="base"),
        Joint("revolute", origin=_origin(), axis=(0.0, 1.0, 0.0), name="shoulder"),
        Joint("revolute", origin=_origin(L1), axis=(0.0, 1.0, 0.0), name="elbow"),
        *_wrist(_origin(L2)),
    ]
    return Robot("elbow-3r", tuple(joints), dh_convention="none"), 4 / 3 * PI * ((L1 + L2) ** 3 - abs(L1 - L2) ** 3)


ARMS = {
    "gantry": gantry,
    "gantry-tool-offset": lambda: gantry(tool=60.0),
    "slide-2r-annulus": slide_2r,
    "slide-2r-quarter-turn": lambda: slide_2r(phi=PI / 2),
    "elbow-3r-shell": elbow_3r,
}


@pytest.fixture(scope="module", params=list(ARMS))
def arm_result(request: pytest.FixtureRequest) -> tuple[str, WorkspaceVolume, float]:
    robot, true_volume = ARMS[request.param]()
    return request.param, workspace_volume(robot), true_volume


def test_sector_area_formula() -> None:
    """``sector_area`` against a direct count on a 5 mm grid: a point is reached when the distance from it to the
    elbow, minus L2, changes sign as the shoulder sweeps its range."""
    L1, L2, phi, step = 400.0, 250.0, PI / 2, 5.0
    axis = np.arange(-700.0, 700.0, step) + step / 2
    X, Y = (g.ravel() for g in np.meshgrid(axis, axis, indexing="ij"))
    keep = (np.hypot(X, Y) <= L1 + L2) & (np.hypot(X, Y) >= L1 - L2)
    X, Y = X[keep], Y[keep]
    lo, hi = np.full(len(X), np.inf), np.full(len(X), -np.inf)
    for t in np.linspace(0.0, phi, 241):
        f = np.hypot(X - L1 * np.cos(t), Y - L1 * np.sin(t)) - L2
        lo, hi = np.minimum(lo, f), np.maximum(hi, f)
    area = np.count_nonzero((lo <= 0.0) & (hi >= 0.0)) * step**2
    assert area == pytest.approx(sector_area(L1, L2, phi), rel=3e-3)
    assert sector_area(L1, L2, 2 * PI) == pytest.approx(PI * ((L1 + L2) ** 2 - (L1 - L2) ** 2), rel=1e-12)


def test_true_volume_within_uncertainty(arm_result: tuple[str, WorkspaceVolume, float]) -> None:
    name, w, true_volume = arm_result
    assert abs(w.volume - true_volume) <= w.uncertainty, (name, w, true_volume)
    assert w.lower <= true_volume <= w.upper, (name, w, true_volume)
    assert w.lower <= w.volume <= w.upper


def test_relative_error_and_uncertainty_small(arm_result: tuple[str, WorkspaceVolume, float]) -> None:
    name, w, true_volume = arm_result
    assert abs(w.volume / true_volume - 1.0) < 0.01, (name, w.volume / true_volume - 1.0)
    assert 0.0 < w.uncertainty < 0.03 * true_volume, (name, w.uncertainty / true_volume)
    assert w.n_configurations == 200_000 and w.length_unit == "mm" and w.voxel > 0.0


@pytest.mark.parametrize("name", list(ARMS))
@pytest.mark.parametrize(("n", "max_error"), [(MIN_CONFIGURATIONS, 0.1), (20_000, 0.02)])
def test_few_configurations_still_honest(name: str, n: int, max_error: float) -> None:
    """Coarse voxels (200 at the minimum of 1000 configurations): larger errors, still inside the uncertainty."""
    robot, true_volume = ARMS[name]()
    for seed in (1, 2):
        w = workspace_volume(robot, n, rng=seed)
        assert abs(w.volume - true_volume) <= w.uncertainty, (name, seed, w, true_volume)
        assert abs(w.volume / true_volume - 1.0) < max_error


def _slide_2r_dict(unit: str) -> dict[str, object]:
    """The annulus arm as a robot file (origin + axis form), lengths in ``unit``."""
    k = {"mm": 1.0, "m": 1e-3}[unit]

    def joint(name: str, kind: str, xyz: float, axis: list[float], limits: list[float]) -> dict[str, object]:
        return {"name": name, "type": kind, "origin": {"xyz": [xyz * k, 0.0, 0.0]}, "axis": axis, "limits": limits}

    return {
        "name": f"slide-2r-{unit}",
        "length_unit": unit,
        "joints": [
            joint("slide", "prismatic", 0.0, [0, 0, 1], [0.0, 300.0 * k]),
            joint("shoulder", "revolute", 0.0, [0, 0, 1], [-180.0, 180.0]),
            joint("elbow", "revolute", 400.0, [0, 0, 1], [-180.0, 180.0]),
            joint("w1", "revolute", 250.0, [0, 0, 1], [-180.0, 180.0]),
            joint("w2", "revolute", 0.0, [0, 1, 0], [-180.0, 180.0]),
            joint("w3", "revolute", 0.0, [1, 0, 0], [-180.0, 180.0]),
        ],
    }


def test_units_metres_and_millimetres() -> None:
    w_mm = workspace_volume(robot_from_dict(_slide_2r_dict("mm")), 100_000)
    w_m = workspace_volume(robot_from_dict(_slide_2r_dict("m")), 100_000)
    assert (w_mm.length_unit, w_m.length_unit) == ("mm", "m")
    assert w_mm.volume == pytest.approx(1e9 * w_m.volume, rel=1e-3)
    assert w_mm.uncertainty == pytest.approx(1e9 * w_m.uncertainty, rel=0.05)
    assert w_mm.voxel == pytest.approx(1e3 * w_m.voxel, rel=1e-9)
    d_mm, d_m = w_mm.to_dict(), w_m.to_dict()
    for key in ("volume_m3", "lower_m3", "upper_m3"):
        assert d_mm[key] == pytest.approx(d_m[key], rel=1e-3)
    assert d_mm["volume_m3"] == pytest.approx(4 * PI * 0.4 * 0.25 * 0.3, rel=0.01)
    assert d_m["volume"] == d_m["volume_m3"]


def test_to_dict_is_plain_json() -> None:
    robot, _ = gantry()
    w = workspace_volume(robot, 20_000)
    d = w.to_dict()
    assert json.loads(json.dumps(d)) == d
    assert set(d) == {
        "volume",
        "uncertainty",
        "lower",
        "upper",
        "voxel",
        "n_configurations",
        "length_unit",
        "volume_m3",
        "uncertainty_m3",
        "lower_m3",
        "upper_m3",
    }
    assert type(d["n_configurations"]) is int and type(d["volume"]) is float
    assert d["volume_m3"] == pytest.approx(w.volume * 1e-9, rel=1e-12)


def test_planar_arm_has_zero_volume() -> None:
    joints = [
        Joint("revolute", origin=_origin(), axis=(0.0, 0.0, 1.0)),
        Joint("revolute", origin=_origin(400.0), axis=(0.0, 0.0, 1.0)),
        *_wrist(_origin(250.0)),
    ]
    w = workspace_volume(Robot("planar", tuple(joints), dh_convention="none"), 50_000)
    assert w.lower == 0.0
    assert w.upper > 0.0
    assert 0.0 <= w.volume <= 1e-3 * w.upper
    assert w.volume <= w.uncertainty + 1e-9 * w.upper


def test_sphere_surface_has_zero_volume() -> None:
    """Two revolute joints and a tool offset: the tool sweeps a sphere's surface (curved, seen from both sides)."""
    joints = [
        Joint("revolute", origin=_origin(), axis=(0.0, 0.0, 1.0)),
        Joint("revolute", origin=_origin(), axis=(0.0, 1.0, 0.0)),
    ]
    T_tool = np.eye(4)
    T_tool[0, 3] = 300.0
    w = workspace_volume(Robot("sphere", tuple(joints), dh_convention="none", T_flange_tool=T_tool), 50_000)
    assert w.lower == 0.0
    assert w.volume <= 0.1 * w.upper
    assert w.volume - w.uncertainty <= 0.0
    assert w.volume < 0.02 * 4 / 3 * PI * 300.0**3  # a ball of that radius


def test_locked_arm_has_zero_volume() -> None:
    joints = [
        Joint("revolute", origin=_origin(), axis=(0.0, 0.0, 1.0), lower=0.3, upper=0.3),
        Joint("revolute", origin=_origin(400.0), axis=(0.0, 1.0, 0.0), lower=-0.2, upper=-0.2),
        Joint("prismatic", origin=_origin(250.0), axis=(1.0, 0.0, 0.0), lower=10.0, upper=10.0),
    ]
    w = workspace_volume(Robot("locked", tuple(joints), dh_convention="none"), MIN_CONFIGURATIONS)
    assert (w.volume, w.lower, w.uncertainty) == (0.0, 0.0, 0.0)
    assert w.upper > 0.0


def test_locked_joint_that_does_not_move_the_tool_changes_nothing() -> None:
    """Locking the wrist's last joint (a roll about the tool offset's own axis) leaves every tool position, hence
    the result, unchanged: locked joints must not stop the rays (a zero range once froze every ray)."""
    robot, true_volume = gantry(tool=60.0)
    joints = list(robot.joints)
    roll = joints[-1]
    joints[-1] = Joint("revolute", origin=roll.origin, axis=roll.axis, lower=0.0, upper=0.0, name="w3-locked")
    locked = Robot("gantry-locked-roll", tuple(joints), dh_convention="none", T_flange_tool=robot.T_flange_tool)
    w = workspace_volume(locked, 50_000)
    assert w == workspace_volume(robot, 50_000)
    assert abs(w.volume - true_volume) <= w.uncertainty


def test_reproducible_and_seed_dependent() -> None:
    robot, true_volume = slide_2r(phi=PI / 2)
    a = workspace_volume(robot, 50_000, rng=7)
    assert workspace_volume(robot, 50_000, rng=7) == a
    assert workspace_volume(robot, 50_000, rng=np.random.default_rng(7)) == a
    b = workspace_volume(robot, 50_000, rng=8)
    assert b != a
    assert abs(a.volume - b.volume) <= a.uncertainty + b.uncertainty
    c = workspace_volume(robot, 50_000, rng=7, chunk=4096)  # another pilot, same estimator
    assert abs(c.volume - true_volume) <= c.uncertainty
    assert abs(a.volume - c.volume) <= a.uncertainty + c.uncertainty


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_configurations": MIN_CONFIGURATIONS - 1},
        {"n_configurations": MAX_CONFIGURATIONS + 1},
        {"n_configurations": 2e5},
        {"n_configurations": True},
        {"n_configurations": "200000"},
        {"n_configurations": None},
        {"samples_per_voxel": 0},
        {"samples_per_voxel": 2.9},
        {"samples_per_voxel": 1e6},
        {"samples_per_voxel": float("nan")},
        {"samples_per_voxel": float("inf")},
        {"samples_per_voxel": "20"},
        {"samples_per_voxel": True},
        {"chunk": 10},
        {"chunk": 4096.0},
        {"rng": "seed"},
        {"rng": 1.5},
        {"rng": True},
    ],
)
def test_bad_arguments(kwargs: dict[str, object]) -> None:
    robot, _ = gantry()
    name = next(iter(kwargs))
    with pytest.raises(UnknownOptionError, match=name):
        workspace_volume(robot, **kwargs)  # type: ignore[arg-type]


def test_bad_robot() -> None:
    with pytest.raises(UnknownOptionError, match="Robot"):
        workspace_volume("ur5")  # type: ignore[arg-type]
    rail = Robot("rail", (Joint("prismatic", lower=-1e300, upper=1e300), Joint("revolute", a=100.0)))
    with pytest.raises(RobotDefinitionError, match="reaches"):
        workspace_volume(rail, MIN_CONFIGURATIONS)


@pytest.mark.parametrize("name", ["ur5", "carm", "franka_panda", "puma560_std", "stanford"])
def test_kernels_match_robot_fk_and_jacobian(name: str) -> None:
    robot = sweepik.load_robot(name)
    q = np.random.default_rng(3).uniform(robot.lower, robot.upper, (40, robot.n_joints))
    ref = robot.chain.points[0]  # the kernels work relative to joint 1's point
    p_fk = robot.fk(q)[:, :3, 3] - ref
    scale = robot.length_scale
    np.testing.assert_allclose(_tool_positions(robot.chain, q), p_fk, atol=1e-12 * scale)
    p, J = _positions_and_jacobians(robot.chain, q)
    np.testing.assert_allclose(p, p_fk, atol=1e-12 * scale)
    np.testing.assert_allclose(J, robot.jacobian(q)[:, :3, :], atol=1e-12 * scale)
