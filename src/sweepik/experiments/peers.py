"""Other all-solutions IK solvers, called on sweepik's robots (the optional ``bench`` extra: ``eaik``, ``ik-geo``,
``ssik``).

``sweepik bench --arms`` times them on the same poses as sweepik; the test suite uses the same adapters as
independent oracles (``tests/oracles.py``, which also FK-checks their answers). EAIK and IK-Geo take a revolute
chain in product-of-exponentials form: axes ``H (6, 3)`` and link vectors ``P (7, 3)`` at q = 0 with the end
orientation the identity, so a target's rotation is passed as ``R_target @ R_end^T`` (``chain.R_end``).

* EAIK (``eaik.IK_HP.HPRobot(H, P)``): its own automatic decomposition; ``hasKnownDecomposition()`` says whether it
  can solve the arm at all.
* IK-Geo (``ik_geo.Robot.<decomposition>(H, P)``): the decomposition is chosen here from the axes of the chain or
  of the reversed chain (a structure at the base becomes one at the tool), with the points of intersecting axes
  moved to their common point as IK-Geo expects. Only its closed forms are used by default: in ik-geo 1.0.3 its
  1-D and 2-D searches are coarse and miss roots.
* ssik (``ssik.Manipulator``; 6R and 7R revolute arms, closed forms and, for arms without one, a Raghavan-Roth
  elimination): built from the same chain (:func:`ssik_manipulator`), lengths in metres because ssik's tolerances
  are absolute and metric (an arm in millimetres lost solutions with them). For the benchmark, ssik at its best
  (:func:`ssik_solver`): its prebuilt artifact when it ships one of the same geometry (:func:`ssik_prebuilt`:
  equal up to constant base and tool transforms), else its C++ backend on our chain with the per-arm precompute
  done once, as ``ssik build`` would bake it; the live ``Manipulator.solve`` redoes that precompute on every call
  (~4x slower on the non-Pieper arms).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from sweepik.errors import SweepikError, UnknownOptionError
from sweepik.model.chain import Chain
from sweepik.model.units import mm_per_unit

Array = NDArray[np.float64]

__all__ = [
    "chain_arrays",
    "eaik_robot",
    "ikgeo_setup",
    "metres_per_unit",
    "ssik_manipulator",
    "ssik_prebuilt",
    "SsikPrebuilt",
    "peers_for",
    "STRUCT_TOL",
    "IKGEO_KINDS",
    "SSIK_FIT_TOL",
    "SSIK_SOURCES",
    "ssik_solver",
    "ssik_status",
]

#: Axes count as parallel / intersecting below this (sine of the angle; distance / ``length_scale``).
STRUCT_TOL = 1e-9

#: IK-Geo's decompositions in order of preference (closed form, then 1D search, then 2D search), with what
#: each needs (0-based joints): a spherical wrist = joints 3, 4, 5 through one point; "par" = parallel axes;
#: "int" = intersecting axes.
IKGEO_KINDS: tuple[tuple[str, str, tuple[tuple[str, tuple[int, ...]], ...]], ...] = (
    ("spherical_two_parallel", "closed", (("int", (3, 4, 5)), ("par", (1, 2)))),
    ("spherical_two_intersecting", "closed", (("int", (3, 4, 5)), ("int", (0, 1)))),
    ("spherical", "closed", (("int", (3, 4, 5)),)),
    ("three_parallel_two_intersecting", "closed", (("par", (1, 2, 3)), ("int", (4, 5)))),
    ("three_parallel", "closed", (("par", (1, 2, 3)),)),
    ("two_parallel", "1d", (("par", (1, 2)),)),
    ("two_intersecting", "1d", (("int", (4, 5)),)),
    ("gen_six_dof", "2d", ()),
)


def chain_arrays(robot: Any) -> tuple[Array, Array, Array, NDArray[np.bool_]]:
    """``(H, P, R_end, revolute)`` of the robot's chain, as plain writable arrays."""
    c = robot.chain
    return (
        np.array(c.H, dtype=np.float64),
        np.array(c.P, dtype=np.float64),
        np.array(c.R_end, dtype=np.float64),
        np.array(c.revolute, dtype=bool),
    )


_EAIK_CACHE: dict[bytes, Any] = {}


def eaik_robot(H: Array, P: Array) -> Any:
    """EAIK's robot for the chain (cached per chain; ImportError without EAIK)."""
    key = H.tobytes() + P.tobytes()
    if key not in _EAIK_CACHE:
        from eaik.IK_HP import HPRobot

        _EAIK_CACHE[key] = HPRobot(H, P)
    return _EAIK_CACHE[key]


def _common_point(H: Array, pts: Array, joints: tuple[int, ...], tol: float) -> Array | None:
    """The point where the axes of ``joints`` (directions H, through points pts) meet, or None."""
    hs = H[list(joints)]
    # Lines meet in one point only if not all parallel (two of three may be, on one line: a wrist at q = 0).
    if max(np.linalg.norm(np.cross(hs[0], h)) for h in hs[1:]) < 1e-6:
        return None
    A = np.zeros((3, 3))
    b = np.zeros(3)
    for j in joints:
        M = np.eye(3) - np.outer(H[j], H[j])
        A += M
        b += M @ pts[j]
    x = np.asarray(np.linalg.solve(A, b), dtype=np.float64)
    for j in joints:
        d = x - pts[j]
        if np.linalg.norm(d - H[j] * (H[j] @ d)) > tol:
            return None
    return x


def _ikgeo_model(H: Array, P: Array, kinds: set[str], tol_len: float) -> tuple[str, str, Array] | None:
    """First IK-Geo decomposition (from ``IKGEO_KINDS``, restricted to ``kinds``) that fits the chain, and
    the link vectors remodelled for it (points of intersecting axes moved to their common point)."""
    pts = np.cumsum(P[:-1], axis=0)  # a point of each axis
    tool = np.sum(P, axis=0)
    for name, kind, needs in IKGEO_KINDS:
        if kind not in kinds:
            continue
        points = pts.copy()
        fits = True
        for what, joints in needs:
            if what == "par":
                h0 = H[joints[0]]
                fits = all(np.linalg.norm(np.cross(h0, H[j])) <= STRUCT_TOL for j in joints[1:])
            else:
                x = _common_point(H, pts, joints, tol_len)
                fits = x is not None
                if fits:
                    points[list(joints)] = x
            if not fits:
                break
        if fits:
            P_new: Array = np.diff(np.concatenate([np.zeros((1, 3)), points, tool[None]]), axis=0)
            return name, kind, P_new
    return None


def ikgeo_setup(ik_geo: Any, robot: Any, kinds: set[str]) -> tuple[Any, str, str, bool, Array] | None:
    """``(ik_geo robot, decomposition, kind, reversed, R_end of the chain used)`` for a 6R robot, or None when
    no decomposition of ``kinds`` ("closed", "1d", "2d") fits the chain or the reversed chain."""
    L = float(robot.length_scale)
    candidates = []
    for reverse in (False, True):
        chain: Chain = robot.chain.reversed() if reverse else robot.chain
        H, P = np.array(chain.H), np.array(chain.P)
        model = _ikgeo_model(H, P, kinds, STRUCT_TOL * L)
        if model is not None:
            order = [k for k, _, _ in IKGEO_KINDS].index(model[0])
            candidates.append((order, reverse, model, chain))
    if not candidates:
        return None
    _, reverse, (name, kind, P_new), chain = min(candidates, key=lambda c: (c[0], c[1]))
    # self-check of the remodelled chain: the same FK as the original one
    remodelled = Chain(chain.H, P_new, chain.revolute, chain.R_end)
    q_chk = np.linspace(-2.5, 2.9, 6)
    Ta, Tb = chain.fk(q_chk), remodelled.fk(q_chk)
    if np.max(np.abs(Ta[:3, :3] - Tb[:3, :3])) > 1e-9 or np.max(np.abs(Ta[:3, 3] - Tb[:3, 3])) > 1e-9 * L:
        raise AssertionError("ik_geo adapter: remodelled chain does not reproduce the FK")  # pragma: no cover
    H = np.ascontiguousarray(chain.H, dtype=np.float64)
    return getattr(ik_geo.Robot, name)(H, np.ascontiguousarray(P_new)), name, kind, reverse, np.array(chain.R_end)


#: A prebuilt ssik artifact is the same arm as ours when ``A fk_ssik(q) B`` reproduces ``robot.fk(q)`` this closely
#: at every check configuration: rotation entries, and positions divided by ``length_scale``. An exact match agrees
#: to rounding (~1e-15); the same arm from rounded published parameters differs by ~1e-5 and is no match.
SSIK_FIT_TOL = 1e-9

#: Configurations (rad) at which the ssik chains' FK is compared with ``robot.fk``.
_SSIK_CHECK_Q = np.array(
    [
        [-2.5, -1.42, -0.34, 0.74, 1.82, 2.9],
        [0.3, 2.1, -1.7, 2.6, -0.9, -2.2],
        [1.1, -0.6, 2.4, -2.8, 0.5, 1.6],
        [-0.8, 0.9, 0.2, -1.3, 2.7, -0.4],
    ]
)


def metres_per_unit(robot: Any) -> float:
    """Metres in one length unit of ``robot`` (ssik works in metres)."""
    return mm_per_unit(robot.length_unit) / 1000.0


def _in_metres(T: ArrayLike, m_per_unit: float) -> Array:
    """Pose(s) ``(..., 4, 4)`` with the position multiplied by ``m_per_unit``."""
    out = np.array(T, dtype=np.float64)
    out[..., :3, 3] *= m_per_unit
    return out


def _ssik_fit_error(robot: Any, fk_ssik: Callable[[Array], Array], A: Array, B: Array) -> float:
    """Largest deviation of ``A fk_ssik(q) B`` from ``robot.fk(q)`` (in metres) over ``_SSIK_CHECK_Q``: rotation
    entries, and positions divided by the arm's size."""
    u = metres_per_unit(robot)
    ours = _in_metres(robot.fk(_SSIK_CHECK_Q), u)
    err = 0.0
    for q, T in zip(_SSIK_CHECK_Q, ours, strict=True):
        M = A @ fk_ssik(q) @ B
        err = max(err, float(np.max(np.abs(M[:3, :3] - T[:3, :3]))))
        err = max(err, float(np.max(np.abs(M[:3, 3] - T[:3, 3]))) / (robot.length_scale * u))
    return err


def _ssik_revolute_6r(robot: Any) -> tuple[Array, Array, Array]:
    """``(H, P, R_end)`` of a 6R robot; ValueError for any other arm."""
    H, P, R_end, rev = chain_arrays(robot)
    if len(rev) != 6 or not rev.all():
        kinds = "".join("R" if r else "P" for r in rev)
        raise SweepikError(f"ssik solves 6R arms (six revolute joints); {robot.name} is {kinds}")
    return H, P, R_end


_SSIK_CACHE: dict[tuple[bytes, str, bytes | None], Any] = {}


def ssik_manipulator(robot: Any, *, limits: bool = True) -> Any:
    """ssik's solver for a 6R ``robot``: an ``ssik.Manipulator`` built from ``robot.chain`` (cached per chain).

    Lengths in metres (ssik's tolerances are absolute and metric): its ``fk(q)`` is ``robot.fk(q)`` in the world
    frame (base and tool included) with the position times ``metres_per_unit(robot)``, which is all a target needs
    (checked on a few configurations at construction). ``limits=True``: the robot's joint limits, so ``solve``
    (``respect_limits=True``, its default) drops answers outside them; ``limits=False``: every joint continuous,
    answers wrapped to (-pi, pi].
    The first ``solve`` of an arm without a closed form in ssik derives its Raghavan-Roth elimination with SymPy
    (1.5 to 3.5 minutes on the bundled swept arms; ssik keeps it on disk, ``~/.cache/ssik``, for later processes).
    ValueError for an arm that is not 6R: ssik has no solver for prismatic joints (it dispatches such a chain to a
    revolute solver that answers nothing or raises); ImportError without ssik.
    """
    H, P, R_end = _ssik_revolute_6r(robot)
    lim = np.array(robot.limits, dtype=np.float64) if limits else None
    key = (robot.chain.key(), robot.length_unit, None if lim is None else lim.tobytes())
    if key not in _SSIK_CACHE:
        import ssik
        from ssik.internals import JointSpec, build_kinbody

        u = metres_per_unit(robot)
        specs = []
        for i in range(6):
            T_left = np.eye(4)
            T_left[:3, 3] = P[i] * u
            T_right = None
            if i == 5:  # the tool: the last link vector and the end orientation
                T_right = np.eye(4)
                T_right[:3, :3], T_right[:3, 3] = R_end, P[6] * u
            bounds = None if lim is None else (float(lim[i, 0]), float(lim[i, 1]))
            specs.append(JointSpec(T_left, H[i], "revolute", T_right, name=robot.joint_names[i], limits=bounds))
        arm = ssik.Manipulator(build_kinbody(specs))
        if _ssik_fit_error(robot, arm.fk, np.eye(4), np.eye(4)) > SSIK_FIT_TOL:
            raise AssertionError("ssik adapter: the ssik chain does not reproduce the FK")  # pragma: no cover
        _SSIK_CACHE[key] = arm
    return _SSIK_CACHE[key]


@dataclass(frozen=True, eq=False)
class SsikPrebuilt:
    """One of ssik's prebuilt artifacts that is the same arm as a robot: ``robot.fk(q) = A fk(q) B`` (lengths in
    metres) for every ``q``, with ``fk`` the artifact's."""

    #: Catalogue name (``ssik.list_arms()``).
    name: str
    #: The artifact module (``ssik.prebuilt.<vendor>.<model>_ik``): ``solve(T)``, ``fk(q)``.
    module: Any
    #: ``ssik.Manipulator.from_prebuilt(name)``: the artifact's chain (``kinbody``), ``joint_limits``, ``solver_name``.
    manipulator: Any
    #: ``(4, 4)``: the robot's world frame from the artifact's base frame (metres).
    A: Array
    #: ``(4, 4)``: the artifact's end frame to the robot's tool frame (metres).
    B: Array
    #: The artifact's joint limits are the robot's (its ``solve`` then drops what sweepik's drops).
    same_limits: bool

    def target(self, T_world_tool: Array, m_per_unit: float) -> Array:
        """The artifact's target ``A^-1 T B^-1`` for a pose ``(4, 4)`` of the robot (its length unit)."""
        return np.asarray(self._A_inv @ _in_metres(T_world_tool, m_per_unit) @ self._B_inv)

    @cached_property
    def _A_inv(self) -> Array:
        return np.asarray(np.linalg.inv(self.A), dtype=np.float64)

    @cached_property
    def _B_inv(self) -> Array:
        return np.asarray(np.linalg.inv(self.B), dtype=np.float64)


def _axis_lines(kb: Any) -> tuple[Array, Array]:
    """Directions ``(n, 3)`` and points ``(n, 3)`` of the joint axes of an ssik KinBody at q = 0 (its base frame)."""
    T = np.eye(4)
    dirs, points = [], []
    for j in kb.joints:
        T = T @ j.T_left
        dirs.append(T[:3, :3] @ j.axis)
        points.append(T[:3, 3].copy())
        T = T @ j.T_right
    return np.array(dirs), np.array(points)


def _fit_base_tool(robot: Any, kb: Any, fk_ssik: Callable[[Array], Array]) -> tuple[Array, Array]:
    """``(A, B)`` with ``robot.fk(q) ~ A fk_ssik(q) B`` (metres), fitted on the joint axes at q = 0: A's rotation
    takes the ssik axis directions onto ours (Kabsch), its translation puts the ssik axis points on our axis lines
    (least squares), and B closes the loop at q = 0. Whether it fits is for the caller to check."""
    H, P, _ = _ssik_revolute_6r(robot)
    u = metres_per_unit(robot)
    h_s, p_s = _axis_lines(kb)
    p_o = np.cumsum(P[:-1], axis=0) * u
    U, _, Vt = np.linalg.svd(H.T @ h_s)
    R = U @ np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt))]) @ Vt
    M = np.zeros((3, 3))
    b = np.zeros(3)
    for h, x, y in zip(H, p_s, p_o, strict=True):
        proj = np.eye(3) - np.outer(h, h)
        M += proj
        b += proj @ (y - R @ x)
    A = np.eye(4)
    A[:3, :3], A[:3, 3] = R, np.linalg.lstsq(M, b, rcond=None)[0]
    B = np.asarray(np.linalg.solve(A @ fk_ssik(np.zeros(6)), _in_metres(robot.fk(np.zeros(6)), u)), dtype=np.float64)
    return A, B


_SSIK_PREBUILT_CACHE: dict[tuple[bytes, str, bytes], SsikPrebuilt | None] = {}


def ssik_prebuilt(robot: Any) -> SsikPrebuilt | None:
    """ssik's prebuilt artifact of the same geometry as the 6R ``robot`` (up to constant base and tool transforms,
    within ``SSIK_FIT_TOL``), or None; cached per chain. Every six-joint artifact of ``ssik.list_arms()`` is tried
    (importing them all takes ~0.4 s). ValueError for an arm that is not 6R; ImportError without ssik."""
    _ssik_revolute_6r(robot)
    key = (robot.chain.key(), robot.length_unit, np.asarray(robot.limits, dtype=np.float64).tobytes())
    if key not in _SSIK_PREBUILT_CACHE:
        import importlib

        import ssik

        found = None
        for entry in ssik.list_arms():
            if entry.dof != 6:
                continue
            arm = ssik.Manipulator.from_prebuilt(entry.name)
            kb = arm.kinbody
            if any(j.joint_type != "revolute" for j in kb.joints):
                continue  # pragma: no cover - every six-joint artifact of ssik 8.2 is 6R
            A, B = _fit_base_tool(robot, kb, arm.fk)
            if _ssik_fit_error(robot, arm.fk, A, B) <= SSIK_FIT_TOL:
                theirs = [(np.nan, np.nan) if b is None else b for b in arm.joint_limits]
                same = bool(np.allclose(np.array(theirs, dtype=np.float64), robot.limits, rtol=0.0, atol=1e-12))
                found = SsikPrebuilt(entry.name, importlib.import_module(entry.import_path), arm, A, B, same)
                break
        _SSIK_PREBUILT_CACHE[key] = found
    return _SSIK_PREBUILT_CACHE[key]


#: Where :func:`ssik_solver` may take ssik's solver from, in order of preference.
SSIK_SOURCES = ("prebuilt", "native", "live")


def _ssik_native(robot: Any) -> Callable[[Array], Any] | None:
    """ssik's native (C++) solve on the robot's own chain, as an artifact that ``ssik build`` made for this arm
    would run it (``ssik._native.try_native_solve`` with the arm's baked Raghavan-Roth tensor where its solver
    needs one), or None when the dispatched solver has no native form or the extension is absent. Private ssik
    API (8.2): any failure to set it up gives None. The artifact's input check (~2 us) is not repeated. Cached per
    chain (the tensor takes seconds to build, more when ssik's derivation is not in its disk cache)."""
    key = (robot.chain.key(), robot.length_unit, np.asarray(robot.limits, dtype=np.float64).tobytes())
    if key not in _SSIK_NATIVE_CACHE:
        _SSIK_NATIVE_CACHE[key] = _ssik_native_setup(robot)
    return _SSIK_NATIVE_CACHE[key]


_SSIK_NATIVE_CACHE: dict[tuple[bytes, str, bytes], Callable[[Array], Any] | None] = {}


def _ssik_native_setup(robot: Any) -> Callable[[Array], Any] | None:
    live = ssik_manipulator(robot)
    u = metres_per_unit(robot)
    try:
        from ssik._native import rr_native_geometry, try_native_solve

        name, kb = live.solver_name, live.kinbody
        geometry = rr_native_geometry(kb) if name == "ikgeo.general_6r" else None
        probe = _in_metres(robot.fk(_SSIK_CHECK_Q[0]), u)
        if try_native_solve(name, kb, probe, rr_geometry=geometry, enumerate_windings=False) is None:
            return None
    except (ImportError, AttributeError, TypeError, ValueError):  # pragma: no cover - depends on the package
        return None
    return lambda T: try_native_solve(name, kb, _in_metres(T, u), rr_geometry=geometry, enumerate_windings=False)


def ssik_solver(
    robot: Any, *, sources: tuple[str, ...] = SSIK_SOURCES
) -> tuple[Callable[[Array], Any], dict[str, Any]]:
    """ssik at its best on a 6R ``robot``, answering what sweepik's default answers: ``(solve, about)``.

    ``solve(T)`` takes a pose ``(4, 4)`` of the robot (world frame, its length unit) and returns ssik's list of
    ``Solution`` (``.q (6,)`` radians, in the robot's joint coordinates) within the robot's joint limits, one per
    geometric branch: ``respect_limits=True`` (ssik's default: out-of-limit answers dropped, the others shifted
    by 2 pi into the limits where that fits) and ``enumerate_windings=False`` (not ssik's default, which lists
    every in-limit winding ``q_i + 2 pi k`` of a joint whose limits span more than 2 pi: 512 configurations
    instead of 8 on a UR5 pose). That is the set sweepik's ``solve`` returns by default: one configuration per
    branch, wrapped into the limits (the same configurations modulo 2 pi, as many). Other options at ssik's
    defaults (``allow_rescue=True``). The first of ``sources`` that applies:

    * ``"prebuilt"``: ssik's shipped artifact of the same geometry and joint limits (:func:`ssik_prebuilt`; the
      UR5's has other limits), its module's ``solve`` with the target mapped to its frames;
    * ``"native"``: ssik's C++ backend on the robot's chain with the per-arm precompute done once
      (:func:`_ssik_native`), what ``ssik build`` would bake for this arm;
    * ``"live"``: ``ssik_manipulator(robot).solve`` (rebuilds per call what the other two bake).

    ``about``: ``{"source": ..., "artifact": name or None, "solver": ssik's dispatched solver}``. The chosen solve
    is tried once on a pose of the arm: ssik can dispatch a chain to a solver that refuses it only when it solves
    (ssik 8.2 on the KUKA iiwa with its first joint held: ``spherical_two_intersecting``, which then finds the
    collinear joints 3 and 5 of the zero pose and raises). ValueError for an arm that is not 6R, when no source
    applies, or when ssik fails on that pose (the message says how); ImportError without ssik.
    """
    solve, about = _ssik_choose(robot, sources)
    try:
        solve(robot.fk(_SSIK_CHECK_Q[0]))
    except Exception as exc:  # any failure of the foreign package on a reachable pose: it cannot solve this arm
        raise SweepikError(f"ssik ({about['source']}, {about['solver']}) fails on {robot.name}: {exc}") from exc
    return solve, about


def _ssik_choose(robot: Any, sources: tuple[str, ...]) -> tuple[Callable[[Array], Any], dict[str, Any]]:
    """The first of ``sources`` that applies to the robot (see :func:`ssik_solver`), untried."""
    for source in sources:
        if source == "prebuilt":
            pre = ssik_prebuilt(robot)
            if pre is not None and pre.same_limits:
                return _ssik_prebuilt_solve(robot, pre), {
                    "source": "prebuilt",
                    "artifact": pre.name,
                    "solver": pre.manipulator.solver_name,
                }
        elif source == "native":
            native = _ssik_native(robot)
            if native is not None:
                return native, {"source": "native", "artifact": None, "solver": ssik_manipulator(robot).solver_name}
        elif source == "live":
            return _ssik_live(robot), {
                "source": "live",
                "artifact": None,
                "solver": ssik_manipulator(robot).solver_name,
            }
        else:
            raise UnknownOptionError(f"unknown ssik source {source!r}; expected some of {SSIK_SOURCES}")
    raise SweepikError(f"none of the ssik sources {sources} applies to {robot.name}")


def _ssik_live(robot: Any) -> Callable[[Array], Any]:
    """``ssik_manipulator(robot).solve`` of the robot's poses (limits applied, one winding per branch)."""
    live = ssik_manipulator(robot)
    u = metres_per_unit(robot)
    return lambda T: live.solve(_in_metres(T, u), enumerate_windings=False)


def _ssik_prebuilt_solve(robot: Any, pre: SsikPrebuilt) -> Callable[[Array], Any]:
    """The artifact module's ``solve`` of the robot's poses (limits applied, one winding per branch)."""
    solve, u = pre.module.solve, metres_per_unit(robot)
    return lambda T: solve(pre.target(T, u), enumerate_windings=False)


def ssik_status(robot: Any) -> dict[str, Any]:
    """Whether ssik can solve ``robot`` and how it would (for reports): ``{"solves": True, "source", "artifact",
    "solver"}`` (the ``about`` of :func:`ssik_solver`), or ``{"solves": False, "why": "not 6R" | "not installed" |
    "fails", "reason": a sentence}``."""
    try:
        _ssik_revolute_6r(robot)  # (first: a prismatic arm is out of ssik's reach, installed or not)
    except SweepikError as exc:
        return {"solves": False, "why": "not 6R", "reason": str(exc)}
    try:
        _, about = ssik_solver(robot)
    except ImportError:
        return {"solves": False, "why": "not installed", "reason": "ssik is not installed (pip install ssik)"}
    except SweepikError as exc:
        return {"solves": False, "why": "fails", "reason": str(exc)}
    return {"solves": True, **about}


def peers_for(robot: Any) -> dict[str, tuple[Callable[[Array], Any], Callable[[Array], Any]]]:
    """``{name: (solve one pose, solve a batch (N, 4, 4))}`` for the installed peers that can solve ``robot`` at
    all (empty: none installed, or the arm is not 6R, or no known decomposition). Raw calls: their answers are
    not FK-checked; EAIK's and IK-Geo's are not limit-filtered either, ssik's are (:func:`ssik_solver`: the set
    sweepik's default returns). ssik has no batch call: its batch is a loop over the poses."""
    out: dict[str, tuple[Callable[[Array], Any], Callable[[Array], Any]]] = {}
    H, P, R_end, rev = chain_arrays(robot)
    if len(rev) != 6 or not rev.all():
        return out
    try:
        bot = eaik_robot(H, P)
    except ImportError:
        bot = None
    if bot is not None and bot.hasKnownDecomposition():

        def _target(T: Array) -> Array:
            T = np.array(T, dtype=np.float64)
            T[:3, :3] = T[:3, :3] @ R_end.T
            return T

        out["EAIK"] = (lambda T: bot.IK(_target(T)), lambda Ts: bot.IK_batched([_target(T) for T in Ts], 1))
    try:
        import ik_geo

        setup = ikgeo_setup(ik_geo, robot, {"closed"})
    except ImportError:
        setup = None
    if setup is not None:
        gbot, _, _, reverse, Rc = setup

        def _geo(T: Array) -> Any:
            M = np.linalg.inv(T) if reverse else T
            return gbot.get_ik(np.ascontiguousarray((M[:3, :3] @ Rc.T).T), np.ascontiguousarray(M[:3, 3]))

        out["IK-Geo"] = (_geo, lambda Ts: [_geo(T) for T in Ts])
    try:
        ssik_one, _ = ssik_solver(robot)
    except (ImportError, ValueError):  # not installed, or it fails on this arm (``ssik_status`` says why)
        return out
    out["ssik"] = (ssik_one, lambda Ts: [ssik_one(T) for T in Ts])
    return out
