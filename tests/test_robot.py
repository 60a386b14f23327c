"""The robot model (Robot, Joint), robot files and input validation."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest
from conftest import random_configs
from hypothesis import given
from hypothesis import strategies as st

import sweepik.errors as errors_module
from sweepik import (
    InvalidPoseError,
    Joint,
    NonFiniteError,
    Robot,
    RobotDefinitionError,
    RobotFileError,
    ShapeError,
    SweepikError,
    UnknownRobotError,
    bundled_robots,
    load_robot,
    robot_from_dict,
)
from sweepik.model.robot import LIMIT_TOL

CARM_TOML = """\
name = "mycarm"
description = "test copy"
dh_convention = "modified"
length_unit = "mm"

[[joints]]
name = "d1"
type = "prismatic"
limits = [0.0, 2000.0]

[[joints]]
name = "theta2"
type = "revolute"
alpha = 90.0
limits = [-180.0, 180.0]

[[joints]]
name = "theta3"
type = "revolute"
alpha = -90.0
theta = -90.0
limits = [-84.0, 116.0]

[[joints]]
name = "theta4"
type = "revolute"
a = 350.0
limits = [-178.0, 66.0]

[[joints]]
name = "theta5"
type = "revolute"
alpha = -90.0
d = 402.0
limits = [-180.0, 180.0]

[[joints]]
name = "theta6"
type = "revolute"
alpha = 90.0
limits = [-180.0, 180.0]
"""


def two_link(**kwargs: object) -> Robot:
    return Robot("two", (Joint("revolute", a=1.0), Joint("prismatic", lower=0.0, upper=2.0)), **kwargs)  # type: ignore[arg-type]


# --------------------------------------------------------------------------------------------------
# Joint and Robot validation
# --------------------------------------------------------------------------------------------------


def test_every_error_derives_from_sweepik_error_and_value_error() -> None:
    classes = [getattr(errors_module, n) for n in errors_module.__all__]
    assert len(classes) >= 8
    for cls in classes:
        assert issubclass(cls, SweepikError)
        assert issubclass(cls, ValueError)
    assert issubclass(RobotFileError, RobotDefinitionError)
    assert issubclass(UnknownRobotError, LookupError)


def test_joint_lower_above_upper_raises() -> None:
    with pytest.raises(RobotDefinitionError, match=r"elbow: lower limit 2 is above upper limit 1"):
        Joint("revolute", lower=2.0, upper=1.0, name="elbow")
    Joint("revolute", lower=1.0, upper=1.0)  # a locked joint is allowed


@pytest.mark.parametrize("jtype", ["rotary", "Revolute", "", "linear"])
def test_joint_unknown_type_raises(jtype: str) -> None:
    with pytest.raises(RobotDefinitionError, match=r"'revolute' or 'prismatic'"):
        Joint(jtype)  # type: ignore[arg-type]


@pytest.mark.parametrize("field", ["a", "alpha", "d", "theta", "lower", "upper"])
@pytest.mark.parametrize("value", [np.nan, np.inf, "1.0", None])
def test_joint_fields_must_be_finite_numbers(field: str, value: object) -> None:
    with pytest.raises(RobotDefinitionError, match=field):
        Joint("revolute", **{field: value})  # type: ignore[arg-type]


def test_joint_accepts_numpy_scalars_and_rejects_bool() -> None:
    j = Joint("revolute", a=np.float32(0.5), d=np.int64(2), lower=np.float64(-1.0), upper=np.float32(1.0))  # type: ignore[arg-type]
    assert (j.a, j.d, j.lower, j.upper) == (0.5, 2.0, -1.0, 1.0)
    assert all(type(getattr(j, f)) is float for f in ("a", "d", "lower", "upper"))
    with pytest.raises(RobotDefinitionError, match="a must be a finite number"):
        Joint("revolute", a=True)


def test_joint_defaults_and_offset() -> None:
    r = Joint("revolute", theta=0.5, d=2.0)
    p = Joint("prismatic", theta=0.5, d=2.0)
    assert (r.lower, r.upper) == (-np.pi, np.pi)
    assert r.is_revolute and not p.is_revolute
    assert r.offset == 0.5 and p.offset == 2.0
    assert isinstance(Joint("revolute", a=1).a, float)


def test_robot_validation() -> None:
    with pytest.raises(RobotDefinitionError, match="non-empty"):
        Robot("empty", ())
    with pytest.raises(RobotDefinitionError, match="non-empty"):
        Robot("bad", ("revolute",))  # type: ignore[arg-type]
    with pytest.raises(RobotDefinitionError, match=r"dh_convention must be 'modified', 'standard' or 'none'.*'craig'"):
        two_link(dh_convention="craig")
    with pytest.raises(InvalidPoseError, match="base transform"):
        two_link(T_world_base=2 * np.eye(4))
    with pytest.raises(ShapeError, match="tool transform"):
        two_link(T_flange_tool=np.eye(3))
    with pytest.raises(RobotDefinitionError, match="single 4x4"):
        two_link(T_world_base=np.stack([np.eye(4), np.eye(4)]))
    # refused when the robot is made, not at its first solve
    with pytest.raises(RobotDefinitionError, match=r"unknown length unit 'furlong'; supported: mm, cm, m, in"):
        two_link(length_unit="furlong")
    twins = tuple(dataclasses.replace(j, name="elbow") for j in two_link().joints)
    with pytest.raises(RobotDefinitionError, match="joint names must differ.*'elbow' used more than once"):
        Robot("two", twins)


def test_robot_is_immutable() -> None:
    base = np.eye(4)
    base[:3, 3] = (1.0, 2.0, 3.0)
    robot = two_link(T_world_base=base)
    base[0, 3] = 99.0  # the robot keeps its own copy
    assert robot.T_world_base[0, 3] == 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        robot.name = "other"  # type: ignore[misc]
    with pytest.raises(dataclasses.FrozenInstanceError):
        robot.joints[0].a = 5.0  # type: ignore[misc]
    for arr in (
        robot.dh_a,
        robot.dh_alpha,
        robot.dh_d,
        robot.dh_theta,
        robot.lower,
        robot.upper,
        robot.is_revolute,
        robot.T_world_base,
        robot.T_flange_tool,
    ):
        with pytest.raises(ValueError, match="read-only"):
            arr[0] = 0
    assert isinstance(robot.joints, tuple)
    lim = robot.limits
    lim[0, 0] = 123.0  # a copy: the robot is unchanged
    assert robot.lower[0] == -np.pi


def test_robot_accessors(carm: Robot) -> None:
    assert carm.n_joints == 6
    assert carm.joint_names == ["d1", "theta2", "theta3", "theta4", "theta5", "theta6"]
    np.testing.assert_array_equal(carm.is_revolute, [False, True, True, True, True, True])
    np.testing.assert_allclose(carm.limits[0], [0.0, 2000.0])
    np.testing.assert_allclose(np.degrees(carm.limits[2]), [-84.0, 116.0], rtol=1e-14)
    assert carm.limits.shape == (6, 2)
    assert carm.length_unit == "mm" and carm.dh_convention == "modified"
    assert carm.length_scale >= 350 + 402
    assert Robot("x", (Joint("revolute"),)).joint_names == ["q1"]


def test_dh_table_in_degrees(carm: Robot) -> None:
    table = carm.dh_table()
    assert [row["joint"] for row in table] == carm.joint_names
    t3 = table[2]
    assert t3["type"] == "revolute"
    np.testing.assert_allclose(
        [float(t3[k]) for k in ("alpha_deg", "theta_deg", "lower", "upper")], [-90, -90, -84, 116]
    )
    assert (table[3]["a"], table[4]["d"]) == (350.0, 402.0)
    assert (table[0]["type"], table[0]["lower"], table[0]["upper"]) == ("prismatic", 0.0, 2000.0)


# --------------------------------------------------------------------------------------------------
# Configuration checks at the public boundary
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("method", ["fk", "frames", "jacobian"])
@pytest.mark.parametrize("q", [[0.0] * 5, [0.0] * 7, np.zeros((3, 5)), 0.0, np.zeros((6, 2))])
def test_wrong_number_of_joints_raises_shape_error(carm: Robot, method: str, q: object) -> None:
    with pytest.raises(ShapeError, match=r"\(\.\.\., 6\)"):
        getattr(carm, method)(q)


def test_non_numeric_configuration_raises_shape_error(carm: Robot) -> None:
    with pytest.raises(ShapeError, match="numeric"):
        carm.fk(["a", 0, 0, 0, 0, 0])  # type: ignore[arg-type]


@pytest.mark.parametrize("method", ["fk", "frames", "jacobian"])
@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_configuration_raises(carm: Robot, method: str, bad: float) -> None:
    q = np.zeros((2, 3, 6))
    q[1, 2, 4] = bad
    with pytest.raises(NonFiniteError, match=r"\(1, 2, 4\)"):
        getattr(carm, method)(q)


# --------------------------------------------------------------------------------------------------
# Limits and wrapping
# --------------------------------------------------------------------------------------------------


def test_within_limits_carm(carm: Robot) -> None:
    deg = np.radians
    cases = {
        (500.0, 0, 0, 0, 0, 0): True,
        (0.0, 0, 0, 0, 0, 0): True,  # at the rail's end
        (-1e-3, 0, 0, 0, 0, 0): False,
        (-0.1 * carm.limit_tol[0], 0, 0, 0, 0, 0): True,  # rounding-size excursions still count as inside
        (2000.0 + 10 * carm.limit_tol[0], 0, 0, 0, 0, 0): False,
        (500.0, 0, deg(116.0) + 0.5 * LIMIT_TOL, 0, 0, 0): True,
        (500.0, 0, deg(116.0) + 10 * LIMIT_TOL, 0, 0, 0): False,
        (500.0, 0, deg(116.0), 0, 0, 0): True,  # at theta3's upper limit
        (500.0, 0, deg(117.0), 0, 0, 0): False,
        (500.0, 0, deg(116.0 + 360.0), 0, 0, 0): True,  # revolute values count modulo 2 pi
        (500.0, 0, 0, deg(-179.0), 0, 0): False,
        (500.0, 0, 0, deg(181.0), 0, 0): False,  # = -179 deg, below theta4's -178 deg
        (500.0, 0, 0, deg(-300.0), 0, 0): True,  # = 60 deg, inside [-178, 66]
        (500.0, 0, 0, deg(-290.0), 0, 0): False,  # = 70 deg, above 66
        (500.0, deg(190.0), 0, 0, 0, 0): True,  # = -170 deg, inside [-180, 180]
    }
    q = np.array(list(cases), dtype=np.float64)
    np.testing.assert_array_equal(carm.within_limits(q), list(cases.values()))
    for qi, expected in cases.items():
        assert bool(carm.within_limits(np.array(qi))) is expected


@pytest.mark.parametrize("method", ["wrap", "within_limits"])
@pytest.mark.parametrize("q", [[0.5], [0.5, 1.0], np.zeros((4, 7))])
def test_wrap_and_within_limits_check_shape(carm: Robot, method: str, q: object) -> None:
    with pytest.raises(ShapeError, match=r"\(\.\.\., 6\)"):
        getattr(carm, method)(q)


def test_within_limits_batched_shape(carm: Robot, rng: np.random.Generator) -> None:
    q = random_configs(carm, rng, (3, 2), spread=3.0)
    inside = carm.within_limits(q)
    assert inside.shape == (3, 2) and inside.dtype == np.bool_
    inner = random_configs(carm, rng, (3, 2), spread=0.99)
    assert np.all(carm.within_limits(inner))


def test_wrap_moves_revolute_values_into_limits(puma: Robot, carm: Robot) -> None:
    # puma q2 has limits [-225, 45] deg: -200 deg is inside and must stay; 160 deg = -200 deg must move there.
    q = np.radians([0.0, 160.0, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(np.degrees(puma.wrap(q))[1], -200.0, rtol=1e-12)
    q = np.radians([0.0, -200.0, 0.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(np.degrees(puma.wrap(q))[1], -200.0, rtol=1e-12)
    # puma q3 has limits [-45, 225] deg: -170 deg is below them, and 190 deg (the same angle) is inside.
    q = np.radians([0.0, 0.0, -170.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(np.degrees(puma.wrap(q))[2], 190.0, rtol=1e-12)
    assert puma.within_limits(q)
    # An angle inside no shifted copy of the limits is left in (-pi, pi].
    q = np.radians([0.0, 0.0, -100.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(np.degrees(puma.wrap(q))[2], -100.0, rtol=1e-12)
    assert not puma.within_limits(q)
    # Prismatic values are never wrapped.
    q = np.array([5000.0, 7.0, -7.0, 0.0, 0.0, 0.0])
    w = carm.wrap(q)
    assert w[0] == 5000.0
    np.testing.assert_allclose(w[1:3], [7.0 - 2 * np.pi, -7.0 + 2 * np.pi], rtol=1e-14)


@given(seed=st.integers(0, 2**32 - 1))
def test_wrap_preserves_angles_and_fk(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for robot in (load_robot("carm"), load_robot("puma560")):
        q = random_configs(robot, rng, 50, spread=6.0)
        w = robot.wrap(q)
        assert w.shape == q.shape
        diff = np.where(robot.is_revolute, (w - q) / (2 * np.pi), 0.0)
        np.testing.assert_allclose(diff, np.round(diff), atol=1e-9)  # whole turns only
        np.testing.assert_array_equal(w[:, ~robot.is_revolute], q[:, ~robot.is_revolute])
        reach = robot.length_scale
        np.testing.assert_allclose(robot.fk(w), robot.fk(q), rtol=0, atol=1e-9 * reach)
        np.testing.assert_array_equal(robot.within_limits(w), robot.within_limits(q))
        assert np.all(robot.wrap(w) == w)  # idempotent


# --------------------------------------------------------------------------------------------------
# Loading robots
# --------------------------------------------------------------------------------------------------


def test_bundled_robots_load() -> None:
    names = bundled_robots()
    assert {"carm", "puma560", "puma560_std"} <= set(names)
    for name in names:
        robot = load_robot(name)
        assert robot.name == name
        assert robot.description


def test_load_robot_by_path_equals_bundled(tmp_path: Path, carm: Robot, rng: np.random.Generator) -> None:
    f = tmp_path / "mycarm.toml"
    f.write_text(CARM_TOML, encoding="utf-8")
    q = random_configs(carm, rng, 100, spread=3.0)
    for arg in (f, str(f)):
        robot = load_robot(arg)
        assert robot.name == "mycarm" and robot.description == "test copy"
        np.testing.assert_allclose(robot.fk(q), carm.fk(q), rtol=0, atol=1e-9)
        np.testing.assert_allclose(robot.limits, carm.limits, rtol=1e-15)
    assert load_robot(carm) is carm  # type: ignore[arg-type]  # accepted at run time


def test_robot_file_base_and_tool(tmp_path: Path, carm: Robot) -> None:
    extra = "\n[base]\nxyz = [10.0, 0.0, 0.0]\nzyz = [90.0, 0.0, 0.0]\n\n[tool]\nxyz = [0.0, 0.0, 5.0]\n"
    f = tmp_path / "tooled.toml"
    f.write_text(CARM_TOML + extra, encoding="utf-8")
    robot = load_robot(f)
    base = np.array([[0.0, -1, 0, 10], [1, 0, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])
    tool = np.eye(4)
    tool[2, 3] = 5.0
    q = np.array([300.0, 0.2, 0.3, -0.4, 0.5, 0.6])
    np.testing.assert_allclose(robot.fk(q), base @ carm.fk(q) @ tool, rtol=0, atol=1e-9)


def test_unknown_robot_lists_bundled(tmp_path: Path) -> None:
    with pytest.raises(UnknownRobotError) as info:
        load_robot("no_such_robot")
    msg = str(info.value)
    assert "no_such_robot" in msg
    for name in bundled_robots():
        assert name in msg
    with pytest.raises(UnknownRobotError, match="does not exist"):
        load_robot(tmp_path / "missing.toml")
    with pytest.raises(SweepikError):
        load_robot(tmp_path)  # a directory is not a robot file


def write_joint_file(tmp_path: Path, joint_body: str, top: str = "") -> Path:
    f = tmp_path / "arm.toml"
    f.write_text(
        f'name = "arm"\n{top}\n[[joints]]\nname = "base"\ntype = "revolute"\nlimits = [-90, 90]\n\n'
        f"[[joints]]\n{joint_body}\n",
        encoding="utf-8",
    )
    return f


@pytest.mark.parametrize(
    ("body", "needles"),
    [
        ('name = "elbow"\nlimits = [0, 1]', ["joint elbow", "'type'", "missing"]),
        ('name = "elbow"\ntype = "revolute"', ["joint elbow", "'limits'", "missing"]),
        ('type = "revolute"', ["joint #2", "'limits'"]),  # unnamed joint: its position
        ('name = "elbow"\ntype = "rotary"\nlimits = [0, 1]', ["joint elbow", "'type'", "'rotary'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0]', ["joint elbow", "'limits'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [10, -10]', ["joint elbow", "'limits'", "above"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0, "x"]', ["joint elbow", "'limits'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0, 1]\na = "long"', ["joint elbow", "'a'", "'long'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0, 1]\nalpha = nan', ["joint elbow", "'alpha'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0, 1]\nd = true', ["joint elbow", "'d'"]),
        ('name = "elbow"\ntype = "revolute"\nlimits = [0, 1]\nlength = 3', ["joint elbow", "length"]),
    ],
)
def test_malformed_joint_names_file_joint_and_field(tmp_path: Path, body: str, needles: list[str]) -> None:
    f = write_joint_file(tmp_path, body)
    with pytest.raises(RobotFileError) as info:
        load_robot(f)
    msg = str(info.value)
    assert str(f) in msg
    for needle in needles:
        assert needle in msg, (needle, msg)


@pytest.mark.parametrize(
    ("text", "needles"),
    [
        ('name = "arm"\n', ["[[joints]]"]),
        ('name = "arm"\njoints = 3\n', ["[[joints]]"]),
        ('name = "arm\n', ["not valid TOML"]),
        ('name = "arm"\ncolour = "red"\n[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n', ["colour"]),
        (
            'dh_convention = "craig"\n[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n',
            ["dh_convention", "craig"],
        ),
        ('[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n[base]\nxyz = [1, 2]\n', ["[base]", "xyz"]),
        (
            '[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n[tool]\nrpy = [1, 2, 3]\nzyz = [1, 2, 3]\n',
            ["[tool]", "not both"],
        ),
        ('[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n[tool]\nxyw = [1, 2, 3]\n', ["[tool]", "xyw"]),
        ('tool = 5\n[[joints]]\ntype = "revolute"\nlimits = [0, 1]\n', ["[tool]"]),
    ],
)
def test_malformed_robot_file(tmp_path: Path, text: str, needles: list[str]) -> None:
    f = tmp_path / "arm.toml"
    f.write_text(text, encoding="utf-8")
    with pytest.raises(RobotFileError) as info:
        load_robot(f)
    msg = str(info.value)
    assert str(f) in msg
    for needle in needles:
        assert needle in msg, (needle, msg)


def test_robot_from_dict_defaults() -> None:
    robot = robot_from_dict({"joints": [{"type": "revolute", "limits": [-90, 90]}]}, source="x/y/elbow.toml")
    assert robot.name == "elbow"  # from the file name
    assert robot.dh_convention == "modified" and robot.length_unit == "mm"
    j = robot.joints[0]
    assert (j.a, j.alpha, j.d, j.theta) == (0.0, 0.0, 0.0, 0.0)
    np.testing.assert_allclose([j.lower, j.upper], [-np.pi / 2, np.pi / 2], rtol=1e-15)
