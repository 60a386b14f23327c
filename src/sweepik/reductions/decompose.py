"""Automatic decomposition: from a robot's geometry to every plan that solves it, and the choice among them.

Detect (``Robot.structure``), then choose (``plans``: every family, theta* and position case that applies, on
the chain and on the reversed chain; ``choose``: the best), then solve (:class:`.generic.GeometricReduction`).

A position case applies when its structural condition holds for **every** value of theta*: the reduced chain
(:func:`.position.reduce_chain`) is checked at several theta* values. Distances are judged relative to the
arm's length scale (``structure.INTERSECT_TOL_REL``), directions with ``structure.PARALLEL_TOL``.

Ranking (``_rank``): a closed form before a sweep; a plan without a blind spot (``Plan.conditional``) before
one with; fewer branches (less work per sample); the forward chain before the reversed; the lower theta*.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import lru_cache
from typing import Any

import numpy as np

from sweepik.errors import NoReductionError
from sweepik.model.chain import Chain, rotation_about
from sweepik.model.robot import Robot
from sweepik.model.structure import (
    INTERSECT_TOL_REL,
    PARALLEL_TOL,
    Structure,
    line_relation,
    near_structure,
    structure_of,
)
from sweepik.reductions.generic import Plan
from sweepik.reductions.position import BRANCHES, CASES, motion, reduce_chain

_reduce_chain: Any = reduce_chain

__all__ = ["plans", "choose", "choice", "companion_plan", "explain", "set_plan_check"]

#: theta* values at which a case's condition is checked (revolute theta*; a prismatic one uses fractions of its
#: range): generic angles, so that a relation holding at all of them holds for every angle.
_ANGLES = (0.0, 0.9, 2.1, -1.3, -2.8)
_FRACTIONS = (0.5, 0.1, 0.9, 0.3, 0.7)
#: A relation holding to this (a sine, or a distance over the length scale) but not exactly still makes every pose
#: nearly a continuum where the exact relation would make it one (``continuum_everywhere``): the Realman RM75 with
#: joint 4 held has axes 3 and 4 on one line to 7.7e-7, its shoulder and wrist axes meeting to 1.1e-6 and 6.2e-7, and
#: its solutions then turn on the rounding of the pose. Real offsets (a millimetre on a metre) are well above it.
DEGENERATE_TOL = 1e-5
#: A dot product entering a division must exceed this (it is a cosine between unit vectors) ...
MIN_DOT = 1e-6
#: ... and is theta*-dependent (the plan has a blind spot) when it varies across the samples by more than this.
VARY_TOL = 1e-9


def _t(v: Any) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


def _reduced(chain: Chain, W: np.ndarray, f: int, x: float) -> tuple[np.ndarray, ...]:
    """``(ha, hb, hc, pab, pbc, pcw)`` of the reduced chain with joint f at x (see position.reduce_chain)."""
    H, P, rev = chain.H, chain.P, chain.revolute
    o3 = P[:4].sum(axis=0)
    out = _reduce_chain(  # a compiled function of tuples
        *(_t(H[i]) for i in range(4)),
        *(bool(rev[i]) for i in range(4)),
        *(_t(P[i]) for i in range(4)),
        _t(W - o3),
        f,
        motion(bool(rev[f]), float(x)),
        _t(W),
    )
    return tuple(np.array(v) for v in out[1:])


def _dist_to_line(p: np.ndarray, o: np.ndarray, h: np.ndarray) -> float:
    d = p - o
    return float(np.linalg.norm(d - np.dot(d, h) * h))


def _parallel(u: np.ndarray, v: np.ndarray) -> bool:
    return float(np.linalg.norm(np.cross(u, v))) < PARALLEL_TOL


def _check(case: str, types: tuple[bool, bool, bool], samples: list[tuple[np.ndarray, ...]], tol: float):
    """``(applies, conditional, meeting points)``: for ab_int / bc_int the point where the axes meet, relative to
    joint a (ab_int) or b (bc_int), at each sample."""
    ra, rb, rc = types
    no = (False, False, None)
    geo = []
    for ha, hb, hc, pab, pbc, pcw in samples:
        oa = np.zeros(3)
        ob = pab
        oc = pab + pbc
        geo.append((ha, hb, hc, oa, ob, oc, oc + pcw))

    def dots(u_of: Any) -> tuple[bool, bool]:
        vals = np.array([u_of(g) for g in geo])
        if np.min(np.abs(vals)) < MIN_DOT:
            return False, False
        return True, bool(np.ptp(vals) > VARY_TOL)

    if rc and any(_dist_to_line(g[6], g[5], g[2]) < tol for g in geo):
        return no  # joint c does not move W (its axis passes through W): W is left to two joints
    if case in ("ab_par", "bc_par"):
        i, j = (0, 1) if case == "ab_par" else (1, 2)
        if not (types[i] and types[j]) or not all(_parallel(g[i], g[j]) for g in geo):
            return no
        if any(_dist_to_line(g[3 + j], g[3 + i], g[i]) < tol for g in geo):  # coincident axes
            return no
        k = 2 if case == "ab_par" else 0  # the joint solved first
        if types[k]:
            if all(_parallel(g[k], g[i]) for g in geo):  # three parallel: the height says nothing
                return no
            return True, False, None
        ok, cond = dots(lambda g: float(np.dot(g[k], g[i])))
        return ok, cond, None
    if case in ("ab_int", "bc_int"):
        i, j = (0, 1) if case == "ab_int" else (1, 2)
        if not (types[i] and types[j]):
            return no
        points = []
        for g in geo:
            rel, pt = line_relation(g[i], g[3 + i], g[j], g[3 + j], tol)
            if rel != "intersecting" or pt is None:
                return no
            points.append(pt - g[3 + i])
        if case == "ab_int" and any(np.linalg.norm(p - points[0]) > tol for p in points):
            return no
        k = 2 if case == "ab_int" else 0
        if types[k]:
            for g, p in zip(geo, points, strict=True):
                centre = g[3 + i] + p
                if _dist_to_line(centre, g[3 + k], g[k]) < tol:  # all three axes through one point
                    return no
        return True, False, points
    if case == "ppp":
        if any(types):
            return no
        ok, cond = dots(lambda g: float(np.dot(g[0], np.cross(g[1], g[2]))))
        return ok, cond, None
    if case == "ppr":
        if ra or rb or not rc:
            return no
        ok, cond = dots(lambda g: float(np.linalg.norm(np.cross(g[0], g[1]))))
        if not ok or all(_parallel(np.cross(g[0], g[1]), g[2]) for g in geo):
            return no
        return True, cond, None
    if case == "rpp":
        if not ra or rb or rc:
            return no
        ok, cond = dots(lambda g: float(np.linalg.norm(np.cross(g[1], g[2]))))
        if not ok or all(_parallel(np.cross(g[1], g[2]), g[0]) for g in geo):
            return no  # (slides in the plane of the turn: W has a continuum of solutions)
        return True, cond, None
    if case == "ac_par":
        if not (ra and rc) or rb or not all(_parallel(g[0], g[2]) for g in geo):
            return no
        ok, cond = dots(lambda g: float(np.dot(g[0], g[1])))
        return ok, cond, None
    return no


def _samples(robot: Robot, chain_index: int, prismatic: bool) -> list[float]:
    if not prismatic:
        return list(_ANGLES)
    lo, hi = float(robot.lower[chain_index]), float(robot.upper[chain_index])
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi - lo > 1e6 * robot.length_scale:
        lo, hi = -robot.length_scale, robot.length_scale
    return [lo + fr * (hi - lo) for fr in _FRACTIONS]


def _position_plans(robot: Robot, chain: Chain, rev_chain: bool, W: np.ndarray, frees: tuple[int, ...], family: str):
    out = []
    tol = INTERSECT_TOL_REL * robot.length_scale
    for f in frees:
        others = [i for i in range(4) if i != f]
        types = tuple(bool(chain.revolute[i]) for i in others)
        robot_f = 5 - f if rev_chain else f
        xs = _samples(robot, robot_f, not chain.revolute[f])
        samples = [_reduced(chain, W, f, x) for x in xs]
        pts = np.cumsum(chain.P[:4], axis=0)
        for case in CASES:
            ok, cond, rel = _check(case, types, samples, tol)  # type: ignore[arg-type]
            if not ok:
                continue
            nb = BRANCHES[case][0]
            if case in ("ab_par",):
                nb = BRANCHES[case][0 if types[2] else 1]
            elif case in ("bc_par",):
                nb = BRANCHES[case][0 if types[0] else 1]
            meet = np.zeros(3)
            if rel is not None:
                if case == "bc_int" and not _meets_as_kernel(chain, f, xs, rel, tol):
                    continue
                meet = pts[others[0] if case == "ab_int" else others[1]] + rel[0]
            out.append(
                Plan(
                    family=family,
                    reversed=rev_chain,
                    free=f,
                    case=case,
                    branches=2 * nb if family == "wrist" else nb,
                    W=_t(W),
                    meet=_t(meet),
                    conditional=cond,
                )
            )
    return out


def _parallel_plans(robot: Robot, chain: Chain, rev_chain: bool, st: Structure) -> list[Plan]:
    """The parallel family (closed form): axes 2, 3, 4 revolute and parallel, no two of them on one line; axes 5 and
    6 revolute, neither parallel to them, and not parallel to each other; axis 1 revolute and not parallel to them,
    or a slide not perpendicular to them (else the heights the family solves for would not move). ``W``: where
    axes 5 and 6 meet, else joint 6's point, with ``meet`` joint 5's point (their offset goes to ``sp6``)."""
    rev, H, P = chain.revolute, chain.H, chain.P
    if not (all(rev[1:]) and st.is_parallel(1, 2) and st.is_parallel(2, 3)):
        return []
    h = H[1]
    pts = np.cumsum(P[:6], axis=0)
    tol = INTERSECT_TOL_REL * robot.length_scale
    if _dist_to_line(pts[2], pts[1], h) < tol or _dist_to_line(pts[3], pts[2], h) < tol:
        return []
    if st.is_parallel(1, 4) or st.is_parallel(1, 5) or st.is_parallel(4, 5):  # (in every configuration)
        return []
    if rev[0] and _parallel(H[0], h):
        return []
    if not rev[0] and abs(float(np.dot(H[0], h))) < MIN_DOT:
        return []
    if st.intersecting(4, 5):
        W = meet = np.array(st.points[(4, 5)])
    else:
        W, meet = pts[5], pts[4]
    branches = 8 if rev[0] else 4
    case = "parallel" if rev[0] else "parallel_slide"
    return [Plan("parallel", rev_chain, 3, case, branches, _t(W), _t(meet))]


def _meets_as_kernel(chain: Chain, f: int, xs: list[float], rel: list[np.ndarray], tol: float) -> bool:
    """The kernel rebuilds b and c's meeting point from its value at the first sample, turned with theta* when
    theta* is a revolute joint 2 (between a and b); the case applies only if that is where the axes meet."""
    turn = f == 1 and bool(chain.revolute[1])
    for x, p in zip(xs, rel, strict=True):
        expected = rotation_about(chain.H[1], x - xs[0]) @ rel[0] if turn else rel[0]
        if np.linalg.norm(p - expected) > tol:
            return False
    return True


def _rank(p: Plan) -> tuple[int, int, int, int, int]:
    return (0 if p.closed_form else 1, int(p.conditional), p.branches, int(p.reversed), p.free)


@lru_cache(maxsize=64)
def _near(robot: Robot) -> tuple[str, ...]:
    """``structure.near_structure`` of the robot's chain, kept per robot (by value)."""
    return near_structure(robot.chain, robot.length_scale)


def _structures(robot: Robot) -> list[tuple[bool, Chain, Structure]]:
    out = []
    for rev_chain in (False, True):
        chain = robot.chain.reversed() if rev_chain else robot.chain
        out.append((rev_chain, chain, structure_of(chain, robot.length_scale)))
    return out


@lru_cache(maxsize=64)
def plans(robot: Robot) -> tuple[Plan, ...]:
    """Every plan that solves ``robot``, best first (empty: none in the catalogue). Cached per robot (by value)."""
    if robot.n_joints != 6:
        return ()
    found: list[Plan] = []
    for rev_chain, chain, st in _structures(robot):
        rev = chain.revolute
        if rev[3] and rev[4] and rev[5] and st.common_point((3, 4, 5)):
            W = np.array(st.points[(3, 4)])
            found += _position_plans(robot, chain, rev_chain, W, (3,), "wrist")
        if rev[4] and rev[5] and st.intersecting(4, 5):
            W = np.array(st.points[(4, 5)])
            found += _position_plans(robot, chain, rev_chain, W, (0, 1, 2, 3), "pair")
        found += _parallel_plans(robot, chain, rev_chain, st)
    return tuple(sorted((p for p in found if _continuum_covered(p, found, robot)), key=_rank))


def _continuum_covered(plan: Plan, found: list[Plan], robot: Robot) -> bool:
    """A closed form whose wrist can turn singular needs a sweep for the continuum there (see
    ``GeometricReduction._continua``). A spherical wrist's single member is always a solution (the position was
    solved first); the parallel family's is not (the planar arm's target turns with the sum of joints 2-4), so a
    parallel plan without such a sweep (e.g. after a slide, with an offset wrist) is not offered rather than answer
    "unreachable" at a reachable singular pose."""
    if plan.family != "parallel":
        return True
    chain = robot.chain.reversed() if plan.reversed else robot.chain
    h, h4, h5 = chain.H[1], chain.H[4], chain.H[5]
    if abs(abs(float(h4 @ h5)) - abs(float(h4 @ h))) > PARALLEL_TOL:  # joint 6's axis never turns onto h
        return True
    moving = {plan.joint(j) for j in (1, 2, 3, 5)}
    return any(p.family == "pair" and not p.conditional and p.free_joint in moving for p in found)


def continuum_everywhere(robot: Robot) -> str | None:
    """Why every pose of ``robot`` is a continuum (or nearly: an arm no decomposition can solve to certification),
    or None. Two consecutive revolute axes on one line (exactly, or to ``DEGENERATE_TOL``: a 7-joint arm whose
    elbow is locked straight, e.g. the Realman RM75 with joint 4 at 0) turn the rest of the arm by the sum of their
    angles alone; a spherical shoulder and a spherical wrist (exactly or nearly: an SRS arm with its elbow locked, the
    KUKA iiwa or the RM75 with joint 4 held) leave a turn about the line through their centres free."""
    st = robot.structure()
    near = near_structure(robot.chain, robot.length_scale, DEGENERATE_TOL)
    coaxial = [f"{i + 1}≡{i + 2}" for i, rel in enumerate(st.pairs) if rel == "coincident"]
    coaxial += [t for t in near if "≈≡" in t]
    ends = [
        st.common_point(run) or any(t.startswith(label + " ") for t in near)
        for run, label in (((0, 1, 2), "1≈∩2∩3"), ((3, 4, 5), "4≈∩5∩6"))
    ]
    if all(robot.is_revolute) and all(ends):
        return (
            f"robot {robot.name!r}: every pose is a continuum (or nearly one): joints 1-3 meet at one point and joints "
            "4-6 at another (exactly or to 1e-5), so the two points keep their distance and a pose fixes the arm only "
            "up to a turn about the line through both (a 7-joint arm with its elbow locked: its self-motion); with "
            "joints locked, lock another joint"
        )
    if not coaxial:
        return None
    return (
        f"robot {robot.name!r}: every pose is a continuum (or nearly one): joints {', '.join(coaxial)} turn about one "
        "line (joints numbered from 1 in this arm), so only the sum of their angles is fixed by a pose; with joints "
        "locked, lock another joint or another value"
    )


def _missing(robot: Robot) -> str:
    if robot.n_joints != 6:
        return f"robot {robot.name!r} has {robot.n_joints} joints: the decompositions solve 6-joint arms"
    st = robot.structure()
    head = f"robot {robot.name!r} ({st.describe()}) is outside sweepik's catalogue: "
    # the UR family's closed form, refused for its continuum (_continuum_covered)
    if any(_parallel_plans(robot, chain, rev_chain, s) for rev_chain, chain, s in _structures(robot)):
        return head + (
            "axes 2-4 are parallel (the UR family), but joint 6's axis can turn parallel to them (its wrist has an "
            "offset): at joint 5 = 0 the solutions form a continuum that only a sweep can report, and no sweep fits "
            "this arm (it needs two axes meeting at the tool or at the base)"
        )
    near = _near(robot)
    nearly = (
        f" Its description has relations that hold only nearly ({', '.join(near)}: rounded, not exact), and a "
        "decomposition built on them would be off by about that much times the arm's size; with them exact, a "
        "decomposition may exist"
        if near
        else ""
    )
    return (
        head
        + (
            "a decomposition needs the last two axes (or the first two) revolute and meeting at a point, with the "
            "other joints placing that point by a chain of subproblems (two revolute axes among them parallel or "
            "meeting, two parallel revolute axes around a slide, a revolute joint before or after two slides, or "
            "three slides), or axes 2-4 parallel (the UR family)."
        )
        + nearly
    )


def not_sweepable(robot: Robot, free_joint: int, full: Robot | None = None, joints: Sequence[int] = ()) -> str:
    """Why ``free_joint`` cannot be theta*, and which joints can (by name, index from 0 and number from 1). With
    ``full`` (an arm with joints held; ``robot`` is the smaller arm solved, its joint i being ``full``'s joint
    ``joints[i]``) the joints are named and counted as in ``full``."""
    avail = sorted({p.free_joint for p in plans(robot) if not p.closed_form})
    arm, index = (robot, list(range(robot.n_joints))) if full is None else (full, list(joints))

    def name(j: int) -> str:
        return f"{arm.joint_names[index[j]]} (index {index[j]}, number {index[j] + 1})"

    held = "" if full is None else " (with joints held)"
    return f"robot {arm.name!r}{held}: no decomposition sweeps {name(free_joint)}; joints that can be swept: " + (
        ", ".join(name(j) for j in avail) or "none"
    )


#: The check of a choice (``plan_check.checked_choice``: plans solved on sample configurations of the arm), registered
#: by the solver's layer, which can solve; None: the ranking alone chooses.
_plan_check: Callable[[Robot, tuple[Plan, ...], tuple[Plan, ...]], tuple[Plan, tuple[Any, ...]]] | None = None


def set_plan_check(
    check: Callable[[Robot, tuple[Plan, ...], tuple[Plan, ...]], tuple[Plan, tuple[Any, ...]]] | None,
) -> None:
    """Register the check that :func:`choose` runs on the plans it chooses among (None: none)."""
    global _plan_check
    _plan_check = check
    choice.cache_clear()


def choose(robot: Robot, free_joint: int | None = None) -> Plan:
    """The best plan for ``robot`` (with theta* = ``free_joint`` if given); NoReductionError if there is none."""
    return choice(robot, free_joint)[0]


@lru_cache(maxsize=64)
def choice(robot: Robot, free_joint: int | None = None, hints: tuple[Plan, ...] = ()) -> tuple[Plan, tuple[Any, ...]]:
    """:func:`choose`'s plan and the checks that chose it (``plan_check.PlanCheck``, in the order made; empty when
    there was nothing to choose from). The candidates: the plans sweeping ``free_joint`` if given, else those
    without a blind spot (all plans when every one has one), best ranked first. The first is chosen, unless the arm
    has a near-structure (``structure.near_structure``): then every candidate is checked on the arm and the one that
    recovers most of the check's configurations is chosen (:mod:`sweepik.plan_check`). A ``free_joint`` whose best
    plan loses any of them raises NoReductionError (a sweep of that joint would miss solutions on this arm). ``hints``
    (candidates, e.g. the plans chosen for the same arm at other lock values): the first that a shorter check on the
    arm finds sound is taken (``plan_check.checked_choice``)."""
    everywhere = continuum_everywhere(robot)
    if everywhere:
        raise NoReductionError(everywhere)
    options = plans(robot)
    if free_joint is not None:
        options = tuple(p for p in options if not p.closed_form and p.free_joint == free_joint)
        if not options:
            raise NoReductionError(not_sweepable(robot, free_joint))
    elif not options:
        raise NoReductionError(_missing(robot))
    else:
        options = tuple(p for p in options if not p.conditional) or options
    near = _near(robot)
    if _plan_check is None or not near or (len(options) == 1 and free_joint is None):
        return options[0], ()
    plan, checks = _plan_check(robot, options, tuple(h for h in hints if h in options))
    best = next(c for c in checks if c.plan == plan)
    if free_joint is not None and best.recovered < best.checked:
        raise NoReductionError(
            f"robot {robot.name!r}: sweeping {robot.joint_names[free_joint]} (index {free_joint}) would miss "
            f"solutions: the arm has a near-structure ({', '.join(near)}), and checked on {best.checked} of its "
            f"configurations that sweep gave back {best.recovered}; leave free_joint unset (the automatic choice) or "
            "see sweepik.analyze(robot)['checks']"
        )
    return plan, checks


def companion_plan(robot: Robot) -> Plan | None:
    """The plan solved beside the automatic choice on an arm with a near-structure (:mod:`sweepik.engine.companion`):
    of the
    other checked plans that gave back every configuration of the check, the best scored one sweeping another joint
    or the other chain; None without a near-structure or such a plan."""
    try:
        plan, checks = choice(robot)
    except NoReductionError:
        return None
    mine = (plan.reversed, plan.free)
    others = [c for c in checks if c.passed and (c.plan.reversed, c.plan.free) != mine and c.plan != plan]
    return max(others, key=lambda c: c.score).plan if others else None


def explain(robot: Robot) -> dict[str, Any]:
    """Plain values for ``sweepik analyze``: structure, every plan, the chosen one (or why none)."""
    st = robot.structure()
    found = plans(robot)
    near = _near(robot)
    info: dict[str, Any] = {
        "robot": robot.name,
        "structure": st.describe(),
        "near_structure": list(near),
        "plans": [_plan_dict(robot, p) for p in found],
        "checks": [],
    }
    try:
        plan, checks = choice(robot)
    except NoReductionError as e:
        info.update(chosen=None, reason=str(e), why=None, companion=None)
        return info
    info.update(chosen=_plan_dict(robot, plan), reason=None)
    info["checks"] = [
        {**_plan_dict(robot, c.plan), "recovered": c.recovered, "checked": c.checked, "solutions": c.solutions}
        for c in checks
    ]
    comp = companion_plan(robot)
    info["companion"] = None if comp is None else _plan_dict(robot, comp)
    if checks:
        best = next(c for c in checks if c.plan == plan)
        info["why"] = (
            f"near-structure ({', '.join(near)}): every plan checked on {best.checked} configurations of the arm; "
            f"this one gave {best.recovered} of them back and {best.solutions} solutions in all, the most"
        )
    else:
        info["why"] = "the best ranked plan (a closed form before a sweep, no blind spot, fewer branches)"
    return info


def _plan_dict(robot: Robot, p: Plan) -> dict[str, Any]:
    return {
        "family": p.family,
        "closed_form": p.closed_form,
        "free_joint": None if p.closed_form else p.free_joint,
        "free_joint_number": None if p.closed_form else p.free_joint + 1,
        "free_joint_name": None if p.closed_form else robot.joint_names[p.free_joint],
        "chain": "reversed" if p.reversed else "forward",
        "case": p.case,
        "branches": p.branches,
        "blind_spot": p.conditional,
        "steps": p.steps(),
    }
