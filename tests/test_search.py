"""The compiled sweep search (sweepik.engine.search) against its NumPy reference (tests/oracles/numpy_sweep.py): the
same candidates, families and samples, staged or in one pass, with or without multiplicities, and the edge samples; a
reduction written in NumPy (no kernel: its residual called back) solves as its compiled kernel does."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import carm_stress_configurations
from oracles import numpy_sweep as sweep
from oracles.numpy_engine import numpy_reduction

import sweepik
from sweepik import load_robot, solve_many
from sweepik.engine import candidates, chunk, search
from sweepik.results import joint_distance

CARM = load_robot("carm")


@pytest.mark.parametrize("reduction", ["carm-d1", "carm-theta2"])
def test_a_reduction_without_its_kernel_solves_as_with_it(reduction: str) -> None:
    """The reduction's NumPy methods (its residual called back from the search, its configurations, its families'
    members in NumPy) give the solutions its compiled kernels give."""
    T = CARM.fk(carm_stress_configurations(300, seed=3))
    fast = solve_many(CARM, T, reduction=reduction)
    ref = solve_many(CARM, T, reduction=numpy_reduction(sweepik.reductions.get_reduction(CARM, reduction)))
    for a, b in zip(fast, ref, strict=True):
        assert len(a) == len(b)
        assert len(a.families) == len(b.families)
        if len(a):
            d = joint_distance(CARM, a.q[:, None, :], b.q[None, :, :]).max(axis=-1)
            assert d.min(axis=1).max() <= 1e-8


def test_compiled_sample_grid_is_the_numpy_one() -> None:
    """``search.sample_grid`` (compiled merge) gives the reference's samples of each pose alone, bit for bit, with
    no sample for a NaN hint (the reference makes it a spare midpoint, so that its rows have one length): hints
    inside and outside the range, NaN hints, hints on the uniform grid and repeated (runs of equal samples spread),
    real reductions. A pose's samples therefore do not depend on the batch it is solved in."""

    def check(red: sweepik.reductions.Reduction, chain: np.ndarray, lo: np.ndarray, hi: np.ndarray, n: int) -> int:
        grid, count = search.sample_grid(red, chain, lo, hi, n)
        hints = candidates.grid_hints(red, chain)
        assert grid.shape[0] == count.shape[0] == chain.shape[0]
        dropped = 0
        for i in range(chain.shape[0]):
            own = None if hints is None else hints[i : i + 1, np.isfinite(hints[i])]
            ref = sweep.merge_grid(lo[i : i + 1], hi[i : i + 1], n, own)[0]
            assert count[i] == ref.size
            np.testing.assert_array_equal(grid[i, : count[i]], ref)
            assert np.isnan(grid[i, count[i] :]).all()
            dropped += grid.shape[1] - count[i]
        return dropped

    rng = np.random.default_rng(4)
    dropped = 0
    for name, reduction in (("carm", "carm-d1"), ("carm", "carm-theta2"), ("carm", "auto"), ("xarm6", "auto")):
        robot = load_robot(name)
        red = sweepik.reductions.get_reduction(robot, reduction)
        chain = chunk.chain_poses(robot, robot.fk(rng.uniform(robot.lower, robot.upper, (200, robot.n_joints))))
        lo, hi = chunk.theta_range(robot, red, chain)
        if search._hints_kernel(red) is None:
            dropped += check(red, chain, lo, hi, sweep.N_SAMPLES)
        else:  # (a hints kernel writes as many for every pose: the reference's grid exactly)
            grid, count = search.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
            np.testing.assert_array_equal(grid, sweep.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES))
            assert (count == grid.shape[1]).all()
    assert dropped > 0  # (xArm 6's poses differ in their number of hints)

    class Hinted(sweepik.reductions.CArmD1):
        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return hints

    N, n = 300, 11
    lo = rng.uniform(-900.0, 0.0, N)
    hi = lo + rng.uniform(1.0, 3000.0, N)
    on_grid = lo[:, None] + (hi - lo)[:, None] * np.linspace(0.0, 1.0, n)[rng.integers(0, n, (N, 8))]
    hints = np.where(rng.random((N, 8)) < 0.5, on_grid, rng.uniform(-2000.0, 4000.0, (N, 8)))
    hints[rng.random((N, 8)) < 0.2] = np.nan
    hints[:, 3] = hints[:, 2]
    assert check(Hinted(CARM), np.broadcast_to(np.eye(4), (N, 4, 4)), lo, hi, n) > 0


def test_margins_made_per_call_share_their_pair_plans_engine_plan() -> None:
    """The generic sweeps' margins are a reduction made afresh for each solve: the engine's plan of them (kernels,
    branches, limits) is worked out once per pair plan (``plan_key``), and is the one a fresh plan would be."""
    from sweepik.reductions.generic import _Margins

    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, "auto")
    m1, m2 = _Margins(red, np.zeros((1, 0))), _Margins(red, np.zeros((2, 0)))
    assert search._plan(m1) is search._plan(m2)
    fresh = search._make_plan(m2)
    got = search._plan(m2)
    assert (got.residual, got.residuals, got.n_all, got.hints) == (fresh.residual, fresh.residuals, fresh.n_all, None)
    assert np.array_equal(got.branches, fresh.branches) and np.array_equal(got.ends, fresh.ends)
    other = sweepik.reductions.get_reduction(load_robot("kinova_jaco2"), "auto")
    if not other.closed_form:
        assert search._plan(_Margins(other, np.zeros((1, 0)))) is not search._plan(m1)


def test_search_without_multiplicities_finds_the_same_candidates() -> None:
    """``search.search(..., multiplicity=False)`` (the margins' search) gives the same candidates and spans, each
    with multiplicity 1; with multiplicities, poses with a double root (theta2 = +-90 deg, theta3 = 0, the paper's
    excluded grid points) and random ones have some above 1 and some of 1, so the comparison sees what it ignores."""
    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    q = carm_stress_configurations(100, seed=5)
    q[:30, 1] = np.pi / 2
    q[:30, 2] = 0.0
    q[:30, 4] = 0.3
    chain = chunk.chain_poses(CARM, CARM.fk(q))
    lo, hi = chunk.theta_range(CARM, red, chain)
    full, spans = search.search(red, chain, lo, hi, sweep.N_SAMPLES)
    bare, spans2 = search.search(red, chain, lo, hi, sweep.N_SAMPLES, multiplicity=False)
    for a, b in ((full.pose, bare.pose), (full.branch, bare.branch), (full.theta, bare.theta)):
        np.testing.assert_array_equal(a, b)
    assert (bare.mult == 1).all() and (full.mult > 1).any() and (full.mult == 1).any()
    np.testing.assert_array_equal(spans.lo, spans2.lo)


def _same_search(a: Any, b: Any) -> None:
    (ca, sa), (cb, sb) = a, b
    for x, y in zip((ca.pose, ca.branch, ca.theta, ca.mult), (cb.pose, cb.branch, cb.theta, cb.mult), strict=True):
        np.testing.assert_array_equal(x, y)
    for x, y in zip((sa.pose, sa.branch, sa.lo, sa.hi), (sb.pose, sb.branch, sb.lo, sb.hi), strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize(
    ("name", "reduction"),
    [
        ("fanuc_crx10ia", "auto"),
        ("kinova_jaco2", "auto"),
        ("xarm6", "auto"),
        ("yaskawa_hc10", "auto"),
        ("carm", "auto"),
        ("carm", "carm-d1"),
    ],
)
def test_one_pass_search_is_the_staged_search(name: str, reduction: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """The search in one compiled pass per pose finds what the staged search finds (every pose's samples first, by
    ``sample_grid``, then the search: ``one_pass=False``), bit for bit, batched and pose by pose: a generic sweep
    (its swing samples, its margins' zeros, its candidates: ``search.EdgeSearch``), theta* revolute or prismatic
    (the C-Arm's rail, automatic decomposition), and a reduction with a hints kernel (carm-d1). Random poses, and
    poses on the singular set (joint 5 at 0, joint 3 at 0, both). With the buffers cut to one candidate, every pose
    with more overflows and is searched again with larger buffers, in both; cut to the median count (carm-d1), some
    are: the same candidates in the same order, twins' copies included."""
    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, reduction)
    assert search._plan(red).one_pass is not None  # (the one-pass search is what is tested)
    rng = np.random.default_rng(11)
    q = rng.uniform(robot.lower, robot.upper, (60, 6))
    q[:10, 4] = 0.0
    q[10:20, 2] = 0.0
    q[20:25, 2] = 0.0
    q[20:25, 4] = 0.0
    chain = chunk.chain_poses(robot, robot.fk(q))
    lo, hi = chunk.theta_range(robot, red, chain)
    n = sweep.N_SAMPLES
    one_pass = search.search(red, chain, lo, hi, n)
    _same_search(one_pass, search.search(red, chain, lo, hi, n, one_pass=False))
    assert one_pass[0].pose.size >= chain.shape[0]  # (candidates found: the comparison is not of empty sets)
    for i in range(0, 60, 7):
        one = search.search(red, chain[i : i + 1], lo[i : i + 1], hi[i : i + 1], n)
        _same_search(one, search.search(red, chain[i : i + 1], lo[i : i + 1], hi[i : i + 1], n, one_pass=False))
    monkeypatch.setattr(search, "MAX_CAND", 1)
    few = slice(0, 25, 6)
    _same_search(
        search.search(red, chain[few], lo[few], hi[few], n),
        search.search(red, chain[few], lo[few], hi[few], n, one_pass=False),
    )
    if reduction == "auto":
        # (a generic sweep redoes a pose whose margins overflow as a whole, the staged search its margins alone:
        # with buffers cut below the margins' zeros they differ, as they may; MAX_CAND is far above them)
        return
    # some poses redone, the others not: the redone ones (and their twins' copies) in their place
    counts = np.bincount(one_pass[0].pose, minlength=chain.shape[0])
    cut = int(np.median(counts))
    assert (counts > cut).any() and (counts <= cut).any()
    monkeypatch.setattr(search, "MAX_CAND", cut)
    _same_search(search.search(red, chain, lo, hi, n), search.search(red, chain, lo, hi, n, one_pass=False))


@pytest.mark.parametrize("engine", ["compiled", "numpy"])
def test_edge_samples_far_from_zero_are_no_candidates(engine: str) -> None:
    """A sample next to a branch-domain edge or at the range's ends is a candidate only where its residual is within
    ``FAR_NOISE`` x noise of zero (as an extremum): a root there would make it small. Every candidate the search
    gives is then that close to zero; before, over half the CRX-10iA's candidates were such samples, far from it.
    (Next to a family's samples they stay candidates: the C-Arm's grid poses are unchanged, see docs/performance.md.)
    """
    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, None)
    chain = chunk.chain_poses(robot, robot.fk(np.random.default_rng(4).uniform(robot.lower, robot.upper, (30, 6))))
    lo, hi = chunk.theta_range(robot, red, chain)
    if engine == "compiled":
        cand, _ = search.search(red, chain, lo, hi, sweep.N_SAMPLES)
    else:
        cand, _ = sweep.find_candidates(red, chain, lo, hi, sweep.N_SAMPLES)
    f = red.residual(chain[cand.pose], cand.theta[:, None], cand.branch[:, None])[:, 0]
    assert cand.theta.size >= 4 * len(chain)  # (the arm's roots: 7.8 solutions a pose on average)
    assert np.all(np.abs(f) <= sweep.FAR_NOISE * red.residual_noise)


@pytest.mark.parametrize("name", ["fanuc_crx10ia", "xarm6"])
def test_edge_intervals_left_alone_hide_no_roots(name: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """An interval beside a branch-domain edge that sits at a sample is resampled at the first level only where it
    bends in that edge's coordinate (``sweep.EDGE_PROBE_REL``). Those left alone hide no pair of roots: sampled
    densely (in the edge's coordinate, where a pair would sit), the residual changes sign exactly as often as its two
    ends show (once or not at all), and comes no nearer zero than they do unless it crosses. Random poses and poses
    on the singular set (joints at 0 and 90 deg)."""
    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, None)
    rng = np.random.default_rng(8)
    q = rng.uniform(robot.lower, robot.upper, (40, 6))
    q[20:30, 4] = 0.0
    q[30:, 2] = np.pi / 2
    chain = chunk.chain_poses(robot, robot.fk(q))
    lo, hi = chunk.theta_range(robot, red, chain)
    seen: list[tuple[Any, ...]] = []
    judge = sweep._Search._edge_at_sample

    def recorded(self: Any, p: Any, b: Any, th: Any, fin: Any, *rest: Any) -> Any:
        judged, bent = judge(self, p, b, th, fin, *rest)
        i, j = np.nonzero(judged & ~bent)
        seen.append((p[i], b[i], th[i, j], th[i, j + 1], fin[i, j], fin[i, j + 1], rest[2][i, j + 1]))
        return judged, bent

    monkeypatch.setattr(sweep._Search, "_edge_at_sample", recorded)
    sweep.find_candidates(red, chain, lo, hi, sweep.N_SAMPLES)
    p, b, t0, t1, f0, f1, right = (np.concatenate(c) for c in zip(*seen, strict=True))
    assert p.size >= len(chain)  # (most edges' intervals are left alone: the test is not vacuous)
    # dense samples, uniform in sqrt(|theta - edge|)
    edge, other = np.where(right, t1, t0), np.where(right, t0, t1)
    x = np.linspace(0.0, 1.0, 2001)[None, :] ** 2
    dense = edge[:, None] + (other - edge)[:, None] * x
    f = red.residual(chain[p], dense, np.broadcast_to(b[:, None], dense.shape))
    assert np.isfinite(f).all()
    changes = np.count_nonzero(np.sign(f[:, 1:]) * np.sign(f[:, :-1]) < 0, axis=1)
    crosses = f0 * f1 < 0
    np.testing.assert_array_equal(changes, crosses.astype(int))
    ends = np.minimum(np.abs(f0), np.abs(f1))
    assert np.all(crosses | (np.abs(f).min(axis=1) >= 0.5 * ends))


@pytest.mark.parametrize("name", ["i2rt_yam", "xarm6", "fanuc_crx10ia"])
def test_domain_edge_samples_lie_inside_their_domains(name: str) -> None:
    """A generic sweep's domain edges (the zeros of its margins) become samples on the domain's side
    (``inside_zeros``, the compiled one-pass search's ``_inside``: the same samples, see
    ``test_one_pass_search_is_the_staged_search``): at each, its margin is >= 0 (0 ... 1e-8), not a rounding step below
    0, where the branches it bounds are NaN and the stretch to the next sample went unsearched (an I2RT YAM written
    with other axis signs lost a solution 0.04 rad from such an edge), unless the margin touches 0 from below (no
    domain on either side). Random poses and poses on the singular sets."""
    from singular import singular_configurations

    from sweepik.engine.settings import EDGE_PROBE_REL

    robot = load_robot(name)
    red = sweepik.reductions.get_reduction(robot, "auto")
    if red.closed_form:
        pytest.skip(f"{name}: a closed form (no sweep, no domain edges)")
    rng = np.random.default_rng(7)
    Q = np.concatenate([rng.uniform(robot.lower, robot.upper, (100, 6)), singular_configurations(robot, 100, rng)])
    chain = chunk.chain_poses(robot, robot.fk(Q))
    margins, lo, hi = red.edge_reduction(chain, red.sample_hints(chain))
    cand, _ = search.search(margins, chain, lo, hi, sweep.N_SAMPLES, None, multiplicity=False)
    if margins.periodic:
        cand = candidates.Candidates(cand.pose, cand.branch, candidates.wrapped(cand.theta), cand.mult)
    reach = EDGE_PROBE_REL * (hi - lo)

    def margin(t: np.ndarray) -> np.ndarray:
        return np.asarray(margins.residual_rows(chain, cand.pose, t[:, None], cand.branch[:, None]))[:, 0]

    before = margin(cand.theta)
    after = margin(search.inside_zeros(margins, chain, cand, reach).theta)
    edge = np.abs(before) <= 1e-8  # (the others: samples next to a margin's own NaN, the range's ends)
    assert edge.sum() > 50 and (before[edge] < 0.0).sum() > 5  # (the rounding put some outside)
    outside = edge & ~(after >= 0.0)
    touching = (margin(cand.theta - reach[cand.pose]) < 0.0) & (margin(cand.theta + reach[cand.pose]) < 0.0)
    assert (touching[outside]).all(), cand.theta[outside & ~touching]
    assert outside.sum() <= edge.sum() / 10
    assert (np.abs(after[edge] - before[edge]) <= 1e-8).all()


def test_a_close_pair_just_inside_an_edge_at_a_sample_is_searched() -> None:
    """The JACO2 next to its singular set (``scripts/singular_audit.py --n 40 --seed 3``, configuration 39): branch 2
    of its joint-1 sweep holds two roots 1.6e-5 apart, 2.3e-4 inside the branch's domain edge, which sits at a sample
    (a margin's zero). The edge's residual is 7.7e-4 against its neighbour's 3.2e-2, and the three samples make a
    straight line in the edge's coordinate, so the bend test left the interval unsearched and both roots were missed
    (4 solutions of 6, the configuration not among them). An edge whose residual is below ``EDGE_LOW`` of its
    neighbour's now has the interval resampled: the compiled search and its NumPy reference find both."""
    from sweepik.engine.chunk import chain_poses

    robot = load_robot("kinova_jaco2")
    q = np.array([1.8657100929952852, 3.0150848528098333, 3.09552824518443, 0.15830510205445636,
                  -2.120970656728688, -2.4609361811184405])  # fmt: skip
    T = robot.fk(q)
    for limits in (True, False):
        sols = sweepik.solve(robot, T, limits=limits)
        assert len(sols) == 6 and np.abs(robot.fk(sols.q) - T).max() < 1e-9
        assert np.max(np.abs(np.angle(np.exp(1j * (sols.nearest(q) - q))))) < 1e-7
    red = sweepik.solving._default_reduction(robot, None)
    chain, lo, hi = chain_poses(robot, T[None]), np.array([-np.pi]), np.array([np.pi])
    for cand in (search.search(red, chain, lo, hi, 64)[0], sweep.find_candidates(red, chain, lo, hi, 64)[0]):
        near = np.abs(cand.theta - q[0]) < 1e-4
        assert np.count_nonzero(near & (cand.branch == 2)) >= 2


def test_a_double_root_in_a_dip_beside_an_edge_at_a_sample_is_searched() -> None:
    """The JACO2 on its singular set (``scripts/singular_audit.py --n 60 --seed 5``, configuration 12): a double root
    of branch 2 2.4e-3 inside the branch's domain edge, which sits at a sample, in a dip ~1e-2 wide that the three
    samples of the bend test (2.7e-3 at the edge, 3.1e-3 and 3.2e-3 before it) do not show; the configuration was
    not among the 8 solutions. The residual halfway between the edge and its neighbour, in the edge's coordinate, now
    decides too (below both: resampled): the compiled search and its NumPy reference find the root."""
    from sweepik.engine.chunk import chain_poses

    robot = load_robot("kinova_jaco2")
    q = np.array([-1.932163912795935, 1.1179441845404252, -0.057268935354375786, 0.30807111710135393,
                  -0.294277518194058, -1.4178137911894344])  # fmt: skip
    T = robot.fk(q)
    sols = sweepik.solve(robot, T, limits=False)
    assert np.abs(robot.fk(sols.q) - T).max() < 1e-9
    assert np.max(np.abs(np.angle(np.exp(1j * (sols.nearest(q) - q))))) < 1e-6
    red = sweepik.solving._default_reduction(robot, None)
    chain, lo, hi = chain_poses(robot, T[None]), np.array([-np.pi]), np.array([np.pi])
    for cand in (search.search(red, chain, lo, hi, 64)[0], sweep.find_candidates(red, chain, lo, hi, 64)[0]):
        assert np.any((cand.branch == 2) & (np.abs(cand.theta - q[0]) < 1e-6))


def test_a_hidden_edge_beside_a_root_is_no_candidate_of_its_own() -> None:
    """The C-Arm with its elbow stretched and the rail at its end (0): a double root at the sample d1 = 0, and the
    branch's domain ending 8e-4 mm on, between two samples, where the residual is still near zero. Taken as a second
    candidate, that edge was merged with the root into one solution 5e-5 mm off it (multiplicity 2; IK(FK(q)) missed
    q by 5e-5). The edge is a candidate only where the residual is no larger there than at the inside sample: the
    root alone, exact, in the compiled search and its NumPy reference."""
    arm = load_robot("carm")
    q = np.array([0.0, -np.pi, -1.4660765716752369, -np.pi / 2, 2.0, -np.pi])
    T = arm.fk(q)
    sols = sweepik.solve(arm, T)
    assert np.max(np.abs(np.angle(np.exp(1j * (sols.nearest(q)[1:] - q[1:]))))) < 1e-9
    assert abs(sols.nearest(q)[0] - q[0]) < 1e-9 and np.all(sols.multiplicity == 1)
    from sweepik.engine.chunk import chain_poses

    red = sweepik.solving._default_reduction(arm, None)
    chain, lo, hi = chain_poses(arm, T[None]), np.array([0.0]), np.array([2000.0])
    for cand in (search.search(red, chain, lo, hi, 64)[0], sweep.find_candidates(red, chain, lo, hi, 64)[0]):
        assert np.all(np.abs(cand.theta) < 1e-9)


def test_a_domain_edge_hidden_between_two_samples_is_searched() -> None:
    """Flexiv Rizon 4 of ssik's catalogue, rewritten (tests/data/rizon4_rewritten.toml), joint 7 held: branch 3 of
    the held arm's sweep lives on [-0.0039, 0.0900], and two roots 7e-5 apart sit 1.5e-3 inside its right edge. The
    margins' sweep missed that edge (a pair of close zeros of a margin), so no sample marked it: the samples around it
    were one inside (0.0499) and one outside (0.0917), and the stretch between went unsearched (the pose answered
    "unreachable"). The compiled search and its NumPy reference now locate the edge and search up to it."""
    from pathlib import Path

    from sweepik.engine.chunk import chain_poses

    robot = load_robot(str(Path(__file__).parent / "data" / "rizon4_rewritten.toml"))
    q = np.array([0.08851973794656232, 0.2905707832504163, -2.5798371727465472, 1.9845555624869284,
                  -1.6838111600274586, -0.9725832260768259, -2.820486620872427])  # fmt: skip
    T = robot.fk(q)
    sols = sweepik.solve(robot, T, locked={6: float(q[6])}, limits=False)
    assert len(sols) and np.abs(robot.fk(sols.q) - T).max() < 1e-9 * robot.length_scale
    d = np.abs(np.angle(np.exp(1j * (sols.q - q))))
    assert np.min(np.max(d, axis=1)) < 1e-6
    held = sweepik.solving.held_joints(robot, {6: float(q[6])})
    red = sweepik.solving._default_reduction(held.arm, held)
    chain = chain_poses(held.arm, T[None])
    lo, hi = np.array([-np.pi]), np.array([np.pi])
    for cand in (search.search(red, chain, lo, hi, 64)[0], sweep.find_candidates(red, chain, lo, hi, 64)[0]):
        assert np.any((cand.branch == 3) & (np.abs(cand.theta - q[0]) < 1e-9))


def test_a_double_root_where_the_last_joint_swings_is_searched() -> None:
    """The CRX-10iA rewritten at random (``tests/rewrites.py``, seed 1001), at an exactly singular configuration (an
    isolated double root: axes 2 and 5 in line): joint 2, the one its ``ab_par`` case turns last, swings by pi
    within 1.3e-4 of theta* where the wrist centre passes 2e-5 from its axis. Branch 3's residual touches zero there,
    2.6e-4 from a simple root with a maximum between them, all in one interval the bend test left alone: only the
    simple root was bracketed, and the configuration was missed (found by an auditing helper). The swing hints now
    sample the windows of the final step's gap too (``geometric.SWING_STEPS``): the compiled search and its NumPy
    reference find the root, and the solve gives the configuration back."""
    from rewrites import rewrite
    from singular import recovered

    from sweepik.engine.chunk import chain_poses

    robot = rewrite(load_robot("fanuc_crx10ia"), np.random.default_rng(1001)).robot
    q = np.array([0.46033568027046856, 0.4304670839774083, 0.24395417189640398, -2.2633087173669666,
                  2.0769880108359935, 0.5162850825294347])  # fmt: skip
    T = robot.fk(q)
    sols = sweepik.solve(robot, T, limits=False)
    assert np.abs(robot.fk(sols.q) - T).max() < 1e-9 * robot.length_scale
    # (a double root: given once, multiplicity 2, 3e-6 from q along the direction the pose fixes only to second order)
    near = np.max(joint_distance(robot, sols.q, q), axis=1) < 1e-5
    assert recovered(robot, sols, q) and np.count_nonzero(near) == 1 and sols.multiplicity[near][0] == 2
    red = sweepik.solving._default_reduction(robot, None)
    chain, lo, hi = chain_poses(robot, T[None]), np.array([-np.pi]), np.array([np.pi])
    for cand in (search.search(red, chain, lo, hi, 64)[0], sweep.find_candidates(red, chain, lo, hi, 64)[0]):
        assert np.any((cand.branch == 3) & (np.abs(cand.theta - q[0]) < 1e-6))
