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

#: Candidates with a pose error below this times the length scale get a Newton polish on the full pose
#: (removes the ill-conditioning of a reduction; spurious candidates are far above it).
POLISH_BELOW_REL = 1e-6

#: ... and above this (already at rounding level: nothing to gain), ...
POLISH_ABOVE_REL = 1e-14

#: ... or with the paper's J above this: near a Z-Y-Z gimbal J magnifies a tiny rotation error by 1/sin(beta),
#: so there the pose is polished down to rounding level.
POLISH_PAPER_ABOVE_REL = 5e-14

#: Paper strategy: the paper's acceptance threshold J < 1e-5 mm (section 4).
PAPER_ACCEPT_MM = 1e-5

#: Candidates within this (relative to the arm's length scale) of their pose seed the continua that a reduction
#: cannot see (``Reduction.continuum_joints``): certified ones and those a polish would certify.
SEED_TOL_REL = 1e-6

#: A root of multiplicity >= 2 is pinned down along theta* only to its flat stretch (~1e-5 of the range for a
#: triple root): one this close outside theta*'s limits gets a copy clipped to the limit, certified like any
#: candidate, so that a solution exactly at a limit (a rail end) is not lost to its rounding.
CLIP_REACH_REL = 1e-4

#: A certified solution at most this far outside a joint limit (radians; prismatic joints: times the arm's length
#: scale) is tried at the limit: near a singular configuration the pose pins a solution down only to ~1e-8, so
#: one exactly at a limit comes out a little beyond it.
SNAP_REACH = 1e-4

#: Newton steps (other joints free, the clamped ones held) for a solution moved onto its limit.
SNAP_ITERATIONS = 4

#: Two certified solutions of a closed form this close (every joint, radians; relative to the length scale for a
#: slide) may be one double root that the closed form's rounding split in two: where two branches meet, a step's
#: cosine sits at +-1 up to rounding magnified by the arm's geometry (1e-12 gives two roots 1.6e-6 rad apart, each
#: certified, as the pose error grows only quadratically along them). Their midpoint is the root.
MEET_REL = 1e-3

#: ... but not when the polish of their midpoint moves it by more than this fraction of their distance: it went over
#: to one of them, and they are two roots (next to a singular set two roots 1e-5 ... 1e-3 apart each solve the pose,
#: and the polish from between them converges to one). With the wrist nearly singular (UR16e, A5 = 1.7e-4 at a
#: shoulder double root) the closed form's split pair lies 2.7e-4 apart: the rounding of joint 1 (1e-8) over A5.
MEET_STAY = 0.1

#: Beyond this (the former ``MEET_REL``), the midpoint must solve the pose no worse than twice the worse of the pair,
#: not merely below ``POLISH_ABOVE_REL``: a PUMA 560 1e-7 rad off its elbow fold has two roots 3e-4 apart whose polished
#: midpoint misses the pose by 6e-15 of the arm's size, 60 times more than they do (the UR16e's split root: 1.3e-16).
MEET_NEAR = 1e-4

#: ... or than this (relative to the length scale: a few roundings of the forward kinematics; a UR18's split root
#: 6e-4 apart, each 1e-16, midpoint 2.2e-16).
MEET_ROUNDING_REL = 1e-15

#: A family's end is at a joint limit when a joint of its member there is this close to it (radians; relative to
#: the length scale for a slide): the limits cut it there (``family_join._cut_short``) ...
AT_LIMIT = 1e-7

#: ... and elsewhere the continuum goes on past it when the member this far beyond it (relative to the joint's
#: range) is a near-solution (within ``POLISH_BELOW_REL``): the family's closed form lost digits there. Past a
#: fold or a branch-domain edge, where a continuum ends, the member misses the pose by ~this times the arm.
PAST_END_REL = 1e-3
