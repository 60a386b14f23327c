"""``sweepik view``: every IK solution of a target drawn at once in the browser, on viser (the ``view`` extra).

A target gizmo to drag; every solution of the target drawn as a skeleton (``viewer.scene``), the chosen one solid and
the others as ghosts, solutions outside the joint limits red (with limits off) and multiple roots orange; each
self-motion family with a slider along it; joint sliders for forward kinematics (the target follows them); with
``poses``, a slider stepping through them. The panel shows the arm's structure, the decomposition and the count.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import SweepikError, UnknownOptionError
from sweepik.model.robot import Robot
from sweepik.model.validate import check_bool, check_configuration, check_int, check_poses
from sweepik.reductions.analysis import analyze, plan_line
from sweepik.results import Solutions
from sweepik.solving import solve
from sweepik.viewer import scene

__all__ = ["Viewer", "view"]

Array = NDArray[np.float64]


def _viser() -> Any:
    try:
        import viser
    except ImportError:
        raise UnknownOptionError("the viewer needs viser: pip install 'sweepik[view]'") from None
    return viser


def _wxyz(R: Array) -> Array:
    """A rotation matrix as viser's quaternion (w, x, y, z)."""
    return np.asarray(_viser().transforms.SO3.from_matrix(R).wxyz, dtype=np.float64)


def _matrix(wxyz: ArrayLike, position: ArrayLike) -> Array:
    T = np.eye(4)
    T[:3, :3] = _viser().transforms.SO3(np.asarray(wxyz, dtype=np.float64)).as_matrix()
    T[:3, 3] = position
    return T


class Viewer:
    """A running viewer of one arm (see :func:`view`): ``url``, ``show(pose)``, ``solutions``, ``close()``."""

    def __init__(
        self,
        robot: Robot,
        *,
        poses: ArrayLike | None = None,
        port: int = 8080,
        host: str = "127.0.0.1",
        limits: bool = True,
        locked: Mapping[Any, float] | None = None,
        urdf: str | Path | None = None,
    ) -> None:
        if not isinstance(robot, Robot):
            raise UnknownOptionError(f"view takes a sweepik.Robot, got {type(robot).__name__}")
        self.robot = robot
        self.locked = dict(locked) if locked else None
        self.limits = check_bool(limits, "limits")
        self.poses = None if poses is None else check_poses(poses, "poses").reshape(-1, 4, 4)
        port = check_int(port, "port", 0, 65535)
        self._lock = threading.RLock()
        self._handles: list[Any] = []
        self._cylinder = scene.unit_cylinder()
        self._family_sliders: list[Any] = []
        self.solutions: Solutions | None = None
        self.chosen = 0
        viser = _viser()
        self.server = viser.ViserServer(host=host, port=port, verbose=False)
        self.url = f"http://{host}:{self.server.get_port()}"
        try:
            self._build_scene()
            self.meshes = None if urdf is None else self._load_meshes(Path(urdf))
            self._build_gui()
        except BaseException:
            self.close()
            raise
        try:
            self.show(self.poses[0] if self.poses is not None else robot.fk(self._home()))
        except BaseException:  # (e.g. a 7-joint arm without a lock: the server is not left running)
            self.close()
            raise

    # ------------------------------------------------------------------ set-up

    def _home(self) -> Array:
        """A configuration to start from: the middle of the joint ranges (the held values for held joints)."""
        q = 0.5 * (self.robot.lower + self.robot.upper)
        for name, value in (self.locked or {}).items():
            k = self.robot.joint_names.index(name) if isinstance(name, str) else int(name)
            q[k] = value
        return q

    def _build_scene(self) -> None:
        size = scene.size_m(self.robot)
        self.server.scene.add_grid("/grid", width=4 * size, height=4 * size, cell_size=size / 5)
        self.target = self.server.scene.add_transform_controls("/target", scale=0.35 * size, line_width=3.0)
        self.server.scene.add_frame("/target/axes", axes_length=0.15 * size, axes_radius=0.008 * size)
        self.target.on_update(lambda _: self._target_moved())

        camera = self.server.initial_camera
        camera.position = (0.8 * size, -0.95 * size, 0.6 * size)
        camera.look_at = (0.0, 0.0, 0.2 * size)
        camera.up = (0.0, 0.0, 1.0)

    def _load_meshes(self, path: Path) -> Any:
        """The URDF's own meshes for the chosen solution (viser's ``ViserUrdf``, yourdfpy), when the file has visual
        geometry that resolves and its root is the chain's base; else None (the skeleton alone, and the panel says
        why)."""
        self.mesh_note = ""
        try:
            import yourdfpy
            from viser.extras import ViserUrdf
        except ImportError:
            self.mesh_note = "meshes: need yourdfpy (pip install yourdfpy)"
            return None
        try:
            urdf = yourdfpy.URDF.load(str(path), build_scene_graph=True, load_meshes=True)
        except Exception as exc:  # noqa: BLE001 - yourdfpy's and trimesh's errors on a file sweepik has read already
            self.mesh_note = f"meshes: not loaded ({type(exc).__name__})"
            return None
        if not urdf.scene.geometry:
            self.mesh_note = "meshes: none found in the file (or their files did not resolve): skeleton only"
            return None
        base = self.robot.description.rpartition("chain ")[2].partition(" -> ")[0]
        if base != urdf.base_link:
            self.mesh_note = "meshes: the chain does not start at the file's root link: skeleton only"
            return None
        names = list(urdf.actuated_joint_names)
        self._mesh_index = [names.index(n) if n in names else -1 for n in self.robot.joint_names]
        self._mesh_cfg = np.zeros(len(names))
        return ViserUrdf(self.server, urdf, root_node_name="/meshes")

    def _pose_meshes(self, q: Array) -> None:
        """The URDF's meshes at ``q`` (joints of the file that are not on the chain stay at 0)."""
        if self.meshes is None:
            return
        for k, i in enumerate(self._mesh_index):
            if i >= 0:
                self._mesh_cfg[i] = q[k]
        self.meshes.update_cfg(self._mesh_cfg)

    def _build_gui(self) -> None:
        gui = self.server.gui
        info = analyze(self.robot, locked=self.locked)
        how = plan_line(info["chosen"]) if info.get("chosen") else str(info.get("reason"))
        note = getattr(self, "mesh_note", "")
        gui.add_markdown(
            f"**{self.robot.name}** · {info['structure']}  \ndecomposition: {how}" + (f"  \n{note}" if note else "")
        )
        self.status = gui.add_markdown("")
        self.choice = gui.add_slider("chosen solution", min=1, max=2, step=1, initial_value=1)
        self.choice.on_update(lambda _: self._chosen(int(self.choice.value) - 1))
        self.ghosts = gui.add_checkbox("show every solution", initial_value=True)
        self.ghosts.on_update(lambda _: self._draw())
        self.limits_box = gui.add_checkbox("joint limits", initial_value=self.limits)
        self.limits_box.on_update(lambda _: self._set_limits(bool(self.limits_box.value)))
        if self.poses is not None and len(self.poses) > 1:
            step = gui.add_slider("pose", min=1, max=len(self.poses), step=1, initial_value=1)
            step.on_update(lambda _: self.show(self.poses[int(step.value) - 1]))
        self.families_folder = gui.add_folder("self-motion families")
        with gui.add_folder("joints (forward kinematics)", expand_by_default=False):
            self.joint_sliders = [self._joint_slider(k) for k in range(self.robot.n_joints)]
            gui.add_button("move the target here").on_click(lambda _: self._target_from_joints())

    def _joint_slider(self, k: int) -> Any:
        lo, hi = self.robot.limits[k]
        rev = bool(self.robot.is_revolute[k])
        conv = np.degrees if rev else (lambda v: v)
        unit = "deg" if rev else self.robot.length_unit
        mid = 0.5 * (lo + hi)
        return self.server.gui.add_slider(
            f"{self.robot.joint_names[k]} [{unit}]",
            min=float(conv(lo)),
            max=float(conv(hi)),
            step=float((conv(hi) - conv(lo)) / 1000.0),
            initial_value=float(conv(mid)),
        )

    # ------------------------------------------------------------------ events

    def _target_moved(self) -> None:
        T = scene.pose_from_metres(self.robot, _matrix(self.target.wxyz, self.target.position))
        self._solve(T)

    def _target_from_joints(self) -> None:
        values = np.array([float(s.value) for s in self.joint_sliders])
        q = np.where(self.robot.is_revolute, np.radians(values), values)
        self.show(self.robot.fk(q))

    def _set_limits(self, on: bool) -> None:
        self.limits = on
        if self.solutions is not None:
            self._solve(self.solutions.pose)

    def _chosen(self, k: int) -> None:
        self.chosen = k
        self._draw()

    # ------------------------------------------------------------------ solving and drawing

    def show(self, pose: ArrayLike) -> Solutions:
        """Move the target to ``pose (4, 4)`` (the robot's length unit) and draw its solutions; returns them."""
        T = check_poses(pose, "pose")
        if T.shape != (4, 4):
            raise SweepikError(f"pose must have shape (4, 4), got {T.shape}")
        Tm = scene.pose_in_metres(self.robot, T)
        with self.server.atomic():
            self.target.wxyz = _wxyz(Tm[:3, :3])
            self.target.position = Tm[:3, 3]
        return self._solve(T)

    def _solve(self, T: Array) -> Solutions:
        with self._lock:
            try:
                sols = solve(self.robot, T, limits=self.limits, locked=self.locked)
            except SweepikError as exc:
                self.status.content = f"cannot solve: {exc}"
                raise
            self.solutions = sols
            self.chosen = 0
            self._update_panel(sols)
            self._draw()
            return sols

    def _update_panel(self, sols: Solutions) -> None:
        n = len(sols)
        parts = [f"**{n} solution{'s' if n != 1 else ''}**"]
        if sols.families:
            parts.append(f"{len(sols.families)} self-motion famil{'y' if len(sols.families) == 1 else 'ies'}")
        if n and np.any(sols.multiplicity > 1):
            parts.append(f"{int(np.sum(sols.multiplicity > 1))} multiple root(s) (orange)")
        if n and not np.all(sols.within_limits):
            parts.append(f"{int(np.sum(~sols.within_limits))} outside the limits (red)")
        if not sols:
            parts.append(str(sols.reason))
        self.status.content = " · ".join(parts)
        self.choice.max = max(n, 2)
        self.choice.value = 1
        self.choice.disabled = n < 2
        for slider in self._family_sliders:
            slider.remove()
        self._family_sliders = []
        with self.families_folder:
            for k, fam in enumerate(sols.families):
                slider = self.server.gui.add_slider(
                    f"family {k + 1}: {self.robot.joint_names[fam.free_joint]}",
                    min=0.0,
                    max=1.0,
                    step=0.001,
                    initial_value=0.5,
                )
                slider.on_update(lambda _: self._draw())
                self._family_sliders.append(slider)

    def _draw(self) -> None:
        with self._lock, self.server.atomic():
            for h in self._handles:
                h.remove()
            self._handles = []
            sols = self.solutions
            if sols is None:
                return
            if len(sols):
                self._pose_meshes(sols.q[min(self.chosen, len(sols) - 1)])
            for k in range(len(sols)):
                chosen = k == self.chosen
                if chosen or self.ghosts.value:
                    rgb = scene.colour(bool(sols.within_limits[k]), int(sols.multiplicity[k]), chosen)
                    self._draw_arm(f"/solutions/{k}", sols.q[k], rgb, 0.012 if chosen else 0.006)
            for k, (fam, slider) in enumerate(zip(sols.families, self._family_sliders, strict=False)):
                lo, hi = fam.interval
                member = fam.at(lo + float(slider.value) * (hi - lo))
                self._draw_arm(f"/families/{k}", member, scene.FAMILY, 0.01)

    def _draw_arm(self, name: str, q: Array, rgb: Sequence[int], width: float) -> None:
        """One configuration as solid cylinders (links, and thicker short ones along the joint axes) and its tool
        frame."""
        sk = scene.skeleton(self.robot, q)
        size = scene.size_m(self.robot)
        links = scene.cylinders(sk.links, width * size)
        axes = scene.cylinders(sk.axes, 2.0 * width * size)
        wxyz, centres, scales = (np.concatenate([x, y]) for x, y in zip(links, axes, strict=True))
        add = self.server.scene
        self._handles.append(
            add.add_batched_meshes_simple(f"{name}/body", self._cylinder[0], self._cylinder[1], batched_wxyzs=wxyz,
                                          batched_positions=centres, batched_scales=scales, batched_colors=rgb,
                                          material="toon3")
        )  # fmt: skip
        self._handles.append(
            add.add_frame(
                f"{name}/tool",
                axes_length=0.08 * size,
                axes_radius=0.2 * width * size,
                wxyz=_wxyz(sk.tool[:3, :3]),
                position=sk.tool[:3, 3],
            )  # fmt: skip
        )

    # ------------------------------------------------------------------ lifetime

    def set_configuration(self, q: ArrayLike) -> Solutions:
        """Move the target to the pose of configuration ``q`` and draw its solutions."""
        return self.show(self.robot.fk(check_configuration(q, self.robot.n_joints)))

    def wait(self) -> None:
        """Block until interrupted (Ctrl-C), then stop the server."""
        try:
            while True:
                time.sleep(0.5)
        except KeyboardInterrupt:
            pass
        finally:
            self.close()

    def close(self) -> None:
        """Stop the server (its port is free again)."""
        self.server.stop()


def view(
    robot: Robot,
    solutions: Solutions | None = None,
    *,
    poses: ArrayLike | None = None,
    port: int = 8080,
    host: str = "127.0.0.1",
    limits: bool = True,
    locked: Mapping[Any, float] | None = None,
    urdf: str | Path | None = None,
    block: bool = True,
) -> Viewer:
    """Open a browser viewer of ``robot`` at ``http://host:port`` (printed; ``port=0`` takes a free one): drag the
    target and every solution follows. ``solutions`` (from :func:`~sweepik.solve`): start at their pose; ``poses
    (N, 4, 4)``: a slider steps through them. ``limits`` and ``locked`` as for ``solve``. ``block``: serve until
    Ctrl-C (False: return the running :class:`Viewer`, whose ``close()`` stops it). ``urdf``: the URDF file the
    robot was read from, to draw the chosen solution with its meshes (when they resolve). Needs the ``view`` extra."""
    v = Viewer(robot, poses=poses, port=port, host=host, limits=limits, locked=locked, urdf=urdf)
    if solutions is not None:
        v.show(solutions.pose)
    print(f"sweepik viewer of {robot.name}: {v.url}", flush=True)
    if block:
        v.wait()
    return v
