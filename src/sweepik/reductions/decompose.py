"""Automatic decomposition: the choice among the plans that solve an arm, and why none does.

Detect (``Robot.structure``), then list (:func:`.plan.plans`: every family, theta* and position case that applies,
on the chain and on the reversed chain, best first), then choose (``choose``: the first, or on an arm with a
near-structure the one the registered check finds sound), then solve (:class:`.generic.GeometricReduction`).
Where no plan applies, ``continuum_everywhere``, ``not_sweepable`` and the ``NoReductionError`` say why.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import lru_cache
from typing import Any

from sweepik.errors import NoReductionError
from sweepik.model.robot import Robot
from sweepik.model.structure import near_structure
from sweepik.reductions.general import general_refusal
from sweepik.reductions.plan import (
    DEGENERATE_TOL,
    GENERAL,
    Plan,
    chain_structures,
    near_structures,
    parallel_plans,
    plans,
)

__all__ = [
    "FEWER_POLISHED",
    "plans",
    "choose",
    "choice",
    "cheapest",
    "companion_plan",
    "explain",
    "passes_check",
    "set_plan_check",
]


def continuum_everywhere(robot: Robot) -> str | None:
    """Why every pose of ``robot`` is a continuum (or nearly: an arm no decomposition can solve to certification),
    or None. Two consecutive revolute axes on one line (exactly, or to ``DEGENERATE_TOL``: a 7-joint arm whose
    elbow is locked straight, e.g. the Realman RM75 with joint 4 at 0) turn the rest of the arm by the sum of their
    angles alone; a spherical shoulder and a spherical wrist (exactly or nearly: an SRS arm with its elbow locked, the
    KUKA iiwa or the RM75 with joint 4 held) leave a turn about the line through their centres free."""
    st = robot.structure()
    near = near_structure(robot.chain, robot.length_scale, DEGENERATE_TOL)
    coaxial = [f"{i + 1}≡{i + 2}" for i, rel in enumerate(st.pairs) if rel == "coincident"]
    coaxial += [t for t in near if "≈≡" in t]
    ends = [
        st.common_point(run) or any(t.startswith(label + " ") for t in near)
        for run, label in (((0, 1, 2), "1≈∩2∩3"), ((3, 4, 5), "4≈∩5∩6"))
    ]
    if all(robot.is_revolute) and all(ends):
        return (
            f"robot {robot.name!r}: every pose is a continuum (or nearly one): joints 1-3 meet at one point and joints "
            "4-6 at another (exactly or to 1e-5), so the two points keep their distance and a pose fixes the arm only "
            "up to a turn about the line through both (a 7-joint arm with its elbow locked: its self-motion); with "
            "joints locked, lock another joint"
        )
    if not coaxial:
        return _rank_deficient(robot)
    return (
        f"robot {robot.name!r}: every pose is a continuum (or nearly one): joints {', '.join(coaxial)} turn about one "
        "line (joints numbered from 1 in this arm), so only the sum of their angles is fixed by a pose; with joints "
        "locked, lock another joint or another value"
    )


#: Configurations (spread over the joint ranges by a fixed sequence) at which ``_rank_deficient`` looks at the
#: Jacobian, and the ratio of its smallest to largest singular value (rows and slide columns scaled by the arm's
#: size) below which the arm counts as moving its tool in fewer than six directions there.
RANK_SAMPLES = 4
RANK_TOL = 1e-9


def _rank_deficient(robot: Robot) -> str | None:
    """Why every pose is a continuum when the arm's six joints move the tool in at most five directions at every
    configuration (a relation the structural checks do not name, e.g. three vertical axes and a horizontal slide
    with a wrist that cannot lift: the height is fixed by the orientation), or None. Seen at ``RANK_SAMPLES``
    configurations: a generic one of rank six shows the arm is not degenerate."""
    if robot.n_joints != 6:
        return None
    import numpy as np  # (only here: the structural checks need no arrays)

    u = (np.arange(1, RANK_SAMPLES + 1)[:, None] * (np.sqrt([2, 3, 5, 7, 11, 13]) % 1.0)) % 1.0
    q = robot.lower + (0.1 + 0.8 * u) * (robot.upper - robot.lower)
    L = robot.length_scale
    J = robot.jacobian(q)
    J = J * np.where(robot.is_revolute, 1.0, L)[None, None, :]
    J[:, :3, :] /= L
    sv = np.linalg.svd(J, compute_uv=False)
    if np.any(sv[:, -1] > RANK_TOL * sv[:, 0]):
        return None
    return (
        f"robot {robot.name!r}: every pose is a continuum: its six joints move the tool in at most five independent "
        f"directions at every configuration (the Jacobian's rank is below 6 at {RANK_SAMPLES} configurations spread "
        "over the joint ranges), so every pose it reaches is reached along a curve of configurations"
    )


def _continuum_refused(robot: Robot) -> bool:
    """The UR family's closed form applies but was refused for its continuum (``plan.continuum_covered``): at joint
    5 = 0 the solutions form a continuum that only a sweep can report, and no sweep fits the arm. The general
    method's elimination is singular there (every value of its eigen-joint a root) and finds no member either, so
    the arm is refused rather than answered "unreachable" at a reachable pose. (Six-joint arms only: the family's
    axes 2-6 are not all there on fewer joints.)"""
    if robot.n_joints != 6:
        return False
    return any(parallel_plans(robot, chain, rev_chain, s) for rev_chain, chain, s in chain_structures(robot))


def _missing(robot: Robot) -> str:
    if robot.n_joints != 6:
        return f"robot {robot.name!r} has {robot.n_joints} joints: the decompositions solve 6-joint arms."
    st = robot.structure()
    head = f"robot {robot.name!r} ({st.describe()}) is outside sweepik's catalogue: "
    if _continuum_refused(robot):
        return head + (
            "axes 2-4 are parallel (the UR family), but joint 6's axis can turn parallel to them (its wrist has an "
            "offset): at joint 5 = 0 the solutions form a continuum that only a sweep can report, and no sweep fits "
            "this arm (it needs two axes meeting at the tool or at the base)"
        )
    near = near_structures(robot)
    nearly = (
        f" Its description has relations that hold only nearly ({', '.join(near)}: rounded, not exact), and a "
        "decomposition built on them would be off by about that much times the arm's size; with them exact, a "
        "decomposition may exist"
        if near
        else ""
    )
    return (
        head
        + (
            "a decomposition needs the last two axes (or the first two) revolute and meeting at a point, with the "
            "other joints placing that point by a chain of subproblems (two revolute axes among them parallel or "
            "meeting, two parallel revolute axes around a slide, a revolute joint before or after two slides, or "
            "three slides), or axes 2-4 parallel (the UR family)."
        )
        + nearly
    )


def not_sweepable(robot: Robot, free_joint: int, full: Robot | None = None, joints: Sequence[int] = ()) -> str:
    """Why ``free_joint`` cannot be theta*, and which joints can (by name, index from 0 and number from 1). With
    ``full`` (an arm with joints held; ``robot`` is the smaller arm solved, its joint i being ``full``'s joint
    ``joints[i]``) the joints are named and counted as in ``full``."""
    avail = sorted({p.free_joint for p in plans(robot) if not p.closed_form})
    arm, index = (robot, list(range(robot.n_joints))) if full is None else (full, list(joints))

    def name(j: int) -> str:
        return f"{arm.joint_names[index[j]]} (index {index[j]}, number {index[j] + 1})"

    held = "" if full is None else " (with joints held)"
    return f"robot {arm.name!r}{held}: no decomposition sweeps {name(free_joint)}; joints that can be swept: " + (
        ", ".join(name(j) for j in avail) or "none"
    )


#: The check of a choice (``plan_check.checked_choice``: plans solved on sample configurations of the arm), registered
#: by the solver's layer, which can solve; None: the ranking alone chooses.
_plan_check: Callable[..., Any] | None = None


def set_plan_check(check: Callable[..., Any] | None) -> None:
    """Register the check that :func:`choose` runs on the plans it chooses among (None: none)."""
    global _plan_check
    _plan_check = check
    choice.cache_clear()


def passes_check(robot: Robot, plan: Plan) -> bool:
    """Whether ``plan`` gives back every configuration of the registered check's short form on ``robot`` (the check
    a hint of :func:`choice` passes; True where no check is registered)."""
    return _plan_check is None or _plan_check(robot, (plan,), (plan,), hints_only=True) is not None


def choose(robot: Robot, free_joint: int | None = None) -> Plan:
    """The best plan for ``robot`` (with theta* = ``free_joint`` if given); NoReductionError if there is none."""
    return choice(robot, free_joint)[0]


@lru_cache(maxsize=64)
def choice(robot: Robot, free_joint: int | None = None, hints: tuple[Plan, ...] = ()) -> tuple[Plan, tuple[Any, ...]]:
    """:func:`choose`'s plan and the checks that chose it (``plan_check.PlanCheck``, in the order made; empty when
    there was nothing to choose from). The candidates: the plans sweeping ``free_joint`` if given, else those
    without a blind spot (all plans when every one has one), best ranked first. The first is chosen, unless the arm
    has a near-structure (``structure.near_structure``): then every candidate is checked on the arm and the one that
    recovers most of the check's configurations is chosen (:mod:`sweepik.plan_check`). A ``free_joint`` whose best
    plan loses any of them raises NoReductionError (a sweep of that joint would miss solutions on this arm). ``hints``
    (candidates, e.g. the plans chosen for the same arm at other lock values): the first that a shorter check on the
    arm finds sound is taken (``plan_check.checked_choice``)."""
    everywhere = continuum_everywhere(robot)
    if everywhere:
        raise NoReductionError(everywhere)
    options = plans(robot)
    if free_joint is not None:
        options = tuple(p for p in options if not p.closed_form and p.free_joint == free_joint)
        if not options:
            raise NoReductionError(not_sweepable(robot, free_joint))
    elif not options:  # (no structure to use: the general method, for six joints)
        if robot.n_joints != 6:
            raise NoReductionError(_missing(robot))
        if _continuum_refused(robot):  # (the general method too would answer "unreachable" on its continuum)
            raise NoReductionError(_missing(robot))
        why = general_refusal(robot)
        if why is not None:
            raise NoReductionError(_missing(robot) + f" The general method does not apply either: {why}.")
        return GENERAL, ()
    else:
        options = tuple(p for p in options if not p.conditional) or options
    near = near_structures(robot)
    hinted = tuple(h for h in hints if h in options)
    if _plan_check is not None and near and free_joint is None and len(options) > 1 and hinted:
        # (a hint the short check finds sound is taken whatever the other options: the general method's own setup,
        # ~20 ms of elimination, is not needed for it)
        quick = _plan_check(robot, options, hinted, hints_only=True)
        if quick is not None:
            return quick
    if near and free_joint is None and general_refusal(robot) is None:
        options = (*options, GENERAL)  # (a decomposition built on a relation that holds only nearly may miss)
    if _plan_check is None or not near or (len(options) == 1 and free_joint is None):
        return options[0], ()
    plan, checks = _plan_check(robot, options, hinted)
    best = next(c for c in checks if c.plan == plan)
    if free_joint is not None and best.recovered < best.checked:
        raise NoReductionError(
            f"robot {robot.name!r}: sweeping {robot.joint_names[free_joint]} (index {free_joint}) would miss "
            f"solutions: the arm has a near-structure ({', '.join(near)}), and checked on {best.checked} of its "
            f"configurations that sweep gave back {best.recovered}; leave free_joint unset (the automatic choice) or "
            "see sweepik.analyze(robot)['checks']"
        )
    return plan, checks


#: Of plans that score alike, one whose check needed Newton steps (``plan_check.PlanCheck.polished``) on at least
#: this share of the configurations fewer than the better ranked's is preferred to it: the Doosan M0609's joint-1
#: sweep polished all 64 of its check, its joint-4 sweep none (single solves 537 and 67 us a pose). A count, not a
#: timing: the choice is the same from run to run and for every way of writing the arm.
FEWER_POLISHED = 0.25


def cheapest(checks: Sequence[Any]) -> Any:
    """The first of ``checks`` (``plan_check.PlanCheck``s, the better ranked first), or the one that needed the
    fewest polishes (the better ranked of equals) if that is ``FEWER_POLISHED`` of the configurations fewer."""
    least = min(checks, key=lambda c: c.polished)
    return least if checks[0].polished - least.polished >= FEWER_POLISHED * checks[0].checked else checks[0]


def companion_plan(robot: Robot) -> Plan | None:
    """The plan solved beside the automatic choice on an arm with a near-structure (:mod:`sweepik.engine.companion`):
    of the other checked plans that gave back every configuration of the check and sweep another joint or the other
    chain, the best scored (ties: ``cheapest``); None without a near-structure or such a plan."""
    try:
        plan, checks = choice(robot, None)  # (the key `choose` uses: one cached choice)
    except NoReductionError:
        return None
    mine = (plan.reversed, plan.free)
    others = [c for c in checks if c.passed and (c.plan.reversed, c.plan.free) != mine and c.plan != plan]
    if not others:
        return None
    top = max(c.score for c in others)
    return cheapest([c for c in others if c.score == top]).plan


def explain(robot: Robot) -> dict[str, Any]:
    """Plain values for ``sweepik analyze``: structure, every plan, the chosen one (or why none)."""
    st = robot.structure()
    found = plans(robot)
    near = near_structures(robot)
    info: dict[str, Any] = {
        "robot": robot.name,
        "structure": st.describe(),
        "near_structure": list(near),
        "plans": [_plan_dict(robot, p) for p in found],
        "checks": [],
    }
    try:
        plan, checks = choice(robot, None)
    except NoReductionError as e:
        info.update(chosen=None, reason=str(e), why=None, companion=None)
        return info
    info.update(chosen=_plan_dict(robot, plan), reason=None)
    info["checks"] = [
        {**_plan_dict(robot, c.plan), "recovered": c.recovered, "checked": c.checked, "solutions": c.solutions}
        for c in checks
    ]
    comp = companion_plan(robot)
    info["companion"] = None if comp is None else _plan_dict(robot, comp)
    if checks:
        best = next(c for c in checks if c.plan == plan)
        info["why"] = (
            f"near-structure ({', '.join(near)}): every plan checked on {best.checked} configurations of the arm; "
            f"this one gave {best.recovered} of them back and {best.solutions} solutions in all, the most"
        )
        alike = [c for c in checks if c.score == best.score]
        if best is not alike[0]:
            info["why"] += (
                f"; of the {len(alike)} plans that did as well it needed Newton steps on the fewest configurations "
                f"({best.polished}, the best ranked on {alike[0].polished})"
            )
    elif plan.family == "general":
        info["why"] = "no structured decomposition applies to this arm: the general method (elimination) solves it"
    else:
        info["why"] = "the best ranked plan (a closed form before a sweep, no blind spot, fewer branches)"
    return info


def _plan_dict(robot: Robot, p: Plan) -> dict[str, Any]:
    return {
        "family": p.family,
        "method": "elimination" if p.family == "general" else "closed form" if p.closed_form else "sweep",
        "closed_form": p.closed_form,
        "free_joint": None if p.closed_form else p.free_joint,
        "free_joint_number": None if p.closed_form else p.free_joint + 1,
        "free_joint_name": None if p.closed_form else robot.joint_names[p.free_joint],
        "chain": "reversed" if p.reversed else "forward",
        "case": p.case,
        "branches": p.branches,
        "blind_spot": p.conditional,
        "steps": p.steps(),
    }
