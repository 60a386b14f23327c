"""Batch runs on the command line: ``sweepik solve ... --poses FILE --out STORE`` (on Dask, into a store) and
``sweepik sample`` (random in-limit configurations and their poses, to try it on)."""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np

from sweepik.cli.common import (
    DEFAULT_ROBOT,
    PROGRESS_EVERY_S,
    CliInputError,
    _add_json,
    _add_robot_options,
    _check_output_path,
    _count,
    _load_robot,
    _nonnegative_int,
    _print_json,
    _Progress,
    _split_robot,
    _subparser,
    _SubParsers,
)
from sweepik.engine.settings import N_SAMPLES
from sweepik.model.robot import Robot

#: Exit status of a run stopped by Ctrl-C (SIGINT), as shells report it (128 + 2).
EXIT_INTERRUPTED = 130
#: Largest number of poses ``sweepik sample`` writes (2^31 - 1; 256 GiB of poses).
MAX_SAMPLES = 2**31 - 1
#: Configurations generated (and their poses computed) at a time by ``sweepik sample``: memory stays ~20 MB.
SAMPLE_BLOCK = 65_536
#: Write a progress line to a non-terminal stderr (a log file) this often (seconds; on a terminal the line is
#: redrawn at most every ``cli_common.PROGRESS_EVERY_S``).
PROGRESS_LOG_EVERY_S = 15.0


# --------------------------------------------------------------------------------------------------
# sweepik solve --out
# --------------------------------------------------------------------------------------------------


def add_store_options(p: argparse.ArgumentParser) -> None:
    """``--out``, ``--workers``, ``--scheduler``, ``--resume``, ``--chunk-size`` of ``sweepik solve``."""
    g = p.add_argument_group(
        "many poses on Dask, into a store",
        "with --out, the poses of --poses are solved on a Dask cluster and every solution is written to STORE "
        "(a Zarr directory; read it with sweepik.load_solutions); stdout gets a summary. Needs sweepik[dask].",
    )
    g.add_argument("--out", metavar="STORE", help="write the solutions of --poses to this store (a new directory)")
    g.add_argument(
        "--workers",
        type=_count(1, 4096),
        metavar="N",
        help="start a local Dask cluster in this process, one worker of N threads (default: one per core)",
    )
    g.add_argument("--scheduler", metavar="ADDRESS", help="use the Dask cluster at ADDRESS (e.g. tcp://host:8786)")
    g.add_argument("--resume", action="store_true", help="continue the interrupted run that wrote STORE")
    g.add_argument(
        "--chunk-size",
        type=_count(1, 2**31),
        metavar="N",
        help="poses per task and store chunk (default: about 8 chunks per worker, 64 to 16,384 poses)",
    )


def wants_store(args: argparse.Namespace) -> bool:
    """True when any option of :func:`add_store_options` is given (the run goes to :func:`cmd_solve_store`)."""
    return any(
        getattr(args, k, None) not in (None, False) for k in ("out", "workers", "scheduler", "resume", "chunk_size")
    )


class RateProgress(_Progress):
    """Progress of a batch run on stderr: a bar, poses done, rate and time left. On a terminal one line redrawn
    (at most every ``PROGRESS_EVERY_S``); elsewhere (a log file) one line every ``PROGRESS_LOG_EVERY_S``. The rate
    counts the poses solved by this run (not those resumed from the store)."""

    def __init__(self) -> None:
        super().__init__()
        self.tty = self.enabled
        self.first: int | None = None  # poses done when the run started (resumed ones)
        self.last = -1e9

    def __call__(self, stage: str, done: int, total: int) -> None:
        now = time.monotonic()
        if self.first is None:
            self.first = done
        every = PROGRESS_EVERY_S if self.tty else PROGRESS_LOG_EVERY_S
        if now - self.last < every and done < total:
            return
        self.last = now
        elapsed = max(now - self.start, 1e-9)
        rate = (done - self.first) / elapsed
        left = f"{_duration((total - done) / rate)} left" if rate > 0 and done < total else "--"
        if done >= total:
            left = f"done in {_duration(elapsed)}"
        width = 30
        filled = int(width * min(done, total) / max(total, 1))
        line = f"{stage} [{'#' * filled}{'.' * (width - filled)}] {done:,}/{total:,} poses  {rate:,.0f} poses/s  {left}"
        if self.tty:
            self.stream.write(f"\r{line}\x1b[K")
            self.open = done < total
            if not self.open:
                self.stream.write("\n")
        else:
            self.stream.write(line + "\n")
        self.stream.flush()


def _duration(seconds: float) -> str:
    s = int(round(seconds))
    if s < 60:
        return f"{s}s"
    if s < 3600:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s // 3600}h{s % 3600 // 60:02d}m"


def _store_poses(args: argparse.Namespace) -> Any:
    """The poses of ``--poses``: a ``.npy`` file by path (memory-mapped by solve_dask), others read whole."""
    others = [f"--{x}" for x in ("xyz", "matrix", "nearest", "tol") if getattr(args, x, None) is not None]
    others += ["--windings"] if getattr(args, "windings", False) else []
    if others:
        raise CliInputError(f"--out solves the poses of --poses FILE; {', '.join(others)} cannot go with it")
    if args.poses is None:
        raise CliInputError("--out, --workers, --scheduler, --resume and --chunk-size need --poses FILE")
    if Path(args.poses).suffix.lower() == ".npy":
        return args.poses
    from sweepik.trajectory import load_poses

    return load_poses(args.poses)


def cmd_solve_store(args: argparse.Namespace, robot: Robot, ik_kwargs: dict[str, Any]) -> int:
    """``sweepik solve ROBOT --poses FILE --out STORE [--workers N | --scheduler ADDRESS] [--resume]``."""
    if args.out is None:
        raise CliInputError("--workers, --scheduler, --resume and --chunk-size go with --out STORE")
    if args.workers is not None and args.scheduler is not None:
        raise CliInputError("give --workers N (a local cluster) or --scheduler ADDRESS (an existing one), not both")
    _check_output_path(args.out, directory=True)
    poses = _store_poses(args)
    from sweepik.distributed import _checked_options, close_local_cluster, run
    from sweepik.io.store import store_info

    options = _checked_options(robot, stored=True, n_samples=N_SAMPLES, **ik_kwargs)
    progress = RateProgress()
    try:
        summary, _ = run(
            robot,
            poses,
            client=args.scheduler,
            n_workers=args.workers,
            out=args.out,
            chunk_size=args.chunk_size,
            resume=args.resume,
            progress=progress,
            keep=False,
            options=options,
        )
    except KeyboardInterrupt:
        progress.close()
        try:
            info = store_info(args.out)
            where = f"{info['stored']} of {info['n_chunks']} chunks stored in {args.out}"
        except Exception:  # the store may not exist yet
            where = f"nothing stored in {args.out}"
        print(f"sweepik: interrupted: {where}; continue with --resume", file=sys.stderr)
        return EXIT_INTERRUPTED
    finally:
        progress.close()
        close_local_cluster()  # (the command's own cluster: stopped before the interpreter winds down)
    t = summary.totals
    if args.json:
        _print_json(
            {
                "store": str(args.out),
                "robot": robot.name,
                **t,
                "chunks": summary.n_chunks,
                "chunk_size": summary.chunk_size,
                "resumed_chunks": summary.resumed_chunks,
                "resumed_poses": summary.resumed_poses,
                "worker_threads": summary.threads,
                "seconds": summary.seconds,
            }
        )
        return 0
    n = max(t["poses"], 1)
    solved_now = t["poses"] - summary.resumed_poses
    print(
        f"solved {t['poses']:,} poses of {robot.name} into {args.out} ({summary.n_chunks:,} chunks of "
        f"{summary.chunk_size:,} poses; {summary.threads} worker threads)"
    )
    rows = [
        ("poses", f"{t['poses']:,}"),
        ("solutions", f"{t['solutions']:,} ({t['solutions'] / n:.2f} per pose)"),
        (
            ("unreachable", f"{t['unreachable']:,} poses (no solution at all)")
            if options["strategy"] == "precise"
            else ("not found", f"{t['unreachable']:,} poses (no solution found by the paper's strategy)")
        ),
        ("out of limits", f"{t['out_of_limits']:,} poses (solutions only outside the joint limits)"),
        ("families", f"{t['families']:,} poses with self-motion families"),
    ]
    if summary.resumed_chunks:
        rows.append(("resumed", f"{summary.resumed_chunks:,} chunks ({summary.resumed_poses:,} poses) already stored"))
    rate = solved_now / summary.seconds if summary.seconds > 0 else 0.0
    rows.append(("time", f"{summary.seconds:.1f} s ({rate:,.0f} poses/s)"))
    width = max(len(k) for k, _ in rows) + 1
    for key, value in rows:
        print(f"  {key + ':':<{width}} {value}")
    return 0


# --------------------------------------------------------------------------------------------------
# sweepik sample
# --------------------------------------------------------------------------------------------------


def add_sample_parser(sub: _SubParsers) -> None:
    p = _subparser(
        sub,
        "sample",
        help="random in-limit configurations and their poses (.npy or .csv), e.g. for 'solve --poses'",
        description=(
            "Draw N configurations uniformly inside the joint limits and write their tool poses (N, 4, 4) to "
            "--out (.npy, or .csv: one pose per row, 16 numbers row-major) and the configurations (N, n_joints; "
            "radians and the robot's length unit) next to it, as <name>.q.npy / <name>.q.csv (or --q-out). ROBOT "
            f"is a bundled robot or a robot file (default: {DEFAULT_ROBOT})."
        ),
    )
    p.add_argument("values", nargs="+", metavar="[ROBOT] N", help="robot (optional), then the number of poses")
    p.add_argument("--out", required=True, metavar="FILE", help="poses file to write (.npy or .csv)")
    p.add_argument("--q-out", metavar="FILE", help="configurations file to write (default: <out>.q.npy / .q.csv)")
    p.add_argument("--seed", type=_nonnegative_int, metavar="S", help="random seed (default: a fresh one, printed)")
    _add_robot_options(p)
    _add_json(p, ": the files written, the seed")


class _SampleWriter:
    """Rows written block by block into ``path``: a memory-mapped ``.npy`` of ``shape``, or CSV text (a pose as its
    16 numbers row-major, as ``load_poses`` reads them; a configuration as its n values), 17 significant digits."""

    def __init__(self, path: str, shape: tuple[int, ...]) -> None:
        self.path, self.shape = path, shape
        self.csv = path.lower().endswith(".csv")

    def __enter__(self) -> _SampleWriter:
        if self.csv:
            self.fh: Any = open(self.path, "w", encoding="utf-8")  # noqa: SIM115 - closed in __exit__
        else:
            self.fh = np.lib.format.open_memmap(self.path, mode="w+", dtype=np.float64, shape=self.shape)
        return self

    def write(self, start: int, rows: np.ndarray) -> None:
        if self.csv:
            np.savetxt(self.fh, rows.reshape(len(rows), -1), delimiter=",", fmt="%.17g")
        else:
            self.fh[start : start + len(rows)] = rows

    def __exit__(self, *exc: object) -> None:
        if self.csv:
            self.fh.close()
        else:
            self.fh.flush()
            del self.fh


def cmd_sample(args: argparse.Namespace) -> int:
    from sweepik.experiments.verify import random_configurations

    name, tokens = _split_robot(args.values)
    if len(tokens) != 1:
        raise CliInputError(f"sample takes [ROBOT] N (one number of poses), got {' '.join(args.values)!r}")
    try:
        n = _count(1, MAX_SAMPLES)(tokens[0])
    except argparse.ArgumentTypeError as exc:
        raise CliInputError(f"N (number of poses): {exc}") from None
    out = args.out
    suffix = ".csv" if out.lower().endswith(".csv") else ".npy"
    stem = out[: -len(suffix)] if out.lower().endswith(suffix) else out
    q_out = args.q_out or stem + ".q" + suffix
    _check_output_path(out, suffixes=(".npy", ".csv"))
    _check_output_path(q_out, suffixes=(".npy", ".csv"))
    if Path(out).resolve() == Path(q_out).resolve():
        raise CliInputError(f"--out and --q-out name the same file {out!r}")
    robot = _load_robot(name, args)
    seed = args.seed if args.seed is not None else int(np.random.SeedSequence().entropy % 2**63)  # type: ignore[operator]
    rng = np.random.default_rng(seed)
    random_configurations(robot, 0, rng)  # refuses a robot without finite limits before any file is written
    with _SampleWriter(out, (n, 4, 4)) as poses, _SampleWriter(q_out, (n, robot.n_joints)) as qs:
        for s in range(0, n, SAMPLE_BLOCK):
            q = random_configurations(robot, min(SAMPLE_BLOCK, n - s), rng)
            qs.write(s, q)
            poses.write(s, robot.fk(q))
    text = (
        f"sampled {n:,} configurations of {robot.name} inside its joint limits (seed {seed}): poses (N, 4, 4) -> "
        f"{out}, configurations (N, {robot.n_joints}; radians, {robot.length_unit}) -> {q_out}"
    )
    if args.json:
        _print_json({"robot": robot.name, "n": n, "seed": seed, "poses": out, "configurations": q_out})
    else:
        print(text)
    return 0
