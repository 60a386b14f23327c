"""Angle wrapping for compiled code (a module of its own: the kernels, the engine and certification all use it, and
it imports nothing of sweepik but the compile options)."""

from __future__ import annotations

import math

from ._jit import inlined

__all__ = ["wrap_pi"]


@inlined
def wrap_pi(x: float) -> float:
    """``pi - ((pi - x) % 2 pi)``, the angle ``x`` wrapped into ``(-pi, pi]``, bit for bit as that expression gives it
    (Python's and NumPy's float modulo, as ``Robot.wrap``), without the modulo's library call when ``|pi - x| < 2 pi``:
    there ``fmod`` returns ``pi - x`` exactly and the modulo adds ``2 pi`` to a negative one (and gives +0 for 0, which
    ``pi -`` does not tell from -0). NaN (a branch that does not exist) is returned as it is: the modulo's call is
    slowest on it (~150 ns)."""
    y = math.pi - x
    two_pi = 2.0 * math.pi
    if 0.0 <= y < two_pi:
        return math.pi - y
    if -two_pi < y < 0.0:
        return math.pi - (y + two_pi)
    if y != y:
        return x
    return math.pi - (y % two_pi)
