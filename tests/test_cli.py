"""The ``sweepik`` command line (sweepik.cli.app)."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik import load_robot
from sweepik.cli.app import main

CARM_ZERO = ["500", "0", "0", "0", "0", "0"]


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def position(out: str) -> tuple[float, float, float]:
    m = re.search(r"position \[mm\]: x = (\S+)\s+y = (\S+)\s+z = (\S+)", out)
    assert m, out
    x, y, z = (float(v) for v in m.groups())
    return x, y, z


def assert_one_line_error(code: int, out: str, err: str, *needles: str) -> None:
    assert code == 2
    assert out == ""
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sweepik: error:"), err
    assert "Traceback" not in err
    for needle in needles:
        assert needle in lines[0], (needle, err)


# --------------------------------------------------------------------------------------------------
# fk
# --------------------------------------------------------------------------------------------------


def test_fk_carm_zero_pose(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "fk", "carm", *CARM_ZERO)
    assert (code, err) == (0, "")
    assert position(out) == (402.0, -350.0, 500.0)
    assert "robot: carm" in out
    assert re.search(r"ZYZ Euler \[deg\]: alpha = 0\.000000\s+beta = 0\.000000\s+gamma = -90\.000000", out), out
    assert "gimbal" in out  # beta = 0: the text says which combination is defined
    # The 4x4 matrix: rows of four numbers; the first row is 0 1 0 402.
    rows = [line.split() for line in out.splitlines() if re.fullmatch(r"\s*(-?\d+\.\d+\s*){4}", line)]
    np.testing.assert_allclose(
        np.array(rows, dtype=float), load_robot("carm").fk(np.array(CARM_ZERO, float)), atol=1e-6
    )
    assert "-0.000000" not in out


def test_fk_default_robot_is_carm(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "fk", *CARM_ZERO)
    assert code == 0
    assert position(out) == (402.0, -350.0, 500.0)
    assert run(capsys, "fk", *CARM_ZERO)[1] == run(capsys, "fk", "carm", *CARM_ZERO)[1]


def test_fk_negative_values_are_positionals(capsys: pytest.CaptureFixture[str]) -> None:
    carm = load_robot("carm")
    for argv, q in [
        (["carm", "500", "-30", "0", "0", "0", "0"], [500, -30, 0, 0, 0, 0]),
        (["-30", "10", "-.5", "-1e1", "-1.5E+1", "-0"], [-30, 10, -0.5, -10, -15, 0]),  # robot left out
    ]:
        code, out, err = run(capsys, "fk", *argv, "--json")
        assert (code, err) == (0, ""), err
        data = json.loads(out)
        q_deg = np.array(q, dtype=np.float64)
        q_rad = np.where(carm.is_revolute, np.radians(q_deg), q_deg)
        np.testing.assert_allclose(data["q"], q_rad, rtol=1e-15)
        np.testing.assert_allclose(data["pose"], carm.fk(q_rad), rtol=0, atol=1e-9)


def test_fk_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "fk", "carm", "700", "10", "20", "-30", "40", "50", "--json")
    assert (code, err) == (0, "")
    data = json.loads(out)
    assert {"robot", "q", "pose", "xyz", "zyz_deg", "length_unit"} <= set(data)
    assert data["robot"] == "carm" and data["length_unit"] == "mm"
    carm = load_robot("carm")
    q = np.array([700.0, *np.radians([10, 20, -30, 40, 50])])
    np.testing.assert_allclose(data["q"], q, rtol=1e-15)
    T = carm.fk(q)
    np.testing.assert_allclose(data["pose"], T, rtol=0, atol=1e-12)
    np.testing.assert_allclose(data["xyz"], T[:3, 3], rtol=0, atol=1e-12)
    np.testing.assert_allclose(data["zyz_deg"], np.degrees(sweepik.zyz_from_matrix(T)), rtol=0, atol=1e-12)
    assert data["within_limits"] is True


def test_fk_rad(capsys: pytest.CaptureFixture[str]) -> None:
    q = ["800", "0.5", "-0.25", "1", "2", "-3"]
    code, out, _ = run(capsys, "fk", "--rad", "carm", *q, "--json")
    assert code == 0
    np.testing.assert_allclose(json.loads(out)["pose"], load_robot("carm").fk(np.array(q, float)), atol=1e-12)
    deg = [q[0], *(str(np.degrees(float(v))) for v in q[1:])]
    code, out_deg, _ = run(capsys, "fk", "carm", *deg, "--json")
    np.testing.assert_allclose(json.loads(out_deg)["pose"], json.loads(out)["pose"], rtol=0, atol=1e-9)


def test_fk_puma_in_metres_and_limits_note(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "fk", "puma560", "0", "0", "0", "0", "0", "0")
    assert code == 0
    assert "position [m]" in out
    code, out, _ = run(capsys, "fk", "carm", "-10", "0", "200", "0", "0", "0")
    assert code == 0
    assert "outside joint limits: d1, theta3" in out
    code, out, _ = run(capsys, "fk", "carm", "-10", "0", "200", "0", "0", "0", "--json")
    assert json.loads(out)["within_limits"] is False


def test_fk_robot_file(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "slider.toml"
    f.write_text(
        'name = "slider"\nlength_unit = "mm"\n[[joints]]\ntype = "prismatic"\nlimits = [0, 10]\n'
        '[[joints]]\ntype = "revolute"\na = 3.0\nlimits = [-90, 90]\n',
        encoding="utf-8",
    )
    code, out, _ = run(capsys, "fk", str(f), "2", "-90")
    assert code == 0
    np.testing.assert_allclose(position(out), (3.0, 0.0, 2.0))


def test_fk_verbose_lists_frames(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "-v", "fk", *CARM_ZERO)
    assert code == 0
    assert "frame origins" in out and "tool" in out
    code2, out2, _ = run(capsys, "fk", *CARM_ZERO, "--verbose")
    assert out2 == out
    assert "frame origins" not in run(capsys, "fk", *CARM_ZERO)[1]


@pytest.mark.parametrize("values", [["1", "2"], CARM_ZERO + ["0"], []])
def test_fk_wrong_number_of_joints(capsys: pytest.CaptureFixture[str], values: list[str]) -> None:
    code, out, err = run(capsys, "fk", "carm", *values)
    assert_one_line_error(code, out, err, "6 joint values", "d1 [mm]", "theta2 [deg]", f"got {len(values)}")


def test_fk_unknown_robot(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "fk", "nosuchbot", *CARM_ZERO)
    assert_one_line_error(code, out, err, "nosuchbot", "carm", "puma560")


@pytest.mark.parametrize("bad", ["nan", "NaN", "inf", "-inf", "1e999"])
def test_fk_non_finite_value(capsys: pytest.CaptureFixture[str], bad: str) -> None:
    code, out, err = run(capsys, "fk", "carm", "500", "0", bad, "0", "0", "0")
    assert_one_line_error(code, out, err, "theta3", "finite")


def test_fk_non_numeric_value(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "fk", "carm", "500", "0", "zero", "0", "0", "0")
    assert_one_line_error(code, out, err, "theta3", "'zero'", "number")


def test_broken_robot_file_is_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "broken.toml"
    f.write_text('[[joints]]\nname = "elbow"\ntype = "revolute"\n', encoding="utf-8")
    code, out, err = run(capsys, "fk", str(f), "0")
    assert_one_line_error(code, out, err, "broken.toml", "elbow", "limits")


# --------------------------------------------------------------------------------------------------
# robots, --version, usage errors
# --------------------------------------------------------------------------------------------------


def test_robots_lists_bundled(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "robots")
    assert (code, err) == (0, "")
    for name in sweepik.bundled_robots():
        assert re.search(rf"^{name}: ", out, re.MULTILINE), name
    assert "C-Arm" in out
    # The C-Arm's DH table: theta3 row with alpha -90, theta -90, limits [-84, 116] deg.
    assert re.search(r"theta3\s+revolute\s+0\s+-90\s+0\s+-90\s+\[-84, 116\] deg", out), out
    assert re.search(r"d1\s+prismatic.*\[0, 2000\] mm", out)


def test_robots_json(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "robots", "--json")
    assert code == 0
    data = {r["name"]: r for r in json.loads(out)}
    assert set(data) == set(sweepik.bundled_robots())
    carm = data["carm"]
    assert carm["dh_table"] == load_robot("carm").dh_table()
    assert carm["length_unit"] == "mm" and carm["dh_convention"] == "modified" and carm["n_joints"] == 6
    assert data["puma560_std"]["dh_convention"] == "standard"


def test_robots_named_and_unknown(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "robots", "puma560")
    assert code == 0 and out.startswith("puma560:") and "carm" not in out
    code, out, err = run(capsys, "robots", "carm", "nosuchbot")
    assert_one_line_error(code, out, err, "nosuchbot")


def test_version(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "--version")
    assert code == 0
    assert out.strip() == f"sweepik {sweepik.__version__}"
    assert re.fullmatch(r"sweepik \d+\.\d+\.\d+\S*", out.strip())


@pytest.mark.parametrize("argv", [[], ["frobnicate"], ["fk", "--bogus", *CARM_ZERO], ["robots", "--precision", "x"]])
def test_usage_errors_return_2(capsys: pytest.CaptureFixture[str], argv: list[str]) -> None:
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert out == ""
    assert "sweepik" in err and "error:" in err and "Traceback" not in err


def test_help_returns_0(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "--help")
    assert code == 0 and "fk" in out and "robots" in out
    code, out, _ = run(capsys, "fk", "--help")
    assert code == 0 and "--rad" in out


def test_console_script_exit_status() -> None:
    script = Path(sys.executable).with_name("sweepik")
    if not script.exists():
        pytest.skip("console script not installed next to this interpreter")
    ok = subprocess.run([str(script), "fk", *CARM_ZERO, "--json"], capture_output=True, text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["xyz"] == pytest.approx([402.0, -350.0, 500.0], abs=1e-9)
    bad = subprocess.run([str(script), "fk", "nosuchbot", "1"], capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2
    assert bad.stderr.startswith("sweepik: error:") and len(bad.stderr.splitlines()) == 1


def test_precision_option(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, _ = run(capsys, "fk", *CARM_ZERO, "--precision", "2")
    assert code == 0
    assert "x = 402.00  y = -350.00  z = 500.00" in out
    code, out, err = run(capsys, "fk", *CARM_ZERO, "--precision", "-1")
    assert code == 2 and out == "" and "--precision" in err


def test_unreadable_robot_file_is_one_line(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    f = tmp_path / "latin1.toml"
    f.write_bytes(b'name = "caf\xe9"\n')
    code, out, err = run(capsys, "fk", str(f), "0")
    assert code in (1, 2) and out == ""
    assert len(err.splitlines()) == 1 and err.startswith("sweepik: error:")


@pytest.mark.parametrize(
    "argv",
    [
        ["verify", "--seed", "-1"],
        ["verify", "--offgrid", "-5"],
        ["solve", "carm", "--xyz", "500", "0", "500", "--zyz", "0", "0", "0", "0"],
        ["path", "carm"],
        ["path", "carm", "poses.csv", "-o", "/nonexistent-dir/out.csv"],
        ["verify", "--json", "/nonexistent-dir/r.json"],
        ["verify", "--report", "/nonexistent-dir/sub/report"],
    ],
)
def test_cli_refuses_at_once(argv: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    """Bad options and unwritable outputs fail before any computation: one stderr line, exit status 2."""
    from sweepik.cli.app import main

    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err


def test_interrupt_is_one_line_and_status_130(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Ctrl-C during a command (here: while a solve prints) ends with one line on stderr and status 130, not a
    traceback."""
    import sweepik.cli.app as cli

    def interrupted(args: object) -> int:
        print("first pose")
        raise KeyboardInterrupt

    monkeypatch.setitem(cli._COMMANDS, "fk", (cli._COMMANDS["fk"][0], interrupted))
    code, out, err = run(capsys, "fk", "carm", "0", "0", "0", "0", "0", "0")
    assert code == 130 and out == "first pose\n"
    assert err.strip().splitlines() == ["sweepik: interrupted"]


# --------------------------------------------------------------------------------------------------
# a newcomer's first commands (issue 38)
# --------------------------------------------------------------------------------------------------


def test_seven_joints_without_lock_names_the_cli_option(capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = run(capsys, "solve", "franka_panda", "--xyz", "0.31", "0", "0.59", "--zyz", "0", "180", "-135")
    assert_one_line_error(code, out, err, "--lock NAME=VALUE", "sweepik analyze franka_panda")
    assert "locked={" not in err


def test_solve_says_its_decomposition_and_the_readme_panda_example_has_a_solution(
    capsys: pytest.CaptureFixture[str],
) -> None:
    code, out, err = run(
        capsys, "solve", "franka_panda", "--xyz", "0.31", "0", "0.59", "--zyz", "0", "180", "-135", "--lock",
        "joint7=45",
    )  # fmt: skip
    assert code == 0 and err == ""
    assert out.splitlines()[0] == "decomposition: closed form, 8 branches, reversed chain"
    assert "1 solution(s)" in out
    code, out, err = run(capsys, "solve", "ur5", "--xyz", "0.3", "0.2", "0.4", "-v")
    assert code == 0 and "solution(s) in" in err and "decomposition: closed form, 8 branches" in out


def test_nearest_with_metric_and_tol_and_windings(capsys: pytest.CaptureFixture[str]) -> None:
    base = ["solve", "ur5", "--xyz", "0.3", "0.2", "0.4", "--zyz", "0", "180", "0", "--nearest", "0", "-90", "90",
            "0", "90", "0", "--metric", "linf"]  # fmt: skip
    code, out, _ = run(capsys, *base, "--tol", "30")
    assert code == 0 and "nearest: none within --tol 30 (linf metric)" in out
    code, out, _ = run(capsys, *base, "--tol", "300", "--windings", "--json")
    pose = json.loads(out)["poses"][0]
    assert len(pose["q"]) == len(pose["winding_of"]) > 8 and pose["nearest"] is not None
    code, out, err = run(capsys, *base, "--tol", "-1")
    assert_one_line_error(code, out, err, "--tol")


def test_robots_shows_origin_axis_joints_and_the_lock_table(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    path = tmp_path / "ur5.urdf"
    path.write_text(sweepik.urdf_text(load_robot("ur5")))
    code, out, _ = run(capsys, "robots", str(path))
    assert code == 0 and "origin + axis joints" in out and "origin xyz [m]" in out and "axis" in out
    code, out, _ = run(capsys, "robots", "franka_panda")
    assert code == 0 and "lock a joint first" in out and "lock joint" in out and "closed form" in out
    row = next(ln for ln in out.splitlines() if ln.strip().startswith("2 (joint2)  0 deg"))
    assert row.rstrip().endswith("none: every pose a continuum")  # joints 1 and 3 coaxial when joint 2 is 0


def test_first_run_says_it_compiles_on_a_terminal_only(
    capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from sweepik.cli import app

    monkeypatch.setattr(app, "_kernels_cached", lambda: False)
    code, out, err = run(capsys, "solve", "ur5", "--xyz", "0.3", "0.2", "0.4")
    assert code == 0 and "compiling" not in err  # (not a terminal: nothing said)
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)
    code, out, err = run(capsys, "solve", "ur5", "--xyz", "0.3", "0.2", "0.4")
    assert code == 0 and "compiling the solver's kernels" in err and "compiling" not in out
    code, out, err = run(capsys, "robots", "ur5")
    assert code == 0 and "compiling" not in err  # (no kernels needed)


def test_paper_strategy_says_when_the_precise_one_finds_more(capsys: pytest.CaptureFixture[str]) -> None:
    """At a C-Arm pose with a double root (two solutions merging), the paper's 10 mm sweep returns one; the output
    says that the precise strategy finds two, in text and in JSON."""
    q_double = np.array([300.0, 0.0, np.pi / 4, np.pi / 4, np.radians(2.0), 0.0])
    T = load_robot("carm").fk(q_double)
    m = [repr(float(v)) for v in T.ravel()]
    precise = sweepik.solve(load_robot("carm"), T)
    paper = sweepik.solve(load_robot("carm"), T, strategy="paper")
    assert len(paper) < len(precise)  # (the premise)
    code, out, _ = run(capsys, "solve", "--matrix", *m, "--strategy", "paper")
    assert code == 0 and f"the precise strategy finds {len(precise)} solution(s)" in out
    code, out, _ = run(capsys, "solve", "--matrix", *m, "--strategy", "paper", "--json")
    assert json.loads(out)["poses"][0]["precise_strategy_finds"] == len(precise)
    code, out, _ = run(capsys, "solve", "--matrix", *m)
    assert "note:" not in out


def test_a_file_that_cannot_be_written_or_read_is_one_line_naming_it(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """Writing fails after the output path's checks passed (a full disk, a path under /proc): one line naming the
    file and its error, exit status 1 (docs/cli.md: an operating-system error after the checks; Python's
    ``[Errno 28] ...`` text before); a robot file that cannot be read (a directory) is bad input, exit status 2."""
    import errno

    out = tmp_path / "arm.toml"

    def full_disk(self: Path, *args: object, **kwargs: object) -> int:
        raise OSError(errno.ENOSPC, "No space left on device", str(self))

    with monkeypatch.context() as m:
        m.setattr(Path, "write_text", full_disk)
        code = main(["convert", "ur5", "-o", str(out)])
    _, err = capsys.readouterr()
    assert code == 1 and err.strip() == f"sweepik: error: {out}: No space left on device"
    unreadable = tmp_path / "arm_dir.toml"
    unreadable.mkdir()
    code = main(["fk", str(unreadable), "0", "0", "0", "0", "0", "0"])
    _, err = capsys.readouterr()
    assert code == 2 and len(err.strip().splitlines()) == 1 and str(unreadable) in err
