"""Issue 12's measurement: ``sweepik solve ROBOT --poses FILE --out STORE --workers W`` against in-process
``solve_many`` on the same poses, alternated (the machine's speed drifts between runs), with each process's peak
RSS and the store's content compared with ``solve_many``'s column by column.

    sweepik sample carm 1000000 --out /tmp/p.npy --seed 1
    python benchmarks/dask_throughput.py /tmp/p.npy [--robot carm] [--workers 2] [--rounds 3]

In-process time: ``solve_many`` on the memory-mapped file in a fresh process, after a warm-up solve of 4,096
poses (kernels loaded); Dask time: the CLI's whole run as a subprocess (interpreter start, cluster start, solving,
store writing and completion). Throughput ratio = in-process time / Dask time, per round.
"""

from __future__ import annotations

import argparse
import json
import shutil
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

import numpy as np
import psutil

IN_PROCESS = """
import json, sys, time
import numpy as np
import sweepik
from sweepik.io.store import merge_blocks
arm = sweepik.load_robot(sys.argv[1])
P = np.load(sys.argv[2], mmap_mode="r")
sweepik.solve_many(arm, np.ascontiguousarray(P[:4096]))
t = time.perf_counter()
batch = sweepik.solve_many(arm, P)
seconds = time.perf_counter() - t
if len(sys.argv) > 3:  # compare with the store
    a, b = merge_blocks(batch.blocks), merge_blocks(sweepik.load_solutions(sys.argv[3]).blocks)
    names = ("poses", "bounds", "q", "error", "error_geodesic", "within_limits", "multiplicity", "n_reachable")
    same = all(np.array_equal(getattr(a, n), getattr(b, n)) for n in names)
    same = same and {k: len(v) for k, v in a.families.items()} == {k: len(v) for k, v in b.families.items()}
    print(json.dumps({"seconds": seconds, "solutions": len(a.q), "identical": bool(same)}))
else:
    print(json.dumps({"seconds": seconds}))
"""


def peak_rss(cmd: list[str]) -> tuple[float, list[int], str]:
    """Run ``cmd``; its wall time, the peak RSS (MiB) of it and of each process it started, and its stdout."""
    t = time.perf_counter()
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True)
    peaks: dict[int, int] = {}

    def poll() -> None:
        me = psutil.Process(proc.pid)
        while proc.poll() is None:
            try:
                for p in [me, *me.children(recursive=True)]:
                    try:
                        peaks[p.pid] = max(peaks.get(p.pid, 0), p.memory_info().rss)
                    except psutil.Error:
                        pass
            except psutil.Error:
                pass
            time.sleep(0.2)

    watcher = threading.Thread(target=poll, daemon=True)
    watcher.start()
    out, _ = proc.communicate()
    seconds = time.perf_counter() - t
    watcher.join()
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed with status {proc.returncode}")
    return seconds, sorted(v >> 20 for v in peaks.values()), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("poses")
    ap.add_argument("--robot", default="carm")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--rounds", type=int, default=3)
    args = ap.parse_args()
    n = len(np.load(args.poses, mmap_mode="r"))
    tmp = Path(tempfile.mkdtemp())
    store = tmp / "s.zarr"
    sweepik = shutil.which("sweepik") or str(Path(sys.executable).with_name("sweepik"))
    for r in range(args.rounds):
        in_proc = json.loads(peak_rss([sys.executable, "-c", IN_PROCESS, args.robot, args.poses])[2])["seconds"]
        shutil.rmtree(store, ignore_errors=True)
        cmd = [sweepik, "solve", args.robot, "--poses", args.poses, "--out", str(store)]
        seconds, peaks, _ = peak_rss([*cmd, "--workers", str(args.workers)])
        print(
            f"round {r + 1}: in-process solve_many {in_proc:.2f} s ({n / in_proc:,.0f} poses/s); Dask CLI "
            f"{seconds:.2f} s ({n / seconds:,.0f} poses/s) = {100 * in_proc / seconds:.1f} %; peak RSS MiB "
            f"(processes of the CLI run): {peaks}",
            flush=True,
        )
    check = json.loads(peak_rss([sys.executable, "-c", IN_PROCESS, args.robot, args.poses, str(store)])[2])
    print(f"store == solve_many: {check['identical']} ({check['solutions']:,} solutions)")
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
