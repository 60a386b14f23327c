"""Self-motion families: from the sweep's spans (runs of theta* along which a branch solves the pose) to
``Family`` objects cut to the members that are certified by forward kinematics and inside the joint limits.
A piece that shrinks to a point where a family touches the limits becomes an isolated solution."""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import certify
from sweepik.engine.candidates import Spans
from sweepik.engine.dedupe import inside_limits
from sweepik.engine.settings import (
    ACCEPT_TOL_REL,
    CLUSTER_FAMILY_REL,
    CONTINUUM_LINK,
    CONTINUUM_THIN,
    CORNER_BISECT,
    CUT_BISECT,
    DIP_STEPS,
    FAMILY_SAMPLES,
    INNER_PROBES,
    MAX_ISOLATED_SOLUTIONS,
    MEMBER_TOL,
    NEAR_FAMILY_SAMPLES,
    NUDGE_REL,
    PEAK_REACH,
    PEAK_STEPS,
)
from sweepik.model.pose import pose_error_geodesic
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions import Reduction
from sweepik.results import Family, joint_distance, thetas_inside

Array = NDArray[np.float64]


def family_members(
    robot: Robot, red: Reduction, chain: Array, pose: NDArray[np.intp], branch: NDArray[np.intp], theta: Array
) -> Array:
    """Members ``(K, n)`` at ``theta (K,)`` of the families (pose, branch) (compiled where possible)."""
    if red.uses_kernel:
        return certify.configurations(robot, red, chain, pose, theta, branch)
    return red.solve_rest(chain[pose], theta[:, None], branch[:, None])[:, 0]


def certified_members(red: Reduction, chain_pose: Array, branch: int, theta: Array, lo: float, hi: float) -> Array:
    """Members ``(K, n)`` at ``theta (K,)`` (inside ``[lo, hi]``) of one family (chain pose ``(4, 4)``, branch),
    each certified by FK: one that is not is replaced by the member ``NUDGE_REL (hi - lo)`` further in, or back
    (if neither is a solution, it is left as it is)."""
    if getattr(red, "corrected", None) is None:
        lo_, hi_ = np.array([lo], dtype=np.float64), np.array([hi], dtype=np.float64)
        return certified_members_of(red, chain_pose[None], np.array([branch], dtype=np.intp), theta[None], lo_, hi_)[0]
    robot = red.robot
    tol = ACCEPT_TOL_REL * robot.length_scale  # (the solver's own acceptance of a solution)
    branches = np.full(theta.size, branch, dtype=np.intp)

    def members(x: Array) -> tuple[Array, NDArray[np.bool_]]:
        own = _own_errors(red, chain_pose[None], x[None], branches[None, : x.size])
        assert own is not None
        return own[0][0], np.all(np.isfinite(own[0][0]), axis=-1) & (own[1][0] <= tol)

    q, ok = members(theta)
    bad = np.nonzero(~ok)[0]
    step = NUDGE_REL * max(hi - lo, 1.0)
    for sign in (1.0, -1.0):
        if bad.size == 0:
            break
        x = np.clip(theta[bad] + sign * step, lo, hi)
        qn, okn = members(x)
        q[bad[okn]] = qn[okn]
        bad = bad[~okn]
    return q


def certified_members_of(
    red: Reduction, chains: Array, branch: NDArray[np.intp], theta: Array, lo: Array, hi: Array
) -> Array:
    """``certified_members`` of ``F`` families of one reduction at once (one without members of its own,
    ``Traced.corrected``): chain poses ``(F, 4, 4)``, branches, ``theta (F, M)``, intervals ``lo``, ``hi (F,)``;
    members ``(F, M, n)``, each the value ``certified_members`` gives."""
    robot = red.robot
    tol = ACCEPT_TOL_REL * robot.length_scale  # (the solver's own acceptance of a solution)
    F, M = theta.shape
    pose, br, x = np.repeat(np.arange(F), M), np.repeat(branch, M), theta.ravel()

    world = robot.T_world_base @ chains @ robot.T_flange_tool if red.uses_kernel else chains

    def members(rows: NDArray[np.intp], xr: Array) -> tuple[Array, NDArray[np.bool_]]:
        if red.uses_kernel:  # (compiled: configuration, FK and error per member, as ``_certified``)
            q, err, _ = certify.certify(robot, red, chains, world, pose[rows], xr, br[rows], paper=False)
            return q, np.all(np.isfinite(q), axis=-1) & (err <= tol)
        q = family_members(robot, red, chains, pose[rows], br[rows], xr)
        return q, _solve_chain(robot, q, chains[pose[rows]], tol)

    q, ok = members(np.arange(x.size), x)
    bad = np.nonzero(~ok)[0]
    step = NUDGE_REL * np.maximum(hi - lo, 1.0)
    for sign in (1.0, -1.0):
        if bad.size == 0:
            break
        f = pose[bad]
        qn, okn = members(bad, np.clip(x[bad] + sign * step[f], lo[f], hi[f]))
        q[bad[okn]] = qn[okn]
        bad = bad[~okn]
    return q.reshape(F, M, -1)


def members_at(families: Sequence[Family], theta: Sequence[Array]) -> list[Array]:
    """``[f.at(t) for f, t in zip(families, theta)]``, the same values; the families of one reduction whose members
    are the engine's (``certified_members``, no joints held, no members of the reduction's own) and asked at as many
    values at once (``certified_members_of``: one call for a batch's families, not one each)."""
    out: list[Array] = [np.zeros((0, 0))] * len(families)
    groups: dict[tuple[int, int], list[int]] = {}
    for k, (f, t) in enumerate(zip(families, theta, strict=True)):
        if f.members is certified_members and f.held is None and getattr(f.reduction, "corrected", None) is None:
            groups.setdefault((id(f.reduction), np.size(t)), []).append(k)
        else:
            out[k] = f.at(t)
    for ks in groups.values():
        fs = [families[k] for k in ks]
        red = fs[0].reduction
        lo, hi = np.array([f.interval for f in fs], dtype=np.float64).T
        th = np.array([np.asarray(theta[k], dtype=np.float64).reshape(-1) for k in ks])
        th = thetas_inside(lo[:, None], hi[:, None], red.periodic, th)
        chains = np.array([f.chain_pose for f in fs])
        branch = np.array([f.branch for f in fs], dtype=np.intp)
        q = red.robot.wrap(certified_members_of(red, chains, branch, th, lo, hi))
        for j, k in enumerate(ks):
            out[k] = q[j].reshape(*np.shape(theta[k]), -1)
    return out


def _solve_chain(robot: Robot, q: Array, chain: Array, tol: float) -> NDArray[np.bool_]:
    """``q (..., n)`` are finite and solve the chain poses ``chain`` (broadcast against ``(..., 4, 4)``) within
    ``tol`` (geodesic error of the flange frame; NumPy)."""
    qz = np.nan_to_num(q)
    flange = certify.flange_poses(robot, qz.reshape(-1, qz.shape[-1])).reshape(*qz.shape[:-1], 4, 4)
    err = pose_error_geodesic(robot.T_base_world @ flange, chain, orientation_weight(robot.length_unit))
    return np.asarray(np.all(np.isfinite(q), axis=-1) & (err <= tol))


def _certified(
    robot: Robot,
    red: Reduction,
    chain: Array,
    world: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    theta: Array,
    tol: float,
) -> tuple[NDArray[np.bool_], Array]:
    """``theta (K, M)``: whether the members exist and are certified by FK (error <= ``tol``), and the members
    ``(K, M, n)`` (NaN made 0)."""
    if red.uses_kernel:
        # compiled: configuration, FK and error per member (flange frame compared with the chain pose)
        M = theta.shape[1]
        flat_p = np.repeat(pose, M)
        flat_b = np.repeat(branch, M)
        # every member certified by FK: a family from a vanishing residual can still hold a point where the
        # branch's closed form breaks down (e.g. the wrist crossing joint 2's axis on the C-Arm)
        q, err, _ = certify.certify(robot, red, chain, world, flat_p, theta.ravel(), flat_b, paper=False)
        q = q.reshape(*theta.shape, robot.n_joints)
        ok = np.all(np.isfinite(q), axis=-1) & (err <= tol).reshape(theta.shape)
    else:
        br = np.broadcast_to(branch[:, None], theta.shape)
        own = _own_errors(red, chain[pose], theta, br)
        if own is not None:
            q, ok = own[0], np.all(np.isfinite(own[0]), axis=-1) & (own[1] <= tol)
        else:
            q = red.solve_rest(chain[pose], theta, br)
            ok = _solve_chain(robot, q, chain[pose][:, None], tol)
    return ok, np.nan_to_num(q)


def _own_errors(red: Reduction, chain: Array, theta: Array, branch: NDArray[np.intp]) -> tuple[Array, Array] | None:
    """The members ``(K, M, n)`` and pose errors ``(K, M)`` of a reduction whose members come with their own (a traced
    continuum's, from the Newton steps that made them: ``continuation.Traced.corrected``), else None."""
    corrected = getattr(red, "corrected", None)
    return None if corrected is None else corrected(chain, theta, branch)


def _members_ok(
    robot: Robot,
    red: Reduction,
    chain: Array,
    world: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    theta: Array,
    limits: bool,
    tol: float,
) -> NDArray[np.bool_]:
    """``theta (K, M)``: members exist, are certified by FK (error <= ``tol``) and (with limits) lie inside the
    limits."""
    ok, qz = _certified(robot, red, chain, world, pose, branch, theta, tol)
    return np.asarray(ok & inside_limits(robot, qz)) if limits else ok


def _members_excess(
    robot: Robot,
    red: Reduction,
    chain: Array,
    world: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    theta: Array,
    limits: bool,
    tol: float,
) -> tuple[NDArray[np.bool_], Array]:
    """``_members_ok``, and each joint's limit excess ``(K, M, n)``: how far its wrapped value lies outside its
    limits widened by their tolerance (<= 0 inside), NaN where a member is not certified or without ``limits``."""
    ok, qz = _certified(robot, red, chain, world, pose, branch, theta, tol)
    if not limits:
        return ok, np.full(qz.shape, np.nan)
    inside = inside_limits(robot, qz)
    over = robot.limit_excess(qz) - robot.limit_tol
    return ok & inside, np.where(ok[..., None], over, np.nan)


_GOLDEN = 0.5 * (np.sqrt(5.0) - 1.0)


def _locate_cuts(
    robot: Robot,
    red: Reduction,
    chain: Array,
    world: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    a: Array,
    b: Array,
    steps: int,
    limits: bool,
    tol: float,
) -> tuple[Array, Array]:
    """Where each family piece ends between ``a`` (a member that is a certified solution, inside the limits with
    ``limits``: ``_members_ok``) and ``b`` (one that is not), to ``2**-steps |b - a|``: ``(a, b)`` narrowed (new
    arrays), ``a`` still certified and ``b`` not. Bisection, except where the piece ends at a joint limit: there a
    false-position step (Illinois) on the limit excess of the joint furthest outside at ``b`` (smooth in theta*,
    <= 0 at ``a``, > 0 at ``b``) takes ~10 member evaluations instead of ``steps``. The step is kept at least half
    the target width from the ends, so that a bracket with an end next to the cut closes at once; where the last
    three steps together did not halve the bracket, the next one bisects (at most ``3 steps + 3`` steps). The NumPy
    reference of ``certify.locate_cuts``."""
    a, b = np.array(a, dtype=np.float64), np.array(b, dtype=np.float64)
    K, n = a.size, robot.n_joints
    target = np.ldexp(np.abs(b - a), -steps)

    def member(x: Array, k: NDArray[np.intp]) -> tuple[NDArray[np.bool_], Array]:
        on, g = _members_excess(robot, red, chain, world, pose[k], branch[k], x[:, None], limits, tol)
        return on[:, 0], g[:, 0]

    every = np.arange(K)
    ga, gb = np.full((K, n), np.nan), np.full((K, n), np.nan)  # each joint's limit excess at a and b
    if limits and K:
        ga, gb = member(a, every)[1], member(b, every)[1]
    w1, w2, w3 = np.full(K, np.inf), np.full(K, np.inf), np.full(K, np.inf)  # widths 1, 2 and 3 steps ago
    side = np.zeros(K, dtype=np.int8)
    for _ in range(3 * steps + 3):
        w = np.abs(b - a)
        k = np.nonzero(w > target)[0]
        if k.size == 0:
            break
        wk = w[k]
        js = np.argmax(np.nan_to_num(gb[k], nan=-np.inf), axis=1)  # (all NaN: no interpolation below)
        gak, gbk = ga[k, js], gb[k, js]
        with np.errstate(invalid="ignore", divide="ignore"):
            interp = (gak <= 0.0) & (gbk > 0.0) & (wk <= 0.5 * w3[k])
            tmin = 0.5 * target[k] / wk
            t = np.where(interp, np.minimum(np.maximum(gak / (gak - gbk), tmin), 1.0 - tmin), 0.5)
        x = a[k] + t * (b[k] - a[k])
        on, gx = member(x, k)
        up, down = k[on], k[~on]
        a[up], ga[up] = x[on], gx[on]
        gb[up] = np.where((side[up] == 1)[:, None], 0.5 * gb[up], gb[up])
        side[up] = 1
        b[down], gb[down] = x[~on], gx[~on]
        ga[down] = np.where((side[down] == -1)[:, None], 0.5 * ga[down], ga[down])
        side[down] = -1
        w3[k], w2[k], w1[k] = w2[k], w1[k], wk
    return a, b


def _joint_excess(
    robot: Robot, red: Reduction, chain: Array, pose: NDArray[np.intp], branch: NDArray[np.intp], x: Array
) -> Array:
    """``(K, n)``: how far each joint of the family member at ``x (K,)`` lies outside its limits (<= 0 inside, inf
    where the member does not exist)."""
    q = family_members(robot, red, chain, pose, branch, x)
    return robot.limit_excess(np.nan_to_num(q, nan=np.inf))


def _limit_excess(
    robot: Robot, red: Reduction, chain: Array, pose: NDArray[np.intp], branch: NDArray[np.intp], x: Array
) -> Array:
    """How far the family member at ``x (K,)`` lies outside the joint limits (its largest excess; <= 0 inside,
    inf where the member does not exist)."""
    return np.asarray(np.max(_joint_excess(robot, red, chain, pose, branch, x), axis=-1))


def _limit_dips(
    robot: Robot,
    red: Reduction,
    chain: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    grid: Array,
    e: Array,
) -> Array:
    """``(K, D)`` extra samples for the family spans sampled at ``grid (K, M)``: where the limit excess has a
    local minimum above zero among the samples, the least excess between the neighbouring samples is located
    (golden section); where it is inside the limits, that point is an extra sample. ``D`` is the most extra
    samples of one span (0 in the common case); shorter rows repeat the span's first sample. ``e (K, M)``: the
    samples' limit excess."""
    K, M = grid.shape
    big = np.where(np.isfinite(e), e, np.inf)
    left = np.concatenate([np.full((K, 1), np.inf), big[:, :-1]], axis=1)
    right = np.concatenate([big[:, 1:], np.full((K, 1), np.inf)], axis=1)
    k, i = np.nonzero((big > 0) & np.isfinite(big) & (big <= left) & (big <= right))
    if k.size == 0:
        return np.zeros((K, 0))
    a, b = grid[k, np.maximum(i - 1, 0)], grid[k, np.minimum(i + 1, M - 1)]
    best_x, best_e = grid[k, i], big[k, i]
    if red.uses_kernel:
        best_x, best_e = certify.dip_search(robot, red, chain, pose[k], branch[k], a, b, best_x, best_e, DIP_STEPS)
    else:
        best_x, best_e = _golden_dips(robot, red, chain, pose[k], branch[k], a, b, best_x, best_e)
    # (inside the limits as ``_members_ok`` takes them: within their tolerance; a family touching a corner of the
    # limits, two joints at theirs at once, meets them at one point only, which the search gets within ~1e-11)
    found = best_e <= np.min(robot.limit_tol)
    return _extra_samples(grid, k[found], best_x[found])


def _extra_samples(grid: Array, rows: NDArray[np.intp], x: Array) -> Array:
    """``(K, D)``: the extra samples ``x`` of the spans ``rows`` (sorted: they come from ``np.nonzero``), the j-th of
    a span in column j; shorter rows repeat the span's first sample (``D``: the most of one span)."""
    width = int(np.bincount(rows, minlength=grid.shape[0]).max()) if rows.size else 0
    extra = np.repeat(grid[:, :1], width, axis=1)
    col = np.arange(rows.size) - np.searchsorted(rows, rows)
    extra[rows, col] = x
    return extra


def _limit_corners(
    robot: Robot,
    red: Reduction,
    chain: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    grid: Array,
    e: Array,
) -> Array:
    """``(K, D)`` extra samples, as ``_limit_dips``'s: where two neighbouring samples both lie outside the limits,
    one joint leaving its limits between them and another coming back in (and none outside at both), the leaving
    joint's crossing of its limit is located (bisection, to ``2**-CORNER_BISECT`` of the step); where the member
    there is inside the limits (their tolerance), it is an extra sample. A family can touch the limits at one point
    only, two joints at theirs at once (a wrist's two joints at their limits on its singular circle: one leaves its
    limits where the other comes back in): the excess of the worst joint there is a V reaching zero, which is not
    a local minimum among the samples when an inside stretch lies next to it, so ``_limit_dips`` does not see it.
    ``e (K, M, n)``: each joint's excess."""
    K, M = grid.shape
    tol = float(np.min(robot.limit_tol))
    with np.errstate(invalid="ignore"):
        worst = np.max(e, axis=-1)
        outside = np.isfinite(worst) & (worst > tol)
        before, after = e[:, :-1] > 0.0, e[:, 1:] > 0.0
        leaves, enters = ~before & after, before & ~after
        finite = np.all(np.isfinite(e[:, :-1]) & np.isfinite(e[:, 1:]), axis=-1)
        # (both samples outside, one joint leaving its limits and another coming back, no joint outside at both)
        corner = outside[:, :-1] & outside[:, 1:] & finite & leaves.any(axis=-1) & enters.any(axis=-1)
        corner &= ~np.any(before & after, axis=-1)
    k, i = np.nonzero(corner)
    if k.size == 0:
        return np.zeros((K, 0))
    j = np.argmax(leaves[k, i], axis=-1)  # (a joint that leaves: its crossing is the corner, if there is one)
    a, b = grid[k, i], grid[k, i + 1]  # (the joint inside its limits at a, outside at b)
    rows = np.arange(k.size)
    for _ in range(CORNER_BISECT):
        m = 0.5 * (a + b)
        out = _joint_excess(robot, red, chain, pose[k], branch[k], m)[rows, j] > 0.0
        a, b = np.where(out, a, m), np.where(out, m, b)
    found = _limit_excess(robot, red, chain, pose[k], branch[k], a) <= tol
    return _extra_samples(grid, k[found], a[found])


def _golden_dips(
    robot: Robot,
    red: Reduction,
    chain: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    a: Array,
    b: Array,
    best_x: Array,
    best_e: Array,
) -> tuple[Array, Array]:
    """The golden-section steps of ``_limit_dips`` (for a reduction without a compiled kernel;
    ``certify.dip_search`` otherwise)."""
    return golden_least(lambda x: _limit_excess(robot, red, chain, pose, branch, x), a, b, best_x, best_e)


def golden_least(
    excess: Callable[[Array], Array],
    a: Array,
    b: Array,
    best_x: Array,
    best_e: Array,
    steps: int = DIP_STEPS,
    slope: Array | None = None,
) -> tuple[Array, Array]:
    """Golden-section search of the least ``excess(x)`` in each bracket ``[a, b]``, starting from the best point
    known ``best_x`` (value ``best_e``); it stops once every best value is at most 0, or after ``steps``. With
    ``slope`` (a bound on ``|d excess / dx|`` per bracket), a bracket is also settled once the excess cannot drop
    to 0 in it any more (``best_e - slope (b - a) > 0``). ``(best_x, best_e)``."""
    c, d = b - _GOLDEN * (b - a), a + _GOLDEN * (b - a)
    ec, ed = excess(c), excess(d)
    for _ in range(steps):
        for x, ex in ((c, ec), (d, ed)):
            better = ex < best_e
            best_x, best_e = np.where(better, x, best_x), np.where(better, ex, best_e)
        settled = best_e <= 0.0
        if slope is not None:
            settled |= best_e - slope * (b - a) > 0.0
        if np.all(settled):
            break
        left = ec < ed  # the least excess lies in [a, d]: d becomes the new right end, c the new inner right point
        a, b = np.where(left, a, c), np.where(left, d, b)
        new_c = np.where(left, b - _GOLDEN * (b - a), d)
        new_d = np.where(left, c, a + _GOLDEN * (b - a))
        fresh = np.where(left, new_c, new_d)  # the one inner point not evaluated yet
        e_fresh = excess(fresh)
        ec, ed = np.where(left, e_fresh, ed), np.where(left, ec, e_fresh)
        c, d = new_c, new_d
    return best_x, best_e


def _limit_peaks(
    robot: Robot, red: Reduction, chain: Array, pose: NDArray[np.intp], branch: NDArray[np.intp], grid: Array, e: Array
) -> Array:
    """``(K, D)`` extra samples for the family spans sampled at ``grid (K, M)``: where a joint's limit excess has a
    local maximum at or below zero among the samples (``PEAK_REACH``), its greatest excess between the neighbouring
    samples is located (golden section); where it is outside the limits, that point is an extra sample, so that
    the span is cut around it. The counterpart of ``_limit_dips`` (an excursion out of the limits narrower than
    the sampling). ``D`` is the most extra samples of one span (0 in the common case). ``e (K, M, n)``: each
    joint's limit excess at the samples (per joint: a peak of one joint can hide under another's rising excess)."""
    K, M = grid.shape
    big = np.where(np.isfinite(e), e, -np.inf)
    pad = np.full((K, 1, e.shape[2]), -np.inf)
    left = np.concatenate([pad, big[:, :-1]], axis=1)
    right = np.concatenate([big[:, 1:], pad], axis=1)
    with np.errstate(invalid="ignore"):
        rise = np.maximum(np.where(np.isfinite(left), big - left, 0.0), np.where(np.isfinite(right), big - right, 0.0))
    # (a revolute joint whose limits span the circle is always inside them, once wrapped)
    bounded = ~(robot.is_revolute & (robot.upper - robot.lower >= 2.0 * np.pi))
    peak = np.isfinite(big) & (big <= 0.0) & (big >= left) & (big >= right) & (big > -PEAK_REACH * rise) & bounded
    k, i, j = np.nonzero(peak)
    if k.size == 0:
        return np.zeros((K, 0))
    a, b = grid[k, np.maximum(i - 1, 0)], grid[k, np.minimum(i + 1, M - 1)]

    def negated(x: Array) -> Array:  # (of each bracket, the joint j whose excess peaks)
        return -_joint_excess(robot, red, chain, pose[k], branch[k], x)[np.arange(x.size), j]

    # the excess changes at most ~PEAK_REACH x its rise per sample step (the brackets are two steps wide)
    slope = PEAK_REACH * rise[k, i, j] / np.maximum(0.5 * (b - a), np.finfo(float).tiny)
    best_x, best_e = golden_least(negated, a, b, grid[k, i], -big[k, i, j], PEAK_STEPS, slope)
    found = best_e < 0.0
    return _extra_samples(grid, k[found], best_x[found])


def merge_spans(spans: Spans) -> Spans:
    """One span per stretch, in order of (pose, branch, lo): spans of one pose and branch that overlap or touch are
    united (the sweep finds a family from its samples and again from flat stretches around roots)."""
    if len(spans) < 2:
        return spans
    order = np.lexsort((spans.lo, spans.branch, spans.pose))
    pose, branch = spans.pose[order].tolist(), spans.branch[order].tolist()
    lo, hi = spans.lo[order].tolist(), spans.hi[order].tolist()
    first = [0]  # the first span of each merged one, and its hi
    ends = [hi[0]]
    for k in range(1, len(lo)):
        if pose[k] == pose[k - 1] and branch[k] == branch[k - 1] and lo[k] <= ends[-1]:
            ends[-1] = max(ends[-1], hi[k])
        else:
            first.append(k)
            ends.append(hi[k])
    keep = order[first]
    return Spans(spans.pose[keep], spans.branch[keep], spans.lo[keep], np.array(ends))


def families_of(
    robot: Robot, red: Reduction, chain: Array, world: Array, spans: Spans, limits: bool, tol: float
) -> tuple[dict[int, list[Family]], NDArray[np.intp], Array]:
    """Family objects per pose: each span cut to the sub-intervals whose members are certified by FK
    (and, with limits, inside the limits): sampled, then each cut located by bisection.
    Pieces that shrink to a point are returned as isolated members ``(pose index, q)``."""
    out: dict[int, list[Family]] = {}
    spans = merge_spans(spans)
    if not len(spans):
        return out, np.zeros(0, np.intp), np.zeros((0, robot.n_joints))
    # only the poses with a family are worked on (the compiled kernels take every pose's parameters)
    used, pose = np.unique(spans.pose, return_inverse=True)
    chain_all, chain, world = chain, chain[used], world[used]
    branch = spans.branch
    u = np.linspace(0.0, 1.0, FAMILY_SAMPLES)
    grid = spans.lo[:, None] + (spans.hi - spans.lo)[:, None] * u
    if limits:
        # a stretch inside the limits narrower than the sampling (a joint dipping just under its limit between
        # samples) gets a sample of its own, and an excursion out of the limits narrower than the sampling (a joint
        # turning through +-pi between two samples) one that cuts the span there
        S, M = grid.shape
        e = _joint_excess(robot, red, chain, np.repeat(pose, M), np.repeat(branch, M), grid.ravel()).reshape(S, M, -1)
        dips = _limit_dips(robot, red, chain, pose, branch, grid, np.max(e, axis=-1))
        peaks = _limit_peaks(robot, red, chain, pose, branch, grid, e)
        corners = _limit_corners(robot, red, chain, pose, branch, grid, e)
        grid = np.sort(np.concatenate([grid, dips, peaks, corners], axis=1), axis=1)
    ok = _members_ok(robot, red, chain, world, pose, branch, grid, limits, tol)
    pad = np.zeros((len(spans), 1), np.int8)
    edges = np.diff(np.concatenate([pad, ok.astype(np.int8), pad], axis=1), axis=1)
    # pieces (span K, first ok sample S, last ok sample E), span by span: each rise of ok pairs with the next fall
    K, S = np.nonzero(edges == 1)
    E = np.nonzero(edges == -1)[1] - 1
    near_p, near_q = _near_family_members(robot, red, chain, pose, branch, grid, ok, used)
    if K.size == 0:
        return out, near_p, near_q
    M = grid.shape[1]
    # bisect each cut between the last sample inside and the first outside
    inside = np.concatenate([grid[K, S], grid[K, E]])
    outside = np.concatenate([grid[K, np.maximum(S - 1, 0)], grid[K, np.minimum(E + 1, M - 1)]])
    cut = np.nonzero(np.concatenate([S > 0, E < M - 1]))[0]  # only cuts inside a span need locating
    if cut.size:
        # members between certified samples are solutions too: each cut lies where members stop being
        # solutions (a limit crossed, a singular point where the branch's closed form breaks down, ...): bisect
        # between the last sample inside and the first outside, all cuts at once
        which = np.concatenate([K, K])[cut]
        a, b = inside[cut], outside[cut]
        if red.uses_kernel:  # (the same steps, compiled: no array work per step)
            a, b = certify.locate_cuts(
                robot, red, chain, world, pose[which], branch[which], a, b, CUT_BISECT, limits, tol
            )
        else:
            a, b = _locate_cuts(robot, red, chain, world, pose[which], branch[which], a, b, CUT_BISECT, limits, tol)
        inside[cut] = a
    n = K.size
    lo, hi = inside[:n], inside[n:]
    if limits and not red.periodic:  # within the limit tolerance, but reported inside theta*'s own limits
        j = red.free_joint
        lo, hi = np.clip(lo, robot.lower[j], robot.upper[j]), np.clip(hi, robot.lower[j], robot.upper[j])
    # a piece that shrinks to a point (the family touches the limits there) is an isolated solution
    point = hi - lo <= CLUSTER_FAMILY_REL * (grid[K, -1] - grid[K, 0] + 1.0)
    duplicate = _repeated_pieces(robot, red, chain, pose[K], branch[K], lo, hi) & ~point
    f_pose, f_branch = spans.pose[K].tolist(), spans.branch[K].tolist()
    for j in np.nonzero(~point & ~duplicate)[0].tolist():
        out.setdefault(f_pose[j], []).append(
            Family(
                red.free_joint,
                (float(lo[j]), float(hi[j])),
                red,
                chain_all[f_pose[j]],
                f_branch[j],
                members=certified_members,
            )
        )
    pk = K[point]
    # its member: of the piece's ends and middle, the one deepest inside the limits
    three = np.stack([lo[point], 0.5 * (lo + hi)[point], hi[point]], axis=1)
    q3 = red.solve_rest(chain[pose[pk]], three, np.broadcast_to(branch[pk][:, None], three.shape))
    over = np.sum(np.maximum(robot.limit_excess(np.nan_to_num(q3, nan=np.inf)), 0.0), axis=-1)
    mid = three[np.arange(pk.size), np.argmin(over, axis=1)] if pk.size else np.zeros(0)
    q_pts = (
        red.solve_rest(chain[pose[pk]], mid[:, None], branch[pk][:, None])[:, 0]
        if pk.size
        else np.zeros((0, robot.n_joints))
    )
    return out, np.concatenate([used[pose[pk]].astype(np.intp), near_p]), np.concatenate([q_pts, near_q])


def _near_family_members(
    robot: Robot,
    red: Reduction,
    chain: Array,
    pose: NDArray[np.intp],
    branch: NDArray[np.intp],
    grid: Array,
    ok: NDArray[np.bool_],
    used: NDArray[np.intp],
) -> tuple[NDArray[np.intp], Array]:
    """A flat stretch of the residual none of whose members reaches the pose is a *near* continuum: the pose lies
    off a self-motion set by a hair (the C-Arm's wrist 1e-10 mm off joint 2's axis), its residual is flat at
    rounding level, and its solutions are isolated points next to the set. Members spread along each such span
    ``(pose index, q)`` go to the solver's candidates, where the Newton polish on the full pose moves them onto
    those solutions (or they fail certification)."""
    none = np.nonzero(~ok.any(axis=1))[0]
    if none.size == 0:
        return np.zeros(0, np.intp), np.zeros((0, robot.n_joints))
    cols = np.linspace(0, grid.shape[1] - 1, NEAR_FAMILY_SAMPLES).round().astype(np.intp)
    theta = grid[none][:, cols]
    k = np.repeat(none, cols.size)
    q = family_members(robot, red, chain, pose[k], branch[k], theta.ravel())
    finite = np.all(np.isfinite(q), axis=-1)
    return used[pose[k]][finite].astype(np.intp), q[finite]


def _same_configuration(robot: Robot, a: Array, b: Array) -> NDArray[np.bool_]:
    d = joint_distance(robot, a, b)
    return np.asarray(np.all(d <= MEMBER_TOL * np.maximum(1.0, np.abs(a)), axis=-1))


def _repeated_pieces(
    robot: Robot, red: Reduction, chain: Array, pose: NDArray[np.intp], branch: NDArray[np.intp], lo: Array, hi: Array
) -> NDArray[np.bool_]:
    """``(P,)`` True for a family piece equal to an earlier one of the same pose: same interval and the same
    members (two branches of a reduction can meet along a whole continuum). One batched member evaluation."""
    P = pose.size
    dup = np.zeros(P, dtype=bool)
    if P < 2:
        return dup
    tol = MEMBER_TOL * np.maximum(1.0, hi - lo)
    # pairs (i, j), j < i, of the same pose with the same interval (within i's tolerance): every earlier piece of
    # each piece's pose, all at once (a pose has a few pieces)
    order = np.argsort(pose, kind="stable")
    first = np.searchsorted(pose[order], pose[order], side="left")  # where each piece's pose starts in ``order``
    earlier = np.arange(P) - first
    n_pairs = int(earlier.sum())
    if n_pairs == 0:
        return dup
    step = np.arange(n_pairs) - np.repeat(np.cumsum(earlier) - earlier, earlier)
    a, b = order[np.repeat(np.arange(P), earlier)], order[np.repeat(first, earlier) + step]
    same = (np.abs(lo[a] - lo[b]) <= tol[a]) & (np.abs(hi[a] - hi[b]) <= tol[a])
    pi, pj = a[same], b[same]
    if pi.size == 0:
        return dup
    # every pair's members compared at once (5 points of the interval), then the pairs in order
    used, where = np.unique(np.concatenate([pi, pj]), return_inverse=True)
    u = np.linspace(0.0, 1.0, 5)
    x = lo[used, None] + (hi - lo)[used, None] * u[None, :]
    at = (np.repeat(pose[used], u.size), np.repeat(branch[used], u.size), x.ravel())
    members = family_members(robot, red, chain, *at)
    members = robot.wrap(members).reshape(used.size, u.size, -1)
    mi, mj = where[: pi.size], where[pi.size :]
    equal = np.all(_same_configuration(robot, members[mi], members[mj]), axis=-1)
    for k in np.lexsort((pj, pi)):
        i, j = pi[k], pj[k]
        if not dup[i] and not dup[j] and equal[k]:
            dup[i] = True
    return dup


def off_families(robot: Robot, checks: list[tuple[Array, tuple[Family, ...]]]) -> list[NDArray[np.bool_]]:
    """For each ``(q (k, n), families)`` of ``checks``, the ``(k,)`` mask of the configurations that are not members
    of any of the families. The members (at the configurations within a family's interval) are evaluated in one
    batch per reduction, bit for bit what ``Family.at`` gives."""
    sizes = np.array([q.shape[0] for q, _ in checks], dtype=np.intp)
    offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.intp)
    on = np.zeros(int(offsets[-1]), dtype=bool)
    if on.size:
        q_all = np.concatenate([q for q, _ in checks])
        pairs: dict[int, list[tuple[int, Family]]] = {}  # (check, family) per reduction
        for g, (q, families) in enumerate(checks):
            if q.shape[0] == 0:
                continue
            for f in families:
                if f.held is not None:  # (members of the full arm: as Family.at expands them)
                    th = q[:, f.free_joint]
                    lo, hi = f.interval
                    rows = np.nonzero(_in_interval(th, lo, hi))[0]
                    if rows.size:
                        same = _same_configuration(robot, f.at(np.clip(th[rows], lo, hi)), q[rows])
                        on[offsets[g] + rows] |= same
                else:
                    pairs.setdefault(id(f.reduction), []).append((g, f))
        for batch in pairs.values():
            red = batch[0][1].reduction
            checked = np.array([gi for gi, _ in batch], dtype=np.intp)
            # every (pair, row of its check): the rows whose theta* lies in the family's interval
            n = sizes[checked]
            pair = np.repeat(np.arange(checked.size), n)
            row = np.arange(pair.size) - np.repeat(np.cumsum(n) - n, n) + offsets[checked][pair]
            fj = np.array([f.free_joint for _, f in batch], dtype=np.intp)
            f_lo = np.array([f.interval[0] for _, f in batch])
            f_hi = np.array([f.interval[1] for _, f in batch])
            th = q_all[row, fj[pair]]
            sel = np.nonzero(_in_interval(th, f_lo[pair], f_hi[pair]))[0]
            if sel.size == 0:
                continue
            pair, row, th = pair[sel], row[sel], np.clip(th[sel], f_lo[pair[sel]], f_hi[pair[sel]])
            branch = np.array([f.branch for _, f in batch], dtype=np.intp)[pair]
            chain = np.stack([f.chain_pose for _, f in batch])
            members = red.robot.wrap(family_members(red.robot, red, chain, pair, branch, th))
            on[row[_same_configuration(robot, members, q_all[row])]] = True
    return [~on[offsets[g] : offsets[g + 1]] for g in range(len(checks))]


def inner_off(robot: Robot, found: Sequence[Family], known: tuple[Family, ...]) -> NDArray[np.bool_]:
    """``(len(found),)``: the families of ``found`` that do not lie on ``known``: one of their members at
    ``INNER_PROBES`` of their interval is not a member of any of ``known``."""
    if not found:
        return np.zeros(0, dtype=bool)
    probes = np.array(INNER_PROBES)
    members = members_at(found, [f.interval[0] + (f.interval[1] - f.interval[0]) * probes for f in found])
    return np.array([o.any() for o in off_families(robot, [(m, known) for m in members])], dtype=bool)


def _in_interval(th: Array, lo: Array | float, hi: Array | float) -> NDArray[np.bool_]:
    """theta* ``th`` within a family's interval ``[lo, hi]``: a configuration at an end of it is on it."""
    slack = MEMBER_TOL * np.maximum(1.0, np.abs(th))
    return np.asarray((th >= lo - slack) & (th <= hi + slack))


def unique_families(families: tuple[Family, ...]) -> tuple[Family, ...]:
    """``families`` without repeats: a family whose free joint and interval equal an earlier one's and whose
    members agree with it (two branches of a reduction can meet along a whole continuum) is dropped."""
    if len(families) < 2:
        return families
    out: list[Family] = []
    probes: list[Array] = []  # members at 5 points of each kept family's interval
    for f in families:
        lo, hi = f.interval
        tol = MEMBER_TOL * max(1.0, hi - lo)
        mine: Array | None = None
        duplicate = False
        for g, g_members in zip(out, probes, strict=True):
            if g.free_joint == f.free_joint and abs(g.interval[0] - lo) <= tol and abs(g.interval[1] - hi) <= tol:
                mine = f.at(np.linspace(lo, hi, 5)) if mine is None else mine
                if np.all(_same_configuration(f.reduction.robot, g_members, mine)):
                    duplicate = True
                    break
        if not duplicate:
            out.append(f)
            probes.append(f.at(np.linspace(lo, hi, 5)) if mine is None else mine)
    return tuple(out)


def collapse_continua(robot: Robot, pose: NDArray[np.intp], q: Array) -> NDArray[np.bool_]:
    """Keep-mask over distinct certified solutions ``q (K, n)`` of poses ``pose (K,)``: on a pose with more than
    ``MAX_ISOLATED_SOLUTIONS``, only the medoid of each group linked within ``CONTINUUM_LINK`` is kept."""
    keep = np.ones(pose.size, dtype=bool)
    if pose.size <= MAX_ISOLATED_SOLUTIONS:
        return keep
    counts = np.bincount(pose)
    scale = np.where(robot.is_revolute, 1.0, 1.0 / orientation_weight(robot.length_unit))
    for i in np.nonzero(counts > MAX_ISOLATED_SOLUTIONS)[0]:
        idx = np.nonzero(pose == i)[0]
        if idx.size > CONTINUUM_THIN:
            # thousands of points along a continuum: one per cell of a grid fine enough that the points of a cell
            # are linked anyway (memory of the comparison below grows with the square of the count)
            cell = CONTINUUM_LINK / (2.0 * np.sqrt(q.shape[1]))
            _, first = np.unique(np.floor(q[idx] * scale / cell), axis=0, return_index=True)
            keep[idx] = False
            idx = idx[np.sort(first)]
        d = q[idx][:, None, :] - q[idx][None, :, :]
        d = np.where(robot.is_revolute, np.abs(np.pi - np.mod(np.pi - d, 2.0 * np.pi)), np.abs(d))
        dist = np.linalg.norm(d * scale, axis=-1)
        label = np.arange(idx.size)
        for _ in range(idx.size):  # connected components: each takes the smallest label linked to it
            new = np.min(np.where(dist <= CONTINUUM_LINK, label[None, :], idx.size), axis=1)
            if np.array_equal(new, label):
                break
            label = new
        labels, inverse, sizes = np.unique(label, return_inverse=True, return_counts=True)
        keep[idx] = sizes[inverse] == 1  # (a group of one is its own medoid)
        for lab in labels[sizes > 1]:
            g = np.nonzero(label == lab)[0]
            keep[idx[g[np.argmin(dist[np.ix_(g, g)].max(axis=1))]]] = True
    return keep
