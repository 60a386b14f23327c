"""Tests of sweepik.experiments.plot under the Agg backend: figures are produced, carry the data, and never show()."""

from __future__ import annotations

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402

import sweepik.experiments.verify as V  # noqa: E402
from sweepik import load_robot  # noqa: E402
from sweepik.errors import SweepikError  # noqa: E402
from sweepik.experiments.plot import plot_figure4, plot_joints_along_path, plot_trajectory_3d, save_verification_figures  # noqa: E402

CARM = load_robot("carm")


@pytest.fixture(autouse=True)
def _no_show_and_close(monkeypatch):
    def fail(*args, **kwargs):
        raise AssertionError("plot functions must not call show()")

    monkeypatch.setattr(plt, "show", fail)
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def fig4() -> dict:
    return V.figure4_data(CARM, "precise")


@pytest.fixture(scope="module")
def traj() -> dict:
    return V.run_trajectory(CARM, "precise")


def _line(ax, label):
    (line,) = [ln for ln in ax.get_lines() if ln.get_label() == label]
    return line


def test_figure4_has_11_desired_markers_at_the_table2_values(fig4, tmp_path) -> None:
    ax = plot_figure4(fig4)
    desired = _line(ax, "desired")
    np.testing.assert_array_equal(desired.get_xdata(), V.TABLE2["theta2_deg"])
    np.testing.assert_array_equal(desired.get_ydata(), V.TABLE2["theta2_deg"])
    assert desired.get_marker() == "o"
    sols = _line(ax, "solutions")
    assert sols.get_marker() == "x"
    assert len(sols.get_ydata()) == sum(len(v) for v in fig4["theta2_solutions_deg"])
    labels = [t.get_text() for t in ax.texts]
    assert labels == [f"({m})" for mult in fig4["multiplicity"] for m in mult if m > 1]
    path = tmp_path / "f4.png"
    ax.get_figure().savefig(path)
    assert path.stat().st_size > 1000


def test_figure4_draws_on_a_given_axes(fig4) -> None:
    fig, ax = plt.subplots()
    assert plot_figure4(fig4, ax=ax) is ax
    assert len(fig.axes) == 1


def test_trajectory_3d_shows_path_points_and_rectangle(traj) -> None:
    ax = plot_trajectory_3d(traj["xyz"], traj["corners"], traj["achieved_xyz"])
    assert ax.name == "3d"
    path = _line(ax, "trajectory")
    xs, ys, zs = path.get_data_3d()
    np.testing.assert_allclose(np.c_[xs, ys, zs], traj["xyz"])
    assert path.get_linewidth() > _line(ax, "rectangle").get_linewidth()
    rect = np.c_[_line(ax, "rectangle").get_data_3d()]
    assert rect.shape == (5, 3)  # 4 corners and back to the first
    np.testing.assert_allclose(rect[0], V.TRAJECTORY_START)
    np.testing.assert_allclose(rect[-1], rect[0])
    assert len(_line(ax, "points").get_data_3d()[0]) == traj["points"]


def test_trajectory_3d_on_a_given_axes() -> None:
    fig = plt.figure()
    ax = fig.add_subplot(projection="3d")
    xyz = np.array([[0.0, 0, 0], [1, 1, 1]])
    assert plot_trajectory_3d(xyz, ax=ax) is ax
    assert [ln.get_label() for ln in ax.get_lines()] == ["trajectory", "points"]


def test_joints_along_path_degrees_left_length_right(traj) -> None:
    q = np.array(traj["q"], dtype=np.float64)
    ax = plot_joints_along_path(q, CARM)
    labels = [ln.get_label() for ln in ax.get_lines()]
    assert labels == ["theta2", "theta3", "theta4", "theta5", "theta6"]
    np.testing.assert_allclose(_line(ax, "theta3").get_ydata(), np.degrees(q[:, 2]))
    fig = ax.get_figure()
    (twin,) = [a for a in fig.axes if a is not ax]
    (d1,) = twin.get_lines()
    assert d1.get_label() == "d1"
    np.testing.assert_allclose(d1.get_ydata(), q[:, 0])
    assert "mm" in twin.get_ylabel() and "deg" in ax.get_ylabel()


def test_joints_along_path_without_robot_and_errors() -> None:
    q = np.zeros((4, 2))
    fig, ax = plt.subplots()
    out = plot_joints_along_path(q, ax=ax, joint_names=["a", "b"], revolute=[True, True])
    assert out is ax and len(fig.axes) == 1 and len(ax.get_lines()) == 2
    with pytest.raises(SweepikError):
        plot_joints_along_path(q, joint_names=["a"])
    with pytest.raises(SweepikError):
        plot_joints_along_path(np.zeros(3))


def test_save_verification_figures(fig4, traj, tmp_path) -> None:
    result = {"strategy": "precise", "grid": {}, "figure4": fig4, "trajectory": traj}
    written = save_verification_figures(result, tmp_path / "figs")
    assert set(written) == {"figure4_precise", "trajectory_3d", "trajectory_joints"}
    for path in written.values():
        assert path.exists() and path.stat().st_size > 1000
    assert plt.get_fignums() == []  # closed after saving


def _legend_clear_of_axes(ax) -> None:
    """The legend lies wholly below the axes (and below the x label of a 2D plot): it hides no data."""
    fig = ax.get_figure()
    fig.canvas.draw()
    leg = ax.get_legend()
    assert leg is not None
    lb = leg.get_window_extent()
    assert lb.y1 <= ax.get_window_extent().y0 + 1e-6
    if ax.name != "3d":
        assert lb.y1 <= ax.xaxis.label.get_window_extent().y0 + 1e-6


def test_legends_hide_no_data(fig4, traj, tmp_path) -> None:
    ax = plot_joints_along_path(np.array(traj["q"], dtype=np.float64), CARM)
    _legend_clear_of_axes(ax)
    assert [t.get_text() for t in ax.get_legend().get_texts()] == [*CARM.joint_names[1:], "d1"]
    _legend_clear_of_axes(plot_trajectory_3d(traj["xyz"], traj["corners"], traj["achieved_xyz"]))
    _legend_clear_of_axes(plot_figure4(fig4))
    # saved figures keep the legend in view (bbox_inches="tight"): the bottom strip of the image, below the x
    # label, holds the legend's lines and text
    written = save_verification_figures({"strategy": "precise", "grid": {}, "trajectory": traj}, tmp_path)
    img = plt.imread(written["trajectory_joints"])[..., :3]
    bottom = img[int(0.93 * img.shape[0]) :]
    assert np.any(bottom.min(axis=-1) < 0.5)
