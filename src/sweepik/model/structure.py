"""The kinematic structure of a chain: which joint axes intersect, which are parallel, where prismatic joints slide.

Only relations that hold in **every** configuration are reported, because only those let a decomposition
replace joints by geometric subproblems:

* consecutive joints i, i + 1: their relation is fixed by the link between them (intersecting at a point,
  parallel, or skew);
* a run of consecutive revolute axes through one common point (a spherical wrist or shoulder): the point stays
  common whatever the joints of the run do;
* parallel axes i < j with only parallel revolute or prismatic joints between them: a prismatic joint only
  translates what follows, a revolute joint parallel to both keeps them parallel.

"Intersecting" and "parallel" are decided with tolerances relative to the arm's size (``INTERSECT_TOL_REL``
times the robot's length scale, ``PARALLEL_TOL`` in radians): a near-intersection is a different arm, and a
decomposition built on a false intersection would return wrong answers (FK certification is the guard).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.model.chain import Chain

Array = NDArray[np.float64]

__all__ = [
    "Structure",
    "structure_of",
    "near_structure",
    "line_relation",
    "PARALLEL_TOL",
    "INTERSECT_TOL_REL",
    "NEAR_TOL",
]

#: Two axes are parallel when the sine of the angle between them is below this (radians). Published arm
#: parameters are exact (90 degrees, 0 mm); rounding a right angle to 7 digits (1.570796) is 3e-7 off.
PARALLEL_TOL = 1e-9
#: Two axis lines intersect when their distance is below this times the robot's length scale.
INTERSECT_TOL_REL = 1e-9
#: A relation that holds to within this (the sine of an angle, or a distance over the length scale) but not to the
#: tolerances above is a **near-structure**: vendors' descriptions rounded (axes parallel to 1e-6 rad, axes that miss
#: by a micrometre, a wrist centre 25 um off an axis). Such an arm is general (treating a 1e-6 rad angle as parallel
#: moves the pose by ~1e-6 of the arm's size, a thousand times what the certification accepts), but a decomposition
#: that sweeps across the near-structure can be ill-conditioned: the automatic choice then checks every plan
#: (:mod:`sweepik.plan_check`). The real offsets of arms (a 10 mm wrist offset on a 1 m arm) are above it.
NEAR_TOL = 1e-3


def cross3(a: Array, b: Array) -> Array:
    """``np.cross`` of two 3-vectors, the same products and differences (the same bits), without its generic
    machinery (~8 us a call: the enumeration of a held arm's plans makes thousands)."""
    a0, a1, a2 = float(a[0]), float(a[1]), float(a[2])
    b0, b1, b2 = float(b[0]), float(b[1]), float(b[2])
    return np.array((a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0))


def line_relation(h1: Array, o1: Array, h2: Array, o2: Array, dist_tol: float) -> tuple[str, Array | None]:
    """('parallel' | 'coincident' | 'intersecting' | 'skew', meeting point or None) of two lines."""
    n = cross3(h1, h2)
    s = float(np.linalg.norm(n))
    d = o2 - o1
    if s < PARALLEL_TOL:
        off = float(np.linalg.norm(d - np.dot(d, h1) * h1))
        return ("coincident" if off < dist_tol else "parallel"), None
    if abs(float(np.dot(d, n))) / s >= dist_tol:
        return "skew", None
    # closest points o1 + t1 h1 and o2 + t2 h2 (they meet within tolerance): midpoint. 1 - b^2 of unit axes is s^2,
    # which keeps its digits where the axes are all but parallel (1 - b^2 rounds to 0 for s below 1e-8)
    b = float(np.dot(h1, h2))
    t1 = (np.dot(d, h1) - b * np.dot(d, h2)) / (s * s)
    t2 = (b * np.dot(d, h1) - np.dot(d, h2)) / (s * s)
    return "intersecting", 0.5 * ((o1 + t1 * h1) + (o2 + t2 * h2))


@dataclass(frozen=True)
class Structure:
    """Invariant relations between a chain's joint axes (joints indexed from 0).

    Attributes:
        revolute: joint types.
        pairs: relation of consecutive joints ``(i, i + 1)``: 'intersecting', 'parallel', 'skew' or
            'coincident' (revolute axes only; a pair involving a prismatic joint is 'parallel' or 'skew' by
            direction).
        points: meeting point (world, q = 0) of each intersecting consecutive revolute pair.
        parallel: all pairs ``(i, j)``, i < j, whose axes stay parallel in every configuration.
        spherical: maximal runs ``(i, ..., j)`` of >= 2 consecutive revolute axes through one common point.
        tol_length: the distance tolerance used (length unit).
    """

    revolute: tuple[bool, ...]
    pairs: tuple[str, ...]
    points: dict[tuple[int, int], tuple[float, float, float]]
    parallel: frozenset[tuple[int, int]]
    spherical: tuple[tuple[int, ...], ...]
    tol_length: float

    @property
    def n_joints(self) -> int:
        return len(self.revolute)

    @property
    def types(self) -> str:
        """Joint types as a string, e.g. ``"PRRRRR"``."""
        return "".join("R" if r else "P" for r in self.revolute)

    def intersecting(self, i: int, j: int) -> bool:
        """Axes i and j (consecutive, or in one spherical run) meet in every configuration."""
        i, j = min(i, j), max(i, j)
        if j == i + 1:
            return self.pairs[i] == "intersecting"
        return any(i in run and j in run for run in self.spherical)

    def is_parallel(self, i: int, j: int) -> bool:
        """Axes i and j stay parallel in every configuration."""
        return (min(i, j), max(i, j)) in self.parallel

    def common_point(self, joints: tuple[int, ...]) -> bool:
        """All these consecutive revolute joints' axes pass through one point."""
        return len(joints) >= 2 and any(set(joints) <= set(run) for run in self.spherical)

    def describe(self) -> str:
        """One line, e.g. ``"PRRRRR: 2∩3, 3∥4, 4∩5, 5∩6"`` (joints numbered from 1)."""
        parts: list[tuple[int, str]] = []
        for run in self.spherical:
            parts.append((run[0], "∩".join(str(k + 1) for k in run) + (" (one point)" if len(run) > 2 else "")))
        parts.extend((i, f"{i + 1}∥{j + 1}") for i, j in sorted(self.parallel))
        parts.sort()
        return f"{self.types}: " + (", ".join(t for _, t in parts) if parts else "no intersecting or parallel axes")

    def as_dict(self) -> dict[str, Any]:
        """Plain values for JSON (joints numbered from 1)."""
        return {
            "types": self.types,
            "pairs": [{"joints": [i + 1, i + 2], "relation": r} for i, r in enumerate(self.pairs)],
            "intersections": [
                {"joints": [i + 1, j + 1], "point": list(p)} for (i, j), p in sorted(self.points.items())
            ],
            "parallel": [[i + 1, j + 1] for i, j in sorted(self.parallel)],
            "spherical": [[k + 1 for k in run] for run in self.spherical],
            "tol_length": self.tol_length,
        }


def structure_of(chain: Chain, length_scale: float, tol_rel: float = INTERSECT_TOL_REL) -> Structure:
    """The invariant structure of ``chain``; distances below ``tol_rel * length_scale`` count as zero."""
    n = chain.n_joints
    H, pts, rev = chain.H, chain.points, chain.revolute
    tol = tol_rel * max(length_scale, 1e-300)
    pairs: list[str] = []
    points: dict[tuple[int, int], tuple[float, float, float]] = {}
    for i in range(n - 1):
        if rev[i] and rev[i + 1]:
            rel, pt = line_relation(H[i], pts[i], H[i + 1], pts[i + 1], tol)
        else:
            rel, pt = ("parallel" if np.linalg.norm(cross3(H[i], H[i + 1])) < PARALLEL_TOL else "skew"), None
        pairs.append(rel)
        if pt is not None:
            points[(i, i + 1)] = (float(pt[0]), float(pt[1]), float(pt[2]))
    parallel = set()
    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(cross3(H[i], H[j])) >= PARALLEL_TOL:
                continue
            between = range(i + 1, j)
            if all((not rev[k]) or np.linalg.norm(cross3(H[i], H[k])) < PARALLEL_TOL for k in between):
                parallel.add((i, j))
    spherical: list[tuple[int, ...]] = []
    i = 0
    while i < n - 1:
        if (i, i + 1) not in points:
            i += 1
            continue
        run = [i, i + 1]
        anchor = np.array(points[(i, i + 1)])
        k = i + 1
        while (k, k + 1) in points and np.linalg.norm(np.array(points[(k, k + 1)]) - anchor) < tol:
            run.append(k + 1)
            k += 1
        spherical.append(tuple(run))
        i = k if len(run) > 2 else i + 1
    return Structure(tuple(bool(r) for r in rev), tuple(pairs), points, frozenset(parallel), tuple(spherical), tol)


def near_structure(chain: Chain, length_scale: float, tol: float = NEAR_TOL) -> tuple[str, ...]:
    """The relations that nearly hold (within ``tol``, default ``NEAR_TOL``) but not exactly, as text (joints numbered
    from 1):
    ``"2≈∥3 (7.3e-06 rad)"`` axes nearly parallel (consecutive, or with only slides and nearly parallel axes
    between), ``"1≈∩2 (1.3e-06)"`` consecutive revolute axes that nearly meet (their distance over the length
    scale), ``"4≈∩5∩6 (2.5e-05)"`` three consecutive revolute axes that nearly share one point, ``"3≈≡4 (7.7e-07)"``
    two consecutive revolute axes nearly on one line (their distance over the length scale)."""
    n = chain.n_joints
    H, pts, rev = chain.H, chain.points, chain.revolute
    scale = max(length_scale, 1e-300)
    out: list[str] = []

    def sin(i: int, j: int) -> float:
        return float(np.linalg.norm(cross3(H[i], H[j])))

    for i in range(n):
        for j in range(i + 1, n):
            s_ij = sin(i, j)
            if not PARALLEL_TOL <= s_ij < tol:
                continue
            if all((not rev[k]) or sin(i, k) < tol for k in range(i + 1, j)):
                out.append(f"{i + 1}≈∥{j + 1} ({s_ij:.1e} rad)")
    for i in range(n - 1):  # consecutive revolute axes on nearly one line
        if rev[i] and rev[i + 1] and sin(i, i + 1) < tol:
            d = pts[i + 1] - pts[i]
            off = float(np.linalg.norm(d - np.dot(d, H[i]) * H[i]))
            if INTERSECT_TOL_REL * scale <= off < tol * scale:
                out.append(f"{i + 1}≈≡{i + 2} ({off / scale:.1e})")
    meets: dict[int, Array] = {}
    for i in range(n - 1):
        if not (rev[i] and rev[i + 1]) or sin(i, i + 1) < tol:
            continue
        rel, pt = line_relation(H[i], pts[i], H[i + 1], pts[i + 1], tol * scale)
        if rel != "intersecting":
            continue
        meets[i] = pt  # type: ignore[assignment]
        d = abs(float(np.dot(pts[i + 1] - pts[i], cross3(H[i], H[i + 1])))) / sin(i, i + 1)
        if d >= INTERSECT_TOL_REL * scale:
            out.append(f"{i + 1}≈∩{i + 2} ({d / scale:.1e})")
    for i in range(n - 2):
        if i in meets and i + 1 in meets:
            d = float(np.linalg.norm(meets[i] - meets[i + 1]))
            if INTERSECT_TOL_REL * scale <= d < tol * scale:
                out.append(f"{i + 1}≈∩{i + 2}∩{i + 3} ({d / scale:.1e})")
    return tuple(out)
