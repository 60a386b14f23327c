"""``sweepik analyze``, the structure/decomposition lines of ``sweepik robots``, and ``--free-joint``."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik.cli.app import main


def run(capsys: pytest.CaptureFixture[str], *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_analyze_api_matches_plans():
    info = sweepik.analyze("carm")
    assert info["structure"] == "PRRRRR: 2∩3, 3∥4, 4∩5, 5∩6"
    assert info["chosen"]["free_joint"] == 0 and info["chosen"]["free_joint_number"] == 1
    assert not info["chosen"]["closed_form"]
    assert len(info["plans"]) == len(sweepik.reductions.decompose.plans(sweepik.load_robot("carm")))
    # a plan with a blind spot is offered but never chosen by default
    assert any(p["blind_spot"] for p in info["plans"]) and not info["chosen"]["blind_spot"]
    assert sweepik.analyze(sweepik.load_robot("puma560"))["chosen"]["closed_form"]
    with pytest.raises(sweepik.SweepikError):
        sweepik.analyze(3)  # type: ignore[arg-type]


def test_analyze_cli_text_and_json(capsys):
    code, out, _ = run(capsys, "analyze", "stanford")
    assert code == 0 and "RRPRRR: 1∩2" in out and "closed form, 8 branches" in out
    code, out, _ = run(capsys, "analyze", "xarm6", "--json")
    info = json.loads(out)
    assert code == 0 and info["chosen"]["chain"] == "reversed" and info["reason"] is None


def test_analyze_cli_outside_the_catalogue_names_the_general_method(capsys, tmp_path: Path):
    text = (Path(sweepik.__file__).parent / "io" / "robots" / "puma560.toml").read_text()
    # joint 5's axis 30 mm off joint 4's and 6's: no spherical wrist, no two axes meeting at either end
    text = text.replace("alpha = 90.0\nlimits = [-100.0, 100.0]", "a = 0.03\nalpha = 90.0\nlimits = [-100.0, 100.0]")
    text = text.replace(
        "alpha = -90.0\nlimits = [-266.0, 266.0]", "a = 0.02\nalpha = -90.0\nd = 0.05\nlimits = [-266.0, 266.0]"
    )
    text = text.replace('[[joints]]\nname = "q2"', '[[joints]]\nname = "q2"\nd = 0.1\na = 0.05', 1)
    path = tmp_path / "odd.toml"
    path.write_text(text)
    code, out, _ = run(capsys, "analyze", str(path))
    assert code == 0 and "chosen: general method (elimination)" in out and "no structured decomposition" in out
    code, out, err = run(capsys, "solve", str(path), "--xyz", "0.3", "0.2", "0.4", "--json")
    assert code == 0 and err == ""
    code, out, err = run(capsys, "solve", str(path), "--xyz", "0.3", "0.2", "0.4", "--free-joint", "2")
    assert code == 2 and out == "" and "no decomposition sweeps" in err and len(err.strip().splitlines()) == 1


def test_robots_lists_structure_and_decomposition(capsys):
    code, out, _ = run(capsys, "robots", "ur5", "carm_swapped")
    assert code == 0
    assert "structure RRRRRR: 1∩2, 2∥3, 2∥4, 3∥4, 4∩5, 5∩6" in out
    assert "decomposition: closed form, 8 branches" in out  # carm_swapped: the paper's rejected closed form
    code, out, _ = run(capsys, "robots", "ur5", "fanuc_crx10ia", "--json")
    info = json.loads(out)
    assert info[0]["decomposition"]["closed_form"] and info[0]["decomposition"]["free_joint"] is None
    assert info[1]["decomposition"]["free_joint"] == 0  # an index, as solve(free_joint=) takes it


def test_free_joint_option(capsys):
    robot = sweepik.load_robot("ur5")
    T = robot.fk(np.array([0.3, -1.0, 1.2, -0.4, 0.9, 0.2]))
    matrix = [repr(float(v)) for v in T.reshape(-1)]
    outs = []
    for joint in ("2", "4", "wrist_2"):
        code, out, _ = run(capsys, "solve", "ur5", "--matrix", *matrix, "--free-joint", joint, "--json", "--rad")
        assert code == 0
        q = np.array(json.loads(out)["poses"][0]["q"])
        outs.append(q[np.lexsort(np.round(q, 6).T[::-1])])
    for o in outs[1:]:
        np.testing.assert_allclose(o, outs[0], atol=1e-6)
    for bad in ("0", "7", "²"):
        code, _, err = run(capsys, "solve", "ur5", "--matrix", *matrix, "--free-joint", bad)
        assert code == 2 and err.startswith("sweepik") and len(err.strip().splitlines()) == 1, (bad, err)
    code, _, err = run(capsys, "solve", "ur5", "--matrix", *matrix, "--free-joint", "7")
    assert "from 1 to 6" in err
    code, out, _ = run(capsys, "solve", "ur5", "--matrix", *matrix, "--free-joint", "2", "--reduction", "auto")
    assert code == 0


@pytest.mark.parametrize("n", [1, 3, 5])
def test_analyze_an_arm_of_fewer_than_six_joints_says_why_nothing_solves_it(capsys, tmp_path: Path, n: int):
    """An arm of fewer than six joints (a robot file with the last joints cut): ``analyze`` gives its structure and
    the reason no decomposition applies; it raised an IndexError (the UR family's continuum check read axes 5 and 6)."""
    import dataclasses

    ur5 = sweepik.load_robot("ur5")
    arm = dataclasses.replace(ur5, joints=ur5.joints[:n])
    info = sweepik.analyze(arm)
    assert info["chosen"] is None and f"has {n} joints" in info["reason"]
    path = tmp_path / "short.toml"
    path.write_text(sweepik.robot_to_toml(arm))
    code, out, err = run(capsys, "analyze", str(path))
    assert code == 0 and f"has {n} joints" in out and err == ""
