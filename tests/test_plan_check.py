"""The choice of a decomposition on arms with a near-structure (issue 35): rounded vendor descriptions.

An arm whose axes are parallel to 1e-6 rad, or miss each other by a micrometre, is a general arm there: a plan that
takes the structure as exact would move the solutions by ~1e-6 of the arm's size, and a plan that is exact but sweeps
across the near-structure can lose solutions (its branch domains shrink to ~1e-4 rad, its roots come in close pairs).
The tolerance (``structure.PARALLEL_TOL``, ``INTERSECT_TOL_REL``: 1e-9) separates the two sides; between it and
``NEAR_TOL`` (1e-3) every plan is checked on the arm and the best one chosen (``plan_check``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from oracles import recovers
from rewrites import rotation

import sweepik
from sweepik import SearchOverflowError, load_robot, plan_check, solve
from sweepik.io.robot_file import bundled_robots
from sweepik.model.origin_axis import origin_axis_form
from sweepik.model.structure import NEAR_TOL, PARALLEL_TOL, near_structure
from sweepik.plan_check import N_CHECK, PlanCheck, check_plan
from sweepik.reductions import decompose


def _tilted(name: str, joint: int, angle: float) -> sweepik.Robot:
    """Bundled arm ``name`` with ``joint``'s axis tilted by ``angle`` (rad) about a direction across it, through the
    same point (the rest of the arm as it was)."""
    robot = origin_axis_form(load_robot(name))
    js = list(robot.joints)
    a = np.array(js[joint].axis)
    across = np.cross(a, [0.3, 0.5, 0.8])
    js[joint] = replace(js[joint], axis=tuple(float(v) for v in rotation(across, angle) @ a))
    return replace(robot, joints=tuple(js), name=f"{name}_tilted")


def _recall(robot: sweepik.Robot, n: int, seed: int) -> int:
    rng = np.random.default_rng(seed)
    Q = rng.uniform(-np.pi, np.pi, (n, 6))
    found = 0
    for q in Q:
        s = solve(robot, robot.fk(q), limits=False)
        assert (s.error_geodesic <= 1e-9 * robot.length_scale).all()
        found += recovers(robot, s, q)
    return found


@pytest.mark.parametrize("angle", [1e-12, 1e-10])
def test_below_the_tolerance_a_structure_is_exact(angle: float) -> None:
    """UR5 with joint 3's axis 1e-12 / 1e-10 rad off parallel: the parallel closed form, every configuration back."""
    robot = _tilted("ur5", 2, angle)
    assert angle < PARALLEL_TOL and not near_structure(robot.chain, robot.length_scale)
    assert sweepik.analyze(robot)["chosen"]["family"] == "parallel"
    assert _recall(robot, 8, 1) == 8


@pytest.mark.parametrize("angle", [1e-8, 1e-6, 1e-4])
def test_above_the_tolerance_a_near_structure_is_a_general_arm(angle: float) -> None:
    """The same arm 1e-8 ... 1e-4 rad off: not parallel (a sweep, exact for the arm), the near-structure named, every
    configuration back."""
    robot = _tilted("ur5", 2, angle)
    info = sweepik.analyze(robot)
    assert info["chosen"]["family"] == "pair"
    assert any(t.startswith("2≈∥3") for t in info["near_structure"]) and angle < NEAR_TOL
    assert _recall(robot, 8, 2) == 8


def test_far_from_a_structure_nothing_is_near() -> None:
    robot = _tilted("ur5", 2, 0.05)
    assert not any("∥" in t for t in near_structure(robot.chain, robot.length_scale))
    assert _recall(robot, 4, 3) == 4


@pytest.mark.parametrize("name", [n for n in bundled_robots() if load_robot(n).n_joints == 6])
def test_an_arm_without_near_structure_takes_the_best_ranked_plan_unchecked(name: str) -> None:
    robot = load_robot(name)
    if near_structure(robot.chain, robot.length_scale):
        pytest.skip(f"{name} is written with a near-structure (a vendor's rounded description)")
    plan, checks = decompose.choice(robot)
    assert checks == ()
    options = [p for p in decompose.plans(robot) if not p.conditional] or list(decompose.plans(robot))
    assert plan == options[0]


def test_a_near_structure_plan_is_chosen_by_its_check() -> None:
    """The UR5 1e-6 rad off: every candidate checked; the chosen one has the best score, and it gives back every one of
    the check's configurations."""
    robot = _tilted("ur5", 2, 1e-6)
    plan, checks = decompose.choice(robot)
    assert len(checks) >= 2
    best = next(c for c in checks if c.plan == plan)
    assert best.score == max(c.score for c in checks)
    assert best.recovered == best.checked == N_CHECK
    assert check_plan(robot, plan) == best  # (cached, the same)
    info = sweepik.analyze(robot)
    assert "near-structure" in info["why"] and len(info["checks"]) == len(checks)


def test_an_arm_whose_every_pose_is_a_continuum_is_refused_saying_why() -> None:
    """The iiwa with its elbow (A4) held: a spherical shoulder and a spherical wrist at a fixed distance, so every pose
    leaves a turn about the line through their centres free (held straight, A3 and A5 also turn about one line)."""
    iiwa = load_robot("kuka_iiwa14")
    for value in (0.3, 0.0):
        info = sweepik.analyze(iiwa, locked={"A4": value})
        assert info["chosen"] is None and "every pose is a continuum" in info["reason"]
        with pytest.raises(sweepik.NoReductionError, match="every pose is a continuum"):
            solve(iiwa, iiwa.fk(np.array([0.1, 0.5, -0.3, value, 0.2, -0.4, 0.6])), locked={"A4": value})


def test_nearly_coaxial_axes_are_a_near_structure() -> None:
    """The UR5 with joint 3's axis moved onto joint 2's line, 1e-7 of the arm's size off it: two consecutive axes
    nearly on one line are named ``2≈≡3``, and the arm is refused (every pose nearly a continuum)."""
    robot = origin_axis_form(load_robot("ur5"))
    js = list(robot.joints)
    # joint 3's frame moved onto joint 2's axis line, 1e-7 of the length scale off it
    T = np.array(js[2].origin)
    h = np.array(js[2].axis)
    T[:3, 3] = T[:3, 3] - (T[:3, 3] - np.dot(T[:3, 3], h) * h) + 1e-7 * robot.length_scale * np.cross(h, [1.0, 0, 0])
    js[2] = replace(js[2], origin=tuple(tuple(float(v) for v in row) for row in T))
    arm = replace(robot, joints=tuple(js), name="ur5_coaxial")
    assert any("2≈≡3" in t for t in near_structure(arm.chain, arm.length_scale))
    with pytest.raises(sweepik.NoReductionError, match="continuum"):
        solve(arm, arm.fk(np.zeros(6)))


def test_of_plans_that_check_alike_one_polishing_far_less_is_chosen() -> None:
    """``decompose.cheapest``: the better ranked plan unless another needed Newton steps on at least
    ``FEWER_POLISHED`` of the configurations fewer (a count: the same from run to run and for every writing)."""
    ur5 = decompose.plans(load_robot("ur5"))
    a, b, c = (PlanCheck(p, 64, 64, 512, 0, k) for p, k in zip(ur5[:3], (20, 8, 0), strict=True))
    assert decompose.cheapest([a, b]) is a  # (12 fewer: under a quarter of 64)
    assert decompose.cheapest([a, b, c]) is c
    assert decompose.cheapest([c, a]) is c


def test_a_near_structure_arm_takes_the_plan_that_needs_no_polish() -> None:
    """The Doosan M0609 (bundled; 1≈∩2 to 1.2e-6 of its size): its joint-1 sweep (ranked first), its joint-4 sweep and
    the general method each give back all 64 configurations with as many solutions; the joint-1 sweep polishes every
    one, the joint-4 sweep none, so the joint-4 sweep is chosen and the joint-1 sweep is its companion."""
    robot = load_robot("doosan_m0609")
    plan, checks = decompose.choice(robot)
    assert (plan.free_joint, plan.case) == (3, "bc_par")
    best = next(c for c in checks if c.plan == plan)
    first = next(c for c in checks if c.score == best.score)
    assert first.plan != plan and first.polished - best.polished >= decompose.FEWER_POLISHED * N_CHECK
    companion = decompose.companion_plan(robot)
    assert companion is not None and companion.free_joint == 0
    assert "Newton steps on the fewest" in sweepik.analyze(robot)["why"]


def test_a_plan_whose_search_overflows_fails_its_check(monkeypatch: pytest.MonkeyPatch) -> None:
    """A plan whose sweep crosses zero more often on a configuration of the check than the search holds
    (``SearchOverflowError``: a Kinova Gen3 rewritten at random, held at joint 3 at -pi, raised ``RuntimeError``
    from the automatic choice) gives back none of them: the choice takes another plan."""
    robot = load_robot("puma560")
    plan = next(p for p in decompose.plans(robot) if not p.closed_form)
    check_plan.cache_clear()

    def overflows(*args: object, **kwargs: object) -> None:
        raise SearchOverflowError("the search of 'x' found more than 1 candidates")

    monkeypatch.setattr(plan_check, "solve_many", overflows)
    check = check_plan(robot, plan, 8)
    check_plan.cache_clear()
    assert (check.recovered, check.checked, check.passed) == (0, 8, False)


def test_the_search_says_when_it_overflows(monkeypatch: pytest.MonkeyPatch) -> None:
    """Buffers too small for a pose even when grown: a ``SearchOverflowError`` (a ``SweepikError``) naming the
    search (here its margins'), not a bare ``RuntimeError``."""
    from sweepik.engine import chunk, search

    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, None)
    chain = chunk.chain_poses(robot, robot.fk(np.random.default_rng(2).uniform(robot.lower, robot.upper, (3, 6))))
    lo, hi = chunk.theta_range(robot, red, chain)
    monkeypatch.setattr(search, "MAX_CAND", 1)
    monkeypatch.setattr(search, "REDO_MAX_CAND", 1)
    with pytest.raises(SearchOverflowError, match="the search of 'margins' found more than 1 candidates"):
        search.search(red, chain, lo, hi, 64)
    assert issubclass(SearchOverflowError, sweepik.SweepikError)
