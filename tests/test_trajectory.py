"""Tests of sweepik.trajectory: following a path with branch continuity, pose files and joint-path files."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from sweepik import SweepikError, load_robot
from sweepik.errors import InvalidPoseError, NonFiniteError, ShapeError, UnknownOptionError
from sweepik.model.pose import pose_from_xyz_zyz, zyz_from_matrix
from sweepik.results import joint_distance
from sweepik.solving import solve
from sweepik.trajectory import (
    BRANCH_SWITCH_ANGLE_RAD,
    PathResult,
    PoseFileError,
    branch_switch_thresholds,
    follow_path,
    load_poses,
    weighted_joint_distance,
    write_joint_path,
)

CARM = load_robot("carm")


def _smooth_configs(n: int = 12) -> np.ndarray:
    """A short joint-space segment (d1 in mm, angles in rad) away from singularities and limits."""
    q0 = np.array([700.0, 0.4, 0.3, -0.5, 0.6, 0.2])
    q1 = np.array([760.0, 0.5, 0.35, -0.4, 0.7, 0.1])
    t = np.linspace(0.0, 1.0, n)[:, None]
    return q0 + t * (q1 - q0)


def test_follow_path_recovers_the_generating_joint_path() -> None:
    q = _smooth_configs()
    res = follow_path(CARM, CARM.fk(q), q_start=q[0])
    assert isinstance(res, PathResult)
    assert res.q.shape == q.shape and res.error.shape == (q.shape[0],)
    assert res.found.all() and res.recall == 1.0
    np.testing.assert_array_less(joint_distance(CARM, res.q, q), 1e-8)
    assert res.branch_switches == 0 and res.switch_steps == ()
    assert res.steps.shape == (q.shape[0] - 1, 6)
    np.testing.assert_allclose(res.max_joint_step, joint_distance(CARM, q[1:], q[:-1]).max(axis=0), atol=1e-8)
    assert np.all(res.error <= 1e-9)


def test_follow_path_start_picks_the_solution_nearest_q_start() -> None:
    q = _smooth_configs(4)
    sols = solve(CARM, CARM.fk(q[0]))
    assert len(sols) >= 2
    for other in sols.q:
        res = follow_path(CARM, CARM.fk(q[:1]), q_start=other)
        np.testing.assert_array_less(joint_distance(CARM, res.q[0], other), 1e-8)


def test_follow_path_without_start_takes_the_first_solution() -> None:
    q = _smooth_configs(3)
    res = follow_path(CARM, CARM.fk(q))
    first = solve(CARM, CARM.fk(q[0])).q[0]
    np.testing.assert_allclose(res.q[0], first)


def test_a_jump_between_distant_poses_counts_as_a_branch_switch() -> None:
    q = np.array([[1250.0, 0.0, 0.0, 0.3, 0.0, 0.0], [400.0, 2.0, 1.0, -1.0, 1.5, 0.5]])
    res = follow_path(CARM, CARM.fk(q), q_start=q[0])
    assert res.branch_switches == 1 and res.switch_steps == (0,)
    thresholds = branch_switch_thresholds(CARM)
    assert thresholds[0] == pytest.approx(200.0)  # 10 % of the 2000 mm rail
    np.testing.assert_allclose(thresholds[1:], BRANCH_SWITCH_ANGLE_RAD)


def test_unreachable_points_are_nan_and_lower_recall() -> None:
    q = _smooth_configs(3)
    P = CARM.fk(q)
    P[1, :3, 3] = (5000.0, 0.0, 0.0)  # far outside the workspace
    res = follow_path(CARM, P, q_start=q[0])
    assert res.found.tolist() == [True, False, True]
    assert np.isnan(res.q[1]).all() and np.isnan(res.error[1])
    assert res.recall == pytest.approx(2 / 3)
    assert np.isnan(res.steps).all()  # both steps touch the missing point
    assert res.branch_switches == 0
    np.testing.assert_array_less(joint_distance(CARM, res.q[2], q[2]), 1e-8)


def test_follow_path_along_a_self_motion_family() -> None:
    # theta2 = 90 deg and theta5 = 0: the rail and joints 3, 4, 6 act in one plane (self-motion).
    direction = np.array([100.0, 0.0, 1.0, 1.0, 0.0, 1.0])
    q = np.array([900.0, math.pi / 2, 0.4, -0.6, 0.0, 0.3]) + np.linspace(0, 0.05, 4)[:, None] * direction
    P = CARM.fk(q)
    assert solve(CARM, P[0]).families
    res = follow_path(CARM, P, q_start=q[0])
    assert res.found.all() and res.branch_switches == 0
    assert np.all(res.error <= 1e-9)
    np.testing.assert_allclose(CARM.fk(res.q)[:, :3, 3], P[:, :3, 3], atol=1e-8)


def test_follow_path_validates_its_input() -> None:
    with pytest.raises(ShapeError):
        follow_path(CARM, np.eye(4))
    with pytest.raises(ShapeError):
        follow_path(CARM, np.zeros((0, 4, 4)))
    with pytest.raises(ShapeError):
        follow_path(CARM, CARM.fk(_smooth_configs(2)), q_start=[0.0, 1.0])
    with pytest.raises(UnknownOptionError):
        follow_path(CARM, CARM.fk(_smooth_configs(2)), strategy="fast")  # type: ignore[arg-type]


def test_weighted_distance_uses_the_papers_100_mm_per_radian() -> None:
    a = np.array([100.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    b = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 2 * math.pi + 1.0])
    assert weighted_joint_distance(CARM, a, np.zeros(6)) == pytest.approx(1.0)
    assert weighted_joint_distance(CARM, b, np.zeros(6)) == pytest.approx(1.0)


# ---------------------------------------------------------------------------------------- pose files


@pytest.fixture
def poses() -> np.ndarray:
    return CARM.fk(_smooth_configs(5))


def test_load_poses_csv_16_columns_round_trip(tmp_path, poses) -> None:
    path = tmp_path / "p.csv"
    np.savetxt(path, poses.reshape(-1, 16), delimiter=",", header="16 numbers per row", fmt="%.17g")
    np.testing.assert_array_equal(load_poses(path), poses)


def test_load_poses_csv_xyz_zyz_degrees_with_header_and_whitespace(tmp_path, poses) -> None:
    xyz, zyz = poses[:, :3, 3], np.degrees(zyz_from_matrix(poses))
    rows = np.hstack([xyz, zyz])
    text = "# x y z alpha beta gamma\nx y z alpha beta gamma\n" + "\n".join(
        " ".join(f"{v:.17g}" for v in r) for r in rows
    )
    (tmp_path / "p.txt").write_text(text + "\n\n")
    got = load_poses(tmp_path / "p.txt")
    np.testing.assert_allclose(got, poses, atol=1e-9)
    (tmp_path / "p.csv").write_text("x,y,z,a,b,g\n" + "\n".join(",".join(f"{v:.17g}" for v in r) for r in rows))
    np.testing.assert_allclose(load_poses(tmp_path / "p.csv"), poses, atol=1e-9)


def test_load_poses_npy_round_trip(tmp_path, poses) -> None:
    np.save(tmp_path / "p.npy", poses)
    np.testing.assert_array_equal(load_poses(tmp_path / "p.npy"), poses)
    np.save(tmp_path / "one.npy", poses[0])
    assert load_poses(tmp_path / "one.npy").shape == (1, 4, 4)


def test_load_poses_json_matrices_and_objects(tmp_path, poses) -> None:
    (tmp_path / "m.json").write_text(json.dumps(poses.tolist()))
    np.testing.assert_array_equal(load_poses(tmp_path / "m.json"), poses)
    objs = [{"xyz": T[:3, 3].tolist(), "zyz_deg": np.degrees(zyz_from_matrix(T)).tolist()} for T in poses]
    (tmp_path / "o.json").write_text(json.dumps({"poses": objs}))
    np.testing.assert_allclose(load_poses(tmp_path / "o.json"), poses, atol=1e-9)


def test_load_poses_xyz_zyz_matches_pose_from_xyz_zyz(tmp_path) -> None:
    (tmp_path / "p.csv").write_text("100,200,300,10,20,30\n")
    expected = pose_from_xyz_zyz([100.0, 200.0, 300.0], np.radians([10.0, 20.0, 30.0]))
    np.testing.assert_allclose(load_poses(tmp_path / "p.csv")[0], expected)


@pytest.mark.parametrize(
    ("name", "content", "error"),
    [
        ("seven.csv", "1,2,3,4,5,6,7\n", PoseFileError),
        ("mixed.csv", "1,2,3,0,0,0\n" + ",".join(["0"] * 16) + "\n", PoseFileError),
        ("word.csv", "1,2,3,0,0,0\n1,2,three,0,0,0\n", PoseFileError),
        ("empty.csv", "# nothing\n\n", PoseFileError),
        ("nan.csv", "1,2,nan,0,0,0\n", NonFiniteError),
        ("skew.csv", ",".join(["1"] * 16) + "\n", InvalidPoseError),
        ("bad.json", "{not json", PoseFileError),
        ("dict.json", '{"a": 1}', PoseFileError),
        ("keys.json", '[{"xyz": [1, 2, 3]}]', PoseFileError),
        ("short.json", '[{"xyz": [1, 2], "zyz_deg": [0, 0, 0]}]', PoseFileError),
        ("shape.json", "[[[1, 0, 0], [0, 1, 0], [0, 0, 1]]]", PoseFileError),
        ("poses.yaml", "- 1\n", PoseFileError),
    ],
)
def test_bad_pose_files_raise_sweepik_errors(tmp_path, name, content, error) -> None:
    path = tmp_path / name
    path.write_text(content)
    with pytest.raises(error) as info:
        load_poses(path)
    assert isinstance(info.value, SweepikError)
    assert name in str(info.value)


def test_bad_npy_and_missing_files(tmp_path) -> None:
    np.save(tmp_path / "flat.npy", np.zeros((3, 16)))
    with pytest.raises(PoseFileError, match=r"\(N, 4, 4\)"):
        load_poses(tmp_path / "flat.npy")
    (tmp_path / "junk.npy").write_text("not an array")
    with pytest.raises(PoseFileError):
        load_poses(tmp_path / "junk.npy")
    with pytest.raises(PoseFileError, match="no such file"):
        load_poses(tmp_path / "missing.csv")


# ----------------------------------------------------------------------------------- joint-path files


def test_write_joint_path_csv_in_degrees_and_mm(tmp_path) -> None:
    q = _smooth_configs(4)
    q[2] = np.nan
    path = write_joint_path(tmp_path / "q.csv", q, CARM)
    lines = path.read_text().splitlines()
    assert lines[0].startswith("#") and "theta2 in deg" in lines[0] and "d1 in mm" in lines[0]
    assert lines[1] == "d1_mm,theta2_deg,theta3_deg,theta4_deg,theta5_deg,theta6_deg"
    back = np.genfromtxt(path, delimiter=",", skip_header=2)
    expected = np.hstack([q[:, :1], np.degrees(q[:, 1:])])
    np.testing.assert_allclose(back, expected, rtol=0, atol=1e-12, equal_nan=True)


def test_write_joint_path_json(tmp_path) -> None:
    q = _smooth_configs(3)
    q[1] = np.nan
    doc = json.loads(write_joint_path(tmp_path / "q.json", q, CARM).read_text())
    assert doc["robot"] == "carm" and doc["joints"][0] == "d1"
    assert doc["units"] == ["mm", "deg", "deg", "deg", "deg", "deg"]
    assert doc["q"][1] == [None] * 6
    np.testing.assert_allclose(doc["q"][0], np.r_[q[0, 0], np.degrees(q[0, 1:])])


def test_write_joint_path_rejects_bad_input(tmp_path) -> None:
    with pytest.raises(UnknownOptionError):
        write_joint_path(tmp_path / "q.txt", _smooth_configs(2), CARM)
    with pytest.raises(ShapeError):
        write_joint_path(tmp_path / "q.csv", np.zeros((2, 5)), CARM)


def test_nearest_and_follow_path_use_one_metric(rng: np.random.Generator) -> None:
    # the metric weighs 100 mm of rail like 1 rad: a reference far along the rail but close in angles
    from sweepik.results import weighted_joint_distance

    arm = load_robot("carm")
    q = rng.uniform(arm.lower, arm.upper, (40, 6))
    ref = rng.uniform(arm.lower, arm.upper, (40, 6))
    T = arm.fk(q)
    for TT, r in zip(T, ref, strict=True):
        sol = solve(arm, TT)
        if not sol:
            continue
        picked = follow_path(arm, TT[None], q_start=r).q[0]
        np.testing.assert_allclose(picked, sol.nearest(r), atol=1e-9)
        assert float(weighted_joint_distance(arm, sol.nearest(r), r)) <= float(sol.distances(r).min()) + 1e-12
