"""Checking a decomposition on the arm itself before using it: every plan must find configurations it is handed.

A plan is exact for an arm when the arm has its structure (``structure.PARALLEL_TOL``, ``INTERSECT_TOL_REL``), but an
exact plan can still be useless in floating point. Vendors' descriptions are rounded: axes parallel to 1e-6 rad, a
wrist centre 25 um off an axis, two axes "meeting" 40 km away. A plan that sweeps across such a near-structure has a
residual whose branch domains shrink to 1e-4 rad or whose roots come in pairs 1e-5 rad apart, and the sweep misses
them: the Doosan M0609 swept on joint 1 found 0 of 8 solutions on 5 poses in 20 while the same arm swept on joint 4
found all (issue 35). (Much of that was the sweep's, not the plan's: a domain edge's sample a rounding step outside
its domain left the stretch beside it unsearched; with edges moved inside, ``search.inside_zeros``, the joint-1 sweep
recovers all 64 of the check, and the M0609 is solved by both sweeps, one the other's companion: ~2 times the time.)

So where an arm has a near-structure (``structure.near_structure``: a relation that holds to ``NEAR_TOL`` but not
exactly), the automatic decomposition checks every plan it could choose on ``N_CHECK`` configurations drawn once per
arm (a fixed seed: the choice is reproducible): ``FK(q)`` solved with the plan, limits off, must give ``q`` back
(``recovered``); the plan that recovers most, then returns most solutions, is chosen (ties: the better ranked). The
check costs a few milliseconds per plan, once per arm (cached by value), and the compilation of each plan's kernels
the first time. An arm without a near-structure takes the ranking's first plan unchecked.

``checked_choice`` is what :func:`sweepik.reductions.get_reduction` calls for ``"auto"`` (registered when
:mod:`sweepik` is imported: the check solves, and the solver lives above the reductions).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from sweepik.engine.chunk import counting_stepwise
from sweepik.errors import SearchOverflowError
from sweepik.model.robot import Robot
from sweepik.reductions import Plan, reduction_for, set_plan_check
from sweepik.reductions.decompose import cheapest
from sweepik.solving import solve_many

__all__ = ["N_CHECK", "N_QUICK", "RECOVER_TOL", "PlanCheck", "check_plan", "checked_choice"]

#: Configurations each plan is checked on. A near-structure loses solutions on many poses (Doosan M1013 swept on joint
#: 1: 96 of 200 with one plan, 40 of 200 with another, 1 of 200 with a third, 0 with a fourth).
N_CHECK = 64
#: Configurations a suggested plan (``checked_choice``'s ``hints``: the plans chosen at other lock values) is
#: checked on.
N_QUICK = 16
#: A configuration is recovered when a solution (or a family member) lies this close to it: radians for revolute
#: joints, times the arm's length scale for prismatic ones (the certified solutions are ~1e-12 off).
RECOVER_TOL = 1e-6
_SEED = 35


@dataclass(frozen=True)
class PlanCheck:
    """How a plan did on the check's configurations: ``recovered`` of ``checked``, and the ``solutions`` (certified,
    distinct) and ``families`` it returned for them in all."""

    plan: Plan
    recovered: int
    checked: int
    solutions: int
    families: int
    #: Configurations whose candidates needed Newton steps (``chunk.counting_stepwise``; the general method polishes
    #: every root inside its elimination: all of them): what a plan costs beyond its sweep (``decompose.cheapest``).
    polished: int = 0

    @property
    def score(self) -> tuple[int, int]:
        """What the choice maximises: configurations recovered, then solutions found (every solution certified,
        so a plan that returns more has missed fewer: on the Doosan M1013 two plans recover all 64 configurations
        but one returns 509 solutions, the other 512)."""
        return self.recovered, self.solutions + self.families

    @property
    def passed(self) -> bool:
        return self.recovered == self.checked


def check_configurations(robot: Robot, n: int = N_CHECK) -> np.ndarray:
    """``(n, 6)`` configurations for the check: revolute joints uniform over one turn, slides over their limits
    (or +- the length scale where a limit is infinite). Fixed seed."""
    rng = np.random.default_rng(_SEED)
    lo = np.where(np.isfinite(robot.lower), robot.lower, -robot.length_scale)
    hi = np.where(np.isfinite(robot.upper), robot.upper, robot.length_scale)
    return np.where(
        robot.is_revolute, rng.uniform(-np.pi, np.pi, (n, robot.n_joints)), rng.uniform(lo, hi, (n, robot.n_joints))
    )


@lru_cache(maxsize=256)
def check_plan(robot: Robot, plan: Plan, n: int = N_CHECK) -> PlanCheck:
    """Solve ``FK(q)`` with ``plan`` (limits off) for ``n`` configurations of the check and count those given back
    (none where the plan's search overflows on one of them: ``SearchOverflowError``)."""
    Q = check_configurations(robot, n)
    try:
        with counting_stepwise() as stepwise:
            batch = solve_many(robot, robot.fk(Q), reduction=reduction_for(robot, plan), limits=False)
    except SearchOverflowError:  # (a pose it cannot answer: none counted as given back)
        return PlanCheck(plan, 0, len(Q), 0, 0, len(Q))
    polished = len(Q) if plan.family == "general" else stepwise[0]
    found = 0
    n_solutions = sum(len(s) for s in batch)
    n_families = sum(len(s.families) for s in batch)
    for sols, q in zip(batch, Q, strict=True):
        if not (len(sols) or sols.families):
            continue
        d = sols.nearest(q) - q
        d = np.where(robot.is_revolute, np.angle(np.exp(1j * d)), d / robot.length_scale)
        found += bool(np.max(np.abs(d)) < RECOVER_TOL)
    return PlanCheck(plan, found, len(Q), n_solutions, n_families, polished)


def checked_choice(
    robot: Robot, options: tuple[Plan, ...], hints: tuple[Plan, ...] = (), hints_only: bool = False
) -> tuple[Plan, tuple[PlanCheck, ...]] | None:
    """The plan of ``options`` (best ranked first) with the best ``PlanCheck.score`` (ties: ``decompose.cheapest``),
    with every plan's check (in the order of ``options``). The first of ``hints`` (plans of ``options``) that gives back
    all of ``N_QUICK`` configurations is taken instead, with the quick checks made; ``hints_only``: None where none
    does (the caller then adds options of its own and asks again)."""
    quick: list[PlanCheck] = []
    for hint in hints:
        quick.append(check_plan(robot, hint, N_QUICK))
        if quick[-1].passed:
            return hint, tuple(quick)
    if hints_only:
        return None
    checks = tuple(check_plan(robot, plan) for plan in options)
    top = max(c.score for c in checks)
    return cheapest([c for c in checks if c.score == top]).plan, checks


set_plan_check(checked_choice)
