"""The lock values at which a held arm is not the arm of other values (``engine.lock_windows``).

Properties: outside the windows (random values, and values a grid step past each window's edges) the held arm has
no near-structure and the structure of every other value; inside, at its centre, it has one or the other; the
windows of an arm rewritten (zeros moved, axes reversed, frames) are the original's mapped; the held chain built
from the value is the held arm's; ``in_windows`` takes a value in any turn; ``window_reference`` is one value of
the window, the same for every value in it.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from rewrites import rewrite

from sweepik import load_robot, solving
from sweepik.engine.lock_windows import GRID_STEP, in_windows, window_reference
from sweepik.model.origin_axis import hold_joints
from sweepik.model.structure import near_structure, structure_of

HELD = [("kuka_iiwa14", 2), ("kuka_iiwa14", 1), ("franka_panda", 0), ("franka_panda", 3), ("kinova_gen3", 4)]


def _relations(chain, scale):  # type: ignore[no-untyped-def]
    st = structure_of(chain, scale)
    return st.pairs, st.parallel, st.spherical


@pytest.mark.parametrize(("name", "k"), HELD)
def test_outside_the_windows_the_held_arm_is_the_arm_of_every_value(name: str, k: int) -> None:
    robot = load_robot(name)
    fast = solving._held_pose(robot, k)
    assert fast is not None
    scale = robot.length_scale
    generic = _relations(fast.chain_at(0.4321), scale)
    rng = np.random.default_rng(k)
    edges = np.concatenate([fast.windows[:, 0] - GRID_STEP, fast.windows[:, 1] + GRID_STEP])
    values = np.concatenate([rng.uniform(-math.pi, math.pi, 300), edges[np.isfinite(edges)]])
    outside = 0
    for v in values:
        if in_windows(float(v), fast.windows):
            continue
        outside += 1
        chain = fast.chain_at(float(v))
        assert near_structure(chain, scale) == ()
        assert _relations(chain, scale) == generic
    assert outside > 250
    for lo, hi in fast.windows:  # (inside: a near-structure or another structure at the centre)
        c = float(np.clip(0.5 * (lo + hi), -math.pi, math.pi)) if np.isfinite(lo + hi) else math.pi
        chain = fast.chain_at(c)
        assert near_structure(chain, scale) or _relations(chain, scale) != generic or hi - lo < 1e-5


@pytest.mark.parametrize(("name", "k"), HELD[:3])
def test_the_held_chain_is_the_held_arms(name: str, k: int) -> None:
    robot = load_robot(name)
    fast = solving._held_pose(robot, k)
    assert fast is not None
    for v in np.random.default_rng(0).uniform(robot.lower[k], robot.upper[k], 5):
        mine, theirs = fast.chain_at(float(v)), hold_joints(robot, {k: float(v)}).arm.chain
        for a, b in ((mine.H, theirs.H), (mine.P, theirs.P), (mine.R_end, theirs.R_end)):
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-14 * max(1.0, robot.length_scale))
        assert np.array_equal(mine.revolute, theirs.revolute)


@pytest.mark.parametrize("seed", [1, 2, 5])
def test_windows_of_an_arm_written_otherwise_are_the_originals_mapped(seed: int) -> None:
    """iiwa A3 held: special at 0 and pi (A2 and A4 parallel); on the arm rewritten, at the images of 0 and pi."""
    original = load_robot("kuka_iiwa14")
    rw = rewrite(original, np.random.default_rng(seed))
    fast, mine = solving._held_pose(rw.robot, 2), solving._held_pose(original, 2)
    assert fast is not None and mine is not None
    for v in np.r_[np.linspace(-3.1, 3.1, 200), 0.0, math.pi, -math.pi, 1e-3, -1e-3, 2e-3]:
        q = np.zeros(7)
        q[2] = v
        image = float(rw.forward(q)[2])
        near_edge = np.any(np.abs(np.abs(v) - np.abs(mine.windows[np.isfinite(mine.windows)])) < 2 * GRID_STEP)
        if not near_edge:
            assert in_windows(image, fast.windows) == in_windows(float(v), mine.windows), v


def test_in_windows_takes_any_turn() -> None:
    fast = solving._held_pose(load_robot("kuka_iiwa14"), 2)
    assert fast is not None
    for v, inside in [(0.0, True), (2 * math.pi, True), (-2 * math.pi + 5e-4, True), (math.pi, True), (-math.pi, True)]:
        assert in_windows(v, fast.windows) is inside
    for v in (0.01, 1.0, -2.0, 3.1, 2 * math.pi + 0.01):
        assert not in_windows(v, fast.windows)
    assert not in_windows(0.0, np.zeros((0, 2)))


def test_a_window_has_one_reference_value() -> None:
    """Every value of a window (any turn; the window round +-pi is one) names the same reference value, which lies
    in that window off its middle; values outside every window name none."""
    fast = solving._held_pose(load_robot("franka_panda"), 5)
    assert fast is not None
    w = fast.windows
    assert w[0, 0] == -math.inf and w[-1, 1] == math.inf  # (a window round +-pi)
    rng = np.random.default_rng(3)
    refs = set()
    for lo, hi in w:
        a, b = (w[-1, 0], w[0, 1] + 2 * math.pi) if lo == -math.inf or hi == math.inf else (lo, hi)
        values = np.r_[a + 1e-3 * (b - a), b - 1e-3 * (b - a), rng.uniform(a, b, 6)]
        found = {window_reference(float(v) + t, w) for v in values for t in (0.0, 2 * math.pi, -4 * math.pi)}
        assert len(found) == 1
        ref = found.pop()
        assert ref is not None and in_windows(ref, w)
        assert abs(math.remainder(ref - 0.5 * (a + b), 2 * math.pi)) > 0.1 * (b - a)
        refs.add(ref)
    assert len(refs) == w.shape[0] - 1  # (the window round +-pi counted once)
    for v in (0.01, 1.0, 3.0, -3.0 + 2 * math.pi):
        assert not in_windows(v, w) and window_reference(v, w) is None
    assert window_reference(0.0, np.zeros((0, 2))) is None


@pytest.mark.parametrize("k", [1, 3, 5])
def test_a_near_structure_at_every_value_is_the_same_outside_the_windows(
    k: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """The Gen3 held at joint 2, 4 or 6: a nearly spherical wrist at every value (``engine.held_joined``). Outside
    the windows the held arm has the near-structure of the reference value, of the same size, and its structure;
    the windows are few and narrow. At joint 6 the held joint's neighbours nearly meet at every value by one
    distance (``SAME_DISTANCE_REL``): the grid's values are not each checked in Python (25,000, ~10 s)."""
    from sweepik.engine import lock_windows
    from sweepik.engine.held_joined import HeldJoined
    from sweepik.reductions import held_pair

    robot = load_robot("kinova_gen3")
    checked = []
    real = lock_windows.near_structure

    def counted(*args, **kwargs):  # type: ignore[no-untyped-def]
        checked.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(lock_windows, "near_structure", counted)
    fast = HeldJoined.of(robot, k, held_pair)
    assert fast is not None and len(checked) < 2000
    scale = robot.length_scale
    reference = fast.first.chain_at(0.4321)
    nearly, generic = near_structure(reference, scale), _relations(reference, scale)
    assert nearly  # (a near-structure at every value)
    assert np.sum(np.minimum(fast.windows[:, 1], math.pi) - np.maximum(fast.windows[:, 0], -math.pi)) < 0.01
    rng = np.random.default_rng(k)
    edges = np.concatenate([fast.windows[:, 0] - GRID_STEP, fast.windows[:, 1] + GRID_STEP])
    for v in np.concatenate([rng.uniform(-math.pi, math.pi, 200), edges[np.isfinite(edges)]]):
        if in_windows(float(v), fast.windows):
            continue
        chain = fast.first.chain_at(float(v))
        assert near_structure(chain, scale) == nearly
        assert _relations(chain, scale) == generic
