"""The browser viewer (``sweepik.viewer``): what it draws (``scene``, plain arrays), the running app (viser), and a
real headless-Chromium screenshot that must show the arm (skipped where viser or Chromium is absent).

``SWEEPIK_SCREENSHOTS=DIR`` keeps the screenshots in DIR (``docs/images`` holds the ones the README shows)."""

from __future__ import annotations

import os
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

import sweepik
from sweepik.viewer import scene

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.parametrize("name", ["ur5", "carm", "puma560_std", "kinova_gen3"])
def test_skeleton_links_join_the_frames_and_axes_stay_put_when_their_joint_turns(name: str) -> None:
    """The links run through every frame origin from base to tool (metres); a revolute joint's axis segment does
    not move when that joint turns (it is the joint's own axis), whatever the convention (modified, standard DH,
    origin + axis)."""
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(0)
    q = robot.lower + rng.random(robot.n_joints) * (robot.upper - robot.lower)
    sk = scene.skeleton(robot, q)
    s = scene.metres_per_unit(robot)
    np.testing.assert_allclose(sk.links[0, 0], robot.frames(q)[0, :3, 3] * s, atol=1e-12)
    np.testing.assert_allclose(sk.links[-1, 1], robot.fk(q)[:3, 3] * s, atol=1e-12)
    np.testing.assert_allclose(sk.links[1:, 0], sk.links[:-1, 1], atol=1e-12)  # one polyline
    for k in np.nonzero(robot.is_revolute)[0]:
        moved = q.copy()
        moved[k] += 0.7
        np.testing.assert_allclose(scene.skeleton(robot, moved).axes[k], sk.axes[k], atol=1e-9)
    T = robot.fk(q)
    np.testing.assert_allclose(scene.pose_from_metres(robot, scene.pose_in_metres(robot, T)), T, atol=1e-9)


def _viewer(robot: sweepik.Robot, **kw: object) -> object:
    pytest.importorskip("viser")
    from sweepik.viewer.app import Viewer

    return Viewer(robot, port=0, **kw)  # type: ignore[arg-type]


def test_viewer_solves_the_target_and_follows_it() -> None:
    robot = sweepik.load_robot("ur5")
    v = _viewer(robot)
    try:
        q = np.array([0.3, -1.0, 1.2, -0.4, 0.9, 0.2])
        sols = v.set_configuration(q)  # type: ignore[attr-defined]
        assert len(sols) == 8 and v.solutions is sols  # type: ignore[attr-defined]
        assert "8 solutions" in v.status.content  # type: ignore[attr-defined]
        assert len(v._handles) == 8 * 2  # type: ignore[attr-defined]  # the body and tool of each
        np.testing.assert_allclose(scene.pose_from_metres(robot, np.eye(4)), np.eye(4))
        v.ghosts.value = False  # type: ignore[attr-defined]
        v._draw()  # type: ignore[attr-defined]
        assert len(v._handles) == 2  # type: ignore[attr-defined]  # the chosen one only
    finally:
        v.close()  # type: ignore[attr-defined]


def test_viewer_gives_a_family_its_slider_and_refuses_bad_input() -> None:
    carm = sweepik.load_robot("carm")
    v = _viewer(carm)
    try:
        sols = v.set_configuration([800.0, np.pi / 2, 0.3, 0.2, 0.0, 0.1])  # type: ignore[attr-defined]
        assert sols.families and len(v._family_sliders) == len(sols.families)  # type: ignore[attr-defined]
        with pytest.raises(sweepik.SweepikError):
            v.show(np.zeros((3, 3)))  # type: ignore[attr-defined]
    finally:
        v.close()  # type: ignore[attr-defined]
    with pytest.raises(sweepik.SweepikError):
        _viewer(carm, poses=np.ones((2, 4, 4)))


def _primitives_urdf() -> str:
    """A 6R arm whose first links carry primitive visuals (a box, a cylinder: no mesh files)."""
    joints = [("0 0 0.1", "0 0 1"), ("0 0 0.2", "0 1 0"), ("0.3 0 0", "0 1 0"), ("0.25 0 0", "1 0 0"),
              ("0 0 0", "0 1 0"), ("0.05 0 0", "1 0 0")]  # fmt: skip
    links = ['<link name="base"><visual><geometry><box size="0.1 0.1 0.1"/></geometry></visual></link>',
             '<link name="l1"><visual><origin xyz="0 0 0.1"/><geometry><cylinder radius="0.03" length="0.2"/>'
             "</geometry></visual></link>",
             '<link name="l2"><visual><origin xyz="0.15 0 0"/><geometry><box size="0.3 0.04 0.04"/></geometry>'
             "</visual></link>",
             *(f'<link name="l{k}"/>' for k in range(3, 7))]  # fmt: skip
    body = [
        f'<joint name="j{k + 1}" type="revolute"><parent link="{"base" if k == 0 else f"l{k}"}"/>'
        f'<child link="l{k + 1}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/>'
        '<limit lower="-3" upper="3" effort="1" velocity="1"/></joint>'
        for k, (xyz, axis) in enumerate(joints)
    ]
    return '<robot name="prim">' + "".join(links + body) + "</robot>"


def test_a_urdf_with_visual_geometry_draws_the_chosen_solution_with_it(tmp_path: Path) -> None:
    """The URDF's own visuals (here primitives, no mesh files) follow the chosen solution, joint by joint name; a
    file without visuals leaves the skeleton alone and the panel says why."""
    pytest.importorskip("yourdfpy")
    path = tmp_path / "prim.urdf"
    path.write_text(_primitives_urdf())
    robot = sweepik.load_robot(path)
    v = _viewer(robot, urdf=path)
    try:
        assert v.meshes is not None  # type: ignore[attr-defined]
        sols = v.set_configuration([0.3, -0.4, 0.5, 0.2, 0.6, 0.1])  # type: ignore[attr-defined]
        np.testing.assert_array_equal(v._mesh_cfg, sols.q[0])  # type: ignore[attr-defined]  # (joints j1..j6 in order)
    finally:
        v.close()  # type: ignore[attr-defined]
    bare = tmp_path / "bare.urdf"
    bare.write_text(sweepik.urdf_text(sweepik.load_robot("ur5")))
    v = _viewer(sweepik.load_robot(bare), urdf=bare)
    try:
        assert v.meshes is None and "skeleton only" in v.mesh_note  # type: ignore[attr-defined]
    finally:
        v.close()  # type: ignore[attr-defined]


def _screenshot(url: str, out: Path) -> None:
    """A headless-Chromium screenshot of ``url`` into ``out``; tried again once if Chromium hangs (seen under load)."""
    try:
        _chromium(url, out, 60)
    except subprocess.TimeoutExpired:
        _chromium(url, out, 120)


def _chromium(url: str, out: Path, timeout: float) -> None:
    profile = out.parent / f"chromium-profile-{out.stem}"
    cmd = [
        str(CHROMIUM), "--headless", "--no-sandbox", "--disable-gpu", "--use-angle=swiftshader",
        "--enable-unsafe-swiftshader", "--disable-background-networking", "--disable-component-update",
        "--disable-sync", "--no-first-run", "--disable-quic", f"--user-data-dir={profile}", "--window-size=1200,800",
        "--hide-scrollbars", "--virtual-time-budget=8000", f"--screenshot={out}", url,
    ]  # fmt: skip
    subprocess.run(cmd, capture_output=True, timeout=timeout, check=True)


def _changed(a: Path, b: Path) -> int:
    """Pixels whose colour differs by more than 40 (of 255) in some channel between two screenshots."""
    import matplotlib.image

    x, y = (np.asarray(matplotlib.image.imread(str(p))[..., :3], dtype=np.float64) for p in (a, b))
    return int(np.sum(np.any(np.abs(x - y) > 40 / 255, axis=-1)))


@pytest.mark.skipif(CHROMIUM is None, reason="no Chromium to take a screenshot")
@pytest.mark.parametrize(
    ("name", "q", "image"),
    [
        ("ur5", [0.3, -1.0, 1.2, -0.4, 0.9, 0.2], "viewer-ur5.png"),
        ("carm", [800.0, np.pi / 2, 0.3, 0.2, 0.0, 0.1], "viewer-carm-family.png"),
    ],
)
def test_the_page_renders_the_arm_in_a_real_browser(name: str, q: list[float], image: str, tmp_path: Path) -> None:
    """Headless Chromium loads the page three times: with every solution drawn, with the chosen one only, and with
    no arm; the arms change thousands of pixels against the empty scene, the chosen UR5 alone too, and the ghosts
    (the UR5's 7 other solutions, the C-Arm's family members) thousands more."""
    robot = sweepik.load_robot(name)
    v = _viewer(robot)
    try:
        sols = v.set_configuration(q)  # type: ignore[attr-defined]
        assert (len(sols) == 8) if name == "ur5" else bool(sols.families)
        shots = {k: tmp_path / f"{k}.png" for k in ("all", "chosen", "none")}
        _screenshot(v.url, shots["all"])  # type: ignore[attr-defined]
        v.ghosts.value = False  # type: ignore[attr-defined]
        if name == "carm":
            v._family_sliders.clear()  # type: ignore[attr-defined]  # (the family member drawn no more)
        v._draw()  # type: ignore[attr-defined]
        _screenshot(v.url, shots["chosen"])  # type: ignore[attr-defined]
        v.solutions = None  # type: ignore[attr-defined]
        v._draw()  # type: ignore[attr-defined]
        _screenshot(v.url, shots["none"])  # type: ignore[attr-defined]
        assert _changed(shots["all"], shots["none"]) > 3000, "no arm on the page"
        if name == "ur5":  # (the C-Arm's pose has families only: nothing is left when they are hidden)
            assert _changed(shots["chosen"], shots["none"]) > 1500, "the chosen arm is not on the page"
        assert _changed(shots["all"], shots["chosen"]) > 1500, "the other solutions (or families) are not on the page"
        keep = os.environ.get("SWEEPIK_SCREENSHOTS")
        if keep:
            shutil.copy(shots["all"], Path(keep) / image)
    finally:
        v.close()  # type: ignore[attr-defined]


def test_view_from_python_and_the_cli_refusals(capsys: pytest.CaptureFixture[str]) -> None:
    pytest.importorskip("viser")
    from sweepik.cli.app import main

    robot = sweepik.load_robot("ur5")
    sols = sweepik.solve(robot, robot.fk([0.3, -1.0, 1.2, -0.4, 0.9, 0.2]))
    v = sweepik.view(robot, sols, port=0, block=False)
    try:
        assert v.url.startswith("http://127.0.0.1:") and len(v.solutions) == len(sols)
        np.testing.assert_array_equal(v.solutions.pose, sols.pose)
    finally:
        v.close()
    assert "sweepik viewer of ur5: http://127.0.0.1:" in capsys.readouterr().out
    assert main(["view", "franka_panda", "--port", "0"]) == 2
    assert "--lock NAME=VALUE" in capsys.readouterr().err
    assert main(["view", "ur5", "--port", "70000"]) == 2


def test_a_viewer_that_cannot_start_leaves_no_server_running() -> None:
    """A 7-joint arm without a lock cannot be solved: the viewer raises, and its port is free again."""
    pytest.importorskip("viser")
    import socket

    from sweepik.viewer.app import Viewer

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    with pytest.raises(sweepik.SweepikError):
        Viewer(sweepik.load_robot("franka_panda"), port=port)
    with socket.socket() as s:
        s.bind(("127.0.0.1", port))  # (free: the server was stopped)
    v = Viewer(sweepik.load_robot("franka_panda"), port=port, locked={"joint7": 0.3})
    v.close()
