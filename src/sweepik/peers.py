"""Other all-solutions IK solvers, called on sweepik's robots (the optional ``bench`` extra: ``eaik``, ``ik-geo``).

``sweepik bench --arms`` times them on the same poses as sweepik; the test suite uses the same adapters as
independent oracles (``tests/oracles.py``, which also FK-checks their answers). Both peers take a revolute chain
in product-of-exponentials form: axes ``H (6, 3)`` and link vectors ``P (7, 3)`` at q = 0 with the end
orientation the identity, so a target's rotation is passed as ``R_target @ R_end^T`` (``chain.R_end``).

* EAIK (``eaik.IK_HP.HPRobot(H, P)``): its own automatic decomposition; ``hasKnownDecomposition()`` says whether it
  can solve the arm at all.
* IK-Geo (``ik_geo.Robot.<decomposition>(H, P)``): the decomposition is chosen here from the axes of the chain or
  of the reversed chain (a structure at the base becomes one at the tool), with the points of intersecting axes
  moved to their common point as IK-Geo expects. Only its closed forms are used by default: in ik-geo 1.0.3 its
  1-D and 2-D searches are coarse and miss roots.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import NDArray

from .chain import Chain

Array = NDArray[np.float64]

__all__ = ["chain_arrays", "eaik_robot", "ikgeo_setup", "peers_for", "STRUCT_TOL", "IKGEO_KINDS"]

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


def peers_for(robot: Any) -> dict[str, tuple[Callable[[Array], Any], Callable[[Array], Any]]]:
    """``{name: (solve one pose, solve a batch (N, 4, 4))}`` for the installed peers that can solve ``robot`` at
    all (empty: none installed, or the arm is not 6R, or no known decomposition). Raw calls: their answers are
    neither FK-checked nor limit-filtered."""
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
    except ImportError:
        return out
    setup = ikgeo_setup(ik_geo, robot, {"closed"})
    if setup is not None:
        gbot, _, _, reverse, Rc = setup

        def _geo(T: Array) -> Any:
            M = np.linalg.inv(T) if reverse else T
            return gbot.get_ik(np.ascontiguousarray((M[:3, :3] @ Rc.T).T), np.ascontiguousarray(M[:3, 3]))

        out["IK-Geo"] = (_geo, lambda Ts: [_geo(T) for T in Ts])
    return out
