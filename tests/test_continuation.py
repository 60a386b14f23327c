"""Continua along a joint other than theta*, traced numerically (sweepik.engine.continuation): the automatic
decomposition
of the C-Arm (rail swept) on its theta2 self-motion, the closed-form wrist arm (carm_swapped) on its own, joint
limits on the traced joint, batches, and no false alarm at random poses. The traced members are checked against an
independent reduction (the hand-written carm-theta2, which sweeps theta2) and by forward kinematics."""

from __future__ import annotations

import copy
import time
import tomllib
from importlib import resources

import numpy as np
import pytest
from oracles import numpy_engine
from singular import recovered

from sweepik import SweepikError, load_robot, solve, solve_many
from sweepik.engine.chunk import chain_poses as _chain_poses
from sweepik.engine.settings import ACCEPT_TOL_REL
from sweepik.io.robot_file import robot_from_dict
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.units import orientation_weight
from sweepik.reductions import get_reduction
from sweepik.results import joint_distance

CARM = load_robot("carm")
#: "the same configuration": every joint within this (mm, radians modulo 2 pi)
SAME = 1e-7


def on_theta2_self_motion(robot, rng: np.random.Generator, n: int) -> np.ndarray:
    """In-limit configurations with theta3 = 0 and theta4 = -90 deg (joint 5's axis on joint 2's: theta2 free)."""
    q = rng.uniform(robot.lower, robot.upper, (n, 6))
    q[:, 2], q[:, 3] = 0.0, -np.pi / 2
    return q


def member_of(robot, sol, q: np.ndarray) -> bool:
    """``q`` is a member of one of ``sol``'s families (its free joint's value wrapped onto the family's interval)."""
    for f in sol.families:
        th = q[f.free_joint]
        if robot.is_revolute[f.free_joint]:
            th = np.mod(th + np.pi, 2.0 * np.pi) - np.pi
        lo, hi = f.interval
        if lo - SAME <= th <= hi + SAME and joint_distance(robot, f.at(np.clip(th, lo, hi)), q).max() <= SAME:
            return True
    return False


def assert_members_certified(robot, sol, T: np.ndarray, count: int = 25, limits: bool = True) -> None:
    for f in sol.families:
        m = f.sample(count)
        err = pose_error_geodesic(robot.fk(m), np.broadcast_to(T, (count, 4, 4)), orientation_weight(robot.length_unit))
        # (the solver's acceptance, with room for this test's own forward kinematics: a different rounding)
        assert err.max() <= 4.0 * ACCEPT_TOL_REL * robot.length_scale
        assert np.all(robot.within_limits(m)) or not limits


def test_traced_family_agrees_with_an_independent_reduction() -> None:
    """The automatic decomposition's traced theta2 family and carm-theta2's swept one: the same members."""
    for q in on_theta2_self_motion(CARM, np.random.default_rng(3), 4):
        T = CARM.fk(q)
        auto, ref = solve(CARM, T, reduction="auto"), solve(CARM, T, reduction="carm-theta2")
        assert [f.free_joint for f in auto.families] == [1] and len(ref.families) == 1
        assert auto.families[0].interval == pytest.approx(ref.families[0].interval)
        assert len(auto) == len(ref) == 0  # (every solution is a member)
        th = np.linspace(-3.1, 3.1, 13)
        d = joint_distance(CARM, auto.families[0].at(th), ref.families[0].at(th))
        assert d.max() <= SAME
        assert member_of(CARM, auto, q)
        assert_members_certified(CARM, auto, T)


def test_batch_on_the_self_motion() -> None:
    """A batch of poses on the self-motion gives each pose its family. (Many candidates each: the poses are redone by
    the NumPy engine, and so are some of them in the search of their margins' zeros, whose swing samples must follow
    the poses redone; these 12 made ``solve_many`` raise a ValueError before.)"""
    q = on_theta2_self_motion(CARM, np.random.default_rng(5), 12)
    sols = solve_many(CARM, CARM.fk(q), reduction="auto")
    for i, sol in enumerate(sols):
        assert member_of(CARM, sol, q[i]), i


def test_closed_form_with_a_position_continuum() -> None:
    """carm_swapped (a spherical wrist: a closed form) with theta3 = 0: the wrist centre on joint 2's axis, theta2
    free. The closed form gives isolated members; the continuum is traced along theta2."""
    robot = load_robot("carm_swapped")
    assert get_reduction(robot, None).closed_form
    rng = np.random.default_rng(5)
    q = rng.uniform(robot.lower, robot.upper, (6, 6))
    q[:, 2] = 0.0
    for qi in q:
        T = robot.fk(qi)
        sol = solve(robot, T)
        assert any(f.free_joint == 1 for f in sol.families)
        assert member_of(robot, sol, qi)
        assert_members_certified(robot, sol, T)


def _carm_with_theta2_limits(lo: float, hi: float):
    data = copy.deepcopy(tomllib.loads((resources.files("sweepik.io") / "robots" / "carm.toml").read_text()))
    data["joints"][1]["limits"] = [lo, hi]
    data["name"] = "carm_theta2_limited"
    return robot_from_dict(data, "variant.toml")


def test_traced_family_cut_to_the_limits() -> None:
    """theta2 limited to [-60, 120] deg: the traced family is the limited stretch, with and without limits."""
    robot = _carm_with_theta2_limits(-60.0, 120.0)
    q = on_theta2_self_motion(robot, np.random.default_rng(6), 3)
    for qi in q:
        T = robot.fk(qi)
        sol = solve(robot, T, reduction="auto")
        assert [f.interval for f in sol.families] == [pytest.approx(np.radians([-60.0, 120.0]))]
        assert member_of(robot, sol, qi)
        f = sol.families[0]
        assert joint_distance(robot, f.at(qi[1] + 2.0 * np.pi), qi).max() <= SAME  # (by whole turns)
        with pytest.raises(SweepikError, match="outside the family's interval"):
            f.at(np.pi)  # (180 deg: off [-60, 120] deg, any number of turns away)
        assert_members_certified(robot, sol, T)
        free = solve(robot, T, reduction="auto", limits=False)
        assert [f.interval for f in free.families] == [pytest.approx((-np.pi, np.pi))]


@pytest.mark.parametrize("name", ["carm", "fanuc_crx10ia", "kinova_jaco2", "carm_swapped", "abb_irb140"])
def test_no_continuum_at_random_poses(name: str) -> None:
    """Away from the special sets no candidate leaves another joint free: nothing is traced."""
    robot = load_robot(name)
    red = get_reduction(robot, "auto")
    q = np.random.default_rng(7).uniform(robot.lower, robot.upper, (300, 6))
    chain = _chain_poses(robot, robot.fk(q))
    pose = np.repeat(np.arange(300), red.n_branches)
    branch = np.tile(np.arange(red.n_branches), 300)
    theta = q[pose, red.free_joint]  # (candidates' theta*: the generating ones)
    assert red.continuum_joints(chain, pose, theta, branch) is None


def _elbow_manipulator():
    """The PUMA 560 without its shoulder offsets (axes 1 and 2 meet): a spherical-wrist closed form whose shoulder
    singularity (the wrist centre on joint 1's axis) leaves joint 1 free."""
    data = copy.deepcopy(tomllib.loads((resources.files("sweepik.io") / "robots" / "puma560_std.toml").read_text()))
    data["joints"][2]["a"], data["joints"][2]["d"] = 0.0, 0.0
    for joint in data["joints"]:
        joint["limits"] = [-180.0, 180.0]
    data["name"] = "elbow_manipulator"
    return robot_from_dict(data, "variant.toml")


def test_shoulder_singularity_of_an_elbow_manipulator() -> None:
    """The wrist centre on joint 1's axis (q3 chosen, q2 solved for it by bisection): four families along joint 1
    (two elbows, two wrists), each certified, one of them holding the generating configuration."""
    from scipy.optimize import brentq

    from sweepik.model.kinematics import chain_frames

    robot = _elbow_manipulator()
    rng = np.random.default_rng(8)
    for _ in range(4):
        q = rng.uniform(-np.pi, np.pi, 6)

        def off_axis(q2: float, q: np.ndarray = q) -> float:  # (x of the wrist centre at q1 = 0: the x-z plane)
            qq = q.copy()
            qq[0], qq[1] = 0.0, q2
            return float(chain_frames(robot, qq[None])[0, 4, 0, 3])

        x = np.linspace(-np.pi, np.pi, 181)
        v = np.array([off_axis(t) for t in x])
        k = int(np.nonzero(v[:-1] * v[1:] < 0)[0][0])
        q[1] = brentq(off_axis, x[k], x[k + 1], xtol=1e-15)
        T = robot.fk(q)
        sol = solve(robot, T)
        assert len(sol.families) == 4 and all(f.free_joint == 0 for f in sol.families)
        assert member_of(robot, sol, q)
        assert_members_certified(robot, sol, T)


@pytest.mark.parametrize("limits", [True, False])
def test_wrist_continuum_the_fallback_sweep_cuts(limits: bool) -> None:
    """carm_swapped on its wrist singularity (theta5 = 90 deg: a continuum along joint 4) with its elbow nearly
    straight (theta3 ~ 0.01 rad), where the fallback sweep of joint 4 loses digits and returned the continuum as short
    pieces: traced from them, the whole continuum is one family holding the generating configuration. Also a batch
    of random poses on that singularity."""
    robot = load_robot("carm_swapped")
    near_straight = np.array(
        [
            [1518.417, -0.0271, 0.0175, -0.4086, np.pi / 2, -2.7027],
            [1923.6208, 2.8781, -0.0117, -1.107, np.pi / 2, 0.5497],
        ]
    )
    rng = np.random.default_rng(3)
    q = rng.uniform(robot.lower, robot.upper, (60, 6))
    q[:, 4] = np.pi / 2
    q = np.concatenate([near_straight, q])
    sols = solve_many(robot, robot.fk(q), limits=limits)
    for i, sol in enumerate(sols):
        assert member_of(robot, sol, q[i]) or joint_distance(robot, sol.q, q[i]).max(axis=-1).min() <= SAME, i
    for i in range(2):
        assert member_of(robot, sols[i], q[i])
        assert_members_certified(robot, sols[i], robot.fk(q[i]), limits=limits)


def _stanford_like(rng: np.random.Generator, slide: tuple[float, float] = (-0.5, 1.5)) -> object:
    """RRP + spherical wrist (the Stanford arm's structure) of random lengths, its slide's travel through 0: there
    the wrist centre sits on joint 2's axis."""
    L = [float(x) for x in rng.uniform(0.1, 0.8, 3)]
    rows = [
        ("revolute", 0.0, -90.0, L[0], 0.0),
        ("revolute", 0.0, 90.0, L[1], 0.0),
        ("prismatic", 0.0, 0.0, 0.0, 0.0),
        ("revolute", 0.0, -90.0, 0.0, 0.0),
        ("revolute", 0.0, 90.0, 0.0, 0.0),
        ("revolute", 0.0, 0.0, L[2], 0.0),
    ]
    joints = [
        {"name": f"j{i + 1}", "type": t, "limits": list(slide) if t == "prismatic" else [-180.0, 180.0]}
        | {"a": a, "alpha": al, "d": d, "theta": th}
        for i, (t, a, al, d, th) in enumerate(rows)
    ]
    return robot_from_dict({"name": "rrp", "dh_convention": "standard", "length_unit": "m", "joints": joints})


@pytest.mark.parametrize("seed", range(3))
def test_final_step_continuum_of_a_stanford_like_arm(seed: int) -> None:
    """The slide at 0 puts the wrist centre on joint 2's axis, which the closed form turns last (sp1): joint 2 is free
    as far as the wrist centre goes, and the spherical wrist follows it, a continuum along joint 2. It is reported as
    families along joint 2 holding the generating configuration, every member certified (before: two or four
    isolated members of it). A pose off that set has no family."""
    rng = np.random.default_rng(seed)
    robot = _stanford_like(rng)
    q = rng.uniform(robot.lower, robot.upper, (4, 6))
    q[:, 2] = 0.0
    q[:, 4] = np.where(np.abs(q[:, 4]) < 0.2, 0.5, q[:, 4])  # (off the wrist's own singularity)
    for qq in q:
        T = robot.fk(qq)
        sol = solve(robot, T)
        assert sol.families and all(f.free_joint == 1 for f in sol.families)
        assert member_of(robot, sol, qq)
        assert_members_certified(robot, sol, T)
    off = q[0].copy()
    off[2] = 0.3
    assert not solve(robot, robot.fk(off)).families


def test_traced_family_passes_where_another_singular_set_crosses() -> None:
    """carm_swapped at theta3 = 0 (its theta2 self-motion) with theta2 = -90 deg: there the continuum crosses another
    singular set, where Newton converges only linearly. The traced families still pass through theta2 = -90 deg (the
    tracing used to stop ~1e-3 short of it on both sides, and the members in between went missing), and their
    members there are certified."""
    robot = load_robot("carm_swapped")
    q = np.array([1723.468, -np.pi / 2, 0.0, -2.2781, -1.8677, -0.6575])
    T = robot.fk(q)
    sol = solve(robot, T, limits=False)
    assert sol.families
    for f in sol.families:
        assert f.free_joint == 1 and f.interval[0] <= -np.pi / 2 <= f.interval[1]
        m = f.at(-np.pi / 2)
        err = pose_error_geodesic(robot.fk(m[None]), T[None], orientation_weight(robot.length_unit))
        assert err[0] <= 4.0 * ACCEPT_TOL_REL * robot.length_scale


@pytest.mark.parametrize("limits", [False, True])
def test_wrist_continuum_traced_from_a_member_at_a_second_singularity(limits: bool) -> None:
    """PUMA 560 with A4 = 0 and A5 = 0 (issue 35): axes 2, 3 and 5 parallel as well as the wrist straight. With the
    limits on, the one seed left is a member whose A5 is 9e-7 (the root of the rounding), where the wrist continuum's
    direction is the second smallest singular one: it came back as that one isolated solution. Now the continuum is
    reported, cut to joint 4's limits, every member a solution."""
    arm = load_robot("puma560")
    q = np.array([2.3568597051599407, 0.6302471995232901, 1.6177742441429797, 2.3660966733039746, 0.0,
                  -0.6885664195971763])  # fmt: skip
    T = arm.fk(q)
    s = solve(arm, T, limits=limits)
    fam = [f for f in s.families if f.free_joint == 3]
    assert fam, s
    f = fam[0]
    if limits:
        np.testing.assert_allclose(f.interval, (arm.lower[3], arm.upper[3]), atol=1e-9)
    m = f.at(np.linspace(f.interval[0], f.interval[1], 9))
    err = pose_error_geodesic(arm.fk(m), np.broadcast_to(T, (9, 4, 4)), orientation_weight(arm.length_unit))
    assert np.all(err <= ACCEPT_TOL_REL * arm.length_scale)
    assert np.any(np.max(np.abs(joint_distance(arm, f.at(q[3:4]), q)), axis=-1) < 1e-6)


@pytest.mark.parametrize(
    "q",
    [
        [399.0308879364266, 2.7778786000458915, 3.1415925535886777, -2.478746263017324, 0.8112104407914167,
         2.683891211730887],
        [1305.229152673277, -1.4209480208846816, -3.141592753589775, 2.788486605067879, -2.3447772999628302,
         2.2919696260401583],
        [1642.2061767892776, 3.0274166388510366, 1.0000032334890302e-07, -0.4768530155683983, 3.013973045327825,
         2.9781318484005785],
    ],
)  # fmt: skip
def test_numerical_continuum_next_to_a_self_motion(q: list[float]) -> None:
    """carm_swapped with its elbow 1e-7 rad off its theta2 self-motion (issue 35): the solutions around the
    configuration form stretches of numerical continuum along theta2 (every member solves the pose to the
    certification), which the closed form's candidates flag only with ``CONTINUUM_AMPLITUDE`` above their 1e-7:
    before, 8 isolated solutions came back, none of them this configuration (0.002 to 0.1 rad away)."""
    from singular import recovered

    arm = load_robot("carm_swapped")
    q_ = np.array(q)
    T = arm.fk(q_)
    s = solve(arm, T, limits=False)
    assert recovered(arm, s, q_)
    w = orientation_weight(arm.length_unit)
    for f in s.families:
        m = f.at(np.linspace(f.interval[0], f.interval[1], 9))
        err = pose_error_geodesic(arm.fk(m), np.broadcast_to(T, (9, 4, 4)), w)
        # (an end sits where members stop being certified: another FK's rounding can put it a hair over)
        assert np.all(err <= 1.01 * ACCEPT_TOL_REL * arm.length_scale), (err / (ACCEPT_TOL_REL * arm.length_scale), f)


@pytest.mark.parametrize(
    "q",
    [
        [0.8368222606646678, 2.9369867087557644, 3.165758277459611e-11 - 1e-7, -0.6809412564547146,
         4.7165911145115574e-05, -0.9678576828074092],
        [-0.7814705648545721, -0.37248370770586936, 2.8268058841444838e-09 + 1e-7, 0.6973900543544262,
         3.341919253568343e-05, 0.9988520203934721],
    ],
)  # fmt: skip
def test_trace_past_a_first_step_that_jumps_where_a_nearly_straight_wrist_swings(q: list[float]) -> None:
    """The Stanford arm with its slide 1e-7 off d3 = 0 and the wrist 3e-5 ... 5e-5 rad from straight: no isolated
    solution, a numerical continuum along theta2 through the configuration (every member solves the pose to
    rounding). The trace's first step from the seed (``PROBE_STEP`` of a step, 3.8e-4 rad) reached the pose but jumped
    0.47 (the wrist's joints 4 and 6 swing fast there: ``TRACE_JUMP`` is 0.25), and steps were not halved below the
    probe's, so the family stopped at its seed, 4.4e-4 rad short of the configuration. A first step that reaches the
    pose now lets the steps halve."""
    from singular import recovered

    arm = load_robot("stanford")
    q_ = np.array(q)
    T = arm.fk(q_)
    s = solve(arm, T, limits=False)
    assert s.families and recovered(arm, s, q_)


def test_compiled_trace_follows_the_reference() -> None:
    """The compiled side of a trace (``continuation._side``) and its NumPy reference follow the same continuum
    to the same ends (the trace's resolution), their members solving the pose; a small buffer hands the compiled
    trace on several times."""
    import sweepik.engine.continuation as cont
    from sweepik.engine.settings import ACCEPT_TOL_REL, TRACE_HALVINGS, TRACE_STEPS

    robot = load_robot("carm")
    q0 = on_theta2_self_motion(robot, np.random.default_rng(2), 1)[0]
    world = robot.fk(q0)
    tol = ACCEPT_TOL_REL * robot.length_scale
    h0 = 2.0 * np.pi / TRACE_STEPS
    buffer = cont._BUFFER
    try:
        cont._BUFFER = 7
        for sign in (1.0, -1.0):
            xs_c, qs_c, done_c = cont._side(robot, world, float(q0[1]), q0, 1, sign, np.pi, h0, tol)
            xs_p, qs_p, done_p = numpy_engine.trace_side(robot, world, float(q0[1]), q0, 1, sign, np.pi, h0, tol)
            assert abs(done_c - done_p) <= 2.0 * h0 * 2.0**-TRACE_HALVINGS
            assert xs_c.size > 7  # (handed on)
            assert np.all(np.diff(xs_c) * sign > 0)
            err = pose_error_geodesic(
                robot.fk(qs_c), np.broadcast_to(world, (len(qs_c), 4, 4)), orientation_weight(robot.length_unit)
            )
            assert np.all(err <= tol)
    finally:
        cont._BUFFER = buffer


@pytest.mark.parametrize(
    ("name", "k", "q", "limits"),
    [
        ("kuka_iiwa14", 0, (0.2, 0.3, 0.4, 0.0, -0.5, 0.0, 1.0), True),
        ("kuka_iiwa14", 0, (0.2, 0.3, 0.4, 0.0, -0.5, 0.0, 1.0), False),
        ("franka_panda", 5, (0.0, 0.0, 0.0, 0.0, 0.0, 0.5, 0.0), True),
        ("franka_panda", 5, (0.1, 0.0, -0.3, 0.0, 0.4, 0.9, 0.2), False),
    ],
)
def test_a_self_motion_of_two_dimensions_is_answered(
    name: str, k: int, q: tuple[float, ...], limits: bool
) -> None:  # fmt: skip
    """Three axes on one line, a self-motion of two dimensions (any share of their angles' sum): a Kuka iiwa held at
    A1 with A4 and A6 at 0 (axes 3, 5 and 7), a Panda held at joint 6 with joints 2 and 4 at 0 (axes 1, 3 and 5; joint
    4 outside its limits). Each of the sweep's candidates lay on a curve of it of its own: each was traced and the
    seeds left filtered against every family traced before (the Panda's: more than 25 minutes), and the fallback
    sweep's search, its residual zero along stretches of every slice, was redone with buffers grown to millions of
    candidates (minutes). Now seconds (``settings.MAX_TRACES``, ``REDO_MAX_FOUND``: the fallback's overflow leaves
    the closed form's answer; the bound here only catches a hang): every solution and family member reaches the pose,
    and the configuration is recovered where it is inside the limits."""
    robot = load_robot(name)
    qq = np.array(q)
    T = robot.fk(qq)
    start = time.perf_counter()
    sol = solve(robot, T, locked={k: q[k]}, limits=limits)
    assert time.perf_counter() - start < 120.0
    tol = 1e-9 * robot.length_scale
    assert len(sol) == 0 or pose_error_geodesic(robot.fk(sol.q), T, 1.0).max() <= tol
    for f in sol.families:
        assert pose_error_geodesic(robot.fk(f.at(np.linspace(*f.interval, 5))), T, 1.0).max() <= tol
    if robot.within_limits(qq) or not limits:
        assert recovered(robot, sol, qq)


def test_a_fallback_batch_that_overflows_goes_pose_by_pose(monkeypatch: pytest.MonkeyPatch) -> None:
    """``chunk._answered``: where the fallback's search overflows on a batch, its poses are solved one by one, and
    only the pose that overflows alone is left to the reduction that handed it over."""
    from sweepik.engine import chunk
    from sweepik.errors import SearchOverflowError

    poses = np.stack([np.eye(4) * (1.0 + i) for i in range(4)])  # (pose i marked i + 1)

    def solved(robot, red, chunk_poses, *args):  # type: ignore[no-untyped-def]
        if np.any(chunk_poses[:, 0, 0] == 3.0):  # (pose 2's search overflows)
            raise SearchOverflowError("the search of 'x' found more than 1 isolated candidates")
        return [float(p[0, 0]) for p in chunk_poses]

    monkeypatch.setattr(chunk, "solve_chunk", solved)
    idx = np.array([0, 2, 3], dtype=np.intp)
    got = [(i.tolist(), b) for i, b in chunk._answered(None, None, poses, idx, "precise", True, 64)]
    assert got == [([0], [1.0]), ([3], [4.0])]
    assert [(i.tolist(), b) for i, b in chunk._answered(None, None, poses, idx[:1], "precise", True, 64)] == [
        ([0], [1.0])
    ]
    assert list(chunk._answered(None, None, poses, np.array([2]), "precise", True, 64)) == []


def test_a_reductions_own_search_is_not_capped() -> None:
    """The cap on a search's isolated candidates is the fallback's alone (``search.candidates_capped``): the Kinova
    Gen3 held at joint 2 at its zero pose, whose own sweep's candidates pass it, is still answered (a first version
    of the cap raised ``SearchOverflowError`` there)."""
    robot = load_robot("kinova_gen3")
    q = np.zeros(7)
    sol = solve(robot, robot.fk(q), locked={1: 0.0})
    assert recovered(robot, sol, q)
