"""Figures of the paper's verification (matplotlib, imported lazily: ``pip install sweepik[plot]``).

Every function takes ``ax=None`` (a new figure is made when None), returns the Axes it drew on and never
calls ``show()``. Inputs are the plain dicts and arrays of :mod:`sweepik.experiments.verify` and
:mod:`sweepik.trajectory`; angles are drawn in degrees, lengths in the robot's length unit.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike

from sweepik.errors import SweepikError

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from sweepik.model.robot import Robot

__all__ = [
    "plot_figure4",
    "plot_trajectory_3d",
    "plot_joints_along_path",
    "save_verification_figures",
]


def _pyplot() -> Any:
    try:
        import matplotlib.pyplot as plt
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SweepikError("plotting needs matplotlib: pip install 'sweepik[plot]'") from exc
    return plt


def _new_figure(projection: str | None = None, figsize: tuple[float, float] = (6.4, 4.8)) -> Any:
    """A new pyplot figure with one Axes (3D when ``projection="3d"``); returns the Axes."""
    plt = _pyplot()
    fig = plt.figure(figsize=figsize)
    return fig.add_subplot(projection=projection) if projection else fig.add_subplot()


#: Gap between the bottom of a 2D Axes and a legend placed below it, in points: clears the tick labels and
#: the x label (at the default font sizes).
_LEGEND_BELOW_PT = 40.0


def _legend_below(ax: Axes, handles: Sequence[Any] | None = None, labels: Sequence[str] | None = None) -> None:
    """A legend in one row under ``ax`` (below its x label, or under the panes of a 3D Axes): outside the axes,
    it hides no data, whatever the data. ``savefig(bbox_inches="tight")`` or ``tight_layout`` keep it in view."""
    from matplotlib.transforms import ScaledTranslation

    if handles is None or labels is None:
        handles, labels = ax.get_legend_handles_labels()
    gap_in = (0.0 if ax.name == "3d" else _LEGEND_BELOW_PT) / 72.0  # points to inches
    fig = ax.get_figure()
    below = ax.transAxes if fig is None else ax.transAxes + ScaledTranslation(0.0, -gap_in, fig.dpi_scale_trans)
    ax.legend(
        handles,
        labels,
        loc="upper center",
        bbox_to_anchor=(0.5, 0.0),
        bbox_transform=below,
        ncol=max(len(labels), 1),
        fontsize=8,
        frameon=False,
    )


def plot_figure4(data: Mapping[str, Any], ax: Axes | None = None) -> Axes:
    """The paper's Figure 4 from :func:`sweepik.experiments.verify.figure4_data`.

    x: the desired theta2 of each verification point (deg); y: theta2 of every solution (deg). Desired
    values are circles (label ``"desired"``), solutions crosses (label ``"solutions"``), and a multiplicity
    above one is written as ``(m)`` next to its cross.
    """
    if ax is None:
        ax = _new_figure()
    desired = np.asarray(data["theta2_desired_deg"], dtype=np.float64)
    xs: list[float] = []
    ys: list[float] = []
    for x, vals, mult in zip(desired, data["theta2_solutions_deg"], data["multiplicity"], strict=True):
        for v, m in zip(vals, mult, strict=True):
            xs.append(float(x))
            ys.append(float(v))
            if m > 1:
                ax.annotate(f"({m})", (x, v), textcoords="offset points", xytext=(6, 3), fontsize=8)
    ax.plot(desired, desired, "o", markersize=11, markerfacecolor="none", markeredgecolor="C0", label="desired")
    ax.plot(xs, ys, "x", color="C3", markersize=7, label="solutions")
    fixed = data.get("fixed", {})
    if fixed:
        txt = ", ".join(
            f"{k.replace('_deg', '').replace('_mm', '')} = {v:g}{' mm' if k.endswith('_mm') else '°'}"
            for k, v in fixed.items()
        )
        ax.set_title(f"θ2 of all solutions ({txt})", fontsize=9)
    ax.set_xlabel("desired θ2 (deg)")
    ax.set_ylabel("θ2 of solutions (deg)")
    ticks = np.arange(-180, 181, 60)
    ax.set_xticks(ticks)
    ax.set_yticks(ticks)
    ax.set_xlim(-180, 180)
    ax.set_ylim(-190, 190)
    ax.grid(True, alpha=0.3)
    _legend_below(ax)
    return ax


def plot_trajectory_3d(
    xyz: ArrayLike,
    corners: ArrayLike | None = None,
    achieved_xyz: ArrayLike | None = None,
    ax: Axes | None = None,
    *,
    length_unit: str = "mm",
) -> Axes:
    """The paper's Figure 5: the path ``xyz (N, 3)`` as a thick line (label ``"trajectory"``), the computed
    points ``achieved_xyz (N, 3)`` (default: ``xyz``) as ``*`` marks (``"points"``), and the rectangle through
    ``corners (K, 3)`` as thin closed lines (``"rectangle"``). ``ax`` must be a 3D Axes if given."""
    if ax is None:
        ax = _new_figure("3d")
    P = np.asarray(xyz, dtype=np.float64)
    A = P if achieved_xyz is None else np.asarray(achieved_xyz, dtype=np.float64)
    if corners is not None:
        C = np.asarray(corners, dtype=np.float64)
        C = np.vstack([C, C[:1]])
        ax.plot(C[:, 0], C[:, 1], C[:, 2], "-", color="0.5", linewidth=0.8, label="rectangle")
    ax.plot(P[:, 0], P[:, 1], P[:, 2], "-", color="C0", linewidth=2.5, label="trajectory")
    ax.plot(A[:, 0], A[:, 1], A[:, 2], "*", color="C3", markersize=7, label="points")
    ax.set_xlabel(f"x ({length_unit})")
    ax.set_ylabel(f"y ({length_unit})")
    ax.set_zlabel(f"z ({length_unit})")  # type: ignore[union-attr]
    _legend_below(ax)
    return ax


def plot_joints_along_path(
    q: ArrayLike,
    robot: Robot | None = None,
    ax: Axes | None = None,
    *,
    joint_names: Sequence[str] | None = None,
    revolute: Sequence[bool] | None = None,
    length_unit: str | None = None,
) -> Axes:
    """Joint values ``q (N, n)`` (radians / length unit; NaN rows allowed) against the point index.

    Revolute joints on ``ax`` in degrees, one line each labelled with the joint name; prismatic joints
    dashed on a twin y-axis (the figure's other Axes) in the length unit. Names, joint
    types and unit come from ``robot`` unless given.
    """
    Q = np.array(q, dtype=np.float64)
    if Q.ndim != 2:
        raise SweepikError(f"q must have shape (N, n), got {Q.shape}")
    n = Q.shape[1]
    names = (
        list(joint_names)
        if joint_names is not None
        else (robot.joint_names if robot else [f"q{i + 1}" for i in range(n)])
    )
    rev = np.asarray(revolute if revolute is not None else (robot.is_revolute if robot else [True] * n), dtype=bool)
    unit = length_unit or (robot.length_unit if robot else "mm")
    if len(names) != n or rev.size != n:
        raise SweepikError(f"q has {n} joints but {len(names)} names and {rev.size} joint types were given")
    if ax is None:
        ax = _new_figure(figsize=(7.0, 4.2))
    k = np.arange(Q.shape[0])
    for i in np.nonzero(rev)[0]:
        ax.plot(k, np.degrees(Q[:, i]), "-o", markersize=3, label=names[i])
    ax.set_xlabel("path point")
    ax.set_ylabel("revolute joints (deg)")
    ax.grid(True, alpha=0.3)
    handles, labels = ax.get_legend_handles_labels()
    if np.any(~rev):
        twin = ax.twinx()
        for j, i in enumerate(np.nonzero(~rev)[0]):
            twin.plot(k, Q[:, i], "--s", markersize=3, color=f"C{(int(rev.sum()) + j) % 10}", label=names[i])
        twin.set_ylabel(f"prismatic joints ({unit})")
        h2, l2 = twin.get_legend_handles_labels()
        handles, labels = handles + h2, labels + l2
    _legend_below(ax, handles, labels)
    return ax


def save_verification_figures(result: Mapping[str, Any], directory: str | PathLike[str]) -> dict[str, Path]:
    """PNG figures of a :func:`sweepik.experiments.verify.run_verify` result (one strategy or both) in ``directory``.

    Writes ``figure4_<strategy>.png`` per strategy present, and from the precise run (else the paper's)
    ``trajectory_3d.png`` (Figure 5) and ``trajectory_joints.png``. Returns ``{name: path}``. Figures are
    closed after saving.
    """
    plt = _pyplot()
    out_dir = Path(directory)
    out_dir.mkdir(parents=True, exist_ok=True)
    runs = {k: v for k, v in result.items() if k in ("paper", "precise") and isinstance(v, Mapping)}
    if not runs and "grid" in result:
        runs = {str(result.get("strategy", "precise")): result}
    written: dict[str, Path] = {}

    def save(ax: Axes, name: str) -> None:
        fig = ax.get_figure()
        path = out_dir / f"{name}.png"
        fig.tight_layout()  # type: ignore[union-attr]
        fig.savefig(path, dpi=120, bbox_inches="tight")  # type: ignore[union-attr]
        plt.close(fig)
        written[name] = path

    for strat, run in runs.items():
        if "figure4" in run:
            ax = plot_figure4(run["figure4"])
            ax.set_title(f"Figure 4 ({strat} strategy)", fontsize=10)
            save(ax, f"figure4_{strat}")
    traj_run = runs.get("precise") or runs.get("paper")
    if traj_run and "trajectory" in traj_run:
        tr = traj_run["trajectory"]
        ax = plot_trajectory_3d(tr["xyz"], tr.get("corners"), np.array(tr["achieved_xyz"], dtype=np.float64))
        ax.set_title("Figure 5: trajectory at the zero-pose orientation", fontsize=10)
        save(ax, "trajectory_3d")
        ax = plot_joints_along_path(
            np.array(tr["q"], dtype=np.float64),
            joint_names=tr.get("joint_names"),
            revolute=tr.get("joint_revolute"),
            length_unit=tr.get("max_joint_step_detail", {}).get("length_unit"),
        )
        ax.set_title("Joint values along the trajectory", fontsize=10)
        save(ax, "trajectory_joints")
    return written
