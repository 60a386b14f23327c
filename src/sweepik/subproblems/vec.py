"""Small 3-vector algebra on tuples ``(x, y, z)`` for compiled scalar code (no array allocation).

Compiled code calls these only: they are compiled without the wrappers that would let Python call them, and
inlined into their callers (:func:`sweepik._jit.inlined`). The subproblems built on them are callable from Python.
"""

from __future__ import annotations

import math

from sweepik._jit import inlined

__all__ = ["add", "sub", "scale", "dot", "cross", "norm", "unit", "rot", "rot_cs", "perp", "along", "orthogonal"]


@inlined
def add(a, b):
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


@inlined
def sub(a, b):
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


@inlined
def scale(s, a):
    return (s * a[0], s * a[1], s * a[2])


@inlined
def dot(a, b):
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@inlined
def cross(a, b):
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@inlined
def norm(a):
    return math.sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2])


@inlined
def unit(a):
    n = norm(a)
    return (a[0] / n, a[1] / n, a[2] / n)


@inlined
def rot(k, theta, v):
    """``v`` rotated by ``theta`` (radians) about the unit axis ``k`` (Rodrigues)."""
    return rot_cs(k, math.cos(theta), math.sin(theta), v)


@inlined
def rot_cs(k, c, s, v):
    """``v`` rotated about the unit axis ``k`` by the angle whose cosine and sine are ``c``, ``s``."""
    kv = dot(k, v)
    kxv = cross(k, v)
    return (
        c * v[0] + s * kxv[0] + (1.0 - c) * kv * k[0],
        c * v[1] + s * kxv[1] + (1.0 - c) * kv * k[1],
        c * v[2] + s * kxv[2] + (1.0 - c) * kv * k[2],
    )


@inlined
def along(k, v):
    """The component of ``v`` along the unit vector ``k``."""
    return scale(dot(k, v), k)


@inlined
def perp(k, v):
    """The component of ``v`` perpendicular to the unit vector ``k``."""
    return sub(v, along(k, v))


@inlined
def orthogonal(k):
    """A unit vector perpendicular to the unit vector ``k``."""
    ax, ay, az = abs(k[0]), abs(k[1]), abs(k[2])
    e = (1.0, 0.0, 0.0) if ax <= ay and ax <= az else ((0.0, 1.0, 0.0) if ay <= az else (0.0, 0.0, 1.0))
    return unit(cross(k, e))
