"""The decoupled family: three slides and three revolute joints in any order (a closed form).

Slides do not turn the tool, so the tool's orientation depends on the three revolute joints alone, whatever their
offsets: ``R_target R_end^T = R(h_a, qa) R(h_b, qb) R(h_c, qc)`` (a < b < c the revolute joints). Joint c's axis
turned onto its target direction fixes qa and qb (``sp2``, two pairs), a vector normal to it fixes qc (``sp1``).
With the angles known, the tool position is linear in the travels: ``t = p0 + sum_k R_k h_k d_k``, ``R_k`` the
rotations of the revolute joints before slide k and ``p0`` the position with every slide at 0 (``lines3``). Two
branches; a Cartesian gantry carrying any wrist (its axes meeting or not) is one.

Blind spots, each a continuum rather than a miss, each given as one member that ``GeometricReduction.
continuum_joints`` hands to the engine to trace: joint c's target axis on joint a's (``sp2`` degenerate: qa and qc
turn together; traced along joint a), and slide directions that turn dependent (a revolute joint before a slide
turning it into the plane of the others: the travels along their common null direction; traced along the slide
that moves most).

The kernels read the generic parameter row of :mod:`.geometric` (``LAYOUT``): the chain's axes, segments and joint
types, the target orientation ``M`` and the target of ``W``, here the tool origin.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sweepik._jit import ERROR_MODEL, inlined
from sweepik.model.chain import Chain, rotation_about
from sweepik.reductions.geometric import _P, _REV, _T, _h, _mat, _v
from sweepik.subproblems import lines2, lines3, sp1, sp2
from sweepik.subproblems.prismatic import PARALLEL_DET
from sweepik.subproblems.vec import add, cross, dot, norm, orthogonal, rot, scale

__all__ = ["decoupled_applies", "configuration", "configurations", "singular_flags", "DEPENDENT_SLIDES"]

#: The slides' directions (unit vectors) are dependent where ``|det|`` of the three is at most this: the travels are
#: then a continuum where the tool position is reachable (one member given, ``singular_flags`` marks the pose).
#: Above it, nearly dependent slides give one isolated solution (``lines3``'s threshold: its travels are then
#: accurate to rounding / |det|, and the engine polishes them).
DEPENDENT_SLIDES = PARALLEL_DET
#: The family applies where ``|det|`` of the slides' directions is above this at random orientations.
INDEPENDENT_SLIDES = 1e-6
#: ``|h_a x M h_c|`` below this: joint c's target axis on joint a's (the orientation is singular, a continuum).
ORIENTATION_SINGULAR = 1e-7


@inlined
def _joints(p):
    """``(revolute a, b, c, slides k0, k1, k2)``: joint indices by type, in chain order (the plan has three each)."""
    r0 = r1 = r2 = s0 = s1 = s2 = 0
    nr = ns = 0
    for i in range(6):
        if p[_REV + i] > 0.5:
            if nr == 0:
                r0 = i
            elif nr == 1:
                r1 = i
            else:
                r2 = i
            nr += 1
        else:
            if ns == 0:
                s0 = i
            elif ns == 1:
                s1 = i
            else:
                s2 = i
            ns += 1
    return r0, r1, r2, s0, s1, s2


@inlined
def _before(p, q, i, v):
    """``v`` turned by the revolute joints before joint ``i`` (the last of them first)."""
    for j in range(i - 1, -1, -1):
        if p[_REV + j] > 0.5:
            v = rot(_h(p, j), q[j], v)
    return v


@inlined
def _orientation(p, branch, q):
    """The revolute joints of branch ``branch`` (0, 1) into ``q (6,)`` (the slides 0); False where the target
    orientation is out of reach (``q`` all NaN)."""
    a, b, c, _, _, _ = _joints(p)
    ha, hb, hc = _h(p, a), _h(p, b), _h(p, c)
    v = _mat(p, hc)
    t1a, t2a, t1b, t2b, cos, _ = sp2(v, hc, ha, hb)
    if math.isnan(cos):  # joint c's target axis on joint a's: a continuum; one member
        qa = 0.0
        qb, _ = sp1(hc, v, hb)
    elif abs(cos) > 1.0 + 1e-12:
        for i in range(6):
            q[i] = math.nan
        return False
    elif branch == 0:
        qa, qb = -t1a, t2a
    else:
        qa, qb = -t1b, t2b
    e = orthogonal(hc)
    qc, _ = sp1(e, rot(hb, -qb, rot(ha, -qa, _mat(p, e))), hc)
    for i in range(6):
        q[i] = 0.0
    q[a], q[b], q[c] = qa, qb, qc
    return True


@inlined
def _slides(p, q):
    """The slides' directions at the revolute joints of ``q``, in chain order."""
    _, _, _, k0, k1, k2 = _joints(p)
    return _before(p, q, k0, _h(p, k0)), _before(p, q, k1, _h(p, k1)), _before(p, q, k2, _h(p, k2))


@inlined
def _solve(p, branch, q):
    """Branch ``branch`` (0, 1) into ``q (6,)``; NaN outside the orientation's reach. Where the slides' directions
    are dependent (``|det| <= DEPENDENT_SLIDES``: a continuum along them where the tool position is reachable), the
    member with the third slide (of the two most independent ones' complement) at 0."""
    if not _orientation(p, branch, q):
        return
    _, _, _, k0, k1, k2 = _joints(p)
    pos = _v(p, _P)
    for i in range(6):
        seg = _v(p, _P + 3 * (i + 1))
        if p[_REV + i] > 0.5:
            seg = rot(_h(p, i), q[i], seg)
        pos = add(pos, _before(p, q, i, seg))
    rest = add(_v(p, _T), scale(-1.0, pos))
    u0, u1, u2 = _slides(p, q)
    if abs(dot(u0, cross(u1, u2))) > DEPENDENT_SLIDES:
        q[k0], q[k1], q[k2] = lines3(u0, u1, u2, rest)
        return
    n01, n02, n12 = norm(cross(u0, u1)), norm(cross(u0, u2)), norm(cross(u1, u2))
    if n01 >= n02 and n01 >= n12:
        q[k0], q[k1] = lines2(u0, u1, rest)
    elif n02 >= n12:
        q[k0], q[k2] = lines2(u0, u2, rest)
    else:
        q[k1], q[k2] = lines2(u1, u2, rest)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def configuration(p, x, branch, out):
    """One branch's configuration (``kernels.CONFIGURATION_SIG``; ``x`` unused: nothing is swept)."""
    if branch > 1:
        for i in range(6):
            out[i] = math.nan
        return
    _solve(p, branch, out)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def configurations(p, x, out):
    """Both branches (``kernels.CONFIGURATIONS_SIG``)."""
    for b in range(out.shape[0]):
        configuration(p, x, b, out[b])


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def singular_flags(params, thr, out, low, start, stop):
    """``kernels.SINGULAR_SIG``: ``out[i]`` where joint c's target axis lies on joint a's (a continuum along joint
    a); ``low[i]`` where a branch's slides are dependent (``DEPENDENT_SLIDES``: a continuum along the slides)."""
    q = np.empty(6)
    for i in range(start, stop):
        p = params[i]
        a, _, c, _, _, _ = _joints(p)
        out[i] = norm(cross(_h(p, a), _mat(p, _h(p, c)))) < ORIENTATION_SINGULAR
        low[i] = False
        for branch in range(2):
            if _orientation(p, branch, q):
                u0, u1, u2 = _slides(p, q)
                low[i] |= abs(dot(u0, cross(u1, u2))) <= DEPENDENT_SLIDES


def decoupled_applies(chain: Chain) -> tuple[bool, bool]:
    """``(applies, conditional)``: three slides and three revolute joints, the revolute axes turning the tool
    through every orientation sp2 can reach (a and b, b and c not parallel), the slides independent at random
    orientations (``conditional``: a revolute joint before a slide turns it, so that they may turn dependent
    somewhere)."""
    rev = np.asarray(chain.revolute, dtype=bool)
    if chain.n_joints != 6 or int(rev.sum()) != 3:
        return False, False
    r = np.flatnonzero(rev)
    s = np.flatnonzero(~rev)
    H = chain.H
    if min(np.linalg.norm(np.cross(H[r[0]], H[r[1]])), np.linalg.norm(np.cross(H[r[1]], H[r[2]]))) < 1e-6:
        return False, False
    rng = np.random.default_rng(0)
    dets = []
    for q in rng.uniform(-np.pi, np.pi, (8, 6)):
        cols = []
        for k in s:
            R = np.eye(3)
            for j in range(k):
                if rev[j]:
                    R = R @ rotation_about(H[j], q[j])
            cols.append(R @ H[k])
        dets.append(abs(float(np.linalg.det(np.array(cols)))))
    if min(dets) < INDEPENDENT_SLIDES:
        return False, False
    return True, bool(np.ptp(dets) > 1e-9)
