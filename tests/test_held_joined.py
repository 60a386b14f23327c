"""A seven-joint arm held at a middle joint whose held arm has a near-structure: its plan's and companion's calls
take the lock value (``engine.held_joined``).

Properties, on the Kinova Gen3 held at joints 2, 4 and 6 (and at joint 4 rewritten at random): at random values
outside the windows the calls answer (most poses) with the held arm's own solutions, solved the general way with the
same two plans, to rounding; every solution reaches the pose and the configuration it was made from is recovered
(random, the wrist straight, the elbow at 0); a pose due a polish is resumed on the held arm at its value;
``solve_many`` with a value per pose gives ``solve``'s answers bit for bit; the general way at a new value takes the
pair without checking a plan; a value in the windows goes the general way; the first and last joints are left to the
turned lock.
"""

from __future__ import annotations

import numpy as np
import pytest
from one_call import assert_same, fk_ok, held_general, same_to_rounding
from oracles import in_limit_configurations, recovers
from rewrites import rewrite

import sweepik
from sweepik import load_robot, solving
from sweepik.engine import held_joined
from sweepik.engine.held_joined import HeldJoined
from sweepik.engine.held_pose import SPECIAL, HeldPose
from sweepik.model.origin_axis import hold_joints
from sweepik.reductions import decompose, held_pair

GEN3 = "kinova_gen3"


def _configurations(robot: sweepik.Robot, k: int, seed: int, n: int = 12) -> np.ndarray:
    """Random configurations in the limits, a quarter with the wrist straight (joint 6 at 0) and a quarter with the
    elbow straight (joint 4 at 0), where those joints are not the one held (``k``)."""
    q = in_limit_configurations(robot, n, np.random.default_rng(seed))
    for j, rows in ((5, slice(0, n // 4)), (3, slice(n // 4, n // 2))):
        if j != k:
            q[rows, j] = 0.0
    return q


@pytest.mark.parametrize(
    ("joint", "rewritten"), [("joint_2", False), ("joint_4", False), ("joint_6", False), ("joint_4", True)]
)
def test_the_calls_answer_as_the_held_arm_at_each_value(
    joint: str, rewritten: bool, monkeypatch: pytest.MonkeyPatch
) -> None:  # fmt: skip
    """Random values and poses: the joined calls answer most poses, with the held arm's own solutions (the general
    way at that value, the same two plans) to rounding; poses due a polish are among them, resumed on the held arm."""
    robot = load_robot(GEN3)
    if rewritten:
        robot = rewrite(robot, np.random.default_rng(3)).robot
    k = robot.joint_names.index(joint)
    fast = solving._held_joined(robot, k)
    assert isinstance(fast, HeldJoined)
    resumed = []

    def counted(*args: object) -> sweepik.results.Block:
        resumed.append(1)
        return real(*args)  # type: ignore[arg-type]

    real = held_joined.resumed
    monkeypatch.setattr(held_joined, "resumed", counted)
    q = _configurations(robot, k, 7 + k)
    answered = 0
    for qq, T in zip(q, robot.fk(q), strict=True):
        v = float(qq[k])
        status, sol = fast.solve(np.ascontiguousarray(T), v, True)
        general = held_general(robot, T, k, v)
        fk_ok(robot, general, T)
        assert recovers(robot, sweepik.solve(robot, T, locked={k: v}, limits=False), qq)
        if sol is None:
            continue
        answered += 1
        same_to_rounding(sol, general, robot)
        fk_ok(robot, sol, T)
        assert np.all(sol.q[:, k] == v) and recovers(robot, sol, qq)
    assert answered >= 8
    assert resumed  # (the companion's sweep leaves a candidate due a polish on most poses at joints 2 and 6)


def test_solve_many_with_a_value_per_pose_is_solve() -> None:
    """``solve_many`` with one lock value per pose answers as ``solve`` pose by pose, bit for bit."""
    robot = load_robot(GEN3)
    q = _configurations(robot, 3, 11, 10)
    T = robot.fk(q)
    batch = sweepik.solve_many(robot, T, locked={"joint_4": q[:, 3]})
    for i in range(len(q)):
        assert_same(batch[i], sweepik.solve(robot, T[i], locked={"joint_4": float(q[i, 3])}))


def test_the_general_way_takes_the_pair_unchecked(monkeypatch: pytest.MonkeyPatch) -> None:
    """Once the pair is chosen, the held arm at a new value (outside the windows) is solved by those two plans
    without any plan checked (``reductions.vouch_held_plan``), and the short check at that value passes them."""
    robot = load_robot(GEN3)
    fast = solving._held_joined(robot, 1)
    assert fast is not None
    for v in (0.3141, -1.2718):
        held = hold_joints(robot, {1: v})
        assert held_pair(held.arm, fast.pair) is not None  # (the short check passes them there)
        with monkeypatch.context() as m:
            m.setattr(decompose, "_plan_check", _no_check)
            red = solving._default_reduction(held.arm, held)
        comp = red.companion
        assert comp is not None
        got = tuple((p.family, p.reversed, p.free, p.case) for p in (red.plan, comp.plan))  # type: ignore[attr-defined]
        assert got == fast.pair


def _no_check(*args: object, **kwargs: object) -> None:
    raise AssertionError("a plan was checked")


def test_a_value_in_the_windows_goes_the_general_way() -> None:
    """Next to the straight elbow (joint 4 near 0: axes 3 and 5 nearly on one line) the held arm is another arm:
    the calls hand the pose on (``SPECIAL``) and the general way answers it, certified."""
    robot = load_robot(GEN3)
    fast = solving._held_joined(robot, 3)
    assert fast is not None
    inside = [w for w in fast.windows if np.all(np.isfinite(w)) and w[0] < 0.0 < w[1]]
    assert len(inside) == 1 and inside[0][1] - inside[0][0] < 0.01
    q = _configurations(robot, 3, 5, 4)
    q[:, 3] = 0.5 * inside[0][1]
    for qq, T in zip(q, robot.fk(q), strict=True):
        assert fast.joined(np.ascontiguousarray(T), float(qq[3]), True) == SPECIAL
        sol = sweepik.solve(robot, T, locked={"joint_4": float(qq[3])}, limits=False)
        fk_ok(robot, sol, T)
        assert recovers(robot, sol, qq)


def test_the_first_and_last_joints_are_left_to_the_turned_lock() -> None:
    """The Gen3's first joint held (a near-structure too) is solved by turning the held arm at one reference value
    (``engine.turned_lock``), not by this module; so would its last be, were it not one sweep at every value
    (``HeldPose``)."""
    robot = load_robot(GEN3)
    assert isinstance(solving._single_pose(robot, {0: 0.4321}), solving.TurnedAt)
    assert isinstance(solving._single_pose(robot, {6: 0.4321}).held, HeldPose)  # type: ignore[union-attr]
    for k in (0, 6):
        assert HeldJoined.of(robot, k, held_pair) is None


def test_a_value_in_the_windows_does_not_depend_on_what_was_solved_before(monkeypatch: pytest.MonkeyPatch) -> None:
    """At a value in the windows the general way's hints are the pair chosen once, not the plans remembered from the
    values solved before (``reductions._HELD_PLANS``): the same solutions whatever those were (an audit found
    ``solve_many`` and ``solve`` apart by 3.7e-6 at such a value, after 64 poses solved at another)."""
    from sweepik import reductions

    robot = load_robot(GEN3)
    k = 3
    fast = solving._held_joined(robot, k)
    assert fast is not None
    q = _configurations(robot, k, 21, 3)
    q[:, k] = 0.5 * fast.windows[1][1]
    swapped = (fast.pair[1], fast.pair[0])
    answers = []
    for remembered in (fast.pair, swapped, ()):
        monkeypatch.setitem(reductions._HELD_PLANS, (robot, (k,)), remembered)
        solving._default_reduction.cache_clear()
        answers.append(
            [sweepik.solve(robot, T, locked={k: float(qq[k])}) for qq, T in zip(q, robot.fk(q), strict=True)]
        )
    for other in answers[1:]:
        for a, b in zip(answers[0], other, strict=True):
            assert_same(a, b)
