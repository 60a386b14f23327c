"""Vendor URDFs (example-robot-data) solved end to end: the URDF arm gives the same solutions as the bundled DH
version of the same arm, and recovers every generating configuration.

The mapping between a vendor URDF and the bundled DH file (found in tests/test_vendor_dh.py): UR's ``base_link``
-> ``tool0`` chain is UR's DH chain turned by 180 degrees about z (same joint values, no tool transform); the
Panda's ``panda_link0`` -> ``panda_link8`` chain is Franka's DH chain with the flange as tool (identity mapping).
"""

from __future__ import annotations

import sysconfig
from pathlib import Path

import numpy as np
import pytest
from oracles import in_limit_configurations, recovers, same_solution_set

import sweepik

ROBOTS = Path(sysconfig.get_paths()["purelib"]) / "cmeel.prefix" / "share" / "example-robot-data" / "robots"
RZ_PI = np.diag([-1.0, -1.0, 1.0, 1.0])
N_POSES = 1000
CERT = 1e-9  # metres: every solution's FK error bound (the solver certifies to 2e-13 x the length scale)


def _urdf(rel: str) -> Path:
    path = ROBOTS / rel
    if not path.is_file():
        pytest.skip(f"example-robot-data is not installed (no {path})")
    return path


def _certified(robot: sweepik.Robot, batch: sweepik.SolutionBatch, poses: np.ndarray) -> None:
    if len(batch.q):
        err = np.abs(robot.fk(batch.q) - poses[batch.pose_index]).max()
        assert err < CERT, err
        assert np.all(batch.within_limits)


@pytest.mark.parametrize("arm", ["ur3", "ur5", "ur10"])
def test_ur_urdf_solves_like_the_bundled_dh_arm(arm: str) -> None:
    urdf = sweepik.load_robot(_urdf(f"ur_description/urdf/{arm}_robot.urdf"), base_link="base_link", tip_link="tool0")
    dh = sweepik.load_robot(arm)
    assert urdf.n_joints == 6 and urdf.length_unit == "m"
    q = in_limit_configurations(urdf, N_POSES, np.random.default_rng(20))
    poses = urdf.fk(q)
    np.testing.assert_allclose(poses, RZ_PI @ dh.fk(q), atol=1e-10)  # the vendor rounds pi/2 to 11 digits
    batch = sweepik.solve_many(urdf, poses)
    _certified(urdf, batch, poses)
    missed = [i for i in range(N_POSES) if not recovers(urdf, batch[i], q[i])]
    assert not missed, missed[:10]
    # the same sets as the DH arm (limits off: the URDF's elbow turns +-180 degrees, the DH file's +-360)
    ours = sweepik.solve_many(urdf, poses[:200], limits=False)
    theirs = sweepik.solve_many(dh, RZ_PI.T @ poses[:200], limits=False)
    for i, (a, b) in enumerate(zip(ours, theirs, strict=True)):
        # the URDF's 1e-11 differences from the DH numbers move a solution by about that much
        assert same_solution_set(a.q, b.q, urdf.is_revolute, urdf.length_scale, tol=1e-6), i


@pytest.mark.parametrize("value", [0.0, 0.9])
def test_panda_urdf_with_a_locked_joint_solves_like_the_bundled_panda(value: float) -> None:
    urdf = sweepik.load_robot(_urdf("panda_description/urdf/panda.urdf"), tip_link="panda_link8")
    dh = sweepik.load_robot("franka_panda")
    assert urdf.n_joints == 7
    name = urdf.joint_names[6]
    q = in_limit_configurations(urdf, N_POSES, np.random.default_rng(21))
    q[:, 6] = value
    poses = urdf.fk(q)
    np.testing.assert_allclose(poses, dh.fk(q), atol=1e-12)
    batch = sweepik.solve_many(urdf, poses, locked={name: value})
    assert batch.q.shape[1] == 7
    _certified(urdf, batch, poses)
    missed = [i for i in range(N_POSES) if not recovers(urdf, batch[i], q[i])]
    assert not missed, missed[:10]
    theirs = sweepik.solve_many(dh, poses[:200], locked={"joint7": value})
    for i in range(200):
        assert same_solution_set(batch[i].q, theirs[i].q, urdf.is_revolute, urdf.length_scale), i


def test_urdf_arm_through_the_cli(capsys: pytest.CaptureFixture[str], tmp_path: Path) -> None:
    from sweepik.cli.app import main

    path = str(_urdf("ur_description/urdf/ur5_robot.urdf"))
    assert main(["analyze", path, "--base-link", "base_link", "--tip-link", "tool0"]) == 0
    assert "closed form" in capsys.readouterr().out
    out = tmp_path / "ur5.toml"
    assert main(["convert", path, "--base-link", "base_link", "--tip-link", "tool0", "-o", str(out)]) == 0
    capsys.readouterr()
    back = sweepik.load_robot(out)
    urdf = sweepik.load_robot(path, base_link="base_link", tip_link="tool0")
    q = in_limit_configurations(urdf, 50, np.random.default_rng(3))
    assert np.abs(back.fk(q) - urdf.fk(q)).max() < 1e-12
    assert main(["solve", path, "--tip-link", "nosuchlink", "--xyz", "0.3", "0.2", "0.4"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nosuchlink" in err
    assert main(["fk", "ur5", "0", "0", "0", "0", "0", "0", "--tip-link", "tool0"]) == 2
    assert "URDF" in capsys.readouterr().err


@pytest.mark.parametrize(
    "text",
    [
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>'
        "<robot name='x'>&b;</robot>",
        '<?xml version="1.0"?><!DOCTYPE r [<!ENTITY x SYSTEM "file:///etc/passwd">]><robot name="x">&x;</robot>',
        '<robot name="x"><link name="a"/><joint name="j" type="revolute"><parent link="zz"/><child link="a"/>'
        '<limit lower="-1" upper="1"/></joint></robot>',
        "<robot name='x'><link name='a'",
    ],
)
def test_bad_urdf_through_the_cli(text: str, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from sweepik.cli.app import main

    path = tmp_path / "bad.urdf"
    path.write_text(text)
    for argv in (["analyze", str(path)], ["solve", str(path), "--xyz", "0", "0", "0"], ["fk", str(path), "0"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.count("\n") == 1 and str(path) in err and "Traceback" not in err, err


def test_bench_arms_takes_a_urdf_chain(capsys: pytest.CaptureFixture[str]) -> None:
    from sweepik.cli.app import main

    path = str(_urdf("ur_description/urdf/ur5_robot.urdf"))
    argv = ["bench", "--arms", path, "--base-link", "base_link", "--tip-link", "tool0", "--single", "3"]
    assert main([*argv, "--batch", "8", "--memory", "0", "--repeats", "1", "--json"]) == 0
    import json

    row = json.loads(capsys.readouterr().out)["arms"]["ur5"]
    assert row["plan"] == "closed form" and row["sweepik"]["batched_us"] > 0
