"""Loading arms by the names other catalogues give them (``sweepik.io.catalogues``) and from MJCF files
(``sweepik.io.mjcf``): forward kinematics equal to the source's own reader (yourdfpy for URDF, MuJoCo's
``mj_kinematics`` for MJCF) to 1e-12, and every refusal a SweepikError that says what to do."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik.io.catalogues import ERD_ARMS, _erd_root

ERD = _erd_root()
needs_erd = pytest.mark.skipif(ERD is None, reason="example-robot-data is not installed")


def _yourdfpy_fk(path: Path, robot: sweepik.Robot, q: np.ndarray, base: str | None, tip: str) -> np.ndarray:
    yourdfpy = pytest.importorskip("yourdfpy")
    urdf = yourdfpy.URDF.load(str(path), load_meshes=False, build_scene_graph=True, load_collision_meshes=False)
    names = urdf.actuated_joint_names
    cfg = np.zeros(len(names))
    for name, v in zip(robot.joint_names, q, strict=True):
        cfg[names.index(name)] = v
    urdf.update_cfg(cfg)
    return urdf.get_transform(tip, base or urdf.base_link)


def _tip_of(robot: sweepik.Robot) -> tuple[str, str]:
    """(base, tip) link names from the description of a robot read from URDF ("chain base -> tip")."""
    base, tip = robot.description.rsplit("chain ", 1)[1].split(" -> ")
    return base, tip


@needs_erd
@pytest.mark.parametrize("name", ["ur5", "ur10_limited", "panda", "kinova", "z1", "xarm7"])
def test_example_robot_data_names_match_yourdfpy(name: str) -> None:
    robot = sweepik.load_robot(f"example-robot-data:{name}")
    base, tip = _tip_of(robot)
    rng = np.random.default_rng(1)
    for q in robot.lower + rng.random((5, robot.n_joints)) * (robot.upper - robot.lower):
        ref = _yourdfpy_fk(ERD / ERD_ARMS[name][0], robot, q, base, tip)
        np.testing.assert_allclose(robot.fk(q), ref, atol=1e-12)


@needs_erd
def test_a_bare_catalogue_name_and_any_case() -> None:
    assert sweepik.load_robot("panda").n_joints == 7  # no bundled arm is called panda: example-robot-data's
    assert sweepik.load_robot("UR5").name == "ur5" == sweepik.load_robot("Ur5").name  # the bundled one
    assert "DH" in sweepik.load_robot("UR5").description or sweepik.load_robot("UR5").dh_convention != "none"


def test_a_typo_gets_the_closest_names() -> None:
    with pytest.raises(sweepik.UnknownRobotError, match="franka_panda"):
        sweepik.load_robot("franka_pnda")
    with pytest.raises(sweepik.UnknownRobotError, match="Bundled robots"):
        sweepik.load_robot("no_such_arm_at_all")


@needs_erd
def test_robot_descriptions_name_from_its_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """robot_descriptions' ``panda_description`` lives in its cached clone of example-robot-data: sweepik reads the
    file where robot_descriptions would (a cache folder built here from the installed wheel's files), and without
    the cache says that a download is needed, downloading nothing."""
    pytest.importorskip("robot_descriptions")
    monkeypatch.setenv("ROBOT_DESCRIPTIONS_CACHE", str(tmp_path))
    with pytest.raises(sweepik.UnknownRobotError, match="download"):
        sweepik.load_robot("panda_description")
    target = tmp_path / "example-robot-data" / "robots" / "panda_description" / "urdf"
    target.mkdir(parents=True)
    shutil.copy(ERD / "panda_description" / "urdf" / "panda.urdf", target / "panda.urdf")
    robot = sweepik.load_robot("robot_descriptions:panda_description", tip_link="panda_hand")
    same = sweepik.load_robot("panda_description", tip_link="panda_hand")
    q = np.array([0.1, -0.4, 0.2, -2.0, 0.3, 1.5, -0.6])
    np.testing.assert_array_equal(robot.fk(q), same.fk(q))
    np.testing.assert_allclose(robot.fk(q), _yourdfpy_fk(target / "panda.urdf", robot, q, None, "panda_hand"),
                               atol=1e-12)  # fmt: skip
    with pytest.raises(sweepik.UnknownRobotError):
        sweepik.load_robot("robot_descriptions:not_a_description")


# ------------------------------------------------------------------ MJCF

MJCF = """<mujoco model="toy">
  <compiler angle="degree" meshdir="assets"/>
  <default>
    <joint axis="0 1 0" range="-170 170"/>
    <default class="wrist"><joint axis="0 0 1"/></default>
  </default>
  <asset><mesh name="base" file="base.stl"/></asset>
  <worldbody>
    <body name="base" pos="0 0 0.1" euler="0 0 30">
      <geom type="mesh" mesh="base"/>
      <body name="l1" pos="0 0 0.2">
        <joint name="j1" axis="0 0 1"/>
        <geom type="capsule" size="0.02" fromto="0 0 0 0 0 0.2"/>
        <body name="l2" pos="0.1 0 0.2" quat="0.7071068 0.7071068 0 0">
          <joint name="j2" pos="0 0 0.05" axis="1 0 0"/>
          <body name="l3" pos="0.3 0 0">
            <joint name="j3" type="slide" axis="1 0 0" range="0 0.2"/>
            <body name="l4" pos="0.2 0.05 0" axisangle="1 0 0 90">
              <joint name="j4" class="wrist"/>
              <body name="l5" pos="0 0 0.1" xyaxes="0 1 0 -1 0 0">
                <joint name="j5" pos="0.01 0 0"/>
                <body name="l6" pos="0 0 0.1">
                  <joint name="j6" class="wrist" limited="false"/>
                  <site name="tool" pos="0 0 0.05" euler="0 90 0"/>
                  <body name="finger" pos="0 0.02 0.06"><joint name="f" type="ball" range="0 45"/></body>
                </body>
              </body>
            </body>
          </body>
        </body>
      </body>
    </body>
  </worldbody>
</mujoco>
"""


def _mj_fk(path: Path, q: np.ndarray, tip: str, site: bool) -> np.ndarray:
    mujoco = pytest.importorskip("mujoco")
    from sweepik.io.mjcf import _compiled

    model = _compiled(str(path))
    data = mujoco.MjData(model)
    data.qpos[: len(q)] = q
    mujoco.mj_kinematics(model, data)
    T = np.eye(4)
    if site:
        i = model.site(tip).id
        T[:3, :3], T[:3, 3] = data.site_xmat[i].reshape(3, 3), data.site_xpos[i]
    else:
        i = model.body(tip).id
        T[:3, :3], T[:3, 3] = data.xmat[i].reshape(3, 3), data.xpos[i]
    return T


@pytest.mark.parametrize(("tip", "site", "base"), [("tool", True, None), ("l6", False, None), ("l6", False, "l1")])
def test_mjcf_chain_matches_mujoco(tmp_path: Path, tip: str, site: bool, base: str | None) -> None:
    """Degrees, default classes, euler / quat / axis-angle / xyaxes bodies, joint anchors off the body origin, a
    slide, an unlimited hinge, a mesh whose file is missing: FK equal to MuJoCo's to 1e-12, at the site or a body,
    from the world or from a body."""
    pytest.importorskip("mujoco")
    path = tmp_path / "toy.xml"
    path.write_text(MJCF)
    robot = sweepik.load_robot(path, base_link=base, tip_link=tip)
    names = ["j1", "j2", "j3", "j4", "j5", "j6"]
    assert robot.joint_names == (names if base is None else names[1:])
    assert robot.joints[2 if base is None else 1].type == "prismatic"
    np.testing.assert_allclose(robot.limits[0], np.radians([-170, 170]))
    rng = np.random.default_rng(4)
    for q in robot.lower + rng.random((20, robot.n_joints)) * (robot.upper - robot.lower):
        full = q if base is None else np.concatenate([[0.0], q])
        T = _mj_fk(path, full, tip, site)
        if base is not None:
            T = np.linalg.inv(_mj_fk(path, full, "l1", False)) @ T
        np.testing.assert_allclose(robot.fk(q), T, atol=1e-12)
    if base is None:  # and it solves: six joints with a slide
        q = np.array([0.3, -0.5, 0.1, 0.7, 0.4, -0.2])
        sols = sweepik.solve(robot, robot.fk(q), limits=False)
        assert np.min(np.max(np.abs(sols.q - q), axis=1)) <= 1e-8


def test_mjcf_refusals(tmp_path: Path) -> None:
    pytest.importorskip("mujoco")
    path = tmp_path / "toy.xml"
    path.write_text(MJCF)
    with pytest.raises(sweepik.MjcfError, match="ball"):
        sweepik.load_robot(path, tip_link="finger")
    with pytest.raises(sweepik.MjcfError, match="not one chain|not in the file"):
        sweepik.load_robot(path, tip_link="nowhere")
    with pytest.raises(sweepik.MjcfError, match="different branches|ball"):
        sweepik.load_robot(path)
    slide = tmp_path / "slide.xml"
    slide.write_text(MJCF.replace('range="0 0.2"', 'limited="false"'))
    with pytest.raises(sweepik.MjcfError, match="range"):
        sweepik.load_robot(slide, tip_link="tool")
    broken = tmp_path / "broken.xml"
    broken.write_text("<mujoco><worldbody><body></mujoco>")
    with pytest.raises(sweepik.MjcfError, match="broken.xml"):
        sweepik.load_robot(broken)
    with pytest.raises(sweepik.SweepikError):
        sweepik.load_robot(tmp_path / "missing.xml")


def test_mjcf_refusals_say_one_thing_and_write_nothing(
    tmp_path: Path, capfd: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    """A NaN in the file: MuJoCo's own warning ("XML contains a 'NaN'") went to the terminal and into
    ``MUJOCO_LOG.TXT`` in the working directory before sweepik's error; now only the error, nothing written. A model
    name that is not UTF-8: an MjcfError naming the file (a UnicodeDecodeError before)."""
    pytest.importorskip("mujoco")
    monkeypatch.chdir(tmp_path)
    nan = tmp_path / "nan.xml"
    nan.write_text(MJCF.replace('<body name="l3" pos="0.3 0 0">', '<body name="l3" pos="nan 0 0">'))
    with pytest.raises(sweepik.MjcfError, match="NaN"):
        sweepik.load_robot(nan, tip_link="tool")
    out, err = capfd.readouterr()
    assert out == "" and err == ""
    assert not (tmp_path / "MUJOCO_LOG.TXT").exists()
    latin = tmp_path / "latin.xml"
    latin.write_bytes(MJCF.encode().replace(b'model="toy"', b'model="\xff"'))
    with pytest.raises(sweepik.MjcfError, match="latin.xml"):
        sweepik.load_robot(latin, tip_link="tool")
