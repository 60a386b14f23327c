"""The engine's tolerances and constants that more than one of its modules read (the rest live beside the one
function that uses them). Relative tolerances multiply the arm's length scale (``Robot.length_scale``)."""

from __future__ import annotations

__all__ = ["ACCEPT_TOL_REL", "PINV_RCOND", "PINV_WIDEN"]

#: Precise strategy: a candidate is a solution when position error + weight x angle is below this times the
#: arm's length scale (C-Arm: 2e-13 x 2752 mm = 5.5e-10 mm). Simple roots refine to ~1e-13 mm, double
#: roots to ~1e-14 mm; a near miss of the residual above this is not a solution.
ACCEPT_TOL_REL = 2e-13
#: Singular values below this fraction of the largest are dropped from the Newton step (pseudo-inverse):
#: keeps the step bounded at singular configurations, without effect at regular ones.
PINV_RCOND = 1e-10
#: A step that no halving makes lower the error is tried again with the singular values below ``PINV_RCOND`` times
#: these dropped: where the arm loses two ranks (a KR 6 with its wrist centre on axis 1 and its elbow straight, a
#: member of its joint-1 continuum corrected with joint 1 held) the step along the nearly null directions is all
#: overshoot, and without them the error went from 2e-4 of the arm's size to 5e-12 (1e-6) and rounding.
PINV_WIDEN = (1.0, 1e4, 1e7)
