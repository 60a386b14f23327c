"""Revolute subproblems: canonical geometric equations in joint angles, solved in closed form (Paden-Kahan;
numbered as in IK-Geo, Elias & Wen 2022).

Every function is a pure function of vectors (3-tuples of floats), compiled with ``numba.njit`` and callable
from Python. Axes ``k`` are unit vectors; angles are radians; ``R(k, theta)`` is the rotation about ``k``.

* ``sp1(p1, p2, k)``: ``R(k, theta) p1 = p2`` (circle-point). One angle; least squares when ``p1``, ``p2`` differ
  in height along ``k`` or in distance from it. Degenerate when ``p1`` lies on the axis (any angle: 0 returned).
* ``sp4(h, p, k, d)``: ``h . R(k, theta) p = d`` (circle-plane). Two angles ``phi +- acos(c)``.
* ``sp3(p1, p2, k, d)``: ``|R(k, theta) p1 - p2| = d`` (circle-sphere), an ``sp4`` in disguise.
* ``sp2(p1, p2, k1, k2)``: ``R(k1, theta1) p1 = R(k2, theta2) p2`` (two circles). Two pairs.
* ``sp5(p0, p1, p2, p3, k1, k2, k3)``: ``p0 + R(k1, theta1) p1 = R(k2, theta2)(p2 + R(k3, theta3) p3)`` (three
  circles). Up to 4 triples.
* ``sp6(h1, k1, p1, ..., d1, d2)``: two equations ``h . R(k, theta1) p + h' . R(k', theta2) p' = d`` (four
  circles). Up to 4 pairs. Both reduce to the roots of a trigonometric polynomial of degree 2 (``trig``).

The two-solution subproblems return both angles, ``c``, the cosine they are built from, and ``r``, the amplitude
it is divided by (its conditioning): ``|c| <= 1`` means
exact solutions (equal ones when ``|c| = 1``, where the two branches meet), ``|c| > 1`` no exact solution (the
angles returned are then the least-squares one, twice), and ``c`` NaN a degenerate case where the angle is
undetermined (0 returned). Callers decide what a small excess of ``|c|`` over 1 means (``in_domain``).

Each has a ``_cs`` form returning the cosine and sine of its angles instead (no atan2, acos, sin or cos: only
square roots), for compiled code that goes on to rotate by them; the angle forms are built on it.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sweepik._jit import ERROR_MODEL, inlined
from sweepik.subproblems.trig import trig2_roots
from sweepik.subproblems.vec import cross, dot, norm, perp, rot, rot_cs, sub

__all__ = [
    "sp1",
    "sp2",
    "sp3",
    "sp4",
    "sp5",
    "sp6",
    "sp1_cs",
    "sp2_cs",
    "sp3_cs",
    "sp4_cs",
    "in_domain",
    "DOMAIN_TOL",
]

#: ``|c|`` up to ``1 + DOMAIN_TOL`` counts as 1 (``in_domain``): rounding of the vectors a subproblem is built
#: from moves ``c`` by a few ulps, and a solution exactly at a branch-domain edge must not turn into "none".
DOMAIN_TOL = 1e-12

#: ``|c|`` within this many roundings of 1 (``eps`` times the magnitudes ``c`` is built from, over ``r``) is 1: the
#: two angles meet. The digits below the rounding carry no information, yet ``sqrt(1 - c^2)`` turns them into two
#: angles ``sqrt(2 tau)`` apart (3 ulps: 2.6e-8) -- which a later ill-conditioned step magnifies: a UR3 on its
#: shoulder fold with the wrist 8.5e-6 from straight had its double root split into two points 3.7e-3 apart (joint 1
#: over the wrist's sine), each solving the pose to rounding, neither the root.
MEET_ROUNDINGS = 4.0
_EPS = float(np.finfo(np.float64).eps)


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def in_domain(c):
    """True when the cosine ``c`` of a two-solution subproblem gives exact (possibly equal) solutions."""
    return abs(c) <= 1.0 + DOMAIN_TOL


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp1_cs(p1, p2, k):
    """``(cos, sin)`` of the least-squares ``theta`` with ``R(k, theta) p1 = p2`` ((1, 0) when degenerate)."""
    a = perp(k, p1)
    b = perp(k, p2)
    x = dot(a, b)
    y = dot(k, cross(a, b))
    n = math.sqrt(x * x + y * y)
    if n == 0.0:
        return 1.0, 0.0
    return x / n, y / n


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp1(p1, p2, k):
    """``theta`` with ``R(k, theta) p1 = p2`` (least squares in general) and the residual ``|R p1 - p2|``."""
    c, s = sp1_cs(p1, p2, k)
    return math.atan2(s, c), norm(sub(rot_cs(k, c, s, p1), p2))


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp4_cs(h, p, k, d):
    """``sp4`` without angles: ``(cos, sin)`` of both solutions, then ``c`` and ``r``:
    ``cos_a, sin_a, cos_b, sin_b, c, r``. The angles are ``phi +- w`` with ``(cos, sin)(phi) = (A, B) / r`` and
    ``cos w = c``, ``sin w = sqrt(1 - c^2)`` (``w`` = 0 or pi outside ``|c| <= 1``: the least-squares angle, and
    within rounding of ``|c| = 1``: ``MEET_ROUNDINGS``)."""
    A = dot(h, perp(k, p))
    B = dot(h, cross(k, p))
    r = math.sqrt(A * A + B * B)
    along = dot(h, k) * dot(k, p)
    if r == 0.0:
        return 1.0, 0.0, 1.0, 0.0, math.nan, 0.0
    c = (d - along) / r
    cp, sp = A / r, B / r
    # tangent (to rounding: ``MEET_ROUNDINGS``) or least squares: one angle
    if abs(c) >= 1.0 - MEET_ROUNDINGS * _EPS * (1.0 + (abs(d) + abs(along)) / r):
        cw = 1.0 if c > 0.0 else -1.0
        return cp * cw, sp * cw, cp * cw, sp * cw, c, r
    sw = math.sqrt(1.0 - c * c)
    return cp * c - sp * sw, sp * c + cp * sw, cp * c + sp * sw, sp * c - cp * sw, c, r


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp4(h, p, k, d):
    """The two ``theta`` with ``h . R(k, theta) p = d`` (``h`` need not be unit), their cosine ``c`` and the
    amplitude ``r``.

    ``R p = k (k.p) + cos(theta) p_perp + sin(theta) (k x p)``, so ``A cos + B sin = d - (h.k)(k.p)`` with
    ``A = h.p_perp``, ``B = h.(k x p)``: ``theta = atan2(B, A) +- acos(c)``, ``c = (d - (h.k)(k.p)) / r``,
    ``r = hypot(A, B)``. A small ``r`` (relative to how fast it changes with the data) means an ill-conditioned
    subproblem: the angles swing fast as the data move.
    """
    ca, sa, cb, sb, c, r = sp4_cs(h, p, k, d)
    if r == 0.0:
        return 0.0, 0.0, c, r
    return math.atan2(sa, ca), math.atan2(sb, cb), c, r


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp3_cs(p1, p2, k, d):
    """``sp3`` without angles (as ``sp4_cs``)."""
    return sp4_cs(p2, p1, k, 0.5 * (dot(p1, p1) + dot(p2, p2) - d * d))


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp3(p1, p2, k, d):
    """The two ``theta`` with ``|R(k, theta) p1 - p2| = d``, their cosine ``c`` and amplitude ``r`` (as ``sp4``)."""
    return sp4(p2, p1, k, 0.5 * (dot(p1, p1) + dot(p2, p2) - d * d))


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp2_cs(p1, p2, k1, k2):
    """``sp2`` without angles: ``c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r`` (cosines and sines of the pairs)."""
    c1a, s1a, c1b, s1b, c, r = sp4_cs(k2, p1, k1, dot(k2, p2))
    c2a, s2a = sp1_cs(p2, rot_cs(k1, c1a, s1a, p1), k2)
    c2b, s2b = sp1_cs(p2, rot_cs(k1, c1b, s1b, p1), k2)
    return c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def sp2(p1, p2, k1, k2):
    """``(theta1, theta2)`` pairs with ``R(k1, theta1) p1 = R(k2, theta2) p2`` (``k1``, ``k2`` not parallel).

    Returns ``theta1_a, theta2_a, theta1_b, theta2_b, c, r``: theta1 from ``k2 . R(k1, theta1) p1 = k2 . p2`` (an
    ``sp4``, cosine ``c``, amplitude ``r``), theta2 from ``sp1`` for each. Exact when ``|c| <= 1`` and
    ``|p1| = |p2|``.
    """
    c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r = sp2_cs(p1, p2, k1, k2)
    return math.atan2(s1a, c1a), math.atan2(s2a, c2a), math.atan2(s1b, c1b), math.atan2(s2b, c2b), c, r


@inlined
def _trig_terms(h, k, p):
    """``(a_c, a_s, a_0)`` with ``h . R(k, t) p = a_c cos t + a_s sin t + a_0``."""
    return dot(h, perp(k, p)), dot(h, cross(k, p)), dot(h, k) * dot(k, p)


#: SP6 is degenerate (its two equations do not fix the angles: a continuum or no solution, not solved) when both
#: 2x2 blocks of its linear system in the cosines and sines are singular to this, relative to their entries.
SP6_SINGULAR = 1e-12


@njit(cache=True, error_model=ERROR_MODEL, forceinline=False)
def sp6(h1, k1, p1, h2, k2, p2, h3, k3, p3, h4, k4, p4, d1, d2):
    """Pairs ``(theta1, theta2)`` with (IK-Geo's SP6, "four circles")::

        h1 . R(k1, theta1) p1 + h2 . R(k2, theta2) p2 = d1
        h3 . R(k3, theta1) p3 + h4 . R(k4, theta2) p4 = d2

    Returns ``(theta1 (4,), theta2 (4,), n)``, NaN-padded, ``n`` the number of solutions (at most 4); ``n = -1``
    when the equations do not fix the angles (degenerate: a continuum or none; not solved).

    Both equations are linear in ``x1 = (cos theta1, sin theta1)`` and ``x2 = (cos theta2, sin theta2)``:
    ``A x1 + B x2 = e``. Eliminating the angle whose block is better conditioned (``x2 = M x1 + v``) leaves
    ``|M x1 + v|^2 = 1``, a trigonometric polynomial of degree 2 in theta1 (:func:`.trig.trig2_roots`).
    """
    a1c, a1s, a10 = _trig_terms(h1, k1, p1)
    b1c, b1s, b10 = _trig_terms(h2, k2, p2)
    a2c, a2s, a20 = _trig_terms(h3, k3, p3)
    b2c, b2s, b20 = _trig_terms(h4, k4, p4)
    e1, e2 = d1 - a10 - b10, d2 - a20 - b20
    t1 = np.empty(4)
    t2 = np.empty(4)
    for i in range(4):
        t1[i] = t2[i] = np.nan
    det_a = a1c * a2s - a1s * a2c
    det_b = b1c * b2s - b1s * b2c
    size = max(abs(a1c), abs(a1s), abs(a2c), abs(a2s), abs(b1c), abs(b1s), abs(b2c), abs(b2s))
    if max(abs(det_a), abs(det_b)) <= SP6_SINGULAR * size * size:
        return t1, t2, -1
    swap = abs(det_a) > abs(det_b)
    if swap:  # eliminate theta1 instead: the roles of the two angles exchange
        a1c, a1s, a2c, a2s, b1c, b1s, b2c, b2s = b1c, b1s, b2c, b2s, a1c, a1s, a2c, a2s
        det_b = det_a
    # x2 = B^-1 (e - A x1) = M x1 + v
    i11, i12, i21, i22 = b2s / det_b, -b1s / det_b, -b2c / det_b, b1c / det_b
    m11, m12 = -(i11 * a1c + i12 * a2c), -(i11 * a1s + i12 * a2s)
    m21, m22 = -(i21 * a1c + i22 * a2c), -(i21 * a1s + i22 * a2s)
    v1, v2 = i11 * e1 + i12 * e2, i21 * e1 + i22 * e2
    q11, q12, q22 = m11 * m11 + m21 * m21, m11 * m12 + m21 * m22, m12 * m12 + m22 * m22
    w1, w2 = m11 * v1 + m21 * v2, m12 * v1 + m22 * v2
    roots, n = trig2_roots(0.5 * (q11 + q22) + v1 * v1 + v2 * v2 - 1.0, 2.0 * w1, 2.0 * w2, 0.5 * (q11 - q22), q12)
    if n < 0:
        return t1, t2, -1
    for i in range(n):
        c, s = math.cos(roots[i]), math.sin(roots[i])
        other = math.atan2(m21 * c + m22 * s + v2, m11 * c + m12 * s + v1)
        if swap:
            t1[i], t2[i] = other, roots[i]
        else:
            t1[i], t2[i] = roots[i], other
    return t1, t2, n


@njit(cache=True, error_model=ERROR_MODEL, forceinline=False)
def sp5(p0, p1, p2, p3, k1, k2, k3):
    """Triples ``(theta1, theta2, theta3)`` with (IK-Geo's SP5, "three circles")::

        p0 + R(k1, theta1) p1 = R(k2, theta2) (p2 + R(k3, theta3) p3)

    Returns ``(theta1 (4,), theta2 (4,), theta3 (4,), n)``, NaN-padded; ``n = -1`` when degenerate (as ``sp6``).

    A rotation about ``k2`` (through the origin) maps one point onto another exactly when both have the same
    height along ``k2`` and the same distance from the origin: two equations in theta1 and theta3 of SP6's form;
    theta2 then follows from ``sp1``.
    """
    nk2 = (-k2[0], -k2[1], -k2[2])
    np2 = (-p2[0], -p2[1], -p2[2])
    d1 = dot(k2, p2) - dot(k2, p0)
    d2 = 0.5 * (dot(p2, p2) + dot(p3, p3) - dot(p0, p0) - dot(p1, p1))
    t1, t3, n = sp6(k2, k1, p1, nk2, k3, p3, p0, k1, p1, np2, k3, p3, d1, d2)
    t2 = np.empty(4)
    for i in range(4):
        t2[i] = np.nan
    for i in range(max(n, 0)):
        a = rot(k3, t3[i], p3)
        a = (a[0] + p2[0], a[1] + p2[1], a[2] + p2[2])
        b = rot(k1, t1[i], p1)
        b = (b[0] + p0[0], b[1] + p0[1], b[2] + p0[2])
        t2[i], _ = sp1(a, b, k2)
    return t1, t2, t3, n
