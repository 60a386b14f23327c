"""Reductions ("given theta*, solve the rest") and their registry."""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache

from sweepik.errors import NoReductionError, UnknownOptionError
from sweepik.model.robot import Robot
from sweepik.reductions import decompose
from sweepik.reductions.base import Reduction
from sweepik.reductions.carm import CArmD1, CArmTheta2
from sweepik.reductions.decompose import choose
from sweepik.reductions.general import GeneralReduction
from sweepik.reductions.generic import GeometricReduction, Plan
from sweepik.reductions.plan import first_plan, position_plan

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


_Sig = tuple[str, bool, int, str]
#: The plan chosen for an arm with joints held, by (full arm, held joints): a new lock value reuses it (see
#: ``automatic_for_held``).
_HELD_PLANS: dict[tuple[Robot, tuple[int, ...]], tuple[_Sig | None, ...]] = {}


def _signature(plan: Plan) -> _Sig:
    return plan.family, plan.reversed, plan.free, plan.case


#: Plans that hold at every value of a held joint but a few (``engine.held_pose``), by (full arm, held joints): the
#: plan's signature and the test of the values where it may not (``vouch_held_plan``).
_VOUCHED: dict[tuple[Robot, tuple[int, ...]], tuple[_Sig, Callable[[float], bool]]] = {}


def vouch_held_plan(full: Robot, held: tuple[int, ...], sig: _Sig, special: Callable[[float], bool]) -> None:
    """``full`` with the joints ``held`` locked is the plan ``sig`` (a ``wrist`` or ``pair`` plan's family, chain,
    theta* and case) at every value where ``special(value)`` is False, and that plan is the first without a blind
    spot there (``engine.held_pose`` checked it): ``automatic_for_held`` then builds that plan at a new value
    (``position_plan``) instead of finding it again (``first_plan``, the near-structure and continuum checks: 1-4 ms),
    with the same outcome."""
    if sig[0] in ("wrist", "pair"):
        if len(_VOUCHED) > 256:  # (bounded, as the caches around it)
            _VOUCHED.clear()
        _VOUCHED[(full, held)] = (sig, special)


def _vouched(full: Robot, held: tuple[int, ...], arm: Robot, values: tuple[float, ...] | None) -> Plan | None:
    """The plan ``vouch_held_plan`` vouched for at these ``values`` (one held joint), None where none was or the value
    is one of its special ones."""
    entry = _VOUCHED.get((full, held))
    if entry is None or values is None or len(values) != 1 or entry[1](values[0]):
        return None
    return position_plan(arm, *entry[0])


def automatic_for_held(
    full: Robot, held: tuple[int, ...], arm: Robot, values: tuple[float, ...] | None = None
) -> Reduction:
    """The automatic reduction of ``arm``, ``full`` with the joints ``held`` locked at some values: as
    ``get_reduction(arm, "auto")`` (on an arm with a near-structure every plan is checked on the arm, ``plan_check``),
    but the plan chosen for other values of the same joints (the same family, theta*, case and chain) is taken
    when a shorter check at these values finds it (or else its companion, :mod:`sweepik.engine.companion`) sound, the
    other of the two as the companion: a new lock value every pose (a redundant arm's self-motion swept, a path with a
    changing elbow angle) would otherwise check every plan again. ``values``: the held joints' values (a plan
    ``vouch_held_plan`` vouched for at them is taken as ``first_plan`` would find it)."""
    key = (full, held)
    sigs = _HELD_PLANS.get(key, ())
    lazy = _without_near_structure(arm, sigs, _vouched(full, held, arm, values))
    if lazy is not None:
        plan, comp = lazy
    else:
        options = decompose.plans(arm)
        hints = tuple(p for sig in sigs for p in options if sig is not None and _signature(p) == sig)
        plan, _ = decompose.choice(arm, None, hints)
        if plan in hints:  # (the other plan chosen with it, unchecked: a companion only adds solutions)
            comp = next((p for p in hints if p != plan), None)
            if comp is None:  # (none remembered: this value's own choice, or its companion, as a second opinion)
                comp = _own_second(arm, plan)
        else:
            comp = decompose.companion_plan(arm)
    red = _held_reduction(arm, plan, comp)
    if len(_HELD_PLANS) > 256:  # (bounded, as the caches around it)
        _HELD_PLANS.clear()
    _HELD_PLANS[key] = (_signature(plan), None if comp is None else _signature(comp))
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


def first_held_reduction(arm: Robot) -> Reduction | None:
    """``automatic_for_held``'s reduction of ``arm`` (an arm with joints held) at values never held before: its first
    plan without a blind spot, no companion; None where that choice checks every plan (a near-structure, a
    continuum everywhere, no plan). Whatever other values chose (``engine.held_pose`` checks the plan of a joint's
    values with it)."""
    lazy = _without_near_structure(arm, ())
    return None if lazy is None else _held_reduction(arm, lazy[0], None)


def _without_near_structure(
    arm: Robot, sigs: tuple[_Sig | None, ...], vouched: Plan | None = None
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
    mine = _signature(plan)
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
def _held_reduction(arm: Robot, plan: Plan, companion: Plan | None) -> Reduction:
    red = reduction_for(arm, plan)
    red.companion = None if companion is None else reduction_for(arm, companion)
    return red
