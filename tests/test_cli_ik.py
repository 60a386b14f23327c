"""CLI: solve, path, verify, bench (small sizes); errors are one line with exit status 2."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik import load_robot
from sweepik.cli.app import main
from sweepik.experiments import bench
from sweepik.model.pose import xyz_zyz_from_pose

CARM = load_robot("carm")


def _xyz_zyz_args(q: np.ndarray) -> list[str]:
    xyz, zyz = xyz_zyz_from_pose(CARM.fk(q))
    return ["--xyz", *map(repr, xyz.tolist()), "--zyz", *map(repr, np.degrees(zyz).tolist())]


def test_solve_xyz_zyz_json_contains_generating_configuration(capsys: pytest.CaptureFixture[str]) -> None:
    q = np.array([700.0, 0.4, 0.3, -0.5, 0.6, -0.2])
    assert main(["solve", "carm", *_xyz_zyz_args(q), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    sols = np.array(out["poses"][0]["q"])
    d = np.abs(np.pi - np.mod(np.pi - (sols - q), 2 * np.pi))
    d[:, 0] = np.abs(sols[:, 0] - q[0])
    assert d.max(axis=1).min() < 1e-6
    assert max(out["poses"][0]["error_J"]) <= 1e-9


def test_solve_matrix_table_and_nearest(capsys: pytest.CaptureFixture[str]) -> None:
    q = np.array([900.0, -0.7, 0.5, -0.9, 1.1, 0.3])
    matrix = [repr(float(v)) for v in CARM.fk(q).ravel()]
    nearest = [repr(float(v)) for v in np.where(CARM.is_revolute, np.degrees(q), q)]
    assert main(["solve", "--matrix", *matrix, "--nearest", *nearest]) == 0
    out = capsys.readouterr().out
    assert "solution(s)" in out and "nearest:" in out
    near = [float(v) for v in out.strip().splitlines()[-1].split(":")[1].split()]
    np.testing.assert_allclose(near, np.where(CARM.is_revolute, np.degrees(q), q), atol=1e-6)


def test_solve_poses_file_and_unreachable(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    T = CARM.fk(np.array([[500.0, 0.1, 0.2, 0.3, 0.4, 0.5], [1200.0, -0.1, 0.2, -0.3, 0.4, -0.5]]))
    far = np.eye(4)
    far[:3, 3] = [9000.0, 0.0, 0.0]
    np.save(tmp_path / "poses.npy", np.concatenate([T, far[None]]))
    assert main(["solve", "--poses", str(tmp_path / "poses.npy"), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [len(p["q"]) > 0 for p in out["poses"]] == [True, True, False]
    assert "unreachable" in out["poses"][2]["reason"]


@pytest.mark.parametrize(
    "argv",
    [
        ["solve"],  # no pose
        ["solve", "--xyz", "1", "2", "3", "--matrix", *["0"] * 16],  # two poses
        ["solve", "--xyz", "1", "2", "nan"],
        ["solve", "--matrix", *["1"] * 16],  # not a rigid transform
        ["solve", "--xyz", "1", "2", "3", "--reduction", "nope"],
        ["solve", "nosuchrobot", "--xyz", "1", "2", "3"],
        ["solve", "--poses", "/no/such/file.csv"],
    ],
)
def test_solve_bad_input_is_one_line_exit_2(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) >= 1 and err[-1].startswith("sweepik")
    assert "Traceback" not in "\n".join(err)


def test_path_writes_joint_csv(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    q = np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]) + np.linspace(0, 0.05, 6)[:, None]
    np.save(tmp_path / "path.npy", CARM.fk(q))
    start = [repr(float(v)) for v in np.where(CARM.is_revolute, np.degrees(q[0]), q[0])]
    out_file = tmp_path / "joints.csv"
    assert main(["path", "carm", str(tmp_path / "path.npy"), "--start", *start, "-o", str(out_file)]) == 0
    assert "branch switches: 0" in capsys.readouterr().out
    rows = np.loadtxt(out_file, delimiter=",", comments="#", skiprows=2)
    np.testing.assert_allclose(rows, np.where(CARM.is_revolute, np.degrees(q), q), atol=1e-6)


def test_verify_json_contract(monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys) -> None:  # type: ignore[no-untyped-def]
    import sweepik.experiments.verify as verify

    full = verify.grid_configurations

    def small(include_singular: bool = False) -> np.ndarray:
        return full(include_singular)[::97]

    monkeypatch.setattr(verify, "grid_configurations", small)
    assert main(["verify", "--strategy", "precise", "--offgrid", "50", "--json", str(tmp_path / "out.json")]) == 0
    res = json.loads((tmp_path / "out.json").read_text())
    for key in ("grid", "grid_all", "offgrid", "trajectory"):
        for metric in ("points", "recall", "J_max", "J_mean", "J_99_6", "seconds_per_point"):
            assert metric in res[key]
        assert res[key]["recall"] == 1.0
        assert res[key]["J_max"] <= 1e-9
    assert "max_joint_step" in res["trajectory"] and res["trajectory"]["points"] >= 40
    assert "paper" in capsys.readouterr().out


def test_bench_runs_small(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import sweepik.experiments.bench as bench

    monkeypatch.setattr(bench, "grid_configurations", lambda include_singular=False: bench_grid_small())
    argv = ["bench", "--single", "20", "--paper", "5", "--memory", "0", "--repeats", "1", "--batch", "8", "--json"]
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["grid_precise"]["poses"] == 100 and out["single_pose"]["poses"] == 20
    assert out["grid_precise"]["us_per_pose"] > 0
    assert out["startup"]["import_s"] > 0 and out["startup"]["first_solve_s"] > 0
    # then every bundled arm, each with its plan, times and the targets it misses
    assert set(out["arms"]) == set(sweepik.bundled_robots())
    for row in out["arms"].values():
        assert row["sweepik"]["single_us"] > 0 and row["sweepik"]["batched_us"] > 0 and isinstance(row["misses"], list)


def test_bench_arms_small(capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["bench", "--arms", "ur5", "carm", "--single", "5", "--batch", "16", "--memory", "200", "--repeats", "1"]
    assert main([*argv, "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["arms"]) == {"ur5", "carm"}
    ur5, carm = out["arms"]["ur5"], out["arms"]["carm"]
    assert ur5["plan"] == "closed form" and carm["plan"] == "sweep joint 1"
    assert ur5["sweepik"]["batched_us"] > 0 and ur5["sweepik"]["single_us"] > 0 and ur5["peak_rss_mib"] > 0
    assert "sweepik carm-d1" in carm and isinstance(carm["misses"], list)
    # ssik, the swept arms' yardstick: 6R arms only (a column either way; timed when installed)
    assert carm["ssik"]["solves"] is False and carm["ssik"]["why"] == "not 6R" and "ssik" not in carm["peers"]
    assert ur5["ssik"]["solves"] == ("ssik" in ur5["peers"])
    assert main(argv[:3] + ["--single", "0", "--batch", "16", "--memory", "0", "--repeats", "1"]) == 0
    table = capsys.readouterr().out
    assert table.splitlines()[0].startswith("arm") and "ur5" in table and "ssik single/batched" in table


def test_bench_times_the_solvers_of_an_arm_in_turn(monkeypatch: pytest.MonkeyPatch) -> None:
    """``bench._side_by_side`` times blocks of poses, then each batched run, by every solver in turn (so that the
    machine's drifting speed falls on all of them alike), after one warm-up call of each; medians and bests per
    solver."""
    import numpy as np

    from sweepik.experiments.bench import _side_by_side

    monkeypatch.setattr(bench, "SINGLE_BLOCK", 2)

    calls: list[tuple[str, str, int]] = []

    def solver(name: str) -> tuple[object, object]:
        return (lambda T: calls.append((name, "one", int(T[0, 0])))), (lambda Ts: calls.append((name, "many", len(Ts))))

    poses = np.arange(20, dtype=float)[:, None, None] * np.ones((1, 4, 4))
    out = _side_by_side({"a": solver("a"), ("peer", "b"): solver("b")}, poses, single=3, batch=12, repeats=2)
    singles = [c for c in calls if c[1] == "one"]
    blocks = [("a", "one", 0), ("a", "one", 1), ("b", "one", 0), ("b", "one", 1), ("a", "one", 2), ("b", "one", 2)]
    assert singles == [("a", "one", 0), ("b", "one", 0), *blocks]
    batches = [c for c in calls if c[1] == "many"]
    assert batches == [("a", "many", 8), ("b", "many", 8)] + [(n, "many", 12) for _ in range(2) for n in "ab"]
    assert set(out) == {"a", ("peer", "b")} and all(v["single_us"] > 0 and v["batched_us"] > 0 for v in out.values())
    calls.clear()
    none = _side_by_side({"a": solver("a")}, poses, single=0, batch=12, repeats=1)
    assert none["a"]["single_us"] is None and not [c for c in calls if c[1] == "one"]


def test_bench_arms_unknown_robot_is_one_line(capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["bench", "--arms", "ur5", "nosuchbot", "--single", "1"]) == 2
    captured = capsys.readouterr()
    assert captured.out == "" and len(captured.err.strip().splitlines()) == 1 and "nosuchbot" in captured.err


def bench_grid_small() -> np.ndarray:
    from sweepik.experiments.verify import grid_configurations

    return grid_configurations(False)[::159][:100]


@pytest.mark.parametrize(
    "argv",
    [["solve", "--xyz", "1", "2", "3", "--strategy", "fast"], ["fk"], ["nosuch"], ["path"], ["solve", "--xyz", "1"]],
)
def test_usage_errors_are_one_line(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("sweepik: error:")
