"""One pose from its chain pose to its final candidates in one compiled call: the search (``fastsweep``'s one-pass
kernels), the certification (``fastcertify``) and the settling (``dedupe.settle``: limits, duplicates) chained.

Each of the three, called from Python, costs more in Python steps around its kernel (buffers, argument checks,
candidate records) than the kernel's own work takes for one pose: ~50 of a C-Arm pose's ~100 us. Here one call
takes every argument, allocates the buffers in compiled code, and calls the three kernels by their addresses
(``kernels.address_of``: they are not linked in and recompiled, so this module compiles in about a second). What
it cannot settle on its own it says, and the solver takes that pose the general way (``solver._solve_chunk``):
family spans, a candidate buffer overflow, a multiple root at a limit of theta*, a candidate due a polish.
"""

from __future__ import annotations

import weakref
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from . import fastsweep
from .dedupe import _tolerance, limit_args
from .fastcertify import chain_args
from .fastsweep import AVAILABLE, _plan, writable
from .reductions.kernels import CONFIGURATION_SIG, address_of, lazy_njit
from .sweep import _unit_grid
from .units import orientation_weight

__all__ = ["OK", "SEARCH_ELSEWHERE", "DUE", "Settled", "settle_one"]

Array = NDArray[np.float64]

#: ``settle_one``'s status: the pose's final candidates are given ...
OK = 0
#: ... its search needs the general path (family spans, a buffer overflow, a multiple root at a limit of theta*) ...
SEARCH_ELSEWHERE = 1
#: ... a candidate is due one of the solver's rarer steps (a polish, a snap to a limit).
DUE = 2


class Settled(NamedTuple):
    """``settle_one``'s result: the candidates (theta*, branch, multiplicity), their configurations and errors
    (``q``, ``err_geo``, ``err_paper``), and of the certified ones (``rows``, in order) the wrapped configurations
    ``w``, ``inside`` the limits and ``keep`` (not a duplicate); all empty unless ``status`` is ``OK``."""

    status: int
    theta: Array
    branch: NDArray[np.int64]
    mult: NDArray[np.int64]
    q: Array
    err_geo: Array
    err_paper: Array
    rows: NDArray[np.int64]
    w: Array
    inside: NDArray[np.bool_]
    keep: NDArray[np.bool_]


if AVAILABLE:
    from numba import boolean, float64, int64
    from numba import void as _void

    from ._jit import function_at
    from .dedupe import _SETTLE_SIG, _settle
    from .fastcertify import _CERTIFY_SIG, _certify
    from .fastsweep import _ONE_PASS_SIG

    _ONE_PASS_FN_SIG, _CERTIFY_FN_SIG, _SETTLE_FN_SIG = _void(*_ONE_PASS_SIG), _void(*_CERTIFY_SIG), _void(*_SETTLE_SIG)
    _as_one_pass, _as_certify, _as_settle = (
        function_at(s) for s in (_ONE_PASS_FN_SIG, _CERTIFY_FN_SIG, _SETTLE_FN_SIG)
    )
    #: The kernels' addresses in ``addr``.
    _A_SEARCH, _A_CERTIFY, _A_SETTLE, _A_CFG = range(4)

    @lazy_njit(
        (int64[::1], int64[::1], int64[::1], int64[::1], int64[::1], float64[::1], float64[:, ::1], float64[::1])
        + (float64[::1], float64[::1], float64[::1], float64[::1], float64[::1], int64[:, ::1], int64, int64)
        + (float64[::1], float64, float64[:, :, ::1], float64[:, ::1], float64[:, ::1], boolean[::1])
        + (float64[:, ::1], float64, float64[::1], boolean[::1], float64[::1], float64[::1], float64[::1], boolean)
        + (float64[::1], float64[::1], float64),
        cache=True,
        nogil=True,
    )
    def _settle_one(
        addr, plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, max_cand, max_fam,
        limits, clip, world, H, P, rev, R_end, weight, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale,
    ):  # pragma: no cover  # fmt: skip
        """``settle_one``'s kernel: pose 0 of ``params``/``world`` searched (one-pass kernel at ``addr[_A_SEARCH]``),
        certified and settled; ``limits``: theta*'s limits, ``clip``: how far outside them a multiple root is clipped
        to them (``solver._limit_copies``: the general path's)."""
        # (np.empty and explicit loops: np.zeros, slice copies and the like each add to the first compilation)
        n = rev.shape[0]
        out_t = np.empty((1, max_cand))
        out_b = np.empty((1, max_cand), dtype=np.int64)
        out_m = np.empty((1, max_cand), dtype=np.int64)
        ints = np.empty(6, dtype=np.int64)  # cnt, fcnt, parts (2), counts, pose (when K > 0: all 0)
        flags = np.empty(2, dtype=np.bool_)  # redo, due
        ints[0], ints[1], ints[2], ints[4] = 0, 0, 0, 0
        flags[0], flags[1] = False, False
        fam = np.empty((1, max_fam, 3))
        _as_one_pass(addr[_A_SEARCH])(
            plan, branches, m_branches, steps, noise, params, hlo, hhi, lo, hi, s, ends, twins, out_t, out_b, out_m,
            ints[0:1], fam, ints[1:2], flags[0:1], 0, 1,
        )  # fmt: skip
        K = ints[0]
        status = OK
        if flags[0] or K > max_cand or ints[1] != 0:
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
        rows = np.empty(K, dtype=np.int64)
        w = np.empty((K, n))
        score = np.empty(K)
        inside = np.empty(K, dtype=np.bool_)
        keep = np.empty(K, dtype=np.bool_)
        ints[3] = K
        _as_settle(addr[_A_SETTLE])(
            q, eg, ep, pose, thr, lrev, lower, upper, ltol, beyond, reach, tol, scale, flags[1:2], rows, w, score,
            inside, keep, ints[2:4], ints[4:5], 0, 1,
        )  # fmt: skip
        c = ints[4]
        if flags[1] and status == OK:
            status, c = DUE, 0
        return status, c, theta, branch, mult, q, eg, ep, rows, w, inside, keep


class _Fixed(NamedTuple):
    """What ``_settle_one`` takes for a reduction and sample count besides the pose (``settle_one``)."""

    head: tuple[Any, ...]  # the arguments before the pose's own (addresses, plan, ...)
    middle: tuple[Any, ...]  # between them (the unit grid, theta*'s ends, the twins)
    limits: Array  # theta*'s limits
    tail: tuple[Any, ...]  # after the target (the chain's geometry, the settling's thresholds, limits, tolerances)
    hint_range: Any  # ``EdgeSearch.hint_range`` (the margins' range of a pose), or None: the search's own


_FIXED: weakref.WeakKeyDictionary[object, dict[tuple[Any, ...], _Fixed | None]] = weakref.WeakKeyDictionary()


def _fixed(robot: Any, red: Any, n_samples: int, thresholds: tuple[float, ...], reach: Array) -> _Fixed | None:
    """The fixed arguments of ``_settle_one`` for ``red`` (None: it has no one-pass search for ``n_samples``),
    worked out once per reduction and settings (a reduction's kernels, plan and robot are fixed once it is used)."""
    key = (n_samples, thresholds)
    try:
        per_red = _FIXED.setdefault(red, {})
    except TypeError:  # (an unhashable reduction: worked out every time)
        per_red = {}
    if key in per_red:
        return per_red[key]
    plan = _plan(red)
    one = plan.one_pass
    fixed = None
    if one is not None and (one.n_samples is None or one.n_samples == n_samples):
        addr = np.zeros(4, dtype=np.int64)
        addr[_A_SEARCH] = address_of(one.kernel, _ONE_PASS_FN_SIG)
        addr[_A_CERTIFY] = address_of(_certify, _CERTIFY_FN_SIG)
        addr[_A_SETTLE] = address_of(_settle, _SETTLE_FN_SIG)
        addr[_A_CFG] = address_of(red.kernel[1], CONFIGURATION_SIG)
        j = red.free_joint
        head = (addr, one.ints[1], plan.branches, one.margin_branches, one.steps, one.noise)
        limits = np.array([robot.lower[j], robot.upper[j]], dtype=np.float64)
        middle = (_unit_grid(n_samples), plan.ends, one.twins)
        rev, lower, upper, ltol, beyond = limit_args(robot)
        H, P, crev, R_end = chain_args(robot)
        weight = float(orientation_weight(robot.length_unit))
        thr = np.array(thresholds, dtype=np.float64)
        tail = (H, P, crev, R_end, weight, thr, rev, lower, upper, ltol, beyond, writable(reach), _tolerance(robot))
        fixed = _Fixed(head, middle, limits, tail + (float(robot.length_scale),), one.hint_range)
    per_red[key] = fixed
    return fixed


def settle_one(
    robot: Any,
    red: Any,
    chain: Array,
    world: Array,
    lo: Array,
    hi: Array,
    n_samples: int,
    params: Array,
    thresholds: tuple[float, float, float, float],
    reach: Array,
    clip_rel: float,
) -> Settled | None:
    """The one pose of ``chain``/``world (1, 4, 4)`` searched over ``[lo, hi]`` (``(1,)`` each), certified and settled
    in one compiled call, as the solver's general path does it (the same values); None where ``red`` has no one-pass
    search for ``n_samples`` (or without Numba). ``thresholds`` and ``reach``: ``dedupe.settle``'s; ``clip_rel``: the
    reach (relative to ``hi - lo``) within which a multiple root outside theta*'s limits is clipped to them."""
    if not AVAILABLE:
        return None
    fixed = _fixed(robot, red, n_samples, thresholds, reach)
    if fixed is None:
        return None
    lo, hi = writable(lo), writable(hi)
    hlo, hhi = (lo, hi) if fixed.hint_range is None else (writable(a) for a in fixed.hint_range(red, chain))
    clip = float(clip_rel * (hi[0] - lo[0]))
    p = np.ascontiguousarray(params, dtype=np.float64)
    buffers = (fastsweep.MAX_CAND, fastsweep.MAX_FAM)  # (read here: a test may cut them)
    status, c, theta, branch, mult, q, eg, ep, rows, w, inside, keep = _settle_one(
        *fixed.head, p, hlo, hhi, lo, hi, *fixed.middle, *buffers, fixed.limits, clip, writable(world), *fixed.tail
    )
    return Settled(status, theta, branch, mult, q, eg, ep, rows[:c], w[:c], inside[:c], keep[:c])
