"""Contract suite of the automatic decomposition over every bundled arm and over random arms of each family.

Properties (issue 9): ``solve(robot, robot.fk(q))`` with no options contains q, every solution is FK-certified
and within limits; the solution set agrees with independent references: another decomposition of the same arm
(another theta*), IK-Geo where it has a closed form for the arm, ssik on the arms sweepik sweeps (its
Raghavan-Roth elimination: an algebraic method, nothing in common with a sweep), and a many-start numerical search.
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest
from oracles import (
    contains,
    edge_configurations,
    ikgeo_solutions,
    in_limit_configurations,
    numerical_solutions,
    pose_errors,
    recovers,
    same_solution_set,
    ssik_solutions,
)
from singular import singular_configurations

import sweepik
from sweepik import NoReductionError
from sweepik.io.robot_file import bundled_robots, robot_from_dict
from sweepik.model.structure import near_structure
from sweepik.reductions.decompose import plans

# the six-joint bundled arms (the seven-joint ones are solved with a joint locked: tests/test_locked.py)
BUNDLED = [n for n in bundled_robots() if sweepik.load_robot(n).n_joints == 6]
CLOSED = {
    "puma560",
    "puma560_std",
    "kuka_kr6_r900",
    "abb_irb140",
    "stanford",
    "carm_swapped",
    "ur3",
    "ur5",
    "ur10",
    "standardbots_spark",
}
CERT_REL = 1e-9
# the bundled 6R arms sweepik sweeps (no closed form): those ssik's Raghavan-Roth elimination is compared on
SWEPT_6R = [
    n
    for n in BUNDLED
    if (r := sweepik.load_robot(n)).is_revolute.all() and not sweepik.analyze(r)["chosen"]["closed_form"]
]
SSIK_POSES = 150  # random in-limit poses per arm (ssik's live solver: ~3-5 ms a pose), plus 2 x 13 edge poses
SSIK_AGREE = 0.995  # share of poses on which both return the same set


def _kw(robot):
    # the C-Arm's file names its hand-derived reduction; the automatic one is asked for by name
    return {"reduction": "auto"} if robot.default_reduction else {}


def _check_set(robot, sols):
    if len(sols):
        assert np.all(sols.error_geodesic <= CERT_REL * robot.length_scale)
        assert np.all(robot.within_limits(sols.q))


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_arm_round_trip(name):
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(zlib.crc32(name.encode()))
    Q = in_limit_configurations(robot, 60, rng)
    Q = np.concatenate([Q, edge_configurations(robot, in_limit_configurations(robot, 1, rng)[0])])
    for q, sols in zip(Q, sweepik.solve_many(robot, robot.fk(Q), **_kw(robot)), strict=True):
        assert recovers(robot, sols, q), (name, q.tolist())
        _check_set(robot, sols)


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_arm_has_expected_decomposition(name):
    robot = sweepik.load_robot(name)
    found = plans(robot)
    assert found, name
    assert found[0].closed_form == (name in CLOSED)


@pytest.mark.parametrize("name", BUNDLED)
def test_other_decompositions_agree(name):
    """Every theta* the decomposition offers gives the same solution set as the chosen plan (closed form or
    sweep: different subproblem chains)."""
    robot = sweepik.load_robot(name)
    frees = sorted({p.free_joint for p in plans(robot) if not p.closed_form and not p.conditional})
    assert frees or name in CLOSED
    rng = np.random.default_rng(7)
    Q = in_limit_configurations(robot, 25, rng)
    T = robot.fk(Q)
    # within the limits: a prismatic theta* is swept over its limits only, a revolute one finds solutions whose
    # prismatic joints lie beyond them
    ref = sweepik.solve_many(robot, T, **_kw(robot))
    for k in frees:
        try:
            other = sweepik.solve_many(robot, T, free_joint=k)
        except sweepik.NoReductionError:  # (a sweep that its check on the arm found lossy: a near-structure)
            assert near_structure(robot.chain, robot.length_scale), (name, k)
            continue
        same = [
            same_solution_set(a.q, b.q, robot.is_revolute, robot.length_scale) for a, b in zip(ref, other, strict=True)
        ]
        assert np.mean(same) >= 0.96, (name, k, np.mean(same))


@pytest.mark.parametrize("name", ["puma560", "puma560_std", "kuka_kr6_r900", "abb_irb140", "ur5"])
def test_against_ikgeo(name):
    pytest.importorskip("ik_geo")
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(11)
    Q = in_limit_configurations(robot, 40, rng)
    T = robot.fk(Q)
    ours = sweepik.solve_many(robot, T, limits=False)
    agree = 0
    for q, t, s in zip(Q, T, ours, strict=True):
        ref = ikgeo_solutions(robot, t)
        assert ref is not None and contains(ref, q, robot.is_revolute, robot.length_scale)
        agree += same_solution_set(s.q, ref, robot.is_revolute, robot.length_scale)
    assert agree >= 0.95 * len(Q), (name, agree)


def _ssik_difference(robot, k, q, T, ours, ref):
    """Why sweepik's and ssik's answers to pose ``k`` differ (for the assertion message): each of ssik's solutions
    sweepik lacks (counting family members), each of sweepik's that ssik lacks, with its FK error, the smallest
    singular value of the Jacobian there (near 0: a multiple root or a continuum, known only to ~sqrt(rounding))
    and whether a many-start numerical search (a third opinion) finds it."""
    rev, L = robot.is_revolute, robot.length_scale
    # an oracle's solution next to a singular configuration is only as exact as its FK error over the Jacobian's
    # smallest singular value (ssik's near a nearly spherical wrist: FK errors 1e-9 ... 4e-7, joints 1e-3 off)
    tol = [max(1e-6, 10.0 * max(pose_errors(robot.fk(x), T, L)) / _sigma_min(robot, x)) for x in ref]
    missing = [x for x, t in zip(ref, tol, strict=True) if not recovers(robot, ours, x, t)]
    extra = [x for x in ours.q if not any(contains(y[None], x, rev, L, t) for y, t in zip(ref, tol, strict=True))]
    if not missing and not extra:
        return None
    num = numerical_solutions(robot, T, n_starts=600, full_circle=True)
    lines = [
        f"pose {k}, q = {np.round(q, 6).tolist()}: sweepik {len(ours.q)} (+ {len(ours.families)} families), "
        f"ssik {len(ref)}, numerical search {len(num)}"
    ]
    for label, xs in (("ssik's, missing from sweepik", missing), ("sweepik's, missing from ssik", extra)):
        for x in xs:
            dp, ang = pose_errors(robot.fk(x), T, L)
            smin = np.linalg.svd(robot.jacobian(x), compute_uv=False)[-1]
            lines.append(
                f"  {label}: {np.round(x, 6).tolist()} FK error {max(dp, ang):.1e}, sigma_min(J) {smin:.1e}, "
                f"numerical search finds it: {contains(num, x, rev, L, 1e-5)}"
            )
    return "\n".join(lines)


def _sigma_min(robot, q):
    """The smallest singular value of the Jacobian at ``q``, lengths over the arm's length scale."""
    J = robot.jacobian(q)
    J[:3] /= robot.length_scale
    return max(float(np.linalg.svd(J, compute_uv=False)[-1]), 1e-300)


def test_swept_6r_arms_are_found():
    assert {"fanuc_crx10ia", "kinova_jaco2", "xarm6", "yaskawa_hc10"} <= set(SWEPT_6R)


@pytest.mark.parametrize("name", SWEPT_6R)
def test_against_ssik(name):
    """sweepik (limits off) and ssik's live solver on the same chain return the same solution set on random and
    edge poses of every swept 6R arm: no wrong solution (every one of sweepik's is FK-certified), and on at least
    SSIK_AGREE of the poses the sets are identical; the assertion message says why on the others."""
    pytest.importorskip("ssik")
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(31)
    Q = in_limit_configurations(robot, SSIK_POSES, rng)
    Q = np.concatenate([Q, edge_configurations(robot, Q[0]), edge_configurations(robot, Q[1])])
    differ = []
    for k, q in enumerate(Q):
        T = robot.fk(q)
        ours = sweepik.solve(robot, T, limits=False)
        ref = ssik_solutions(robot, T)
        assert ref is not None
        assert recovers(robot, ours, q), (name, k, q.tolist())
        assert np.all(ours.error_geodesic <= CERT_REL * robot.length_scale), (name, k, q.tolist())
        why = _ssik_difference(robot, k, q, T, ours, ref)
        if why is not None:
            differ.append(why)
    allowed = int((1.0 - SSIK_AGREE) * len(Q))
    assert len(differ) <= allowed, f"{name}: {len(differ)} of {len(Q)} poses differ (allowed {allowed}):\n" + "\n".join(
        differ
    )


@pytest.mark.parametrize("name", ["fanuc_crx10ia", "kinova_jaco2", "yaskawa_hc10", "xarm6", "carm", "stanford"])
def test_against_numerical_search(name):
    robot = sweepik.load_robot(name)
    rng = np.random.default_rng(13)
    Q = in_limit_configurations(robot, 3, rng)
    for q in Q:
        T = robot.fk(q)
        s = sweepik.solve(robot, T, limits=False, **_kw(robot))
        num = numerical_solutions(robot, T, n_starts=300)
        inside = robot.within_limits(num) if num.size else np.zeros(0, bool)
        assert same_solution_set(s.q[robot.within_limits(s.q)], num[inside], robot.is_revolute, robot.length_scale)


def test_carm_automatic_equals_hand_derivations():
    robot = sweepik.load_robot("carm")
    rng = np.random.default_rng(17)
    Q = in_limit_configurations(robot, 150, rng)
    T = robot.fk(Q)
    auto = sweepik.solve_many(robot, T, reduction="auto")
    for ref_name in ("carm-d1", "carm-theta2"):
        ref = sweepik.solve_many(robot, T, reduction=ref_name)
        same = [
            same_solution_set(a.q, b.q, robot.is_revolute, robot.length_scale) for a, b in zip(auto, ref, strict=True)
        ]
        assert np.mean(same) >= 0.99, (ref_name, np.mean(same))


# ---------------------------------------------------------------------------------------------------------
# random arms of each family: other dimensions, base and tool transforms, prismatic joints where allowed
# ---------------------------------------------------------------------------------------------------------


def _arm(rows, rng, convention="standard", transforms=True):
    """A robot from DH rows ``(type, a, alpha_deg, d, theta_deg)`` with random limits-free revolute joints."""
    joints = []
    for i, (kind, a, alpha, d, theta) in enumerate(rows):
        limits = [-180.0, 180.0] if kind == "revolute" else [-0.5, 1.5]
        row = {"a": a, "alpha": alpha, "d": d, "theta": theta}
        joints.append({"name": f"j{i + 1}", "type": kind, "limits": limits, **row})
    data = {"name": "random", "dh_convention": convention, "length_unit": "m", "joints": joints}
    if transforms:
        data["base"] = {"xyz": rng.normal(size=3).tolist(), "zyz": rng.uniform(-180, 180, 3).tolist()}
        data["tool"] = {"xyz": rng.normal(scale=0.1, size=3).tolist(), "zyz": rng.uniform(-180, 180, 3).tolist()}
    return robot_from_dict(data)


def _L(rng):
    return float(rng.uniform(0.1, 0.8))


FAMILIES = {
    # spherical wrist after a shoulder with 2 || 3 (PUMA-like), closed form
    "wrist_parallel": lambda g: [
        ("revolute", _L(g), 90, _L(g), 0),
        ("revolute", _L(g), 0, _L(g), 0),
        ("revolute", _L(g), 90, 0, 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # Stanford-like RRP + spherical wrist, closed form with a prismatic joint
    "wrist_rrp": lambda g: [
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, _L(g), 0),
        ("prismatic", 0, 0, 0, 0),
        ("revolute", 0, -90, 0, 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # Cartesian gantry PPP + spherical wrist
    "wrist_ppp": lambda g: [
        ("prismatic", 0, -90, 0, 0),
        ("prismatic", 0, -90, 0, -90),
        ("prismatic", 0, 0, 0, 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # three parallel axes, the last two meeting (UR-like): closed form
    "three_parallel": lambda g: [
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # three parallel axes, an offset between the last two (IK-Geo's three-parallel case): closed form by sp6
    "three_parallel_offset": lambda g: [
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", _L(g), -60, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # the same with joint 6's axis able to turn parallel to joints 2-4 (a continuum at q5 = 0, swept by joint 6)
    "three_parallel_offset_90": lambda g: [
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", -_L(g), 0, 0, 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", _L(g), -90, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # the same after an oblique slide
    "slide_parallel_offset": lambda g: [
        ("prismatic", _L(g), 30, 0, 0),
        ("revolute", _L(g), 0, _L(g), 0),
        ("revolute", _L(g), 0, 0, 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", _L(g), -60, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # a slide oblique to three parallel axes, the last two meeting: closed form with a prismatic joint
    "slide_parallel": lambda g: [
        ("prismatic", _L(g), 30, 0, 0),
        ("revolute", _L(g), 0, _L(g), 0),
        ("revolute", _L(g), 0, 0, 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # two intersecting axes at the tool, the rest general except 2 || 3 (CRX-like), swept
    "pair_parallel": lambda g: [
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", _L(g), 0, 0, 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # cylindrical arm RPP (a turn, a lift along it, a radial reach) + spherical wrist: closed form (rpp)
    "wrist_rpp": lambda g: [
        ("revolute", 0, 0, _L(g), 0),
        ("prismatic", 0, -90, 0, 0),
        ("prismatic", 0, 0, 0, 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # a skewed cylindrical arm (slides neither along nor across the turn), the last two axes meeting only: swept
    "pair_rpp": lambda g: [
        ("revolute", 0.1 * _L(g), 20, _L(g), 0),
        ("prismatic", 0.1 * _L(g), -70, 0.1, 10),
        ("prismatic", 0.1 * _L(g), 30, 0.1, 0),
        ("revolute", _L(g), -90, _L(g), 0),
        ("revolute", 0, 90, _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # a general 3R positioning chain (no two axes meeting or parallel) + spherical wrist: Pieper's quartic (rrr)
    "wrist_general": lambda g: [
        *[("revolute", _L(g), float(g.uniform(20, 70)), _L(g), 0) for _ in range(3)],
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # the same at the base (a spherical shoulder, as the Panda with joint 5 held): rrr on the reversed chain
    "shoulder_general": lambda g: [
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
        *[("revolute", _L(g), float(g.uniform(20, 70)), _L(g), 0) for _ in range(4)],
    ],
    # a Cartesian gantry carrying a wrist whose axes are pairwise offset: orientation from the three revolute joints,
    # then the slides linearly (decoupled)
    "gantry_offset_wrist": lambda g: [
        ("prismatic", 0, -90, 0, 0),
        ("prismatic", 0, -90, 0, -90),
        ("prismatic", 0, 0, 0, 0),
        ("revolute", _L(g), float(g.uniform(20, 70)), _L(g), 0),
        ("revolute", _L(g), float(g.uniform(20, 70)), _L(g), 0),
        ("revolute", 0, 0, _L(g), 0),
    ],
    # slides and turns interleaved (R P R P R P), every axis oblique: decoupled, the slides turning with the joints
    "interleaved_rp": lambda g: [
        ("revolute", 0.2 * _L(g), float(g.uniform(20, 70)), _L(g), 0),
        ("prismatic", 0.2 * _L(g), float(g.uniform(20, 70)), 0.1, 0),
        ("revolute", 0.2 * _L(g), float(g.uniform(20, 70)), _L(g), 0),
        ("prismatic", 0.2 * _L(g), float(g.uniform(20, 70)), 0.1, 0),
        ("revolute", 0.2 * _L(g), float(g.uniform(20, 70)), _L(g), 0),
        ("prismatic", 0.0, 0, 0.1, 0),
    ],
    # C-Arm-like: a prismatic rail first, other dimensions
    "rail_pair": lambda g: [
        ("prismatic", 0, 0, 0, 0),
        ("revolute", 0, 90, 0, 0),
        ("revolute", 0, -90, 0, -90),
        ("revolute", _L(g), 0, 0, 0),
        ("revolute", 0, -90, _L(g), 0),
        ("revolute", 0, 90, 0, 0),
    ],
}


@pytest.mark.parametrize("family", sorted(FAMILIES))
@pytest.mark.parametrize("seed", range(3))
def test_random_family_arm(family, seed):
    rng = np.random.default_rng(1000 * seed + len(family))
    convention = "modified" if family == "rail_pair" else "standard"
    robot = _arm(FAMILIES[family](rng), rng, convention)
    assert plans(robot), robot.structure().describe()
    Q = in_limit_configurations(robot, 30, rng)
    for q, sols in zip(Q, sweepik.solve_many(robot, robot.fk(Q)), strict=True):
        assert recovers(robot, sols, q), (family, q.tolist())
        _check_set(robot, sols)
    if seed == 0:  # one pose against the numerical search
        T = robot.fk(Q[0])
        s = sweepik.solve(robot, T, limits=False)
        num = numerical_solutions(robot, T, n_starts=300)
        num = num[robot.within_limits(num)] if num.size else num
        assert same_solution_set(s.q[robot.within_limits(s.q)], num, robot.is_revolute, robot.length_scale)


@pytest.mark.parametrize("family", ["three_parallel", "slide_parallel", "three_parallel_offset"])
def test_parallel_closed_form_agrees_with_a_sweep(family):
    """The parallel family's closed form and a sweep give the same sets, also where joint 6's axis turns onto the
    parallel axes (q5 = 0 on the UR-like arms: a continuum, reported by the sweep as a family), next to it (q5 =
    1e-7: the closed form's angles lose half their digits there, the sweep answers) and at a straight elbow."""
    rng = np.random.default_rng(23)
    robot = _arm(FAMILIES[family](rng), rng)
    assert plans(robot)[0].family == "parallel"
    free = min(p.free_joint for p in plans(robot) if not p.closed_form and not p.conditional)
    Q = in_limit_configurations(robot, 24, rng)
    Q[:5, 4] = 0.0
    Q[5:10, 2] = 0.0
    Q[20:, 4] = 1e-7
    T = robot.fk(Q)
    closed = sweepik.solve_many(robot, T)
    swept = sweepik.solve_many(robot, T, free_joint=free)
    for q, a, b in zip(Q, closed, swept, strict=True):
        assert recovers(robot, a, q) and recovers(robot, b, q)
        _check_set(robot, a)
        assert bool(a.families) == bool(b.families)
        if not a.families:
            assert same_solution_set(a.q, b.q, robot.is_revolute, robot.length_scale)
        # with continua (cut into pieces differently by different sweeps), every solution and family member of one
        # side is a solution or family member of the other
        for x, y in ((a, b), (b, a)):
            for m in [*x.q, *(m for fam in x.families for m in fam.sample(5))]:
                assert recovers(robot, y, m)


def test_parallel_offset_singular_wrist_is_a_family():
    """Offset wrist whose joint 6 turns parallel to joints 2-4 at q5 = 0: the closed form hands those poses (and
    those next to them) to a sweep of joint 6, which recovers q and reports the continuum as a family."""
    rng = np.random.default_rng(23)
    robot = _arm(FAMILIES["three_parallel_offset_90"](rng), rng)
    assert plans(robot)[0].family == "parallel"
    Q = in_limit_configurations(robot, 16, rng)
    Q[:6, 4] = 0.0
    Q[6:10, 4] = 1e-7
    for k, (q, sols) in enumerate(zip(Q, sweepik.solve_many(robot, robot.fk(Q)), strict=True)):
        assert recovers(robot, sols, q), q.tolist()
        _check_set(robot, sols)
        if k < 6:
            assert sols.families
            for m in (m for fam in sols.families for m in fam.sample(5)):
                assert np.all(pose_errors_ok(robot, m, robot.fk(q)))


def pose_errors_ok(robot, q, T):
    dp, ang = pose_errors(robot.fk(q), T, robot.length_scale)
    return (dp <= 1e-9) & (ang <= 1e-9)


def test_interleaved_slides_turning_dependent_are_a_family():
    """Three slides interleaved with three revolute joints (the decoupled closed form): where the revolute joints
    turn the slides' directions into one plane, the travels along their common null direction are a continuum. The
    configurations of the singular set where that happens come back, as members of a family along a slide whose
    samples reproduce the pose; the others on the singular set come back too."""
    rng = np.random.default_rng(7001)
    robot = _arm(FAMILIES["interleaved_rp"](rng), rng)
    assert sweepik.analyze(robot)["chosen"]["case"] == "decoupled"
    Q = singular_configurations(robot, 40, rng)
    slides = ~robot.is_revolute
    dependent = np.array(
        [np.linalg.svd(robot.jacobian(q[None])[0][:3, slides], compute_uv=False)[-1] < 1e-12 for q in Q]
    )
    assert dependent.sum() >= 5
    for q, sols, dep in zip(Q, sweepik.solve_many(robot, robot.fk(Q), limits=False), dependent, strict=True):
        assert recovers(robot, sols, q), q.tolist()
        if dep:
            assert sols.families and all(not robot.is_revolute[f.free_joint] for f in sols.families)
            for m in (m for fam in sols.families for m in fam.sample(5)):
                assert np.all(pose_errors_ok(robot, m, robot.fk(q)))


def test_slide_parallel_offset_with_a_singular_wrist_is_refused():
    """After a slide, three parallel axes and an offset wrist whose joint 6 can turn parallel to them: no sweep
    can describe that continuum, so the closed form is not offered (it would answer "unreachable" there)."""
    rows = FAMILIES["slide_parallel_offset"](np.random.default_rng(2))
    rows[4] = ("revolute", rows[4][1], -90, rows[4][3], 0)
    robot = _arm(rows, np.random.default_rng(2))
    with pytest.raises(NoReductionError, match="UR family"):
        sweepik.solve(robot, robot.fk(np.full(6, 0.3)))


def test_near_singular_ur5_wrist():
    """UR5 with joint 5 next to 0 (where its closed form's angles lose half their digits): answered by the sweep."""
    robot = sweepik.load_robot("ur5")
    Q = in_limit_configurations(robot, 30, np.random.default_rng(29))
    Q[:10, 4], Q[10:20, 4], Q[20:, 4] = 1e-7, -3e-8, 0.0
    for q, sols in zip(Q, sweepik.solve_many(robot, robot.fk(Q)), strict=True):
        assert recovers(robot, sols, q), q.tolist()
        _check_set(robot, sols)


def test_arm_outside_the_catalogue_takes_the_general_method():
    """No structured plan: the general method solves it (tests/test_general.py); no joint can be swept."""
    rng = np.random.default_rng(3)
    rows = [("revolute", _L(rng), float(rng.uniform(20, 70)), _L(rng), 0) for _ in range(6)]
    robot = _arm(rows, rng)
    assert plans(robot) == ()
    assert sweepik.analyze(robot)["chosen"]["family"] == "general"
    q = np.full(6, 0.4)
    assert recovers(robot, sweepik.solve(robot, robot.fk(q), limits=False), q)
    with pytest.raises(NoReductionError):
        sweepik.solve(robot, robot.fk(np.zeros(6)), free_joint=0)


def test_ur_family_refused_for_its_continuum_says_so():
    """Axes 2-4 parallel with an offset wrist whose joint 6 can turn parallel to them, and no two axes meeting at
    the tool or the base (an offset a1): the closed form cannot report the continuum at q5 = 0 and no sweep fits,
    and the refusal says that (not the generic description of the catalogue)."""
    rows = [
        ("revolute", 0.1, 90, 0.089, 0),
        ("revolute", -0.425, 0, 0, 0),
        ("revolute", -0.392, 0, 0, 0),
        ("revolute", 0, 90, 0.109, 0),
        ("revolute", 0.05, -90, 0.095, 0),
        ("revolute", 0, 0, 0.082, 0),
    ]
    robot = _arm(rows, np.random.default_rng(0))
    with pytest.raises(NoReductionError, match=r"UR family.*continuum"):
        sweepik.solve(robot, robot.fk(np.full(6, 0.3)))


def test_free_joint_errors():
    robot = sweepik.load_robot("ur5")
    T = robot.fk(np.full(6, 0.3))
    with pytest.raises(NoReductionError, match=r"no decomposition sweeps \w+ \(index 0, number 1\)"):
        sweepik.solve(robot, T, free_joint=0)
    with pytest.raises(sweepik.SweepikError, match="fixes its own theta"):
        sweepik.solve(robot, T, free_joint=1, reduction="carm-d1")
    assert len(sweepik.solve(robot, T, free_joint=1, reduction="auto"))
    with pytest.raises(sweepik.SweepikError):
        sweepik.solve(robot, T, free_joint=9)
    by_name = sweepik.solve(robot, T, free_joint=robot.joint_names[1])
    by_index = sweepik.solve(robot, T, free_joint=1)
    assert same_solution_set(by_name.q, by_index.q, robot.is_revolute, robot.length_scale)


def test_origin_and_axis_chain_solves_like_its_dh_twin():
    """A chain written URDF-style (fixed origin transform + axis per joint, no DH) decomposes and solves."""
    puma = sweepik.load_robot("puma560")
    frames = puma.frames(np.zeros(6))
    joints, prev = [], np.eye(4)
    for i in range(6):
        origin = np.linalg.inv(prev) @ frames[i + 1]
        axis = (0.0, 0.0, 1.0) if i % 2 else (0.0, 0.0, -1.0)  # some axes flipped: the joint values change sign
        if axis[2] < 0:
            lower, upper = -puma.upper[i], -puma.lower[i]
        else:
            lower, upper = puma.lower[i], puma.upper[i]
        joints.append(sweepik.Joint("revolute", lower=lower, upper=upper, origin=tuple(map(tuple, origin)), axis=axis))
        prev = frames[i + 1]
    robot = sweepik.Robot("puma_urdf", joints, dh_convention="none", length_unit="m")
    flip = np.array([-1.0, 1.0, -1.0, 1.0, -1.0, 1.0])
    rng = np.random.default_rng(5)
    Q = in_limit_configurations(puma, 40, rng)
    np.testing.assert_allclose(robot.fk(Q * flip), puma.fk(Q), atol=1e-12)
    assert plans(robot)[0].closed_form
    for q, a, b in zip(Q, sweepik.solve_many(robot, puma.fk(Q)), sweepik.solve_many(puma, puma.fk(Q)), strict=True):
        assert recovers(robot, a, q * flip)
        assert same_solution_set(a.q * flip, b.q, puma.is_revolute, puma.length_scale)


def test_moving_meeting_point_is_not_used():
    """Regression: a prismatic theta* between joints 2 and 4 that does not slide along joint 4's axis moves the
    point where axes 2 and 4 meet; the bc_int case (which rebuilds that point from one sample) must not apply."""
    points = [(0.2, 0, 0), (0, 0, 0.5), (0, 0, 0.5), (0, 0.3, 0.5), (0, 0.6, 1.0), (0, 0.6, 1.0)]
    axes = [(0, 0, 1), (0, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 0), (0, 0, 1)]
    kinds = ["revolute", "revolute", "prismatic", "revolute", "revolute", "revolute"]
    joints, prev = [], np.zeros(3)
    for i in range(6):
        origin = np.eye(4)
        origin[:3, 3] = np.array(points[i]) - prev
        prev = np.array(points[i])
        lo, hi = (-np.pi, np.pi) if kinds[i] == "revolute" else (-0.4, 0.4)
        joints.append(
            sweepik.Joint(
                kinds[i], lower=lo, upper=hi, origin=tuple(map(tuple, origin)), axis=axes[i], name=f"j{i + 1}"
            )
        )
    robot = sweepik.Robot("moving_meet", joints, dh_convention="none", length_unit="m")
    assert not any(p.case == "bc_int" and p.free == 2 and not p.reversed for p in plans(robot))
    Q = in_limit_configurations(robot, 20, np.random.default_rng(0))
    # (no structured plan left: the general method answers, and must give every configuration back)
    for q, sols in zip(Q, sweepik.solve_many(robot, robot.fk(Q)), strict=True):
        assert recovers(robot, sols, q)


def test_swept_slide_range_counts_the_other_slides():
    """A rail along the Stanford arm's first axis, its last joint held: PRRPRR with the rail swept. The rail's
    search range must include the travel of the arm's own slide (d3): without it, 12 of 20 poses were answered
    'unreachable'."""
    from sweepik.model.origin_axis import hold_joints, origin_axis_form
    from sweepik.model.robot import Joint, Robot

    st = origin_axis_form(sweepik.load_robot("stanford"))
    rail = Joint(
        "prismatic", lower=-0.5, upper=0.5, name="rail", origin=tuple(map(tuple, np.eye(4))), axis=st.joints[0].axis
    )
    robot = Robot(
        "rail+stanford",
        (rail, *st.joints),
        dh_convention="none",
        T_flange_tool=st.T_flange_tool,
        length_unit=st.length_unit,
    )
    held = hold_joints(robot, {6: 0.4})
    assert sweepik.analyze(held.arm)["chosen"]["free_joint_name"] == "rail"
    rng = np.random.default_rng(3)
    Q = in_limit_configurations(held.arm, 40, rng)
    for q, sols in zip(Q, sweepik.solve_many(held.arm, held.arm.fk(Q)), strict=True):
        assert recovers(held.arm, sols, q), q
