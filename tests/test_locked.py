"""Arms with joints held at fixed values (``locked=``), the origin + axis form, TOML joint files, ``convert``.

Properties tested (not examples):
* the held arm is the full arm with the joint fixed: same FK, for every bundled arm, several values;
* a 7-joint arm with one joint locked (at 0 and at other values): every configuration generated with that value is
  recovered, every solution is full length, holds the locked value and passes the FK check, and the solution set
  equals an independent solver's (IK-Geo on the held chain; the many-start numerical search where IK-Geo has no
  closed form);
* what ``analyze`` says a lock leaves is what ``solve`` does with it;
* errors: unknown joint, value outside the limits or not finite, not six joints left, a 7-joint arm without lock.
"""

from __future__ import annotations

import json
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from oracles import ikgeo_solutions, in_limit_configurations, numerical_solutions, recovers, same_solution_set

import sweepik
from sweepik import LockedJointError
from sweepik.cli.app import main
from sweepik.io.robot_file import _parse, robot_to_toml
from sweepik.model.origin_axis import hold_joints, joint_origins, origin_axis_form
from sweepik.model.robot import Joint, Robot

SEVEN = ["franka_panda", "kuka_iiwa14"]


def _configurations(robot: Robot, n: int, seed: int, held: dict[int, float]) -> np.ndarray:
    q = in_limit_configurations(robot, n, np.random.default_rng(seed))
    for k, v in held.items():
        q[:, k] = v
    return q


def _fk_scale(robot: Robot) -> float:
    return 1e-12 * max(robot.length_scale, 1.0)


@pytest.mark.parametrize("name", sweepik.bundled_robots())
def test_origin_axis_form_and_held_arm_have_the_full_arms_fk(name: str) -> None:
    robot = sweepik.load_robot(name)
    q = _configurations(robot, 40, 1, {})
    assert np.abs(origin_axis_form(robot).fk(q) - robot.fk(q)).max() < _fk_scale(robot)
    rng = np.random.default_rng(2)
    for k in range(robot.n_joints):
        value = float(rng.uniform(max(robot.lower[k], -3.0), min(robot.upper[k], 3.0)))
        held = hold_joints(robot, {robot.joint_names[k]: value}, n_free=None)
        qk = q.copy()
        qk[:, k] = value
        assert held.arm.n_joints == robot.n_joints - 1
        assert np.abs(held.arm.fk(np.delete(qk, k, axis=1)) - robot.fk(qk)).max() < _fk_scale(robot)
        assert np.allclose(held.expand(np.delete(qk, k, axis=1)), qk)


def test_two_joints_held_at_once() -> None:
    robot = sweepik.load_robot("kuka_iiwa14")
    held = hold_joints(robot, {2: 0.4, 6: -1.0}, n_free=None)
    q = _configurations(robot, 30, 3, dict(held.held))
    assert np.abs(held.arm.fk(q[:, list(held.free)]) - robot.fk(q)).max() < _fk_scale(robot)


def _check_locked(robot: Robot, joint: int, value: float, n: int, seed: int, reference: str, n_ref: int) -> None:
    q = _configurations(robot, n, seed, {joint: value})
    poses = robot.fk(q)
    batch = sweepik.solve_many(robot, poses, locked={robot.joint_names[joint]: value})
    assert batch.q.shape[1] == robot.n_joints
    if len(batch.q):
        assert np.allclose(batch.q[:, joint], value, atol=1e-12)
        assert np.abs(robot.fk(batch.q) - poses[batch.pose_index]).max() < 1e-9 * robot.length_scale
        assert np.all(robot.within_limits(batch.q))
    missed = [i for i in range(n) if not recovers(robot, batch[i], q[i])]
    assert not missed, f"{robot.name} {robot.joint_names[joint]}={value}: missed poses {missed[:10]}"
    held = hold_joints(robot, {joint: value})
    for i in range(n_ref):
        ours = sweepik.solve(robot, poses[i], locked={joint: value}, limits=False)
        assert not ours.families
        if reference == "ikgeo":
            ref = ikgeo_solutions(held.arm, poses[i])
            assert ref is not None, "IK-Geo has a closed form for this held arm"
        else:
            ref = numerical_solutions(held.arm, poses[i], n_starts=300, seed=i)
        ref_full = held.expand(ref)
        assert same_solution_set(ours.q, ref_full, robot.is_revolute, robot.length_scale, tol=1e-6), (i, ours.q, ref)


@pytest.mark.parametrize("value", [0.0, 0.7, -2.5])
def test_panda_with_joint7_locked_closed_form(value: float) -> None:
    robot = sweepik.load_robot("franka_panda")
    info = sweepik.analyze(robot, locked={"joint7": value})
    assert info["chosen"]["closed_form"]
    _check_locked(robot, 6, value, 1000, seed=10, reference="ikgeo", n_ref=150)


@pytest.mark.parametrize("value", [0.3, -1.9])
def test_panda_with_joint5_locked_quartic_closed_form(value: float) -> None:
    """Joint 5 held: joints 1-3 meet (a spherical shoulder) and joints 4, 6, 7 form a general 3R chain; the closed
    form places the shoulder point with them by sp5 (Pieper's quartic, case rrr, on the reversed chain)."""
    robot = sweepik.load_robot("franka_panda")
    info = sweepik.analyze(robot, locked={"joint5": value})
    assert info["chosen"]["closed_form"] and info["chosen"]["case"] == "rrr"
    _check_locked(robot, 4, value, 600, seed=13, reference="numerical", n_ref=8)


@pytest.mark.parametrize("value", [0.0, -1.1])
def test_iiwa_with_joint3_locked(value: float) -> None:
    robot = sweepik.load_robot("kuka_iiwa14")
    _check_locked(robot, 2, value, 1000, seed=11, reference="ikgeo", n_ref=150)


def test_panda_with_joint1_locked_sweeps() -> None:
    """Joint 1 held: no closed form, a sweep (what analyze says); the numerical search is the reference."""
    robot = sweepik.load_robot("franka_panda")
    value = 0.4
    info = sweepik.analyze(robot, locked={"joint1": value})
    assert info["chosen"] is not None and not info["chosen"]["closed_form"]
    _check_locked(robot, 0, value, 1000, seed=12, reference="numerical", n_ref=12)


@pytest.mark.parametrize("name", SEVEN)
def test_analyze_locks_are_what_solve_does(name: str) -> None:
    robot = sweepik.load_robot(name)
    info = sweepik.analyze(robot)
    assert info["chosen"] is None and "lock" in info["reason"]
    assert [lock["joint"] for lock in info["locks"]] == list(range(7))
    rng = np.random.default_rng(5)
    for lock in info["locks"]:
        k = lock["joint"]
        for row in lock["values"]:
            v = row["value"]
            q = _configurations(robot, 3, int(rng.integers(1 << 30)), {k: v})
            if row["chosen"] is None:
                with pytest.raises(sweepik.NoReductionError):
                    sweepik.solve(robot, robot.fk(q[0]), locked={k: v})
                continue
            for qi in q:
                assert recovers(robot, sweepik.solve(robot, robot.fk(qi), locked={k: v}), qi)


@pytest.mark.parametrize(
    ("name", "joint"), [("franka_panda", "joint3"), ("franka_panda", "joint1"), ("kuka_iiwa14", "A3")]
)
def test_analyze_with_locks_numbers_theta_star_as_solve_takes_it(name: str, joint: str) -> None:
    """With joints held, every swept plan's ``free_joint`` from ``analyze`` is the full arm's index: given back to
    ``solve(..., locked=..., free_joint=...)`` it sweeps that joint (the solutions then contain q); a joint no plan
    sweeps is refused naming the sweepable ones by the full arm's indices and numbers."""
    robot = sweepik.load_robot(name)
    k = robot.joint_names.index(joint)
    lock = {joint: 0.4}
    info = sweepik.analyze(robot, locked=lock)
    assert info["held"] == lock and k + 1 not in info["arm_joints"] and len(info["arm_joints"]) == 6
    swept = [p for p in info["plans"] if not p["closed_form"]]
    assert swept
    q = _configurations(robot, 1, 3, {k: 0.4})[0]
    for plan in swept:
        j = plan["free_joint"]
        assert robot.joint_names[j] == plan["free_joint_name"] and plan["free_joint_number"] == j + 1
        assert recovers(robot, sweepik.solve(robot, robot.fk(q), locked=lock, free_joint=j), q)
    other = next(j for j in range(robot.n_joints) if j != k and j not in {p["free_joint"] for p in swept})
    with pytest.raises(sweepik.NoReductionError) as err:
        sweepik.solve(robot, robot.fk(q), locked=lock, free_joint=other)
    for plan in swept:
        assert f"{plan['free_joint_name']} (index {plan['free_joint']}, number {plan['free_joint'] + 1})" in str(
            err.value
        )


def test_family_of_a_held_arm_is_full_length() -> None:
    """A 7-joint arm built from the KUKA KR 6 with an extra joint; at its singular wrist the held arm has a
    self-motion family, whose members are full-length configurations reaching the pose."""
    base = origin_axis_form(sweepik.load_robot("kuka_kr6_r900"))
    extra = Joint(
        "revolute", lower=-2.0, upper=2.0, name="extra", origin=tuple(map(tuple, np.eye(4))), axis=(1, 0.3, 0.2)
    )
    joints = list(base.joints)
    robot = Robot("k7", (*joints[:3], extra, *joints[3:]), dh_convention="none", T_flange_tool=base.T_flange_tool)
    q = np.array([0.3, -1.2, 1.0, 0.6, 0.4, 0.0, 0.8])  # joint 6 (the wrist's middle joint) at 0
    sols = sweepik.solve(robot, robot.fk(q), locked={"extra": 0.6})
    assert recovers(robot, sols, q)
    assert sols.families
    for fam in sols.families:
        assert fam.free_joint != 3
        members = fam.sample(7)
        assert members.shape == (7, 7) and np.allclose(members[:, 3], 0.6)
        assert np.abs(robot.fk(members) - sols.pose).max() < 1e-9


def test_locked_errors() -> None:
    panda = sweepik.load_robot("franka_panda")
    T = panda.fk(np.array([0.1, 0.2, 0.3, -1.0, 0.2, 1.0, 0.1]))
    with pytest.raises(sweepik.SweepikError, match="7 joints"):
        sweepik.solve(panda, T)
    for locked, needle in [
        ({"elbow": 0.0}, "no joint named"),
        ({"joint4": 0.0}, "outside its limits"),
        ({"joint7": float("nan")}, "finite"),
        ({"joint7": "0"}, "number"),
        ({9: 0.0}, "outside 0..6"),
        ({"joint6": 1.0, "joint7": 0.0}, "5 left"),
        ([("joint7", 0.0)], "mapping"),
    ]:
        with pytest.raises(LockedJointError, match=needle):
            sweepik.solve(panda, T, locked=locked)
    ur5 = sweepik.load_robot("ur5")
    with pytest.raises(LockedJointError, match="out of scope"):
        sweepik.solve(ur5, np.eye(4), locked={"elbow": 0.1})
    assert len(sweepik.solve(ur5, ur5.fk(np.full(6, 0.3)), locked={})) > 0  # nothing locked: the 6-joint arm
    with pytest.raises(sweepik.SweepikError, match="locked"):
        sweepik.solve(panda, T, locked={"joint7": 0.1}, free_joint=6)


@pytest.mark.parametrize("name, joint", [("kuka_iiwa14", "A3"), ("franka_panda", "joint7")])
def test_a_lock_value_per_pose_solves_each_pose_with_its_own(name: str, joint: str) -> None:
    """``solve_many(..., locked={joint: values})`` with one value per pose: each pose's solutions are ``solve``'s
    with its value held (the held column is that value), every generating configuration is recovered, and
    ``iter_solve`` yields the same; runs of one value (poses 4-6) and values in any order."""
    robot = sweepik.load_robot(name)
    k = robot.joint_names.index(joint)
    q = in_limit_configurations(robot, 10, np.random.default_rng(5))
    q[5:7, k] = q[4, k]  # (a run of one value)
    T = robot.fk(q)
    batch = sweepik.solve_many(robot, T, locked={joint: q[:, k]})
    streamed = list(sweepik.iter_solve(robot, T, locked={joint: list(q[:, k])}, chunk_size=2))
    assert len(batch) == len(streamed) == 10
    for i in range(10):
        one = sweepik.solve(robot, T[i], locked={joint: float(q[i, k])})
        got = batch[i]
        assert len(got) == len(one) == len(streamed[i]) > 0
        assert np.allclose(np.sort(got.q, axis=0), np.sort(one.q, axis=0), atol=1e-9)
        assert np.all(got.q[:, k] == q[i, k])
        assert np.abs(robot.fk(got.q) - T[i]).max() < 1e-9
        assert recovers(robot, got, q[i])


def test_a_self_motion_sampled_over_lock_values_in_one_call() -> None:
    """One pose and a grid of lock values: one solve per value (the pose repeated), each solution holding its
    value and reaching the pose; the generating configuration's value is among them and recovered there."""
    robot = sweepik.load_robot("kuka_iiwa14")
    q0 = np.array([0.3, 0.8, 0.4, -1.2, 0.5, 0.9, -0.2])
    grid = np.linspace(-1.2, 1.2, 13)
    grid[6] = q0[2]
    batch = sweepik.solve_many(robot, robot.fk(q0), locked={"A3": grid})
    assert len(batch) == grid.size
    for v, sols in zip(grid, batch, strict=True):
        assert np.all(sols.q[:, 2] == v)
        assert np.abs(robot.fk(sols.q) - robot.fk(q0)).max() < 1e-9
    assert recovers(robot, batch[6], q0)
    assert sum(len(s) for s in batch) > 13


def test_lock_values_per_pose_errors() -> None:
    panda = sweepik.load_robot("franka_panda")
    T = panda.fk(in_limit_configurations(panda, 3, np.random.default_rng(1)))
    for values, needle in [
        ([0.1, 0.2], r"shape \(2,\).*one per pose \(3\)"),
        ([0.1, float("nan"), 0.2], "pose 1: .*finite"),
        ([0.1, 0.2, 3.1], "pose 2: .*outside its limits"),
        (["a", "b", "c"], "numbers"),
        (["0.1", "0.2", "0.3"], "numbers, one per pose, got '0.1'"),  # (text NumPy would read as numbers)
        ([None, 0.1, 0.2], "numbers, one per pose, got None"),
        (np.zeros((3, 1)), "shape"),
        ([True, False, True], "not booleans"),  # (as a single True is refused: not a joint value)
        (np.ones(3, dtype=bool), "not booleans"),
    ]:
        with pytest.raises(LockedJointError, match=needle):
            sweepik.solve_many(panda, T, locked={"joint7": values})
    with pytest.raises(LockedJointError, match="outside its limits"):
        sweepik.iter_solve(panda, T, locked={"joint7": [0.1, 0.2, 0.3], "joint4": 0.0})  # (checked when called)
    assert len(sweepik.solve_many(panda, np.zeros((0, 4, 4)), locked={"joint7": []})) == 0


def test_a_lock_value_in_a_0d_array_is_a_number() -> None:
    """``np.array(v)`` (0-d, as NumPy reductions give) holds a joint as ``v`` does; a 0-d array of booleans or text
    is refused as the scalar is."""
    panda = sweepik.load_robot("franka_panda")
    q = in_limit_configurations(panda, 1, np.random.default_rng(4))[0]
    T = panda.fk(q)
    want = sweepik.solve(panda, T, locked={"joint7": float(q[6])})
    got = sweepik.solve(panda, T, locked={"joint7": np.array(q[6])})
    np.testing.assert_array_equal(got.q, want.q)
    assert recovers(panda, got, q)
    for bad in (np.array(True), np.array("0.1")):
        with pytest.raises(LockedJointError, match="needs a number"):
            sweepik.solve(panda, T, locked={"joint7": bad})


# ------------------------------------------------------------------------------------------ TOML joint form


@pytest.mark.parametrize("name", sweepik.bundled_robots())
def test_robot_to_toml_round_trip(name: str) -> None:
    robot = sweepik.load_robot(name)
    q = _configurations(robot, 40, 4, {})
    for form in (robot, origin_axis_form(robot)):
        back = _parse(robot_to_toml(form), "written.toml")
        assert back.dh_convention == form.dh_convention
        assert np.abs(back.fk(q) - robot.fk(q)).max() < _fk_scale(robot)
        assert np.allclose(back.limits, robot.limits, rtol=1e-14, atol=1e-14)
        assert back.joint_names == robot.joint_names


def test_toml_joint_form_solves_like_dh() -> None:
    ur5 = sweepik.load_robot("ur5")
    joints = _parse(robot_to_toml(origin_axis_form(ur5)), "ur5_joints.toml")
    q = _configurations(ur5, 20, 6, {})
    for qi in q:
        a, b = sweepik.solve(ur5, ur5.fk(qi)), sweepik.solve(joints, ur5.fk(qi))
        assert same_solution_set(a.q, b.q, ur5.is_revolute, ur5.length_scale)


@pytest.mark.parametrize(
    ("joint", "needle"),
    [
        ("origin = { xyz = [0, 0, 1], rpy = [0, 0, 0] }\naxis = [0, 0, 0]", "axis"),
        ("origin = { xyz = [0, 0], rpy = [0, 0, 0] }", "xyz"),
        ("origin = { xyz = [0, 0, 1], zyz = [0, 0, 0] }", "zyz"),
        ('origin = { xyz = [0, 0, 1], rpy = [0, "a", 0] }', "rpy"),
        ("axis = [0, 0, 1]\na = 0.3", "write every joint one way"),
        ("origin = 3", "origin"),
        ("axis = [1e300, 0, nan]", "axis"),
    ],
)
def test_toml_joint_form_errors(tmp_path: Path, joint: str, needle: str) -> None:
    text = f'name = "bad"\n[[joints]]\ntype = "revolute"\nlimits = [-90, 90]\n{joint}\n'
    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(sweepik.RobotFileError, match=needle) as info:
        sweepik.load_robot(path)
    assert str(path) in str(info.value)


def test_joint_origins_match_frames() -> None:
    """``joint_origins`` of a DH arm composes to its link frames (standard DH: the fixed part moves one joint on)."""
    for name in ("ur5", "puma560_std", "carm"):
        robot = sweepik.load_robot(name)
        origins, axes, tail = joint_origins(robot)
        q = np.zeros(robot.n_joints)
        T = np.array(robot.T_world_base)
        for origin in origins:
            T = T @ origin
        assert np.abs(T @ tail - robot.fk(q)).max() < _fk_scale(robot)
        assert np.allclose(np.linalg.norm(axes, axis=1), 1.0)


# ------------------------------------------------------------------------------------------------ CLI


def test_cli_lock_and_convert(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    def _cli(*args: str) -> SimpleNamespace:
        code = main(list(args))
        out = capsys.readouterr()
        return SimpleNamespace(returncode=code, stdout=out.out, stderr=out.err)

    panda = sweepik.load_robot("franka_panda")
    q = np.radians([10, -20, 30, -90, 40, 100, 50])
    matrix = [repr(float(v)) for v in panda.fk(q).ravel()]
    run = _cli("solve", "franka_panda", "--matrix", *matrix, "--lock", "joint7=50", "--json")
    assert run.returncode == 0, run.stderr
    found = np.array(json.loads(run.stdout)["poses"][0]["q"])
    assert found.shape[1] == 7 and np.min(np.abs(found - q).max(axis=1)) < 1e-9
    run = _cli("solve", "franka_panda", "--matrix", *matrix, "--lock", "7=0.8727", "--rad", "--json")
    assert run.returncode == 0 and np.allclose(np.array(json.loads(run.stdout)["poses"][0]["q"])[:, 6], 0.8727)
    for bad in (["--lock", "joint9=1"], ["--lock", "joint7"], ["--lock", "joint7=x"], []):
        run = _cli("solve", "franka_panda", "--matrix", *matrix, *bad)
        assert run.returncode == 2 and run.stderr.count("\n") == 1 and "Traceback" not in run.stderr, run.stderr
    run = _cli("analyze", "franka_panda", "--json")
    assert run.returncode == 0 and len(json.loads(run.stdout)["locks"]) == 7
    out = tmp_path / "panda_locked.toml"
    run = _cli("convert", "franka_panda", "-o", str(out), "--lock", "joint7=50")
    assert run.returncode == 0, run.stderr
    six = sweepik.load_robot(out)
    assert six.n_joints == 6 and np.abs(six.fk(np.delete(q, 6)) - panda.fk(q)).max() < 1e-12
    run = _cli("convert", "franka_panda", "-o", str(tmp_path / "x.txt"))
    assert run.returncode == 2 and "toml or .urdf" in run.stderr


def test_locked_value_on_a_joint_turning_more_than_once_is_kept() -> None:
    """A joint with limits beyond +-pi: 4 rad and 4 - 2 pi are two configurations; the one asked for is held."""
    base = origin_axis_form(sweepik.load_robot("puma560"))
    extra = Joint("revolute", lower=-2 * np.pi, upper=2 * np.pi, name="extra", origin=tuple(map(tuple, np.eye(4))))
    robot = Robot("p7", (*base.joints, extra), dh_convention="none", T_flange_tool=base.T_flange_tool)
    q = np.array([0.3, -0.5, 0.4, 0.2, 0.6, -0.3, 4.0])
    sols = sweepik.solve(robot, robot.fk(q), locked={"extra": 4.0})
    assert len(sols) and np.all(sols.q[:, 6] == 4.0)
    assert recovers(robot, sols, q)
    # outside the limits, an angle is taken modulo 2 pi into them; beyond the configuration bound it is refused
    v = hold_joints(robot, {6: 4.0 + 2 * np.pi}).held[0][1]
    assert abs(v) <= 2 * np.pi and np.cos(v - 4.0) == pytest.approx(1.0)
    with pytest.raises(LockedJointError, match="magnitude"):
        hold_joints(robot, {6: 1e300})


def test_lock_option_names_with_equals_sign(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    base = origin_axis_form(sweepik.load_robot("puma560"))
    extra = Joint("revolute", lower=-2.0, upper=2.0, name="a=b", origin=tuple(map(tuple, np.eye(4))))
    robot = Robot("p7", (*base.joints, extra), dh_convention="none", T_flange_tool=base.T_flange_tool)
    path = tmp_path / "p7.toml"
    path.write_text(robot_to_toml(robot))
    q = np.array([0.3, -0.5, 0.4, 0.2, 0.6, -0.3, 0.5])
    matrix = [repr(float(v)) for v in robot.fk(q).ravel()]
    assert main(["solve", str(path), "--matrix", *matrix, "--lock", "a=b=0.5", "--rad", "--json"]) == 0
    found = np.array(json.loads(capsys.readouterr().out)["poses"][0]["q"])
    assert np.min(np.abs(found - q).max(axis=1)) < 1e-9


def test_writers_escape_names(tmp_path: Path) -> None:
    base = origin_axis_form(sweepik.load_robot("ur5"))
    names = ["new\nline", "cr\rx", "del\x7f", 'q"uote', "back\\slash", "tab\t", "ü€"]
    joints = tuple(
        Joint(j.type, lower=j.lower, upper=j.upper, name=n, origin=j.origin, axis=j.axis)
        for j, n in zip(base.joints, names, strict=False)
    )
    robot = Robot("weird\nname", joints, dh_convention="none", T_flange_tool=base.T_flange_tool, description="a\nb")
    back = _parse(robot_to_toml(robot), "weird.toml")
    assert back.joint_names == robot.joint_names and back.name == robot.name and back.description == "a\nb"


def test_a_plan_remembered_from_another_value_gets_a_second_opinion() -> None:
    """Kinova Gen3, joint 6 held (axes 5 and 7 of the held arm nearly meet at every value): held at 0 first, its plan
    is remembered; at -0.4934 the short check passes that plan, which alone lost two of a pose's eight solutions (a
    rounding of its meeting point): this value's own choice joins it as a companion, and the configuration the pose
    was made from is found."""
    from sweepik.reductions import _HELD_PLANS

    robot = sweepik.load_robot("kinova_gen3")
    _HELD_PLANS.clear()
    q = np.array([1.5874311837898043, -0.019612219433625455, 2.160060773265002, -2.5503606983923333, 1.0427411412059486,
                  -0.4933821199999999, -1.0891509835647515])  # fmt: skip
    q0 = q.copy()
    q0[5] = 0.0
    sweepik.solve(robot, robot.fk(q0), locked={"joint_6": 0.0}, limits=False)
    sols = sweepik.solve(robot, robot.fk(q), locked={"joint_6": float(q[5])}, limits=False)
    assert len(sols) == 8 and recovers(robot, sols, q)
