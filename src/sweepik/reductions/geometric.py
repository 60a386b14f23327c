"""Kinematic families built from subproblems: one compiled kernel per family, over a generic parameter row.

A family knows no arm: it reads the chain's product-of-exponentials geometry (:mod:`sweepik.model.chain`) and the
target from the parameter row (``LAYOUT``), which :mod:`.decompose` fills from the robot's structure. Two families:

``pair`` (one joint swept): the last two axes are revolute and meet at a point ``W`` (a wrist centre) that only
    the first four joints move. Fix one of those four (theta*), place ``W`` with the other three (a case of
    :mod:`.position`), and what is left is the orientation: joints 5 and 6 can turn the tool onto its target
    orientation exactly when joint 5's axis keeps its angle to joint 6's axis in the target, so the signed
    residual is ``h5 . (R_04^T R_target h6) - h5 . h6`` (dimensionless, built from vectors: no angle wrap);
    joints 5 and 6 then follow from ``sp1``. Branches: those of the position case.

``wrist`` (closed form, no sweep): the last three axes are revolute and meet at ``W``. The first three joints
    place ``W`` (a case of :mod:`.position` with joint 4 fixed at any value: it does not move ``W``), joints 4
    and 5 turn joint 6's axis onto its target (``sp2``, 2 branches) and joint 6 follows from ``sp1``. Every
    branch gives a configuration (least squares where it has no exact one); FK certification keeps the solutions.

``parallel`` (closed form, no sweep; the UR family): axes 2, 3, 4 revolute and parallel (direction ``h``), the
    last two revolute. Joints 2-4 turn about ``h`` only, so the height along ``h`` of joint 6's point ``W`` seen
    from joint 1 depends on joints 1 and 5 only, and so does the angle of joint 6's axis to ``h``. When the last
    two axes meet at ``W``: joint 1 from ``sp4`` on the height (or ``lp4`` for a slide; 2 branches), joint 5 from
    ``sp4`` on the angle (2); with an offset between them, both from ``sp6`` (up to 4 pairs). Joint 6 and the sum
    of joints 2-4 follow from ``sp1``, and the planar arm of joints 2-4 places ``W``: joint 3 from ``sp3`` (2),
    joint 2 from ``sp1``, joint 4 from the sum. 8 branches (4 with a slide first). Where joint 6's axis turns onto
    ``h`` the last joints' rotations combine (a continuum, as a singular wrist).

A structure at the base is the same structure at the tool of the reversed chain solving the inverse pose
(``Chain.reversed``): the parameter row then holds the reversed chain and the kernel writes the joints back in
the robot's order.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np
from numba import float64, int64, njit
from numba.extending import register_jitable
from numpy.typing import NDArray

from sweepik._jit import ERROR_MODEL, inlined, writable
from sweepik.engine import parallel
from sweepik.engine.settings import PARALLEL_MIN
from sweepik.reductions.kernels import (
    CONFIGURATION_SIG,
    CONFIGURATIONS_SIG,
    RESIDUAL_SIG,
    RESIDUALS_SIG,
    SWING_SIG,
    LazyKernel,
    address_of,
    as_configuration,
    as_residual,
    as_residuals,
    lazy_njit,
)
from sweepik.reductions.position import BOTH, CASES, FINAL_JOINTS, NEITHER, angle, motion, move, place, reduce_chain
from sweepik.subproblems import in_domain, lp4, sp1, sp1_cs, sp2, sp3_cs, sp4_cs, sp6
from sweepik.subproblems.vec import add, cross, dot, norm, orthogonal, rot, rot_cs, scale, sub

Array = NDArray[np.float64]

#: Parameter row: offsets of each field (a generic layout, the same for every arm and family).
LAYOUT = {
    "H": 0,  # joint axes (6, 3) of the chain solved (reversed for a structure at the base)
    "P": 18,  # segments (7, 3)
    "rev": 39,  # joint types (6,): 1 revolute, 0 prismatic
    "M": 45,  # target orientation R_target @ R_end^T (3, 3), row-major
    "t": 54,  # target position of the wrist centre W
    "W": 57,  # W at the zero configuration
    "O": 60,  # meeting point of the position case's intersecting axes, zero configuration
    "free": 63,  # theta*: index (0-3) of the swept joint among the first four; 3 for the wrist family
    "case": 64,  # position case (index into position.CASES)
    "reversed": 65,  # 1: the chain is reversed, joints are written back in reverse order
    "pos_branches": 66,  # branches of the position case (the wrist family multiplies them by 2)
    "need": 67,  # first-step branches whose residuals the all-branch kernel computes: bit b1 (twins skip some)
    "need_margin": 68,  # steps whose margins the all-branch margin kernel computes: bit k
    "need_amplitude": 69,  # the same for the amplitudes (swing hints)
}
N_PARAMS = 70
# The offsets as module constants (Numba freezes globals into the compiled kernels: a change of LAYOUT needs the
# on-disk cache cleared, see docs/decomposition.md).
_H, _P, _REV, _M = LAYOUT["H"], LAYOUT["P"], LAYOUT["rev"], LAYOUT["M"]
_T, _W, _O, _FREE = LAYOUT["t"], LAYOUT["W"], LAYOUT["O"], LAYOUT["free"]
_CASE, _REVERSED, _POS_BRANCHES = LAYOUT["case"], LAYOUT["reversed"], LAYOUT["pos_branches"]
_NEED, _NEED_MARGIN, _NEED_AMPLITUDE = LAYOUT["need"], LAYOUT["need_margin"], LAYOUT["need_amplitude"]


# Read with constant offsets all over the kernels: as jitable functions (typed for an int64 offset first), not
# dispatchers, which Numba compiles once per literal offset (_h was compiled 7 times, _v 5 times).
@register_jitable
def _v(p, i):
    return (p[i], p[i + 1], p[i + 2])


@register_jitable
def _h(p, i):
    return _v(p, _H + 3 * i)


@inlined
def _mat(p, v):
    """``M v`` for the target orientation ``M`` of the row."""
    m = _M
    return (
        p[m] * v[0] + p[m + 1] * v[1] + p[m + 2] * v[2],
        p[m + 3] * v[0] + p[m + 4] * v[1] + p[m + 5] * v[2],
        p[m + 6] * v[0] + p[m + 7] * v[1] + p[m + 8] * v[2],
    )


@inlined
def _mat_t(p, v):
    """``M^T v``."""
    m = _M
    return (
        p[m] * v[0] + p[m + 3] * v[1] + p[m + 6] * v[2],
        p[m + 1] * v[0] + p[m + 4] * v[1] + p[m + 7] * v[2],
        p[m + 2] * v[0] + p[m + 5] * v[1] + p[m + 8] * v[2],
    )


#: ``position.FINAL_JOINTS`` by case code: 0, 1, 2 for joints a, b, c of the reduced chain, -1 for none.
_FINAL = tuple(-1 if (x := FINAL_JOINTS[c]) is None else "abc".index(x) for c in CASES)


@inlined
def _final_gap(fx, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, ma, mb, mc):
    """The distance of ``W`` from the axis of the joint the case turns last (``fx``: 0, 1, 2 for a, b, c), given the
    motions of the reduced chain's joints (``W - o_a = T_a(pab + T_b(pbc + T_c(pcw)))``): inf where there is no such
    joint or it is a slide. Where it vanishes, that joint turns ``W`` about itself: free as far as ``W`` goes."""
    u = pcw
    h, r = hc, rc
    if fx <= 1:
        u = add(pbc, move(hc, rc, mc, u))
        h, r = hb, rb
        if fx == 0:
            u = add(pab, move(hb, rb, mb, u))
            h, r = ha, ra
    if fx < 0 or not r:
        return math.inf
    return norm(sub(u, scale(dot(u, h), h)))


@inlined
def _arm(p, x, b1, b2, case, f, rev):
    """The first four joints with joint ``free`` at ``x``, on branch ``b1`` of the position case's first step and
    ``b2`` of its second (``position.place``: 0, 1, both or neither): ``(A, B, c1, c2, a1, a2)`` with ``A`` the
    motions ``(m0, m1, m2, m3)`` (``position.motion``) of branch ``2 b1``, ``B`` those of branch ``2 b1 + 1``, the
    cosines ``(c1, c2)`` and amplitudes ``(a1, a2)`` of the case's steps, and the final step's gaps ``(g1, g2)`` on
    branches ``2 b1`` and ``2 b1 + 1`` (``_final_gap``; meaningless where ``b2`` did not ask for the branch).
    ``case`` (the position case), ``f`` (theta*'s index among the first four joints) and ``rev`` (their types, True:
    revolute): constants of the kernel (see ``case_kernels``)."""
    h0, h1, h2, h3 = _h(p, 0), _h(p, 1), _h(p, 2), _h(p, 3)
    r0, r1, r2, r3 = rev
    s0, s1, s2, s3 = _v(p, _P), _v(p, _P + 3), _v(p, _P + 6), _v(p, _P + 9)
    o1 = (s0[0] + s1[0], s0[1] + s1[1], s0[2] + s1[2])
    o2 = (o1[0] + s2[0], o1[1] + s2[1], o1[2] + s2[2])
    o3 = (o2[0] + s3[0], o2[1] + s3[1], o2[2] + s3[2])
    s4 = sub(_v(p, _W), o3)
    mx = motion(rev[f], x)
    tp, ha, hb, hc, pab, pbc, pcw = reduce_chain(h0, h1, h2, h3, r0, r1, r2, r3, s0, s1, s2, s3, s4, f, mx, _v(p, _T))
    meet = _v(p, _O)
    pts = (s0, o1, o2, o3)
    a = 1 if f == 0 else 0
    b = 2 if f <= 1 else 1
    c = 2 if f == 3 else 3
    if case == 2:
        o = sub(meet, pts[a])
    else:
        o = sub(meet, pts[b])
        if f == 1 and r1:
            o = rot_cs(h1, mx[0], mx[1], o)
    ra, rb, rc = rev[a], rev[b], rev[c]
    ma, mb, mc, na, nb, nc, c1, c2, a1, a2 = place(case, b1, b2, tp, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, o)
    fx = _FINAL[case] if 0 <= case < len(_FINAL) else -1
    g1 = _final_gap(fx, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, ma, mb, mc)
    g2 = _final_gap(fx, ha, hb, hc, ra, rb, rc, pab, pbc, pcw, na, nb, nc)
    if f == 0:
        return (mx, ma, mb, mc), (mx, na, nb, nc), c1, c2, a1, a2, g1, g2
    if f == 1:
        return (ma, mx, mb, mc), (na, mx, nb, nc), c1, c2, a1, a2, g1, g2
    if f == 2:
        return (ma, mb, mx, mc), (na, nb, mx, nc), c1, c2, a1, a2, g1, g2
    return (ma, mb, mc, mx), (na, nb, nc, mx), c1, c2, a1, a2, g1, g2


@inlined
def _missing(m0, m1, m2, m3):
    """Some motion is NaN (an unknown case, dependent prismatic directions)."""
    return math.isnan(m0[0] + m0[2] + m1[0] + m1[2] + m2[0] + m2[2] + m3[0] + m3[2])


@inlined
def _orientation(p, m, c1, c2):
    """The pair family's residual for the motions ``m`` of the first four joints and the cosines of the position
    case's steps (``_orientations`` of one branch): NaN outside the branch's domain."""
    return _orientations(p, m, m, c1, c2)[0]


@inlined
def _orientations(p, m, n, c1, c2):
    """The pair family's residuals of two branches of one first step (motions ``m`` and ``n`` of the first four
    joints, the same cosines): joint 5's axis turned by ``R_04``, dotted with the target's joint-6 axis, less
    ``h5 . h6``; NaN outside a branch's domain. The target's axis is computed once for both, and each joint's rotation
    of joint 5's axis once while the two branches' motions and vectors so far agree (from the last joint: the first
    step's joint, and theta* when it is joint 4)."""
    if not (in_domain(c1) and in_domain(c2)):
        return math.nan, math.nan
    h4, h5 = _h(p, 4), _h(p, 5)
    g, k = _mat(p, h5), dot(h4, h5)
    vm, vn = h4, h4
    shared = True
    for i in range(3, -1, -1):
        if p[_REV + i] > 0.5:
            hi = _h(p, i)
            a, b = m[i], n[i]
            vm = rot_cs(hi, a[0], a[1], vm)
            shared = shared and a[0] == b[0] and a[1] == b[1]
            vn = vm if shared else rot_cs(hi, b[0], b[1], vn)
    rm = math.nan if _missing(m[0], m[1], m[2], m[3]) else dot(vm, g) - k
    rn = math.nan if _missing(n[0], n[1], n[2], n[3]) else dot(vn, g) - k
    return rm, rn


@inlined
def _back(p, m0, m1, m2, m3, v):
    """``R_04^T v = R_3^T R_2^T R_1^T R_0^T v``: ``v`` seen from frame 4 (joint 0's rotation undone first)."""
    ms = (m0, m1, m2, m3)
    for i in range(4):
        if p[_REV + i] > 0.5:
            v = rot_cs(_h(p, i), ms[i][0], -ms[i][1], v)
    return v


@inlined
def _last_two(p, m0, m1, m2, m3, h4, h5):
    """Joints 5 and 6 (indices 4, 5) turning the tool onto the target, given the first four."""
    q4, _ = sp1(h5, _back(p, m0, m1, m2, m3, _mat(p, h5)), h4)
    e = orthogonal(h5)
    q5, _ = sp1(e, rot(h4, -q4, _back(p, m0, m1, m2, m3, _mat(p, e))), h5)
    return q4, q5


@inlined
def _write(p, out, m0, m1, m2, m3, q4, q5):
    """The configuration in the robot's joint order (reversed for a reversed chain)."""
    qs = (
        angle(p[_REV] > 0.5, m0),
        angle(p[_REV + 1] > 0.5, m1),
        angle(p[_REV + 2] > 0.5, m2),
        angle(p[_REV + 3] > 0.5, m3),
        q4,
        q5,
    )
    rev = p[_REVERSED] > 0.5
    for i in range(6):
        out[5 - i if rev else i] = qs[i]


@inlined
def _wrist_first(p, m):
    """The wrist family's work shared by a position branch's two wrist branches (motions ``m`` of the first four
    joints): joint 6's target axis seen from frame 4 ``v``, a unit vector normal to joint 6's axis seen from there
    ``be``, and ``sp2`` turning joint 6's axis onto ``v`` with joints 4 and 5."""
    m0, m1, m2, m3 = m
    h3, h4, h5 = _h(p, 3), _h(p, 4), _h(p, 5)
    v = _back(p, m0, m1, m2, m3, _mat(p, h5))
    be = _back(p, m0, m1, m2, m3, _mat(p, orthogonal(h5)))
    return v, be, sp2(v, h5, h3, h4)


@inlined
def _wrist_joints(p, m, v, be, s, wb, out):
    """The configuration of wrist branch ``wb`` (0, 1) given ``_wrist_first``'s ``v, be, s``, into ``out``."""
    m0, m1, m2, _ = m
    h3, h4, h5 = _h(p, 3), _h(p, 4), _h(p, 5)
    t1a, t2a, t1b, t2b, c, _ = s
    if math.isnan(c):  # joint 6's axis on joint 4's: a continuum (wrist singular); one member
        q3 = 0.0
        q4, _ = sp1(h5, v, h4)
    elif wb == 0:
        q3, q4 = -t1a, t2a
    else:
        q3, q4 = -t1b, t2b
    e = orthogonal(h5)
    q5, _ = sp1(e, rot(h4, -q4, rot(h3, -q3, be)), h5)
    _write(p, out, m0, m1, m2, (math.cos(q3), math.sin(q3), 0.0), q4, q5)  # (motion(True, q3))


# Steps of the position case: k = 0 is its first step, k = 1, 2 its second step on the first step's branch k - 1.
# ``_arm(p, x, b1, NEITHER, case, free, rev)`` with ``b1 = 0`` for k = 0, else ``k - 1``, holds step k's cosine at
# index 2 (k = 0) or 3 and its amplitude at 4 or 5. (The margin and amplitude kernels, ``case_kernels``, call _arm
# themselves rather than through a helper: each compiled level re-optimises everything it calls.)


@inlined
def _o3(p):
    """Joint 4's point (index 3) at the zero configuration."""
    o = _v(p, _P)
    for i in range(1, 4):
        o = add(o, _v(p, _P + 3 * i))
    return o


@inlined
def _parallel_g(p, m0, v):
    """``R_0^T M v``: the target orientation seen after joint 1."""
    w = _mat(p, v)
    if p[_REV] > 0.5:
        return rot_cs(_h(p, 0), m0[0], -m0[1], w)
    return w


@inlined
def _parallel_first(p, branch):
    """The parallel family's first steps: motion of joint 1, ``(cos, sin)`` of joint 5, and cosines ``(c0, c4)``
    (``|c| <= 1`` inside the branch's domain; NaN: no such branch). Joint 5 moves ``W`` (joint 6's point) by
    ``s5 = W - O`` (``O`` on joint 5's axis): zero when the last two axes meet."""
    h0, h, h4, h5 = _h(p, 0), _h(p, 1), _h(p, 4), _h(p, 5)
    v = sub(_v(p, _T), _v(p, _P))
    o4 = _v(p, _O)
    s5 = sub(_v(p, _W), o4)
    # the height of W along h seen from joint 1 does not depend on joints 2-4: that of O plus h . R_4 s5
    height = dot(h, add(add(add(_v(p, _P + 3), _v(p, _P + 6)), _v(p, _P + 9)), sub(o4, _o3(p))))
    b4 = (branch // 2) % 2
    if p[_REV] < 0.5:  # a slide first: joint 5 from the angle of joint 6's axis to h, then the slide
        ua, va, ub, vb, c4, _ = sp4_cs(h, h5, h4, dot(h, _mat(p, h5)))
        m4 = (ua, va) if b4 == 0 else (ub, vb)
        m0 = (1.0, 0.0, lp4(h, v, scale(-1.0, h0), height + dot(h, rot_cs(h4, m4[0], m4[1], s5))))
        return m0, m4, 0.0, c4
    if dot(s5, s5) > 0.0:  # an offset wrist: joints 1 and 5 together (sp6), up to 4 pairs
        nh = scale(-1.0, h)
        a, b, n = sp6(h, h0, v, nh, h4, s5, h, h0, _mat(p, h5), nh, h4, h5, height, 0.0)
        k = branch // 2
        if k >= n:
            nan = (math.nan, math.nan, math.nan)
            return nan, (math.nan, math.nan), math.nan, math.nan
        return (math.cos(a[k]), -math.sin(a[k]), 0.0), (math.cos(b[k]), math.sin(b[k])), 0.0, 0.0
    ua, va, ub, vb, c0, _ = sp4_cs(h, v, h0, height)
    m0 = (ua, -va, 0.0) if branch // 4 == 0 else (ub, -vb, 0.0)
    # the angle of joint 6's axis to h does not depend on joints 2-4 or 6
    ua, va, ub, vb, c4, _ = sp4_cs(h, h5, h4, dot(h, _parallel_g(p, m0, h5)))
    m4 = (ua, va) if b4 == 0 else (ub, vb)
    return m0, m4, c0, c4


@inlined
def _parallel_shared(p, branch):
    """The parallel family's work shared by branches ``branch`` and ``branch ^ 1`` (they differ in the planar
    arm's elbow only): ``(ok, m0, m4, c5, s5, cf, sf, d, sp3 of the planar arm)``; ``ok`` False: no such branch."""
    h0, h, h4, h5 = _h(p, 0), _h(p, 1), _h(p, 4), _h(p, 5)
    m0, m4, _, _ = _parallel_first(p, branch)
    s2, s3 = _v(p, _P + 6), _v(p, _P + 9)
    if math.isnan(m0[0] + m0[2]) or branch >= (8 if p[_REV] > 0.5 else 4):
        nan = math.nan
        return False, m0, m4, nan, nan, nan, nan, s2, (nan, nan, nan, nan, nan, nan)
    # joint 6: h^T R_0^T M = h^T R_4 R_5, i.e. R_5^T (R_4^T h) = M^T R_0 h
    r0h = rot_cs(h0, m0[0], m0[1], h) if p[_REV] > 0.5 else h
    c5, s5 = sp1_cs(rot_cs(h4, m4[0], -m4[1], h), _mat_t(p, r0h), h5)
    s5 = -s5
    # the sum phi of joints 2-4: R(h, phi) = R_0^T M R_5^T R_4^T
    e = orthogonal(h)
    cf, sf = sp1_cs(e, _parallel_g(p, m0, rot_cs(h5, c5, -s5, rot_cs(h4, m4[0], -m4[1], e))), h)
    # the planar arm: R_1 (s2 + R_2 s3) = R_0^T (t - s0) - s1 - R(h, phi) (s4 + R_4 s5)
    s1 = _v(p, _P + 3)
    o4 = _v(p, _O)
    s4 = add(sub(o4, _o3(p)), rot_cs(h4, m4[0], m4[1], sub(_v(p, _W), o4)))
    t0 = sub(_v(p, _T), _v(p, _P))
    if p[_REV] > 0.5:
        t0 = rot_cs(h0, m0[0], -m0[1], t0)
    else:
        t0 = sub(t0, scale(m0[2], h0))
    d = sub(sub(t0, s1), rot_cs(h, cf, sf, s4))
    return True, m0, m4, c5, s5, cf, sf, d, sp3_cs(s3, scale(-1.0, s2), h, norm(d))


@inlined
def _parallel_finish(p, shared, elbow, out):
    """The configuration of the branch with planar-arm elbow ``elbow`` (``branch % 2``) from ``_parallel_shared``."""
    ok, m0, m4, c5, s5, cf, sf, d, planar = shared
    if not ok:
        for i in range(6):
            out[i] = math.nan
        return
    h = _h(p, 1)
    s2, s3 = _v(p, _P + 6), _v(p, _P + 9)
    ua, va, ub, vb, _, _ = planar
    c2, s2_ = (ua, va) if elbow == 0 else (ub, vb)
    c1, s1_ = sp1_cs(add(s2, rot_cs(h, c2, s2_, s3)), d, h)
    # joint 4 = phi - joint 2 - joint 3 (angles as unit complex numbers)
    c12, s12 = c1 * c2 - s1_ * s2_, s1_ * c2 + c1 * s2_
    c3, s3_ = cf * c12 + sf * s12, sf * c12 - cf * s12
    # the angles above turn about h (joint 2's axis); an axis written the other way round (-h) turns by minus them
    g2 = 1.0 if dot(_h(p, 2), h) > 0.0 else -1.0
    g3 = 1.0 if dot(_h(p, 3), h) > 0.0 else -1.0
    _write(
        p,
        out,
        m0,
        (c1, s1_, 0.0),
        (c2, g2 * s2_, 0.0),
        (c3, g3 * s3_, 0.0),
        math.atan2(m4[1], m4[0]),
        math.atan2(s5, c5),
    )


def _parallel_configuration(p, x, branch, out):
    _parallel_finish(p, _parallel_shared(p, branch), branch % 2, out)


def _parallel_configurations(p, x, out):
    """Every branch's ``_parallel_configuration`` at once, ``out (n_branches, 6)`` (``Reduction.
    kernel_configurations``): the two elbows of the planar arm share the rest."""
    n = out.shape[0]
    for pair in range((n + 1) // 2):
        shared = _parallel_shared(p, 2 * pair)
        _parallel_finish(p, shared, 0, out[2 * pair])
        if 2 * pair + 1 < n:
            _parallel_finish(p, shared, 1, out[2 * pair + 1])


def _no_residual(p, x, branch):
    return 0.0


#: Swing hints: up to this many local minima of each step's amplitude per pose, ...
SWING_MINIMA = 4
#: ... each giving its centre and this many samples spread over the window where the angle swings
#: (``centre + w tan(u)``, u uniform in (-pi/2, pi/2), w the window's half-width).
SWING_SAMPLES = 16
#: Golden-section steps locating a minimum between two grid steps (at most; 0.618^50 ~ 3e-11 of the bracket) ...
SWING_GOLDEN = 50
#: ... stopping once the bracket is this fraction of the window's estimated half-width.
SWING_LOCATE = 0.01
#: Only minima below this times the rise to the next sample are located (a window narrower than the grid step
#: has r* < |r'| h, while the rise is at most |r'| h).
SWING_DEPTH = 2.0
#: The amplitudes a swing can be looked for in: the position case's steps (k = 0, 1, 2) and the final step's gap on
#: each position branch (k = 3 ... 6: the joint it turns swings where ``W`` passes next to its axis).
SWING_STEPS = 7
SWING_PER_POSE = SWING_STEPS * SWING_MINIMA * (SWING_SAMPLES + 1)


def _swing(amp, amps, params, lo, hi, n, periodic, ks, out, start, stop):
    """Swing hints of poses ``start .. stop - 1`` (``swing_hints``). ``amp``: the address of ``amplitude``
    (``kernels.address_of``: called, not linked in: Numba re-optimises everything a compiled function links, and the
    amplitude links the whole position case), ``amps`` every step's at once (``amplitudes``, for the scan's samples);
    one function rather than a loop calling a per-pose one, for the same reason."""
    amp, amps = as_residual(amp), as_residuals(amps)
    scan = np.empty((n + 3, SWING_STEPS))  # the amplitudes at lo - h, lo, lo + h, ..., lo + (n + 1) h
    vals = np.empty(SWING_STEPS)
    for i in range(start, stop):
        g = (math.sqrt(5.0) - 1.0) / 2.0
        p = params[i]
        h = (hi[i] - lo[i]) / n
        cnt = 0
        for j in range(n + 3 if ks.shape[0] > 0 else 0):
            amps(p, lo[i] - h if j == 0 else (lo[i] if j == 1 else lo[i] + (j - 1) * h), vals)
            for m in range(SWING_STEPS):
                scan[j, m] = vals[m]
        for k in ks:
            found = 0
            xm, am = lo[i] - h, scan[0, k]
            x0, a0 = lo[i], scan[1, k]
            for j in range(1, n + 2):
                x1 = lo[i] + j * h
                a1 = scan[j + 1, k]
                # a minimum can hide a window narrower than the grid only if it is deep compared with the rise
                # to its neighbours (V-shaped: r = sqrt(r*^2 + r'^2 (x - x*)^2) with r* < |r'| h)
                deep = a0 < SWING_DEPTH * max(am - a0, a1 - a0)
                if a0 <= am and a0 <= a1 and a0 < math.inf and deep and found < SWING_MINIMA:
                    a, b = xm, x1
                    c, d = b - g * (b - a), a + g * (b - a)
                    fc, fd = amp(p, c, k), amp(p, d, k)
                    for _ in range(SWING_GOLDEN):
                        # located well enough: the bracket is a small part of the window it centres
                        fm = min(fc, fd)
                        slope = max(abs(am - fm) / max(c - xm, 1e-300), abs(a1 - fm) / max(x1 - d, 1e-300))
                        if b - a < SWING_LOCATE * fm / max(slope, 1e-300):
                            break
                        if fc < fd:
                            b, d, fd = d, c, fc
                            c = b - g * (b - a)
                            fc = amp(p, c, k)
                        else:
                            a, c, fc = c, d, fd
                            d = a + g * (b - a)
                            fd = amp(p, d, k)
                    xs = 0.5 * (a + b)
                    rs = amp(p, xs, k)
                    slope = max(abs(am - rs) / max(xs - xm, 1e-300), abs(a1 - rs) / max(x1 - xs, 1e-300))
                    if slope > 0.0 and rs < slope * h:
                        w = rs / slope
                        for m in range(SWING_SAMPLES + 1):
                            t = xs
                            if m > 0:
                                t = xs + w * math.tan(math.pi * (m / (SWING_SAMPLES + 1.0) - 0.5))
                            if periodic:
                                t = lo[i] + (t - lo[i]) % (hi[i] - lo[i])
                            if lo[i] <= t <= hi[i]:
                                out[i, cnt] = t
                                cnt += 1
                        found += 1
                xm, am, x0, a0 = x0, a0, x1, a1


def swing_hints(params, lo, hi, n, periodic, ks, out, amplitude, amplitudes):
    """Samples of theta* ``out (N, SWING_PER_POSE)`` (NaN-padded) where a step of the position case is nearly
    degenerate, or the wrist centre passes next to the axis of the joint it turns last: around each local minimum
    ``r*`` of the amplitude (or gap) ``r(theta*)`` narrower than the grid step ``h``, where the angle turns by up to
    pi within ``w = r* / |r'|``. ``ks``: the amplitudes to examine (see
    ``amplitude`` of ``case_kernels``: the arm's kernel, given as ``amplitude``, with ``amplitudes`` its all-step
    kernel, which must compute at least the steps ``ks``). Batches use both cores, as the engine's search."""
    parallel.run(
        swing,
        params.shape[0],
        PARALLEL_MIN,
        address_of(amplitude, RESIDUAL_SIG),
        address_of(amplitudes, RESIDUALS_SIG),
        params,
        writable(lo),
        writable(hi),
        n,
        periodic,
        ks,
        out,
    )


#: ``_swing`` with its signature (``kernels.SWING_SIG``): the engine calls it by its address too
#: (``search.EdgeSearch``).
swing = LazyKernel(_swing, SWING_SIG, cache=True, nogil=True)


wrist_residual = LazyKernel(_no_residual, RESIDUAL_SIG, cache=True)
parallel_configuration = LazyKernel(_parallel_configuration, CONFIGURATION_SIG, cache=True)
parallel_configurations = LazyKernel(_parallel_configurations, CONFIGURATIONS_SIG, cache=True)


# Kernels enter as addresses (``kernels.address_of``) through an explicit signature: compiled once and cached (a
# dispatcher argument would be typed, compiled and appended to the cache anew in every process).
_EVALUATE_SIG = (
    int64,
    float64[:, ::1],
    int64[::1],
    float64[::1],
    int64[::1],
    float64[::1],
)
_CONFIGURE_SIG = (
    int64,
    float64[:, ::1],
    int64[::1],
    float64[::1],
    int64[::1],
    float64[:, ::1],
)


@lazy_njit(_EVALUATE_SIG, cache=True)
def _evaluate(res, params, pose, theta, branch, out):
    res = as_residual(res)
    for k in range(pose.shape[0]):
        out[k] = res(params[pose[k]], theta[k], branch[k])


@lazy_njit(_CONFIGURE_SIG, cache=True)
def _configure(cfg, params, pose, theta, branch, out):
    cfg = as_configuration(cfg)
    for k in range(pose.shape[0]):
        cfg(params[pose[k]], theta[k], branch[k], out[k])


def evaluate(res, params, pose, theta, branch, out):
    """``out[k] = res(params[pose[k]], theta[k], branch[k])`` (a vectorised residual for the reduction's NumPy
    methods)."""
    _evaluate(address_of(res, RESIDUAL_SIG), params, pose, theta, branch, out)


def configure(cfg, params, pose, theta, branch, out):
    """``cfg(params[pose[k]], theta[k], branch[k], out[k])`` for every k."""
    _configure(address_of(cfg, CONFIGURATION_SIG), params, pose, theta, branch, out)


#: ``_evaluate``'s (the last array: the candidates' errors), then the tolerance, branches per position branch,
#: thresholds, joints and the output.
_CONTINUUM_SIG = _EVALUATE_SIG + (float64, int64, float64[::1], int64[::1], int64[::1])


@lazy_njit(_CONTINUUM_SIG, cache=True, nogil=True)
def _continuum_rows(amp, params, pose, theta, branch, err, tol, div, thr, joints, out):
    amp = as_residual(amp)
    flagged = 0
    for k in range(pose.shape[0]):
        out[k] = -1
        if not err[k] <= tol:
            continue
        p = params[pose[k]]
        pb = branch[k] // div  # (the position branch)
        if joints[2] >= 0 and amp(p, theta[k], 3 + pb) < thr[3]:
            out[k] = joints[2]
        if joints[1] >= 0:
            s = 1 + pb // 2
            if amp(p, theta[k], s) < thr[s]:
                out[k] = joints[1]
        if joints[0] >= 0 and amp(p, theta[k], 0) < thr[0]:
            out[k] = joints[0]
        flagged += out[k] >= 0
    return flagged


def continuum_rows(amplitude, params, pose, theta, branch, err, tol, div, thr, joints, out):
    """For candidates ``(pose[k], theta[k], branch[k])`` with ``err[k] <= tol`` (the others: -1): ``out[k]`` the
    joint that a step of the position case leaves free there (its amplitude, ``amplitude`` of ``case_kernels`` given
    by its address, ``kernels.address_of``, below ``thr[step]``; ``joints``: the first and second steps' joints and
    the final step's, -1 for none, its gap below ``thr[3]``; the first step's wins), else -1. ``div``: branches per
    position branch (2 for the wrist family). Returns the number of rows flagged."""
    return _continuum_rows(amplitude, params, pose, theta, branch, err, tol, div, thr, joints, out)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def pose_rows(poses, base, tool, reverse, r_end, w_tool, row, out):
    """The parameter rows ``out (N, N_PARAMS)`` of chain poses ``(N, 4, 4)``: ``row`` (the arm's fixed part) with the
    target orientation ``R r_end^T`` and wrist centre ``p + R w_tool`` of ``base @ pose @ tool`` (its inverse for a
    ``reverse``d chain), as ``GeometricReduction._params`` computes them with NumPy (one call instead of ~10 NumPy
    calls on small arrays: ~10 us of a one-pose solve)."""
    R, Rt, p, q = np.empty((3, 3)), np.empty((3, 3)), np.empty(3), np.empty(3)
    for i in range(poses.shape[0]):
        T = poses[i]
        for a in range(3):  # base @ pose (rotation, then translation)
            for c in range(3):
                R[a, c] = base[a, 0] * T[0, c] + base[a, 1] * T[1, c] + base[a, 2] * T[2, c]
            p[a] = base[a, 0] * T[0, 3] + base[a, 1] * T[1, 3] + base[a, 2] * T[2, 3] + base[a, 3]
        for a in range(3):  # ... @ tool
            for c in range(3):
                Rt[a, c] = R[a, 0] * tool[0, c] + R[a, 1] * tool[1, c] + R[a, 2] * tool[2, c]
            p[a] = R[a, 0] * tool[0, 3] + R[a, 1] * tool[1, 3] + R[a, 2] * tool[2, 3] + p[a]
        if reverse:  # the inverse transform
            for a in range(3):
                q[a] = -(Rt[0, a] * p[0] + Rt[1, a] * p[1] + Rt[2, a] * p[2])
            for a in range(3):
                p[a] = q[a]
                for c in range(a + 1, 3):
                    Rt[a, c], Rt[c, a] = Rt[c, a], Rt[a, c]
        o = out[i]
        for k in range(row.shape[0]):
            o[k] = row[k]
        for a in range(3):
            for c in range(3):
                o[_M + 3 * a + c] = Rt[a, 0] * r_end[c, 0] + Rt[a, 1] * r_end[c, 1] + Rt[a, 2] * r_end[c, 2]
            o[_T + a] = p[a] + (Rt[a, 0] * w_tool[0] + Rt[a, 1] * w_tool[1] + Rt[a, 2] * w_tool[2])


#: A closed form's wrist is singular (joint 6's target axis along joint 4's, or along the parallel axes: a continuum
#: of solutions) when the sine of the angle between them is below 1e-9; within this of it the closed form's angles
#: carry the square root of the rounding (~1e-8) and can miss the pose by far more than the certification accepts.
#: Poses that near are solved by the fallback sweep instead (``GeometricReduction.degenerate``).
WRIST_SINGULAR = 1e-6


@inlined
def _shoulder_flat(p):
    """The parallel family (joint 1 revolute): joint 6's point ``W`` lies on joint 1's axis, within ``WRIST_SINGULAR``
    of its distance from joint 1's point (``parallel_singular``)."""
    if p[_REV] < 0.5:
        return False
    v = sub(_v(p, _T), _v(p, _P))
    return norm(cross(_h(p, 0), v)) <= WRIST_SINGULAR * norm(v)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def parallel_shoulder(params, out, start, stop):
    """``out[i]`` for poses ``start .. stop - 1``: the poses of ``parallel_singular`` whose joint 1 turns freely
    (``_shoulder_flat``; the others' continua turn joints 2-4 and 6)."""
    for i in range(start, stop):
        out[i] = _shoulder_flat(params[i])


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def parallel_singular(params, out, start, stop):
    """``out[i]`` for poses ``start .. stop - 1``: some exact branch of joint 1 leaves pose i with joint 6's axis
    along the parallel axes (joint 6 and the sum of joints 2-4 then turn about one direction: a continuum), or
    joint 6's point ``W`` lies on joint 1's axis (within ``WRIST_SINGULAR`` of its distance from joint 1's point):
    joint 1's ``sp4`` on the height of ``W`` no longer involves joint 1. Reachable only where that height is 0 (axes
    1 and 2 meet: a Unitree Z1), and there joint 1 turns freely, the others following: a continuum."""
    h, h5 = _h(params[0], 1), _h(params[0], 5)
    for i in range(start, stop):
        p = params[i]
        out[i] = False
        if _shoulder_flat(p):
            out[i] = True
            continue
        for b in range(0, 8, 2):
            m0, _, c0, _ = _parallel_first(p, b)
            if math.isnan(m0[0] + m0[2]) or not in_domain(c0):
                continue
            # joint 6's axis seen after joint 1 along h (judged before joint 5's sp4, whose angle near there
            # carries the square root of the rounding)
            if norm(cross(_parallel_g(p, m0, h5), h)) < WRIST_SINGULAR:
                out[i] = True


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def parallel_singular_flags(params, thr, out, low, start, stop):
    """``parallel_singular`` with the signature of the other families' ``wrist_singular`` (``kernels.SINGULAR_SIG``):
    ``low`` all False (the parallel family's steps have no amplitudes), ``thr`` unused."""
    parallel_singular(params, out, start, stop)
    for i in range(start, stop):
        low[i] = False


class CaseKernels(NamedTuple):
    """The compiled kernels of the pair and wrist families for one position case (``position.CASES``): Python calls
    ``wrist_singular(params, thr, out, low, start, stop)``; the others are :class:`~.kernels.LazyKernel` objects with
    the engine's signatures (``pair_margin`` and ``amplitude`` take the step ``k`` where the others take a branch;
    ``pair_residuals`` and ``pair_margins`` are their all-branch kernels, ``Reduction.kernel_residuals``;
    ``pair_every`` the residuals and margins at once)."""

    pair_residual: Any
    pair_residuals: Any
    pair_every: Any
    pair_configuration: Any
    pair_margin: Any
    pair_margins: Any
    amplitude: Any
    amplitudes: Any
    wrist_configuration: Any
    wrist_configurations: Any
    wrist_singular: Any


_CASE_KERNELS: dict[tuple[int, int, tuple[bool, ...]], CaseKernels] = {}


def _residual_kernels(case: int, free: int, rev: tuple[bool, ...]) -> tuple[Any, ...]:
    """``case_kernels``' residuals: one branch's, every branch's, and every branch's with the margins."""

    def residual(p, x, branch):
        arm = _arm(p, x, branch // 2, branch % 2, case, free, rev)
        m = arm[0] if branch % 2 == 0 else arm[1]
        return _orientation(p, m, arm[2], arm[3])

    def residuals(p, x, out):
        """Every branch's ``residual`` at once (``Reduction.kernel_residuals``): the two branches of each first
        step share its work, and a first step whose branches the search skips (twins, ``LAYOUT['need']``) is
        not computed (its entries are left as they are)."""
        nb = int(p[_POS_BRANCHES])
        need = int(p[_NEED])
        both = BOTH + 0 * nb  # (a run-time value: see position.place)
        if nb == 4 and need & 3 == 3:
            # the usual case written out: both first-step branches in one stretch of code, so that the compiler
            # shares their common work (theta*'s motion, the reduced chain) and interleaves the rest
            a0 = _arm(p, x, 0 * nb, both, case, free, rev)
            a1 = _arm(p, x, 1 + 0 * nb, both, case, free, rev)
            r0, r1 = _orientations(p, a0[0], a0[1], a0[2], a0[3])
            r2, r3 = _orientations(p, a1[0], a1[1], a1[2], a1[3])
            out[0], out[1], out[2], out[3] = r0, r1, r2, r3
            return
        for b1 in range((nb + 1) // 2):
            if need & (1 << b1):
                arm = _arm(p, x, b1, both, case, free, rev)
                out[2 * b1] = _orientation(p, arm[0], arm[2], arm[3])
                if 2 * b1 + 1 < nb:
                    out[2 * b1 + 1] = _orientation(p, arm[1], arm[2], arm[3])

    def every(p, x, out):
        """``residuals`` of the four branches and ``margins`` of the three steps at once, into ``out[:4]`` and
        ``out[4:7]``, bit for bit theirs (the margins' cosines are those the residuals' first four joints come
        from): the engine's uniform samples (``search.EdgeSearch.every``) for a plan that searches both
        first-step branches (``LAYOUT['need']`` 3)."""
        nb = int(p[_POS_BRANCHES])
        both = BOTH + 0 * nb  # (a run-time value: see position.place)
        a0 = _arm(p, x, 0 * nb, both, case, free, rev)
        a1 = _arm(p, x, 1 + 0 * nb, both, case, free, rev)
        r0, r1 = _orientations(p, a0[0], a0[1], a0[2], a0[3])
        r2, r3 = _orientations(p, a1[0], a1[1], a1[2], a1[3])
        out[0], out[1], out[2], out[3] = r0, r1, r2, r3
        out[4] = 1.0 - a0[2] * a0[2]
        out[5] = 1.0 - a0[3] * a0[3]
        out[6] = 1.0 - a1[3] * a1[3]

    return residual, residuals, every


def _step_kernels(case: int, free: int, rev: tuple[bool, ...]) -> tuple[Any, ...]:
    """``case_kernels``' configuration of a branch, and the steps' margins and amplitudes."""

    def configuration(p, x, branch, out):
        arm = _arm(p, x, branch // 2, branch % 2, case, free, rev)
        m0, m1, m2, m3 = arm[0] if branch % 2 == 0 else arm[1]
        if _missing(m0, m1, m2, m3):
            for i in range(6):
                out[i] = math.nan
            return
        q4, q5 = _last_two(p, m0, m1, m2, m3, _h(p, 4), _h(p, 5))
        _write(p, out, m0, m1, m2, m3, q4, q5)

    def margin(p, x, k):
        """``1 - c^2`` of step k's cosine c: positive inside the branch domains, zero at their edges (found by
        the same sweep, and sampled as hints)."""
        if k == 0:  # (the first step's cosine alone: the compiler drops the second step)
            arm = _arm(p, x, 0 * k, NEITHER + 0 * k, case, free, rev)
            return 1.0 - arm[2] * arm[2]
        arm = _arm(p, x, k - 1, NEITHER + 0 * k, case, free, rev)
        return 1.0 - arm[3] * arm[3]

    def margins(p, x, out):
        """``margin`` of steps 0 and 1 (one first-step branch) and of step 2 (the other) at once, as they are
        wanted (``LAYOUT['need_margin']``: bit k for step k)."""
        need = int(p[_NEED_MARGIN])
        neither = NEITHER + 0 * need
        if need & 3:
            arm = _arm(p, x, 0 * need, neither, case, free, rev)
            out[0] = 1.0 - arm[2] * arm[2]
            out[1] = 1.0 - arm[3] * arm[3]
        if need & 4:
            arm = _arm(p, x, 1 + 0 * need, neither, case, free, rev)
            out[2] = 1.0 - arm[3] * arm[3]

    def amplitude(p, x, k):
        """Amplitude of step k (see ``margin``); for k >= 3 the final step's gap on position branch k - 3
        (``_final_gap``)."""
        if k >= 3:
            pb = k - 3
            arm = _arm(p, x, pb // 2, pb % 2, case, free, rev)
            return arm[6] if pb % 2 == 0 else arm[7]
        if k == 0:  # (the first step alone, as ``margin``)
            arm = _arm(p, x, 0 * k, NEITHER + 0 * k, case, free, rev)
            return arm[4]
        arm = _arm(p, x, k - 1, NEITHER + 0 * k, case, free, rev)
        return arm[5]

    def amplitudes(p, x, out):
        """``amplitude`` of the steps wanted (``LAYOUT['need_amplitude']``: bit k for step k, k >= 3 the final
        step's gaps) at once, into ``out (SWING_STEPS,)``."""
        need = int(p[_NEED_AMPLITUDE])
        neither, both = NEITHER + 0 * need, BOTH + 0 * need
        if need & 27:  # (steps 0, 1; the gaps of position branches 0, 1)
            arm = _arm(p, x, 0 * need, both if need & 24 else neither, case, free, rev)
            out[0], out[1] = arm[4], arm[5]
            if need & 24:
                out[3], out[4] = arm[6], arm[7]
        if need & 100:  # (step 2; the gaps of position branches 2, 3)
            arm = _arm(p, x, 1 + 0 * need, both if need & 96 else neither, case, free, rev)
            out[2] = arm[5]
            if need & 96:
                out[5], out[6] = arm[6], arm[7]

    return configuration, margin, margins, amplitude, amplitudes


def _wrist_kernels(case: int, free: int, rev: tuple[bool, ...]) -> tuple[Any, ...]:
    """``case_kernels``' wrist family configurations (one branch, every branch) and its singular-wrist test."""

    def wrist(p, x, branch, out):
        nb = int(p[_POS_BRANCHES])
        pb = branch // 2  # the position branch
        arm = _arm(p, 0.0, pb // 2, pb % 2, case, free, rev)
        m = arm[0] if pb % 2 == 0 else arm[1]
        if _missing(m[0], m[1], m[2], m[3]) or branch >= 2 * nb:
            for i in range(6):
                out[i] = math.nan
            return
        v, be, s = _wrist_first(p, m)
        _wrist_joints(p, m, v, be, s, branch % 2, out)

    def wrists(p, x, out):
        """Every branch's ``wrist`` configuration at once, ``out (n_branches, 6)`` (``Reduction.
        kernel_configurations``): the two branches of a first position step share its work (``_arm`` with
        ``BOTH``), the two wrist branches of a position branch share their ``sp2``."""
        nb = int(p[_POS_BRANCHES])
        both = BOTH + 0 * nb  # (a run-time value: see position.place)
        for b1 in range((nb + 1) // 2):
            arm = _arm(p, 0.0, b1, both, case, free, rev)
            for j in range(2):
                pb = 2 * b1 + j
                if pb >= nb:
                    break
                m = arm[0] if j == 0 else arm[1]
                if _missing(m[0], m[1], m[2], m[3]):
                    for i in range(6):
                        out[2 * pb, i] = math.nan
                        out[2 * pb + 1, i] = math.nan
                    continue
                v, be, s = _wrist_first(p, m)
                _wrist_joints(p, m, v, be, s, 0, out[2 * pb])
                _wrist_joints(p, m, v, be, s, 1, out[2 * pb + 1])
        for r in range(2 * nb, out.shape[0]):
            for i in range(6):
                out[r, i] = math.nan

    def singular(params, thr, out, low, start, stop):
        """``out[i]`` for poses ``start .. stop - 1``: some exact position branch of the wrist family leaves
        pose i with a singular wrist; ``low[i]``: the amplitude of a step of the position case is below its
        threshold ``thr[k]`` (``k = 0, 1, 2`` as ``amplitude`` numbers them: a joint left free there)."""
        h3, h5 = _h(params[0], 3), _h(params[0], 5)
        for i in range(start, stop):
            p = params[i]
            out[i] = False
            low[i] = False
            nb = int(p[_POS_BRANCHES])
            both = BOTH + 0 * nb  # (a run-time value: see position.place)
            for b1 in range((nb + 1) // 2):
                # the two branches of a first step share its work (as in ``wrists``, the same values)
                arm = _arm(p, 0.0, b1, both, case, free, rev)
                if arm[4] < thr[0] or arm[5] < thr[1 + b1]:
                    low[i] = True
                for j in range(2):
                    if 2 * b1 + j >= nb:
                        break
                    if (arm[6] if j == 0 else arm[7]) < thr[3]:
                        low[i] = True
                    m0, m1, m2, m3 = arm[0] if j == 0 else arm[1]
                    if _missing(m0, m1, m2, m3) or not (in_domain(arm[2]) and in_domain(arm[3])):
                        continue
                    v = _back(p, m0, m1, m2, m3, _mat(p, h5))
                    if norm(cross(v, h3)) < WRIST_SINGULAR:
                        out[i] = True

    return wrist, wrists, singular


def case_kernels(case: int, free: int, revolute: tuple[bool, ...]) -> CaseKernels:
    """The pair and wrist families' kernels for position case ``case`` (its index in ``position.CASES``; -1: none),
    theta* the joint ``free`` (0-3) of the solved chain's first four, whose types are ``revolute`` (4 booleans).

    One set per arm structure, each compiled on first use: these are constants of the kernels (closure variables,
    which Numba types as literals), so an arm compiles the chain of subproblems of its own case only and not the
    others' (``position.place``), and the compiler drops the branches for other theta* and joint types (about 15 %
    of a residual's time). Numba's disk cache keeps one entry per set (it keys a closure on its variables).
    """
    case, free = int(case), int(free)
    rev = tuple(bool(r) for r in revolute)
    if len(rev) != 4 or not 0 <= free <= 3:
        raise ValueError(f"case_kernels: free={free} must be 0-3 and revolute 4 booleans, not {revolute!r}")
    key = (case, free, rev)
    ck = _CASE_KERNELS.get(key)
    if ck is None:
        # (the kernels are closures over the case, each written out in full, not calling functions with the case:
        # Numba re-optimises all that a compiled function calls, and a level more costs ~0.3 s per kernel on a fresh
        # install)
        residual, residuals, every = _residual_kernels(case, free, rev)
        configuration, margin, margins, amplitude, amplitudes = _step_kernels(case, free, rev)
        wrist, wrists, singular = _wrist_kernels(case, free, rev)
        ck = _CASE_KERNELS[key] = CaseKernels(
            LazyKernel(residual, RESIDUAL_SIG, cache=True),
            LazyKernel(residuals, RESIDUALS_SIG, cache=True),
            LazyKernel(every, RESIDUALS_SIG, cache=True),
            LazyKernel(configuration, CONFIGURATION_SIG, cache=True),
            LazyKernel(margin, RESIDUAL_SIG, cache=True),
            LazyKernel(margins, RESIDUALS_SIG, cache=True),
            LazyKernel(amplitude, RESIDUAL_SIG, cache=True),
            LazyKernel(amplitudes, RESIDUALS_SIG, cache=True),
            LazyKernel(wrist, CONFIGURATION_SIG, cache=True),
            LazyKernel(wrists, CONFIGURATIONS_SIG, cache=True),
            njit(cache=True, nogil=True, error_model=ERROR_MODEL)(singular),
        )
    return ck
