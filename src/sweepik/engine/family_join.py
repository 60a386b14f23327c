"""A chunk's families joined with its isolated solutions and with the fallback reduction's: continua that the sweep's
closed form cut short traced whole, families crossing each other (``crossings``) added, isolated solutions lying
on a family reported by the family."""

from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import Traced, continuum_families, correct
from sweepik.engine.crossings import crossing_grids, crossing_seeds
from sweepik.engine.families import (
    inner_off,
    members_at,
    off_families,
    unique_families,
)
from sweepik.engine.polish import geodesic_errors
from sweepik.engine.settings import ACCEPT_TOL_REL, AT_LIMIT, INNER_PROBES, PAST_END_REL, POLISH_BELOW_REL
from sweepik.engine.settle import per_joint
from sweepik.model.robot import Robot
from sweepik.model.units import orientation_weight
from sweepik.reductions import Reduction
from sweepik.results import Block, Family, Solutions

Array = NDArray[np.float64]


def _cut_short(robot: Robot, family: Family, target: Array, limits: bool) -> bool:
    """The family's continuum goes on past one of its ends (the sweep's closed form lost it there: its members stop
    being certified), where no joint limit cuts it."""
    j = family.free_joint
    ends = np.array(family.interval)
    span = (-np.pi, np.pi) if robot.is_revolute[j] else (float(robot.lower[j]), float(robot.upper[j]))
    inner = (np.abs(ends - span[0]) > AT_LIMIT) & (np.abs(ends - span[1]) > AT_LIMIT)
    if limits:
        m = robot.wrap(family.at(ends))
        slack = per_joint(robot, AT_LIMIT)
        inner &= ~np.any((np.abs(m - robot.lower) <= slack) | (np.abs(m - robot.upper) <= slack), axis=-1)
    if not inner.any():
        return False
    past = (ends + np.array([-1.0, 1.0]) * PAST_END_REL * (span[1] - span[0]))[inner]
    red = family.reduction
    q = red.solve_rest(family.chain_pose[None], past[None, :], np.full((1, past.size), family.branch))[0]
    err = geodesic_errors(robot, q, np.broadcast_to(target, (past.size, 4, 4)), orientation_weight(robot.length_unit))
    return bool(np.any(err <= POLISH_BELOW_REL * robot.length_scale))


def trace_cut_continua(
    robot: Robot,
    sweep: Reduction,
    chain: Array,
    poses: Array,
    idx: NDArray[np.intp],
    alt: Block,
    limits: bool,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
) -> None:
    """A closed form's degenerate poses ``idx``, answered by its fallback ``sweep`` (``alt``): where the sweep's closed
    form loses digits along a continuum (the C-Arm with joints 5 and 6 swapped, its elbow nearly straight), the
    continuum comes out as short pieces and isolated members. From those (each isolated solution, the middle of each
    piece) it is traced along the sweep's joint (:mod:`.continuation`: exact members, and only from a configuration
    where the arm is singular); the continua found go to ``fams``, and the fallback's families they cover are
    dropped from ``fallback``. The fallback's families traced already (:mod:`.rough_continua`) are whole: the
    isolated solutions on them are no seeds, and a continuum traced again along one of them is not added."""
    pose = [idx[np.repeat(np.arange(idx.size), np.diff(alt.bounds))]]
    seeds = [alt.q]
    whole: dict[int, tuple[Family, ...]] = {}  # (the fallback's traced families, per pose of the chunk)
    for k, pieces in alt.families.items():  # (few poses)
        whole[int(idx[k])] = tuple(f for f in pieces if isinstance(f.reduction, Traced))
        cut = [f for f in pieces if not isinstance(f.reduction, Traced) and _cut_short(robot, f, poses[idx[k]], limits)]
        if cut:
            pose.append(np.full(len(cut), idx[k], dtype=np.intp))
            seeds.append(np.array([f.at(0.5 * (f.interval[0] + f.interval[1])) for f in cut]))
    p, q = np.concatenate(pose), np.concatenate(seeds)
    if whole and p.size:
        off = np.ones(p.size, dtype=bool)
        for i, known in whole.items():
            rows = np.nonzero(p == i)[0]
            off[rows] = off_families(robot, [(q[rows], known)])[0]
        p, q = p[off], q[off]
    traced: dict[int, list[Family]] = {}
    if p.size:
        joint = np.full(p.size, sweep.free_joint, dtype=np.intp)
        tol = ACCEPT_TOL_REL * robot.length_scale
        # (the continua's pieces that shrink to a point at a limit are left out: the fallback has them as solutions)
        traced, _, _ = continuum_families(robot, chain, poses, p, q, joint, limits, tol)
    for i in sorted(set(traced) | set(whole)):
        found, known = traced.get(i, []), whole.get(i, ())
        sol = fallback[i]
        if found and known:  # a traced family's continuum again (from an isolated solution on it): not added ...
            new = inner_off(robot, found, known)
            again = tuple(f for f, o in zip(found, new, strict=True) if not o)
            found = [f for f, o in zip(found, new, strict=True) if o]
            if again and len(sol):  # ... and its seeds are members of it (at a fold, or where it meets itself)
                sol = sol.kept(off_families(robot, [(sol.q, again)])[0])
        if found:
            fams.setdefault(i, []).extend(found)
        swept = [f for f in sol.families if not isinstance(f.reduction, Traced)]
        if swept and (found or known):  # the pieces: covered when their ends and middle are members of a continuum
            ends = [f.at(np.linspace(f.interval[0], f.interval[1], 3)) for f in swept]
            uncovered = off_families(robot, [(m, tuple(found) + known) for m in ends])
            sol = dataclasses.replace(
                sol, families=known + tuple(f for f, o in zip(swept, uncovered, strict=True) if o.any())
            )
        fallback[i] = sol


def add_crossing_families(
    robot: Robot,
    chain: Array,
    poses: Array,
    limits: bool,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
) -> None:
    """The continua that cross the families found (``fams`` and the fallback's, per pose), traced from where they
    cross (:mod:`.crossings`) and added to ``fams`` when not on a family found already."""
    tol = ACCEPT_TOL_REL * robot.length_scale
    known: dict[int, tuple[Family, ...]] = {}
    for i in sorted(set(fams) | set(fallback)):
        known[i] = tuple(fams.get(i, ())) + (fallback[i].families if i in fallback else ())
    grids = iter(crossing_grids(robot, [f for fs in known.values() for f in fs]))  # (the batch's at once)
    seed_p, seed_q, seed_j = [], [], []
    for i, fs in known.items():
        q, j = crossing_seeds(robot, fs, [next(grids) for _ in fs])
        if j.size:
            seed_p.append(np.full(j.size, i, dtype=np.intp))
            seed_q.append(q)
            seed_j.append(j)
    if not seed_p:
        return
    p, q, j = np.concatenate(seed_p), np.concatenate(seed_q), np.concatenate(seed_j)
    # onto the solution set; those that fall back onto a family found already are not traced (most crossings of a
    # family with another singular set branch into no other continuum)
    q, err = correct(robot, q, poses[p], j, tol)
    new = err <= tol
    for i in np.unique(p[new]).tolist():
        rows = np.nonzero(new & (p == i))[0]
        new[rows] = off_families(robot, [(q[rows], known[i])])[0]
    if not new.any():
        return
    traced, _, _ = continuum_families(robot, chain, poses, p[new], q[new], j[new], limits, tol)
    for i, found in traced.items():
        fams.setdefault(i, []).extend(f for f, o in zip(found, inner_off(robot, found, known[i]), strict=True) if o)


def _not_repeated(robot: Robot, families: dict[int, tuple[Family, ...]]) -> dict[int, tuple[Family, ...]]:
    """Each pose's ``families`` without those lying on an earlier one, ends and ``INNER_PROBES`` included: one
    continuum found twice, along two joints (a wrist with its slide at zero: the q4/q6 continuum traced along joint 4
    and along joint 6), or a piece of one found whole too. One that lies on two others (a piece reaching 3.5e-4 rad
    past the end of the one it crosses there) stays. The batch's poses at once; the ends first, the inner probes only
    of a family whose ends lie on the other."""
    several = {i: fs for i, fs in families.items() if len(fs) > 1}
    pairs = [(i, a, b) for i, fs in several.items() for a in range(1, len(fs)) for b in range(a)]  # (a on b, pose i)
    for fractions in (np.array([0.0, 1.0]), np.array(INNER_PROBES)):
        if not pairs:
            break
        asked = sorted({(i, a) for i, a, _ in pairs})
        probed = [several[i][a] for i, a in asked]
        at = [f.interval[0] + (f.interval[1] - f.interval[0]) * fractions for f in probed]
        members = dict(zip(asked, members_at(probed, at), strict=True))
        offs = off_families(robot, [(members[i, a], (several[i][b],)) for i, a, b in pairs])
        pairs = [pair for pair, off in zip(pairs, offs, strict=True) if not off.any()]
    on = set(pairs)
    out = dict(families)
    for i, mine in several.items():
        kept: list[int] = []
        for a in range(len(mine)):
            if not any((i, a, b) in on for b in kept):
                kept.append(a)
        out[i] = tuple(mine[a] for a in kept)
    return out


def with_families(
    robot: Robot,
    red: Reduction,
    fams: dict[int, list[Family]],
    fallback: dict[int, Solutions],
    pose_idx: NDArray[np.intp],
    q: Array,
    err_paper: Array,
    err_geo: Array,
    inside: NDArray[np.bool_],
    mult: NDArray[np.intp],
) -> tuple[dict[int, tuple[Family, ...]], NDArray[np.intp], Array, Array, Array, NDArray[np.bool_], NDArray[np.intp]]:
    """The families of the poses that have some (``fams``, and the fallback reduction's, ``fallback``), and the
    solutions with those on a family dropped and the fallback's added: ``(families, pose_idx, q, err_paper,
    err_geo, inside, mult)``."""
    families: dict[int, tuple[Family, ...]] = {}
    keep = np.ones(pose_idx.size, dtype=bool)
    extra: list[tuple[int, Solutions, NDArray[np.bool_]]] = []
    checks: list[tuple[Array, tuple[Family, ...]]] = []  # (configurations, families) of each pose, checked at once
    targets: list[tuple[int, Solutions | None, NDArray[np.intp]]] = []
    for i in sorted(set(fams) | set(fallback)):
        other = fallback.get(i)
        own = tuple(fams.get(i, ()))
        families[i] = own if other is None else unique_families(own + other.families)
    families = _not_repeated(robot, families)
    for i, fam in families.items():
        other = fallback.get(i)
        rows = np.nonzero(pose_idx == i)[0]
        if other is not None and (rows.size == 0 or red.closed_form):
            keep[rows] = False
            checks.append((other.q, fam))
            targets.append((i, other, rows))
        else:
            checks.append((q[rows], fam))
            targets.append((i, None, rows))
    for (i, other, rows), off in zip(targets, off_families(robot, checks), strict=True):
        if other is None:
            keep[rows] = off
        else:
            extra.append((i, other, off))
    if extra or not keep.all():
        p_parts, q_parts, e_parts = [pose_idx[keep]], [q[keep]], [err_paper[keep]]
        g_parts, in_parts, m_parts = [err_geo[keep]], [inside[keep]], [mult[keep]]
        for i, other, k in extra:
            p_parts.append(np.full(int(k.sum()), i, dtype=pose_idx.dtype))
            q_parts.append(other.q[k])
            e_parts.append(other.error[k])
            g_parts.append(other.error_geodesic[k])
            in_parts.append(other.within_limits[k])
            m_parts.append(other.multiplicity[k])
        pose_idx, q, err_paper = np.concatenate(p_parts), np.concatenate(q_parts), np.concatenate(e_parts)
        err_geo, inside, mult = np.concatenate(g_parts), np.concatenate(in_parts), np.concatenate(m_parts)
    return families, pose_idx, q, err_paper, err_geo, inside, mult
