"""Two continua that cross (issue 35, point 5): a spherical-wrist arm with its wrist centre on axis 1 (a continuum along
joint 1) and its wrist straight (A5 = 0: the wrist's own circle, A4 and A6 turning against each other) holds both, and
they meet in one configuration. Configurations on the wrist circle away from the meeting point must come back as
solutions or family members, and every member of every family must solve the pose."""

from __future__ import annotations

import zlib

import numpy as np
import pytest
from scipy.optimize import brentq
from singular import families_certified, recovered

import sweepik
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.units import orientation_weight


def _shoulder_singular(robot: sweepik.Robot, rng: np.random.Generator) -> np.ndarray:
    """A configuration with det J = 0 along joint 2 (with A5 away from 0 the only factor that joint 2 moves: the
    shoulder's, where the wrist centre lies on axis 1), then A5 = 0."""
    while True:
        q = rng.uniform(-np.pi, np.pi, 6)
        q[4] = rng.choice([-1.0, 1.0]) * rng.uniform(0.3, 2.8)
        xs = np.linspace(-np.pi, np.pi, 721)
        Q = np.repeat(q[None], xs.size, axis=0)
        Q[:, 1] = xs
        det = np.linalg.det(robot.jacobian(Q))
        idx = np.flatnonzero(np.sign(det[:-1]) * np.sign(det[1:]) < 0)
        if idx.size:
            break
    i = int(rng.choice(idx))

    def f(x: float) -> float:
        qq = q.copy()
        qq[1] = x
        return float(np.linalg.det(robot.jacobian(qq)))

    q[1] = brentq(f, xs[i], xs[i + 1], xtol=1e-15)
    q[4] = 0.0
    return q


def _on_wrist_circle(robot: sweepik.Robot, q: np.ndarray, t: float) -> np.ndarray:
    """``q`` with A4 moved by ``t`` and A6 by -t or +t, whichever keeps the pose (axes 4 and 6 aligned at A5 = 0)."""
    T = robot.fk(q)
    best = None
    for sign in (-1.0, 1.0):
        c = q.copy()
        c[3] += t
        c[5] += sign * t
        e = float(np.max(np.abs(robot.fk(c) - T)))
        if best is None or e < best[0]:
            best = (e, c)
    assert best is not None and best[0] < 1e-9 * robot.length_scale, "not a wrist circle"
    return best[1]


@pytest.mark.parametrize("name", ["kuka_kr6_r900", "abb_irb140"])
def test_the_wrist_circle_crossing_a_joint_1_continuum_comes_back(name: str) -> None:
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    w = orientation_weight(robot.length_unit)
    for _ in range(3):
        q = _shoulder_singular(robot, rng)
        T = robot.fk(q)
        s = sweepik.solve(robot, T, limits=False)
        assert s.families, "no continuum reported"
        for t in (0.4, -1.1, 2.0):
            assert recovered(robot, s, _on_wrist_circle(robot, q, t)), (name, q.tolist(), t)
        for f in s.families:
            m = f.at(np.linspace(f.interval[0], f.interval[1], 7))
            err = pose_error_geodesic(robot.fk(m), np.broadcast_to(T, (len(m), 4, 4)), w)
            assert np.all(err <= 1e-9 * robot.length_scale), (name, q.tolist(), f)


def test_the_issue_reproducers_wrist_circle() -> None:
    """The KR 6 and IRB 140 configurations of issue 35 (wrist centre on axis 1, A5 = 0): 0 solutions and the joint-1
    families only, the wrist circle through them missing."""
    cases = {
        "kuka_kr6_r900": [-0.449947703404042, -0.6365112470698561, -2.038806599570209, -1.6754080220239238, 0.0,
                          -2.6548778051440474],
        "abb_irb140": [-2.633936123427877, -1.1638693734790628, 0.3487714784042786, -2.47670646646433, 0.0,
                       -3.027679808844194],
    }  # fmt: skip
    for name, q in cases.items():
        robot = sweepik.load_robot(name)
        q = np.array(q)
        s = sweepik.solve(robot, robot.fk(q), limits=False)
        assert recovered(robot, s, q), name


def test_vertex_least_reaches_a_vertex_and_settles_a_rounded_one() -> None:
    """``vertex_least`` on V-shaped functions: a V reaching zero is found below zero in a few steps; a V rounded off
    above zero (two families that only nearly meet) is settled above zero, as the golden section settled it."""
    from sweepik.engine.crossings import vertex_least

    calls = []

    def v_shape(x: np.ndarray) -> np.ndarray:
        calls.append(x.size)
        return np.abs(x - np.array([0.3137, -0.71])[: x.size]) * np.array([2.0, 0.5])[: x.size] - 1e-7

    a, m, b = np.array([0.25, -0.8]), np.array([0.3, -0.7]), np.array([0.35, -0.6])
    x, e = vertex_least(v_shape, a, m, b, v_shape(a), v_shape(m), v_shape(b))
    assert np.all(e <= 0.0) and np.allclose(x, [0.3137, -0.71], atol=1e-6)
    assert len(calls) - 3 <= 6

    def rounded(x: np.ndarray) -> np.ndarray:
        return np.sqrt((2.0 * (x - 0.3137)) ** 2 + 1e-10) - 1e-7

    a, m, b = np.array([0.25]), np.array([0.3]), np.array([0.35])
    x, e = vertex_least(rounded, a, m, b, rounded(a), rounded(m), rounded(b))
    assert e[0] > 0.0 and abs(x[0] - 0.3137) < 1e-3


def test_the_compiled_second_singular_value_is_lapacks() -> None:
    """``continuation.second_singular`` (Jacobi rotations, warm along a family's members) against NumPy's SVD of the
    same scaled Jacobians (``scaled_singular``): on KR 6 configurations at random and along its wrist circle (a
    family: the least singular value zero), 1e-10 relative to the largest."""
    from sweepik.engine.continuation import scaled_singular, second_singular

    robot = sweepik.load_robot("kuka_kr6_r900")
    rng = np.random.default_rng(2)
    q = rng.uniform(robot.lower, robot.upper, (40, 6))
    circle = np.repeat(q[:1], 30, axis=0)
    circle[:, 4] = 0.0
    circle[:, 3] += np.linspace(0.0, 1.0, 30)
    circle[:, 5] -= np.linspace(0.0, 1.0, 30)
    for Q, cold in ((q, np.ones(len(q), dtype=bool)), (circle, np.arange(len(circle)) == 0)):
        s, _ = scaled_singular(robot, Q)
        np.testing.assert_allclose(second_singular(robot, Q, cold), s[:, -2] / s[:, 0], rtol=0, atol=1e-10)


def test_the_batch_grids_are_each_familys_own() -> None:
    """``crossings.crossing_grids`` over the families of many poses at once (members of one reduction's families in
    one call, the singular values in one call) gives each family the values of its own probe (``_second_singular``
    on its grid), bit for bit, or None where they hold no dip to search: C-Arm grid poses with families (swept
    ones) and KR 6 poses whose wrist centre lies on axis 1 (traced continua as well)."""
    from sweepik.engine.crossings import _dips, _grid, _second_singular, crossing_grids
    from sweepik.experiments.bench import grid_configurations

    cases = []
    carm = sweepik.load_robot("carm")
    q = grid_configurations(include_singular=False)[::7][:600]
    cases.append((carm, [f for s in sweepik.solve_many(carm, carm.fk(q)) for f in s.families]))
    kr6 = sweepik.load_robot("kuka_kr6_r900")
    rng = np.random.default_rng(11)
    poses = [kr6.fk(_shoulder_singular(kr6, rng)) for _ in range(3)]
    cases.append((kr6, [f for T in poses for f in sweepik.solve(kr6, T).families]))
    for robot, fams in cases:
        assert len(fams) >= 3
        grids = crossing_grids(robot, fams)
        for f, g in zip(fams, grids, strict=True):
            if not f.interval[1] > f.interval[0]:
                assert g is None
                continue
            own = _second_singular(robot, f, _grid(f))
            if g is None:  # (no dip to search, or the screen shows no crossing: left out)
                assert not _dips(own[None]).any() or not _full_grid_seeds(robot, f)
            else:
                np.testing.assert_array_equal(g, own)


def test_continua_crossing_where_a_member_is_at_pi_are_found() -> None:
    """The Stanford arm at q2 = -90 deg, d3 = 0, q5 = 0: its two continua along q2 (members with q2 at +-pi) each
    cross a continuum along q4. The direction across a family at a crossing needs the family's tangent, taken
    between members either side of it: modulo 2 pi, not across a turn (a wrapped joint at +-pi stepped by 2 pi sent
    the seeds along the wrong joint, and one crossing continuum was lost). Both are found, every member of every
    family solves the pose, and the two along q4 are distinct."""
    from sweepik.engine.families import off_families

    robot = sweepik.load_robot("stanford")
    q = np.array([-0.47646912326117485, -np.pi / 2, 0.0, 2.036223930072506, 0.0, 0.29396685086745444])
    T = robot.fk(q)
    sol = sweepik.solve(robot, T, limits=False)
    families_certified(robot, sol, T)
    assert sum(f.free_joint == 1 for f in sol.families) == 2
    along = [f for f in sol.families if f.free_joint == 3]
    assert len(along) == 2
    assert off_families(robot, [(along[1].sample(15), (along[0],))])[0].sum() >= 13


def _full_grid_seeds(robot: sweepik.Robot, family: sweepik.Family) -> int:
    """How many seeds ``crossing_seeds`` gives from the family's whole grid, without the screen."""
    from sweepik.engine.crossings import _dips, _grid, _second_singular, crossing_seeds

    own = _second_singular(robot, family, _grid(family))
    return len(crossing_seeds(robot, (family,), [own if _dips(own[None]).any() else None])[1])


def test_the_screen_passes_no_family_that_crosses_another() -> None:
    """``crossings.screened`` (the cofactors' signs at every fourth member) lets no family through whose whole grid
    the search finds a crossing on: the C-Arm with joints 5 and 6 swapped and the KR 6 (where a family's members go
    over to the wrist turned by pi just past the crossing) on and next to their singular sets. And it does let most
    families through (the C-Arm's grid poses: the screen is what saves their probes)."""
    from singular import singular_configurations

    from sweepik.engine.crossings import screened
    from sweepik.experiments.bench import grid_configurations

    crossing = 0
    for name, seed in (("carm_swapped", 1), ("kuka_kr6_r900", 11)):
        robot = sweepik.load_robot(name)
        rng = np.random.default_rng(seed)
        Q = singular_configurations(robot, 30, rng)
        if name == "kuka_kr6_r900":
            Q = np.array([_shoulder_singular(robot, rng) for _ in range(3)])
        fams = [f for s in sweepik.solve_many(robot, robot.fk(Q), limits=False) for f in s.families]
        fams = [f for f in fams if f.interval[1] > f.interval[0]]
        for f, passed in zip(fams, screened(robot, fams), strict=True):
            found = _full_grid_seeds(robot, f)
            crossing += found > 0
            assert not (passed and found), (name, f)
    assert crossing >= 4
    carm = sweepik.load_robot("carm")
    q = grid_configurations(include_singular=False)[::7][:600]
    fams = [f for s in sweepik.solve_many(carm, carm.fk(q)) for f in s.families]
    assert np.mean(screened(carm, fams)) > 0.5


def test_the_cofactors_give_the_determinant_with_the_column_replaced() -> None:
    """``crossings._cofactors``: ``w . x`` is the determinant of the scaled Jacobian with the joint's column replaced
    by ``x`` (so ``w`` is normal to the other five columns, and zero only where they are dependent)."""
    from sweepik.engine.continuation import scaled_jacobians
    from sweepik.engine.crossings import _cofactors

    rng = np.random.default_rng(3)
    for name in ("ur5", "carm"):
        robot = sweepik.load_robot(name)
        q = rng.uniform(robot.lower, robot.upper, (50, 6))
        joint = rng.integers(0, 6, 50)
        x = rng.normal(size=(50, 6))
        w = _cofactors(robot, q, joint)
        J = scaled_jacobians(robot, q)
        J[np.arange(50), :, joint] = x
        np.testing.assert_allclose(np.einsum("ki,ki->k", w, x), np.linalg.det(J), rtol=1e-9, atol=1e-12)
