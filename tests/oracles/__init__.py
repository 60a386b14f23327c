"""Independent reference IK solvers for the tests (not a test file): all solutions of one pose on any 6-joint arm.

Nothing here uses sweepik's solver. Three oracles:

* :func:`numerical_solutions` -- a many-start Levenberg-Marquardt search, vectorised over the starts with NumPy,
  that uses only ``robot.fk``, ``robot.jacobian``, the limits, the joint types and ``length_scale``.
  Works on every arm (prismatic joints included); it is a search, so it can miss a solution whose basin no
  start falls in: rare with 400 starts on 6R arms (1 of 300 random PUMA/UR5 poses, a near-singular one): near a
  singular pose (smallest singular value of the Jacobian ~1e-5, e.g. the wrist centre almost on the shoulder
  axis) the valleys are narrow and it may return only some of the solutions; at an exactly singular solution
  it does not reach the tolerance at all.
* :func:`eaik_solutions` -- EAIK (``pip install EAIK``; Ostermeier et al., subproblem decomposition with
  automatic kinematic remodelling), 6R arms with a decomposition it knows.
* :func:`ikgeo_solutions` -- IK-Geo's Python bindings (``pip install ik-geo``; Elias & Wen), 6R arms whose
  structure matches one of its closed-form decompositions (chosen here from the axes, on the chain or on the
  reversed chain); its 1D/2D searches only on request (in 1.0.3 they are coarse and incomplete).
* :func:`ssik_solutions` -- ssik (``pip install ssik``): every 6R arm, closed forms where the structure has one,
  else a Raghavan-Roth elimination (a 16th-degree problem solved as an eigenvalue problem), so it is an
  independent oracle for the arms sweepik sweeps. Called live on the robot's own chain (not a prebuilt artifact).

All four take the target ``pose`` (4x4, world frame: base and tool transforms included, as ``robot.fk``) and
return an array ``(k, n)`` of distinct solutions (revolute values wrapped to (-pi, pi], prismatic as is),
joint limits NOT applied, sorted lexicographically. The three wrappers return None when the package is not
installed or cannot handle the arm; the solutions they return are filtered to those whose FK matches the pose
within ``FK_TOL`` (relative to ``length_scale`` for position, radians for orientation). Pass a dict as
``info`` to learn what the solver returned (counts of solutions, least-squares flags, rejected ones, the
decomposition used).

EAIK and IK-Geo describe the arm in product-of-exponentials form, which ``robot.chain`` provides (``H (n, 3)``,
``P (n + 1, 3)``, ``R_end``; world frame at q = 0). Their end effector has orientation I at q = 0, so their
target orientation is ``R_target @ R_end.T``. Quirk: ik_geo 1.0.3's Python layer reads the rotation matrix
transposed (and returns its own ``forward_kinematics`` rotation transposed), so it is handed ``R.T``. ssik gets the
same chain as a list of joint transforms (``sweepik.experiments.peers.ssik_manipulator``), in metres.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.experiments.peers import chain_arrays as _chain_arrays
from sweepik.experiments.peers import eaik_robot as _eaik_robot
from sweepik.experiments.peers import ikgeo_setup as _ikgeo_setup
from sweepik.experiments.peers import metres_per_unit as _metres_per_unit
from sweepik.experiments.peers import ssik_manipulator as _ssik_manipulator

Array = NDArray[np.float64]

__all__ = [
    "FK_TOL",
    "numerical_solutions",
    "eaik_solutions",
    "ikgeo_solutions",
    "ssik_solutions",
    "wrap",
    "pose_errors",
    "same_solution_set",
    "contains",
    "in_limit_configurations",
    "edge_configurations",
    "recovers",
]

#: The wrappers keep a returned solution when its FK matches the pose this closely (relative position error,
#: i.e. divided by ``length_scale``, and rotation angle in radians).
FK_TOL = 1e-6


# ----------------------------------------------------------------------------------------------------------
# small helpers (shared with the tests)
# ----------------------------------------------------------------------------------------------------------


def wrap(q: np.ndarray, revolute: np.ndarray) -> Array:
    """Revolute values wrapped to (-pi, pi]; prismatic values unchanged."""
    qa = np.asarray(q, dtype=np.float64)
    return np.where(revolute, np.pi - np.mod(np.pi - qa, 2.0 * np.pi), qa)


def _vee_skew(E: Array) -> Array:
    return 0.5 * np.stack([E[..., 2, 1] - E[..., 1, 2], E[..., 0, 2] - E[..., 2, 0], E[..., 1, 0] - E[..., 0, 1]], -1)


def _log_so3(E: Array) -> tuple[Array, Array]:
    """Axis-angle vectors ``(..., 3)`` and angles ``(...)`` of rotation matrices ``E (..., 3, 3)``.

    Accurate near 0 (from the skew part), and near pi (axis from the symmetric part)."""
    v = _vee_skew(E)  # sin(theta) * axis
    s = np.linalg.norm(v, axis=-1)
    c = 0.5 * (np.trace(E, axis1=-2, axis2=-1) - 1.0)
    theta = np.arctan2(s, c)
    with np.errstate(divide="ignore", invalid="ignore"):
        k = np.where(s > 1e-300, theta / s, 1.0)
    phi = v * k[..., None]
    near_pi = c < -0.99
    if np.any(near_pi):
        En = E[near_pi]
        # E = I + sin K + (1 - cos) K^2 and K^2 = a a^T - I, so sym(E) - cos I = (1 - cos) a a^T.
        M = 0.5 * (En + np.swapaxes(En, -1, -2)) - c[near_pi][:, None, None] * np.eye(3)
        col = np.argmax(np.einsum("kii->ki", M), axis=-1)
        a = M[np.arange(len(col)), :, col]
        a /= np.linalg.norm(a, axis=-1, keepdims=True)
        sign = np.where(np.einsum("ki,ki->k", a, v[near_pi]) < 0.0, -1.0, 1.0)
        phi[near_pi] = a * (sign * theta[near_pi])[:, None]
    return phi, theta


def pose_errors(T: Array, target: Array, length_scale: float) -> tuple[Array, Array]:
    """Position error divided by ``length_scale`` and rotation angle (rad) of poses ``T (..., 4, 4)``."""
    dp = np.linalg.norm(T[..., :3, 3] - target[:3, 3], axis=-1) / length_scale
    _, ang = _log_so3(np.swapaxes(target[:3, :3], -1, -2) @ T[..., :3, :3])
    return dp, ang


def _joint_distance(a: Array, b: Array, revolute: np.ndarray, length_scale: float) -> Array:
    """Max over joints of the distance (revolute: modulo 2 pi; prismatic: divided by ``length_scale``)."""
    d = np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)
    d = np.where(revolute, np.abs(np.pi - np.mod(np.pi - d, 2.0 * np.pi)), np.abs(d) / length_scale)
    return np.max(d, axis=-1)


def _dedup(q: Array, cost: Array, revolute: np.ndarray, length_scale: float, tol: float) -> Array:
    """Distinct rows of ``q`` (modulo 2 pi), the one of least ``cost`` kept from each cluster, sorted."""
    n = q.shape[-1]
    if len(q) == 0:
        return np.zeros((0, n))
    q = wrap(q, revolute)
    order = np.argsort(cost, kind="stable")
    kept: list[Array] = []
    for i in order:
        if not kept or np.min(_joint_distance(np.array(kept), q[i], revolute, length_scale)) > tol:
            kept.append(q[i])
    out = np.array(kept)
    return out[np.lexsort(out.T[::-1])]


def contains(solutions: Array, q: Array, revolute: np.ndarray, length_scale: float, tol: float = 1e-6) -> bool:
    """True when one row of ``solutions`` equals ``q`` (revolute modulo 2 pi) within ``tol``."""
    sols = np.asarray(solutions, dtype=np.float64)
    if sols.size == 0:
        return False
    return bool(np.min(_joint_distance(sols, q, revolute, length_scale)) <= tol)


def same_solution_set(a: Array, b: Array, revolute: np.ndarray, length_scale: float, tol: float = 1e-6) -> bool:
    """True when every row of ``a`` is in ``b`` and every row of ``b`` in ``a`` (modulo 2 pi, within ``tol``)."""
    return all(contains(b, q, revolute, length_scale, tol) for q in a) and all(
        contains(a, q, revolute, length_scale, tol) for q in b
    )


#: Two solutions of a multiple root or next to the singular set (sweepik: one of multiplicity 2; another solver: two
#: roots split by rounding, ~sqrt(eps) apart) are the same to this; other roots to 1e-6.
MULTIPLE_ROOT_TOL = 1e-4


def unmatched_solutions(
    q: Array, multiplicity: np.ndarray, theirs: Array, robot: Any
) -> tuple[list[Array], list[Array]]:
    """The rows of sweepik's solutions ``q`` (with their ``multiplicity``) that ``theirs`` lacks, and the rows of
    ``theirs`` that ``q`` lacks: compared to 1e-6, or to ``MULTIPLE_ROOT_TOL`` where one of the two rows is a
    multiple root of sweepik's or lies next to the singular set (its Jacobian's singular values' ratio below
    ``NEAR_SINGULAR``: close roots there are known to ~sqrt(eps) only, and split or merge by rounding)."""
    rev, L = robot.is_revolute, robot.length_scale
    theirs = np.asarray(theirs, dtype=np.float64).reshape(-1, robot.n_joints)

    def loose(rows: Array) -> np.ndarray:
        if rows.shape[0] == 0:
            return np.zeros(0, dtype=bool)
        J = robot.jacobian(rows)
        J[:, :3] /= L
        sv = np.linalg.svd(J, compute_uv=False)
        return sv[:, -1] < NEAR_SINGULAR * sv[:, 0]

    ours_loose = loose(q) | (np.asarray(multiplicity) > 1)
    theirs_loose = loose(theirs)
    only_ours = [
        x for x, lx in zip(q, ours_loose, strict=True)
        if not (contains(theirs, x, rev, L, 1e-6) or contains(theirs if lx else theirs[theirs_loose], x, rev, L,
                                                                   MULTIPLE_ROOT_TOL))
    ]  # fmt: skip
    only_theirs = [
        x for x, lx in zip(theirs, theirs_loose, strict=True)
        if not (contains(q, x, rev, L, 1e-6) or contains(q if lx else q[ours_loose], x, rev, L, MULTIPLE_ROOT_TOL))
    ]  # fmt: skip
    return only_ours, only_theirs


#: ... (see ``unmatched_solutions``)
NEAR_SINGULAR = 1e-5


# ----------------------------------------------------------------------------------------------------------
# 1. many-start numerical search
# ----------------------------------------------------------------------------------------------------------


def in_limit_configurations(robot: Any, n: int, rng: np.random.Generator) -> Array:
    """``(n, n_joints)`` configurations uniform inside the limits, revolute joints also inside [-pi, pi]."""
    lo = np.where(robot.is_revolute, np.maximum(robot.lower, -np.pi), robot.lower)
    hi = np.where(robot.is_revolute, np.minimum(robot.upper, np.pi), robot.upper)
    return rng.uniform(lo, hi, size=(n, robot.n_joints))


def edge_configurations(robot: Any, base: Array) -> Array:
    """``base`` with each joint at each of its limits (one at a time), and with joint 5 at 0 (a wrist
    singularity of most arms): ``(2 n_joints + 1, n_joints)``."""
    out = []
    for j in range(robot.n_joints):
        for lim in (robot.lower[j], robot.upper[j]):
            q = np.array(base, dtype=np.float64)
            q[j] = lim
            out.append(q)
    q = np.array(base, dtype=np.float64)
    q[4] = 0.0
    out.append(q)
    return np.array(out)


def recovers(robot: Any, sols: Any, q: Array, tol: float = 1e-6) -> bool:
    """``q`` is among the solutions ``sols`` (a ``sweepik.Solutions``), or on one of its families: revolute joints
    modulo 2 pi, prismatic ones relative to the length scale."""
    d = sols.nearest(q) - q
    d = np.where(robot.is_revolute, np.angle(np.exp(1j * d)), d / robot.length_scale)
    return bool(np.max(np.abs(d)) < tol)


def _skew(v: Array) -> Array:
    K = np.zeros((*v.shape[:-1], 3, 3))
    K[..., 0, 1], K[..., 0, 2] = -v[..., 2], v[..., 1]
    K[..., 1, 0], K[..., 1, 2] = v[..., 2], -v[..., 0]
    K[..., 2, 0], K[..., 2, 1] = -v[..., 1], v[..., 0]
    return K


def _inv_left_jacobian(phi: Array, theta: Array) -> Array:
    """Inverse of SO(3)'s left Jacobian at ``phi``: d log(exp(w) E) / dw at w = 0 for E = exp(phi)."""
    K = _skew(phi)
    small = theta < 1e-4
    th = np.where(small, 1.0, theta)
    with np.errstate(divide="ignore", invalid="ignore"):
        c = 1.0 / th**2 - (1.0 + np.cos(th)) / (2.0 * th * np.sin(th))
    c = np.where(small, 1.0 / 12.0 + theta**2 / 720.0, c)
    c = np.where(np.isfinite(c), c, 1.0 / np.pi**2)
    return np.eye(3) - 0.5 * K + c[..., None, None] * (K @ K)


def _residual(robot: Any, q: Array, target: Array, L: float) -> tuple[Array, Array, Array]:
    """6-vector errors ``(N, 6)`` (position / L, axis-angle of R_target^T R(q)), plus the log's phi, theta."""
    T = robot.fk(q)
    e = np.empty((len(q), 6))
    e[:, :3] = (T[:, :3, 3] - target[:3, 3]) / L
    phi, theta = _log_so3(target[:3, :3].T @ T[:, :3, :3])
    e[:, 3:] = phi
    return e, phi, theta


def _sample_starts(robot: Any, n_starts: int, rng: np.random.Generator, full_circle: bool) -> Array:
    lo = np.array(robot.lower, dtype=np.float64)
    hi = np.array(robot.upper, dtype=np.float64)
    rev = np.asarray(robot.is_revolute, dtype=bool)
    wide = rev & ((hi - lo) >= 2.0 * np.pi)
    if full_circle:
        wide = rev
    lo = np.where(wide, -np.pi, lo)
    hi = np.where(wide, np.pi, hi)
    return lo + (hi - lo) * rng.random((n_starts, len(lo)))


def _scaled_jacobian(robot: Any, q: Array, phi: Array, theta: Array, target: Array, L: float, scale: Array) -> Array:
    """Jacobian ``(m, 6, n)`` of the 6-vector error with respect to the scaled unknowns ``z = q / scale``."""
    J = robot.jacobian(q)  # (m, 6, n): linear velocity of the tool point, angular velocity (world)
    Je = np.empty_like(J)
    Je[:, :3] = J[:, :3] / L
    Je[:, 3:] = _inv_left_jacobian(phi, theta) @ (target[:3, :3].T @ J[:, 3:])
    return Je * scale


def numerical_solutions(
    robot: Any,
    pose: np.ndarray,
    n_starts: int = 400,
    seed: int = 0,
    tol: float | None = None,
    *,
    iterations: int = 100,
    max_iterations: int = 400,
    polish: int = 6,
    kick_every: int = 10,
    kick: float = 0.05,
    dedup_tol: float = 1e-5,
    full_circle: bool = False,
    info: dict[str, Any] | None = None,
) -> Array:
    """All IK solutions of ``pose`` that a many-start Levenberg-Marquardt search finds: ``(k, n)``.

    Starts: uniform random within the joint limits (revolute joints with limits 2 pi wide or more, or all
    revolute joints with ``full_circle=True``: within [-pi, pi]). Each start is refined by LM on the 6-vector
    error ``((p(q) - p_target) / length_scale, log(R_target^T R(q)))`` with the robot's geometric Jacobian
    (rotation rows mapped by the inverse left Jacobian of SO(3)), prismatic joints scaled by ``length_scale``,
    steps capped at 1 rad; every ``kick_every`` iterations the rows that did not gain a factor 4 get a random
    kick (``kick`` rad) off the fold they creep along; ``iterations`` LM iterations (doubled up to
    ``max_iterations`` while fewer than a quarter of the rows have converged), then ``polish``
    undamped Gauss-Newton steps on the nearly converged rows (their joint values then stop short of the root
    only by ~ rounding / smallest singular value, which matters near singular poses). Kept: rows whose FK
    is within ``tol * length_scale`` in position and ``tol`` rad in rotation (``tol`` default 1e-9); joints not
    limited; revolute values wrapped to (-pi, pi]; duplicates (within ``dedup_tol``, revolute modulo 2 pi,
    prismatic relative to ``length_scale``) removed, the most accurate of each kept. Rows sorted.
    Pass a dict as ``info`` to get ``converged`` (rows within tol) and ``distinct`` counts.
    """
    target = np.asarray(pose, dtype=np.float64)
    L = float(robot.length_scale)
    rev = np.asarray(robot.is_revolute, dtype=bool)
    n = len(rev)
    tol_ = 1e-9 if tol is None else float(tol)
    scale = np.where(rev, 1.0, L)  # q = scale * z: the unknowns z are all O(1)
    rng = np.random.default_rng(seed)
    q = _sample_starts(robot, n_starts, rng, full_circle)
    e, phi, theta = _residual(robot, q, target, L)
    cost = np.einsum("ki,ki->k", e, e)
    lam = np.full(n_starts, 1e-3)
    active = np.ones(n_starts, dtype=bool)
    eye = np.eye(n)
    done_cost = (1e-3 * tol_) ** 2
    checked = cost.copy()

    def take(rows: Array, mask: Array, qc: Array, ec: Array, phic: Array, thetac: Array, costc: Array) -> None:
        acc = rows[mask]
        q[acc], e[acc], phi[acc], theta[acc], cost[acc] = qc[mask], ec[mask], phic[mask], thetac[mask], costc[mask]

    budget = iterations
    it = 0
    while True:
        it += 1
        if it > budget:
            # Few rows converged (a near-singular pose: narrow valleys, slow progress): allow more iterations.
            if budget >= max_iterations or np.mean(cost <= tol_**2) >= 0.25:
                break
            budget = min(2 * budget, max_iterations)
        if it % kick_every == 0 and it + kick_every <= budget:
            # Rows that did not gain a factor 4 since the last check creep along a fold (GN ignores the negative
            # curvature of a saddle near a near-double solution, or of a workspace-boundary local minimum):
            # kick them off it at random and reset their damping.
            stuck = np.flatnonzero((cost > done_cost) & (cost > 0.25 * checked))
            if stuck.size:
                q[stuck] += rng.normal(0.0, kick, (stuck.size, n)) * scale
                e[stuck], phi[stuck], theta[stuck] = _residual(robot, q[stuck], target, L)
                cost[stuck] = np.einsum("ki,ki->k", e[stuck], e[stuck])
                lam[stuck] = 1e-3
                active[stuck] = True
            checked = cost.copy()
        idx = np.flatnonzero(active)
        if idx.size == 0:
            break
        Je = _scaled_jacobian(robot, q[idx], phi[idx], theta[idx], target, L, scale)
        JtJ = np.swapaxes(Je, 1, 2) @ Je
        g = np.einsum("kji,kj->ki", Je, e[idx])
        A = JtJ + lam[idx, None, None] * (eye + np.einsum("kii->ki", JtJ)[:, :, None] * eye)
        try:
            dz = -np.linalg.solve(A, g[..., None])[..., 0]
        except np.linalg.LinAlgError:
            dz = -np.stack([np.linalg.lstsq(a, b, rcond=None)[0] for a, b in zip(A, g, strict=True)])
        dz = np.where(np.isfinite(dz), dz, 0.0)
        dz *= np.minimum(1.0, 1.0 / np.maximum(np.max(np.abs(dz), axis=-1), 1e-300))[:, None]
        qc = q[idx] + dz * scale
        ec, phic, thetac = _residual(robot, qc, target, L)
        costc = np.einsum("ki,ki->k", ec, ec)
        better = costc < cost[idx]
        take(idx, better, qc, ec, phic, thetac, costc)
        lam[idx[better]] = np.maximum(lam[idx[better]] / 5.0, 1e-16)
        lam[idx[~better]] *= 8.0
        # Stop rows that are converged far below the tolerance, or hopelessly stuck.
        active[idx] = (cost[idx] > done_cost) & (lam[idx] < 1e12)

    # Polish: undamped Gauss-Newton (pseudo-inverse) on the rows near a root.
    for _ in range(polish):
        idx = np.flatnonzero((cost < (1e3 * tol_) ** 2) & (cost > done_cost))
        if idx.size == 0:
            break
        Je = _scaled_jacobian(robot, q[idx], phi[idx], theta[idx], target, L, scale)
        dz = -np.einsum("kij,kj->ki", np.linalg.pinv(Je, rcond=1e-13), e[idx])
        qc = q[idx] + dz * scale
        ec, phic, thetac = _residual(robot, qc, target, L)
        costc = np.einsum("ki,ki->k", ec, ec)
        take(idx, costc <= cost[idx], qc, ec, phic, thetac, costc)

    dp, ang = pose_errors(robot.fk(q), target, L)
    ok = (dp <= tol_) & (ang <= tol_)
    sols = _dedup(q[ok], (dp + ang)[ok], rev, L, dedup_tol)
    if info is not None:
        info.update(n_starts=n_starts, converged=int(np.sum(ok)), distinct=len(sols), iterations=it - 1)
    return sols


# ----------------------------------------------------------------------------------------------------------
# chain helpers for the wrappers
# ----------------------------------------------------------------------------------------------------------


def _rot(k: Array, t: float) -> Array:
    K = _skew(np.asarray(k, dtype=np.float64))
    return np.eye(3) + np.sin(t) * K + (1.0 - np.cos(t)) * (K @ K)


def _poe_fk(H: Array, P: Array, q: Array) -> tuple[Array, Array]:
    """Product-of-exponentials FK of a revolute chain (end orientation I at q = 0): (R, p)."""
    R = np.eye(3)
    p = P[0].copy()
    for i in range(len(H)):
        R = R @ _rot(H[i], q[i])
        p = p + R @ P[i + 1]
    return R, p


def _filter(
    robot: Any, pose: Array, Q: Array, is_ls: np.ndarray, name: str, info: dict[str, Any] | None, **extra: Any
) -> Array:
    """Solutions of ``Q`` whose FK matches ``pose`` within FK_TOL, wrapped, deduplicated (1e-9), sorted."""
    rev = np.asarray(robot.is_revolute, dtype=bool)
    L = float(robot.length_scale)
    n = len(rev)
    Q = np.asarray(Q, dtype=np.float64).reshape(-1, n)
    finite = np.all(np.isfinite(Q), axis=-1)
    Qf = Q[finite]
    if len(Qf):
        dp, ang = pose_errors(robot.fk(Qf), pose, L)
        ok = (dp <= FK_TOL) & (ang <= FK_TOL)
    else:
        dp = ang = np.zeros(0)
        ok = np.zeros(0, dtype=bool)
    sols = _dedup(Qf[ok], (dp + ang)[ok], rev, L, 1e-9)
    if info is not None:
        info.update(
            solver=name,
            returned=len(Q),
            non_finite=int(np.sum(~finite)),
            rejected=int(np.sum(~ok)),
            n_ls=int(np.sum(is_ls)),
            kept_ls=int(np.sum(is_ls[finite][ok])),
            rejected_not_ls=int(np.sum(~is_ls[finite][~ok])),
            max_err_kept=float(np.max((np.maximum(dp, ang))[ok])) if np.any(ok) else 0.0,
            distinct=len(sols),
            **extra,
        )
    return sols


# ----------------------------------------------------------------------------------------------------------
# 2a. EAIK
# ----------------------------------------------------------------------------------------------------------


def eaik_solutions(robot: Any, pose: np.ndarray, *, info: dict[str, Any] | None = None) -> Array | None:
    """EAIK's IK solutions of ``pose`` (``(k, n)``, FK-checked), or None (no EAIK, not 6R, no decomposition).

    Called as ``eaik.IK_HP.HPRobot(H, P).IK(T)`` with T's rotation ``R_target @ R_end.T``; the result has ``.Q``
    ``(m, 6)`` and ``.is_LS`` ``(m,)`` (least-squares solutions, which are kept only if their FK matches).
    """
    try:
        import eaik.IK_HP  # noqa: F401
    except ImportError:
        return None
    H, P, R_end, rev = _chain_arrays(robot)
    if len(rev) != 6 or not np.all(rev):
        return None
    try:
        bot = _eaik_robot(H, P)
        if not bot.hasKnownDecomposition():
            if info is not None:
                info.update(solver="eaik", family=bot.getKinematicFamily(), unsupported=True)
            return None
        target = np.asarray(pose, dtype=np.float64).copy()
        target[:3, :3] = target[:3, :3] @ R_end.T
        res = bot.IK(target)
    except (RuntimeError, ValueError) as exc:  # pragma: no cover - depends on the package
        if info is not None:
            info.update(solver="eaik", error=repr(exc))
        return None
    Q = np.asarray(res.Q, dtype=np.float64).reshape(-1, 6)
    is_ls = np.asarray(res.is_LS, dtype=bool).reshape(-1)
    return _filter(robot, np.asarray(pose, dtype=np.float64), Q, is_ls, "eaik", info, family=bot.getKinematicFamily())


# ----------------------------------------------------------------------------------------------------------
# 2b. IK-Geo
# ----------------------------------------------------------------------------------------------------------

_IKGEO_CACHE: dict[tuple[bytes, bytes, bytes, str], Any] = {}


def ikgeo_solutions(
    robot: Any,
    pose: np.ndarray,
    *,
    allow_search: str = "none",
    info: dict[str, Any] | None = None,
) -> Array | None:
    """IK-Geo's IK solutions of ``pose`` (``(k, n)``, FK-checked), or None (no ik_geo, not 6R, no decomposition).

    The decomposition is picked from the joint axes of the chain or of the reversed chain (structure at the base
    becomes structure at the tool). By default (``allow_search="none"``) only the closed-form ones:
    ``spherical_two_parallel``, ``spherical_two_intersecting``, ``spherical`` (joints 4-6 meet in a point),
    ``three_parallel_two_intersecting``, ``three_parallel`` (joints 2-4 parallel). ``"1d"`` also allows the
    1D-search ones (``two_parallel``, ``two_intersecting``) and ``"2d"`` the general ``gen_six_dof``; in
    ik_geo 1.0.3 the searches are coarse and unrefined (every solution flagged least-squares, FK off by ~1e-5
    of the arm's size, so this wrapper's FK check drops them) and miss roots (its own ``two_parallel_bot``
    does not recover the configuration its own FK came from), so they are no oracle.

    Called as ``ik_geo.Robot.<decomposition>(h, p).get_ik(R.T, t)`` with ``h (6, 3)``, ``p (7, 3)`` (points of
    intersecting axes moved to their common point), ``R = R_target @ R_end.T``; it returns
    ``[(q, is_ls), ...]``. The decomposition is chosen once per arm (cached).
    """
    try:
        import ik_geo
    except ImportError:
        return None
    kinds = {"none": {"closed"}, "1d": {"closed", "1d"}, "2d": {"closed", "1d", "2d"}}[allow_search]
    H, P, R_end, rev = _chain_arrays(robot)
    if len(rev) != 6 or not np.all(rev):
        return None
    target = np.asarray(pose, dtype=np.float64)
    key = (H.tobytes(), P.tobytes(), R_end.tobytes(), allow_search)
    if key not in _IKGEO_CACHE:
        _IKGEO_CACHE[key] = _ikgeo_setup(ik_geo, robot, kinds)
    setup = _IKGEO_CACHE[key]
    if setup is None:
        if info is not None:
            info.update(solver="ik_geo", unsupported=True)
        return None
    bot, name, kind, reverse, Rc = setup
    T = np.linalg.inv(target) if reverse else target
    R = T[:3, :3] @ Rc.T
    raw = bot.get_ik(np.ascontiguousarray(R.T), np.ascontiguousarray(T[:3, 3]))
    Q = np.array([s[0] for s in raw], dtype=np.float64).reshape(-1, 6)
    is_ls = np.array([bool(s[1]) for s in raw], dtype=bool)
    if reverse:
        Q = Q[:, ::-1]
    return _filter(robot, target, Q, is_ls, "ik_geo", info, decomposition=name, kind=kind, reversed=reverse)


# ----------------------------------------------------------------------------------------------------------
# 2c. ssik
# ----------------------------------------------------------------------------------------------------------


def ssik_solutions(robot: Any, pose: np.ndarray, *, info: dict[str, Any] | None = None) -> Array | None:
    """ssik's IK solutions of ``pose`` (``(k, n)``, FK-checked), or None (no ssik, the arm is not 6R, or ssik
    raises on it: ``info["error"]``).

    Called as ``ssik_manipulator(robot, limits=False).solve(T, respect_limits=False, enumerate_windings=False)``:
    ssik's live ``Manipulator`` on the robot's own chain with every joint continuous (no limit filter, no polish
    held back by a limit), one representative per geometric branch, target position in metres; its other options
    at their defaults (``allow_rescue=True``: a T-perturbation rescue when the analytic path finds nothing; its
    answers are tagged ``refinement_used == "lm"``, counted in ``info["rescued"]``). The first call on an arm
    without a closed form in ssik derives its elimination (1.5 to 3.5 min; cached on disk by ssik, ``~/.cache/ssik``).
    ``info`` also gets ``dispatched`` (ssik's solver) and ``fk_residual_max`` (ssik's own FK residual).
    """
    try:
        import ssik  # noqa: F401
    except ImportError:
        return None
    rev = np.asarray(robot.is_revolute, dtype=bool)
    if len(rev) != 6 or not np.all(rev):
        if info is not None:
            info.update(solver="ssik", unsupported=True)
        return None
    arm = _ssik_manipulator(robot, limits=False)
    target = np.asarray(pose, dtype=np.float64)
    T = target.copy()
    T[:3, 3] *= _metres_per_unit(robot)
    try:
        sols = arm.solve(T, respect_limits=False, enumerate_windings=False)
    except (RuntimeError, ValueError) as exc:  # e.g. a dispatched solver that refuses the chain when it solves
        if info is not None:
            info.update(solver="ssik", dispatched=arm.solver_name, error=repr(exc))
        return None
    Q = np.array([s.q for s in sols], dtype=np.float64).reshape(-1, 6)
    extra = {
        "dispatched": arm.solver_name,
        "rescued": sum(s.refinement_used == "lm" for s in sols),
        "fk_residual_max": max((float(s.fk_residual) for s in sols), default=0.0),
    }
    return _filter(robot, target, Q, np.zeros(len(Q), dtype=bool), "ssik", info, **extra)


def in_metres(robot: Any, name: str) -> Any:
    """The DH ``robot`` (length unit mm) written again in metres, from a robot file's dict: the same arm through
    another description (lengths, prismatic limits, centres of mass / 1000; masses and gravity unchanged)."""
    from sweepik.io.robot_file import robot_from_dict

    assert robot.length_unit == "mm" and robot.dh_convention != "none"
    joints = []
    for j in robot.joints:
        limits = [np.degrees(j.lower), np.degrees(j.upper)] if j.is_revolute else [j.lower / 1000, j.upper / 1000]
        joints.append(
            {
                "type": j.type,
                "a": j.a / 1000,
                "alpha": np.degrees(j.alpha),
                "d": j.d / 1000,
                "theta": np.degrees(j.theta),
                "limits": limits,
                "mass": j.mass,
                "com": [c / 1000 for c in j.com],
            }
        )
    data = {"name": name, "length_unit": "m", "dh_convention": robot.dh_convention, "gravity": list(robot.gravity)}
    return robot_from_dict({**data, "joints": joints})


def ssik_general_native(H: Array, P: Array, R_end: Array) -> Any:
    """ssik 8.2's general 6R solver (``ikgeo.general_6r``, Raghavan-Roth / Manocha-Canny) on its native C++ path for
    the 6R chain ``(H, P, R_end)`` in metres: ``solve(T) -> (k, 6)`` (every branch, no limits, no windings), or None
    (no ssik, or ssik dispatches another solver). Its first call on an arm derives the elimination with SymPy (4-9
    minutes, cached by ssik in ``~/.cache/ssik`` under the exact geometry). ssik's live ``Manipulator.solve`` is not
    used for these arms: on random general arms it answers only through its numerical rescue (measured)."""
    try:
        import ssik
        from ssik._native import rr_native_geometry, try_native_solve
        from ssik.internals import JointSpec, build_kinbody
    except ImportError:
        return None
    specs = []
    for i in range(6):
        TL = np.eye(4)
        TL[:3, 3] = P[i]
        TR = None
        if i == 5:
            TR = np.eye(4)
            TR[:3, :3], TR[:3, 3] = R_end, P[6]
        specs.append(JointSpec(TL, H[i], "revolute", TR, name=f"j{i}", limits=(-np.pi, np.pi)))
    kb = build_kinbody(specs)
    name = ssik.Manipulator(kb).solver_name
    if name != "ikgeo.general_6r":
        return None
    geometry = rr_native_geometry(kb)

    def solve(T: Array) -> Array:
        sols = try_native_solve(name, kb, np.asarray(T, dtype=np.float64), rr_geometry=geometry,
                                enumerate_windings=False, respect_limits="wrap")  # fmt: skip
        return np.array([s.q for s in (sols or [])], dtype=np.float64).reshape(-1, 6)

    return solve
