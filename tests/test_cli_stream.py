"""CLI: streamed output of big batches (solve --poses, path), progress on stderr, early refusal of bad outputs
and counts, and the text of self-motion families and multiple roots."""

from __future__ import annotations

import io
import json
import os
import sys
from pathlib import Path

import numpy as np
import pytest

import sweepik.cli.common as cli_common
import sweepik.cli.solve as cli_solve
import sweepik.solving as solver
from sweepik import load_robot, solve_many
from sweepik.cli.app import main
from sweepik.cli.common import _is_number, _print_json, _print_json_stream, _Progress
from sweepik.trajectory import follow_path

CARM = load_robot("carm")


def _deg(*q: float) -> np.ndarray:
    return np.array([q[0], *np.radians(q[1:])])


#: Poses of every kind: regular ones, a double root (multiplicity 2), self-motion families only, unreachable.
Q_REGULAR = [_deg(500, 10, 20, -30, 40, 50), _deg(1200, -40, 60, 10, -70, 20), _deg(800, 30, -20, 45, 80, -10)]
Q_DOUBLE = _deg(300, 0, 45, 45, 2, 0)
Q_FAMILY = np.array([800.0, np.pi / 2, 0.3, 0.2, 0.0, 0.1])


def _poses() -> np.ndarray:
    far = np.eye(4)
    far[:3, 3] = [9000.0, 0.0, 0.0]
    T = CARM.fk(np.array([*Q_REGULAR, Q_DOUBLE, Q_FAMILY]))
    return np.concatenate([T[:2], far[None], T[2:]])


@pytest.fixture(scope="module")
def poses_file(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("stream") / "poses.npy"
    np.save(path, _poses())
    return path


class _FakeTTY(io.StringIO):
    def isatty(self) -> bool:
        return True


def _set_chunk(monkeypatch: pytest.MonkeyPatch, chunk: int) -> None:
    """Make the solver work ``chunk`` poses at a time (its chunks shrink to fit its sample budget)."""
    monkeypatch.setattr(solver, "SAMPLE_BUDGET", chunk * solver.N_SAMPLES)


def _run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


# --------------------------------------------------------------------------------------------------
# Streaming: output identical to one solve_many call formatted at once
# --------------------------------------------------------------------------------------------------


@pytest.mark.parametrize("chunk", [1, 2, 4096])
def test_solve_json_streamed_is_bit_identical_to_solve_many(
    chunk: int, poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    _set_chunk(monkeypatch, chunk)
    code, out, err = _run(capsys, "solve", "carm", "--poses", str(poses_file), "--json")
    assert (code, err) == (0, "")
    sols = solve_many(CARM, _poses())
    doc = {
        "robot": "carm",
        "joint_names": CARM.joint_names,
        "units": "radians and mm",
        "strategy": "precise",
        "decomposition": "reduction carm-d1 (the robot file's default)",
        "poses": [cli_solve._solution_json(CARM, s, None) for s in sols],
    }
    assert out == json.dumps(doc, indent=2, allow_nan=False) + "\n"
    data = json.loads(out)
    assert [p["q"] for p in data["poses"]] == [s.q.tolist() for s in sols]
    assert [p["multiplicity"] for p in data["poses"]] == [s.multiplicity.tolist() for s in sols]
    assert data["poses"][4]["multiplicity"] == [2, 1]  # the double root
    assert data["poses"][5]["q"] == [] and len(data["poses"][5]["families"]) > 0
    assert data["poses"][2]["reason"].startswith("unreachable")


def test_solve_text_streamed_is_identical_whatever_the_chunk(
    poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    outs = []
    for chunk in (4096, 2, 1):
        _set_chunk(monkeypatch, chunk)
        code, out, err = _run(capsys, "solve", "--poses", str(poses_file), "--no-limits", "--precision", "9")
        assert (code, err) == (0, "")
        outs.append(out)
    assert outs[0] == outs[1] == outs[2]
    blocks = outs[0].split("pose ")[1:]
    assert [b.split(":")[0] for b in blocks] == [str(k) for k in range(1, 7)]
    sols = solve_many(CARM, _poses(), limits=False)
    for block, sol in zip(blocks, sols, strict=True):
        rows = [r for r in map(str.split, block.splitlines()) if len(r) >= 8 and r[0].isdigit() and _is_number(r[1])]
        assert len(rows) == len(sol)
        shown = np.array([r[1:7] for r in rows], dtype=float).reshape(-1, 6)
        np.testing.assert_allclose(shown, np.where(CARM.is_revolute, np.degrees(sol.q), sol.q), atol=1e-9)


def test_print_json_stream_matches_print_json(capsys: pytest.CaptureFixture[str]) -> None:
    head = {"a": 1, "b": {"c": [1.5, None, "x\ny"]}, "empty": []}
    items = [{"q": [[1.0, 2.0]], "f": [], "s": "a\tb"}, [], {}, 3, "z"]
    for n in (0, 1, len(items)):
        _print_json({**head, "items": items[:n]})
        ref = capsys.readouterr().out
        _print_json_stream(head, "items", iter(items[:n]))
        assert capsys.readouterr().out == ref
    with pytest.raises(ValueError):
        _print_json_stream(head, "a", [])


def test_path_in_chunks_equals_one_follow_path(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    q = np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]) + np.linspace(0, 0.3, 11)[:, None]
    P = CARM.fk(q)
    P[4, :3, 3] = [9000.0, 0.0, 0.0]  # unreachable, as are 6 and 7: a chunk without any solution
    P[6:8, :3, 3] = [9000.0, 0.0, 0.0]
    np.save(tmp_path / "path.npy", P)
    ref = follow_path(CARM, P)
    for chunk in (3, 2, 1, 4096):
        _set_chunk(monkeypatch, chunk)
        code, out, err = _run(capsys, "path", str(tmp_path / "path.npy"), "--json")
        assert (code, err) == (0, "")
        data = json.loads(out)
        got = np.array([[np.nan if v is None else v for v in row] for row in data["q"]])
        np.testing.assert_array_equal(got, ref.q)
        assert data["branch_switches"] == ref.branch_switches
        assert data["switch_steps"] == list(ref.switch_steps)
        assert data["max_joint_step"] == ref.max_joint_step.tolist()
        assert data["found"] == int(ref.found.sum()) == 8
        np.testing.assert_array_equal(follow_path(CARM, P).q, ref.q)  # the library call, chunked likewise


# --------------------------------------------------------------------------------------------------
# Progress: on stderr, only on a terminal
# --------------------------------------------------------------------------------------------------


def test_no_progress_when_stderr_is_not_a_terminal(
    poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cli_common, "PROGRESS_AFTER_S", 0.0)
    _set_chunk(monkeypatch, 2)
    for argv in (["solve", "--poses", str(poses_file)], ["path", str(poses_file)]):
        code, out, err = _run(capsys, *argv)
        assert code == 0 and out and err == ""


@pytest.mark.parametrize("command", ["solve", "path"])
def test_progress_on_a_terminal(
    command: str, poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cli_common, "PROGRESS_AFTER_S", 0.0)
    _set_chunk(monkeypatch, 2)
    tty = _FakeTTY()
    monkeypatch.setattr(sys, "stderr", tty)
    argv = ["solve", "--poses", str(poses_file), "--json"] if command == "solve" else ["path", str(poses_file)]
    assert main(argv) == 0
    out = capsys.readouterr().out
    text = tty.getvalue()
    assert f"\r{command}" in text and "6/6" in text and text.endswith("\n")
    assert "\r" not in out and "6/6" not in out  # standard output stays clean
    if command == "solve":
        json.loads(out)


def test_no_solve_progress_when_the_output_streams_to_the_terminal(
    poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(cli_common, "PROGRESS_AFTER_S", 0.0)
    tty_err, tty_out = _FakeTTY(), _FakeTTY()
    monkeypatch.setattr(sys, "stderr", tty_err)
    monkeypatch.setattr(sys, "stdout", tty_out)
    assert main(["solve", "--poses", str(poses_file)]) == 0
    assert tty_err.getvalue() == "" and "pose 6:" in tty_out.getvalue()


def test_progress_class(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(cli_common, "PROGRESS_AFTER_S", 0.0)
    monkeypatch.setattr(cli_common, "PROGRESS_EVERY_S", 0.0)
    tty = _FakeTTY()
    monkeypatch.setattr(sys, "stderr", tty)
    p = _Progress()
    p("stage", 1, 4)
    assert tty.getvalue().startswith("\rstage") and tty.getvalue().endswith("1/4")
    p.close()  # an unfinished line is ended
    assert tty.getvalue().endswith("1/4\n")
    p("stage", 4, 4)
    assert tty.getvalue().endswith("4/4\n")
    p.close()
    assert tty.getvalue().count("\n") == 2
    off = _Progress(enabled=False)
    off("stage", 1, 1)
    assert tty.getvalue().count("\n") == 2
    monkeypatch.setattr(sys, "stderr", io.StringIO())  # not a terminal
    quiet = _Progress()
    quiet("stage", 1, 1)
    assert sys.stderr.getvalue() == ""


def test_bench_progress_on_a_terminal(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    import sweepik.experiments.bench as bench
    from sweepik.experiments.verify import grid_configurations

    monkeypatch.setattr(bench, "grid_configurations", lambda include_singular=False: grid_configurations()[:20])
    monkeypatch.setattr(cli_common, "PROGRESS_AFTER_S", 0.0)
    tty = _FakeTTY()
    monkeypatch.setattr(sys, "stderr", tty)
    argv = ["bench", "--single", "5", "--paper", "2", "--memory", "0", "--repeats", "2", "--batch", "8", "--json"]
    assert main(argv) == 0
    assert json.loads(capsys.readouterr().out)["grid_precise"]["poses"] == 20
    text = tty.getvalue()
    assert "bench: grid" in text and "2/2" in text and "bench: paper strategy" in text


# --------------------------------------------------------------------------------------------------
# Refused at once: unwritable outputs, bad counts
# --------------------------------------------------------------------------------------------------


def _no_work(monkeypatch: pytest.MonkeyPatch) -> None:
    """Make every long computation fail the test if it starts."""
    import sweepik.experiments.bench as bench
    import sweepik.experiments.verify as verify
    import sweepik.trajectory as trajectory

    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("computation started before the bad argument was refused")

    monkeypatch.setattr(verify, "run_verify", fail)
    monkeypatch.setattr(bench, "run_bench", fail)
    monkeypatch.setattr(trajectory, "follow_path", fail)
    monkeypatch.setattr(cli_solve, "iter_solve", fail)


def _one_line_exit_2(code: int, out: str, err: str, *needles: str) -> None:
    assert code == 2 and out == ""
    lines = err.splitlines()
    assert len(lines) == 1 and lines[0].startswith("sweepik: error:") and "Traceback" not in err, err
    for needle in needles:
        assert needle in lines[0], (needle, err)


@pytest.mark.parametrize(
    "kind",
    ["missing-dir", "is-a-dir", "parent-is-a-file", "bad-extension", "report-is-a-file", "verify-json-dir"],
)
def test_unwritable_output_refused_before_any_computation(
    kind: str,
    tmp_path: Path,
    poses_file: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    _no_work(monkeypatch)
    a_file = tmp_path / "file.txt"
    a_file.write_text("x")
    target, argv = {
        "missing-dir": (str(tmp_path / "nope" / "j.csv"), ["path", str(poses_file), "-o"]),
        "is-a-dir": (str(tmp_path), ["path", str(poses_file), "-o"]),
        "parent-is-a-file": (str(a_file / "j.json"), ["path", str(poses_file), "-o"]),
        "bad-extension": (str(tmp_path / "j.txt"), ["path", str(poses_file), "-o"]),
        "report-is-a-file": (str(a_file), ["verify", "--report"]),
        "verify-json-dir": (str(tmp_path), ["verify", "--json"]),
    }[kind]
    code, out, err = _run(capsys, *argv, target)
    _one_line_exit_2(code, out, err, target)


def test_unwritable_directory_refused(
    tmp_path: Path, poses_file: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    _no_work(monkeypatch)
    ro = tmp_path / "ro"
    ro.mkdir()
    ro.chmod(0o500)
    real_access = os.access
    if os.access(ro, os.W_OK):  # running as root: the permission bits do not stop us, pretend they do
        monkeypatch.setattr(os, "access", lambda p, mode: False if Path(p) == ro else real_access(p, mode))
    try:
        for argv in (
            ["path", str(poses_file), "-o", str(ro / "j.csv")],
            ["verify", "--json", str(ro / "r.json")],
            ["verify", "--report", str(ro / "report")],
        ):
            code, out, err = _run(capsys, *argv)
            _one_line_exit_2(code, out, err, str(ro), "not writable")
    finally:
        ro.chmod(0o700)


@pytest.mark.parametrize(
    "argv",
    [
        ["verify", "--seed", "-1"],
        ["verify", "--seed", "x"],
        ["verify", "--offgrid", "-5"],
        ["verify", "--offgrid", "10000000000000"],
        ["bench", "--single", "-3"],
        ["bench", "--paper", "-1"],
        ["bench", "--memory", "1000000000"],
        ["bench", "--repeats", "0"],
        ["bench", "--repeats", "2.5"],
    ],
)
def test_bad_counts_refused_at_once(
    argv: list[str], capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    _no_work(monkeypatch)
    code, out, err = _run(capsys, *argv)
    _one_line_exit_2(code, out, err, argv[1])


# --------------------------------------------------------------------------------------------------
# Messages: stray numbers, missing pose file, families, multiplicity
# --------------------------------------------------------------------------------------------------


def test_extra_angle_after_zyz_is_named(capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch) -> None:
    _no_work(monkeypatch)
    code, out, err = _run(capsys, "solve", "carm", "--xyz", "1", "2", "3", "--zyz", "0", "0", "0", "0")
    _one_line_exit_2(code, out, err, "--zyz takes 3 values (A B G)", "'0'", "sweepik solve --help")
    assert "unknown robot" not in err
    code, out, err = _run(capsys, "solve", "--xyz", "1", "2", "3", "--zyz", "0", "0", "0", "-5")
    _one_line_exit_2(code, out, err, "'-5'", "--zyz 3 angles")
    code, out, err = _run(capsys, "solve", "carm", "--matrix", *["0"] * 17)
    _one_line_exit_2(code, out, err, "--matrix takes 16 values")
    code, out, err = _run(capsys, "fk", "carm", *["0"] * 6, "--bogus")
    _one_line_exit_2(code, out, err, "unrecognized arguments: --bogus", "sweepik fk --help")


@pytest.mark.parametrize("robot", ["carm", "puma560", "my_arm.toml"])
def test_path_with_only_a_robot_says_the_pose_file_is_missing(robot: str, capsys: pytest.CaptureFixture[str]) -> None:
    code, out, err = _run(capsys, "path", robot)
    _one_line_exit_2(code, out, err, "POSES_FILE is missing", robot)


def test_family_only_pose_is_described(capsys: pytest.CaptureFixture[str]) -> None:
    matrix = [repr(float(v)) for v in CARM.fk(Q_FAMILY).ravel()]
    code, out, err = _run(capsys, "solve", "--matrix", *matrix, "--precision", "3")
    assert (code, err) == (0, "")
    sol = solve_many(CARM, CARM.fk(Q_FAMILY)[None])[0]
    nf = len(sol.families)
    assert len(sol) == 0 and nf > 1
    assert f"0 isolated solutions and {nf} self-motion families" in out
    assert "0 solution(s)" not in out
    for k, fam in enumerate(sol.families):
        lo, hi = fam.interval
        assert f"self-motion family {k + 1}: every d1 in [{lo:.3f}, {hi:.3f}] mm gives a solution" in out
    rows = [ln.split() for ln in out.splitlines() if ln.split()[:1] == ["1"] and ln.split()[1] in ("from", "to")]
    members = np.array([r[2:] for r in rows], dtype=float)
    np.testing.assert_allclose(members[:, 0], sol.families[0].interval, atol=1e-3)
    np.testing.assert_allclose(CARM.fk(_deg(*members[0])), CARM.fk(Q_FAMILY), atol=1e-2)


def test_revolute_family_interval_in_degrees(capsys: pytest.CaptureFixture[str]) -> None:
    """A family whose free joint is revolute (none on the C-Arm's reductions): interval and members in degrees,
    or radians with --rad."""
    from types import SimpleNamespace

    members = {0.5: _deg(700, 0, 10, 20, 30, 40), 1.0: _deg(900, 0, 15, 25, 35, 45)}
    fam = SimpleNamespace(free_joint=2, interval=(0.5, 1.0), at=lambda t: np.array([members[v] for v in t]))
    sol = SimpleNamespace(families=(fam,))
    for rad, (lo, hi) in ((False, ("28.648", "57.296")), (True, ("0.500", "1.000"))):
        args = SimpleNamespace(precision=3, rad=rad)
        cli_solve._print_families(CARM, sol, args)  # type: ignore[arg-type]
        out = capsys.readouterr().out
        unit = "rad" if rad else "deg"
        assert f"self-motion family 1: every theta3 in [{lo}, {hi}] {unit} gives a solution" in out
        from_row = next(ln.split() for ln in out.splitlines() if ln.split()[:2] == ["1", "from"])
        assert from_row[2:] == (
            ["700.000", "0.000", "0.175", "0.349", "0.524", "0.698"]
            if rad
            else ["700.000", "0.000", "10.000", "20.000", "30.000", "40.000"]
        )


def test_multiplicity_column_only_where_a_root_is_multiple(capsys: pytest.CaptureFixture[str]) -> None:
    def table(q: np.ndarray) -> list[str]:
        matrix = [repr(float(v)) for v in CARM.fk(q).ravel()]
        code, out, err = _run(capsys, "solve", "--matrix", *matrix)
        assert (code, err) == (0, "")
        return out.splitlines()

    double = table(Q_DOUBLE)
    assert double[0].startswith("decomposition: ")
    assert double[2].split()[-1] == "multiplicity"
    assert sorted(ln.split()[-1] for ln in double[3:5]) == ["1", "2"]
    regular = table(Q_REGULAR[0])
    assert "multiplicity" not in "\n".join(regular)
    assert regular[2].split()[-1] == "[mm]"  # the last column is J


def test_format_table_with_known_numeric_columns_is_unchanged() -> None:
    from sweepik.cli.common import _format_table

    header = ["#", "d1 [mm]", "theta2 [deg]", "J [mm]", "in limits", "multiplicity"]
    rows = [
        ["1", "300.000000", "-0.000001", "8.53e-14", "yes", "2"],
        ["10", "1308.642000", "-112.5", "1.1e-13", "no", "1"],
    ]
    numeric = [True, True, True, True, False, True]
    assert _format_table(header, rows, numeric=numeric) == _format_table(header, rows)
    assert _format_table(header, [], numeric=numeric) == _format_table(header, [])
