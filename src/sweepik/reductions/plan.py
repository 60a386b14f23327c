"""Plans: every way the catalogue's families solve an arm, found from its geometry.

A :class:`Plan` is one family ('pair': sweep theta*; 'wrist', 'parallel': closed forms) on the forward or reversed
chain, with theta* and the position case placing the wrist centre. ``plans(robot)`` lists every plan that applies,
best first; :mod:`.decompose` chooses among them and :mod:`.generic` solves with one.

A position case applies when its structural condition holds for **every** value of theta*: the reduced chain
(:func:`.position.reduce_chain`) is checked at several theta* values. Distances are judged relative to the
arm's length scale (``structure.INTERSECT_TOL_REL``), directions with ``structure.PARALLEL_TOL``.

Ranking (``rank``): a closed form before a sweep; a structured position case before ``rrr`` (the quartic); a
plan without a blind spot (``Plan.conditional``) before one with; fewer branches (less work per sample); the
forward chain before the reversed; the lower theta*.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

import numpy as np

from sweepik.model.chain import Chain, rotation_about
from sweepik.model.robot import Robot
from sweepik.model.structure import (
    INTERSECT_TOL_REL,
    PARALLEL_TOL,
    Structure,
    cross3,
    line_relation,
    near_structure,
    structure_of,
)
from sweepik.reductions.decoupled import decoupled_applies
from sweepik.reductions.position import BRANCHES, CASES, motion, reduce_chain

_reduce_chain: Any = reduce_chain

__all__ = [
    "Plan",
    "GENERAL",
    "plans",
    "rank",
    "chain_structures",
    "near_structures",
    "parallel_plans",
    "continuum_covered",
    "first_plan",
    "position_plan",
]


@dataclass(frozen=True)
class Plan:
    """One way to solve an arm: ``family`` ('pair': sweep theta*; 'wrist', 'parallel': closed forms) on the forward or
    ``reversed`` chain, with ``free`` (0-3, in the solved chain's order) the fixed joint among the first four
    and ``case`` the position case placing the wrist centre ``W``; ``meet`` the meeting point of the axes that
    case uses (world frame, at the zero configuration of the joints other than theta*; for a prismatic theta* at
    the middle of its sampled range: its position relative to joint a or b does not depend on the slide)."""

    family: str
    reversed: bool
    free: int
    case: str
    branches: int
    W: tuple[float, float, float]
    meet: tuple[float, float, float]
    #: theta* enters a division (a line-plane or lines step whose direction turns with theta*): the plan has a
    #: blind spot where that product vanishes and is chosen only on request.
    conditional: bool = False

    @property
    def closed_form(self) -> bool:
        return self.family in ("wrist", "parallel", "decoupled", "general")

    def joint(self, i: int) -> int:
        """Robot index of joint ``i`` of the solved chain."""
        return 5 - i if self.reversed else i

    @property
    def free_joint(self) -> int:
        """Robot index of theta* (for the closed form: the joint the family fixes, which does not move ``W``)."""
        return self.joint(self.free)

    def steps(self) -> list[str]:
        """The subproblem chain, in words (joints numbered from 1 as the robot numbers them)."""
        if self.family == "general":
            return [
                "elimination: the kinematic equations reduced to a matrix polynomial in one joint's half-angle "
                "tangent (Raghavan-Roth), its roots the eigenvalues of a generalized eigenproblem (Manocha-Canny)",
                "the other joints from the eigenvectors and closed forms",
                "every root polished by Newton steps on the forward kinematics",
            ]
        if self.family == "decoupled":
            return [
                "the revolute joints turn the tool alone (slides do not turn it)",
                "the first two revolute joints: sp2 on the last one's axis; the last: sp1",
                "the slides: lines3 (the position is linear in them)",
            ]
        if self.family == "parallel":
            j = [self.joint(i) + 1 for i in range(6)]
            axes = f"the parallel axes {j[1]}, {j[2]}, {j[3]}"
            if self.case != "parallel":  # a slide first
                first = [
                    f"joint {j[4]}: sp4 on the angle of joint {j[5]}'s axis to {axes}",
                    f"joint {j[0]}: lp4 on the height of joint {j[5]}'s point along them",
                ]
            elif self.W != self.meet:
                first = [
                    f"joints {j[0]}, {j[4]}: sp6 on the height of joint {j[5]}'s point along {axes} and the angle "
                    f"of joint {j[5]}'s axis to them"
                ]
            else:
                first = [
                    f"joint {j[0]}: sp4 on the height of the wrist centre along {axes}",
                    f"joint {j[4]}: sp4 on the angle of joint {j[5]}'s axis to them",
                ]
            return [
                *first,
                f"joint {j[5]} and the sum of joints {j[1]}-{j[3]}: sp1",
                f"joints {j[2]}, {j[1]}: sp3, sp1; joint {j[3]} from the sum",
            ]
        others = [i for i in range(4) if i != self.free]
        a, b, c = (self.joint(i) + 1 for i in others)
        how = "sp5, a quartic" if self.case == "rrr" else self.case
        place = f"joints {a}, {b}, {c} place the wrist centre ({how})"
        if self.family == "wrist":
            j4, j5, j6 = (self.joint(i) + 1 for i in (3, 4, 5))
            return [place, f"joints {j4}, {j5}: sp2 on joint {j6}'s axis", f"joint {j6}: sp1"]
        j5, j6 = self.joint(4) + 1, self.joint(5) + 1
        return [
            f"sweep joint {self.free_joint + 1}",
            place,
            f"residual: angle of joint {j5}'s axis to joint {j6}'s in the target",
            f"joints {j5}, {j6}: sp1",
        ]


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


def _norm(v: np.ndarray) -> float:
    """``np.linalg.norm`` of a 3-vector, as it computes it (``sqrt(v . v)``: the same bits), without its argument
    handling (a held arm's plan enumeration takes thousands)."""
    return math.sqrt(float(v.dot(v)))


def _dist_to_line(p: np.ndarray, o: np.ndarray, h: np.ndarray) -> float:
    d = p - o
    return _norm(d - np.dot(d, h) * h)


def _parallel(u: np.ndarray, v: np.ndarray) -> bool:
    return _norm(cross3(u, v)) < PARALLEL_TOL


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
        ok, cond = dots(lambda g: float(np.dot(g[0], cross3(g[1], g[2]))))
        return ok, cond, None
    if case == "ppr":
        if ra or rb or not rc:
            return no
        ok, cond = dots(lambda g: _norm(cross3(g[0], g[1])))
        if not ok or all(_parallel(cross3(g[0], g[1]), g[2]) for g in geo):
            return no
        return True, cond, None
    if case == "rpp":
        if not ra or rb or rc:
            return no
        ok, cond = dots(lambda g: _norm(cross3(g[1], g[2])))
        if not ok or all(_parallel(cross3(g[1], g[2]), g[0]) for g in geo):
            return no  # (slides in the plane of the turn: W has a continuum of solutions)
        return True, cond, None
    if case == "ac_par":
        if not (ra and rc) or rb or not all(_parallel(g[0], g[2]) for g in geo):
            return no
        ok, cond = dots(lambda g: float(np.dot(g[0], g[1])))
        return ok, cond, None
    if case == "rrr":
        if not (ra and rb and rc) or not all(_sp5_regular(g) for g in geo):
            return no
        return True, False, None
    return no


def _fixed_target(samples: list[tuple[np.ndarray, ...]], tol: float) -> bool:
    """The reduced chains of every theta* sample are one and the same (to ``tol``): theta* does not move ``W``."""
    first = samples[0]  # (``np.allclose(u, v, rtol=0, atol=tol)`` of finite vectors, without its overhead)
    return all(all(bool(np.all(np.abs(u - v) <= tol)) for u, v in zip(first, g, strict=True)) for g in samples)


def _sp5_regular(g: tuple[np.ndarray, ...]) -> bool:
    """The ``rrr`` case's ``sp5`` fixes the three angles (a quartic, not a continuum) for targets of ``W`` all around:
    the 2x2 blocks of its ``sp6`` are not both singular at random targets at the reach of the reduced chain. They
    are where axes a and b are parallel, or b and c (structured cases), or a slide-free chain folds onto one line."""
    ha, hb, hc, _, ob, oc, w = g
    pab, pbc, pcw = ob, oc - ob, w - oc
    reach = float(np.linalg.norm(pab) + np.linalg.norm(pbc) + np.linalg.norm(pcw))
    if reach == 0.0:
        return False
    rng = np.random.default_rng(0)
    for tp in rng.normal(size=(3, 3)) * reach:
        # sp6's blocks (``subproblems.revolute.sp6`` with sp5's arguments): theta1 terms of hb . R(ha, t) tp and
        # (-pab) . R(ha, t) tp, theta3 terms of -hb . R(hc, t) pcw and -pbc . R(hc, t) pcw
        def terms(h: np.ndarray, k: np.ndarray, p: np.ndarray) -> tuple[float, float]:
            perp = p - np.dot(k, p) * k
            return float(np.dot(h, perp)), float(np.dot(h, cross3(k, p)))

        a1, a2 = terms(hb, ha, tp), terms(-pab, ha, tp)
        b1, b2 = terms(-hb, hc, pcw), terms(-pbc, hc, pcw)
        det_a, det_b = a1[0] * a2[1] - a1[1] * a2[0], b1[0] * b2[1] - b1[1] * b2[0]
        size = max(abs(v) for v in (*a1, *a2, *b1, *b2))
        if max(abs(det_a), abs(det_b)) <= 1e-9 * size * size:
            return False
    return True


def _samples(robot: Robot, chain_index: int, prismatic: bool) -> list[float]:
    if not prismatic:
        return list(_ANGLES)
    lo, hi = float(robot.lower[chain_index]), float(robot.upper[chain_index])
    if not (np.isfinite(lo) and np.isfinite(hi)) or hi - lo > 1e6 * robot.length_scale:
        lo, hi = -robot.length_scale, robot.length_scale
    return [lo + fr * (hi - lo) for fr in _FRACTIONS]


def _position_plans(robot: Robot, chain: Chain, rev_chain: bool, W: np.ndarray, frees: tuple[int, ...], family: str):
    out = []
    for f in frees:
        free = _Free(robot, chain, rev_chain, W, f)
        for case in CASES:
            plan = free.plan(case, family)
            if plan is not None:
                out.append(plan)
    return out


class _Free:
    """One theta* (joint ``f`` of the solved chain, the wrist centre ``W``): its reduced chains at the sample values
    (worked out when first needed), and the plan of each position case (``plan``)."""

    def __init__(self, robot: Robot, chain: Chain, rev_chain: bool, W: np.ndarray, f: int) -> None:
        self.chain, self.rev_chain, self.W, self.f = chain, rev_chain, W, f
        self.tol = INTERSECT_TOL_REL * robot.length_scale
        self.others = [i for i in range(4) if i != f]
        self.types = tuple(bool(chain.revolute[i]) for i in self.others)
        robot_f = 5 - f if rev_chain else f
        self.xs = _samples(robot, robot_f, not chain.revolute[f])
        self._samples: list[tuple[np.ndarray, ...]] | None = None

    @property
    def samples(self) -> list[tuple[np.ndarray, ...]]:
        if self._samples is None:
            self._samples = [_reduced(self.chain, self.W, self.f, x) for x in self.xs]
        return self._samples

    def branches(self, case: str, family: str) -> int:
        """The plan's branches for ``case`` (known before its check)."""
        types = self.types
        nb = BRANCHES[case][0]
        if case in ("ab_par",):
            nb = BRANCHES[case][0 if types[2] else 1]
        elif case in ("bc_par",):
            nb = BRANCHES[case][0 if types[0] else 1]
        return 2 * nb if family == "wrist" else nb

    def plan(self, case: str, family: str) -> Plan | None:
        """The plan of ``family`` placing the wrist centre by ``case``, or None where it does not apply."""
        f, tol, samples = self.f, self.tol, self.samples
        if case == "rrr" and family != "wrist" and not (f == 3 and _fixed_target(samples, tol)):
            # the quartic's roots are no branches a sweep can follow, unless theta* leaves W's problem as it is
            # (joint 4 turning about the wrist centre: the sweep answering a singular wrist, ``generic._continua``)
            return None
        ok, cond, rel = _check(case, self.types, samples, tol)  # type: ignore[arg-type]
        if not ok:
            return None
        meet = np.zeros(3)
        if rel is not None:
            if case == "bc_int" and not _meets_as_kernel(self.chain, f, self.xs, rel, tol):
                return None
            pts = np.cumsum(self.chain.P[:4], axis=0)
            meet = pts[self.others[0] if case == "ab_int" else self.others[1]] + rel[0]
        return Plan(
            family=family,
            reversed=self.rev_chain,
            free=f,
            case=case,
            branches=self.branches(case, family),
            W=_t(self.W),
            meet=_t(meet),
            conditional=cond,
        )


def parallel_plans(robot: Robot, chain: Chain, rev_chain: bool, st: Structure) -> list[Plan]:
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


#: Closed forms that use no structure of the position (ranked after those that do).
UNSTRUCTURED = ("rrr", "decoupled")


def rank(p: Plan) -> tuple[int, int, int, int, int, int]:
    return (
        0 if p.closed_form else 1,
        int(p.case in UNSTRUCTURED),
        int(p.conditional),
        p.branches,
        int(p.reversed),
        p.free,
    )


#: The general method (:mod:`.general`): no structure used; chosen where no structured plan applies, and checked
#: beside them on an arm with a near-structure.
GENERAL = Plan("general", False, 0, "general", 16, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0))


def decoupled_plans(robot: Robot, chain: Chain) -> list[Plan]:
    """The decoupled family (closed form, :mod:`.decoupled`): three slides and three revolute joints in any order;
    ``W`` is the tool origin (no point is special)."""
    ok, cond = decoupled_applies(chain)
    if not ok:
        return []
    W = _t(chain.P.sum(axis=0))
    return [Plan("decoupled", False, 0, "decoupled", 2, W, (0.0, 0.0, 0.0), conditional=cond)]


@lru_cache(maxsize=64)
def near_structures(robot: Robot) -> tuple[str, ...]:
    """``structure.near_structure`` of the robot's chain, kept per robot (by value)."""
    return near_structure(robot.chain, robot.length_scale)


def chain_structures(robot: Robot) -> list[tuple[bool, Chain, Structure]]:
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
    for rev_chain, chain, st in chain_structures(robot):
        for family, W, frees in _position_families(chain, st):
            found += _position_plans(robot, chain, rev_chain, W, frees, family)
        found += parallel_plans(robot, chain, rev_chain, st)
        if not rev_chain:
            found += decoupled_plans(robot, chain)
    return tuple(sorted((p for p in found if continuum_covered(p, found, robot)), key=rank))


def first_plan(robot: Robot) -> Plan | None:
    """The first plan of :func:`plans` that has no blind spot (``conditional``): the automatic choice on an arm without
    a near-structure (``decompose.choice``), found by checking the candidates in the order ``plans`` ranks them and
    stopping at the first that applies, where ``plans`` checks every one (a held arm at a new lock value: ~0.3 ms of
    ~2.6). None where none applies so, or where the first is a parallel plan (whether its continuum is covered depends
    on the other plans, ``continuum_covered``): ``plans`` decides."""
    if robot.n_joints != 6:
        return None
    # (rank with no blind spot: a plan's own is only larger; ties in the order plans() finds them, as its stable sort)
    found: list[tuple[tuple[int, ...], int, Plan | tuple[_Free, str, str]]] = []
    for rev_chain, chain, st in chain_structures(robot):
        for family, W, frees in _position_families(chain, st):
            for f in frees:
                free = _Free(robot, chain, rev_chain, W, f)
                for case in CASES:
                    least = Plan(family, rev_chain, f, case, free.branches(case, family), (0.0,) * 3, (0.0,) * 3)
                    found.append((rank(least), len(found), (free, case, family)))
        others = parallel_plans(robot, chain, rev_chain, st) + ([] if rev_chain else decoupled_plans(robot, chain))
        found.extend((rank(p), len(found), p) for p in others)
    for _, _, c in sorted(found, key=lambda c: (c[0], c[1])):
        plan = c if isinstance(c, Plan) else c[0].plan(c[1], c[2])
        if plan is None or plan.conditional:
            continue
        return None if plan.family == "parallel" else plan
    return None


def position_plan(robot: Robot, family: str, reversed_chain: bool, free: int, case: str) -> Plan | None:
    """The plan of :func:`plans` with this family (``wrist`` or ``pair``), chain, theta* and case, checked alone;
    None where it does not apply."""
    chain = robot.chain.reversed() if reversed_chain else robot.chain
    for fam, W, frees in _position_families(chain, structure_of(chain, robot.length_scale)):
        if fam == family and free in frees:
            return _Free(robot, chain, reversed_chain, W, free).plan(case, family)
    return None


def _position_families(chain: Chain, st: Structure) -> list[tuple[str, np.ndarray, tuple[int, ...]]]:
    """The families placing a wrist centre on ``chain`` (structure ``st``), in the order :func:`plans` tries them:
    ``(family, W, the joints theta* may be)``."""
    rev = chain.revolute
    out: list[tuple[str, np.ndarray, tuple[int, ...]]] = []
    if rev[3] and rev[4] and rev[5] and st.common_point((3, 4, 5)):
        out.append(("wrist", np.array(st.points[(3, 4)]), (3,)))
    if rev[4] and rev[5] and st.intersecting(4, 5):
        out.append(("pair", np.array(st.points[(4, 5)]), (0, 1, 2, 3)))
    return out


def continuum_covered(plan: Plan, found: list[Plan], robot: Robot) -> bool:
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
