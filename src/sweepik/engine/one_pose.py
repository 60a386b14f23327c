"""One pose from its chain pose to its final candidates in one compiled call: the search (``search``'s one-pass
kernels), the certification (``certify``) and the settling (``dedupe.settle``: limits, duplicates) chained
(``settle_one``); for a closed form, its all-branch certification and the settling (``settle_closed``).

Each of these, called from Python, costs more in Python steps around its kernel (buffers, argument checks,
candidate records) than the kernel's own work takes for one pose: ~50 of a C-Arm pose's ~100 us. Here one call
takes every argument, allocates the buffers in compiled code, and calls the kernels by their addresses
(``kernels.address_of``: they are not linked in and recompiled, so each kernel here compiles in 1-2 s on a fresh
install). What it cannot settle on its own it says, and the solver takes that pose the general way
(``chunk.solve_chunk``): family spans, a candidate buffer overflow, a multiple root at a limit of theta*, a
candidate due a polish or a snap to a limit, a candidate where a continuum may run along another joint
(``Reduction.continuum_kernel``).
"""

from __future__ import annotations

import weakref
from typing import Any, NamedTuple

import numpy as np
from numba import boolean, float64, int64
from numba import void as _void
from numpy.typing import NDArray

from sweepik._jit import function_at, inlined, internal, writable
from sweepik.engine import search
from sweepik.engine.candidates import unit_grid
from sweepik.engine.certify import (
    _CERTIFY_EVERY_SIG,
    _CERTIFY_SIG,
    _certify,
    _certify_every_branch,
    chain_args,
    nearly_singular_row,
)
from sweepik.engine.dedupe import _SETTLE_SIG, _rows_within, _settle, duplicate_tolerance, limit_args
from sweepik.engine.search import _ONE_PASS_SIG, _plan
from sweepik.engine.settings import PARTNER_SINGULAR
from sweepik.model.units import orientation_weight
from sweepik.reductions.geometric import _CONTINUUM_SIG, _continuum_rows
from sweepik.reductions.kernels import (
    CONFIGURATION_SIG,
    CONFIGURATIONS_SIG,
    address_of,
    as_singular,
    defining_class,
    lazy_njit,
    owned_kernel,
)

__all__ = [
    "OK",
    "SEARCH_ELSEWHERE",
    "DUE",
    "CONTINUUM",
    "MEET",
    "SINGULAR",
    "Settled",
    "settle_one",
    "settle_closed",
    "closed_fixed",
    "every_branch_settled",
    "searched_settled",
    "sweep_fixed",
    "SETTLE_ONE_SIG",
    "SETTLE_CLOSED_SIG",
]

Array = NDArray[np.float64]

#: ``settle_one``'s status: the pose's final candidates are given ...
OK = 0
#: ... its search needs the general path (family spans, a buffer overflow, a multiple root at a limit of theta*) ...
SEARCH_ELSEWHERE = 1
#: ... a candidate is due one of the solver's rarer steps (a polish, a snap to a limit; a sweep's call gives its
#: candidates then: ``searched_settled``) ...
DUE = 2
#: ... or a continuum may run along another joint through a certified one (``Reduction.continuum_joints``) ...
CONTINUUM = 3
#: ... or two branches of a closed form meet (one dropped as the other's duplicate, or two kept within the reach
#: given, ``settings.MEET_REL``): the solver merges them into one solution of higher multiplicity ...
MEET = 4
#: ... or a closed form's pose is degenerate, or a step may leave its joint free there (``Reduction.singular_kernel``):
#: the solver asks ``degenerate`` and ``continuum_joints`` (its fallback sweep, the continua it traces).
SINGULAR = 5


class Settled(NamedTuple):
    """``settle_one``'s result: the pose's solutions as the solver's block holds them (``q`` wrapped, ``error``,
    ``error_geodesic``, ``within_limits``, ``multiplicity``: the certified candidates that are no duplicate, in order,
    with ``only_inside`` those within the limits), how many certified candidates there were (``certified``) and how
    many of them are no duplicate (``reachable``); all empty unless ``status`` is ``OK``. A closed form's also has
    every branch's theta* (0), branch and geodesic error (``theta``, ``branch``, ``err_all``; empty for a sweep), and
    ``checked``: the call checked the pose's singular set itself (``SINGULAR``)."""

    status: int
    certified: int
    reachable: int
    q: Array
    error: Array
    error_geodesic: Array
    within_limits: NDArray[np.bool_]
    multiplicity: NDArray[np.int64]
    theta: Array
    branch: NDArray[np.int64]
    err_all: Array
    checked: bool = False


_ONE_PASS_FN_SIG, _CERTIFY_FN_SIG, _SETTLE_FN_SIG = _void(*_ONE_PASS_SIG), _void(*_CERTIFY_SIG), _void(*_SETTLE_SIG)
_EVERY_FN_SIG, _CONTINUUM_FN_SIG = _void(*_CERTIFY_EVERY_SIG), int64(*_CONTINUUM_SIG)
_as_one_pass, _as_certify, _as_settle, _as_every, _as_continuum = (
    function_at(s) for s in (_ONE_PASS_FN_SIG, _CERTIFY_FN_SIG, _SETTLE_FN_SIG, _EVERY_FN_SIG, _CONTINUUM_FN_SIG)
)
#: The kernels' addresses in ``addr``, and ``continuum_rows``' (0: no continuum check) with its fixed integers
#: (the amplitude kernel's address, branches per position branch), ``Reduction.continuum_kernel``'s.
#: ``_A_SING``: a closed form's ``singular_kernel`` (0: none).
_A_SEARCH, _A_CERTIFY, _A_SETTLE, _A_CFG, _A_ROWS, _A_AMP, _A_DIV, _A_SING, _A_SIZE = range(9)


@internal
def _settled(settle, q, eg, ep, pose, mult, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, H, P, rev, R_end):
    """One pose's certified candidates settled (``dedupe._settle`` at the address ``settle``): whether one is
    due the solver's rarer steps (a certified one on a valley's slope too: above ``thr[5]``, nearly singular,
    ``settings.VALLEY_ABOVE_REL``), and the count, rows, wrapped configurations, limit check and duplicate mask
    of the certified ones (buffers as long as the candidates)."""
    K, n = q.shape
    rows = np.empty(K, dtype=np.int64)
    w = np.empty((K, n))
    score = np.empty(K)
    inside = np.empty(K, dtype=np.bool_)
    keep = np.empty(K, dtype=np.bool_)
    ints = np.empty(3, dtype=np.int64)  # parts (2), counts
    ints[0], ints[1], ints[2] = 0, K, 0
    due = np.empty(1, dtype=np.bool_)
    due[0] = False
    _as_settle(settle)(
        q, eg, ep, pose, mult, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, due, rows, w, score,
        inside, keep, ints[0:2], ints[2:3], 0, 1,
    )  # fmt: skip
    for a in range(ints[2]):  # (certified, not due: at most thr[1], the polish's floor, or on the paper's J)
        if due[0]:
            break
        k = rows[a]
        if eg[k] > thr[5] and nearly_singular_row(H, P, rev, R_end, q[k], scale, PARTNER_SINGULAR):
            due[0] = True
    return due[0], ints[2], rows, w, inside, keep


@inlined
def _branches_meet(c, w, keep, rev, meet):
    """Of a closed form's ``c`` settled branches, one was dropped as another's duplicate, or two kept ones are
    within ``meet`` of each other (per joint, revolute ones modulo 2 pi: ``dedupe.near_pairs``)."""
    for a in range(c):
        if not keep[a]:
            return True
        for b in range(a + 1, c):
            if _rows_within(w, a, b, rev, meet):
                return True
    return False


@internal
def _kept_meet(c, w, keep, rev, meet):
    """Two of the ``c`` settled candidates that are kept (no duplicate) lie within ``meet`` of each other."""
    for a in range(c):
        if keep[a]:
            for b in range(a + 1, c):
                if keep[b] and _rows_within(w, a, b, rev, meet):
                    return True
    return False


@internal
def _final(c, rows, w, inside, keep, eg, ep, mult, only_inside):
    """The solutions of the ``c`` settled candidates (``_settled``'s): the rows kept (with ``only_inside``, those
    within the limits too), in order, as the solver's block holds them; and how many were kept."""
    n = w.shape[1]
    reachable, m = 0, 0
    for k in range(c):
        if keep[k]:
            reachable += 1
            if inside[k] or not only_inside:
                m += 1
    q = np.empty((m, n))
    e_p = np.empty(m)
    e_g = np.empty(m)
    ins = np.empty(m, dtype=np.bool_)
    mu = np.empty(m, dtype=np.int64)
    m = 0
    for k in range(c):
        if keep[k] and (inside[k] or not only_inside):
            r = rows[k]
            for j in range(n):
                q[m, j] = w[k, j]
            e_p[m], e_g[m], ins[m], mu[m] = ep[r], eg[r], inside[k], mult[r]
            m += 1
    return reachable, q, e_p, e_g, ins, mu


#: ``_settle_one``'s and ``_settle_closed``'s arguments (``single_pose`` takes most of them too).
SETTLE_ONE_SIG = (
    (int64[::1], int64[::1], int64[::1], int64[::1], int64[::1], float64[::1], float64[:, ::1], float64[::1])
    + (float64[::1], float64[::1], float64[::1], float64[::1], float64[::1], int64[:, ::1], int64, int64)
    + (float64[::1], float64, float64[:, :, ::1], float64[:, ::1], float64[:, ::1], boolean[::1])
    + (float64[:, ::1], float64, float64[::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean)
    + (float64[::1], float64[::1], float64, int64[::1], float64[::1], float64[::1], boolean)
)
SETTLE_CLOSED_SIG = (
    (int64[::1], float64[:, ::1], float64[:, :, ::1], int64, float64[:, ::1], float64[:, ::1], boolean[::1])
    + (float64[:, ::1], float64, float64[::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean)
    + (float64[::1], float64[::1], float64, float64[::1], float64[::1], boolean)
)


@lazy_njit(SETTLE_ONE_SIG, cache=True, nogil=True)
def _settle_one(
    addr, plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, max_cand, max_fam,
    limits, clip, world, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
    c_joints, c_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """``settle_one``'s kernel (``searched_settled``)."""
    return searched_settled(
        addr, plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, max_cand, max_fam,
        limits, clip, world, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
        c_joints, c_thr, meet, only_inside,
    )  # fmt: skip


@internal
def searched_settled(
    addr, plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, max_cand, max_fam,
    limits, clip, world, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
    c_joints, c_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """Pose 0 of ``params``/``world`` searched (one-pass kernel at ``addr[_A_SEARCH]``), certified and settled (with
    status ``DUE``: the candidates instead, ``(DUE, K, 0, q, error, error_geodesic, -, multiplicity)``, each
    certified, none on a continuum along another joint; the rest of the general way takes them, ``chunk.resumed``);
    ``limits``: theta*'s limits, ``clip``: how far outside them a multiple root is clipped to them
    (``chunk._limit_copies``: the general path's); ``c_joints``, ``c_thr``: the joints and thresholds of the
    continuum check (``addr[_A_ROWS]``, unless 0), the seed tolerance after the thresholds; ``MEET`` where two of
    the certified solutions (within the limits or not) lie within ``meet`` of each other (per joint, revolute ones
    modulo 2 pi: the general way merges them, ``settle.meetings``, and counts them once in ``reachable``);
    ``only_inside``: the solutions within the limits only (``_final``). Compiled callers only (``settle_one``,
    ``single_pose``)."""
    # (np.empty and explicit loops: np.zeros, slice copies and the like each add to the first compilation)
    n = rev.shape[0]
    out_t = np.empty((1, max_cand))
    out_b = np.empty((1, max_cand), dtype=np.int64)
    out_m = np.empty((1, max_cand), dtype=np.int64)
    ints = np.empty(2, dtype=np.int64)  # cnt, fcnt
    redo = np.empty(1, dtype=np.bool_)
    ints[0], ints[1], redo[0] = 0, 0, False
    fam = np.empty((1, max_fam, 3))
    _as_one_pass(addr[_A_SEARCH])(
        plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, out_t, out_b, out_m,
        ints[0:1], fam, ints[1:2], redo, 0, 1,
    )  # fmt: skip
    K = ints[0]
    status = OK
    if redo[0] or K > max_cand or ints[1] != 0:
        status, K = SEARCH_ELSEWHERE, 0
    for k in range(K):
        t = out_t[0, k]
        if out_m[0, k] >= 2 and ((limits[0] - clip <= t < limits[0]) or (limits[1] < t <= limits[1] + clip)):
            status, K = SEARCH_ELSEWHERE, 0
            break
    theta = np.empty(K)
    branch = np.empty(K, dtype=np.int64)
    mult = np.empty(K, dtype=np.int64)
    pose = np.empty(K, dtype=np.int64)
    for k in range(K):
        theta[k], branch[k], mult[k], pose[k] = out_t[0, k], out_b[0, k], out_m[0, k], 0
    q = np.empty((K, n))
    eg = np.empty(K)
    ep = np.empty(K)
    _as_certify(addr[_A_CERTIFY])(
        addr[_A_CFG], params, world, pose, theta, branch, True, H, P, rev, R_end, weight, q, eg, ep, 0, K
    )
    due, c, rows, w, inside, keep = _settled(
        addr[_A_SETTLE], q, eg, ep, pose, mult, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, H, P, rev,
        R_end,
    )  # fmt: skip
    if due and status == OK:
        status, c = DUE, 0
    if (status == OK or status == DUE) and addr[_A_ROWS] != 0 and K > 0:
        free = np.empty(K, dtype=np.int64)
        nt = c_thr.shape[0] - 1
        flagged = _as_continuum(addr[_A_ROWS])(
            addr[_A_AMP], params, pose, theta, branch, eg, c_thr[nt], addr[_A_DIV], c_thr[:nt], c_joints, free
        )
        if flagged > 0:
            status, c = CONTINUUM, 0
    if status == DUE:  # (its certified candidates, for the solver's rarer steps: ``chunk.resumed``)
        return status, K, 0, q, ep, eg, np.empty(0, dtype=np.bool_), mult
    if status == OK and _kept_meet(c, w, keep, lrev, meet):
        status, c = MEET, 0
    reachable, qf, e_p, e_g, ins, mu = _final(c, rows, w, inside, keep, eg, ep, mult, only_inside)
    return status, c, reachable, qf, e_p, e_g, ins, mu


@lazy_njit(SETTLE_CLOSED_SIG, cache=True, nogil=True)
def _settle_closed(
    addr, params, world, nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
    s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """``settle_closed``'s kernel (``every_branch_settled``)."""
    return every_branch_settled(
        addr, params, world, nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
        s_thr, meet, only_inside,
    )  # fmt: skip


@internal
def every_branch_settled(
    addr, params, world, nb, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
    s_thr, meet, only_inside,
):  # pragma: no cover  # fmt: skip
    """Every branch of pose 0 of ``params``/``world`` (the all-branch configuration kernel at ``addr[_A_CFG]``)
    certified and settled; ``MEET`` where a branch is dropped as another's duplicate or two kept ones are within
    ``meet`` (per joint, revolute ones modulo 2 pi: ``dedupe.near_pairs``); ``SINGULAR`` where the singular kernel
    at ``addr[_A_SING]`` (unless 0; thresholds ``s_thr``) flags it. Compiled callers only (``settle_closed``,
    ``single_pose``)."""
    q = np.empty((nb, rev.shape[0]))
    eg = np.empty(nb)
    ep = np.empty(nb)
    _as_every(addr[_A_CERTIFY])(addr[_A_CFG], params, world, nb, H, P, rev, R_end, weight, q, eg, ep, 0, 1)
    pose = np.empty(nb, dtype=np.int64)
    mult = np.empty(nb, dtype=np.int64)
    for k in range(nb):
        pose[k], mult[k] = 0, 1
    due, c, rows, w, inside, keep = _settled(
        addr[_A_SETTLE], q, eg, ep, pose, mult, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, H, P, rev,
        R_end,
    )  # fmt: skip
    status = DUE if due else OK
    if status == OK and _branches_meet(c, w, keep, lrev, meet):
        status = MEET
    if status == OK and addr[_A_SING] != 0:
        flags = np.empty(2, dtype=np.bool_)  # degenerate, a step's amplitude low
        as_singular(addr[_A_SING])(params, s_thr, flags[0:1], flags[1:2], 0, 1)
        if flags[0] or flags[1]:
            status = SINGULAR
    if status != OK:
        c = 0
    reachable, qf, e_p, e_g, ins, mu = _final(c, rows, w, inside, keep, eg, ep, mult, only_inside)
    return status, c, reachable, qf, e_p, e_g, ins, mu, eg


_NONE = np.zeros(0)
_NO_BRANCH = np.zeros(0, dtype=np.int64)
for _a in (_NONE, _NO_BRANCH):
    _a.flags.writeable = False


class _Fixed(NamedTuple):
    """What ``_settle_one`` takes for a reduction and sample count besides the pose (``settle_one``)."""

    head: tuple[Any, ...]  # the arguments before the pose's own (addresses, plan, ...)
    middle: tuple[Any, ...]  # between them (the unit grid, theta*'s ends, the twins)
    limits: Array  # theta*'s limits
    tail: tuple[Any, ...]  # after the target: ``_tail``, then the continuum check's joints and thresholds
    hint_range: Any  # ``EdgeSearch.hint_range`` (the margins' range of a pose), or None: the search's own


_FIXED: weakref.WeakKeyDictionary[object, dict[tuple[Any, ...], Any]] = weakref.WeakKeyDictionary()


def _kept(red: Any, key: tuple[Any, ...], make: Any) -> Any:
    """``make()``, worked out once per reduction and ``key`` (a reduction's kernels, plan and robot are fixed once
    it is used; an unhashable reduction: every time)."""
    try:
        per_red = _FIXED.setdefault(red, {})
    except TypeError:
        return make()
    if key not in per_red:
        per_red[key] = make()
    return per_red[key]


def _tail(robot: Any, thresholds: tuple[float, ...], reach: Array) -> tuple[Any, ...]:
    """The kernels' last arguments: the chain's geometry and orientation weight (the certification's), the
    thresholds, limits, snap reach, duplicate tolerances and length scale (the settling's)."""
    rev, lower, upper, ltol, beyond = limit_args(robot)
    H, P, crev, R_end = chain_args(robot)
    weight = float(orientation_weight(robot.length_unit))
    thr = np.array(thresholds, dtype=np.float64)
    settling = (
        thr,
        rev,
        lower,
        upper,
        ltol,
        beyond,
        writable(reach),
        duplicate_tolerance(robot),
        float(robot.length_scale),
    )
    return (H, P, crev, R_end, weight, *settling)


def sweep_fixed(
    robot: Any, red: Any, n_samples: int, thresholds: tuple[float, ...], reach: Array, seed_tol: float
) -> _Fixed | None:
    """The fixed arguments of ``_settle_one`` for ``red`` (None: it has no one-pass search for ``n_samples``, or
    checks its continua in Python only: it overrides ``continuum_joints`` and not ``continuum_kernel``)."""

    def make() -> _Fixed | None:
        plan = _plan(red)
        one = plan.one_pass
        if one is None or not (one.n_samples is None or one.n_samples == n_samples):
            return None
        cls = red.__class__
        python_only = defining_class(cls, "continuum_joints") is not defining_class(cls, "continuum_kernel")
        if python_only and defining_class(cls, "continuum_joints") is not defining_class(cls, "continuum_poses"):
            return None  # (else the solver asks ``continuum_poses`` after the call)
        addr = np.zeros(_A_SIZE, dtype=np.int64)
        addr[_A_SEARCH] = address_of(one.kernel, _ONE_PASS_FN_SIG)
        addr[_A_CERTIFY] = address_of(_certify, _CERTIFY_FN_SIG)
        addr[_A_SETTLE] = address_of(_settle, _SETTLE_FN_SIG)
        addr[_A_CFG] = address_of(red.kernel[1], CONFIGURATION_SIG)
        c_joints, c_thr = np.zeros(0, dtype=np.int64), np.zeros(1)
        cont = red.continuum_kernel()
        if cont is not None:  # (the solver's seed tolerance after the thresholds)
            amplitude, div, c_thr, c_joints = cont
            addr[_A_ROWS] = address_of(_continuum_rows, _CONTINUUM_FN_SIG)
            addr[_A_AMP], addr[_A_DIV] = amplitude, div
            c_thr = np.append(c_thr, seed_tol)
            c_joints = np.ascontiguousarray(c_joints, dtype=np.int64)
        j = red.free_joint
        head = (addr, one.ints[1], plan.branches, one.margin_branches, one.steps, one.noise)
        limits = np.array([robot.lower[j], robot.upper[j]], dtype=np.float64)
        middle = (unit_grid(n_samples), plan.ends, one.twins)
        tail = (*_tail(robot, thresholds, reach), c_joints, c_thr)
        return _Fixed(head, middle, limits, tail, one.hint_range)

    return _kept(red, ("sweep", n_samples, thresholds, seed_tol), make)


def settle_one(
    robot: Any,
    red: Any,
    chain: Array,
    world: Array,
    lo: Array,
    hi: Array,
    n_samples: int,
    params: Array,
    thresholds: tuple[float, ...],
    reach: Array,
    clip_rel: float,
    seed_tol: float,
    meet: Array,
    only_inside: bool,
) -> Settled | None:
    """The one pose of ``chain``/``world (1, 4, 4)`` searched over ``[lo, hi]`` (``(1,)`` each), certified and settled
    in one compiled call, as the solver's general path does it (the same values); None where ``red`` has no one-pass
    search for ``n_samples``. ``thresholds`` and ``reach``: ``dedupe.settle``'s; ``clip_rel``: the
    reach (relative to ``hi - lo``) within which a multiple root outside theta*'s limits is clipped to them;
    ``seed_tol``: the pose error within which a candidate is checked for a continuum (``continuum_joints``);
    ``meet``: the reach per joint within which two solutions may be one root (``MEET``); ``only_inside``: the
    solutions within the joint limits only (the solver's ``limits``)."""
    fixed = sweep_fixed(robot, red, n_samples, thresholds, reach, seed_tol)
    if fixed is None:
        return None
    lo, hi = writable(lo), writable(hi)
    hlo, hhi = (lo, hi) if fixed.hint_range is None else (writable(a) for a in fixed.hint_range(red, chain))
    clip = float(clip_rel * (hi[0] - lo[0]))
    p = np.ascontiguousarray(params, dtype=np.float64)
    buffers = (search.MAX_CAND, search.MAX_FAM)  # (read here: a test may cut them)
    status, c, reachable, q, ep, eg, inside, mult = _settle_one(
        *fixed.head, p, hlo, hhi, lo, hi, *fixed.middle, *buffers, fixed.limits, clip, writable(world), *fixed.tail,
        writable(meet), bool(only_inside),
    )  # fmt: skip
    return Settled(status, c, reachable, q, ep, eg, inside, mult, _NONE, _NO_BRANCH, _NONE)


def settle_closed(
    robot: Any,
    red: Any,
    world: Array,
    params: Array,
    thresholds: tuple[float, ...],
    reach: Array,
    meet: Array,
    only_inside: bool,
) -> Settled | None:
    """A closed form's one pose ``world (1, 4, 4)``: every branch (in order: ``Settled.branch``) certified and settled
    in one compiled call, as ``settle_one``; ``MEET`` where two branches meet (``meet``: the reach per joint within
    which two kept ones do); None where ``red`` has no all-branch configuration kernel."""
    fixed = closed_fixed(robot, red, thresholds, reach)
    if fixed is None:
        return None
    addr, nb, theta, branch, tail, s_thr = fixed
    p = np.ascontiguousarray(params, dtype=np.float64)
    status, c, reachable, q, ep, eg, inside, mu, err_all = _settle_closed(
        addr, p, writable(world), nb, *tail, s_thr, writable(meet), bool(only_inside)
    )
    return Settled(status, c, reachable, q, ep, eg, inside, mu, theta, branch, err_all, bool(addr[_A_SING] != 0))


def closed_fixed(robot: Any, red: Any, thresholds: tuple[float, ...], reach: Array) -> tuple[Any, ...] | None:
    """What ``every_branch_settled`` takes for the closed form ``red`` besides the pose's rows, the target, the
    meeting reach and ``only_inside``, kept per reduction: ``(addr, nb, theta, branch, tail, s_thr)``; None where
    ``red`` has no all-branch configuration kernel."""

    def make() -> tuple[Any, ...] | None:
        cfgs = owned_kernel(red, "kernel_configurations")
        if cfgs is None:
            return None
        addr = np.zeros(_A_SIZE, dtype=np.int64)
        addr[_A_CERTIFY] = address_of(_certify_every_branch, _EVERY_FN_SIG)
        addr[_A_SETTLE] = address_of(_settle, _SETTLE_FN_SIG)
        addr[_A_CFG] = address_of(cfgs, CONFIGURATIONS_SIG)
        s_thr = np.zeros(1)
        cls = red.__class__
        owner = defining_class(cls, "singular_kernel")
        sing = None
        if owner is defining_class(cls, "degenerate") and owner is defining_class(cls, "continuum_joints"):
            sing = red.singular_kernel()
        if sing is not None:
            addr[_A_SING], s_thr = sing[0], np.ascontiguousarray(sing[1], dtype=np.float64)
        nb = int(red.n_branches)
        branches = np.arange(nb, dtype=np.int64)
        return addr, nb, np.zeros(nb), branches, _tail(robot, thresholds, reach), s_thr

    return _kept(red, ("closed", thresholds), make)
