"""Prismatic subproblems: a point moved along a line (a prismatic joint) instead of around a circle.

Pure functions of vectors (3-tuples), compiled with ``numba.njit``; directions ``h`` are unit vectors, ``t`` the
joint's travel (length unit).

* ``lp1(p1, p2, h)``: ``p1 + t h = p2`` (line-point), least squares ``t = h . (p2 - p1)``, and the miss distance.
* ``lp3(p1, p2, h, d)``: ``|p1 + t h - p2| = d`` (line-sphere): ``t = -h.v +- sqrt(d^2 - |v_perp|^2)``,
  ``v = p1 - p2``; also returns ``disc = (d^2 - |v_perp|^2)`` (negative: the line misses the sphere; the
  closest ``t`` is returned twice).
* ``lp4(h, p, k, d)``: ``h . (p + t k) = d`` (line-plane), NaN when the line is parallel to the plane.
* ``lines2(h1, h2, v)``: ``t1 h1 + t2 h2 = v`` (least squares) for two non-parallel lines.
* ``lines3(h1, h2, h3, v)``: ``t1 h1 + t2 h2 + t3 h3 = v`` for three independent directions (NaN otherwise).
"""

from __future__ import annotations

import math

from numba import njit

from sweepik._jit import ERROR_MODEL
from sweepik.subproblems.vec import add, cross, dot, norm, perp, scale, sub

__all__ = ["lp1", "lp3", "lp4", "lines2", "lines3", "PARALLEL_DET"]

#: Unit directions whose Gram (``lines2``) or triple-product (``lines3``) determinant is below this are treated as
#: dependent (the sine of the angle between two lines below 1e-6): NaN, never a huge travel from rounding.
PARALLEL_DET = 1e-12


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def lp1(p1, p2, h):
    t = dot(h, sub(p2, p1))
    return t, norm(sub(add(p1, scale(t, h)), p2))


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def lp3(p1, p2, h, d):
    v = sub(p1, p2)
    w = perp(h, v)
    disc = d * d - dot(w, w)
    s = math.sqrt(max(disc, 0.0))
    m = -dot(h, v)
    return m + s, m - s, disc


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def lp4(h, p, k, d):
    hk = dot(h, k)
    if hk == 0.0:
        return math.nan
    return (d - dot(h, p)) / hk


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def lines2(h1, h2, v):
    a = dot(h1, h2)
    det = 1.0 - a * a
    if det <= PARALLEL_DET:
        return math.nan, math.nan
    b1, b2 = dot(h1, v), dot(h2, v)
    return (b1 - a * b2) / det, (b2 - a * b1) / det


@njit(cache=True, error_model=ERROR_MODEL, forceinline=True)
def lines3(h1, h2, h3, v):
    det = dot(h1, cross(h2, h3))
    if abs(det) <= PARALLEL_DET:
        return math.nan, math.nan, math.nan
    return dot(v, cross(h2, h3)) / det, dot(h1, cross(v, h3)) / det, dot(h1, cross(h2, v)) / det
