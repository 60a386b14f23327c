"""The general method's usual case in one compiled call per pose, on a 16x16 eigenproblem instead of 24x24.

The elimination (:mod:`.elimination`) ends in a 12x12 matrix polynomial ``S(x) = A x^2 + B x + C`` in the eigen-joint's
half-angle tangent. Its determinant has degree 24, of which ``(1 + x^2)^4`` is spurious (clearing the half-angle's
denominators): the 24x24 companion matrix spends a third of its eigenvalues, and more than half of the arithmetic,
on roots known in advance. They can be removed before the eigenproblem:

* The left null space of ``S(i)`` (4-dimensional) depends on the arm and the arrangement only, not on the pose or on
  the half-angle's shift (the eigen-joint's ``e^{-i theta}`` coefficient is a fixed row combination of the pose's
  data): it is computed once per arm (``deflation``), ``U (12, 4)`` complex, and checked at a second pose.
* For each column ``u`` of ``U``, the row ``u^T S(x)`` vanishes at ``x = i``, so it is ``(x - i)`` times the linear
  row ``(u^T A) x + (u^T B + i u^T A)``. Its real and imaginary parts give 8 real rows of degree 1; 4 rows
  orthogonal to them (``V``) stay quadratic. The transformed polynomial has the same real roots and determinant
  ``p_16(x)`` up to a constant.
* Its linearization by row degrees is 16x16: unknowns ``(v, w = x V^T A v)``, equations ``P1 x v + P0 v = 0`` (8),
  ``x (V^T B v + w) + V^T C v = 0`` (4), ``w - x V^T A v = 0`` (4): the pencil ``x E + F``. Its eigenvalues are
  those of ``-E^-1 F``, computed with LAPACK's ``dgeev`` (:mod:`.lapack`).

The back-substitution, polish and FK check are the elimination's own (``_candidates_std``). A pose whose answer the
elimination would question (a real root that does not polish, an odd count or none, a root at a singular
configuration, a leading matrix ill conditioned for every shift) is marked, and the caller solves it by
``GeneralIK.solve``, which asks the other arrangements (measured: about 1 pose in 100 on random arms, most of them on
purpose singular; and every pose out of reach, ~250 us instead of ~45 on random arms).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from sweepik._jit import ERROR_MODEL
from sweepik.engine import parallel
from sweepik.engine.settings import PARALLEL_MIN
from sweepik.reductions import lapack
from sweepik.reductions.elimination import (
    FK_TOL,
    IMAG_TOL,
    MERGE_TOL,
    GeneralIK,
    _Arrangement,
    _candidates_std,
    _chain_fk,
    _filter_candidates,
    _inv_rc,
    _merge_nb,
    _pencil,
    _pose_in_nb,
)

__all__ = ["FastPath", "fast_path", "solve_poses"]

#: The left null space of ``S(i)``: its 4 smallest singular values are zero to this, relative (else no deflation).
NULL_TOL = 1e-11
#: ... and the 8th is above this (rank exactly 8: the spurious roots semisimple).
RANK_TOL = 1e-8
#: The leading matrix's reciprocal condition number under which a pose takes the full path (as the companion's).
RCOND_MIN = 1e-10
#: A root whose Jacobian's pivot ratio is under this is at a singular configuration (``GeneralIK``'s test).
SINGULAR_PIVOT = 1e-5


class FastPath(NamedTuple):
    """What the compiled solve of one arrangement needs (``fast_path``)."""

    pose_in: tuple  # (reversed, M0R, M0p)
    pencil: tuple  # _pencil's arguments after (Rt, pt) and before slot_off: see _front
    deflation: tuple  # (Ur, Ui, V)
    completion: tuple  # _candidates_std's arguments that depend on the arm only
    chain: tuple  # (H, P, rev, R_end) of the arm (normalised lengths)
    phis: NDArray[np.float64]
    b0: NDArray[np.float64]
    scale: float


def _S_at_i(ik: GeneralIK, a: _Arrangement, q: NDArray[np.float64]) -> NDArray[np.complex128]:
    """``S(i)`` of arrangement ``a`` at the pose of configuration ``q``."""
    RT, pT = _chain_fk(ik.H, ik.P, ik.rev, ik.R_end, q)
    _, Rt, pt, q0, N, _, _ = ik._pose_data(a, RT, pT)
    M, _, _ = ik._coeffs(a, Rt, pt, a.slot_off.copy(), q0, N)
    return -M[2] + 1j * M[1] + M[0]


def deflation(ik: GeneralIK, a: _Arrangement, rng: np.random.Generator) -> tuple | None:
    """``(Ur, Ui, V)``: the left null space of arrangement ``a``'s ``S(i)`` (real and imaginary parts, ``(12, 4)``) and
    an orthonormal basis of the rows orthogonal to both parts (``(12, 4)``); None where ``S(i)`` does not have rank 8
    at a random pose, or its null space differs at a second one."""
    qs = rng.uniform(-np.pi, np.pi, (2, 6))
    qs[:, ~ik.rev] = rng.uniform(-0.5, 0.5, (2, int((~ik.rev).sum())))
    S = _S_at_i(ik, a, qs[0])
    U, sv, _ = np.linalg.svd(S)
    if sv[0] == 0.0 or sv[8] > NULL_TOL * sv[0] or sv[7] < RANK_TOL * sv[0]:
        return None
    null = U[:, 8:].conj()  # u^T S(i) = 0
    S2 = _S_at_i(ik, a, qs[1])
    if np.linalg.norm(null.T @ S2) > NULL_TOL * np.linalg.norm(S2):
        return None
    both = np.concatenate([null.real, null.imag], axis=1)
    basis, r = np.linalg.qr(both, mode="complete")
    if abs(r[7, 7]) < RANK_TOL * abs(r[0, 0]):
        return None
    return np.ascontiguousarray(null.real), np.ascontiguousarray(null.imag), np.ascontiguousarray(basis[:, 8:])


def fast_path(ik: GeneralIK) -> FastPath | None:
    """The compiled path of ``ik``'s arrangement for it (``GeneralIK.fast``), or None where it has none (no
    arrangement of the standard construction with a revolute eigen-joint, not swapped, recovers every trial pose, or
    no deflation) or LAPACK is not at hand."""
    a = ik.fast
    if not lapack.AVAILABLE or a is None:
        return None
    defl = deflation(ik, a, np.random.default_rng(7))
    if defl is None:
        return None
    path = FastPath(
        pose_in=(a.reversed, a.M0R, a.M0p),
        pencil=(a.ops_kind, a.ops_h, a.ops_c, a.ops_slot, a.n_pre, a.o, a.hl, a.ref, a.slot_kind, a.G, a.q0, a.N),
        deflation=defl,
        completion=(a.slot_off, a.pinvQ, a.E_kind, a.E_idx, a.slots_idx, a.L, a.H, a.P, a.rev, a.R_end),
        chain=(ik.H, ik.P, ik.rev, ik.R_end),
        phis=np.ascontiguousarray(ik._phis[:4]),
        b0=ik._rng_b0,
        scale=ik.scale,
    )
    return path if _agrees(ik, path, np.random.default_rng(11)) else None


#: Random configurations on which the compiled path must give the full elimination's answer (``_agrees``) ...
CHECK_POSES = 12
#: ... or this many, where the arrangements' ranking was taken over from the same arm held at another value
#: (``GeneralIK.hinted``: its compiled path passed the full check there).
HINTED_CHECK_POSES = 4


def _agrees(ik: GeneralIK, path: FastPath, rng: np.random.Generator) -> bool:
    """The compiled path answers ``CHECK_POSES`` (``HINTED_CHECK_POSES``) random poses of the arm with as many
    solutions as the full elimination of its arrangement (``GeneralIK.count``) where it answers at all. An arm whose
    three axes are parallel to a few micrometres (the I2RT big YAM: joints 2-4 to 2.7e-6 rad) has pairs of roots 1e-4
    apart in the eigen-joint that the deflated pencil merged into one: 4 of 8 solutions at one random pose in 13, the
    full elimination all 8."""
    n = HINTED_CHECK_POSES if ik.hinted else CHECK_POSES
    q = rng.uniform(-np.pi, np.pi, (n, 6))
    q[:, ~ik.rev] = rng.uniform(-1.0, 1.0, (n, int(np.sum(~ik.rev))))
    world = np.empty((n, 4, 4))
    for k in range(n):
        R, p = _chain_fk(ik.H, ik.P, ik.rev, ik.R_end, q[k])
        world[k] = np.eye(4)
        world[k, :3, :3], world[k, :3, 3] = R, p * ik.scale
    _, count = solve_poses(path, world, 16)
    for k in np.flatnonzero(count >= 0).tolist():
        if ik.count(ik.fast, world[k]) != count[k]:
            return False
    return True


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _front(Rt, pt, phis, slot_off, pencil, deflation):
    """The 16x16 matrix ``-E^-1 F`` of the deflated pencil (the other slots' offsets ``slot_off[1:]``) for the first
    shift phi whose leading matrix ``E`` is well
    conditioned (else the best): ``(G, M (3, 12, 12) the pencil's coefficients, phi, rcond)``."""
    ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, ref, slot_kind, G, q0, N = pencil
    Ur, Ui, V = deflation
    best_rc, best_phi = -1.0, 0.0
    bestM = np.zeros((3, 12, 12))
    bestE = np.zeros((16, 16))
    F = np.zeros((16, 16))
    so = slot_off.copy()
    for k in range(phis.shape[0]):
        so[0] = phis[k]
        M = _pencil(ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, slot_kind, so, G, q0, N)
        C, B, A = M[0], M[1], M[2]
        rA, iA, rB, iB = Ur.T @ A, Ui.T @ A, Ur.T @ B, Ui.T @ B
        E = np.zeros((16, 16))
        E[:4, :12] = rA
        E[4:8, :12] = iA
        E[8:12, :12] = V.T @ B
        E[12:16, :12] = -(V.T @ A)
        for j in range(4):
            E[8 + j, 12 + j] = 1.0
        Einv, rc = _inv_rc(E)
        if rc > best_rc:
            best_rc, best_phi, bestM = rc, phis[k], M
            bestE = Einv
            F[:] = 0.0
            F[:4, :12] = rB - iA
            F[4:8, :12] = iB + rA
            F[8:12, :12] = V.T @ C
            for j in range(4):
                F[12 + j, 12 + j] = 1.0
        if rc > 1e-6:
            break
    return -(bestE @ F), bestM, best_phi, best_rc


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _solve_pose(RT, pT, path, out):
    """One pose (``RT``, ``pT`` normalised) by the compiled path: its solutions into ``out[:k]``; returns ``k``, or -1
    where the pose takes the full path (see the module docstring)."""
    pose_in, pencil, deflation, completion, chain, phis, b0 = path
    reversed_, M0R, M0p = pose_in
    slot_off, pinvQ, E_kind, E_idx, slots_idx, L_idx, Ha, Pa, reva, Rend_a = completion
    H, P, rev, R_end = chain
    ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, ref, slot_kind, _, q0, _ = pencil
    RTa, _, Rt, pt = _pose_in_nb(RT, pT, reversed_, M0R, M0p)
    Gm, M, phi, rc = _front(Rt, pt, phis, slot_off, pencil, deflation)
    if not rc > RCOND_MIN:
        return -1
    wr, wi, info = lapack.eigenvalues(Gm)
    if info != 0:
        return -1
    xs, ims = _filter_candidates(wr + 1j * wi, IMAG_TOL)
    so = slot_off.copy()
    so[0] = phi
    S, prs, n_fail = _candidates_std(
        M, xs, ims, phi, b0, ops_kind, ops_h, ops_c, ops_slot, n_pre, o, hl, Rt, pt, ref, slot_kind, so, q0, pinvQ,
        E_kind, E_idx, slots_idx, L_idx, Ha, Pa, reva, Rend_a, RTa, reversed_, H, P, rev, R_end, RT, pT, FK_TOL,
    )  # fmt: skip
    if n_fail > 0:
        return -1
    keep = _merge_nb(S, rev, MERGE_TOL)
    k = 0
    for i in range(S.shape[0]):
        if keep[i]:
            if prs[i] < SINGULAR_PIVOT or k == out.shape[0]:
                return -1
            out[k] = S[i]
            k += 1
    return -1 if k % 2 == 1 or k == 0 else k  # (none: the full path asks another arrangement, GeneralIK.solve)


@njit(cache=True, nogil=True, error_model=ERROR_MODEL)
def _solve_batch(world, path, scale, out, count, start, stop):
    """Poses ``start .. stop - 1`` of ``world (N, 4, 4)`` (the chain's frame, the arm's lengths): solutions into
    ``out (N, B, 6)`` (lengths in the arm's unit, NaN rows after the last), their number into ``count`` (-1: the full
    path)."""
    for i in range(start, stop):
        RT = np.ascontiguousarray(world[i, :3, :3])
        pT = world[i, :3, 3] / scale
        out[i] = np.nan
        k = _solve_pose(RT, pT, path, out[i])
        count[i] = k
        for j in range(max(k, 0)):
            for c in range(6):
                if not path[4][2][c]:
                    out[i, j, c] *= scale


def solve_poses(path: FastPath, world: NDArray[np.float64], n_max: int) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """``(solutions (N, n_max, 6) NaN-padded, count (N,))`` of the poses ``world (N, 4, 4)`` by the compiled path,
    on the engine's threads; count -1 marks a pose for ``GeneralIK.solve``."""
    n = world.shape[0]
    out = np.empty((n, n_max, 6))
    count = np.empty(n, dtype=np.int64)
    tup = (path.pose_in, path.pencil, path.deflation, path.completion, path.chain, path.phis, path.b0)
    w = np.ascontiguousarray(world, dtype=np.float64)
    parallel.run(_solve_batch, n, PARALLEL_MIN, w, tup, float(path.scale), out, count)
    return out, count.astype(np.intp)
