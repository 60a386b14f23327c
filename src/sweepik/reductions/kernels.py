"""Scalar kernels of the C-Arm reductions, compiled with Numba for the generic engine (:mod:`sweepik.engine.search`).

A reduction's kernel is a pair of compiled functions with fixed signatures (``RESIDUAL_SIG``,
``CONFIGURATION_SIG``): ``residual(params, theta, branch) -> float`` and ``configuration(params, theta, branch,
out)``, where ``params`` is one row of ``Reduction.kernel_params(poses)``. The engine receives them as
addresses of compiled code (``address_of``), so it is compiled once for every reduction. These two compute exactly what
``CArmD1``/``CArmTheta2`` compute vectorised (``residual``, ``solve_rest``), for one pose, theta* and branch.
"""

from __future__ import annotations

import math
from functools import cache
from typing import Any

import numba
import numpy as np
from numba import boolean, float64, int64, types, void

from sweepik._jit import ERROR_MODEL, function_at, internal
from sweepik.errors import UnknownOptionError
from sweepik.subproblems.trig import wrap_pi

_njit: Any = numba.njit  # (untyped: Numba's stubs do not list every option sweepik passes)

#: Same as carm.DISC_TOL (kept here so that this module has no import cycle with carm.py).
DISC_TOL = 1e-12

#: Row layout of ``kernel_params`` for both C-Arm reductions: Px, Py, Pz, z (3), L1, L2, R (9, row-major), and Px
#: as given (the first Px is snapped to 0 when tiny, ``carm.PX_SNAP_REL``; the sample hints take it as given).
N_PARAMS = 18
#: Samples placed across the narrow window |Pz - d1| ~ |Px| where theta2 swings by pi (carm-d1's hints), at
#: d1 = Pz - |Px| tan(a) for angles a evenly inside (-pi/2, pi/2).
SWING_SAMPLES = 16
TAN_SWING = np.tan(np.linspace(-np.pi / 2, np.pi / 2, SWING_SAMPLES + 2)[1:-1])
#: Hints per pose of carm-d1 (``CArmD1.sample_hints``): the rail positions where the wrist comes within reach and
#: leaves it (outer and inner circle), Pz, and the swing window.
N_D1_HINTS = 5 + SWING_SAMPLES


def _elbow(u: float, Py: float, eps: float, L1: float, L2: float) -> tuple[float, float]:
    """(C34, S34) of the planar two-link problem (NaN outside its domain), as carm._CArmBase._elbow."""
    rho2 = u * u + Py * Py
    k = (rho2 + L2 * L2 - L1 * L1) / (2.0 * L2)
    disc = rho2 - k * k
    if disc < -DISC_TOL * (L1 + L2) ** 2 or not rho2 > 0.0:
        # (rho2 = 0, the wrist on joint 3's axis, is inside the domain only when L1 = L2: there NumPy's 0 / 0 is NaN)
        return math.nan, math.nan
    s = eps * math.sqrt(max(disc, 0.0))
    return (k * u - s * Py) / rho2, (k * Py + s * u) / rho2


def _elbow_residual(
    c2: float, s2: float, u: float, Py: float, zx: float, zy: float, zz: float, eps: float, L1: float, L2: float
) -> float:
    c34, s34 = _elbow(u, Py, eps, L1, L2)
    return c34 * (c2 * zx + s2 * zz) + s34 * zy


def _d1_position(Px: float, Pz: float, d1: float, b: int) -> tuple[float, float, float, float]:
    """(C2, S2, u, elbow sign) of branch b at rail position d1 (carm-d1)."""
    sigma = 1.0 if b < 2 else -1.0
    eps = 1.0 if b % 2 == 0 else -1.0
    t = Pz - d1
    r = math.sqrt(Px * Px + t * t)  # (not math.hypot: ~8 % of a search, and no overflow at robot scales)
    if r > 0.0:
        return sigma * Px / r, sigma * t / r, sigma * r, eps
    return sigma, 0.0, 0.0, eps


def _carm_d1(p, d1: float, b: int) -> float:
    Px, Py, Pz, zx, zy, zz, L1, L2 = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    c2, s2, u, eps = _d1_position(Px, Pz, d1, b)
    return _elbow_residual(c2, s2, u, Py, zx, zy, zz, eps, L1, L2)


def _carm_d1_all(p, d1: float, out) -> None:
    """The residuals of the four branches at rail position d1 into ``out[:4]``: bit for bit those of
    ``_carm_d1(p, d1, b)``, with what the branches share (the rail-to-wrist distance, the elbow's square root)
    computed once. The branches differ by the signs sigma and eps only, and IEEE arithmetic is symmetric under a
    change of sign (``fl(-a * b) = -fl(a * b)``, the same for division, sums and differences), so each branch's
    sign-flipped operands are exactly its own intermediate values."""
    Px, Py, Pz, zx, zy, zz, L1, L2 = p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7]
    t = Pz - d1
    r = math.sqrt(Px * Px + t * t)
    # _elbow: u * u = r * r for both signs
    rho2 = r * r + Py * Py
    if not (r > 0.0 and rho2 > 0.0):  # the wrist on joint 2's axis (or r * r below the floats): branch by branch
        for b in range(4):
            out[b] = _carm_d1(p, d1, b)
        return
    # _d1_position: c2 = sigma Px / r, s2 = sigma t / r, u = sigma r; c2 zx + s2 zz = sigma a
    a = Px / r * zx + t / r * zz
    k = (rho2 + L2 * L2 - L1 * L1) / (2.0 * L2)
    disc = rho2 - k * k
    if disc < -DISC_TOL * (L1 + L2) ** 2:
        for b in range(4):
            out[b] = math.nan
        return
    sq = math.sqrt(max(disc, 0.0))
    kr, sp, kp, sr = k * r, sq * Py, k * Py, sq * r
    for b in range(4):
        sigma = 1.0 if b < 2 else -1.0
        eps = 1.0 if b % 2 == 0 else -1.0
        # k u - s Py and k Py + s u with u = sigma r, s = eps sq
        c34 = (sigma * kr - eps * sp) / rho2
        s34 = (kp + (eps * sigma) * sr) / rho2
        out[b] = c34 * (sigma * a) + s34 * zy


def _carm_theta2(p, th2: float, b: int) -> float:
    Px, Py, zx, zy, zz, L1, L2 = p[0], p[1], p[3], p[4], p[5], p[6], p[7]
    eps = 1.0 if b == 0 else -1.0
    c2, s2 = math.cos(th2), math.sin(th2)
    if abs(c2) <= 1e-300:
        return math.nan
    return _elbow_residual(c2, s2, Px / c2, Py, zx, zy, zz, eps, L1, L2)


RESIDUAL_SIG = float64(float64[::1], float64, int64)
#: ``residuals(params, theta, out)``: every branch's residual at theta* into ``out`` (optional, see
#: ``Reduction.kernel_residuals``).
RESIDUALS_SIG = void(float64[::1], float64, float64[::1])
CONFIGURATION_SIG = void(float64[::1], float64, int64, float64[::1])
#: ``configurations(params, theta, out)``: every branch's configuration at theta* into ``out (n_branches, n)``
#: (optional, see ``Reduction.kernel_configurations``).
CONFIGURATIONS_SIG = void(float64[::1], float64, float64[:, ::1])
#: ``hints(params, out)``: a reduction's sample hints of one pose (optional, see ``Reduction.kernel_hints``).
HINTS_SIG = void(float64[::1], float64[::1])
#: ``swing(amplitude, amplitudes, params, lo, hi, n, periodic, steps, out, start, stop)``: a generic sweep's swing
#: samples of poses ``start .. stop - 1`` (``geometric.swing_hints``; ``amplitude`` and ``amplitudes`` the
#: addresses of its amplitude kernels), which the engine calls pose by pose (``search.EdgeSearch``).
SWING_SIG = void(
    int64, int64, float64[:, ::1], float64[::1], float64[::1], int64, boolean, int64[::1], float64[:, ::1], int64,
    int64,
)  # fmt: skip
#: ``singular(params, thr, out, low, start, stop)``: a closed form's poses ``start .. stop - 1`` to hand to the
#: general path (``out``: ``degenerate``; ``low``: where ``continuum_joints`` may flag a branch; see
#: ``Reduction.singular_kernel``).
SINGULAR_SIG = void(float64[:, ::1], float64[::1], boolean[::1], boolean[::1], int64, int64)
_elbow = internal(_elbow)
_d1_position = internal(_d1_position)
_elbow_residual = internal(_elbow_residual)


class LazyKernel:
    """A Numba function with one explicit signature, compiled (or loaded from the disk cache) on first use instead
    of at import: a process loads only the kernels its arms need (each takes 10-100 ms to load from the cache).

    Call it like the compiled function; :func:`address_of` takes it like a dispatcher. Only for functions called
    from Python (compiled code needs the dispatcher itself). ``fn`` may be a dispatcher that compiled code calls too:
    the kernel is then that dispatcher's overload for ``sig`` (compiled once, not a second time by a dispatcher of
    its own), and ``options`` are that dispatcher's.
    """

    def __init__(self, fn: Any, sig: Any, **options: Any) -> None:
        self._shared = fn if hasattr(fn, "overloads") else None
        self.py_func = fn if self._shared is None else fn.py_func
        # (no C wrapper: the engine calls a kernel by its address with Numba's own convention, Python through the
        # CPython wrapper; a C wrapper costs ~0.05 s of compilation each)
        self._sig, self._options = sig, {"error_model": ERROR_MODEL, "no_cfunc_wrapper": True, **options}
        self._dispatcher: Any = None
        self._unchecked: Any = None

    @property
    def dispatcher(self) -> Any:
        if self._dispatcher is None:
            if self._shared is not None:
                self._shared.compile(self._sig)
                self._dispatcher = self._shared
            else:
                self._dispatcher = _njit(self._sig, **self._options)(self.py_func)
        return self._dispatcher

    def _overload(self) -> Any:
        """The dispatcher's compiled overload for the signature (None where Numba keeps none)."""
        from numba.core import sigutils

        args, _ = sigutils.normalize_signature(self._sig)
        return self.dispatcher.overloads.get(tuple(args))

    @property
    def signature(self) -> Any:
        """The compiled signature (a Numba ``Signature``)."""
        return self._overload().signature

    @property
    def unchecked(self) -> Any:
        """The compiled function's own CPython entry point, without the dispatcher's type resolution (~1 us of a
        call with 27 arguments: a single pose's whole call is ~10). Unchecked: only for a caller that passes exactly
        the signature's types (arrays of its dtype, dimensions and layout); another type would be read as this one.
        The dispatcher where Numba gives no entry point."""
        if self._unchecked is None:
            self._unchecked = getattr(self._overload(), "entry_point", None) or self.dispatcher
        return self._unchecked

    def __call__(self, *args: Any) -> Any:
        d = self._dispatcher
        return (self.dispatcher if d is None else d)(*args)


def lazy_njit(sig: Any, **options: Any) -> Any:
    """Decorator: :class:`LazyKernel` of the function, with ``sig`` and Numba's ``options`` (e.g. ``cache=True``)."""
    return lambda fn: LazyKernel(fn, sig, **options)


carm_d1_residual: Any
carm_theta2_residual: Any
carm_d1_residuals: Any
carm_d1_configuration: Any
carm_theta2_configuration: Any
_carm_d1 = _njit(cache=True, error_model=ERROR_MODEL, no_cfunc_wrapper=True)(_carm_d1)  # (_carm_d1_all calls it)
carm_d1_residual = LazyKernel(_carm_d1, RESIDUAL_SIG)  # (its overload for the engine's signature)
carm_theta2_residual = LazyKernel(_carm_theta2, RESIDUAL_SIG, cache=True)
carm_d1_residuals = LazyKernel(_carm_d1_all, RESIDUALS_SIG, cache=True)


def owned_kernel(reduction: Any, name: str) -> Any:
    """``reduction.<name>`` (an optional kernel: ``kernel_residuals``, ``kernel_configurations``, ``kernel_hints``) if
    the class that sets ``kernel`` sets it too (as a class attribute, or declares it for its instances to set), else
    None: a subclass with its own ``kernel`` must not get its parent's all-branch kernels."""
    owner = kernel_owner(reduction.__class__)
    if owner is None or name not in vars(owner):
        return None
    # read from the class (a compiled function stored as a class attribute would bind to the instance), unless
    # the instance set its own
    return vars(reduction).get(name, vars(owner)[name])


@cache
def defining_class(cls: type, name: str) -> type | None:
    """The class of ``cls``'s MRO that sets ``name`` (None: none does). Cached: every solve asks."""
    return next((c for c in cls.__mro__ if name in vars(c)), None)


def kernel_owner(cls: type) -> type | None:
    """The class of ``cls``'s MRO that sets ``kernel`` (None: none does)."""
    return defining_class(cls, "kernel")


_ADDRESSES: dict[Any, tuple[int, Any, set[int]]] = {}


def address_of(fn: Any, sig: Any) -> int:
    """The address of ``fn``'s compiled entry point, for an engine kernel to call it through ``as_residual`` & co.
    (``_jit.function_at``): an int costs nothing to pass, where a first-class function argument costs two Python
    calls per kernel call. ``fn`` is a :class:`LazyKernel` or a Numba dispatcher, compiled (here, if need be) for
    ``sig`` (one of this module's ``*_SIG``), return type included: called through its address, a function of another
    signature would read its arguments wrong (UnknownOptionError). Compiles ``fn`` or loads it from the cache on
    first use."""
    known = _ADDRESSES.get(fn)
    if known is None:
        if isinstance(fn, LazyKernel):
            disp, own = fn.dispatcher, fn.signature
        else:
            if not hasattr(fn, "overloads"):
                raise UnknownOptionError(f"a reduction's kernel must be a Numba function ({sig}), got {fn!r}")
            if tuple(sig.args) not in fn.overloads:
                try:  # (a dispatcher without this signature yet: compiled for it, where it may be)
                    fn.compile(tuple(sig.args))
                except Exception as exc:
                    raise UnknownOptionError(
                        f"a reduction's kernel {fn!r} cannot be compiled for the engine's signature {sig}: {exc}"
                    ) from None
            disp, own = fn, fn.overloads[tuple(sig.args)].signature
        cres = disp.overloads[own.args]
        address = int(cres.library.get_pointer_to_function(cres.fndesc.llvm_func_name))
        known = _ADDRESSES[fn] = (address, own, set())
    address, own, checked = known
    if id(sig) not in checked:  # (the engine's signatures are module constants: compared once each)
        if own.args != sig.args or own.return_type != sig.return_type:
            raise UnknownOptionError(f"a reduction's kernel {fn!r} is compiled for {own}, the engine calls it as {sig}")
        checked.add(id(sig))
    return address


#: In compiled code, the function at an address (``address_of``) of each kernel signature.
as_residual = function_at(RESIDUAL_SIG)
as_residuals = function_at(RESIDUALS_SIG)
as_configuration = function_at(CONFIGURATION_SIG)
as_configurations = function_at(CONFIGURATIONS_SIG)
as_hints = function_at(HINTS_SIG)
as_swing = function_at(SWING_SIG)
as_singular = function_at(SINGULAR_SIG)


def _carm_configuration(p, x: float, b: int, out, rail: bool) -> None:
    """Full configuration of branch ``b`` at theta* = ``x`` (d1 if ``rail`` else theta2) into ``out (6,)`` (NaN
    where the branch does not exist), as CArmD1/CArmTheta2.solve_rest."""
    Px, Py, Pz, L1, L2 = p[0], p[1], p[2], p[6], p[7]
    if rail:
        d1 = x
        c2, s2, u, eps = _d1_position(Px, Pz, d1, b)
    else:
        eps = 1.0 if b == 0 else -1.0
        c2, s2 = math.cos(x), math.sin(x)
        if abs(c2) <= 1e-300:
            for i in range(6):
                out[i] = math.nan
            return
        u = Px / c2
        d1 = Pz - s2 * u
    c34, s34 = _elbow(u, Py, eps, L1, L2)
    if math.isnan(c34):
        for i in range(6):
            out[i] = math.nan
        return
    th3 = math.atan2(u - L2 * c34, L2 * s34 - Py)
    th4 = math.atan2(s34, c34) - th3
    th4 = wrap_pi(th4)
    # V = R_B2^T R_D rows, N = R_24^T V; R = p[8:17] row-major
    v0 = (c2 * p[8] + s2 * p[14], c2 * p[9] + s2 * p[15], c2 * p[10] + s2 * p[16])
    v1z = -s2 * p[10] + c2 * p[16]
    v2 = (-p[11], -p[12], -p[13])
    n0z = s34 * v0[2] + c34 * v2[2]
    n1x = c34 * v0[0] - s34 * v2[0]
    n1y = c34 * v0[1] - s34 * v2[1]
    out[0] = d1
    out[1] = math.atan2(s2, c2)
    out[2] = th3
    out[3] = th4
    out[4] = math.atan2(n0z, v1z)
    out[5] = math.atan2(n1x, n1y)


def _carm_d1_configuration(p, x: float, b: int, out) -> None:
    _carm_configuration(p, x, b, out, True)


def _carm_theta2_configuration(p, x: float, b: int, out) -> None:
    _carm_configuration(p, x, b, out, False)


def _carm_d1_hints(p, out) -> None:
    """carm-d1's sample hints of one pose into ``out (N_D1_HINTS,)``, value for value as ``CArmD1.sample_hints``
    (NaN where no rail position brings the wrist onto a circle)."""
    Px, Py, Pz, L1, L2 = p[17], p[1], p[2], p[6], p[7]
    q2 = Px * Px + Py * Py
    for k in range(2):
        r = ((L1 + L2) ** 2 if k == 0 else (L1 - L2) ** 2) - q2
        t = math.sqrt(r) if r >= 0.0 else math.nan
        out[2 * k], out[2 * k + 1] = Pz - t, Pz + t
    out[4] = Pz
    for m in range(SWING_SAMPLES):
        out[5 + m] = Pz - abs(Px) * TAN_SWING[m]


def _carm_params(poses, L1: float, L2: float, snap: float, out) -> None:
    """The C-Arm's kernel parameter rows (``N_PARAMS`` layout) of chain poses ``(N, 4, 4)`` into ``out``, as
    ``_CArmBase.kernel_params`` lays them out: Px snapped to 0 where ``|Px| <= snap``, and as given in column 17."""
    for i in range(poses.shape[0]):
        px = poses[i, 0, 3]
        out[i, 0] = 0.0 if abs(px) <= snap else px
        out[i, 1], out[i, 2] = poses[i, 1, 3], poses[i, 2, 3]
        for r in range(3):
            out[i, 3 + r] = poses[i, r, 2]
        out[i, 6], out[i, 7] = L1, L2
        for r in range(3):
            for c in range(3):
                out[i, 8 + 3 * r + c] = poses[i, r, c]
        out[i, 17] = px


carm_d1_hints = LazyKernel(_carm_d1_hints, HINTS_SIG, cache=True)
# (a row per pose in one call: the same columns by NumPy slicing cost ~10 NumPy calls, ~10 us for one pose)
_poses_type = types.Array(float64, 3, "A", readonly=True)  # (takes writable and read-only poses alike)
carm_params = LazyKernel(_carm_params, void(_poses_type, float64, float64, float64, float64[:, ::1]), cache=True)
_carm_configuration = internal(_carm_configuration)
carm_d1_configuration = LazyKernel(_carm_d1_configuration, CONFIGURATION_SIG, cache=True)
carm_theta2_configuration = LazyKernel(_carm_theta2_configuration, CONFIGURATION_SIG, cache=True)
