"""Bad input everywhere: a corpus generated here (robot files, pose files, library arguments) must end in a
SweepikError (library) or one stderr line with exit status 2 (CLI) - never a traceback, a hang, a MemoryError or
a silent wrong answer. Nothing big is checked in: files are written to ``tmp_path`` (huge ones sparse)."""

from __future__ import annotations

import io
import json
import os
import struct
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import sweepik
from sweepik import solving
from sweepik.cli.app import main
from sweepik.engine import chunk
from sweepik.io.robot_file import MAX_ANGLE_DEG, MAX_LENGTH, MAX_LIMIT, MAX_ROBOT_FILE_BYTES
from sweepik.trajectory import MAX_NPY_POSES, MAX_POSE_TEXT_BYTES, load_poses

CARM_TOML = (Path(sweepik.__file__).parent / "io" / "robots" / "carm.toml").read_text()
CARM = sweepik.load_robot("carm")
Q_GOOD = np.array([700.0, 0.4, 0.3, -0.5, 0.6, 0.2])
GOOD_POSE = CARM.fk(Q_GOOD)
MATRIX_ARGS = [repr(float(v)) for v in GOOD_POSE.ravel()]


def _offset_last_joint(text: str) -> str:
    """The C-Arm text with the last joint's axis 30 mm off joint 5's (its DH row ``a = 30``)."""
    head, sep, tail = text.rpartition("a = 0.0\nalpha = 90.0")
    return head + "a = 30.0\nalpha = 90.0" + tail


def _cli(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str]:
    code = main(argv)
    _, err = capsys.readouterr()
    return code, err


def _assert_one_error_line(code: int, err: str, name: str | None, case: object = None) -> None:
    """Exit status 2, exactly one stderr line naming ``name`` (the file), no traceback."""
    assert code == 2, (case, code, err)
    assert len(err.strip().splitlines()) == 1, (case, err)
    assert "Traceback" not in err and err.startswith("sweepik: error: "), (case, err)
    if name is not None:
        assert name in err, (case, err)


def _sparse(path: Path, size: int) -> Path:
    """A file of ``size`` bytes that takes no disk space (refused on its size, never read)."""
    with path.open("wb") as fh:
        fh.truncate(size)
    return path


# ------------------------------------------------------------------------------------------ robot files


def _field(toml: str, key: str, value: str, nth: int = 0) -> str:
    """``toml`` with the ``nth`` line ``key = ...`` given ``value``."""
    lines = toml.splitlines(keepends=True)
    hits = [i for i, ln in enumerate(lines) if ln.split("=")[0].strip() == key]
    lines[hits[nth]] = f"{key} = {value}\n"
    return "".join(lines)


#: Values no robot-file field accepts (numbers, strings and lists alike).
_BAD_VALUES = {
    "str": '"x"',
    "bool": "true",
    "inf": "inf",
    "ninf": "-inf",
    "nan": "nan",
    "1e308": "1e308",
    "n1e308": "-1e308",
    "date": "1979-05-27",
    "table": "{x = 1}",
    "nested": "[[[1.0]]]",
    "digits": "9" * 5000,
}
_NUMERIC_FIELDS = {"a": 3, "alpha": 1, "d": 4, "theta": 2, "limits": 0}
_TEXT_FIELDS = ("name", "description", "length_unit", "default_reduction", "dh_convention")


def _robot_corpus() -> dict[str, tuple[bytes, bool]]:
    """name -> (file content, True when loading must fail). Others must load or fail cleanly."""
    rng = np.random.default_rng(8)
    must: dict[str, bytes] = {
        "deep_array": ("x = " + "[" * 50_000 + "]" * 50_000 + "\n").encode(),
        "deep_table": ("x = " + "{a = " * 5_000 + "1" + "}" * 5_000 + "\n").encode(),
        "deep_array_in_field": _field(CARM_TOML, "a", "[" * 3000 + "]" * 3000, 3).encode(),
        "json_robot": json.dumps({"name": "carm", "joints": [{"type": "revolute", "limits": [0, 1]}]}).encode(),
        "json_deep": b"[" * 100_000 + b"]" * 100_000,
        "reduction_list": _field(CARM_TOML, "default_reduction", '["carm-d1"]').encode(),
        "a_1e308": CARM_TOML.replace("a = 350.0", "a = 1e308").encode(),
        "a_beyond_max_length": CARM_TOML.replace("a = 350.0", f"a = {MAX_LENGTH * 10:g}").encode(),
        "alpha_beyond_max_angle": _field(CARM_TOML, "alpha", f"{MAX_ANGLE_DEG * 10:g}", 1).encode(),
        "limits_beyond_max": _field(CARM_TOML, "limits", f"[0.0, {MAX_LIMIT * 10:g}]").encode(),
        "limits_full_range": _field(CARM_TOML, "limits", "[-1.7e308, 1.7e308]").encode(),
        "limits_three": _field(CARM_TOML, "limits", "[0.0, 1.0, 2.0]").encode(),
        "limits_reversed": _field(CARM_TOML, "limits", "[2000.0, 0.0]").encode(),
        "base_xyz_huge": (CARM_TOML + "\n[base]\nxyz = [1e300, 0, 0]\n").encode(),
        "tool_zyz_huge": (CARM_TOML + "\n[tool]\nzyz = [0, 1e308, 0]\n").encode(),
        "tool_extra_key": (CARM_TOML + "\n[tool]\nrpw = [0, 0, 0]\n").encode(),
        "tool_not_table": (CARM_TOML.replace('name = "carm"', 'name = "carm"\ntool = 3')).encode(),
        "digits": CARM_TOML.replace("a = 350.0", "a = " + "9" * 5000).encode(),
        "digits_name": CARM_TOML.replace('name = "carm"', "name = " + "7" * 5000).encode(),
        "utf16": CARM_TOML.encode("utf-16"),
        "utf16_be": CARM_TOML.encode("utf-16-be"),
        "latin1": CARM_TOML.replace("C-Arm", "C-Arm \xe9").encode("latin-1"),
        "nul_bytes": CARM_TOML.replace("a = 350.0", "a = 350.0\0").encode(),
        "empty": b"",
        "only_comment": b"# nothing here\n",
        "joints_string": b'joints = "abc"\n',
        "joints_ints": b"joints = [1, 2]\n",
        "joints_empty": b"joints = []\n",
        "joint_no_type": CARM_TOML.replace('type = "prismatic"\n', "").encode(),
        "joint_unknown_key": CARM_TOML.replace('type = "prismatic"', 'type = "prismatic"\nstiffness = 3.0').encode(),
        "top_unknown_key": ("speed = 3\n" + CARM_TOML).encode(),
        "type_bad": CARM_TOML.replace('type = "prismatic"', 'type = "spherical"').encode(),
        "type_list": CARM_TOML.replace('type = "prismatic"', 'type = ["prismatic"]').encode(),
        "negative_length_solve": CARM_TOML.replace("a = 350.0", "a = -350.0").encode(),
        "zero_d_solve": CARM_TOML.replace("d = 402.0", "d = 0.0").encode(),
        "unknown_reduction_solve": _field(CARM_TOML, "default_reduction", '"nope"').encode(),
        "huge_alpha_solve": _field(CARM_TOML, "alpha", "45.0", 1).encode(),
    }
    for key in _TEXT_FIELDS:
        for label, value in (("number", "3"), ("list", '["x"]'), ("bool", "false"), ("table", "{a = 1}")):
            must[f"{key}_{label}"] = _field(CARM_TOML, key, value).encode()
    must["joint_name_number"] = _field(CARM_TOML, "name", "3", 1).encode()
    for key, nth in _NUMERIC_FIELDS.items():  # each DH field of a joint (and its limits) given each bad value
        for label, value in _BAD_VALUES.items():
            must[f"{key}_{label}"] = _field(CARM_TOML, key, value, nth).encode()
    for label, value in (("inf", "inf"), ("str", '"0"'), ("bool", "true"), ("huge", "1e300"), ("list", "[0]")):
        must[f"base_xyz_{label}"] = (CARM_TOML + f"\n[base]\nxyz = [0, {value}, 0]\n").encode()
        must[f"tool_zyz_{label}"] = (CARM_TOML + f"\n[tool]\nzyz = [{value}, 0, 0]\n").encode()
    corpus = {k: (v, True) for k, v in must.items()}

    lines = CARM_TOML.splitlines(keepends=True)
    values = [*_BAD_VALUES.values(), "0", "-1", "1e-300", "1e12", '""', "[]", "[0, 0]", "-0.0", "360"]
    for k in range(40):  # random, seeded: truncations, byte flips, shuffled lines, random field values
        cut = int(rng.integers(1, len(CARM_TOML)))
        corpus[f"truncated_{k}"] = (CARM_TOML[:cut].encode(), False)
        blob = bytearray(CARM_TOML.encode())
        for pos in rng.integers(0, len(blob), size=5):
            blob[pos] = int(rng.integers(0, 256))
        corpus[f"flipped_{k}"] = (bytes(blob), False)
        shuffled = list(lines)
        rng.shuffle(shuffled)
        corpus[f"shuffled_{k}"] = ("".join(shuffled).encode(), False)
        mutated = list(lines)
        for i in rng.choice([i for i, ln in enumerate(lines) if "=" in ln], size=2, replace=False):
            mutated[i] = f"{lines[i].split('=')[0].strip()} = {values[int(rng.integers(len(values)))]}\n"
        corpus[f"mutated_{k}"] = ("".join(mutated).encode(), False)
    for k in range(20):
        corpus[f"random_{k}"] = (rng.bytes(int(rng.integers(1, 400))), False)
    return corpus


ROBOT_CORPUS = _robot_corpus()


@pytest.mark.parametrize("case", sorted(ROBOT_CORPUS))
def test_robot_file_corpus(case: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Loading fails with a RobotFileError naming the file, or the robot loads and a solve either works or
    refuses with a SweepikError; the CLI says so in one line with exit status 2."""
    content, must_fail = ROBOT_CORPUS[case]
    path = tmp_path / f"{case}.toml"
    path.write_bytes(content)
    try:
        robot = sweepik.load_robot(path)
    except sweepik.RobotFileError as exc:
        assert str(path) in str(exc), (case, exc)
        robot = None
    assert not (must_fail and robot is not None and not case.endswith("_solve")), case
    code, err = _cli(["robots", str(path)], capsys)
    if robot is None:
        _assert_one_error_line(code, err, str(path), case)
        code, err = _cli(["solve", str(path), "--matrix", *MATRIX_ARGS], capsys)
        _assert_one_error_line(code, err, str(path), case)
        return
    assert code == 0 and err == "", (case, err)
    try:
        sweepik.solve(robot, robot.fk(np.clip(np.zeros(robot.n_joints), robot.lower, robot.upper)))
        solved = True
    except sweepik.SweepikError:
        solved = False
    assert not (must_fail and solved), case
    code, err = _cli(["solve", str(path), "--matrix", *MATRIX_ARGS], capsys)
    if solved:
        assert code == 0 and "Traceback" not in err, (case, err)
    else:
        _assert_one_error_line(code, err, None, case)


@pytest.mark.parametrize(("key", "nth"), sorted(_NUMERIC_FIELDS.items()))
def test_robot_field_errors_name_file_and_field(key: str, nth: int, tmp_path: Path) -> None:
    path = tmp_path / "arm.toml"
    path.write_text(_field(CARM_TOML, key, "[0.0, 1e308]" if key == "limits" else "1e308", nth))
    with pytest.raises(sweepik.RobotFileError, match=f"field '{key}' must be a finite number of magnitude") as info:
        sweepik.load_robot(path)
    assert str(path) in str(info.value)


def test_huge_limits_stay_allowed(tmp_path: Path) -> None:
    """Limits up to MAX_LIMIT mean "no practical end" (a range upper - lower stays finite)."""
    path = tmp_path / "rail.toml"
    path.write_text(_field(CARM_TOML, "limits", f"[{-MAX_LIMIT:g}, {MAX_LIMIT:g}]"))
    robot = sweepik.load_robot(path)
    assert np.isfinite(robot.upper[0] - robot.lower[0])
    assert len(sweepik.solve(robot, GOOD_POSE)) > 0
    # ... but the paper's 10 mm sweep over that range is refused instead of allocating it
    with pytest.raises(sweepik.UnknownOptionError, match="strategy 'paper' would sweep d1"):
        sweepik.solve(robot, GOOD_POSE, strategy="paper")


def test_robot_path_is_a_directory(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / "arm.toml"
    d.mkdir()
    for path in (d, tmp_path):
        with pytest.raises(sweepik.RobotFileError, match="is a directory") as info:
            sweepik.load_robot(path)
        assert str(path) in str(info.value)
        _assert_one_error_line(*_cli(["robots", str(path)], capsys), str(path))


def test_oversized_robot_file_refused_before_reading(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    path = _sparse(tmp_path / "big.toml", 10 * MAX_ROBOT_FILE_BYTES)
    opened: list[Path] = []
    real_open = Path.open

    def spy_open(self: Path, *args: Any, **kwargs: Any) -> Any:
        opened.append(self)
        return real_open(self, *args, **kwargs)

    monkeypatch.setattr(Path, "open", spy_open)
    with pytest.raises(sweepik.RobotFileError, match=f"larger than the {MAX_ROBOT_FILE_BYTES} bytes") as info:
        sweepik.load_robot(path)
    assert str(path) in str(info.value) and path not in opened
    # a file just at the limit is read (and fails on its content, not its size)
    _sparse(path, MAX_ROBOT_FILE_BYTES)
    with pytest.raises(sweepik.RobotFileError, match="not valid TOML"):
        sweepik.load_robot(path)


def test_file_growing_after_stat_is_read_only_up_to_the_limit(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """The size seen by stat is not trusted: at most limit + 1 bytes are read."""
    path = tmp_path / "grows.toml"
    path.write_bytes(b"#" * (MAX_ROBOT_FILE_BYTES + 100))
    from sweepik.model import validate

    real = validate.file_status

    def stale(p: Path, error: type[sweepik.SweepikError], what: str) -> os.stat_result | None:
        st = real(p, error, what)
        return None if st is None else os.stat_result((st.st_mode, *[0] * 5, 10, *[0] * 3))

    monkeypatch.setattr(validate, "file_status", stale)
    with pytest.raises(sweepik.RobotFileError, match="larger than"):
        sweepik.load_robot(path)


@pytest.mark.parametrize("failing", ["open", "stat"])
def test_unreadable_files_name_the_file(
    failing: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    """No permission (simulated: the tests may run as root, who reads anything) -> a SweepikError naming the file,
    exit status 2 in the CLI."""
    robot_path = tmp_path / "arm.toml"
    robot_path.write_text(CARM_TOML)
    pose_path = tmp_path / "poses.json"
    pose_path.write_text(json.dumps([GOOD_POSE.tolist()]))
    real = getattr(Path, failing)

    def denied(self: Path, *args: Any, **kwargs: Any) -> Any:
        if self in (robot_path, pose_path):
            raise PermissionError(13, "Permission denied", str(self))
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Path, failing, denied)
    with pytest.raises(sweepik.RobotFileError, match="Permission denied") as info:
        sweepik.load_robot(robot_path)
    assert str(robot_path) in str(info.value)
    with pytest.raises(sweepik.PoseFileError, match="Permission denied") as pinfo:
        load_poses(pose_path)
    assert str(pose_path) in str(pinfo.value)
    _assert_one_error_line(*_cli(["robots", str(robot_path)], capsys), str(robot_path))
    _assert_one_error_line(*_cli(["solve", "carm", "--poses", str(pose_path)], capsys), str(pose_path))


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root reads files without permission")
def test_unreadable_files_for_real(tmp_path: Path) -> None:
    path = tmp_path / "arm.toml"
    path.write_text(CARM_TOML)
    path.chmod(0)
    with pytest.raises(sweepik.RobotFileError, match="Permission denied"):
        sweepik.load_robot(path)


@pytest.mark.parametrize(
    "name",
    [None, 3, 2.5, {"joints": []}, ["carm"], b"carm", "x" * 5000, "x" * 5000 + ".toml", "a\0b.toml", "nope"],
)
def test_bad_robot_names(name: object, capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(sweepik.SweepikError):
        sweepik.load_robot(name)  # type: ignore[arg-type]
    if isinstance(name, str):
        _assert_one_error_line(*_cli(["robots", name], capsys), None, name)


def test_robot_from_dict_refuses_non_tables() -> None:
    for data in ([], "carm", None, {"joints": [{"type": "revolute", "limits": [0, 1], 3: 4}]}):
        with pytest.raises(sweepik.RobotFileError):
            sweepik.robot_from_dict(data)  # type: ignore[arg-type]


# ------------------------------------------------------------------------------------------- pose files


def _npy(shape: tuple[int, ...], descr: object = "<f8", data: bytes = b"\0" * 128, version: int = 1) -> bytes:
    """An .npy file with this header (``descr`` as NumPy writes it: a string or a list of fields) and data."""
    header = f"{{'descr': {descr!r}, 'fortran_order': False, 'shape': {shape}, }}"
    header += " " * (118 - len(header)) + "\n"
    head = b"\x93NUMPY" + bytes([version, 0])
    return head + struct.pack("<H" if version == 1 else "<I", len(header)) + header.encode("latin1") + data


def _valid_npy() -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.stack([GOOD_POSE, GOOD_POSE]))
    return buf.getvalue()


_POSE_JSON = json.dumps([GOOD_POSE.tolist()])
_POSE_CSV = ",".join(repr(float(v)) for v in GOOD_POSE.ravel()) + "\n"


def _pose_corpus() -> dict[str, tuple[bytes | Callable[[Path], None], bool]]:
    """file name -> (content or writer, True when loading must fail)."""
    rng = np.random.default_rng(9)
    valid = _valid_npy()
    must: dict[str, bytes | Callable[[Path], None]] = {
        "utf16.csv": "x,y,z,a,b,c\n1,2,3,0,0,0\n".encode("utf-16"),
        "utf16.json": _POSE_JSON.encode("utf-16"),
        "binary.csv": bytes(range(256)) * 4,
        "binary.json": bytes(range(255, -1, -1)) * 4,
        "latin1.csv": "# pose \xe9\n1,2,3,0,0,0\n".encode("latin-1"),
        "deep.json": b"[" * 100_000 + b"]" * 100_000,
        "deep_object.json": b'{"a": ' * 50_000 + b"1" + b"}" * 50_000,
        "deep_pose.json": ("[" + "[" * 70 + "1" + "]" * 70 + "]").encode(),
        "digits.json": b"[[" + b"9" * 5000 + b"]]",
        "bigint.json": _POSE_JSON.replace("1.0", "1" + "0" * 400, 1).encode(),
        "bigint_xyz.json": ('[{"xyz": [1' + "0" * 400 + ', 0, 0], "zyz_deg": [0, 0, 0]}]').encode(),
        "bool.json": json.dumps([np.eye(4, dtype=bool).tolist()]).encode(),
        "strings.json": json.dumps([[[str(v) for v in row] for row in GOOD_POSE.tolist()]]).encode(),
        "xyz_strings.json": b'[{"xyz": ["1", "2", "3"], "zyz_deg": [0, 0, 0]}]',
        "xyz_bool.json": b'[{"xyz": [true, 2, 3], "zyz_deg": [0, 0, 0]}]',
        "xyz_nested.json": b'[{"xyz": [[1], 2, 3], "zyz_deg": [0, 0, 0]}]',
        "null_pose.json": b"[null]",
        "null.json": b"null",
        "poses_null.json": b'{"poses": null}',
        "empty_list.json": b"[]",
        "empty.json": b"",
        "empty.csv": b"",
        "empty.txt": b"   \n\n",
        "header_only.csv": b"x,y,z,alpha,beta,gamma\n",
        "ragged.csv": b"1,2,3,0,0,0\n1,2,3\n",
        "text.csv": b"a,b,c,d,e,f\nx,y,z,1,2,3\n",
        "typo_in_first_row.csv": b"400,-350,50O,0,0,0\n400,-350,500,0,0,0\n",
        "nul.csv": b"400,-350,500,0,0,0\0\n",
        "notpose.csv": ("," * 15 + "\n").encode(),
        "wide.csv": (",".join(["1"] * 100_000) + "\n").encode(),
        "nan.csv": b"nan,0,0,0,0,0\n",
        "digits.csv": ("9" * 5000 + ",0,0,0,0,0\n").encode(),
        "far.csv": b"1e200,0,0,0,0,0\n",
        "far.json": b'[{"xyz": [0, 0, -1e31], "zyz_deg": [0, 0, 0]}]',
        "crafted.npy": _npy((10**11, 4, 4)),
        "crafted_overflow.npy": _npy((2**62, 2**62, 4, 4)),
        "crafted_neg.npy": _npy((-1, 4, 4)),
        "crafted_truncated.npy": _npy((1000, 4, 4)),
        "crafted_zero.npy": _npy((0, 4, 4)),
        "crafted_string.npy": _npy((1, 4, 4), descr="<U8", data=b"\0" * 512),
        "crafted_bool.npy": _npy((1, 4, 4), descr="|b1"),
        "crafted_struct.npy": _npy((1, 4, 4), descr=[("a", "<f8")]),
        "crafted_version3.npy": _npy((1, 4, 4), version=3),
        "crafted_version9.npy": _npy((1, 4, 4), version=9),
        "crafted_header.npy": b"\x93NUMPY\x01\x00" + struct.pack("<H", 20) + b"__import__('os')  \n",
        "truncated.npy": valid[: len(valid) - 8],
        "header_cut.npy": valid[:30],
        "zip.npy": b"PK\x03\x04" + rng.bytes(200),
        "garbage.npy": rng.bytes(300),
        "empty.npy": b"",
        "object.npy": lambda p: np.save(p, np.zeros((2, 4, 4)).astype(object), allow_pickle=True),
        "complex.npy": lambda p: np.save(p, np.zeros((2, 4, 4), complex)),
        "shape.npy": lambda p: np.save(p, np.zeros((2, 3, 3))),
        "flat.npy": lambda p: np.save(p, np.zeros((2, 16))),
        "scalar.npy": lambda p: np.save(p, np.float64(1.0)),
        "nan.npy": lambda p: np.save(p, np.full((1, 4, 4), np.nan)),
        "zero_poses.npy": lambda p: np.save(p, np.zeros((0, 4, 4))),
        "notrigid.json": json.dumps([np.ones((4, 4)).tolist()]).encode(),
        "dict.json": json.dumps({"poses": [{"xyz": [1, 2]}]}).encode(),
        "huge.json": b"[[[1e400,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]]",
        "unknown.xyz": b"1 2 3",
        "noext": b"1 2 3",
    }
    corpus = {k: (v, True) for k, v in must.items()}
    for k in range(15):  # random, seeded: byte flips and truncations of valid files, random bytes
        for name, text in (("json", _POSE_JSON), ("csv", _POSE_CSV)):
            blob = bytearray(text.encode())
            for pos in rng.integers(0, len(blob), size=3):
                blob[pos] = int(rng.integers(0, 256))
            corpus[f"flipped_{k}.{name}"] = (bytes(blob), False)
            corpus[f"truncated_{k}.{name}"] = (text.encode()[: int(rng.integers(0, len(text)))], False)
        blob = bytearray(valid)
        for pos in rng.integers(0, len(blob), size=3):
            blob[pos] = int(rng.integers(0, 256))
        corpus[f"flipped_{k}.npy"] = (bytes(blob), False)
        corpus[f"random_{k}.csv"] = (rng.bytes(int(rng.integers(1, 300))), False)
        corpus[f"random_{k}.npy"] = (b"\x93NUMPY" + rng.bytes(int(rng.integers(1, 300))), False)
    return corpus


POSE_CORPUS = _pose_corpus()


def _write(tmp_path: Path, name: str, content: bytes | Callable[[Path], None]) -> Path:
    path = tmp_path / name
    if callable(content):
        content(path)
    else:
        path.write_bytes(content)
    return path


def test_pose_file_corpus(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """Every pose file either loads as finite rigid poses (N >= 1, only for the random cases) or raises a
    SweepikError naming the file; the CLI (solve --poses and path) exits 2 with one line naming it."""
    for name, (content, must_fail) in POSE_CORPUS.items():
        path = _write(tmp_path, name, content)
        try:
            poses = load_poses(path)
        except sweepik.SweepikError as exc:
            assert str(path) in str(exc), (name, exc)
            poses = None
        if poses is not None:
            assert not must_fail, name
            assert poses.ndim == 3 and poses.shape[0] >= 1 and poses.shape[1:] == (4, 4), name
            assert poses.dtype == np.float64 and np.all(np.isfinite(poses)), name
            continue
        _assert_one_error_line(*_cli(["solve", "carm", "--poses", str(path)], capsys), str(path), name)
        if must_fail and name.endswith((".json", ".npy")):
            _assert_one_error_line(*_cli(["path", "carm", str(path)], capsys), str(path), name)


def test_valid_pose_files_still_load(tmp_path: Path) -> None:
    """The checks refuse nothing valid: BOM, Fortran order, big-endian, integers, float32, a single (4, 4)."""
    expected = np.stack([GOOD_POSE, GOOD_POSE])
    (tmp_path / "bom.csv").write_bytes(b"\xef\xbb\xbf" + (_POSE_CSV * 2).encode())
    (tmp_path / "bom.json").write_bytes(b"\xef\xbb\xbf" + json.dumps(expected.tolist()).encode())
    (tmp_path / "header.csv").write_text("x,y,z,alpha,beta,gamma\n400,-350,500,0,0,0\n")
    np.save(tmp_path / "fortran.npy", np.asfortranarray(expected))
    np.save(tmp_path / "big_endian.npy", expected.astype(">f8"))
    np.save(tmp_path / "float32.npy", expected.astype(np.float32))
    np.save(tmp_path / "ints.npy", np.eye(4, dtype=np.int32)[None])
    np.save(tmp_path / "single.npy", GOOD_POSE)
    with (tmp_path / "v2.npy").open("wb") as fh:
        np.lib.format.write_array(fh, expected, version=(2, 0))
    for name in ("bom.csv", "bom.json", "fortran.npy", "big_endian.npy", "v2.npy"):
        np.testing.assert_allclose(load_poses(tmp_path / name), expected, rtol=0, atol=1e-12, err_msg=name)
    np.testing.assert_allclose(load_poses(tmp_path / "float32.npy"), expected, rtol=0, atol=1e-3)
    np.testing.assert_array_equal(load_poses(tmp_path / "ints.npy"), np.eye(4)[None])
    np.testing.assert_array_equal(load_poses(tmp_path / "single.npy"), GOOD_POSE[None])
    assert load_poses(tmp_path / "header.csv").shape == (1, 4, 4)


def test_first_csv_row_with_a_typo_is_not_taken_for_a_header(tmp_path: Path) -> None:
    path = tmp_path / "p.csv"
    path.write_text("400,-350,5OO,0,0,0\n400,-350,500,0,0,0\n")  # letter O: before, silently dropped
    with pytest.raises(sweepik.PoseFileError, match="data row 1 holds a non-numeric field"):
        load_poses(path)


def test_npy_header_declaring_more_poses_than_allowed(tmp_path: Path) -> None:
    path = tmp_path / "many.npy"
    path.write_bytes(_npy((MAX_NPY_POSES + 1, 4, 4)))
    with pytest.raises(sweepik.PoseFileError, match=f"a pose file holds 1 to {MAX_NPY_POSES}"):
        load_poses(path)
    path.write_bytes(_npy((10**11, 4, 4)))
    with pytest.raises(sweepik.PoseFileError, match="100000000000 poses"):
        load_poses(path)
    path.write_bytes(_npy((3, 4, 4), data=b"\0" * 100))
    with pytest.raises(sweepik.PoseFileError, match="truncated"):
        load_poses(path)


@pytest.mark.parametrize("ext", [".csv", ".txt", ".json"])
def test_oversized_text_pose_file_refused_before_reading(ext: str, tmp_path: Path) -> None:
    path = _sparse(tmp_path / f"big{ext}", MAX_POSE_TEXT_BYTES + 1)
    with pytest.raises(sweepik.PoseFileError, match=f"larger than the {MAX_POSE_TEXT_BYTES} bytes") as info:
        load_poses(path)
    assert str(path) in str(info.value)


@pytest.mark.parametrize("ext", [".csv", ".npy", ".json"])
def test_pose_path_not_a_regular_file(ext: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / f"dir{ext}"
    d.mkdir()
    with pytest.raises(sweepik.PoseFileError, match="is a directory") as info:
        load_poses(d)
    assert str(d) in str(info.value)
    _assert_one_error_line(*_cli(["solve", "carm", "--poses", str(d)], capsys), str(d))
    with pytest.raises(sweepik.PoseFileError, match="no such file"):
        load_poses(tmp_path / f"missing{ext}")
    with pytest.raises(sweepik.PoseFileError, match="NUL byte"):
        load_poses(f"a\0b{ext}")
    with pytest.raises(sweepik.PoseFileError, match="File name too long"):
        load_poses("x" * 5000 + ext)


@pytest.mark.parametrize("path", [None, 3, ["p.csv"], b"p.csv"])
def test_pose_path_of_wrong_type(path: object) -> None:
    with pytest.raises(sweepik.PoseFileError, match="must be a str or os.PathLike"):
        load_poses(path)  # type: ignore[arg-type]


# -------------------------------------------------------------------------------------- library arguments


@pytest.mark.parametrize(
    "kwargs",
    [
        {"n_samples": "64"},
        {"n_samples": 64.5},
        {"n_samples": 64.0},
        {"n_samples": np.float64(64)},
        {"n_samples": float("nan")},
        {"n_samples": float("inf")},
        {"n_samples": True},
        {"n_samples": False},
        {"n_samples": None},
        {"n_samples": [64]},
        {"n_samples": 10**9},
        {"n_samples": solving.MAX_SAMPLES + 1},
        {"n_samples": 2**200},
        {"n_samples": 7},
        {"n_samples": -64},
        {"limits": "no"},
        {"limits": "False"},
        {"limits": None},
        {"limits": 0},
        {"limits": 1},
        {"limits": np.array([True])},
        {"reduction": ["carm-d1"]},
        {"reduction": np.array(["carm-d1"])},
        {"reduction": 3},
        {"reduction": "nope"},
        {"reduction": ""},
        {"strategy": ["precise"]},
        {"strategy": np.array(["precise", "paper"])},
        {"strategy": None},
        {"strategy": "fast"},
        {"strategy": "PRECISE"},
    ],
    ids=repr,
)
def test_bad_solver_arguments(kwargs: dict[str, object]) -> None:
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve(CARM, GOOD_POSE, **kwargs)  # type: ignore[arg-type]
    for batch in (GOOD_POSE[None], np.zeros((0, 4, 4)), []):  # an empty batch checks its arguments too
        with pytest.raises(sweepik.SweepikError):
            sweepik.solve_many(CARM, batch, **kwargs)  # type: ignore[arg-type]


@pytest.mark.parametrize("chunk", [0, -3, 2.5, 3.0, "10", None, True, solving.MAX_CHUNK + 1])
def test_bad_chunk_size(chunk: object) -> None:
    for batch in (GOOD_POSE[None], []):
        with pytest.raises(sweepik.UnknownOptionError, match="chunk_size"):
            sweepik.solve_many(CARM, batch, chunk_size=chunk)  # type: ignore[arg-type]


@pytest.mark.parametrize("robot", ["carm", "no_such", None, {"joints": []}, 3, CARM.joints[0], [CARM]], ids=repr)
def test_robot_argument_must_be_a_robot(robot: object) -> None:
    with pytest.raises(sweepik.UnknownOptionError, match="sweepik.Robot"):
        sweepik.solve(robot, GOOD_POSE)  # type: ignore[arg-type]
    with pytest.raises(sweepik.UnknownOptionError, match="sweepik.Robot"):
        sweepik.solve_many(robot, [])  # type: ignore[arg-type]


def _bad_arrays(good: np.ndarray) -> dict[str, object]:
    obj = good.astype(object)
    obj.flat[0] = 1j
    none = good.astype(object)
    none.flat[-1] = None
    deep: list[Any] = [1.0]
    for _ in range(70):  # beyond NumPy's 64 dimensions
        deep = [deep]
    return {
        "complex": good.astype(complex),
        "complex_zero_imag": good + 0j,
        "complex_list": (good + 0j).tolist(),
        "complex_object": obj,
        "none_object": none,
        "strings": good.astype(str),
        "string_list": good.astype(str).tolist(),
        "bytes": good.astype("S32"),
        "bool": good.astype(bool),
        "structured": np.zeros(good.shape, dtype=[("a", "f8")]),
        "datetime": np.zeros(good.shape, dtype="M8[s]"),
        "huge_int": np.full(good.shape, 10**400, dtype=object),
        "ragged": [[1.0, 2.0], [3.0]],
        "deep": deep,
        "dict": {},
        "none": None,
        "text": "abc",
    }


@pytest.mark.parametrize("case", sorted(_bad_arrays(GOOD_POSE)))
def test_bad_pose_arrays(case: str) -> None:
    bad = _bad_arrays(GOOD_POSE)[case]
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve(CARM, bad)  # type: ignore[arg-type]
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve_many(CARM, bad if case in ("ragged", "deep", "dict", "none", "text") else [bad])  # type: ignore[list-item]


@pytest.mark.parametrize("case", sorted(_bad_arrays(Q_GOOD)))
@pytest.mark.parametrize("method", ["fk", "frames", "jacobian", "wrap", "within_limits"])
def test_bad_configuration_arrays(case: str, method: str) -> None:
    with pytest.raises(sweepik.ShapeError):
        getattr(CARM, method)(_bad_arrays(Q_GOOD)[case])


def test_complex_is_refused_with_a_clear_message() -> None:
    with pytest.raises(sweepik.ShapeError, match="real"):
        sweepik.solve(CARM, GOOD_POSE.astype(complex))
    with pytest.raises(sweepik.ShapeError, match="real"):
        CARM.fk(np.zeros(6, complex))
    sols = sweepik.solve(CARM, GOOD_POSE)
    with pytest.raises(sweepik.ShapeError, match="real"):
        sols.nearest(Q_GOOD + 0j)
    with pytest.raises(sweepik.ShapeError, match="strings"):
        CARM.jacobian(["700", "0", "0", "0", "0", "0"])


def test_accepted_numpy_scalars_and_object_arrays() -> None:
    """NumPy integers and bools are fine where an int or a bool is asked; object arrays of real numbers too."""
    sols = sweepik.solve(CARM, GOOD_POSE.astype(object), n_samples=np.int64(64), limits=np.bool_(True))
    assert len(sols) > 0 and np.min(np.abs(sols.q - Q_GOOD).max(axis=-1)) < 1e-8
    assert sweepik.solve_many(CARM, [], chunk_size=np.int32(5)) == []
    np.testing.assert_array_equal(CARM.fk(Q_GOOD.astype(np.float32)), CARM.fk(Q_GOOD.astype(np.float32).tolist()))


def test_large_n_samples_runs_in_small_chunks(monkeypatch: pytest.MonkeyPatch) -> None:
    """Memory stays bounded by construction: chunk x n_samples <= SAMPLE_BUDGET, whatever chunk_size says."""
    sizes: list[int] = []
    real = chunk.solve_chunk

    def spy(robot: sweepik.Robot, red: Any, poses: np.ndarray, *args: Any, **kwargs: Any) -> Any:
        sizes.append(poses.shape[0])
        return real(robot, red, poses, *args, **kwargs)

    monkeypatch.setattr(solving, "solve_chunk", spy)
    P = np.repeat(GOOD_POSE[None], 5, axis=0)
    n = solving.SAMPLE_BUDGET // 2
    assert n <= solving.MAX_SAMPLES
    many = sweepik.solve_many(CARM, P, n_samples=n, chunk_size=1000)
    assert sizes == [2, 2, 1] and len(many) == 5
    sizes.clear()
    sweepik.solve_many(CARM, P, chunk_size=1000)
    assert sizes == [5]


def test_paper_strategy_on_a_long_rail_is_refused(tmp_path: Path) -> None:
    path = tmp_path / "rail.toml"
    path.write_text(_field(CARM_TOML, "limits", "[0.0, 1e9]"))
    robot = sweepik.load_robot(path)
    with pytest.raises(sweepik.UnknownOptionError, match="at most 200000"):
        sweepik.solve_many(robot, GOOD_POSE[None], strategy="paper")
    assert len(sweepik.solve(robot, GOOD_POSE)) > 0  # the precise strategy has no such limit


@pytest.mark.parametrize("coordinate", [1e31, -1e100, 1e308])
def test_absurdly_far_poses_are_refused(coordinate: float, capsys: pytest.CaptureFixture[str]) -> None:
    """Beyond MAX_TRANSLATION the solver's products would overflow (warnings, not an answer): refused up front."""
    T = GOOD_POSE.copy()
    T[1, 3] = coordinate
    with pytest.raises(sweepik.InvalidPoseError, match="translation must be at most 1e\\+30"):
        sweepik.solve(CARM, T)
    with pytest.raises(sweepik.InvalidPoseError, match=r"\(pose \(1,\)\)"):
        sweepik.solve_many(CARM, np.stack([GOOD_POSE, T]))
    code, err = _cli(["solve", "carm", "--xyz", "0", repr(coordinate), "0"], capsys)
    _assert_one_error_line(code, err, None)
    T[1, 3] = 1e29  # within the bound: simply out of reach
    assert sweepik.solve(CARM, T).reason.startswith("unreachable")


@pytest.mark.parametrize("value", [1e308, -1e31])
def test_absurd_joint_values_refused(value: float, capsys: pytest.CaptureFixture[str]) -> None:
    q = np.array([value, 0.0, 0.0, 0.0, 0.0, 0.0])
    with pytest.raises(sweepik.NonFiniteError, match="at most 1e"):
        CARM.fk(q)
    with pytest.raises(sweepik.NonFiniteError):
        CARM.fk(q[[1, 0, 2, 3, 4, 5]])  # an angle too
    code, err = _cli(["fk", "carm", repr(value), "0", "0", "0", "0", "0"], capsys)
    assert code == 2 and "at most 1e+30" in err


def test_arm_outside_the_catalogue_is_no_longer_bad_input(tmp_path: Path) -> None:
    """The C-Arm with its last joint offset (no two axes meeting at either end; once refused as outside the catalogue)
    is solved by the general method, and gives the configuration back."""
    path = tmp_path / "offset.toml"
    path.write_text(_offset_last_joint(CARM_TOML.replace('default_reduction = "carm-d1"\n', "")))
    robot = sweepik.load_robot(path)
    assert sweepik.analyze(robot)["chosen"]["family"] == "general"
    sols = sweepik.solve(robot, robot.fk(Q_GOOD), limits=False)
    d = sols.q - Q_GOOD
    d[:, robot.is_revolute] = np.mod(d[:, robot.is_revolute] + np.pi, 2 * np.pi) - np.pi
    assert sols.q.size and np.abs(d).max(axis=1).min() < 1e-8


# ------------------------------------------------------------------ the small helpers


@pytest.mark.parametrize(
    ("xyz", "zyz"),
    [
        ([0.1, float("nan"), 0.3], [0.0, 0.0, 0.0]),
        ([0.1, 0.2, 0.3], [0.0, float("inf"), 0.0]),
        ([0.1, 0.2], [0.0, 0.0, 0.0]),
        ([0.1, 0.2, 0.3], [0.0, 0.0, 0.0, 0.0]),
        ([[0.1, 0.2, 0.3]] * 2, [[0.0, 0.0, 0.0]] * 3),
        ("0.1 0.2 0.3", [0.0, 0.0, 0.0]),
    ],
)
def test_pose_from_xyz_zyz_refuses_bad_values(xyz: object, zyz: object) -> None:
    with pytest.raises(sweepik.SweepikError):
        sweepik.pose_from_xyz_zyz(xyz, zyz)


def test_zyz_from_matrix_refuses_what_is_not_a_rotation() -> None:
    for bad in (np.diag([1.0, 1.0, -1.0]), 2.0 * np.eye(3), np.ones((3, 3)), np.eye(3)[:2], np.full((3, 3), np.nan)):
        with pytest.raises(sweepik.SweepikError):
            sweepik.zyz_from_matrix(bad)
    R = sweepik.matrix_from_zyz([0.1, 0.2, 0.3])
    np.testing.assert_allclose(sweepik.zyz_from_matrix(R), [0.1, 0.2, 0.3], atol=1e-12)
    np.testing.assert_allclose(sweepik.zyz_from_matrix(np.stack([R, R])), [[0.1, 0.2, 0.3]] * 2, atol=1e-12)


def test_pose_errors_refuse_wrong_shapes() -> None:
    T = np.eye(4)
    for a, b in ((np.eye(3), T), (T, np.zeros((4, 3))), (np.stack([T] * 2), np.stack([T] * 3)), ("T", T)):
        with pytest.raises(sweepik.SweepikError):
            sweepik.pose_error_paper(a, b)
        with pytest.raises(sweepik.SweepikError):
            sweepik.pose_error_geodesic(a, b)
    assert sweepik.pose_error_paper(np.stack([T] * 2), T).shape == (2,)  # broadcasting still works


def test_wrap_angle_refuses_strings_and_family_sample_a_negative_count() -> None:
    with pytest.raises(sweepik.SweepikError):
        sweepik.wrap_angle("3.5")
    assert float(sweepik.wrap_angle(3 * np.pi)) == pytest.approx(np.pi)
    robot = sweepik.load_robot("puma560")
    q = np.array([0.2, -0.3, 0.4, 0.5, 0.0, 0.1])
    fam = sweepik.solve(robot, robot.fk(q), limits=False).families[0]
    for bad in (-3, 0, 2.5, "5", True):
        with pytest.raises(sweepik.SweepikError):
            fam.sample(bad)  # type: ignore[arg-type]
    assert fam.sample(3).shape == (3, 6)


def test_solve_many_of_an_empty_array_of_positions_is_refused() -> None:
    with pytest.raises(sweepik.ShapeError, match=r"\(0, 3\)"):
        sweepik.solve_many(CARM, np.zeros((0, 3)))
    with pytest.raises(sweepik.ShapeError):
        list(sweepik.iter_solve(CARM, np.zeros((0, 4))))
    assert len(sweepik.solve_many(CARM, np.zeros((0, 4, 4)))) == 0 and len(sweepik.solve_many(CARM, [])) == 0
