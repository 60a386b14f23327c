"""Reductions ("given theta*, solve the rest") and their registry."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

from sweepik.errors import LockedJointError, NoReductionError, SweepikError, UnknownOptionError
from sweepik.model.origin_axis import hold_joints
from sweepik.model.robot import Robot
from sweepik.reductions import decompose, general
from sweepik.reductions.base import Reduction
from sweepik.reductions.carm import CArmD1, CArmTheta2
from sweepik.reductions.decompose import choose
from sweepik.reductions.general import GeneralReduction, general_refusal
from sweepik.reductions.generic import GeometricReduction, Plan
from sweepik.reductions.plan import GENERAL, first_plan, position_plan

__all__ = [
    "Reduction",
    "CArmD1",
    "CArmTheta2",
    "GeometricReduction",
    "GeneralReduction",
    "Plan",
    "reduction_for",
    "REDUCTIONS",
    "get_reduction",
    "is_default",
    "first_held_reduction",
    "AUTO",
    "set_plan_check",
    "automatic_for_held",
    "vouch_held_plan",
    "held_pair",
    "paired_reduction",
    "plan_signature",
    "PlanSignature",
]

#: Name of the reduction derived from the arm's geometry (``reductions.decompose``).
AUTO = "auto"

#: Registry: name -> factory(robot). Factories raise RobotDefinitionError for robots they do not fit.
REDUCTIONS: dict[str, Callable[[Robot], Reduction]] = {
    "carm-d1": CArmD1,
    "carm-theta2": CArmTheta2,
}
#: Short aliases accepted by ``solve(..., reduction=...)`` and the CLI.
_ALIASES = {"d1": "carm-d1", "theta2": "carm-theta2"}


def get_reduction(robot: Robot, reduction: str | Reduction | None, free_joint: int | None = None) -> Reduction:
    """Resolve ``reduction`` for ``robot``: an instance as is; a name (``"auto"``: derived from the arm's
    geometry); None: the robot's ``default_reduction`` if it names one, else ``"auto"``. ``free_joint`` (a joint
    index) asks the automatic decomposition for that theta*. NoReductionError when no decomposition applies."""
    if isinstance(reduction, Reduction):
        return reduction
    name = _name(robot, reduction, free_joint)
    if name == AUTO:
        return _automatic(robot, free_joint)
    if name not in REDUCTIONS:
        names = sorted(REDUCTIONS) + sorted(_ALIASES) + [AUTO]
        if reduction is None:  # (the robot file's default_reduction)
            raise UnknownOptionError(
                f"robot {robot.name!r}: its default_reduction {robot.default_reduction!r} is not a reduction; "
                f"choose one of {names}"
            )
        raise UnknownOptionError(f"unknown reduction {reduction!r}; choose one of {names}")
    return _cached(robot, name)


def _name(robot: Robot, reduction: str | None, free_joint: int | None) -> str:
    """The registry name (or ``AUTO``) that ``reduction`` resolves to (``get_reduction``)."""
    if reduction is None:
        reduction = AUTO if free_joint is not None else (robot.default_reduction or AUTO)
    return _ALIASES.get(reduction, reduction)


def is_default(robot: Robot, reduction: object) -> bool:
    """Whether ``reduction`` (None or a name) resolves to ``robot``'s default reduction, the one None gives."""
    return reduction is None or (type(reduction) is str and _name(robot, reduction, None) == _name(robot, None, None))


@lru_cache(maxsize=64)
def _cached(robot: Robot, name: str) -> Reduction:
    # Robots are values (equal and hashed by content): one reduction instance per (robot, name).
    return REDUCTIONS[name](robot)


def reduction_for(robot: Robot, plan: Plan) -> Reduction:
    """The reduction that solves ``robot`` with ``plan``: the general method's, or a geometric family's."""
    if plan.family == "general":
        return GeneralReduction(robot)
    return GeometricReduction(robot, plan)


@lru_cache(maxsize=64)
def _automatic(robot: Robot, free_joint: int | None) -> Reduction:
    red = reduction_for(robot, choose(robot, free_joint))
    if free_joint is None:  # (an arm with a near-structure: a second plan's solutions joined, sweepik.engine.companion)
        comp = decompose.companion_plan(robot)
        red.companion = None if comp is None else reduction_for(robot, comp)
    return red


def set_plan_check(check: Callable[..., object] | None) -> None:
    """Register the check that the automatic decomposition runs on the plans it chooses among
    (``decompose.set_plan_check``); cached choices are dropped."""
    decompose.set_plan_check(check)
    _automatic.cache_clear()


#: A plan as ``position_plan`` builds it on a held arm at another value: family, chain, theta*, case.
PlanSignature = tuple[str, bool, int, str]
#: The plan chosen for an arm with joints held, by (full arm, held joints): a new lock value reuses it (see
#: ``automatic_for_held``).
_HELD_PLANS: dict[tuple[Robot, tuple[int, ...]], tuple[PlanSignature | None, ...]] = {}


def plan_signature(plan: Plan) -> PlanSignature:
    """What ``position_plan`` needs to build ``plan`` on a held arm at another value: family, chain, theta*, case."""
    return plan.family, plan.reversed, plan.free, plan.case


#: Plans that hold at every value of a held joint but a few (``engine.held_pose``), by (full arm, held joints): the
#: plan's signature, its companion's (or None) and the windows of values where they may not (``vouch_held_plan``).
_VOUCHED: dict[
    tuple[Robot, tuple[int, ...]], tuple[PlanSignature, PlanSignature | None, Callable[[float], float | None]]
] = {}
#: What the plan choice of a held arm found at a window's reference value (``_window_second``), by (full arm, held
#: joints, reference value): its plan's signature and its companion's (None: none; the plan None: no plan).
_WINDOW_CHOICES: dict[tuple[Robot, tuple[int, ...], float], tuple[PlanSignature | None, PlanSignature | None]] = {}


def vouch_held_plan(
    full: Robot,
    held: tuple[int, ...],
    sig: PlanSignature,
    window: Callable[[float], float | None],
    companion: PlanSignature | None = None,
) -> None:
    """``full`` with the joints ``held`` locked is the plan ``sig`` (a ``wrist`` or ``pair`` plan's family, chain,
    theta* and case) at every value outside a few windows (``window(value)``: the reference value of the window
    holding ``value``, ``engine.lock_windows.window_reference``; None outside them), and that plan is the first
    without a blind spot there (``engine.held_pose`` checked it): ``automatic_for_held`` then builds that plan at a
    new value (``position_plan``) instead of finding it again (``first_plan``, the near-structure and continuum
    checks: 1-4 ms), with the same outcome; inside a window, the second opinion it joins is chosen once, at the
    window's reference value (``_window_second``). With ``companion``: a held arm with a near-structure solved by
    ``sig`` and that companion at every such value (``engine.held_joined`` checked both at five values and where axes
    turn perpendicular), taken as they are instead of checked again (every plan at a value seen first, or the short
    check of the plan chosen before: 5-10 ms a value on the Kinova Gen3)."""
    if sig[0] in ("wrist", "pair") and (companion is None or companion[0] in ("wrist", "pair")):
        if len(_VOUCHED) > 256:  # (bounded, as the caches around it)
            _VOUCHED.clear()
        _VOUCHED[(full, held)] = (sig, companion, window)


def _vouched(
    full: Robot, held: tuple[int, ...], arm: Robot, values: tuple[float, ...] | None
) -> tuple[Plan, Plan | None] | None:  # fmt: skip
    """The plan ``vouch_held_plan`` vouched for at these ``values`` (one held joint), and its companion (None: none
    vouched for); None where none was, the value is one of its special ones, or a plan does not apply."""
    entry = _VOUCHED.get((full, held))
    if entry is None or values is None or len(values) != 1 or entry[2](values[0]) is not None:
        return None
    plan = position_plan(arm, *entry[0])
    if plan is None or entry[1] is None:
        return None if plan is None else (plan, None)
    comp = position_plan(arm, *entry[1])
    return None if comp is None else (plan, comp)


def held_pair(arm: Robot, pair: tuple[PlanSignature, PlanSignature] | None = None) -> Reduction | None:
    """``arm`` (a held arm) solved by a plan and a companion as ``engine.held_joined`` takes them at each value:
    with ``pair`` None the automatic choice at a value seen first (every plan checked, ``get_reduction(arm,
    "auto")``) where it has a companion and both are ``wrist`` or ``pair`` plans; else the plans ``pair`` names
    (``plan_signature``s: chosen plan, companion) where both apply and both pass the short check on ``arm``
    (``decompose.passes_check``). None otherwise."""
    if pair is None:
        try:
            red = _automatic(arm, None)
        except SweepikError:
            return None
        comp = getattr(red, "companion", None)
        if not (isinstance(red, GeometricReduction) and isinstance(comp, GeometricReduction)):
            return None
        return red if red.plan.family in ("wrist", "pair") and comp.plan.family in ("wrist", "pair") else None
    plan, comp = (position_plan(arm, *sig) for sig in pair)
    if plan is None or comp is None or not (decompose.passes_check(arm, plan) and decompose.passes_check(arm, comp)):
        return None
    return paired_reduction(arm, plan, comp)


def automatic_for_held(
    full: Robot, held: tuple[int, ...], arm: Robot, values: tuple[float, ...] | None = None
) -> Reduction:
    """The automatic reduction of ``arm``, ``full`` with the joints ``held`` locked at some values: as
    ``get_reduction(arm, "auto")`` (on an arm with a near-structure every plan is checked on the arm, ``plan_check``),
    but the plan chosen for other values of the same joints (the same family, theta*, case and chain) is taken
    when a shorter check at these values finds it (or else its companion, :mod:`sweepik.engine.companion`) sound, the
    other of the two as the companion: a new lock value every pose (a redundant arm's self-motion swept, a path with a
    changing elbow angle) would otherwise check every plan again. ``values``: the held joints' values (a plan
    ``vouch_held_plan`` vouched for at them is taken as ``first_plan`` would find it; at its special values, the plans
    vouched for are the hints, not those of the values solved before, so that the answer does not depend on them)."""
    key = (full, held)
    if full.n_joints == 7 and len(held) == 1:
        general.held_arm(arm, full, held[0])  # (its elimination's setup, if it needs one, takes a hint)
    entry = _VOUCHED.get(key)
    # (a joint whose plans are vouched for: they are the hints at its special values too, whatever was solved before)
    sigs = _HELD_PLANS.get(key, ()) if entry is None else entry[:2]
    vouched = _vouched(full, held, arm, values)
    lazy = vouched if vouched is not None and vouched[1] is not None else None  # (a pair: ``engine.held_joined``)
    if lazy is None:
        lazy = _without_near_structure(arm, sigs, None if vouched is None else vouched[0])
    if lazy is not None:
        plan, comp = lazy
    else:
        options = decompose.plans(arm)
        hints = tuple(p for sig in sigs for p in options if sig is not None and plan_signature(p) == sig)
        plan, _ = decompose.choice(arm, None, hints)
        if plan in hints:  # (the other plan chosen with it, unchecked: a companion only adds solutions)
            comp = next((p for p in hints if p != plan), None)
            if comp is None and plan_signature(GENERAL) in sigs and general_refusal(arm) is None:
                comp = GENERAL  # (its setup takes the ranking found at the other values: ``general._setup``)
            if comp is None:  # (none remembered: this value's own choice, or its companion, as a second opinion)
                ref = None if entry is None or values is None or len(values) != 1 else entry[2](values[0])
                comp = _own_second(arm, plan) if ref is None else _window_second(full, held, arm, plan, ref)
        else:
            comp = decompose.companion_plan(arm)
    red = paired_reduction(arm, plan, comp)
    if len(_HELD_PLANS) > 256:  # (bounded, as the caches around it)
        _HELD_PLANS.clear()
    _HELD_PLANS[key] = (plan_signature(plan), None if comp is None else plan_signature(comp))
    return red


def _own_second(arm: Robot, plan: Plan) -> Plan | None:
    """A companion for ``plan``, the plan remembered from other values that the short check at these values found
    sound: the plan this value alone chooses, or its companion where that is ``plan``. A check that samples
    configurations can pass a plan that loses a pose's roots near the near-structure (the Kinova Gen3 with joint 6
    held at -0.49 after 0: two of eight, by a rounding of the meeting point)."""
    try:
        own, _ = decompose.choice(arm, None)
    except NoReductionError:
        return None
    return own if own != plan else decompose.companion_plan(arm)


def _window_second(full: Robot, held: tuple[int, ...], arm: Robot, plan: Plan, ref: float) -> Plan | None:
    """``_own_second`` at a value in a window of a vouched plan, chosen once for the window: at its reference value
    ``ref`` (``vouch_held_plan``), every plan checked there, and the plan that choice takes (or its companion, where
    that is ``plan``) built at this value. Each value in a window chose its own (8 plans checked, 0.2-0.6 s a value on
    the Panda held at joint 6); the choice at a fixed value keeps the answer independent of the values solved
    before. This value's own choice where the one at ``ref`` does not apply here (or ``ref`` is outside the
    limits)."""
    key = (full, held, ref)
    found = _WINDOW_CHOICES.get(key)
    if found is None:
        try:
            at_ref = hold_joints(full, {held[0]: ref}).arm
        except LockedJointError:
            return _own_second(arm, plan)
        try:
            own, _ = decompose.choice(at_ref, None)
        except NoReductionError:
            found = (None, None)
        else:
            comp = decompose.companion_plan(at_ref)
            found = (plan_signature(own), None if comp is None else plan_signature(comp))
        if len(_WINDOW_CHOICES) > 256:  # (bounded, as the caches around it)
            _WINDOW_CHOICES.clear()
        _WINDOW_CHOICES[key] = found
    own_sig, comp_sig = found
    second = own_sig if own_sig != plan_signature(plan) else comp_sig
    if second is None:
        return None
    if second == plan_signature(GENERAL):
        return GENERAL if general_refusal(arm) is None else None
    built = position_plan(arm, *second) if second[0] in ("wrist", "pair") else None
    return built if built is not None else _own_second(arm, plan)


def first_held_reduction(arm: Robot) -> Reduction | None:
    """``automatic_for_held``'s reduction of ``arm`` (an arm with joints held) at values never held before: its first
    plan without a blind spot, no companion; None where that choice checks every plan (a near-structure, a
    continuum everywhere, no plan). Whatever other values chose (``engine.held_pose`` checks the plan of a joint's
    values with it)."""
    lazy = _without_near_structure(arm, ())
    return None if lazy is None else paired_reduction(arm, lazy[0], None)


def _without_near_structure(
    arm: Robot, sigs: tuple[PlanSignature | None, ...], vouched: Plan | None = None
) -> tuple[Plan, Plan | None] | None:
    """``automatic_for_held``'s plan and companion for an arm without a near-structure (nor a continuum everywhere),
    the same ones, without every plan checked: ``decompose.choice`` takes the first plan without a blind spot
    (``plan.first_plan``), and the companion is the other plan chosen with it before (``sigs``) where that plan
    applies (``plan.position_plan``), else None (``companion_plan``'s without a near-structure). None: the arm needs
    ``plans`` (a near-structure, a parallel plan first, no plan, or a companion of a family ``position_plan`` does not
    build). ``vouched``: the plan ``vouch_held_plan`` vouched for (no near-structure there, the first plan)."""
    plan = vouched
    if plan is None:
        if decompose.near_structures(arm) or decompose.continuum_everywhere(arm) is not None:
            return None
        plan = first_plan(arm)
        if plan is None:
            return None
    mine = plan_signature(plan)
    if mine not in sigs:
        return plan, None
    for sig in sigs:  # (the hints, in their order: the first other one that applies)
        if sig is None or sig == mine:
            continue
        if sig[0] not in ("wrist", "pair"):
            return None
        other = position_plan(arm, *sig)
        if other is not None:
            return plan, other
    return plan, None


@lru_cache(maxsize=64)
def paired_reduction(arm: Robot, plan: Plan, companion: Plan | None) -> Reduction:
    """``arm`` solved by ``plan`` with ``companion`` (None: none) joined (:mod:`sweepik.engine.companion`)."""
    red = reduction_for(arm, plan)
    red.companion = None if companion is None else reduction_for(arm, companion)
    return red
