"""The compiled kernels are cached on disk: a second process solving the same arms compiles nothing.

A kernel that is recompiled in every process (e.g. a compiled loop taking another compiled function as a plain
dispatcher argument) costs seconds before each first solve and grows the cache: Numba reports each save with
``NUMBA_DEBUG_CACHE=1``.
"""

from __future__ import annotations

import os
import subprocess
import sys

SCRIPT = """
import numpy as np, sweepik
for name, kw in (("ur5", {}), ("carm", {"reduction": "auto"}), ("fanuc_crx10ia", {}), ("carm", {}), ("puma560", {})):
    robot = sweepik.load_robot(name)
    sweepik.solve(robot, robot.fk(np.full(6, 0.3)), **kw)
    sweepik.solve_many(robot, robot.fk(np.full((70, 6), 0.3)), **kw)
"""


def test_second_process_compiles_nothing():
    env = dict(os.environ, NUMBA_DEBUG_CACHE="1")
    run = [sys.executable, "-c", SCRIPT]
    first = subprocess.run(run, capture_output=True, text=True, env=env, timeout=900)
    assert first.returncode == 0, first.stderr
    second = subprocess.run(run, capture_output=True, text=True, env=env, timeout=900)
    assert second.returncode == 0, second.stderr
    saved = [line for line in second.stdout.splitlines() if "data saved" in line]
    assert not saved, saved
