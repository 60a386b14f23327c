"""The on-disk solution store (``sweepik.io.store``): what ``load_solutions`` reads equals ``solve_many`` (same
solutions,
same order, errors, flags, multiplicities, reasons, self-motion families, robot), on the C-Arm (a sweep) and UR5 (a
closed form with a fallback sweep), with unreachable, out-of-limit and self-motion poses; a 7-joint arm with a lock;
a store interrupted between chunks (or inside one) is refused as incomplete and never looks complete; a store is
resumed only with the same robot, options, poses and chunk size. The stores here are written in this process, chunk
by chunk, with the function a Dask worker runs (``distributed._solve_task``); ``tests/test_dask.py`` runs them on a
cluster."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import zarr

import sweepik
from sweepik import Robot, SolutionBatch, StoreError, load_robot, load_solutions, solve_many
from sweepik.distributed import _checked_options, _solve_task
from sweepik.io.store import CHUNKS, StoreWriter, robot_from_json, robot_to_json, store_info

CARM = load_robot("carm")
UR5 = load_robot("ur5")

#: C-Arm configurations on its self-motion set (tests/test_singular_set.py): d1 families through the wrist-on-axis
#: point and over a narrow in-limit stretch
CARM_FAMILY_Q = [
    [1635.85004, np.pi / 2, 1.9463, 0.42645, 0.0, -2.42881],
    [72.12311928462101, np.pi / 2, 2.011940442154147, 0.50674176, 0.0, -0.52394],
]
#: UR5 at its singular wrist (q5 = 0): joints 4 and 6 turn together, a family of the fallback sweep
UR5_FAMILY_Q = [[0.3, -1.0, 1.2, 0.4, 0.0, 0.7]]


def far_pose(robot: Robot) -> np.ndarray:
    """A pose far outside the workspace (unreachable)."""
    T = np.eye(4)
    T[:3, 3] = 50.0 * robot.length_scale
    return T


def test_poses(robot: Robot, n: int, family_q: list[list[float]], seed: int) -> np.ndarray:
    """``n`` random in-limit poses, poses only reachable outside the limits, an unreachable pose and self-motion
    poses, shuffled together: ``(N, 4, 4)``."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), size=(n, robot.n_joints))
    outside = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), size=(6, robot.n_joints))
    j = np.arange(6) % robot.n_joints
    span = robot.upper[j] - robot.lower[j]
    outside[np.arange(6), j] = np.where(robot.is_revolute[j], robot.upper[j] + 0.3, robot.upper[j] + 0.3 * span)
    P = np.concatenate([robot.fk(q), robot.fk(outside), far_pose(robot)[None], robot.fk(np.array(family_q))])
    return P[rng.permutation(len(P))]


test_poses.__test__ = False  # type: ignore[attr-defined]  # a helper, not a test


def assert_same_batch(got: SolutionBatch, ref: SolutionBatch) -> None:
    """``got`` holds exactly ``ref``'s content: robot, poses, every column bit for bit, reasons and families
    (same free joint, interval, branch, chain pose and reduction, and the same members)."""
    assert len(got) == len(ref)
    assert got.robot == ref.robot
    for name in ("offsets", "q", "error", "error_geodesic", "within_limits", "multiplicity"):
        a, b = getattr(got, name), getattr(ref, name)
        assert a.dtype == b.dtype and a.shape == b.shape, name
        np.testing.assert_array_equal(a, b, err_msg=name)
    assert sorted(got.families) == sorted(ref.families)
    for i in range(len(ref)):
        g, r = got[i], ref[i]
        np.testing.assert_array_equal(g.pose, r.pose)
        assert g.reason == r.reason
        assert len(g.families) == len(r.families)
        for fg, fr in zip(g.families, r.families, strict=True):
            assert (fg.free_joint, fg.interval, fg.branch) == (fr.free_joint, fr.interval, fr.branch)
            np.testing.assert_array_equal(fg.chain_pose, fr.chain_pose)
            assert (fg.reduction.name, fg.reduction.free_joint) == (fr.reduction.name, fr.reduction.free_joint)
            assert (fg.held is None) == (fr.held is None)
            mid = 0.5 * (fr.interval[0] + fr.interval[1])
            np.testing.assert_array_equal(
                fg.at([fr.interval[0], mid, fr.interval[1]]), fr.at([fr.interval[0], mid, fr.interval[1]])
            )


def categories(batch: SolutionBatch) -> dict[str, int]:
    """Poses with solutions, unreachable, only out of limits, and with self-motion families."""
    out = {"solved": 0, "unreachable": 0, "out_of_limits": 0, "families": len(batch.families)}
    for i in range(len(batch)):
        reason = batch.reason(i)
        key = (
            "solved"
            if reason is None
            else "out_of_limits"
            if reason.startswith("out of joint limits")
            else "unreachable"
        )
        out[key] += 1
    return out


def options(robot: Robot, **kw: Any) -> dict[str, Any]:
    base: dict[str, Any] = dict(
        reduction=None, free_joint=None, strategy="precise", limits=True, n_samples=64, locked=None
    )
    base.update(kw)
    return _checked_options(robot, stored=True, **base)


def write_store(
    path: Path, robot: Robot, P: np.ndarray, chunk: int, chunks: list[int] | None = None, **kw: Any
) -> StoreWriter:
    """A store of ``P`` solved chunk by chunk in this process (only ``chunks`` of them when given: not finished)."""
    opts = options(robot, **kw)
    writer = StoreWriter(path, robot, opts, len(P), chunk)
    todo = range(writer.n_chunks) if chunks is None else chunks
    for k in todo:
        s, e = writer.span(k)
        writer.write(k, _solve_task(robot, P[s:e], opts, s))
    if chunks is None:
        writer.finish()
    return writer


@pytest.mark.parametrize(
    ("robot", "family_q", "chunk", "kinds"),
    [
        (CARM, CARM_FAMILY_Q, 17, ("solved", "unreachable", "out_of_limits", "families")),
        # UR5's joints turn +-360 deg: every pose it reaches has solutions inside the limits
        (UR5, UR5_FAMILY_Q, 23, ("solved", "unreachable", "families")),
    ],
    ids=["carm", "ur5"],
)
def test_store_round_trip_equals_solve_many(
    tmp_path: Path, robot: Robot, family_q: list[list[float]], chunk: int, kinds: tuple[str, ...]
) -> None:
    P = test_poses(robot, 120, family_q, seed=7)
    ref = solve_many(robot, P)
    seen = categories(ref)
    # the poses cover every kind of answer (else the round trip would not test it)
    assert all(seen[k] >= 1 for k in kinds), seen
    write_store(tmp_path / "s.zarr", robot, P, chunk)
    got = load_solutions(tmp_path / "s.zarr")
    assert_same_batch(got, ref)
    info = store_info(tmp_path / "s.zarr")
    assert info["complete"] and info["stored"] == -(-len(P) // chunk)
    s = info["summary"]
    assert s["poses"] == len(P) and s["solutions"] == len(ref.q)
    assert (s["unreachable"], s["out_of_limits"], s["families"]) == (
        seen["unreachable"],
        seen["out_of_limits"],
        seen["families"],
    )


def test_store_keeps_locked_joints_and_options(tmp_path: Path) -> None:
    # a 7-joint arm with a joint held, without limits, sweeping a chosen joint: every option is stored and used
    robot = load_robot("kuka_iiwa14")
    rng = np.random.default_rng(3)
    q = rng.uniform(np.maximum(robot.lower, -np.pi), np.minimum(robot.upper, np.pi), size=(30, 7))
    q[:, 2] = 0.25
    P = np.concatenate([robot.fk(q), far_pose(robot)[None]])
    kw = dict(locked={"A3": 0.25}, limits=False)
    ref = solve_many(robot, P, **kw)
    write_store(tmp_path / "s.zarr", robot, P, 8, **kw)
    got = load_solutions(tmp_path / "s.zarr")
    assert_same_batch(got, ref)
    assert got.q.shape[1] == 7 and not ref.within_limits.all()


def test_paper_strategy_reason_is_stored(tmp_path: Path) -> None:
    P = np.concatenate([CARM.fk(np.array([[800.0, 0.3, 0.2, -0.4, 0.5, 0.1]])), far_pose(CARM)[None]])
    ref = solve_many(CARM, P, strategy="paper")
    write_store(tmp_path / "s.zarr", CARM, P, 1, strategy="paper")
    got = load_solutions(tmp_path / "s.zarr")
    assert_same_batch(got, ref)
    assert "paper's strategy" in str(got.reason(1))


def test_empty_batch_round_trip(tmp_path: Path) -> None:
    write_store(tmp_path / "s.zarr", CARM, np.zeros((0, 4, 4)), 10)
    got = load_solutions(tmp_path / "s.zarr")
    assert len(got) == 0 and got.robot == CARM and got.q.shape == (0, 6)


def test_robot_content_round_trips_exactly() -> None:
    # the robot file (degrees) is not always exact (franka_panda moves by an ulp); the stored content is
    held = sweepik.model.origin_axis.hold_joints(load_robot("kuka_iiwa14"), {2: 0.25}).arm
    for robot in [load_robot(name) for name in sweepik.bundled_robots()] + [held]:
        back = robot_from_json(robot_to_json(robot))
        assert back == robot and hash(back) == hash(robot), robot.name


def test_interrupted_store_is_incomplete_and_never_looks_complete(tmp_path: Path) -> None:
    P = test_poses(CARM, 40, CARM_FAMILY_Q, seed=1)
    path = tmp_path / "s.zarr"
    writer = write_store(path, CARM, P, 10, chunks=[0, 2])
    # a chunk interrupted mid-write: its arrays are there, its 'done' attribute is not
    partial = writer.chunks.create_group("00000001")
    partial.create_array("poses", data=P[10:20], chunks=(10, 4, 4))
    assert sorted(writer.done()) == [0, 2]
    with pytest.raises(StoreError, match=r"incomplete .*2 of 5 chunks stored.*resume"):
        load_solutions(path)
    with pytest.raises(StoreError, match="3 of 5 chunks are missing"):
        writer.finish()
    assert not store_info(path)["complete"]
    # the root's 'complete' is written last: a reader opening the store now still sees it incomplete
    assert zarr.open_group(str(path), mode="r").attrs["complete"] is False


def test_resume_checks_robot_options_poses_and_size(tmp_path: Path) -> None:
    P = test_poses(CARM, 30, CARM_FAMILY_Q, seed=2)
    path = tmp_path / "s.zarr"
    write_store(path, CARM, P, 10, chunks=[0])
    opts = options(CARM)
    with pytest.raises(StoreError, match="already exists"):
        StoreWriter(path, CARM, opts, len(P), 10)
    with pytest.raises(StoreError, match="another robot"):
        StoreWriter(path, UR5, options(UR5), len(P), 10, resume=True)
    with pytest.raises(StoreError, match="another solver options"):
        StoreWriter(path, CARM, options(CARM, limits=False), len(P), 10, resume=True)
    with pytest.raises(StoreError, match="another number of poses"):
        StoreWriter(path, CARM, opts, len(P) + 1, 10, resume=True)
    with pytest.raises(StoreError, match="another chunk size"):
        StoreWriter(path, CARM, opts, len(P), 11, resume=True)
    writer = StoreWriter(path, CARM, opts, len(P), 10, resume=True)
    done = writer.done()
    from sweepik.io.store import poses_digest

    writer.check_poses(0, done[0], poses_digest(P[:10]))  # the same poses: accepted
    moved = P[:10].copy()
    moved[3, 0, 3] += 1e-9
    with pytest.raises(StoreError, match=r"poses \[0:10\] differ"):
        writer.check_poses(0, done[0], poses_digest(moved))
    # finishing the resumed store gives the complete one
    for k in range(1, writer.n_chunks):
        s, e = writer.span(k)
        writer.write(k, _solve_task(CARM, P[s:e], opts, s))
    writer.finish()
    assert_same_batch(load_solutions(path), solve_many(CARM, P))


def test_not_a_store(tmp_path: Path) -> None:
    with pytest.raises(StoreError, match="no such solution store"):
        load_solutions(tmp_path / "missing.zarr")
    (tmp_path / "file.zarr").write_text("x")
    with pytest.raises(StoreError, match="not a solution store"):
        load_solutions(tmp_path / "file.zarr")
    zarr.open_group(str(tmp_path / "plain.zarr"), mode="w").attrs["x"] = 1
    with pytest.raises(StoreError, match="not a sweepik solution store"):
        load_solutions(tmp_path / "plain.zarr")
    (tmp_path / "empty").mkdir()
    with pytest.raises(StoreError):
        load_solutions(tmp_path / "empty")
    with pytest.raises(StoreError, match="directory .* is missing"):
        StoreWriter(tmp_path / "no" / "s.zarr", CARM, options(CARM), 1, 1)


def test_store_layout_is_plain_zarr(tmp_path: Path) -> None:
    # any Zarr reader sees the columns: chunk k's poses and solutions, pose i's rows bounds[i]:bounds[i + 1]
    P = test_poses(CARM, 10, CARM_FAMILY_Q, seed=4)
    write_store(tmp_path / "s.zarr", CARM, P, 8)
    root = zarr.open_group(str(tmp_path / "s.zarr"), mode="r")
    ref = solve_many(CARM, P)
    g = root[CHUNKS]["00000001"]
    np.testing.assert_array_equal(g["poses"][...], P[8:16])
    b = g["bounds"][...]
    np.testing.assert_array_equal(g["q"][...][b[1] : b[2]], ref[9].q)
    assert root.attrs["robot_toml"].startswith("# written by sweepik")
    assert root.attrs["options"]["strategy"] == "precise"


def test_a_second_writer_and_another_version_are_refused(tmp_path: Path) -> None:
    """A store being written by a live process (its lock) is refused to a second run; a lock left by a process
    that is gone is taken over; a store written by another sweepik version is not resumed."""
    import socket

    import zarr

    from sweepik.io.store import LOCK_FILE

    P = test_poses(CARM, 20, CARM_FAMILY_Q, seed=3)
    path = tmp_path / "s.zarr"
    write_store(path, CARM, P, 10, chunks=[0])
    opts = options(CARM)
    (path / LOCK_FILE).write_text(f"{os.getppid()} {socket.gethostname()}")  # a live process, not this one
    with pytest.raises(StoreError, match="another run"):
        StoreWriter(path, CARM, opts, len(P), 10, resume=True)
    (path / LOCK_FILE).write_text(f"{2**22 + 12345} {socket.gethostname()}")  # no such process: stale
    writer = StoreWriter(path, CARM, opts, len(P), 10, resume=True)
    for k in range(1, writer.n_chunks):
        s, e = writer.span(k)
        writer.write(k, _solve_task(CARM, P[s:e], opts, s))
    writer.finish()
    assert not (path / LOCK_FILE).exists()
    assert_same_batch(load_solutions(path), solve_many(CARM, P))
    other = tmp_path / "o.zarr"
    write_store(other, CARM, P, 10, chunks=[0])
    zarr.open_group(str(other), mode="r+").attrs["sweepik_version"] = "0.0.1-other"
    with pytest.raises(StoreError, match="written by sweepik 0.0.1-other"):
        StoreWriter(other, CARM, opts, len(P), 10, resume=True)


def test_traced_families_round_trip(tmp_path: Path) -> None:
    """Families traced numerically (the C-Arm's theta2 self-motion under the automatic decomposition,
    sweepik.engine.continuation) are stored with their nodes and give the same members when loaded."""
    q = np.array([[500.0, 0.3, 0.0, -np.pi / 2, 0.2, 1.0], [1200.0, -1.1, 0.0, -np.pi / 2, -0.7, 2.5]])
    rng = np.random.default_rng(5)
    P = np.concatenate([CARM.fk(q), CARM.fk(rng.uniform(CARM.lower, CARM.upper, (5, 6)))])
    ref = solve_many(CARM, P, reduction="auto")
    assert [f.reduction.name for i in (0, 1) for f in ref[i].families] == ["traced", "traced"]
    write_store(tmp_path / "t.zarr", CARM, P, 3, reduction="auto")
    assert_same_batch(load_solutions(tmp_path / "t.zarr"), ref)
