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
"""

from __future__ import annotations

import math

from numba import njit

from .vec import cross, dot, norm, perp, rot, sub

__all__ = ["sp1", "sp2", "sp3", "sp4", "in_domain", "DOMAIN_TOL"]

#: ``|c|`` up to ``1 + DOMAIN_TOL`` counts as 1 (``in_domain``): rounding of the vectors a subproblem is built
#: from moves ``c`` by a few ulps, and a solution exactly at a branch-domain edge must not turn into "none".
DOMAIN_TOL = 1e-12


@njit(cache=True)
def in_domain(c):
    """True when the cosine ``c`` of a two-solution subproblem gives exact (possibly equal) solutions."""
    return abs(c) <= 1.0 + DOMAIN_TOL


@njit(cache=True)
def sp1(p1, p2, k):
    """``theta`` with ``R(k, theta) p1 = p2`` (least squares in general) and the residual ``|R p1 - p2|``."""
    a = perp(k, p1)
    b = perp(k, p2)
    theta = math.atan2(dot(k, cross(a, b)), dot(a, b))
    return theta, norm(sub(rot(k, theta, p1), p2))


@njit(cache=True)
def sp4(h, p, k, d):
    """The two ``theta`` with ``h . R(k, theta) p = d`` (``h`` need not be unit), their cosine ``c`` and the
    amplitude ``r``.

    ``R p = k (k.p) + cos(theta) p_perp + sin(theta) (k x p)``, so ``A cos + B sin = d - (h.k)(k.p)`` with
    ``A = h.p_perp``, ``B = h.(k x p)``: ``theta = atan2(B, A) +- acos(c)``, ``c = (d - (h.k)(k.p)) / r``,
    ``r = hypot(A, B)``. A small ``r`` (relative to how fast it changes with the data) means an ill-conditioned
    subproblem: the angles swing fast as the data move.
    """
    A = dot(h, perp(k, p))
    B = dot(h, cross(k, p))
    r = math.hypot(A, B)
    rhs = d - dot(h, k) * dot(k, p)
    if r == 0.0:
        return 0.0, 0.0, math.nan, 0.0
    c = rhs / r
    phi = math.atan2(B, A)
    if abs(c) >= 1.0:  # tangent or least squares: one angle (phi + pi is phi - pi)
        w = 0.0 if c > 0.0 else math.pi
        return phi + w, phi + w, c, r
    w = math.acos(c)
    return phi + w, phi - w, c, r


@njit(cache=True)
def sp3(p1, p2, k, d):
    """The two ``theta`` with ``|R(k, theta) p1 - p2| = d``, their cosine ``c`` and amplitude ``r`` (as ``sp4``)."""
    return sp4(p2, p1, k, 0.5 * (dot(p1, p1) + dot(p2, p2) - d * d))


@njit(cache=True)
def sp2(p1, p2, k1, k2):
    """``(theta1, theta2)`` pairs with ``R(k1, theta1) p1 = R(k2, theta2) p2`` (``k1``, ``k2`` not parallel).

    Returns ``theta1_a, theta2_a, theta1_b, theta2_b, c, r``: theta1 from ``k2 . R(k1, theta1) p1 = k2 . p2`` (an
    ``sp4``, cosine ``c``, amplitude ``r``), theta2 from ``sp1`` for each. Exact when ``|c| <= 1`` and
    ``|p1| = |p2|``.
    """
    t1a, t1b, c, r = sp4(k2, p1, k1, dot(k2, p2))
    t2a, _ = sp1(p2, rot(k1, t1a, p1), k2)
    t2b, _ = sp1(p2, rot(k1, t1b, p1), k2)
    return t1a, t2a, t1b, t2b, c, r
