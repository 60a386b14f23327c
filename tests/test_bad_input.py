"""Bad input everywhere: a corpus generated here (robot files, pose files, library arguments) must end in a
SweepikError (library) or one stderr line with exit status 2 (CLI) - never a traceback, a hang or a wrong answer."""

from __future__ import annotations

import json
import struct
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik.cli import main
from sweepik.robot_file import MAX_ROBOT_FILE_BYTES
from sweepik.trajectory import load_poses

CARM_TOML = (Path(sweepik.__file__).parent / "robots" / "carm.toml").read_text()
GOOD_POSE = sweepik.load_robot("carm").fk(np.array([700.0, 0.4, 0.3, -0.5, 0.6, 0.2]))


def _robot_corpus() -> dict[str, bytes]:
    rng = np.random.default_rng(8)
    c: dict[str, bytes] = {
        "deep_array": ("x = " + "[" * 50_000 + "]" * 50_000 + "\n").encode(),
        "deep_table": ("x = " + "{a = " * 5_000 + "1" + "}" * 5_000 + "\n").encode(),
        "reduction_list": CARM_TOML.replace(
            'default_reduction = "carm-d1"', 'default_reduction = ["carm-d1"]'
        ).encode(),
        "a_1e308": CARM_TOML.replace("a = 350.0", "a = 1e308").encode(),
        "a_inf": CARM_TOML.replace("a = 350.0", "a = inf").encode(),
        "a_nan": CARM_TOML.replace("a = 350.0", "a = nan").encode(),
        "digits": CARM_TOML.replace("a = 350.0", "a = " + "9" * 5000).encode(),
        "utf16": CARM_TOML.encode("utf-16"),
        "latin1": CARM_TOML.replace("C-Arm", "C-Arm \xe9").encode("latin-1"),
        "empty": b"",
        "oversize": b"# " + b"x" * (MAX_ROBOT_FILE_BYTES + 10),
        "name_list": CARM_TOML.replace('name = "carm"', "name = [1, 2]").encode(),
        "unit_number": CARM_TOML.replace('length_unit = "mm"', "length_unit = 3").encode(),
        "limits_str": CARM_TOML.replace("limits = [0.0, 2000.0]", 'limits = ["0", "2000"]').encode(),
        "limits_reversed": CARM_TOML.replace("limits = [0.0, 2000.0]", "limits = [2000.0, 0.0]").encode(),
        "type_bad": CARM_TOML.replace('type = "prismatic"', 'type = "spherical"').encode(),
        "negative_length": CARM_TOML.replace("a = 350.0", "a = -350.0").encode(),
        "zero_d": CARM_TOML.replace("d = 402.0", "d = 0.0").encode(),
    }
    lines = CARM_TOML.splitlines(keepends=True)
    for k in range(40):  # truncated files and random byte flips of a valid file
        cut = int(rng.integers(1, len(CARM_TOML)))
        c[f"truncated_{k}"] = CARM_TOML[:cut].encode()
        blob = bytearray(CARM_TOML.encode())
        for pos in rng.integers(0, len(blob), size=5):
            blob[pos] = int(rng.integers(0, 256))
        c[f"flipped_{k}"] = bytes(blob)
        shuffled = list(lines)
        rng.shuffle(shuffled)
        c[f"shuffled_{k}"] = "".join(shuffled).encode()
    for k in range(20):
        c[f"random_{k}"] = rng.bytes(int(rng.integers(1, 400)))
    return c


ROBOT_CORPUS = _robot_corpus()


def _one_error_line(code: int, err: str, path: Path) -> bool:
    return code == 2 and len(err.strip().splitlines()) == 1 and str(path) in err and "Traceback" not in err


@pytest.mark.parametrize("case", sorted(ROBOT_CORPUS))
def test_robot_file_corpus(case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Loading fails with a RobotFileError naming the file, or the robot loads and a solve either works or
    refuses with a SweepikError; the CLI says so in one line with exit status 2."""
    path = tmp_path / f"{case}.toml"
    path.write_bytes(ROBOT_CORPUS[case])
    try:
        robot = sweepik.load_robot(path)
    except sweepik.SweepikError:
        robot = None
    code = main(["robots", str(path)])
    _, err = capsys.readouterr()
    if robot is None:
        assert _one_error_line(code, err, path), (case, err)
        return
    assert code == 0 and "Traceback" not in err
    try:
        sweepik.solve(robot, robot.fk(np.clip(np.zeros(robot.n_joints), robot.lower, robot.upper)))
        solved = True
    except sweepik.SweepikError:
        solved = False
    if not case.startswith(("truncated_", "flipped_", "shuffled_", "random_")):
        assert not solved, case
    matrix = [repr(float(v)) for v in GOOD_POSE.ravel()]
    code = main(["solve", str(path), "--matrix", *matrix])
    _, err = capsys.readouterr()
    assert "Traceback" not in err
    assert code == 0 if solved else (code == 2 and len(err.strip().splitlines()) == 1), (case, err)


def test_robot_file_that_is_a_directory(tmp_path: Path) -> None:
    d = tmp_path / "arm.toml"
    d.mkdir()
    with pytest.raises(sweepik.RobotFileError, match="not a file"):
        sweepik.load_robot(d)


def _npy_with_header(shape: tuple[int, ...]) -> bytes:
    header = f"{{'descr': '<f8', 'fortran_order': False, 'shape': {shape}, }}"
    header += " " * (118 - len(header)) + "\n"
    return b"\x93NUMPY\x01\x00" + struct.pack("<H", len(header)) + header.encode("latin1") + b"\0" * 128


def _pose_corpus(tmp_path: Path) -> dict[str, Path]:
    rng = np.random.default_rng(9)
    files: dict[str, bytes | Callable[[Path], None]] = {
        "utf16.csv": "x,y,z,a,b,c\n1,2,3,0,0,0\n".encode("utf-16"),
        "binary.csv": bytes(range(256)) * 4,
        "utf16.json": json.dumps([GOOD_POSE.tolist()]).encode("utf-16"),
        "deep.json": b"[" * 100_000 + b"]" * 100_000,
        "digits.json": b"[[" + b"9" * 5000 + b"]]",
        "empty.json": b"",
        "empty.csv": b"",
        "ragged.csv": b"1,2,3,0,0,0\n1,2,3\n",
        "text.csv": b"a,b,c,d,e,f\nx,y,z,1,2,3\n",
        "notpose.csv": ("," * 15 + "\n").encode(),
        "crafted.npy": _npy_with_header((10**11, 4, 4)),
        "crafted_neg.npy": _npy_with_header((-1, 4, 4)),
        "garbage.npy": rng.bytes(300),
        "object.npy": lambda p: np.save(p, np.zeros((2, 4, 4)).astype(object), allow_pickle=True),
        "complex.npy": lambda p: np.save(p, np.zeros((2, 4, 4), complex)),
        "shape.npy": lambda p: np.save(p, np.zeros((2, 3, 3))),
        "nan.npy": lambda p: np.save(p, np.full((1, 4, 4), np.nan)),
        "notrigid.json": json.dumps([np.ones((4, 4)).tolist()]).encode(),
        "dict.json": json.dumps({"poses": [{"xyz": [1, 2]}]}).encode(),
        "huge.json": b"[[[1e400,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]",
        "unknown.xyz": b"1 2 3",
    }
    for k in range(15):
        blob = bytearray(json.dumps([GOOD_POSE.tolist()]).encode())
        for pos in rng.integers(0, len(blob), size=3):
            blob[pos] = int(rng.integers(0, 256))
        files[f"flipped_{k}.json"] = bytes(blob)
        files[f"random_{k}.csv"] = rng.bytes(int(rng.integers(1, 300)))
    out = {}
    for name, content in files.items():
        p = tmp_path / name
        if callable(content):
            content(p)
        else:
            p.write_bytes(content)
        out[name] = p
    out["missing.csv"] = tmp_path / "missing.csv"
    out["directory.json"] = tmp_path / "directory.json"
    out["directory.json"].mkdir()
    return out


def test_pose_file_corpus(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    for name, path in _pose_corpus(tmp_path).items():
        try:
            load_poses(path)
            loaded = True
        except sweepik.SweepikError:
            loaded = False
        if not name.startswith(("flipped_", "random_")):
            assert not loaded, name
        if loaded:
            continue
        code = main(["solve", "carm", "--poses", str(path)])
        _, err = capsys.readouterr()
        assert _one_error_line(code, err, path), (name, err)


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_samples": "64"},
        {"n_samples": 64.5},
        {"n_samples": float("nan")},
        {"n_samples": True},
        {"n_samples": 10**9},
        {"n_samples": 7},
        {"limits": "no"},
        {"limits": None},
        {"reduction": ["carm-d1"]},
        {"reduction": "nope"},
        {"strategy": ["precise"]},
        {"strategy": "fast"},
    ],
)
def test_bad_solver_arguments(kwargs: dict[str, object]) -> None:
    arm = sweepik.load_robot("carm")
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve(arm, GOOD_POSE, **kwargs)  # type: ignore[arg-type]
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve_many(arm, GOOD_POSE[None], **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("chunk", [0, -3, 2.5, "10", None])
def test_bad_chunk_size(chunk: object) -> None:
    with pytest.raises(sweepik.SweepikError, match="chunk_size"):
        sweepik.solve_many(sweepik.load_robot("carm"), GOOD_POSE[None], chunk_size=chunk)  # type: ignore[arg-type]


def test_complex_and_foreign_inputs() -> None:
    arm = sweepik.load_robot("carm")
    with pytest.raises(sweepik.ShapeError, match="real"):
        sweepik.solve(arm, GOOD_POSE.astype(complex))
    with pytest.raises(sweepik.ShapeError, match="real"):
        arm.fk(np.zeros(6, complex))
    for robot in ("carm", None, {"joints": []}):
        with pytest.raises(sweepik.SweepikError, match="sweepik.Robot"):
            sweepik.solve(robot, GOOD_POSE)  # type: ignore[arg-type]
    # accepted: NumPy integers and bools
    assert len(sweepik.solve(arm, GOOD_POSE, n_samples=np.int64(64), limits=np.bool_(True))) > 0
