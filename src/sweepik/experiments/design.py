"""``sweepik design``: compare candidate mechanisms over one task, the paper's design argument made a tool.

The paper (sections 2 and 7) chose the C-Arm for its actuator sizes and safety rather than for a closed-form IK.
:func:`compare_designs` measures, for each candidate arm, over the same task:

* **IK**: the decomposition solve uses (closed form, or a 1-D sweep over which joint), seconds per pose, the
  histogram of solutions per pose, the share of task poses reached, with a multiple root or a self-motion family,
  and how many of the solutions that reach a pose keep within the joint limits;
* **workspace**: the reachable volume of the tool point (:func:`sweepik.experiments.workspace.workspace_volume`, with
its
  uncertainty) and, for the maps, every task pose's position with its number of solutions;
* **effort**: the static joint torques (prismatic joints: forces) holding a payload at the tool and, when the
  robot file gives them, the link masses (:func:`sweepik.experiments.statics.gravity_torques`), at every in-limit
  solution of
  every task pose: per joint, the largest, percentiles and mean of ``|tau|``;
* **manipulability**: at the same configurations, Yoshikawa's ``w = sqrt(det(J J^T))`` and the smallest singular
  value of the Jacobian (distance to a singularity), with J in SI units (m per rad or per m; rad per rad).

**The task** is one set of tool poses that every candidate solves. By default ``samples`` poses of random
configurations drawn uniformly inside the joint limits, an equal share from each candidate, so that every
candidate's workspace is represented and a pose one design cannot reach counts against it. ``poses`` gives the
task instead; ``region`` keeps only task poses whose position lies in a box. Lengths given to this module
(``poses``, ``region``, ``payload_com``) are in the **first candidate's length unit**; each candidate gets them in
its own unit. All candidates share the world frame (each robot file's ``[base]`` places its arm in it).
"""

from __future__ import annotations

import time
import zlib
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import LockedJointError, UnknownOptionError
from sweepik.experiments.statics import gravity_torques, torque_units
from sweepik.experiments.verify import random_configurations
from sweepik.experiments.workspace import workspace_volume
from sweepik.io.robot_file import load_robot
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import as_float_array, check_bool, check_int, check_poses
from sweepik.reductions import get_reduction
from sweepik.reductions.analysis import analyze, plan_line
from sweepik.solving import solve_many

__all__ = ["compare_designs", "DesignComparison", "Candidate", "jacobian_singular_values", "MAX_DESIGN_SAMPLES"]

Array = NDArray[np.float64]
Progress = Callable[[str, int, int], None]

#: Largest task (poses) and workspace sample (configurations) accepted.
MAX_DESIGN_SAMPLES = 1_000_000
MAX_WORKSPACE_SAMPLES = 10_000_000
#: Seconds per pose: the best of ``TIMING_REPEATS`` runs of ``solve_many`` on the first ``TIMED_POSES`` task poses,
#: after the whole task was solved once (which compiles what the arm needs, whatever the batch size).
TIMED_POSES = 2048
TIMING_REPEATS = 3
#: With ``region``: draw at most ``REGION_TRIES`` times ``max(share, REGION_DRAW)`` configurations of a candidate
#: looking for its share of poses inside it (a candidate that puts none there simply adds none to the task).
REGION_TRIES = 50
REGION_DRAW = 2000
#: Percentiles of |tau| and of the manipulability measures reported.
PERCENTILES = (5, 50, 95, 99)


def _no_progress(stage: str, done: int, total: int) -> None:
    return None


@dataclass(frozen=True)
class Candidate:
    """The measurements of one candidate arm over the task (plain values; ``to_dict`` for JSON)."""

    robot: Robot
    decomposition: dict[str, Any]
    ik: dict[str, Any]
    solutions_per_pose: NDArray[np.intp]
    #: Every in-limit solution of every task pose ``(K, n)``, where effort and manipulability are measured.
    solutions_q: Array
    workspace: dict[str, Any]
    effort: dict[str, Any]
    manipulability: dict[str, Any]

    @property
    def name(self) -> str:
        return self.robot.name

    def to_dict(self) -> dict[str, Any]:
        r = self.robot
        return {
            "name": r.name,
            "description": r.description,
            "joints": [
                {"name": n, "type": j.type, "mass_kg": j.mass} for n, j in zip(r.joint_names, r.joints, strict=True)
            ],
            "length_unit": r.length_unit,
            "gravity": list(r.gravity),
            "decomposition": self.decomposition,
            "ik": self.ik,
            "solutions_per_pose": self.solutions_per_pose.tolist(),
            "workspace": self.workspace,
            "effort": self.effort,
            "manipulability": self.manipulability,
        }


@dataclass(frozen=True)
class DesignComparison:
    """What :func:`compare_designs` returns: the task, the candidates' measurements, and the verdicts."""

    candidates: list[Candidate]
    task: dict[str, Any]
    #: Task positions ``(N, 3)`` in the first candidate's length unit (world frame), for the maps.
    positions: Array
    payload: dict[str, Any]
    verdicts: list[dict[str, Any]] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        return {
            "task": self.task,
            "payload": self.payload,
            "candidates": [c.to_dict() for c in self.candidates],
            "verdicts": self.verdicts,
            "positions": self.positions.tolist(),
        }


# --------------------------------------------------------------------------------------------------
# The task
# --------------------------------------------------------------------------------------------------


def _scale(robot: Robot, unit_robot: Robot) -> float:
    """Length units of ``robot`` per length unit of ``unit_robot``."""
    return mm_per_unit(unit_robot.length_unit) / mm_per_unit(robot.length_unit)


def _in_unit(poses: Array, factor: float) -> Array:
    out = np.array(poses, dtype=np.float64)
    out[..., :3, 3] *= factor
    return out


def _check_region(region: ArrayLike | None) -> Array | None:
    if region is None:
        return None
    box = as_float_array(region, "region")
    if box.shape != (3, 2) or not np.all(np.isfinite(box)) or np.any(box[:, 0] >= box[:, 1]):
        raise UnknownOptionError(
            "region must be [[xmin, xmax], [ymin, ymax], [zmin, zmax]] (finite, each min below its max), "
            f"got {region!r}"
        )
    return box


def _inside(poses: Array, box: Array | None) -> NDArray[np.bool_]:
    if box is None:
        return np.ones(poses.shape[0], dtype=bool)
    p = poses[:, :3, 3]
    return np.asarray(np.all((p >= box[:, 0]) & (p <= box[:, 1]), axis=-1))


def _task(
    robots: list[Robot], samples: int, poses: ArrayLike | None, box: Array | None, rng: np.random.Generator
) -> tuple[Array, str]:
    """Task poses in the first robot's unit and a sentence saying where they come from."""
    first = robots[0]
    if poses is not None:
        P = check_poses(poses, "poses")
        if P.ndim == 2:
            P = P[None]
        keep = _inside(P, box)
        if not np.any(keep):
            raise UnknownOptionError("no task pose lies inside the region")
        return P[keep], f"{int(keep.sum())} given poses" + (" inside the region" if box is not None else "")
    share = [samples // len(robots) + (1 if i < samples % len(robots) else 0) for i in range(len(robots))]
    parts = []
    for robot, n in zip(robots, share, strict=True):
        factor = 1.0 / _scale(robot, first)
        found: list[Array] = []
        got = 0
        draw = n if box is None else max(n, REGION_DRAW)
        for _ in range(REGION_TRIES if box is not None and n > 0 else 1):
            T = _in_unit(robot.fk(random_configurations(robot, draw, rng)), factor)
            T = T[_inside(T, box)]
            found.append(T[: n - got])
            got += len(found[-1])
            if got >= n:
                break
        parts.append(np.concatenate(found))
    P = np.concatenate(parts)
    if P.shape[0] == 0:
        raise UnknownOptionError(
            "no candidate puts its tool inside the region in "
            f"{REGION_TRIES * REGION_DRAW:,} random configurations: the task is empty"
        )
    counts = ", ".join(f"{len(p)} of {r.name}" for p, r in zip(parts, robots, strict=True))
    where = " with the tool inside the region" if box is not None else ""
    return P, f"poses of random in-limit configurations{where} ({counts})"


# --------------------------------------------------------------------------------------------------
# Measurements
# --------------------------------------------------------------------------------------------------


def _stats(x: Array) -> dict[str, Any]:
    """max, min, mean and ``PERCENTILES`` of ``x`` (None each when empty)."""
    if x.size == 0:
        return {"n": 0, "max": None, "min": None, "mean": None, **{f"p{p}": None for p in PERCENTILES}}
    out: dict[str, Any] = {"n": int(x.size), "max": float(x.max()), "min": float(x.min()), "mean": float(x.mean())}
    out.update({f"p{p}": float(v) for p, v in zip(PERCENTILES, np.percentile(x, PERCENTILES), strict=True)})
    return out


def _check_solvable(robot: Robot) -> None:
    """LockedJointError / NoReductionError (naming the arm) if ``solve`` cannot solve this candidate."""
    if robot.n_joints != 6:
        raise LockedJointError(
            f"candidate {robot.name!r} has {robot.n_joints} joints; design compares six-joint arms: write it with "
            "joints held, e.g. 'sweepik convert ROBOT --lock NAME=VALUE -o arm6.toml', and compare that file"
        )
    get_reduction(robot, None, None)


def _decomposition(robot: Robot) -> dict[str, Any]:
    red = get_reduction(robot, None, None)
    info = analyze(robot)
    chosen = info.get("chosen")
    if red.closed_form:
        kind, free = "closed form", None
    else:
        kind, free = "1-D sweep", robot.joint_names[red.free_joint]
    return {
        "kind": kind,
        "free_joint": free,
        "free_joint_number": None if free is None else red.free_joint + 1,
        "reduction": red.name,
        "branches": int(red.n_branches),
        "structure": info["structure"],
        "automatic": plan_line(chosen) if chosen else None,
    }


def _ik(robot: Robot, P: Array) -> tuple[dict[str, Any], Any]:
    t0 = time.perf_counter()
    batch = solve_many(robot, P)
    first = time.perf_counter() - t0  # with the one-off compilation of what this arm needs
    timed = P[:TIMED_POSES]
    runs = []
    for _ in range(TIMING_REPEATS):
        t0 = time.perf_counter()
        solve_many(robot, timed)
        runs.append((time.perf_counter() - t0) / max(timed.shape[0], 1))
    counts = batch.counts
    n = len(batch)
    hist = np.bincount(counts) if n else np.zeros(1, dtype=np.intp)
    multiple = np.zeros(n, dtype=bool)
    if batch.q.shape[0]:
        multiple[batch.pose_index[batch.multiplicity > 1]] = True
    families = np.zeros(n, dtype=bool)
    families[list(batch.families)] = True
    reaching = int(batch.n_reachable.sum())
    ik = {
        "n_poses": n,
        "seconds_per_pose": min(runs),
        "seconds_per_pose_runs": runs,
        "first_call_seconds": first,
        "solutions_histogram": {str(k): int(v) for k, v in enumerate(hist) if v},
        "mean_solutions": float(counts[counts > 0].mean()) if np.any(counts > 0) else None,
        "max_solutions": int(counts.max()) if n else 0,
        "reached_share": float(np.mean((counts > 0) | families)) if n else 0.0,
        "multiple_root_share": float(multiple.mean()) if n else 0.0,
        "self_motion_share": float(families.mean()) if n else 0.0,
        "solutions_ignoring_limits": reaching,
        "solutions_within_limits": int(counts.sum()),
        "within_limits_share": float(counts.sum() / reaching) if reaching else None,
    }
    return ik, batch


def _effort(robot: Robot, q: Array, payload: float, com: Array, links: bool) -> dict[str, Any]:
    tau = gravity_torques(robot, q, payload=payload, payload_com=com, links=links)
    rev = np.abs(tau[:, robot.is_revolute])
    return {
        "n_configurations": int(q.shape[0]),
        "units": torque_units(robot),
        "per_joint": [{"joint": name, **_stats(np.abs(tau[:, i]))} for i, name in enumerate(robot.joint_names)],
        # per configuration, the largest torque of any revolute joint (N·m; forces of prismatic joints apart)
        "largest": _stats(rev.max(axis=1)) if rev.size else _stats(np.zeros(0)),
    }


def jacobian_singular_values(robot: Robot, q: Array) -> Array:
    """Singular values ``(K, min(6, n))`` of the geometric Jacobian at ``q (K, n)``, largest first, with its linear
    rows in metres (per radian, or per metre for a prismatic joint): SI units whatever the robot's unit."""
    if q.shape[0] == 0:
        return np.zeros((0, min(6, robot.n_joints)))
    J = robot.jacobian(q)
    J[:, :3, robot.is_revolute] *= mm_per_unit(robot.length_unit) / 1000.0  # a prismatic column is m/m already
    return np.asarray(np.linalg.svd(J, compute_uv=False), dtype=np.float64)


def _manipulability(robot: Robot, q: Array) -> dict[str, Any]:
    s = jacobian_singular_values(robot, q)
    w = np.prod(s, axis=-1)
    return {
        "n_configurations": int(q.shape[0]),
        "yoshikawa": _stats(w),
        "sigma_min": _stats(s[:, -1]),
        "inverse_condition": _stats(s[:, -1] / np.maximum(s[:, 0], np.finfo(float).tiny)),
    }


def _measure(
    robot: Robot,
    P: Array,
    payload: float,
    com: Array,
    links: bool,
    workspace_samples: int,
    rng: np.random.Generator,
) -> Candidate:
    ik, batch = _ik(robot, P)
    q = batch.q
    volume = workspace_volume(robot, workspace_samples, rng=rng)  # rng: this candidate's own stream
    return Candidate(
        robot=robot,
        decomposition=_decomposition(robot),
        ik=ik,
        solutions_per_pose=np.asarray(batch.counts, dtype=np.intp),
        solutions_q=q,
        workspace=volume.to_dict(),
        effort=_effort(robot, q, payload, com, links),
        manipulability=_manipulability(robot, q),
    )


# --------------------------------------------------------------------------------------------------
# Verdicts
# --------------------------------------------------------------------------------------------------


#: Two measurements closer than this fraction of the larger are a tie (sampling noise, not a design difference);
#: timings, noisier, use ``TIME_TIE``.
TIE = 0.01
TIME_TIE = 0.1
#: Reachable volumes differ only if they are further apart than this many times the sum of their uncertainties (an
#: estimate from few samples can sit low by about its uncertainty).
VOLUME_MARGIN = 2.0
#: A holding effort below this fraction of the largest in the comparison is rounding noise: zero.
EFFORT_NOISE = 1e-9


def _best(
    values: list[float | None], larger: bool, margin: list[float] | None = None, tie: float = TIE, floor: float = 0.0
) -> tuple[int | None, bool]:
    """Index of the best value and whether it beats every other by more than their combined margins (or, without
    margins, by more than ``tie`` times the larger magnitude), and by more than ``floor`` (the noise level)."""
    known = {i: float(v) for i, v in enumerate(values) if v is not None}
    if len(known) < len(values) or not known:  # a candidate without the measurement (no pose reached): no verdict
        return None, False
    pick = (max if larger else min)(known, key=lambda i: known[i])
    best = known[pick]
    clear = True
    for i, v in known.items():
        if i == pick:
            continue
        gap = abs(best - v)
        tol = (margin[pick] + margin[i]) if margin is not None else tie * max(abs(best), abs(v))
        clear &= gap > max(tol, floor)
    return pick, clear


def _verdict(
    cands: list[Candidate],
    what: str,
    values: list[float | None],
    larger: bool,
    fmt: Callable[[float], str],
    margin: list[float] | None = None,
    why: str = "",
    tie: float = TIE,
    floor: float = 0.0,
) -> dict[str, Any]:
    pick, clear = _best(values, larger, margin, tie, floor)
    shown = {c.name: (None if v is None else fmt(v)) for c, v in zip(cands, values, strict=True)}
    winner = None if pick is None or not clear else cands[pick].name
    return {
        "criterion": what,
        "better": "larger" if larger else "smaller",
        "winner": winner,
        "values": shown,
        "why": why,
    }


def _unit_format(unit: str) -> Callable[[float], str]:
    return lambda v: f"{v:.2f} {unit}"


def _percent(digits: int) -> Callable[[float], str]:
    return lambda v: f"{100 * v:.{digits}f} %"


#: The criteria compared for every candidate: (name, value of a candidate, larger is better, format, why, tie).
_CRITERIA: list[tuple[str, Callable[[Candidate], float | None], bool, Callable[[float], str], str, float]] = [
    ("IK time per pose", lambda c: c.ik["seconds_per_pose"], False, lambda v: f"{v * 1e6:.1f} µs",
     "solving faster", TIME_TIE),
    ("task poses reached", lambda c: c.ik["reached_share"], True, _percent(1), "reaching more of the task", TIE),
    ("mean solutions per reached pose", lambda c: c.ik["mean_solutions"], True, lambda v: f"{v:.2f}",
     "more ways to reach a pose", TIE),
    ("poses with a multiple root", lambda c: c.ik["multiple_root_share"], False, _percent(2),
     "fewer singular poses in the task", TIE),
    ("solutions within joint limits", lambda c: c.ik["within_limits_share"], True, _percent(1),
     "joint limits cut fewer solutions", TIE),
    ("median smallest singular value", lambda c: c.manipulability["sigma_min"]["p50"], True, lambda v: f"{v:.4g}",
     "further from singularities", TIE),
]  # fmt: skip


def _verdicts(cands: list[Candidate]) -> list[dict[str, Any]]:
    noise = EFFORT_NOISE * max((s["max"] or 0.0) for c in cands for s in c.effort["per_joint"])
    out = [
        _verdict(cands, what, [get(c) for c in cands], larger, fmt, why=why, tie=tie)
        for what, get, larger, fmt, why, tie in _CRITERIA
    ]
    out.append(
        _verdict(
            cands,
            "reachable volume",
            [c.workspace["volume_m3"] for c in cands],
            True,
            lambda v: f"{v:.4g} m³",
            margin=[VOLUME_MARGIN * c.workspace["uncertainty_m3"] for c in cands],
            why=f"a larger workspace (beyond {VOLUME_MARGIN:g} times the estimates' uncertainties)",
        )
    )
    out.append(
        _verdict(
            cands,
            "largest holding torque (revolute joints)",
            [c.effort["largest"]["max"] for c in cands],
            False,
            _unit_format("N·m"),
            why="smaller actuators",
            floor=noise,
        )
    )
    n = min(c.robot.n_joints for c in cands)
    for i in range(n):
        units = {c.effort["units"][i] for c in cands}
        if len(units) != 1:
            continue  # a revolute joint against a prismatic one: torques and forces do not compare
        unit = units.pop()
        label = " / ".join(sorted({c.robot.joint_names[i] for c in cands}))
        out.append(
            _verdict(
                cands,
                f"joint {i + 1} ({label}) holding effort, max",
                [c.effort["per_joint"][i]["max"] for c in cands],
                False,
                _unit_format(unit),
                why="a smaller actuator there",
                floor=noise,
            )
        )
    return out


# --------------------------------------------------------------------------------------------------
# The entry point
# --------------------------------------------------------------------------------------------------


def compare_designs(
    robots: Sequence[Robot | str],
    *,
    payload: float = 0.0,
    payload_com: ArrayLike = (0.0, 0.0, 0.0),
    links: bool = True,
    samples: int = 2000,
    poses: ArrayLike | None = None,
    region: ArrayLike | None = None,
    workspace_samples: int = 200_000,
    seed: int = 0,
    progress: Progress | None = None,
) -> DesignComparison:
    """Measure each candidate in ``robots`` (Robots, bundled names or robot files; at least one) over one task.

    ``payload`` (kg) at ``payload_com`` (tool frame; first candidate's length unit) is held at the tool; ``links``
    adds the link masses of the robot files. ``samples``: the task's size when it is drawn (see the module
    docstring); ``poses (N, 4, 4)``: the task instead; ``region [[xmin, xmax], [ymin, ymax], [zmin, zmax]]``: keep
    task poses whose position is inside. ``workspace_samples`` configurations per candidate estimate its
    volume. ``seed`` makes the run reproducible. ``progress(stage, done, total)`` is called per candidate.
    """
    if isinstance(robots, str | Robot) or not isinstance(robots, Sequence) or not robots:
        raise UnknownOptionError("robots must be a non-empty list of robots (Robot, bundled name or robot file)")
    arms = [load_robot(r) for r in robots]
    names = [a.name for a in arms]
    if len(set(names)) != len(names):
        raise UnknownOptionError(f"candidates must have different names, got {names}")
    samples = check_int(samples, "samples", 1, MAX_DESIGN_SAMPLES)
    workspace_samples = check_int(workspace_samples, "workspace_samples", 1000, MAX_WORKSPACE_SAMPLES)
    seed = check_int(seed, "seed", 0, 2**63 - 1)
    links = check_bool(links, "links")
    box = _check_region(region)
    for arm in arms:  # every candidate solvable before any work
        _check_solvable(arm)
    report = _no_progress if progress is None else progress
    first = arms[0]
    # checked once here, in the first candidate's unit (gravity_torques checks it again per candidate)
    gravity_torques(first, np.zeros(first.n_joints), payload=payload, payload_com=payload_com)
    com = np.array(payload_com, dtype=np.float64)
    rng = np.random.default_rng(seed)
    P, source = _task(arms, samples, poses, box, rng)
    report("design", 0, len(arms))
    cands = []
    for k, robot in enumerate(arms):
        factor = _scale(robot, first)
        own = np.random.default_rng([seed, zlib.crc32(robot.name.encode())])  # not dependent on the order
        cands.append(_measure(robot, _in_unit(P, factor), float(payload), com * factor, links, workspace_samples, own))
        report("design", k + 1, len(arms))
    task = {
        "n_poses": int(P.shape[0]),
        "source": source,
        "seed": seed,
        "length_unit": first.length_unit,
        "region": None if box is None else box.tolist(),
        "workspace_samples": workspace_samples,
    }
    load = {"mass_kg": float(payload), "com": com.tolist(), "com_unit": first.length_unit, "links": links}
    return DesignComparison(cands, task, P[:, :3, 3].copy(), load, _verdicts(cands))
