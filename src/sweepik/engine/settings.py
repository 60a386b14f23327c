"""The engine's tolerances and constants, in one place: the sweep search's (both engines read them), certification's,
the settling steps', the families', the tracer's, the partners' and the paper's strategy's. A module's private
constants (buffer sizes, performance thresholds) stay beside the function that uses them. Relative tolerances
multiply the arm's length scale (``Robot.length_scale``); ``_REL`` names say so, angles are in radians.

Compiled kernels read these as constants when they are compiled (cached on disk): a change takes effect with the next
compilation."""

from __future__ import annotations

import numpy as np

# Certification and the settling steps (chunk.py, settle.py, family_join.py)

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
#: ... and a candidate the search gives as a multiple root (an extremum of the residual touching zero, multiplicity
#: 2 or more) up to this: a double root is fixed in theta* only to about the square root of the rounding, and next to
#: a branch domain's edge the residual grows like the square root of the distance to it (a Kinova JACO2 on its
#: singular set: a double root 3e-9 rad from the edge, the edge's candidate missing the pose by 8e-6 of the arm's
#: size, certified after the polish). Such candidates are few (singular poses): the common pose pays nothing.
POLISH_MULTIPLE_REL = 1e-4
#: ... and a simple root's candidate up to this when its configuration is nearly singular
#: (``partners.nearly_singular``): a root 7.8e-7 rad inside a branch domain's edge, on a tangent bump 2e-6 wide that
#: no sampling sees (an xArm 6 on its singular set), leaves the edge's candidate 1.3e-4 rad from it, missing the pose
#: by 1.4e-6 of the arm's size; polished, it is the root. Up to ``POLISH_MULTIPLE_REL`` the C-Arm's single solves took
#: 1.3 times as long (a tenth of its poses has such a candidate, mostly a residual's shallow minimum); up to this, a
#: hundredth.
POLISH_SINGULAR_REL = 1e-5

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

#: Passes over a pose's pairs of close solutions: a merged pair's root lies between them, so its pairs with the rest
#: of a cluster (a flat valley next to the singular set: up to five points 1e-6 ... 1e-5 apart) are asked again.
MEET_PASSES = 4

#: Where a pair's midpoint misses the pose, the points of the segment between them (fractions of the way) corrected
#: with the joint that moves most held: on one arc of solutions they solve the pose as the pair does (a valley that
#: curves), between two roots they cannot. Newton steps of each correction.
MEET_ARC = (0.25, 0.5, 0.75)
MEET_ARC_STEPS = 12

#: A family's end is at a joint limit when a joint of its member there is this close to it (radians; relative to
#: the length scale for a slide): the limits cut it there (``family_join._cut_short``) ...
AT_LIMIT = 1e-7

#: ... and elsewhere the continuum goes on past it when the member this far beyond it (relative to the joint's
#: range) is a near-solution (within ``POLISH_BELOW_REL``): the family's closed form lost digits there. Past a
#: fold or a branch-domain edge, where a continuum ends, the member misses the pose by ~this times the arm.
PAST_END_REL = 1e-3


# The sweep search (both engines, sweep.py): samples, refinement, roots, extrema, flat stretches, families, roots' order

#: Default number of uniform samples of theta* over its range (hints and refinements come on top).
#: Checked against an independent polynomial solver (tests/carm_oracle.py) and against dense sampling.
N_SAMPLES = 64
#: Samples per refined interval, and the number of refinement levels (resolution: step / SUB**LEVELS).
SUB_SAMPLES = 8
MAX_LEVELS = 4
#: An interval is resampled when min(|f_i|, |f_i+1|) <= BEND * |f''| h^2 (a parabola dips h^2 |f''| / 8
#: below its chord: BEND = 1 leaves a factor 8 for curvature varying within the step). Next to a domain edge
#: (square-root behaviour: no curvature estimate in theta) curvature is judged in the coordinate
#: sqrt(|theta - edge|), in which the residual is smooth (``_edge_coordinate``), and the interval is resampled only
#: where that test says so; at the first level only where the edge sits at a sample (``EDGE_PROBE_REL``), else
#: always.
BEND = 1.0
#: ... and, an edge at a sample, whatever that test says, where the residual at the edge is below this fraction of its
#: neighbour's: it falls towards zero there, and a pair of close roots may sit between the two (the JACO2 next to its
#: singular set: a pair 1.6e-5 apart, 2.3e-4 inside a branch's edge, the edge's residual 1/42 of its neighbour's and
#: the three samples a straight line in the edge's coordinate).
EDGE_LOW = 0.1
#: An interior extremum of |residual| is examined only if its sample is within EXTREMUM_REACH |f''| h^2 of
#: zero: 8 times the deepest dip a parabola through the three samples can have (|f''| h^2 / 2).
EXTREMUM_REACH = 4.0
U_UNIFORM = np.linspace(0.0, 1.0, SUB_SAMPLES + 2)
U_EDGE = 0.5 * (1.0 - np.cos(np.pi * U_UNIFORM))
#: |residual| at or below which a sample counts as lying on a self-motion family (residuals are computed to
#: ~1e-15; an isolated root makes three consecutive samples this small only with probability ~0). No looser: a
#: pose a hair off a self-motion (theta5 = 1e-9 at theta2 = 90 deg on the C-Arm) has a residual of that hair's
#: size along the whole former family, with isolated roots in it that a looser threshold would hide, while its
#: members miss the pose by more than the FK acceptance (about 1e-12 rad of orientation).
FAMILY_TOL = 1e-12
#: Roots of one branch joined by a stretch where the residual stays at rounding noise form a cluster; a
#: cluster longer than this fraction of the theta* range is reported as a family (a numerical continuum:
#: every point of it solves the pose to rounding precision), a shorter one as its midpoint. A double root
#: (f ~ c x^2) is flat at noise level over ~2 sqrt(1e-16 / c), about 1e-8 of the range: far shorter.
CLUSTER_FAMILY_REL = 1e-5
#: Probe distance (relative to the range) deciding whether a root sits in a flat stretch of the residual,
#: the largest half-width searched for such a stretch, and bisection steps locating its ends.
FLAT_PROBE_REL = 1e-9
FLAT_MAX_REL = 1e-2
FLAT_BISECT = 30
#: ... but a stretch too short to be a family (it marks a root of high multiplicity, see ``_center_flat``) only
#: to this fraction of its half-width: its centre is the root, and rounding leaves the root undetermined across
#: the whole stretch anyway (2^-12; 30 halvings would pin the ends to 1e-9 of it).
FLAT_SHORT_TOL = 2.0**-12
#: Bisection steps locating where a family ends between its last sample and the next one.
FAMILY_BISECT = 40
#: Minimum number of consecutive vanishing samples that make a family.
FAMILY_MIN_RUN = 3
#: A flat stretch (|residual| within the noise around a root) ends where the residual leaves the noise. It
#: leaves it *smoothly* next to an isolated root of high multiplicity (just past the end |f| is barely above
#: the noise) and by a *jump* (a branch swap) or at a domain edge (NaN) where a continuum ends: a residual
#: analytic along a branch that vanishes on an interval vanishes up to such an end. |f| above JUMP_NOISE x noise
#: just past the end counts as a jump.
JUMP_NOISE = 1e3
#: Multiplicity of a root: from the growth of |f| away from it, measured where |f| first exceeds
#: MULT_LEVEL x noise (on either side), comparing |f| at distances d and 2 d (ratio 2^m for a root of order m).
MULT_LEVEL = 1e4
#: Largest multiplicity reported (rounding decides nothing finer).
MULT_MAX = 8
#: A located extremum of |residual| whose |residual| exceeds FAR_NOISE x the residual's noise (on the side of its
#: samples) is not a candidate: 1e-2 for residuals of O(1) sines and cosines (noise 1e-14; C-Arm: the sine of the
#: wrist's misalignment), 1e-2 of the arm's size for the pose-error residual; far above what certification
#: (2e-13 of the arm's size) or the Newton polish (candidates within 1e-6 of it) accept. Extrema found that far
#: after their first location are not located further. Samples next to a domain edge or at the range's ends
#: farther from zero are no candidates either; next to a family's samples (masked as NaN) they stay candidates
#: whatever their residual: their flat-stretch probe can join two pieces of the family.
FAR_NOISE = 1e12
#: A domain edge sits at a sample (a generic sweep's margins' zeros are samples) when its branch's residual is not
#: finite this far past it (relative to the theta* range): the first level then judges the interval beside it in that
#: edge's coordinate, as the levels below do (``BEND``).
EDGE_PROBE_REL = 1e-9
#: A margin's zero (a domain edge, ``Reduction.edge_reduction``) found a rounding step outside the domain is moved
#: onto its inside (margin >= 0) before it becomes a sample, by the least of ``EDGE_PROBE_REL x range x 2^-k``,
#: k = EDGE_NUDGES - 1 ... 0, that gets there: a sample outside is NaN for the branches the edge bounds, and the
#: stretch from it to the next sample would go unsearched (an extremum touching zero there was missed).
EDGE_NUDGES = 24
#: ... only a zero whose margin is within this below 0 (a rounding step outside: 2e-11 ... 5e-10 seen; the margins'
#: search also gives samples next to a margin's own NaN and the range's ends, which no nudge moves inside, and trying
#: them all made a Doosan M0609's solve 2-3 times slower).
EDGE_MARGIN = 1e-8
#: Root tolerance relative to the theta* range (2000 mm -> 2e-13 mm, 2 pi -> 6e-16 rad).
XTOL_REL = 1e-16
#: Half-step of the central difference used to locate extrema, relative to the theta* range.
#: Balances rounding (1e-16 / h) against truncation (h^2): the extremum lands within ~1e-8 of the range.
DIFF_STEP_REL = 1e-7
#: The extremum is then relocated with steps DIFF_SHRINK and DIFF_SHRINK^2 times smaller (DIFF_LEVELS in all).
DIFF_SHRINK = 16.0
DIFF_LEVELS = 3


# The compiled search's buffers (search.py)

#: Candidates and family spans kept per pose (the C-Arm has at most 8 rail positions; edges and near misses add
#: candidates). A pose that overflows them is searched again with larger buffers (``REDO_GROW``).
MAX_CAND = 256
MAX_FAM = 16
#: Pending resampled intervals per pose and branch (depth-first, so a few dozen suffice).
STACK = 512
#: A pose that overflows the buffers is searched again with buffers REDO_GROW times larger (the stack too), then,
#: while it still overflows, large enough for twice the counts it reached, up to REDO_MAX_CAND candidates a pose
#: (~100 MB; past it, an error: a residual crossing zero that often is not an arm's. A UR5 pose on a continuum the
#: sweep sees only roughly crossed it 91,000 times before such continua were traced first,
#: :mod:`sweepik.engine.rough_continua`; a stretch of a continuum too short to be traced, 0.05 rad of a random
#: slide_parallel arm's, gives ~10,000 flat stretches).
REDO_GROW = 8
REDO_MAX_CAND = 1 << 22
#: ... but in a fallback's search (``search.candidates_capped``: ``chunk._answered``) a pose whose isolated candidates
#: (not its family spans) overflow buffers of this many raises at once, and the fallback leaves it: on a
#: self-motion of two dimensions (a Panda held at joint 6, axes 1, 3 and 5 on one line) a sweep's residual is zero
#: along stretches of every slice, and its crossings grew eight times each round (168,000 ... 4 million; minutes).
#: The families of a slide_parallel arm's pose above need buffers of 290,000 for 9,055 family spans, no candidate; a
#: Kinova Gen3 held at joint 2 at its zero pose, its own sweep's candidates past this cap, is answered in ~3 s.
REDO_MAX_FOUND = 1 << 17
#: Batches at least this large are searched with parallel threads.
PARALLEL_MIN = 64


# Certification (certify.py)

#: Candidates whose geodesic error exceeds this times the orientation weight (1e-4 x 100 mm = 0.01 mm) are far
#: from any solution (accepted ones are below 1e-9 mm, polished ones below 3e-3 mm): their J is reported as inf.
J_CUTOFF_FACTOR = 1e-4


# The Newton polish (polish.py)

#: Newton steps at most (a step that does not lower the error ends a configuration's polish). Next to a double root
#: on a singular set the steps drop the small singular direction and creep along the valley (5-10 % of the error a
#: step): an I2RT YAM written with other axis signs had its candidates 4e-5 rad off the root at 1.5e-11 of the arm,
#: certified after 11 steps; 8 left them uncertified and the pose without a solution. The big YAM of ssik's catalogue,
#: rewritten, had the general method's double root 1.7e-4 rad off at 1.6e-11: certified after 28 steps (16 left it
#: at 1.4e-11, and the pose one solution short). Regular roots take 2-4.
ITERATIONS = 32
#: A Newton step that raises the error is halved up to this many times (backtracking): next to a fold of the
#: arm's workspace (an elbow nearly straight) the full step overshoots, a shorter one converges. Where the arm loses
#: two ranks (a KR 6 with its wrist centre on axis 1 and its elbow straight) the step from a member interpolated
#: between traced ones points far along the nearly null direction: 8 halvings never got below its 6e-5 error, 20 do.
BACKTRACK = 20


# Duplicates and multiplicity (dedupe.py)

#: Two solutions are the same when every revolute joint agrees within this (radians, modulo 2 pi) ...
DEDUPE_ANGLE = 1e-6
#: ... and every prismatic joint within this times the arm's length scale.
DEDUPE_LENGTH_REL = 1e-8


# Self-motion families (families.py)

#: A local maximum of a joint's limit excess among a span's samples, inside the limits, is searched between its
#: neighbouring samples when it lies within this many times the rise from a neighbour below zero: the excess can
#: exceed zero between two samples inside the limits only where it is still climbing that steeply (a joint turning
#: through +-pi, outside limits narrower than the circle, between two samples is the common case). Where the excess
#: is linear on both sides of its peak, the peak is at most one rise above the sample (1 would do); 1.5 leaves room
#: for curvature.
PEAK_REACH = 1.5
#: Members sampled along a span none of whose members is a solution, returned as candidates to polish.
NEAR_FAMILY_SAMPLES = 9
#: A 6-DOF serial arm has at most 16 isolated IK solutions (a general 6R arm; fewer with prismatic joints). A pose
#: with more certified, distinct solutions holds a numerical continuum: near a self-motion (e.g. two joint axes
#: almost coaxial) a whole arc of configurations reproduces the pose to rounding level, the residual's rounding
#: noise crosses zero along it again and again, and the Newton polish moves every such crossing onto the arc.
MAX_ISOLATED_SOLUTIONS = 16
#: On such a pose, solutions closer than this (joint distance, radians; prismatic joints in units of the
#: paper's 100 mm per radian, see ``trajectory.weighted_joint_distance``) are linked; each linked group is
#: reported once, by its medoid: the pose pins these solutions down no better than the group's extent.
CONTINUUM_LINK = 0.05
#: A pose with more solutions than this is thinned to one per grid cell before they are linked (bounded memory).
CONTINUUM_THIN = 1024
#: Samples along a family span to certify its members and cut it to the joint limits.
FAMILY_SAMPLES = 33
#: Where the branch's closed form breaks down at an isolated theta* of a family (a removable singular point, e.g. the
#: C-Arm's wrist crossing joint 2's axis, d1 = Pz), ``certified_members`` gives the member this far away (relative
#: to the interval): the branch is continuous on either side, and the solution at the point is their limit.
NUDGE_REL = 2.0**-30
#: Where a family piece ends between its samples (1/32 of the span apart) is located to 2**-CUT_BISECT of that,
#: ~1e-8 mm on the C-Arm's rail (``_locate_cuts``).
CUT_BISECT = 32
#: Bisection steps locating a joint's crossing of its limit between two samples outside the limits (``families.
#: _limit_corners``): ~1.5e-11 of a step (a few 1e-12 rad), well inside the limits' tolerance (1e-9) at a point where a
#: family touches the limits (two joints at theirs).
CORNER_BISECT = 36
#: Golden-section steps locating the least limit excess between samples (the bracket shrinks 0.618x a step;
#: the search stops once every bracket has a point inside the limits).
DIP_STEPS = 50
#: Golden-section steps of a peak's search: the bracket (two sample steps) shrinks to 0.618^24 ~ 1e-5 of itself, so
#: an excursion out of the limits wider than ~1e-5 of the sampling is found (most searches find none and run them
#: all: fewer than the dips' steps, which usually stop early).
PEAK_STEPS = 24
#: Two points are the same member when every joint agrees within this (radians modulo 2 pi / relative length).
MEMBER_TOL = 1e-6
#: Where a family's members are probed to tell whether it lies on other families (fractions of its interval): not
#: its ends, which may sit at a fold of the continuum, where two traces of it stop at different distances (the other
#: joints move as the square root of the distance to the fold: 1e-5 rad of the free joint short of it, ~3e-3 rad).
INNER_PROBES = (0.05, 0.25, 0.5, 0.75, 0.95)


# Continua traced along another joint (continuation.py)

#: Nominal steps of the traced joint over a turn (revolute) or over its travel (prismatic) ...
TRACE_STEPS = 64
#: ... halved on a failed step at most this many times before the family is taken to end there.
TRACE_HALVINGS = 14
#: A corrected member farther than this from its prediction (``solutions.weighted_joint_distance``: radians, and
#: 100 mm of a slide per radian) is refused: the correction jumped to another piece of the solution set.
TRACE_JUMP = 0.25
#: Newton steps per correction (at most: a member stops once within rounding). Where the continuum crosses another
#: singular set (carm_swapped's theta2 self-motion at theta2 = -90 deg) Newton converges only linearly: with 6 steps
#: the tracing stopped ~1e-3 short of the crossing on both sides, and the solutions in that gap went missing.
TRACE_NEWTON = 20
#: ... stopping once the error is at most this times the certification's tolerance ...
TRACE_FLOOR = 1e-3
#: ... or once a full step fails to lower an error at most this times it (rounding level, ~1.6e-15 of the arm's
#: size: the halvings and narrower steps tried after a failed step cannot gain there, and cost a correction as much
#: as its converging steps; compiled tracing only).
TRACE_SETTLED = 8e-3
#: A seed is followed only where a continuum can pass along the joint: the arm's Jacobian (lengths over the arm's
#: length scale) has its smallest singular value below this fraction of its largest (members of a continuum: ~1e-17,
#: ~1e-9 where two singular directions meet, and up to ~1e-7 where the member is pinned down only to the root of the
#: rounding: a PUMA 560 member with A5 = 9e-7, A4 = 0, its wrist continuum's direction the second smallest at
#: 9.4e-8; regular solutions: above ~1e-3) ...
TRACE_SINGULAR = 1e-5
#: ... and the joint's share of the nearly null directions (the continuum's tangent among them) is above this.
TRACE_SHARE = 1e-3
#: Seeds corrected at once (``continuum_families``).
SEED_BATCH = 8
#: Families traced from one pose along one joint at most (``continuum_families``). A pose has a few; where each seed
#: traces a family of its own, the pose lies on a self-motion of two or more dimensions (three revolute axes on one
#: line: a Kuka iiwa with its elbow and wrist straight, a Panda with its elbow straight), and its candidates, thousands
#: of them, are each on a curve of it of their own: traced, each filtered against every other, they took minutes.
#: The families returned there are curves on it (the first traced), not all of it.
MAX_TRACES = 32
#: A traced stretch shorter than this fraction of a step is no family (the candidate is isolated).
TRACE_MIN = 0.5
#: A trace's first step is this fraction of a step; until the trace has gone ``TRACE_MIN`` of a step from its seed,
#: its steps are not halved below it (then they double up to a whole step). A member of a continuum can be followed
#: that far (~2.5e-4 rad) from anywhere on it, and corrected there to rounding level (Newton with the traced joint held
#: converges quadratically along a continuum: rank 5) ...
PROBE_STEP = 2.0**-8
#: ... so a first step corrected no closer than this times the certification's tolerance starts from an isolated
#: solution next to a singular set (a wrist centre 1e-7 off a Staubli RX160's axis 1: 0.17 of the tolerance after a
#: first step, 1.2 after 16 times that). Following such a solution as far as the tolerance lets it go, with steps
#: halved down to 2^-14, cost 30-45 ms a seed (8 seeds: 250-430 ms a pose).
PROBE_ERROR = 1e-2


# Families that cross (crossings.py)

#: Members sampled along a family (its interval, ends included) ...
CROSS_SAMPLES = 65
#: ... and steps at most of the search for a least second singular value between them (``crossings.vertex_least``),
#: until it is below ``CROSS_SINGULAR`` (a crossing, located to about that over its slope: far closer than the seeds'
#: step) or cannot get there any more.
CROSS_STEPS = 40
#: ... or until its bracket is this narrow (relative to the joint's value, at least 1: below it the second singular
#: value is rounding).
VERTEX_WIDTH = 1e-13
#: The second singular value (over the largest) at a crossing: members of a continuum have their smallest at ~1e-17.
CROSS_SINGULAR = 1e-7
#: A family whose second singular value stays below this over half its members is not searched: the arm
#: loses a second rank all along it (the KR 6's wrist centre on axis 1 with the elbow straight), where no other
#: continuum branches off at one point.
CROSS_RANK = 1e-5
#: A least sampled value is searched only where the V through it and its neighbours reaches down to this fraction of
#: it (exactly to zero for a crossing between two samples, up to the curvature of the singular value).
VERTEX_REL = 0.25
#: Before a family's ``CROSS_SAMPLES`` are probed, every ``CROSS_SCREEN``-th of them (and every one of the first and
#: last stretch, next to its ends) is screened (``crossings.screened``): a crossing is where the arm loses a second
#: rank, where the cofactors of its Jacobian without the family's joint (a vector normal to what the other five
#: columns span: smooth and signed, zero only there, or where the family's parametrisation turns) pass through zero
#: and change sign. A family whose screen shows no sign change between neighbours and no interior zero is not
#: probed further.
CROSS_SCREEN = 4
#: ... a cofactor vector at most this fraction of the family's largest counts as zero (its sign is rounding).
SCREEN_ZERO = 1e-9
#: ... and a member this far from the last in any joint (radians; times the length scale for a slide) is not
#: compared with it: the family's members may have gone over to another branch between them.
SCREEN_JUMP = 1.0
#: Distance of the seeds from the crossing along the second null direction (radians; times the length scale for a
#: slide): far enough that the correction does not fall back onto the family, near enough to land on the continuum
#: that crosses it.
CROSS_STEP = 1e-3


# Close partners across a fold (partners.py)

#: A solution is probed when its Jacobian's smallest singular value is at most this fraction of its largest (lengths
#: over the arm's size): across a fold (the pose error ~ a x^2 along the nearly null direction) two roots d apart have
#: a smallest singular value of ~a d (the CRX-10iA pair, 2e-5 apart: 8.7e-7, a = 0.04), so 1e-4 takes roots up to
#: ~1e-3 apart on such a fold, and fewer solutions of random poses than 1e-3 (each probe is 8 short Newton runs).
PARTNER_SINGULAR = 1e-4
#: Distances along the nearly null direction (radians, or length over the arm's size) Newton starts from, each way.
PARTNER_STEPS = (1e-6, 1e-5, 1e-4, 1e-3)
#: Newton steps from each start (it converges in ~5 from next to a root; a start that does not is no partner).
PARTNER_NEWTON = 12
#: A point found must solve the pose to the rounding of forward kinematics (this times the arm's size, as
#: ``settings.MEET_ROUNDING_REL``), not merely within the certification's tolerance: between two roots 3e-4 apart next
#: to a PUMA 560's elbow fold the pose error stays below 3 % of that tolerance along a curved valley, and Newton ends
#: anywhere in it (6e-15 of the size); the CRX-10iA's partner: 2e-16.
PARTNER_ROUNDING = 1e-15
#: A point found is the solution itself when every joint lies within this of it (radians; relative for a slide).
PARTNER_SAME = 1e-9
#: ... and a second solution only when the midpoint between them misses the pose by more than this times the
#: certification's tolerance (the CRX-10iA pair: 50 times) ...
PARTNER_MIDPOINT = 4.0
#: ... and Newton from that midpoint ends within this fraction of their distance of one of them (it goes over to it),
#: or does not reach the pose.
PARTNER_STAY = 0.1
#: A polished solution whose pose error stays above FK rounding (``PARTNER_ROUNDING``) next to a fold lies in a flat
#: valley of near-solutions (a double root that a near-structure blurs: an I2RT YAM, axes 2-4 parallel to 3e-6 rad,
#: its polish stopping 1e-5 ... 5e-4 rad from the root at 4e-3 ... 7e-2 of the tolerance). Its lowest point is searched
#: along the nearly null direction within this reach each way (radians; times the length scale for a slide; the YAM
#: valley above is certified to 2e-3 each way, 20 times the tolerance at 1e-2) ...
VALLEY_REACH = 1e-2
#: ... on this many samples (each corrected by Newton with the joint that direction moves most held), then by golden
#: section between the neighbours of the least (``families.golden_least``). A valley whose
#: ends at the reach still solve the pose is a continuum's stretch: no point of it is moved.
VALLEY_SAMPLES = 41
VALLEY_STEPS = 30
#: A valley is one where its ends at the reach miss the pose by more than the tolerance, or by more than this times
#: its lowest point's error (at least ``PARTNER_ROUNDING``): the GP8's below rises to 4e-14 of its size at the reach
#: from 1e-16 at its bottom; a continuum's points solve the pose to rounding all along.
VALLEY_RISE = 4.0
#: A certified solution whose pose error is above this times the arm's size, though below ``POLISH_ABOVE_REL``, may
#: lie on a valley's slope too, nearly singular: a closed form's root just off a fold with the wrist nearly straight
#: (ssik's Yaskawa GP8, the elbow 1e-7 rad off its fold and q5 = 6.5e-5: subproblem 3 loses eps over the distance to
#: the fold, the wrist's step multiplies it by 1/sin q5) comes out 2.2e-3 rad from the root along the nearly null
#: direction at 9.7e-15 of the size, a polish not helping (``PINV_RCOND`` drops that direction). Such solutions, nearly
#: singular (``PARTNER_SINGULAR``: checked in compiled code for the one-pose kernels, ``certify.nearly_singular_row``),
#: are settled step by step and moved to their valley's bottom (``partners.valley_bottoms``). A solution above it is
#: rare (0.2 % of a UR5's random poses have one, 2-7 % of a swept arm's), a nearly singular one rarer.
VALLEY_ABOVE_REL = 4e-15


# The paper's strategy (paper_sweep.py)

#: Coarse step of the sweep: 10 mm (prismatic theta*) or 1 degree (revolute theta*).
COARSE_STEP_MM = 10.0
COARSE_STEP_DEG = 1.0
#: Number of refinement levels (each a tenth of the previous step) and steps on each side per level.
LEVELS = 4
HALF_WIDTH = 10
