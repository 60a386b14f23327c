"""Placing a point with three joints: the position part of a geometric decomposition.

A family (:mod:`.geometric`) fixes all but three of the joints that move a point ``W`` (a wrist centre: the
point where the last axes meet, which the remaining joints do not move) and asks for the three joint values
``a < b < c`` that put ``W`` on its target. That is one of the chains of subproblems below, chosen once per
arm by :mod:`.decompose` from the chain's structure (``CASES``):

===========  ============================================  ===========================================
case         structure                                     subproblem chain (branches)
===========  ============================================  ===========================================
``ab_par``   a, b revolute and parallel                    c: sp4 on the a-height (2) or lp4 (1); b: sp3
                                                           (2); a: sp1
``bc_par``   b, c revolute and parallel                    a: sp4 on the b-height (2) or lp4 (1); c: sp3
                                                           (2); b: sp1
``ab_int``   a, b revolute, axes meet at O                 c: sp3 / lp3 on the distance from O (2);
                                                           a, b: sp2 (2)
``bc_int``   b, c revolute, axes meet at O                 a: sp3 / lp3 on the distance from O (2);
                                                           b, c: sp2 (2)
``ppp``      three prismatic                               lines3 (1)
``ppr``      a, b prismatic, c revolute                    c: sp4 on the normal of a, b (2); a, b: lines2
``ac_par``   a, c revolute and parallel, b prismatic       b: lp4 on the a-height (1); c: sp3 (2); a: sp1
``rpp``      a revolute, b, c prismatic                    a: sp4 on the normal of b, c (2); b, c: lines2
``rrr``      three revolute, no structure (wrist family    a, b, c: sp5, a quartic (4)
             only: its roots are not branches a sweep
             could follow)
===========  ============================================  ===========================================

Outside a branch's domain (a circle or line that misses its sphere or plane) a step continues with its
least-squares angle or travel (so configurations stay defined for certification and polish) and reports its
cosine ``|c| > 1``: the family's residual is NaN there, and the domain edges (``|c| = 1``, where a step's two
branches meet) are sampled (:mod:`.generic`).

The reduced chain (``reduce_chain``) is written in product-of-exponentials form: with segments ``s0 .. s4``
(``s0`` from the world origin to joint 0's point, ``s_i`` from joint i-1's point to joint i's, ``s4`` from joint
3's point to ``W``), ``W = s0 + T0(s1 + T1(s2 + T2(s3 + T3(s4))))`` where ``T_i`` rotates about (revolute) or
slides along (prismatic) joint i's axis. The fixed joint ``f`` is absorbed into the segments and the axes that
follow it.
"""

from __future__ import annotations

import math

from numba import njit, types
from numba.extending import overload

from sweepik._jit import ERROR_MODEL, inlined
from sweepik.subproblems import lines2, lines3, lp3, lp4, sp1_cs, sp2_cs, sp3_cs, sp4_cs, sp5
from sweepik.subproblems.vec import add, cross, dot, norm, rot_cs, scale, sub, unit

__all__ = [
    "CASES",
    "BRANCHES",
    "STEP_JOINTS",
    "FINAL_JOINTS",
    "BOTH",
    "NEITHER",
    "reduce_chain",
    "place",
    "motion",
    "angle",
    "move",
    "move_back",
]

#: Case names, in the order of their integer codes in a family's parameter row.
CASES = ("ab_par", "bc_par", "ab_int", "bc_int", "ppp", "ppr", "ac_par", "rpp", "rrr")
#: Branches of each case: (with the first unknown revolute, with it prismatic) for the cases where it matters.
BRANCHES = {
    "ab_par": (4, 2),  # indexed by joint c's type
    "bc_par": (4, 2),  # indexed by joint a's type
    "ab_int": (4, 4),
    "bc_int": (4, 4),
    "ppp": (1, 1),
    "ppr": (2, 2),
    "ac_par": (2, 2),
    "rpp": (2, 2),
    "rrr": (4, 4),
}

#: The joint (``a``, ``b`` or ``c``) that each case's two-solution steps turn, for their amplitudes ``(r1, r2)`` of
#: ``place`` (None: no such step). Where a step's amplitude vanishes its equation no longer involves that joint: the
#: joint is free as far as ``W`` goes (a continuum along it, when the orientation follows it too).
STEP_JOINTS = {
    "ab_par": ("c", "b"),
    "bc_par": ("a", "c"),
    "ab_int": ("c", "a"),
    "bc_int": ("a", "b"),
    "ppp": (None, None),
    "ppr": (None, "c"),
    "ac_par": (None, "c"),
    "rpp": (None, "a"),
    "rrr": (None, None),
}
#: The joint each case turns last by ``sp1`` (None: none, or a slide solved linearly). Where ``W`` lies on its axis
#: (``geometric._final_gap`` vanishes) the step no longer involves it: the joint is free as far as ``W`` goes (the
#: Stanford arm's shoulder joint 2 with its slide at 0, an arm whose wrist centre reaches its shoulder's axis).
FINAL_JOINTS = {
    "ab_par": "a",
    "bc_par": "b",
    "ab_int": "b",
    "bc_int": "c",
    "ppp": None,
    "ppr": None,
    "ac_par": "a",
    "rpp": None,
    "rrr": None,
}


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def motion(rev, x):
    """A joint value as a *motion* ``(cos, sin, travel)``: ``(cos x, sin x, 0)`` for a revolute joint,
    ``(1, 0, x)`` for a prismatic one. Kernels rotate by cosines and sines and never need the angle itself."""
    if rev:
        return math.cos(x), math.sin(x), 0.0
    return 1.0, 0.0, x


@inlined
def angle(rev, m):
    """The joint value of motion ``m`` (radians or travel)."""
    if rev:
        return math.atan2(m[1], m[0])
    return m[2]


@inlined
def _rev(c, s):
    return c, s, 0.0


@inlined
def _pris(t):
    return 1.0, 0.0, t


@inlined
def move(h, rev, m, v):
    """``T(v)``: ``v`` rotated about ``h`` (revolute) or translated along it (prismatic) by motion ``m``."""
    if rev:
        return rot_cs(h, m[0], m[1], v)
    return add(v, scale(m[2], h))


@inlined
def move_back(h, rev, m, v):
    """The inverse of ``move``."""
    if rev:
        return rot_cs(h, m[0], -m[1], v)
    return sub(v, scale(m[2], h))


@inlined
def _turn(h, rev, m, v):
    """The rotation part of ``move`` (directions)."""
    if rev:
        return rot_cs(h, m[0], m[1], v)
    return v


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def reduce_chain(h0, h1, h2, h3, r0, r1, r2, r3, s0, s1, s2, s3, s4, f, x, t):
    """The three-joint problem left when joint ``f`` (0-3) of the first four is fixed at the motion ``x``.

    Returns ``(tp, ha, hb, hc, pab, pbc, pcw)``: the target of ``W`` relative to joint a's point ``tp`` and the
    reduced chain ``W - o_a = T_a(pab + T_b(pbc + T_c(pcw)))`` with the axes of a, b, c. Joint types are those
    of the unknown joints in order (the caller knows them).
    """
    if f == 0:
        tp = sub(move_back(h0, r0, x, sub(t, s0)), s1)
        return tp, h1, h2, h3, s2, s3, s4
    tp = sub(t, s0)
    if f == 1:
        return (
            tp,
            h0,
            _turn(h1, r1, x, h2),
            _turn(h1, r1, x, h3),
            add(s1, move(h1, r1, x, s2)),
            _turn(h1, r1, x, s3),
            _turn(h1, r1, x, s4),
        )
    if f == 2:
        return tp, h0, h1, _turn(h2, r2, x, h3), s1, add(s2, move(h2, r2, x, s3)), _turn(h2, r2, x, s4)
    return tp, h0, h1, h2, s1, s2, add(s3, move(h3, r3, x, s4))


#: ``b2`` of ``place``: both second-step branches, or neither (only the cosines and amplitudes are wanted).
BOTH = -1
NEITHER = 2
_NO_ANGLE = (math.nan, math.nan)


@inlined
def _first(b2):
    return b2 == 0 or b2 == BOTH


@inlined
def _second(b2):
    return b2 == 1 or b2 == BOTH


@inlined
def _line_cos(disc, d):
    """A line-sphere discriminant as the cosine of a circle subproblem (|c| <= 1 inside the domain)."""
    if d > 0.0:
        return math.sqrt(max(0.0, d * d - disc)) / d
    return 0.0 if disc >= 0.0 else math.inf


@inlined
def _ab_par(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``ab_par`` of ``place``: the height along h_a does not depend on qa, qb."""
    c1 = 0.0
    r1 = math.inf
    height = dot(ha, sub(sub(tp, pab), pbc))
    if rc:
        ua, va, ub, vb, c1, r1 = sp4_cs(ha, pcw, hc, height)
        mc = _rev(ua, va) if b1 == 0 else _rev(ub, vb)
    else:
        mc = _pris(lp4(ha, pcw, hc, height))
    w = add(pbc, move(hc, rc, mc, pcw))
    ua, va, ub, vb, c2, r2 = sp3_cs(w, scale(-1.0, pab), hb, norm(tp))
    # (rot_cs for move(hb, True, ...): a constant True would have move compiled once more, for its literal type)
    ca, sa = sp1_cs(add(pab, rot_cs(hb, ua, va, w)), tp, ha) if _first(b2) else _NO_ANGLE
    cb, sb = sp1_cs(add(pab, rot_cs(hb, ub, vb, w)), tp, ha) if _second(b2) else _NO_ANGLE
    return _rev(ca, sa), _rev(ua, va), mc, _rev(cb, sb), _rev(ub, vb), mc, c1, c2, r1, r2


@inlined
def _bc_par(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``bc_par`` of ``place``: the height along h_b does not depend on qb, qc."""
    c1 = 0.0
    r1 = math.inf
    height = dot(hb, add(add(pab, pbc), pcw))
    if ra:
        ua, va, ub, vb, c1, r1 = sp4_cs(hb, tp, ha, height)
        ma = _rev(ua, -va) if b1 == 0 else _rev(ub, -vb)
    else:
        ma = _pris(lp4(hb, tp, scale(-1.0, ha), height))
    target = sub(move_back(ha, ra, ma, tp), pab)
    ua, va, ub, vb, c2, r2 = sp3_cs(pcw, scale(-1.0, pbc), hc, norm(target))
    ca, sa = sp1_cs(add(pbc, rot_cs(hc, ua, va, pcw)), target, hb) if _first(b2) else _NO_ANGLE
    cb, sb = sp1_cs(add(pbc, rot_cs(hc, ub, vb, pcw)), target, hb) if _second(b2) else _NO_ANGLE
    return ma, _rev(ca, sa), _rev(ua, va), ma, _rev(cb, sb), _rev(ub, vb), c1, c2, r1, r2


@inlined
def _ab_int(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``ab_int`` of ``place``: |W - O| depends on qc only."""
    c1 = 0.0
    r1 = math.inf
    base = add(sub(pab, o), pbc)
    d = norm(sub(tp, o))
    if rc:
        ua, va, ub, vb, c1, r1 = sp3_cs(pcw, scale(-1.0, base), hc, d)
        mc = _rev(ua, va) if b1 == 0 else _rev(ub, vb)
    else:
        u, v, disc = lp3(add(base, pcw), (0.0, 0.0, 0.0), hc, d)
        c1 = _line_cos(disc, d)
        mc = _pris(u if b1 == 0 else v)
    w0 = add(base, move(hc, rc, mc, pcw))
    c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c2, r2 = sp2_cs(sub(tp, o), w0, ha, hb)
    return _rev(c1a, -s1a), _rev(c2a, s2a), mc, _rev(c1b, -s1b), _rev(c2b, s2b), mc, c1, c2, r1, r2


@inlined
def _bc_int(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``bc_int`` of ``place``: |W - O| is fixed; O moves with joint a only."""
    c1 = 0.0
    r1 = math.inf
    w1 = add(sub(pbc, o), pcw)
    d = norm(w1)
    centre = add(pab, o)
    if ra:
        ua, va, ub, vb, c1, r1 = sp3_cs(centre, tp, ha, d)
        ma = _rev(ua, va) if b1 == 0 else _rev(ub, vb)
    else:
        u, v, disc = lp3(centre, tp, ha, d)
        c1 = _line_cos(disc, d)
        ma = _pris(u if b1 == 0 else v)
    target = sub(move_back(ha, ra, ma, tp), centre)
    c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c2, r2 = sp2_cs(target, w1, hb, hc)
    return ma, _rev(c1a, -s1a), _rev(c2a, s2a), ma, _rev(c1b, -s1b), _rev(c2b, s2b), c1, c2, r1, r2


@inlined
def _ppp(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``ppp`` of ``place`` (one branch: the second outcome repeats the first)."""
    qa, qb, qc = lines3(ha, hb, hc, sub(sub(sub(tp, pab), pbc), pcw))
    ma, mb, mc = _pris(qa), _pris(qb), _pris(qc)
    return ma, mb, mc, ma, mb, mc, 0.0, 0.0, math.inf, math.inf


@inlined
def _ppr(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``ppr`` of ``place``: the height along ha x hb does not depend on qa, qb."""
    n = cross(ha, hb)
    if norm(n) == 0.0:  # parallel slides (a blind spot of a plan whose slides turn with theta*)
        return _no_case(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
    n = unit(n)
    ua, va, ub, vb, c2, r2 = sp4_cs(n, pcw, hc, dot(n, sub(sub(tp, pab), pbc)))
    rest = sub(sub(tp, pab), pbc)
    qa, qb = lines2(ha, hb, sub(rest, rot_cs(hc, ua, va, pcw))) if _first(b2) else _NO_ANGLE
    qa2, qb2 = lines2(ha, hb, sub(rest, rot_cs(hc, ub, vb, pcw))) if _second(b2) else _NO_ANGLE
    return _pris(qa), _pris(qb), _rev(ua, va), _pris(qa2), _pris(qb2), _rev(ub, vb), 0.0, c2, math.inf, r2


@inlined
def _ac_par(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``ac_par`` of ``place``: the height along ha fixes the prismatic b."""
    qb = lp4(ha, add(add(pab, pbc), pcw), hb, dot(ha, tp))
    w = add(add(pab, scale(qb, hb)), pbc)
    ua, va, ub, vb, c2, r2 = sp3_cs(pcw, scale(-1.0, w), hc, norm(tp))
    ca, sa = sp1_cs(add(w, rot_cs(hc, ua, va, pcw)), tp, ha) if _first(b2) else _NO_ANGLE
    cb, sb = sp1_cs(add(w, rot_cs(hc, ub, vb, pcw)), tp, ha) if _second(b2) else _NO_ANGLE
    return _rev(ca, sa), _pris(qb), _rev(ua, va), _rev(cb, sb), _pris(qb), _rev(ub, vb), 0.0, c2, math.inf, r2


@inlined
def _rpp(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``rpp`` of ``place`` (a cylindrical arm's slides after its turn): ``W - o = R_a (p + qb hb + qc hc)``
    with ``p = pab + pbc + pcw``, so the height of ``R_a^T tp`` along ``n = hb x hc`` is ``n . p`` whatever qb, qc:
    ``tp . R_a n = n . p`` (sp4 about h_a, 2 branches); then ``R_a^T tp - p`` along hb and hc (lines2)."""
    n = cross(hb, hc)
    if norm(n) == 0.0:  # parallel slides (a blind spot of a plan whose slides turn with theta*)
        return _no_case(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
    n = unit(n)
    p = add(add(pab, pbc), pcw)
    ua, va, ub, vb, c2, r2 = sp4_cs(tp, n, ha, dot(n, p))
    qb, qc = lines2(hb, hc, sub(rot_cs(ha, ua, -va, tp), p)) if _first(b2) else _NO_ANGLE
    qb2, qc2 = lines2(hb, hc, sub(rot_cs(ha, ub, -vb, tp), p)) if _second(b2) else _NO_ANGLE
    return _rev(ua, va), _pris(qb), _pris(qc), _rev(ub, vb), _pris(qb2), _pris(qc2), 0.0, c2, math.inf, r2


@inlined
def _rrr(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Case ``rrr`` of ``place``: three revolute joints with no structure (a general 3R positioning chain, Pieper's
    arm with a spherical wrist and any shoulder). ``R_a^T tp = pab + R_b(pbc + R_c pcw)`` is SP5 with theta1 =
    -qa: up to four roots of a quartic, position branches 0-3 in the order ``sp5`` gives them; a
    branch with no root is NaN. Both steps report cosine 0 and infinite amplitude: a root of the quartic is
    exact or absent, and a double root (two branches meeting) is found by ``trig.trig2_roots`` as one."""
    t1, t2, t3, n = sp5(scale(-1.0, pab), tp, pbc, pcw, ha, hb, hc)
    i, j = 2 * b1, 2 * b1 + 1
    nan = (math.nan, math.nan, math.nan)
    ma, mb, mc = nan, nan, nan
    na, nb, nc = nan, nan, nan
    if i < n and _first(b2):
        ma, mb, mc = (
            _rev(math.cos(t1[i]), -math.sin(t1[i])),
            _rev(math.cos(t2[i]), math.sin(t2[i])),
            _rev(math.cos(t3[i]), math.sin(t3[i])),
        )
    if j < n and _second(b2):
        na, nb, nc = (
            _rev(math.cos(t1[j]), -math.sin(t1[j])),
            _rev(math.cos(t2[j]), math.sin(t2[j])),
            _rev(math.cos(t3[j]), math.sin(t3[j])),
        )
    return ma, mb, mc, na, nb, nc, 0.0, 0.0, math.inf, math.inf


def place(case, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """Motions putting ``W`` at ``tp`` on branch ``b1`` of the first step and branch ``b2`` of the second (0, 1,
    ``BOTH`` or ``NEITHER``): ``(ma, mb, mc)`` (see ``motion``) of branch ``2 b1``, those of branch ``2 b1 + 1``
    (NaN where not asked for, except in a case that gets them at no cost), the cosines ``(c1, c2)`` of
    the two steps (0 for a one-solution step): ``|c| <= 1`` inside the branch's domain, and their amplitudes
    ``(r1, r2)`` (inf for a one-solution step): where one nears 0 the step's angle swings fast. Outside the domain
    the steps continue with least squares (NaN only for an unknown case or dependent prismatic directions). A case
    whose first step has one solution ignores ``b1`` (its branches are 0 and 1); one with a single branch gives it
    twice.

    Both second-step branches at once (``BOTH``): they share the first step and the second step's subproblem, so
    that a kernel wanting every branch (``geometric.case_kernels``, ``residuals``) does that work once per ``b1``.
    ``b2`` should be a run-time value in the caller (a constant would have Numba compile this once more for its
    literal type); the compiler still drops the unused final steps when the caller's value is known.

    ``o``: for ``ab_int`` the meeting point of axes a and b relative to joint a's point; for ``bc_int`` that of b
    and c relative to joint b's point, in the reduced chain's frame.

    For compiled code only (an ``overload``, ``_place``): with ``case`` a constant of the caller's (a literal type,
    as a family kernel made for one arm's case passes it), only that case's chain of subproblems is compiled, not all
    nine (about 2 s less on a fresh install); with a variable ``case``, every case.
    """
    raise NotImplementedError("position.place is compiled code's")


#: The cases' functions, in the order of ``CASES``.
_CASE_FUNCTIONS = (_ab_par, _bc_par, _ab_int, _bc_int, _ppp, _ppr, _ac_par, _rpp, _rrr)


@inlined
def _no_case(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """An unknown case: NaN motions."""
    nan = (math.nan, math.nan, math.nan)
    return nan, nan, nan, nan, nan, nan, math.nan, math.nan, math.nan, math.nan


@overload(place, prefer_literal=True)
def _place(case, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
    """``place`` in compiled code: the case's own function for a constant ``case``, else a dispatch over them all."""
    if isinstance(case, types.IntegerLiteral):
        k = case.literal_value
        fn = _CASE_FUNCTIONS[k] if 0 <= k < len(_CASE_FUNCTIONS) else _no_case

        def one(case, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
            return fn(b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)

        return one

    def every(case, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o):
        if case == 0:
            return place(0, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 1:
            return place(1, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 2:
            return place(2, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 3:
            return place(3, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 4:
            return place(4, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 5:
            return place(5, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 6:
            return place(6, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 7:
            return place(7, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        if case == 8:
            return place(8, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
        return place(-1, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)

    return every
