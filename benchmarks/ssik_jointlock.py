"""ssik 8.2's joint-lock solver (``ssik.solvers.jointlock.seven_r.solve``, one lock value a call) on its prebuilt
seven-joint arms: the time a pose and whether its answer holds the configuration the pose was made from, to set
against ``benchmarks/lock_values.py`` (sweepik with a new lock value every pose). Run from the repository root
(``pip install -e '.[bench]'``).

    python benchmarks/ssik_jointlock.py [--n 30] [--locks franka_panda_ik:5 gen3_ik:6 ...]

Each lock ``arm:joint`` (joint index from 0): ``--n`` configurations uniform within the artifact's limits, their
poses by the artifact's ``fk``, each solved with that joint locked at its value (``lock_samples=[value]``,
``lock_idx=joint``, the artifact's baked ``KinBody``). A lock whose answers mostly miss the configuration is not a
fair reference (the solver may want a chain normalised otherwise): the recovered count says so.
"""

from __future__ import annotations

import argparse
import importlib
import time

import numpy as np

LOCKS = ["franka_panda_ik:5", "franka_panda_ik:0", "franka_panda_ik:6", "iiwa14_ik:2", "gen3_ik:6", "gen3_ik:0"]


def main() -> None:
    import ssik
    from ssik.solvers.jointlock import seven_r

    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=30)
    ap.add_argument("--locks", nargs="*", default=LOCKS)
    args = ap.parse_args()
    paths = {a.name: a.import_path for a in ssik.list_arms()}
    for lock in args.locks:
        name, joint = lock.split(":")
        k = int(joint)
        mod = importlib.import_module(paths[name])
        kb = mod._KB
        rng = np.random.default_rng(0)
        limits = [j.limits if j.limits is not None else (-np.pi, np.pi) for j in kb.joints]
        q = np.array([[rng.uniform(*lim) for lim in limits] for _ in range(args.n)])
        poses = [mod.fk(qq) for qq in q]
        seven_r.solve(kb, poses[0], lock_samples=[q[0, k]], lock_idx=k)  # (loaded)
        found = 0
        t0 = time.perf_counter()
        for qq, T in zip(q, poses, strict=True):
            sols, _ = seven_r.solve(kb, T, lock_samples=[qq[k]], lock_idx=k)
            d = [np.abs(np.angle(np.exp(1j * (np.asarray(s.q) - qq)))).max() for s in sols]
            found += bool(d) and min(d) < 1e-6
        dt = (time.perf_counter() - t0) / args.n
        print(f"{name} joint {k}: {dt * 1e3:.2f} ms a pose, configuration recovered {found}/{args.n}", flush=True)


if __name__ == "__main__":
    main()
