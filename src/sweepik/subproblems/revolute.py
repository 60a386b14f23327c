"""Revolute subproblems: canonical geometric equations in joint angles, solved in closed form (Paden-Kahan;
numbered as in IK-Geo, Elias & Wen 2022).

Every function is a pure function of vectors (3-tuples of floats), compiled with ``numba.njit`` and callable
from Python. Axes ``k`` are unit vectors; angles are radians; ``R(k, theta)`` is the rotation about ``k``.

* ``sp1(p1, p2, k)``: ``R(k, theta) p1 = p2`` (circle-point). One angle; least squares when ``p1``, ``p2`` differ
  in height along ``k`` or in distance from it. Degenerate when ``p1`` lies on the axis (any angle: 0 returned).
* ``sp4(h, p, k, d)``: ``h . R(k, theta) p = d`` (circle-plane). Two angles ``phi +- acos(c)``.
* ``sp3(p1, p2, k, d)``: ``|R(k, theta) p1 - p2| = d`` (circle-sphere), an ``sp4`` in disguise.
* ``sp2(p1, p2, k1, k2)``: ``R(k1, theta1) p1 = R(k2, theta2) p2`` (two circles). Two pairs.

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

from numba import njit

from .vec import cross, dot, norm, perp, rot_cs, sub

__all__ = ["sp1", "sp2", "sp3", "sp4", "sp1_cs", "sp2_cs", "sp3_cs", "sp4_cs", "in_domain", "DOMAIN_TOL"]

#: ``|c|`` up to ``1 + DOMAIN_TOL`` counts as 1 (``in_domain``): rounding of the vectors a subproblem is built
#: from moves ``c`` by a few ulps, and a solution exactly at a branch-domain edge must not turn into "none".
DOMAIN_TOL = 1e-12


@njit(cache=True)
def in_domain(c):
    """True when the cosine ``c`` of a two-solution subproblem gives exact (possibly equal) solutions."""
    return abs(c) <= 1.0 + DOMAIN_TOL


@njit(cache=True)
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


@njit(cache=True)
def sp1(p1, p2, k):
    """``theta`` with ``R(k, theta) p1 = p2`` (least squares in general) and the residual ``|R p1 - p2|``."""
    c, s = sp1_cs(p1, p2, k)
    return math.atan2(s, c), norm(sub(rot_cs(k, c, s, p1), p2))


@njit(cache=True)
def sp4_cs(h, p, k, d):
    """``sp4`` without angles: ``(cos, sin)`` of both solutions, then ``c`` and ``r``:
    ``cos_a, sin_a, cos_b, sin_b, c, r``. The angles are ``phi +- w`` with ``(cos, sin)(phi) = (A, B) / r`` and
    ``cos w = c``, ``sin w = sqrt(1 - c^2)`` (``w`` = 0 or pi outside ``|c| <= 1``: the least-squares angle)."""
    A = dot(h, perp(k, p))
    B = dot(h, cross(k, p))
    r = math.sqrt(A * A + B * B)
    rhs = d - dot(h, k) * dot(k, p)
    if r == 0.0:
        return 1.0, 0.0, 1.0, 0.0, math.nan, 0.0
    c = rhs / r
    cp, sp = A / r, B / r
    if abs(c) >= 1.0:  # tangent or least squares: one angle
        cw = 1.0 if c > 0.0 else -1.0
        return cp * cw, sp * cw, cp * cw, sp * cw, c, r
    sw = math.sqrt(1.0 - c * c)
    return cp * c - sp * sw, sp * c + cp * sw, cp * c + sp * sw, sp * c - cp * sw, c, r


@njit(cache=True)
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


@njit(cache=True)
def sp3_cs(p1, p2, k, d):
    """``sp3`` without angles (as ``sp4_cs``)."""
    return sp4_cs(p2, p1, k, 0.5 * (dot(p1, p1) + dot(p2, p2) - d * d))


@njit(cache=True)
def sp3(p1, p2, k, d):
    """The two ``theta`` with ``|R(k, theta) p1 - p2| = d``, their cosine ``c`` and amplitude ``r`` (as ``sp4``)."""
    return sp4(p2, p1, k, 0.5 * (dot(p1, p1) + dot(p2, p2) - d * d))


@njit(cache=True)
def sp2_cs(p1, p2, k1, k2):
    """``sp2`` without angles: ``c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r`` (cosines and sines of the pairs)."""
    c1a, s1a, c1b, s1b, c, r = sp4_cs(k2, p1, k1, dot(k2, p2))
    c2a, s2a = sp1_cs(p2, rot_cs(k1, c1a, s1a, p1), k2)
    c2b, s2b = sp1_cs(p2, rot_cs(k1, c1b, s1b, p1), k2)
    return c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r


@njit(cache=True)
def sp2(p1, p2, k1, k2):
    """``(theta1, theta2)`` pairs with ``R(k1, theta1) p1 = R(k2, theta2) p2`` (``k1``, ``k2`` not parallel).

    Returns ``theta1_a, theta2_a, theta1_b, theta2_b, c, r``: theta1 from ``k2 . R(k1, theta1) p1 = k2 . p2`` (an
    ``sp4``, cosine ``c``, amplitude ``r``), theta2 from ``sp1`` for each. Exact when ``|c| <= 1`` and
    ``|p1| = |p2|``.
    """
    c1a, s1a, c2a, s2a, c1b, s1b, c2b, s2b, c, r = sp2_cs(p1, p2, k1, k2)
    return math.atan2(s1a, c1a), math.atan2(s2a, c2a), math.atan2(s1b, c1b), math.atan2(s2b, c2b), c, r
