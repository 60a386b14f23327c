"""An arm solved with a companion plan, its plans' one calls joined (``engine.joined_pose``): which arms take them,
and the general path's answer bit for bit, as bundled and rewritten at random, held at a joint too."""

from __future__ import annotations

import numpy as np
import pytest
from one_call import answered_as_the_general_path, assert_reproduced, assert_same, configurations, general_path
from rewrites import rewrite

import sweepik
from sweepik import load_robot, solving
from sweepik.engine.joined_pose import JoinedPose


def test_which_arms_join_which_one_calls() -> None:
    """Both plans' one calls where each answers the probes often, settled or from their candidates (the Gen3 lite;
    the Doosan M0609, whose companion's candidates are all due a polish); the first alone where the companion is the
    general method (the I2RT YAM)."""
    lite, doosan, yam = (
        solving._single_pose(load_robot(name), None) for name in ("kinova_gen3_lite", "doosan_m0609", "i2rt_yam")
    )
    assert isinstance(lite, JoinedPose) and lite.second is not None
    assert isinstance(doosan, JoinedPose) and doosan.second is not None
    assert isinstance(yam, JoinedPose) and yam.second is None


@pytest.mark.parametrize("name", ["kinova_gen3_lite", "doosan_m0609", "i2rt_yam"])
@pytest.mark.parametrize("seed", [0, 1])
def test_an_arm_with_a_companion_joins_the_one_calls_as_the_general_path(
    name: str, seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """An arm solved with a companion plan (``engine.joined_pose``), as bundled and rewritten at random: each pose's
    solutions are the general path's bit for bit, limits on and off, most poses answered by the one calls; every
    solution reproduces the pose and the generating configuration is among them."""
    robot = load_robot(name)
    rng = np.random.default_rng(seed)
    if seed:
        robot = rewrite(robot, rng).robot
    q = configurations(robot, rng, 8)
    assert answered_as_the_general_path(monkeypatch, robot, q) >= len(q)


def test_a_held_arm_with_a_companion_joins_the_one_calls_as_the_general_path(monkeypatch: pytest.MonkeyPatch) -> None:
    """The Gen3 held at joint 3 (a fixed value), where its two plans' calls do not take the value (``HeldJoined``,
    left out here): its held arm is solved with a companion, both one calls joined once the value is asked for again
    (not at a value asked for once: building them costs more than the general way); the general path's solutions
    bit for bit, full length."""
    robot = load_robot("kinova_gen3")
    locked = {"joint_3": 0.7}
    monkeypatch.setattr(solving, "_HELD_ASKED", {})  # (whatever other tests asked before)
    monkeypatch.setattr(solving, "_held_joined", lambda robot, k: None)
    assert solving._single_pose(robot, locked) is None
    assert isinstance(solving._single_pose(robot, locked), JoinedPose)
    rng = np.random.default_rng(5)
    q = configurations(robot, rng, 8)
    q[:, 2] = 0.7
    assert answered_as_the_general_path(monkeypatch, robot, q, locked) >= len(q)


def test_a_turned_lock_whose_reference_has_a_companion_joins_at_once(monkeypatch: pytest.MonkeyPatch) -> None:
    """The Gen3's first joint held (a turned lock: every value solved by the held arm at one reference value,
    ``engine.turned_lock``): its reference held arm has a companion, and every value asks for it, so its one calls
    are joined at the first value asked for; the general path's solutions bit for bit at new values."""
    robot = load_robot("kinova_gen3")
    monkeypatch.setattr(solving, "_HELD_ASKED", {})
    solving._reference_pose.cache_clear()
    rng = np.random.default_rng(9)
    q = configurations(robot, rng, 6)
    for qq, T in zip(q, robot.fk(q), strict=True):
        locked = {"joint_1": float(qq[0])}
        fast = solving._single_pose(robot, locked)
        assert isinstance(fast, solving.TurnedAt) and isinstance(fast.fast, JoinedPose)
        for limits in (True, False):
            sol = sweepik.solve(robot, T, limits=limits, locked=locked)
            assert_same(sol, general_path(monkeypatch, robot, T, limits=limits, locked=locked))
        assert_reproduced(robot, sweepik.solve(robot, T, limits=False, locked=locked), T, qq)
