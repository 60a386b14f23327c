"""Tests of sweepik.experiments.verify: the paper's section-6 experiments on small subsets (the full run is a CLI
job)."""

from __future__ import annotations

import itertools
import json
import math

import numpy as np
import pytest

import sweepik.experiments.verify as V
from sweepik import load_robot
from sweepik.errors import RobotDefinitionError, UnknownOptionError
from sweepik.experiments import verify_report
from sweepik.solving import iter_solve, solve_many

CARM = load_robot("carm")


def _deg(q: np.ndarray) -> np.ndarray:
    return np.hstack([q[..., :1], np.round(np.degrees(q[..., 1:]), 9)])


def _generic_subset(n: int, seed: int = 7) -> np.ndarray:
    """Nonsingular grid configurations outside the special sets of ``configuration_classes``."""
    g = V.grid_configurations(include_singular=False)
    g = g[V.configuration_classes(g) == "regular"]
    return g[np.random.default_rng(seed).choice(len(g), n, replace=False)]


# --------------------------------------------------------------------------------------------- grid


def test_grid_has_16500_points_and_the_table2_values() -> None:
    g = V.grid_configurations(include_singular=True)
    assert g.shape == (16500, 6)
    d = _deg(g)
    for col, key in enumerate(V.TABLE2):
        assert sorted(set(d[:, col].tolist())) == sorted(V.TABLE2[key])
    assert len({tuple(r) for r in d.tolist()}) == 16500


def test_nonsingular_grid_drops_exactly_the_600_singular_points() -> None:
    full = _deg(V.grid_configurations(include_singular=True))
    kept = _deg(V.grid_configurations(include_singular=False))
    assert kept.shape == (15900, 6)
    dropped = {tuple(r) for r in full.tolist()} - {tuple(r) for r in kept.tolist()}
    assert len(dropped) == 600
    assert all(abs(r[1]) == 90 and r[2] == 0 for r in dropped)
    expected = {
        (d1, t2, 0.0, t4, t5, t6)
        for d1, t2, t4, t5, t6 in itertools.product(
            V.TABLE2["d1_mm"], (-90.0, 90.0), V.TABLE2["theta4_deg"], V.TABLE2["theta5_deg"], V.TABLE2["theta6_deg"]
        )
    }
    assert dropped == expected
    assert V.singular_mask(V.grid_configurations(include_singular=True)).sum() == 600


def test_configuration_classes_of_the_grid() -> None:
    g = V.grid_configurations(include_singular=True)
    classes = V.configuration_classes(g)
    counts = {c: int(np.count_nonzero(classes == c)) for c in V.CONFIG_CLASSES}
    assert counts == {"self-motion": 600, "excluded-singular": 480, "branch-crossing": 585, "regular": 14835}
    # the paper's singular set = excluded-singular + the 120 self-motion points with theta3 = 0
    sing = V.singular_mask(g)
    assert np.all(sing[classes == "excluded-singular"])
    assert np.count_nonzero(sing & (classes == "self-motion")) == 120
    rand = V.random_configurations(CARM, 100, np.random.default_rng(0))
    assert set(V.configuration_classes(rand).tolist()) == {"regular"}


def test_run_grid_precise_on_a_subset_finds_every_generating_configuration() -> None:
    res = V.run_grid(CARM, _generic_subset(200), "precise")
    assert res["points"] == 200
    assert res["recall"] == 1.0 and res["recall_loose"] == 1.0
    assert res["missed_total"] == 0 and res["missed"] == []
    assert res["J_max"] <= 1e-9 and res["J_mean"] <= res["J_max"] and res["J_99_6"] <= res["J_max"]
    assert res["no_solution"] == 0
    assert sum(res["solutions_histogram"].values()) == 200
    assert sum(res["distinct_d1_histogram"].values()) == 200
    assert all(1 <= int(k) <= 4 for k in res["distinct_d1_histogram"])  # the paper: 1 to 4 values of d1
    assert res["seconds_per_point"] > 0
    json.dumps(res, allow_nan=False)


def test_run_grid_counts_a_pose_found_on_a_self_motion_family() -> None:
    # theta2 = 90 deg, theta5 = 0: a continuum of solutions; the generating configuration lies on it.
    q = np.array([[800.0, math.pi / 2, 0.5, -0.5, 0.0, 0.2], [1200.0, -math.pi / 2, -0.5, 0.3, 0.0, -0.4]])
    res = V.run_grid(CARM, q, "precise")
    assert res["family_poses"] == 2
    assert res["recall"] == 1.0 and res["J_max"] <= 1e-9


# Poses where two solution branches cross (theta2 = 0, theta5 = 0, theta3 + theta4 = -90 deg): the solver
# locates the double root along d1 only to ~1e-5 mm (sqrt of machine epsilon), see docs/verification.md.
_DOUBLE_ROOTS = np.array(
    [
        [d1, 0.0, t3, -math.pi / 2 - t3, 0.0, t6]
        for d1 in (500.0, 1000.0, 1500.0)
        for t3 in np.radians([-60.0, -30.0])
        for t6 in np.radians([-60.0, 0.0, 60.0])
    ]
)


def test_double_root_poses_are_found_to_double_root_accuracy() -> None:
    assert set(V.configuration_classes(_DOUBLE_ROOTS).tolist()) == {"branch-crossing"}
    res = V.run_grid(CARM, _DOUBLE_ROOTS, "precise")
    assert res["recall_loose"] == 1.0
    assert res["J_max"] <= 1e-9


def test_double_root_poses_are_found_to_1e_6() -> None:
    assert V.run_grid(CARM, _DOUBLE_ROOTS, "precise")["recall"] == 1.0


def test_missed_configurations_are_reported(monkeypatch) -> None:
    # Make every solve return nothing: each generating configuration is then missed.
    import sweepik.experiments.verify as mod

    def nothing(robot, poses, **kw):
        return iter_solve(robot, poses + np.array([[0, 0, 0, 1e4], [0, 0, 0, 0], [0, 0, 0, 0], [0, 0, 0, 0]]), **kw)

    monkeypatch.setattr(mod, "iter_solve", nothing)
    q = _generic_subset(25)
    res = V.run_grid(CARM, q, "precise")
    assert res["recall"] == 0.0 and res["no_solution"] == 25
    assert res["missed_total"] == 25 and len(res["missed"]) == 20
    np.testing.assert_allclose(res["missed"], q[:20])
    assert res["J_max"] is None
    assert res["missed_by_class"] == {"regular": 25}
    json.dumps(res, allow_nan=False)


def test_random_configurations_are_seeded_in_limits_and_off_grid() -> None:
    a = V.random_configurations(CARM, 500, np.random.default_rng(3))
    b = V.random_configurations(CARM, 500, np.random.default_rng(3))
    np.testing.assert_array_equal(a, b)
    assert a.shape == (500, 6) and CARM.within_limits(a).all()
    assert not np.any(np.isclose(np.mod(a[:, 0], 10.0), 0.0, atol=1e-3))  # d1 off the paper's 10 mm grid
    with pytest.raises(UnknownOptionError):
        V.random_configurations(CARM, -1)


# ------------------------------------------------------------------------------------------ figure 4


def test_figure4_data_finds_every_desired_theta2() -> None:
    data = V.figure4_data(CARM, "precise")
    assert data["theta2_desired_deg"] == list(V.TABLE2["theta2_deg"])
    assert data["desired_found"] == [True] * 11
    assert len(data["theta2_solutions_deg"]) == len(data["multiplicity"]) == 11
    for want, vals, mult, n in zip(
        data["theta2_desired_deg"],
        data["theta2_solutions_deg"],
        data["multiplicity"],
        data["n_solutions"],
        strict=True,
    ):
        assert any(abs(v - want) < 1e-6 for v in vals)
        assert sum(mult) == n
        # "very common to have an alternate solution for theta2 that is 180 deg off"
    off = sum(
        any(abs(abs(v - w) - 180) < 1e-6 for v in vals)
        for w, vals in zip(data["theta2_desired_deg"], data["theta2_solutions_deg"], strict=True)
    )
    assert off >= 8
    json.dumps(data, allow_nan=False)


# ---------------------------------------------------------------------------------------- trajectory


def test_trajectory_poses_form_the_closed_rectangle_at_the_zero_pose_orientation() -> None:
    P = V.trajectory_poses(CARM)
    assert P.shape == (4 * V.POINTS_PER_EDGE + 1, 4, 4)
    np.testing.assert_allclose(P[0, :3, 3], V.TRAJECTORY_START)
    np.testing.assert_allclose(P[-1], P[0])
    np.testing.assert_allclose(P[:, :3, :3], np.broadcast_to(CARM.fk(np.zeros(6))[:3, :3], (P.shape[0], 3, 3)))
    C = np.array(V.TRAJECTORY_CORNERS)
    edges = np.roll(C, -1, axis=0) - C
    np.testing.assert_allclose([edges[i] @ edges[(i + 1) % 4] for i in range(4)], 0.0, atol=1e-9)  # a rectangle
    np.testing.assert_allclose(P[:: V.POINTS_PER_EDGE][:4, :3, 3], C)


def test_every_pose_along_the_rectangle_is_reachable_within_limits() -> None:
    dense = V.trajectory_poses(CARM, per_edge=50)
    assert all(len(s) >= 1 for s in solve_many(CARM, dense))


def test_run_trajectory_precise_is_continuous_and_exact() -> None:
    tr = V.run_trajectory(CARM, "precise")
    assert tr["points"] >= 41 and tr["recall"] == 1.0
    assert tr["branch_switches"] == 0 and tr["switch_steps"] == []
    assert tr["J_max"] <= 1e-9
    assert 0 < tr["max_joint_step"] < 30  # degrees
    step = tr["max_joint_step_detail"]
    assert step["angle_deg"] == tr["max_joint_step"]
    assert 0 < step["angle_deg"] < 30 and 0 < step["length"] < 200 and step["length_unit"] == "mm"
    assert set(step["per_joint"]) == set(CARM.joint_names)
    np.testing.assert_allclose(tr["achieved_xyz"], tr["xyz"], atol=1e-9)
    json.dumps(tr, allow_nan=False)


# ---------------------------------------------------------------------------------------- run_verify


@pytest.fixture
def small_grid(monkeypatch):
    """run_verify on 60 grid points (12 of them singular) instead of 16,500."""
    full = V.grid_configurations

    def small(include_singular: bool = False) -> np.ndarray:
        g = full(include_singular=True)
        pick = np.r_[np.nonzero(V.singular_mask(g))[0][:12], np.nonzero(~V.singular_mask(g))[0][::331][:48]]
        g = g[pick]
        return g if include_singular else g[~V.singular_mask(g)]

    monkeypatch.setattr(V, "grid_configurations", small)


def test_run_verify_json_contract_one_strategy(small_grid) -> None:
    res = V.run_verify(CARM, "precise", offgrid=20, seed=1)
    for key in ("grid", "grid_all", "offgrid", "trajectory"):
        for metric in ("points", "recall", "J_max", "J_mean", "J_99_6", "seconds_per_point"):
            assert metric in res[key], (key, metric)
    assert "max_joint_step" in res["trajectory"]
    assert res["grid_all"]["points"] == 60 and res["grid"]["points"] == 48 and res["offgrid"]["points"] == 20
    assert res["paper_reference"] == V.PAPER_TABLES
    json.dumps(res, allow_nan=False)


def test_run_verify_both_and_the_table(small_grid, tmp_path) -> None:
    pytest.importorskip("matplotlib")
    seen: list[str] = []
    res = V.run_verify(CARM, "both", offgrid=10, progress=lambda stage, done, total: seen.append(stage))
    assert set(res) == {"paper", "precise", "paper_reference"}
    assert any(s.startswith("paper") for s in seen) and any(s.startswith("precise") for s in seen)
    paper_grid = res["paper"]["grid"]
    assert paper_grid["J_max"] <= 1e-9  # grid-exact d1: the paper's strategy hits the roots exactly
    assert set(paper_grid["missed_by_class"]) <= {"self-motion", "branch-crossing"}
    json.dumps(res, allow_nan=False)
    table = verify_report.format_table(res)
    head = table.splitlines()[0]
    assert "paper" in head and "sweepik paper-strategy" in head and "sweepik precise" in head
    assert "3.49e-06" in table and "1.27e-13" in table and "15,900" in table
    assert len(table.splitlines()[2].split()) > 0
    report = verify_report.write_report(res, tmp_path / "out")
    text = report.read_text()
    assert "Grid-exact d1 flatters" in text and "| J_max (mm) | 3.49e-06 |" in text
    for name in ("figure4_precise.png", "figure4_paper.png", "trajectory_3d.png", "trajectory_joints.png"):
        assert (tmp_path / "out" / name).stat().st_size > 1000
        assert f"]({name})" in text


def test_format_table_for_one_strategy_marks_the_other_column_missing(small_grid) -> None:
    res = V.run_verify(CARM, "precise", offgrid=0)
    assert res["offgrid"]["points"] == 0 and res["offgrid"]["recall"] is None
    rows = {ln.split("  ")[0].strip(): ln for ln in verify_report.format_table(res).splitlines()}
    assert rows["J_max (mm)"].split()[-2] == "-"  # no paper-strategy run


def test_run_verify_rejects_bad_options() -> None:
    with pytest.raises(UnknownOptionError):
        V.run_verify(CARM, "fast")  # type: ignore[arg-type]
    with pytest.raises(UnknownOptionError):
        V.run_verify(CARM, "precise", offgrid=-1)
    with pytest.raises(RobotDefinitionError, match="C-Arm"):
        V.run_verify(load_robot("puma560"))
    with pytest.raises(UnknownOptionError):
        V.run_grid(CARM, _generic_subset(2), "fast")  # type: ignore[arg-type]
