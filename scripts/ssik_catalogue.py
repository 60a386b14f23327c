"""sweepik on ssik's prebuilt catalogue of vendors' arms: recall and wrong answers (issue 35).

Each prebuilt ssik arm (``ssik.list_arms()``) is rebuilt in sweepik in origin + axis form from the artifact's own
per-joint constants (``T_left[i] @ Rot(axis_i, q_i) @ T_right[i]``), lengths in metres; its FK is checked against the
artifact's ``fk``. For every six-joint arm: random configurations (uniform over [-pi, pi)) and configurations on
singular sets (``tests/singular.py``), limits off; each pose solved once by ``sweepik.solve`` must give back the
generating configuration (recall, ``singular.recovered``) and every solution must reproduce the pose (wrong); "slow"
counts solves over ``--slow`` seconds, first solves included (an arm's kernels load on its first poses).
``--agreement``: the solution sets compared with ssik's own solver's (:class:`Agreement`).

    python scripts/ssik_catalogue.py [--n 50] [--singular 0] [--arms ur5_ik ...] [--rewrite] [--seed 0] [--agreement]

``--rewrite`` rewrites each arm at random first (axis reversals, zero offsets, base/tool transforms, millimetres):
the recall must not change.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests"))

from catalogue import check_fk, robot_from_ssik, ssik_module  # noqa: E402
from rewrites import rewrite  # noqa: E402
from singular import one_root, recovered, singular_configurations  # noqa: E402

import sweepik  # noqa: E402
from sweepik.engine.settings import ACCEPT_TOL_REL  # noqa: E402
from sweepik.model.robot import Robot  # noqa: E402


def _root_near(robot: Robot, x: np.ndarray, T: np.ndarray) -> np.ndarray | None:
    """The root of ``T`` that ``x`` is an approximation of: SciPy's Levenberg-Marquardt on the pose error (position
    over the length scale, rotation vector) from ``x``, if it gets the pose to the certification's tolerance
    (``settings.ACCEPT_TOL_REL``, 2e-13: what sweepik asks of its own solutions) within 1e-3 of ``x``; else None
    (``x`` misses the pose and no root lies next to it). (At 1e-12, points of flat valleys next to the singular set
    counted: on the big YAM, pairs 2e-3 either side of a double root sweepik gives, each stopping at 8e-13.)"""
    from scipy.optimize import least_squares
    from scipy.spatial.transform import Rotation

    L = robot.length_scale

    def residual(v: np.ndarray) -> np.ndarray:
        F = robot.fk(v)
        rot = Rotation.from_matrix(T[:3, :3].T @ F[:3, :3]).as_rotvec()
        return np.concatenate([(F[:3, 3] - T[:3, 3]) / L, rot])

    fit = least_squares(residual, x, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=400)
    moved = np.max(np.abs(fit.x - x) / np.where(robot.is_revolute, 1.0, L))
    ok = np.max(np.abs(residual(fit.x))) <= ACCEPT_TOL_REL and moved <= 1e-3
    return fit.x if ok else None


class Agreement:
    """Set agreement with ssik's own solver (``--agreement``): per pose without a continuum, sweepik's solution set
    and ssik's (``solve(T, respect_limits=False, enumerate_windings=False)``) compared by
    ``oracles.unmatched_solutions``; every solution only ssik has is polished (:func:`_root_near`): where it lands on
    a root of the pose that sweepik's answer does not hold (``singular.recovered``: the same root to the precision the
    pose fixes it, an arc of rounding-level solutions included) it is a miss of sweepik's, else ssik's error (a
    configuration missing the pose by 1e-10 ... 1e-6, or a second copy of a root sweepik has). One only sweepik has
    (each passed sweepik's certification) is a miss of ssik's, unless it is the same root as another of sweepik's
    solutions (``singular.one_root``: a second copy, counted apart as ``close``). Poses with a continuum are counted
    apart.

    ``same``: poses whose two sets match solution for solution; ``right``: poses where sweepik lacks no root ssik
    found and gives none twice (the differences left are ssik's: a solution off the pose, a second copy, a
    root it lacks)."""

    def __init__(self) -> None:
        self.same = self.right = self.poses = self.continua = 0
        self.ssik_only_ok = self.ssik_only_bad = self.ours_only = self.close = 0

    def add(self, name: str, robot: Robot, solver_robot: Robot, q: np.ndarray, sols, rw) -> None:  # type: ignore[no-untyped-def]
        from oracles import unmatched_solutions

        if sols.families:
            self.continua += 1
            return
        m = ssik_module(name)
        theirs = [x.q for x in m.solve(robot.fk(q), respect_limits=False, enumerate_windings=False)]
        ref = np.array(theirs, dtype=np.float64).reshape(-1, robot.n_joints)
        if rw is not None:
            ref = rw.forward(ref)
        extra_ours, extra_theirs = unmatched_solutions(sols.q, sols.multiplicity, ref, solver_robot)
        self.poses += 1
        self.same += not (extra_ours or extra_theirs)
        self.ours_only += len(extra_ours)
        close = sum(
            any(one_root(solver_robot, x, s) for s in sols.q if np.any(s != x)) for x in map(np.asarray, extra_ours)
        )
        self.close += close
        T = solver_robot.fk(rw.forward(q[None])[0] if rw is not None else q)
        lacks = 0
        for x in extra_theirs:
            root = _root_near(solver_robot, x, T)
            missed = root is not None and not recovered(solver_robot, sols, root)
            lacks += missed
            self.ssik_only_bad += not missed
        self.ssik_only_ok += lacks
        self.right += not (lacks or close)

    def merge(self, other: Agreement) -> None:
        for k, v in vars(other).items():
            setattr(self, k, getattr(self, k) + v)

    def line(self) -> str:
        if not (self.poses or self.continua):
            return ""
        return (
            f"  same sets {self.same}/{self.poses}, sweepik's right {self.right} (continua {self.continua}); only "
            f"ssik: {self.ssik_only_ok} roots sweepik lacks, {self.ssik_only_bad} not; only sweepik {self.ours_only} "
            f"({self.close} the same root as another)"
        )


def main() -> None:
    import ssik

    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=50)
    ap.add_argument("--arms", nargs="*", default=None)
    ap.add_argument("--rewrite", action="store_true")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--singular", type=int, default=0, help="configurations on (and near) the singular set per arm")
    ap.add_argument("--slow", type=float, default=0.05, help="report solves slower than this (s)")
    ap.add_argument("--agreement", action="store_true", help="compare each solution set with ssik's own solve")
    args = ap.parse_args()
    names = args.arms or [a.name for a in ssik.list_arms() if a.dof == 6]
    total = total_rec = 0
    overall = Agreement()
    for name in names:
        rng = np.random.default_rng(args.seed)
        robot = robot_from_ssik(name)
        fk_err = check_fk(robot, name, rng)
        Q = rng.uniform(-np.pi, np.pi, (args.n, robot.n_joints))
        if args.singular:
            Q = np.concatenate([Q, singular_configurations(robot, args.singular, rng)])
        solver_robot, Qs = robot, Q
        if args.rewrite:
            rw = rewrite(robot, rng)
            solver_robot, Qs = rw.robot, rw.forward(Q)
        try:
            a = sweepik.analyze(solver_robot)
            c = a["chosen"]
            plan = (a["structure"], c and (c["family"], c["free_joint"], c["chain"], c["case"]), a["reason"])
        except Exception as exc:  # noqa: BLE001
            plan = f"refused: {exc}"
        T = solver_robot.fk(Qs)
        rec = wrong = slow = 0
        misses = []
        agree = Agreement()
        t0 = time.perf_counter()
        for i, (t, q) in enumerate(zip(T, Qs, strict=True)):
            t1 = time.perf_counter()
            try:
                s = sweepik.solve(solver_robot, t, limits=False)
            except sweepik.SweepikError:
                misses.append(i)
                continue
            dt = time.perf_counter() - t1
            slow += dt > args.slow
            ok = recovered(solver_robot, s, q)
            rec += ok
            if not ok:
                misses.append(i)
            if len(s):
                wrong += int((s.error_geodesic > 1e-9 * solver_robot.length_scale).sum())
            if args.agreement:
                agree.add(name, robot, solver_robot, Q[i], s, rw if args.rewrite else None)
        dt = time.perf_counter() - t0
        total += len(Q)
        total_rec += rec
        print(
            f"{name:24s} fk {fk_err:.1e}  recall {rec:3d}/{len(Q)}  wrong {wrong}  slow {slow}  "
            f"{dt / len(Q) * 1e3:6.2f} ms/pose  {str(plan)[:70]}  misses {misses[:6]}{agree.line()}",
            flush=True,
        )
        overall.merge(agree)
    print(f"total recall {total_rec}/{total} ({100 * total_rec / max(total, 1):.2f} %){overall.line()}")


if __name__ == "__main__":
    main()
