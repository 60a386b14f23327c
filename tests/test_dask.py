"""``solve_dask`` on a local Dask cluster (2 worker processes) and the batch CLI (``sweepik solve --out``,
``sweepik sample``): results equal ``solve_many`` for NumPy, memory-mapped ``.npy`` and Dask-array poses, with and
without a store; an interrupted store is resumed (only its missing chunks are solved) to the same content; a worker
killed mid-run (SIGKILL) is replaced and its chunks rerun, the result still complete and identical; the CLI
interrupted by SIGINT half-way exits 130 leaving an incomplete store, and ``--resume`` completes it identically; bad
values are one line on stderr with exit status 2."""

from __future__ import annotations

import contextlib
import logging
import os
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import dask.array as da
import numpy as np
import pytest
from distributed import Client, LocalCluster
from test_store import CARM, CARM_FAMILY_Q, UR5, UR5_FAMILY_Q, assert_same_batch, test_poses, write_store

from sweepik import InvalidPoseError, StoreError, UnknownOptionError, load_solutions, solve_dask, solve_many
from sweepik import errors as sweepik_errors
from sweepik.cli.app import main
from sweepik.io.store import store_info
from sweepik.reductions import CArmD1

#: Seconds to wait for a subprocess to store chunks or to end (generous: the machine may be busy).
WAIT_S = 120


@pytest.fixture(scope="module")
def client() -> Iterator[Client]:
    with (
        LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0", silence_logs=logging.CRITICAL
        ) as cluster,
        Client(cluster) as c,
    ):
        yield c


@pytest.fixture(scope="module")
def carm_poses() -> tuple[np.ndarray, Any]:
    P = test_poses(CARM, 300, CARM_FAMILY_Q, seed=11)
    return P, solve_many(CARM, P)


def test_solve_dask_equals_solve_many(client: Client, carm_poses: tuple[np.ndarray, Any], tmp_path: Path) -> None:
    P, ref = carm_poses
    # NumPy poses, results collected by the client (no store); chunks unaligned with solve_many's
    assert_same_batch(solve_dask(CARM, P, client, chunk_size=29), ref)  # (no store: small chunks cost little)
    # a .npy path (memory-mapped by the client) into a store, read back
    np.save(tmp_path / "p.npy", P)
    got = solve_dask(CARM, tmp_path / "p.npy", client, out=tmp_path / "a.zarr", chunk_size=64)
    assert_same_batch(got, ref)
    assert_same_batch(load_solutions(tmp_path / "a.zarr"), ref)
    # a Dask array whose chunks are not the tasks' (each worker computes the pieces it solves)
    lazy = da.from_array(P, chunks=(50, 4, 4))
    assert_same_batch(solve_dask(CARM, lazy, client, out=tmp_path / "b.zarr", chunk_size=40), ref)


def test_solve_dask_general_method_arm(client: Client) -> None:
    """An arm without structure (the general method, issue 37) on the workers, as in process."""
    from general_arms import poses_of, random_arm

    robot = random_arm("6r", 1)
    P = robot.fk(poses_of(robot, 40, 8, seed=3))
    assert_same_batch(solve_dask(robot, P, client, chunk_size=17), solve_many(robot, P))


def test_solve_dask_closed_form_arm_with_fallback_family(client: Client, tmp_path: Path) -> None:
    P = test_poses(UR5, 100, UR5_FAMILY_Q, seed=12)
    ref = solve_many(UR5, P)
    assert ref.families  # the singular-wrist pose's family, from the fallback sweep, comes back from a worker
    np.save(tmp_path / "p.npy", P)
    mapped = np.load(tmp_path / "p.npy", mmap_mode="r")  # a read-only memory map
    assert_same_batch(solve_dask(UR5, mapped, client, chunk_size=16), ref)


def test_resume_solves_only_missing_chunks(client: Client, carm_poses: tuple[np.ndarray, Any], tmp_path: Path) -> None:
    P, ref = carm_poses
    path = tmp_path / "s.zarr"
    write_store(path, CARM, P, 25, chunks=[0, 3, 4])  # an interrupted run: 3 chunks stored, no completion mark
    with pytest.raises(StoreError, match="incomplete"):
        load_solutions(path)
    calls: list[int] = []
    got = solve_dask(CARM, P, client, out=path, resume=True, progress=lambda stage, done, total: calls.append(done))
    assert_same_batch(got, ref)
    n_chunks = -(-len(P) // 25)
    assert calls[0] == 75 and calls[-1] == len(P)  # the stored chunks counted first ...
    assert len(calls) == 1 + n_chunks - 3  # ... and only the missing ones solved
    assert store_info(path)["complete"]
    # resuming a complete store solves nothing and gives the same content
    calls.clear()
    assert_same_batch(solve_dask(CARM, P, client, out=path, resume=True, progress=lambda *a: calls.append(a[1])), ref)
    assert calls == [len(P)]
    # other poses than the stored ones are refused
    other = P.copy()
    other[80] = P[81]
    with pytest.raises(StoreError, match=r"poses \[75:100\] differ"):
        solve_dask(CARM, other, client, out=path, resume=True)


def test_store_that_cannot_be_resumed_is_refused_before_a_local_cluster_starts(
    carm_poses: tuple[np.ndarray, Any], tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import distributed

    def no_cluster(*args: Any, **kwargs: Any) -> None:
        raise AssertionError("a local cluster was started")

    monkeypatch.setattr(distributed, "LocalCluster", no_cluster)
    P, _ = carm_poses
    path = tmp_path / "s.zarr"
    write_store(path, CARM, P, 25, chunks=[0, 3])
    other = P.copy()
    other[80] = P[81]  # chunk 3 holds poses 75:100
    with pytest.raises(StoreError, match=r"poses \[75:100\] differ"):
        solve_dask(CARM, other, out=path, resume=True)
    with pytest.raises(StoreError, match="solver options"):
        solve_dask(CARM, P, out=path, resume=True, limits=False)
    with pytest.raises(StoreError, match="number of poses"):
        solve_dask(CARM, P[:-1], out=path, resume=True)
    with pytest.raises(StoreError, match="chunk_size 30"):
        solve_dask(CARM, P, out=path, resume=True, chunk_size=30)


def test_killed_worker_chunks_rerun(client: Client, carm_poses: tuple[np.ndarray, Any], tmp_path: Path) -> None:
    P, ref = carm_poses
    P, ref_list = np.concatenate([P] * 3), list(ref) * 3
    pids = client.run(os.getpid)
    victim = sorted(pids.values())[0]
    killed_at: list[int] = []

    def progress(stage: str, done: int, total: int) -> None:
        if done > 0 and not killed_at:
            os.kill(victim, signal.SIGKILL)  # one worker process dies while chunks are in flight
            killed_at.append(done)

    got = solve_dask(CARM, P, client, out=tmp_path / "s.zarr", chunk_size=40, progress=progress)
    assert killed_at and 0 < killed_at[0] < len(P) // 2
    assert len(got) == len(P) and store_info(tmp_path / "s.zarr")["complete"]
    for g, r in zip(got, ref_list, strict=True):
        np.testing.assert_array_equal(g.q, r.q)
        np.testing.assert_array_equal(g.error_geodesic, r.error_geodesic)
        assert g.reason == r.reason and len(g.families) == len(r.families)
    # the nanny replaced the dead worker: the cluster has two workers again, none of them the killed process
    client.wait_for_workers(2, timeout=WAIT_S)
    assert victim not in client.run(os.getpid).values()


def test_solve_dask_errors(client: Client, tmp_path: Path) -> None:
    P = CARM.fk(np.array([[800.0, 0.3, 0.2, -0.4, 0.5, 0.1]] * 50))
    with pytest.raises(UnknownOptionError, match="strategy"):
        solve_dask(CARM, P, client, strategy="fast")
    with pytest.raises(UnknownOptionError, match="reduction must be a name"):
        solve_dask(CARM, P, client, out=tmp_path / "r.zarr", reduction=CArmD1(CARM))
    with pytest.raises(UnknownOptionError, match="client must be"):
        solve_dask(CARM, P, client=42)
    with pytest.raises(UnknownOptionError, match="n_workers"):
        solve_dask(CARM, P, client, n_workers=2)
    with pytest.raises(UnknownOptionError, match="resume"):
        solve_dask(CARM, P, client, resume=True)
    # refused before the store is created: the corrected call is not met by "already exists"
    for bad_client, n_workers in ((42, None), (client, 2)):
        with pytest.raises(UnknownOptionError):
            solve_dask(CARM, P, bad_client, out=tmp_path / "refused.zarr", chunk_size=10, n_workers=n_workers)
        assert not (tmp_path / "refused.zarr").exists()
    from sweepik import ShapeError

    with pytest.raises(ShapeError, match=r"\(N, 4, 4\)"):
        solve_dask(CARM, P[0], client)
    (tmp_path / "taken.zarr").mkdir()
    with pytest.raises(StoreError, match="already exists"):
        solve_dask(CARM, P, client, out=tmp_path / "taken.zarr")
    # a pose that is not a rigid transform fails its chunk, named by its place in the run; the store stays incomplete
    bad = P.copy()
    bad[42, 0, 0] = 2.0
    with pytest.raises(InvalidPoseError, match=r"poses\[40:50\]"):
        solve_dask(CARM, bad, client, out=tmp_path / "bad.zarr", chunk_size=10)
    assert not store_info(tmp_path / "bad.zarr")["complete"]
    # an empty batch
    assert len(solve_dask(CARM, np.zeros((0, 4, 4)), client)) == 0


# --------------------------------------------------------------------------------------------------
# CLI
# --------------------------------------------------------------------------------------------------


def _cli(*args: str) -> list[str]:
    return [sys.executable, "-m", "sweepik.cli", *args]


def test_cli_sigint_half_way_then_resume(client: Client, tmp_path: Path) -> None:
    poses, store = str(tmp_path / "p.npy"), str(tmp_path / "s.zarr")
    assert main(["sample", "carm", "400", "--out", poses, "--seed", "5"]) == 0
    # the paper's strategy (~200 poses/s per core), 40 chunks: seconds of work on 2 workers, and the client writes
    # the chunks one after the other (~80 ms each), so the run is still going when the first chunk is stored
    run = ["solve", "carm", "--poses", poses, "--out", store, "--workers", "2", "--strategy", "paper"]
    proc = subprocess.Popen(_cli(*run, "--chunk-size", "10"), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + WAIT_S
        while time.monotonic() < deadline and proc.poll() is None:
            with contextlib.suppress(StoreError):  # (not created yet)
                if store_info(store)["stored"] >= 1:
                    break
            time.sleep(0.02)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=WAIT_S)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, err
    assert "interrupted" in err and "--resume" in err and "Traceback" not in err and "Warning" not in err
    info = store_info(store)
    assert not info["complete"] and 1 <= info["stored"] < info["n_chunks"]  # stopped mid-run
    with pytest.raises(StoreError, match="incomplete"):
        load_solutions(store)
    # without --resume the store is not touched
    done = subprocess.run(_cli(*run), capture_output=True, text=True, timeout=WAIT_S)
    assert done.returncode == 2 and "already exists" in done.stderr
    # --resume completes it (here on an existing cluster, by its address): the stored chunks are kept, the others solved
    resume = [*run[:-4], "--strategy", "paper", "--scheduler", client.scheduler.address, "--resume"]
    done = subprocess.run(_cli(*resume), capture_output=True, text=True, timeout=WAIT_S)
    assert done.returncode == 0, done.stderr
    assert "Warning" not in done.stderr and "Traceback" not in done.stderr
    assert "resumed:" in done.stdout and "poses:         400" in done.stdout and "not found:" in done.stdout
    assert "400/400 poses" in done.stderr  # the progress line (stderr, here a pipe: one line per 15 s and the last)
    P = np.load(poses)
    assert_same_batch(load_solutions(store), solve_many(CARM, P, strategy="paper"))


def test_cli_bad_values_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    poses = str(tmp_path / "p.npy")
    np.save(poses, CARM.fk(np.array([[800.0, 0.3, 0.2, -0.4, 0.5, 0.1]])))
    (tmp_path / "taken.zarr").mkdir()
    (tmp_path / "file").write_text("x")
    cases = [
        (["solve", "carm", "--poses", poses, "--workers", "2"], "go with --out"),
        (
            ["solve", "carm", "--poses", poses, "--out", "x.zarr", "--workers", "2", "--scheduler", "tcp://h:1"],
            "not both",
        ),
        (["solve", "carm", "--xyz", "1", "2", "3", "--out", str(tmp_path / "s.zarr")], "--xyz cannot go"),
        (["solve", "carm", "--out", str(tmp_path / "s.zarr")], "need --poses"),
        (["solve", "carm", "--poses", poses, "--out", str(tmp_path / "s.zarr"), "--workers", "0"], "--workers"),
        (["solve", "carm", "--poses", poses, "--out", str(tmp_path / "taken.zarr")], "already exists"),
        (["solve", "carm", "--poses", poses, "--out", str(tmp_path / "file")], "not a directory"),
        (["solve", "carm", "--poses", poses, "--out", str(tmp_path / "no" / "s.zarr")], "does not exist"),
        (["solve", "carm", "--poses", str(tmp_path / "none.npy"), "--out", str(tmp_path / "s.zarr")], "no such file"),
        (["solve", "carm", "--poses", poses, "--out", str(tmp_path / "s.zarr"), "--strategy", "x"], "strategy"),
        (["sample", "carm", "-5", "--out", str(tmp_path / "q.npy")], "number of poses"),
        (["sample", "carm", "abc", "--out", str(tmp_path / "q.npy")], "number of poses"),
        (["sample", "carm", "5", "6", "--out", str(tmp_path / "q.npy")], "sample takes"),
        (["sample", "carm", "5", "--out", str(tmp_path / "q.txt")], ".npy"),
        (["sample", "carm", "5", "--out", str(tmp_path / "q.npy"), "--q-out", str(tmp_path / "q.npy")], "same file"),
        (["sample", "carm", "5"], "--out"),
    ]
    for argv, message in cases:
        assert main(argv) == 2, argv
        err = capsys.readouterr().err
        assert message in err and err.count("\n") == 1, (argv, err)
    assert not (tmp_path / "s.zarr").exists()


def test_cli_sample(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = str(tmp_path / "p.npy")
    assert main(["sample", "ur5", "70000", "--out", out, "--seed", "3"]) == 0  # two blocks of configurations
    assert "seed 3" in capsys.readouterr().out
    P, q = np.load(out), np.load(tmp_path / "p.q.npy")
    assert P.shape == (70000, 4, 4) and q.shape == (70000, 6)
    np.testing.assert_array_equal(P, UR5.fk(q))
    assert np.all((q >= UR5.lower) & (q <= UR5.upper))
    # the same seed gives the same configurations, drawn as one block would be
    np.testing.assert_array_equal(q, np.random.default_rng(3).uniform(UR5.lower, UR5.upper, size=(70000, 6)))
    other = str(tmp_path / "o.npy")
    assert main(["sample", "ur5", "5", "--out", other, "--q-out", str(tmp_path / "o_q.npy")]) == 0
    assert "seed " in capsys.readouterr().out and np.load(tmp_path / "o_q.npy").shape == (5, 6)


def test_default_chunking_is_solve_many_bit_for_bit_on_a_swept_arm(client: Client, tmp_path: Path) -> None:
    """A swept 6R arm's store equals solve_many bit for bit (the default chunk size follows solve_many's batches; with
    the compiled engine a pose's samples do not depend on its batch anyway, see ``search.sample_grid``)."""
    import sweepik

    arm = sweepik.load_robot("fanuc_crx10ia")
    from sweepik.experiments.verify import random_configurations

    P = arm.fk(random_configurations(arm, 2500, np.random.default_rng(5)))
    assert_same_batch(solve_dask(arm, P, client, out=tmp_path / "f.zarr"), solve_many(arm, P))


@pytest.mark.parametrize("address", ["not an address", "tcp://localhost:notaport", "http://x:1"])
def test_malformed_scheduler_address_is_a_clear_error(address: str) -> None:
    with pytest.raises(sweepik_errors.SweepikError, match="address"):
        solve_dask(CARM, test_poses(CARM, 2, CARM_FAMILY_Q, seed=1), address)


def test_store_of_a_run_that_cannot_connect_is_removed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """A cluster that cannot be reached (or started) leaves no new store behind."""
    from sweepik import distributed

    @contextlib.contextmanager
    def unreachable(client: Any, n_workers: int | None) -> Iterator[Any]:
        raise sweepik_errors.SweepikError("cannot reach the Dask scheduler (test)")
        yield  # pragma: no cover

    monkeypatch.setattr(distributed, "_connected", unreachable)
    P = CARM.fk(np.array([[800.0, 0.3, 0.2, -0.4, 0.5, 0.1]] * 20))
    with pytest.raises(sweepik_errors.SweepikError, match="cannot reach"):
        solve_dask(CARM, P, "tcp://127.0.0.1:9", out=tmp_path / "s.zarr", chunk_size=10)
    assert not (tmp_path / "s.zarr").exists()


def test_the_local_cluster_is_kept_for_the_next_call(carm_poses: tuple[np.ndarray, Any]) -> None:
    """``client=None`` starts a local cluster once per process: a second call uses the same one (its client is the
    same object), a call with another size replaces it, and ``close_local_cluster`` stops it."""
    from sweepik import distributed

    P, _ = carm_poses
    distributed.close_local_cluster()
    try:
        first = solve_dask(CARM, P[:50], n_workers=1)
        kept = distributed._LOCAL[0][2]
        second = solve_dask(CARM, P[50:100], n_workers=1)
        assert distributed._LOCAL[0][2] is kept and len(distributed._LOCAL) == 1
        assert_same_batch(first, solve_many(CARM, P[:50]))
        assert_same_batch(second, solve_many(CARM, P[50:100]))
    finally:
        distributed.close_local_cluster()
    assert distributed._LOCAL == []


SCRIPT = """
import numpy as np
import sweepik
arm = sweepik.load_robot("carm")
q = arm.lower + np.random.default_rng(1).random((40, 6)) * (arm.upper - arm.lower)
{body}
"""


@pytest.mark.parametrize("guarded", [False, True])
def test_a_plain_script_works_guarded_or_not(guarded: bool, tmp_path: Path) -> None:
    """A script calling ``solve_dask`` at its top level, without ``if __name__ == "__main__":``: the local cluster
    runs in the script's own process, so nothing re-runs the script (with worker processes it failed with "Nanny
    failed to start"); guarded, the same."""
    call = "batch = sweepik.solve_dask(arm, arm.fk(q), n_workers=2)\nprint('solved', len(batch))"
    body = call if not guarded else "if __name__ == '__main__':\n    " + call.replace("\n", "\n    ")
    script = tmp_path / "script.py"
    script.write_text(SCRIPT.format(body=body))
    proc = subprocess.run([sys.executable, str(script)], capture_output=True, text=True, timeout=WAIT_S, cwd=tmp_path)
    assert proc.returncode == 0 and "solved 40" in proc.stdout, proc.stderr[-2000:]
    assert "Traceback" not in proc.stderr
