"""Canonical geometric subproblems (revolute: circles; prismatic: lines), compiled scalar functions of vectors.

They know no robot: a kinematic family (:mod:`sweepik.reductions.families`) composes them over a chain's axes and
points. See docs/subproblems.md for each equation, its solution set and its degenerate cases.
"""

from sweepik.subproblems.prismatic import lines2, lines3, lp1, lp3, lp4
from sweepik.subproblems.revolute import (
    DOMAIN_TOL,
    in_domain,
    sp1,
    sp1_cs,
    sp2,
    sp2_cs,
    sp3,
    sp3_cs,
    sp4,
    sp4_cs,
    sp5,
    sp6,
)
from sweepik.subproblems.trig import trig2_roots

__all__ = [
    "sp1",
    "sp2",
    "sp3",
    "sp4",
    "sp5",
    "sp6",
    "trig2_roots",
    "sp1_cs",
    "sp2_cs",
    "sp3_cs",
    "sp4_cs",
    "in_domain",
    "DOMAIN_TOL",
    "lp1",
    "lp3",
    "lp4",
    "lines2",
    "lines3",
]
