"""Closed-form reductions of the C-Arm (paper Table 1): theta* = d1 (the paper's choice) and theta* = theta2.

Geometry used by both (derivation in docs/carm.md). With the chain pose ``R_D, P = (Px, Py, Pz)``:

* Entry {2,4} of eq. (4): ``-S2 Px + C2 (Pz - d1) = 0`` ties theta2 to d1.
* The wrist point in frame 2 is ``(u, 0, -Py)`` with ``u = C2 Px + S2 (Pz - d1)``; it must equal
  ``(S3 L1 + C34 L2, 0, C3 L1 - S34 L2)`` (eq. 1c): a planar two-link problem, two elbow branches
  ``eps = +-1`` while ``|L1 - L2| <= rho = sqrt(u^2 + Py^2) <= L1 + L2``. Its circle-line form gives
  ``(C34, S34) = (k (u, Py) + eps s (-Py, u)) / rho^2`` with ``k = (rho^2 + L2^2 - L1^2) / (2 L2)``,
  ``s = sqrt(rho^2 - k^2)``, and ``L1 (S3, C3) = (u - L2 C34, L2 S34 - Py)``.
* The wrist: ``N = R_04^T R_D`` must be ``RotY(theta5) RotZ(theta6)``, which holds iff ``N[1, 2] = 0``
  (joint 5's axis, y of frame 4, perpendicular to the desired tool z axis). That entry,
  ``C34 (C2 zx + S2 zz) + S34 zy``, is the signed residual: algebraic (no trigonometric calls),
  dimensionless, continuous across the elbow domain edges. Then ``theta5 = atan2(N02, N22)``,
  ``theta6 = atan2(N10, N11)``.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from sweepik.errors import RobotDefinitionError
from sweepik.model.robot import Robot
from sweepik.reductions import kernels
from sweepik.reductions.base import Array, IntArray, Reduction

#: |Px| below this times L1 + L2 (7.5e-10 mm on the C-Arm) is taken as exactly 0: the wrist then lies in the
#: plane of joint 2's axis and the rail, where theta2 = +-90 deg exactly; rounding of the pose would otherwise
#: make d1 = Pz - Px tan(theta2) and the theta2 swing ill-defined.
PX_SNAP_REL = 1e-12
#: Relative tolerance on the structure check of a robot against the C-Arm's DH table.
_STRUCT_TOL = 1e-9
#: rho^2 - k^2 down to -DISC_TOL * (L1 + L2)^2 counts as 0: the elbow domain edges are sampled exactly
#: (sample hints) and must not turn into NaN by rounding.
DISC_TOL = 1e-12
#: The theta2 reduction hands poses with |Px| <= BLIND_PX_REL * (L1 + L2) to the d1 sweep for the
#: solutions with |cos(theta2)| <= BLIND_COS (its blind spot and ill-conditioned neighbourhood).
BLIND_PX_REL = 1e-2
BLIND_COS = 2e-2
#: Number of extra samples placed across the narrow window |Pz - d1| ~ |Px| where theta2 swings by pi.
_SWING_SAMPLES = kernels.SWING_SAMPLES
_TAN_SWING = kernels.TAN_SWING


def carm_lengths(robot: Robot) -> tuple[float, float]:
    """(L1, L2) of a robot with the C-Arm's structure; RobotDefinitionError if it has another structure."""
    j = robot.joints
    types = [x.type for x in j]
    alpha = np.degrees(robot.dh_alpha)
    ok = (
        robot.dh_convention == "modified"
        and types == ["prismatic"] + ["revolute"] * 5
        and np.allclose(alpha, [0, 90, -90, 0, -90, 90], atol=_STRUCT_TOL)
        and np.allclose(robot.dh_a[[0, 1, 2, 4, 5]], 0.0, atol=_STRUCT_TOL)
        and np.allclose(robot.dh_d[:4], 0.0, atol=_STRUCT_TOL)
        and abs(robot.dh_d[5]) <= _STRUCT_TOL
        and np.allclose(robot.dh_theta, [0, 0, -np.pi / 2, 0, 0, 0], atol=_STRUCT_TOL)
    )
    if not ok:
        raise RobotDefinitionError(
            f"robot {robot.name!r} does not have the C-Arm's DH structure (paper Table 1); "
            "the carm-d1/carm-theta2 reductions do not apply"
        )
    L1, L2 = float(robot.dh_a[3]), float(robot.dh_d[4])
    if not (L1 > 0.0 and L2 > 0.0):
        # the closed form divides by L1 and L2 and takes theta3 from the direction of link L1: it holds for
        # positive lengths only (a zero length is another arm: the wrist point no longer moves with theta3/4)
        raise RobotDefinitionError(
            f"robot {robot.name!r}: the carm-d1/carm-theta2 reductions need L1 = a (joint 4 row) > 0 and "
            f"L2 = d (joint 5 row) > 0, got L1 = {L1:g}, L2 = {L2:g} (their closed form is derived for positive "
            "lengths; a zero length is another kinematic structure)"
        )
    return L1, L2


#: Poses this close to the theta2 self-motion (``_CArmBase._self_motion``: the wrist's distance from joint 2's axis
#: over L1 + L2, and the orientation's terms that fix theta2) have their candidates traced along theta2.
NEAR_SELF_MOTION = 1e-6


class _CArmBase(Reduction):
    def __init__(self, robot: Robot, free_joint: int, n_branches: int) -> None:
        super().__init__(robot, free_joint, n_branches)
        self.L1, self.L2 = carm_lengths(robot)
        self.px_snap = PX_SNAP_REL * (self.L1 + self.L2)

    def kernel_params(self, poses: Array) -> Array:
        """``(N, 18)``: the columns laid out at ``kernels.N_PARAMS``, for the compiled kernels (kernels.py)."""
        N = poses.shape[0]
        out = np.empty((N, kernels.N_PARAMS))
        if kernels.carm_params is not None:
            kernels.carm_params(np.asarray(poses, dtype=np.float64), self.L1, self.L2, self.px_snap, out)
            return out
        out[:, 0:3] = poses[:, :3, 3]
        np.copyto(out[:, 0], 0.0, where=np.abs(out[:, 0]) <= self.px_snap)
        out[:, 3:6] = poses[:, :3, 2]
        out[:, 6], out[:, 7] = self.L1, self.L2
        out[:, 8:17] = poses[:, :3, :3].reshape(N, 9)
        out[:, 17] = poses[:, 0, 3]
        return out

    def _wrist_on_axis(self, poses: Array) -> NDArray[np.bool_] | None:
        """Poses with the wrist on joint 2's axis, ``|Px| <= 1e-9 (L1 + L2)``; None where none has it (the common
        case, told for one pose by a float comparison rather than NumPy calls)."""
        tol = 1e-9 * (self.L1 + self.L2)
        if poses.shape[0] == 1:
            return np.ones(1, dtype=bool) if abs(float(poses[0, 0, 3])) <= tol else None
        near = np.abs(poses[:, 0, 3]) <= tol
        return near if near.any() else None

    def _self_motion(self, poses: Array, tol: float) -> NDArray[np.bool_] | None:
        """Poses on the theta2 self-motion to ``tol``: the wrist on joint 2's axis (``|Px| <= tol (L1 + L2)``) where
        the orientation does not fix theta2 either (``CArmD1.degenerate``); None where none is."""
        reach = max(tol, 1e-9) * (self.L1 + self.L2)
        if poses.shape[0] == 1 and abs(float(poses[0, 0, 3])) > reach:  # (one pose, the common case: no NumPy calls)
            return None
        near = np.abs(poses[:, 0, 3]) <= reach
        if not near.any():
            return None
        Py, z = poses[:, 1, 3], poses[:, :3, 2]
        out = np.zeros(poses.shape[0], dtype=bool)
        for eps in (1.0, -1.0):
            c34, s34 = self._elbow(np.zeros_like(Py), Py, np.full_like(Py, eps))
            with np.errstate(invalid="ignore"):
                flat = (np.hypot(c34 * z[:, 0], c34 * z[:, 2]) <= tol) & (np.abs(s34 * z[:, 1]) <= tol)
            out |= near & flat
        return out

    def continuum_poses(self, poses: Array) -> NDArray[np.bool_] | None:
        return self._self_motion(poses, NEAR_SELF_MOTION)

    def continuum_joints(
        self, poses: Array, pose: IntArray, theta: Array, branch: IntArray, error: Array | None = None, tol: float = 0.0
    ) -> IntArray | None:
        """Candidates of poses within ``NEAR_SELF_MOTION`` of the theta2 self-motion (``_self_motion``): joint 2. A
        pose 1e-9 rad off it (theta4) holds a numerical continuum along theta2 over half a turn, every member solving
        the pose within the certification's tolerance; the sweep gives a few of its points, 0.1 ... 1.4 rad apart.
        The solver traces the continuum from them (nothing where the candidates are isolated solutions)."""
        near = self.continuum_poses(poses)
        if near is None or not near[pose].any():
            return None
        flag = near[pose] if error is None else near[pose] & (error <= tol)
        return np.where(flag, 1, -1).astype(np.intp)

    def _position(self, poses: Array, theta: Array, branch: IntArray | None) -> tuple[Array, ...]:
        """(d1, C2, S2, u, Py, C34, S34, z, R) at theta*; each subclass ties theta2 and d1 its own way."""
        raise NotImplementedError

    def residual(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        _, c2, s2, _, _, c34, s34, z, _ = self._position(poses, theta, branch)
        return self._residual(c2, s2, c34, s34, z)

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        d1, c2, s2, u, Py, c34, s34, _, R = self._position(poses, theta, branch)
        shape = c34.shape
        return self._configuration(
            np.broadcast_to(d1, shape), np.broadcast_to(c2, shape), np.broadcast_to(s2, shape), u, Py, c34, s34, R
        )

    # --- shared closed form ----------------------------------------------------------------------
    def _elbow(self, u: Array, Py: Array, eps: Array) -> tuple[Array, Array]:
        """(C34, S34) of the planar two-link problem; NaN outside its domain."""
        L1, L2 = self.L1, self.L2
        rho2 = u * u + Py * Py
        k = (rho2 + L2 * L2 - L1 * L1) / (2.0 * L2)
        disc = rho2 - k * k
        disc = np.where(disc >= -DISC_TOL * (L1 + L2) ** 2, np.maximum(disc, 0.0), np.nan)
        s = eps * np.sqrt(disc)
        with np.errstate(invalid="ignore", divide="ignore"):
            c34 = (k * u - s * Py) / rho2
            s34 = (k * Py + s * u) / rho2
        return c34, s34

    @staticmethod
    def _residual(c2: Array, s2: Array, c34: Array, s34: Array, z: Array) -> Array:
        return c34 * (c2 * z[0] + s2 * z[2]) + s34 * z[1]

    def _configuration(
        self, d1: Array, c2: Array, s2: Array, u: Array, Py: Array, c34: Array, s34: Array, R: Array
    ) -> Array:
        """Full configurations ``(..., 6)`` from the position part; R: ``(3, 3, ...)`` rows/cols leading."""
        L2 = self.L2
        th2 = np.arctan2(s2, c2)
        th3 = np.arctan2(u - L2 * c34, L2 * s34 - Py)
        th4 = np.arctan2(s34, c34) - th3
        th4 = np.pi - np.mod(np.pi - th4, 2.0 * np.pi)
        # V = R_B2^T R_D (rows), N = R_24^T V
        V0 = c2 * R[0] + s2 * R[2]
        V1 = -s2 * R[0] + c2 * R[2]
        V2 = -R[1]
        N0 = s34 * V0 + c34 * V2
        N1 = c34 * V0 - s34 * V2
        th5 = np.arctan2(N0[2], V1[2])
        th6 = np.arctan2(N1[0], N1[1])
        return np.stack([d1, th2, th3, th4, th5, th6], axis=-1)


def _unpack(poses: Array, extra_dims: int, snap: float) -> tuple[Array, Array, Array, Array, Array]:
    """Px, Py, Pz, z axis (3, N, 1...) and R (3, 3, N, 1...) broadcastable against (N, M[, B]); |Px| <= snap
    is taken as 0 (see ``PX_SNAP_REL``)."""
    shape = (poses.shape[0],) + (1,) * extra_dims
    P = poses[:, :3, 3]
    Px, Py, Pz = (P[:, i].reshape(shape) for i in range(3))
    Px = np.where(np.abs(Px) <= snap, 0.0, Px)
    R = np.moveaxis(poses[:, :3, :3], 0, -1).reshape(3, 3, *shape)
    z = R[:, 2]
    return Px, Py, Pz, z, R


class CArmD1(_CArmBase):
    """theta* = d1 (paper section 4). Four branches: b = 0..3 with sigma = +1 for b < 2 (theta2 of eq. 5b),
    -1 otherwise (eq. 5a), and elbow eps = +1 for even b.

    Blind spot: where the wrist point lies on joint 2's axis (Px = 0 and d1 = Pz) theta2 is not fixed by the
    position; ``special_solutions`` solves that slice from the orientation.
    """

    name = "carm-d1"
    #: Branches (sigma, eps) and (-sigma, -eps) have the same residual, bit for bit: c2, s2, u and the elbow's root
    #: change sign together, so C34 does too and S34 does not, and the residual's products keep their values (IEEE
    #: arithmetic is symmetric under sign changes). Their configurations differ (theta2 by pi, the elbow mirrored).
    twins = ((0, 3), (1, 2))
    kernel = (kernels.carm_d1_residual, kernels.carm_d1_configuration)
    kernel_residuals = kernels.carm_d1_residuals
    kernel_hints = kernels.carm_d1_hints
    n_kernel_hints = kernels.N_D1_HINTS
    fallback = "carm-theta2"
    blind_spots = "d1 = Pz with Px = 0 (wrist on joint 2's axis): solved separately as a special slice"

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot, free_joint=0, n_branches=4)
        L = self.L1 + self.L2
        self._reach = np.array([-L, L])  # (read only: shared by every search range)
        self._reach.flags.writeable = False

    def _signs(self, ndim: int, branch: IntArray | None) -> tuple[Array, Array]:
        if branch is None:
            b = np.arange(4).reshape((1,) * ndim + (4,))
        else:
            b = np.asarray(branch)
        sigma = np.where(b < 2, 1.0, -1.0)
        eps = np.where(b % 2 == 0, 1.0, -1.0)
        return sigma, eps

    def _position(self, poses: Array, theta: Array, branch: IntArray | None) -> tuple[Array, ...]:
        extra = 2 if branch is None else 1
        Px, Py, Pz, z, R = _unpack(poses, extra, self.px_snap)
        sigma, eps = self._signs(theta.ndim, branch)
        d1 = theta[..., None] if branch is None else theta
        t = Pz - d1
        r = np.sqrt(Px * Px + t * t)  # (as the kernels: kernels._d1_position)
        safe = r > 0
        rr = np.where(safe, r, 1.0)
        c2 = np.where(safe, sigma * Px / rr, sigma)
        s2 = np.where(safe, sigma * t / rr, 0.0)
        u = sigma * r
        c34, s34 = self._elbow(u, Py, eps)
        return d1, c2, s2, u, Py, c34, s34, z, R

    def sample_hints(self, poses: Array) -> Array:
        L1, L2 = self.L1, self.L2
        Px, Py, Pz = poses[:, 0, 3], poses[:, 1, 3], poses[:, 2, 3]
        q2 = Px * Px + Py * Py
        with np.errstate(invalid="ignore"):
            t_out = np.sqrt((L1 + L2) ** 2 - q2)  # NaN where no d1 reaches the wrist
            t_in = np.sqrt((L1 - L2) ** 2 - q2)
        # theta2 swings by pi across |t| ~ |Px| around d1 = Pz: sample that window densely in angle.
        swing = Pz[:, None] - np.abs(Px)[:, None] * _TAN_SWING[None, :]
        cols = [Pz - t_out, Pz + t_out, Pz - t_in, Pz + t_in, Pz]
        return np.concatenate([np.stack(cols, axis=-1), swing], axis=-1)

    def degenerate(self, poses: Array) -> NDArray[np.bool_] | None:
        """Wrist on joint 2's axis (Px = 0) where the orientation does not fix theta2 either (A = B = c = 0 in
        ``special_solutions``, e.g. theta3 = 0, theta4 = -90 deg, theta5 = 0): a continuum along theta2, which a
        d1 sweep cannot describe; carm-theta2 reports it as a family."""
        return self._self_motion(poses, 1e-9)

    def search_range(self, poses: Array) -> Array:
        return poses[:, 2, 3, None] + self._reach

    def special_solutions(self, poses: Array) -> Array | None:
        """Wrist on joint 2's axis (Px = 0, d1 = Pz): u = 0, theta34 from the elbow, theta2 from the
        orientation (``A cos theta2 + B sin theta2 = c``). 4 candidates per pose (NaN where none)."""
        sel = self._wrist_on_axis(poses)
        if sel is None:
            return None
        Px, Py, Pz, z, R = _unpack(poses, 0, self.px_snap)
        out = []
        for eps in (1.0, -1.0):
            c34, s34 = self._elbow(np.zeros_like(Py), Py, np.full_like(Py, eps))
            # c34 (c2 zx + s2 zz) + s34 zy = 0  ->  c2 zx + s2 zz = rhs
            A, B = c34 * z[0], c34 * z[2]
            rhs = -s34 * z[1]
            amp = np.hypot(A, B)
            with np.errstate(invalid="ignore", divide="ignore"):
                base = np.arctan2(B, A)
                delta = np.arccos(rhs / amp)
            for sgn in (1.0, -1.0):
                th2 = base + sgn * delta
                c2, s2 = np.cos(th2), np.sin(th2)
                q = self._configuration(Pz, c2, s2, np.zeros_like(Py), Py, c34, s34, R)
                out.append(np.where(sel[..., None], q, np.nan))
        return np.stack(out, axis=1)


class CArmTheta2(_CArmBase):
    """theta* = theta2 (revolute, periodic). Two branches (elbow eps = +1 for b = 0).

    Given theta2, entry {2,4} fixes ``d1 = Pz - Px tan(theta2)``. Blind spot: cos(theta2) = 0, where d1
    drops out of that equation (possible only when Px = 0), and its neighbourhood, where d1 is
    ill-conditioned; ``blind_spot`` hands it to the d1 reduction. Self-motion families
    (theta2 = +-90 deg with theta5 = 0) lie entirely in that slice: ``degenerate`` hands them to carm-d1.
    """

    name = "carm-theta2"
    kernel = (kernels.carm_theta2_residual, kernels.carm_theta2_configuration)
    fallback = "carm-d1"
    blind_spots = "cos(theta2) = 0 (d1 drops out): solved separately as a special slice; families need carm-d1"

    def __init__(self, robot: Robot) -> None:
        super().__init__(robot, free_joint=1, n_branches=2)

    def _position(self, poses: Array, theta: Array, branch: IntArray | None) -> tuple[Array, ...]:
        extra = 2 if branch is None else 1
        Px, Py, Pz, z, R = _unpack(poses, extra, self.px_snap)
        th = theta[..., None] if branch is None else theta
        b = np.arange(2).reshape((1,) * theta.ndim + (2,)) if branch is None else np.asarray(branch)
        eps = np.where(b == 0, 1.0, -1.0)
        c2, s2 = np.cos(th), np.sin(th)
        with np.errstate(divide="ignore", invalid="ignore"):
            u = Px / c2
            d1 = Pz - s2 * u
        u = np.where(np.abs(c2) > 1e-300, u, np.nan)
        c34, s34 = self._elbow(u, Py, eps)
        return d1, c2, s2, u, Py, c34, s34, z, R

    def sample_hints(self, poses: Array) -> Array:
        L1, L2 = self.L1, self.L2
        Px, Py = poses[:, 0, 3], poses[:, 1, 3]
        cols = [np.full_like(Px, np.pi / 2), np.full_like(Px, -np.pi / 2), np.zeros_like(Px), np.full_like(Px, np.pi)]
        # Near cos(theta2) = 0, d1 = Pz - Px tan(theta2) races through its whole range within a window of
        # width ~|Px| / (L1 + L2): sample that window uniformly in d1 (i.e. theta2 = atan(t / Px)).
        t = np.linspace(-(L1 + L2), L1 + L2, _SWING_SAMPLES * 2 + 1)
        win = np.arctan2(t[None, :], Px[:, None])
        cols += list(win.T) + list((win - np.pi).T)
        for bound in ((L1 + L2) ** 2, (L1 - L2) ** 2):
            with np.errstate(invalid="ignore", divide="ignore"):
                umax = np.sqrt(bound - Py * Py)  # |u| = |Px / cos theta2| at the domain edge
                c = np.abs(Px) / umax
                a = np.where(c <= 1.0, np.arccos(np.minimum(c, 1.0)), np.nan)
            cols += [a, -a, np.pi - a, a - np.pi]
        return np.stack(cols, axis=-1)

    def degenerate(self, poses: Array) -> NDArray[np.bool_] | None:
        """Wrist in the plane Px = 0: self-motion families (theta2 = +-90 deg with theta5 = 0) lie in the blind
        spot cos(theta2) = 0, where a theta2 sweep cannot describe them; carm-d1 reports them."""
        return self._wrist_on_axis(poses)

    def blind_spot(self, poses: Array) -> tuple[IntArray, Reduction, Array] | None:
        """Poses near the blind spot cos(theta2) = 0, with the d1 reduction that solves them.

        Near theta2 = +-90 deg, d1 = Pz - Px tan(theta2) races through its range within a window of width
        ~|Px| / (L1 + L2) in theta2, so a theta2 sweep is ill-conditioned there and blind at its centre.
        For poses with |Px| below ``BLIND_PX_REL * (L1 + L2)`` the d1 sweep supplies the solutions with
        |cos(theta2)| <= ``BLIND_COS`` (``blind_spot_kept``); the theta2 sweep supplies all others.
        """
        Px = poses[:, 0, 3]
        idx = np.nonzero(np.abs(Px) <= BLIND_PX_REL * (self.L1 + self.L2))[0]
        if idx.size == 0:
            return None
        d1red = CArmD1(self.robot)
        return idx, d1red, d1red.search_range(poses[idx])

    def blind_spot_kept(self, q: Array) -> NDArray[np.bool_]:
        return np.abs(np.cos(q[:, 1])) <= BLIND_COS
