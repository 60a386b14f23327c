"""Reachable workspace volume of the tool point, with an honest uncertainty.

The workspace is the set of tool-origin positions reachable with *any* orientation inside the joint limits.
:func:`workspace_volume` estimates its volume (length unit cubed) from configurations drawn uniformly inside the
limits (:func:`sweepik.experiments.verify.random_configurations`), in three steps.

1. **Voxels.** Tool positions are binned into cubic voxels of edge ``h`` on a grid whose origin is shifted by a
   random fraction of a voxel (so that flat faces of the workspace do not line up with voxel faces); ``h`` is
   chosen from a pilot chunk so that occupied voxels get about ``samples_per_voxel`` samples each (fewer when
   that would leave under ``MIN_VOXELS`` voxels). A voxel is *inside* when its 26 neighbours are all occupied (26,
   not 6: a voxel cut by a plane has a neighbour across one of its corners that lies wholly outside, so inside
   voxels are whole) and on the *boundary* otherwise. An empty voxel with 5 or 6 occupied face neighbours is a
   hole in the sampling (a voxel outside the workspace has at most 4, in a groove one voxel wide) and counts in.
2. **Rays to the boundary.** Uniform joint samples reach the boundary poorly: the density of tool positions near
   a boundary varies like a power of the distance to it, diverging at the fold of a 3-joint position map and
   vanishing where more joints move the point (an arm stretched out with a wrist offset), so a whole layer of the
   workspace gets few or no samples. From one configuration in each boundary voxel the tool point is therefore
   driven along the voxel's outward direction (the mean direction of its empty neighbours) by damped least
   squares on the position Jacobian, joints clipped at their limits, until it cannot advance. Every configuration
   on the way lies inside the limits, so its position is reachable (it fills voxels the samples missed). Where a
   ray stalls the point is on the boundary: the Jacobian without the columns of joints held at a limit has rank
   2, its columns span the boundary's tangent plane and its left null vector is the normal. A second round casts
   from boundary voxels still without a boundary point nearby. A stall with occupied voxels beyond it (an inner
   singular surface, covered by another branch of the arm) is dropped; one with nothing behind it lies on a
   sheet (a workspace of no thickness, such as a sphere's surface) and is kept with both normals.
3. **Fill of boundary voxels.** Each boundary voxel's inside fraction is measured at 64 stratified random points:
   a point is inside when it lies behind the tangent plane of the nearest boundary point found in the voxel's
   3x3x3 neighbourhood; where the two nearest planes meet at an edge (normals more than ``EDGE_ANGLE_DEG``
   apart) it must lie behind both at a convex edge, behind either at a concave one. Voxels with no boundary point
   nearby (thin parts; rays that failed) take ``min(1/2, their samples' bounding-box fraction)``, so a flat, linear
   or point workspace comes out as (nearly) zero with ``lower == 0``.

``volume = lower + h**3 * sum of boundary fills``; ``lower`` counts the inside voxels, ``upper`` every occupied
voxel (samples and ray points) and hole.

**Why not the simpler estimates.** ``upper`` counts every boundary voxel whole (+10 to +20 % at the default
settings). Filling boundary voxels by their sample count relative to their inside neighbours is exact only when
the density stays flat up to the boundary (a gantry's joint-limit faces); measured at 2e5 samples it is off by
+3 to +8 % at the fold of a 2R or 3R arm and by -10 to -18 % on a gantry with a 60 mm tool offset, the kind of
boundary real 6-joint arms have. Tangent planes locate the boundary inside the voxel whatever the density.

**Uncertainty** is the sum of: the guessed fill of boundary voxels with no boundary point nearby (in full), and
half of each hole; half the disagreement between the fills from the nearest and from the second-nearest tangent
plane (how well the boundary is resolved: large at edges and strongly curved parts); the sampling error of the 64
points per voxel; the change of the estimate with voxels twice as large (holes, misclassified voxels, edge
effects grow with the voxel); and ``UNCERTAINTY_FLOOR_REL`` of the volume. On the five arms with known workspaces
of ``tests/test_workspace.py`` (10 seeds each, the truth always within the uncertainty) the defaults (2e5
configurations) give errors of at most 0.3 % with uncertainties of 0.7 to 1.5 %; 1e4 to 5e4 configurations at
most 0.8 % within 0.8 to 2.3 %; 1e3 at most 6 % within 2 to 15 %; 1e6 at most 0.07 % within 0.6 to 0.9 %. The
UR5, C-Arm and Panda come within 0.4 % of their values at 5e6 configurations.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from sweepik.errors import RobotDefinitionError, UnknownOptionError
from sweepik.experiments.verify import random_configurations
from sweepik.model.chain import Chain
from sweepik.model.robot import Robot
from sweepik.model.units import mm_per_unit
from sweepik.model.validate import check_int, short_repr

__all__ = ["WorkspaceVolume", "workspace_volume"]

Array = NDArray[np.float64]
IntArray = NDArray[np.int64]
BoolArray = NDArray[np.bool_]

#: Fewest and most configurations: at 1e3 (200 voxels) errors reach 5 %, within uncertainties of 2 to 15 %;
#: 1e8 takes several minutes.
MIN_CONFIGURATIONS = 1_000
MAX_CONFIGURATIONS = 100_000_000
#: Samples per occupied voxel. Fewer (smaller voxels) leave holes where the density is low and cost more rays
#: (5: UR5 -1.0 %, 3 to 5 s); more coarsen the voxels. At 2e5 configurations errors stay within 0.55 % from 10 to
#: 40 on the test arms, the UR5, C-Arm and Panda, while the time falls from about 1.2 s to 0.45 s.
DEFAULT_SAMPLES_PER_VOXEL = 20.0
#: With few configurations ``samples_per_voxel`` is lowered (not below SMALL_SAMPLES_PER_VOXEL) so that there are
#: about MIN_VOXELS occupied voxels: at 5e3 configurations and 20 per voxel (250 voxels) the voxels are too
#: coarse for the workspace's features (errors up to 10 %); at 5 per voxel the errors stay within 1.3 %.
MIN_VOXELS = 2_000
SMALL_SAMPLES_PER_VOXEL = 5.0
#: Below 3 samples per voxel the holes in the uniform sampling merge and the volume comes out 5 to 40 % low.
SAMPLES_PER_VOXEL_RANGE = (3.0, 1000.0)
DEFAULT_CHUNK = 65_536
CHUNK_RANGE = (1_024, 10_000_000)
#: Largest tool reach (links plus prismatic travel, length unit) accepted: robot files bound lengths at 1e12.
MAX_REACH = 1e12

#: Ray casting: at most RAY_STEPS steps of at most one voxel each; a ray has stalled when its step has shrunk
#: below RAY_STALL voxels (each failed step divides it by 5).
RAY_STEPS = 16
RAY_ROUNDS = 2
RAY_STALL = 1e-2
#: A stall is a boundary point when the free Jacobian has rank 2: smallest singular value below RANK_GAP times the
#: middle one (the point cannot move along the normal) and the middle one above RANK_MIN times the largest (a
#: tangent plane, not an edge where only a line is free).
RANK_GAP = 0.05
RANK_MIN = 0.05
#: Boundary voxels whose empty neighbours' mean direction is shorter than this are thin: no ray is cast from them.
MIN_OUTWARD = 0.2
#: Boundary points considered per voxel (nearest to its centre), fill points per axis, and the angle between the
#: two nearest tangent planes above which they are taken as two faces meeting at an edge.
NEAREST_PLANES = 8
FILL_POINTS_PER_AXIS = 4
EDGE_ANGLE_DEG = 30.0
#: At an edge, a boundary point less than EDGE_TOL voxels in front of the other point's plane counts as behind it.
EDGE_TOL = 0.05
#: An empty voxel with this many of its 6 face neighbours occupied is a sampling hole, counted in; each adds
#: HOLE_DOUBT of a voxel to the uncertainty.
HOLE_FACES = 5
HOLE_DOUBT = 0.5
#: Relative floor of the uncertainty: curvature between tangent points and the grid offset leave errors of a few
#: 0.1 % that the other terms do not see (largest error measured at the defaults: 0.4 %, on the UR5).
UNCERTAINTY_FLOOR_REL = 0.005

#: Voxel indices are packed in 21 bits per axis, offset by 2**20.
_BITS = 21
_HALF = 1 << (_BITS - 1)
_MASK = (1 << _BITS) - 1
_OFFSETS = np.array([(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1) if (i, j, k) != (0, 0, 0)])
_UNITS = _OFFSETS / np.linalg.norm(_OFFSETS, axis=1)[:, None]
_SHIFTS = (_OFFSETS[:, 0] << (2 * _BITS)) + (_OFFSETS[:, 1] << _BITS) + _OFFSETS[:, 2]
_SHIFTS27 = np.append(_SHIFTS, 0)


@dataclass(frozen=True)
class WorkspaceVolume:
    """Estimated volume of the tool point's reachable workspace (see the module docstring).

    ``volume``, ``uncertainty``, ``lower`` and ``upper`` are in ``length_unit`` cubed, ``voxel`` (the voxel edge) in
    ``length_unit``. ``lower``/``upper`` bracket the volume by whole voxels (inside ones / every occupied one).
    """

    volume: float
    uncertainty: float
    lower: float
    upper: float
    voxel: float
    n_configurations: int
    length_unit: str

    def to_dict(self) -> dict[str, float | int | str]:
        """Plain JSON-ready values, plus the four volumes in cubic metres (``volume_m3`` ...)."""
        m3 = (mm_per_unit(self.length_unit) / 1000.0) ** 3
        out: dict[str, float | int | str] = {
            "volume": self.volume,
            "uncertainty": self.uncertainty,
            "lower": self.lower,
            "upper": self.upper,
            "voxel": self.voxel,
            "n_configurations": self.n_configurations,
            "length_unit": self.length_unit,
        }
        for key in ("volume", "uncertainty", "lower", "upper"):
            out[f"{key}_m3"] = float(getattr(self, key)) * m3
        return out


def workspace_volume(
    robot: Robot,
    n_configurations: int = 200_000,
    *,
    rng: np.random.Generator | int | None = 0,
    samples_per_voxel: float = DEFAULT_SAMPLES_PER_VOXEL,
    chunk: int = DEFAULT_CHUNK,
) -> WorkspaceVolume:
    """Volume of the positions the tool origin reaches with any orientation, with its uncertainty.

    ``n_configurations`` (``MIN_CONFIGURATIONS`` to ``MAX_CONFIGURATIONS``) are drawn uniformly inside the joint
    limits, ``chunk`` at a time; the rays of the module docstring evaluate further configurations (at most
    ``RAY_STEPS`` per boundary voxel, of which there are a few times ``(n / samples_per_voxel) ** (2/3)``),
    ``chunk`` rays at a time. ``samples_per_voxel`` (``SAMPLES_PER_VOXEL_RANGE``) is lowered for small ``n``, to
    no less than ``SMALL_SAMPLES_PER_VOXEL``, so that there are about ``MIN_VOXELS`` voxels. Memory grows with the
    number of voxels, about ``n / samples_per_voxel``, not with ``n`` (10^6 configurations: about 120 MB at the
    peak). ``rng`` is a Generator or a seed (the default 0 makes the result
    reproducible; None draws a fresh seed). Raises UnknownOptionError for a bad argument and RobotDefinitionError
    for a tool reach (links plus prismatic travel) beyond ``MAX_REACH``.

    >>> from sweepik import load_robot
    >>> w = workspace_volume(load_robot("ur5"), 20_000)
    >>> abs(w.volume - 3.58) < 0.1 and w.lower <= w.volume <= w.upper and w.length_unit == "m"
    True
    """
    if not isinstance(robot, Robot):
        raise UnknownOptionError(f"robot must be a sweepik Robot, got {type(robot).__name__}")
    n = check_int(n_configurations, "n_configurations", MIN_CONFIGURATIONS, MAX_CONFIGURATIONS)
    s = _check_real(samples_per_voxel, "samples_per_voxel", *SAMPLES_PER_VOXEL_RANGE)
    chunk_size = check_int(chunk, "chunk", *CHUNK_RANGE)
    seed_ok = rng is None or isinstance(rng, np.random.Generator | numbers.Integral)
    if not seed_ok or isinstance(rng, bool):
        raise UnknownOptionError(f"rng must be a numpy Generator, an integer seed or None, got {short_repr(rng)}")
    g = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    reach = _reach_bound(robot.chain, robot.lower, robot.upper)
    if not reach <= MAX_REACH:
        raise RobotDefinitionError(
            f"robot {robot.name!r}: the tool reaches up to {reach:g} {robot.length_unit} (links plus prismatic "
            f"travel), beyond the {MAX_REACH:g} a workspace volume is computed for"
        )

    s = min(s, max(SMALL_SAMPLES_PER_VOXEL, n / MIN_VOXELS))
    grid, cells = _sample(robot, n, s, chunk_size, g, reach)
    surf_p, surf_n = _boundary_points(robot, grid, cells, chunk_size, reach)
    volume, lower, upper, err = _estimate(cells, grid, surf_p, surf_n, g)
    coarse, *_ = _estimate(cells.coarsened(), grid.coarsened(), surf_p, surf_n, g)
    return WorkspaceVolume(
        volume=volume,
        uncertainty=err + abs(coarse - volume) + UNCERTAINTY_FLOOR_REL * volume,
        lower=lower,
        upper=upper,
        voxel=grid.h,
        n_configurations=n,
        length_unit=robot.length_unit,
    )


def _sample(
    robot: Robot, n: int, samples: float, chunk: int, rng: np.random.Generator, reach: float
) -> tuple[_Grid, _Cells]:
    """Step 1: ``n`` uniform configurations, ``chunk`` at a time; the first chunk sets the voxel edge."""
    pilot = random_configurations(robot, min(n, chunk), rng)  # RobotDefinitionError for infinite limits
    pilot_p = _tool_positions(robot.chain, pilot)
    h = _voxel_edge(pilot_p, n, samples, reach)
    grid = _Grid(h, pilot_p[0] - h * rng.uniform(0.0, 1.0, 3))
    cells = _Cells(robot.n_joints)
    cells.add(grid.keys(pilot_p), pilot, pilot_p)
    done = len(pilot)
    while done < n:
        q = random_configurations(robot, min(chunk, n - done), rng)
        p = _tool_positions(robot.chain, q)
        cells.add(grid.keys(p), q, p)
        done += len(q)
    cells.flush()
    return grid, cells


def _boundary_points(robot: Robot, grid: _Grid, cells: _Cells, chunk: int, reach: float) -> tuple[Array, Array]:
    """Step 2: rays from the boundary voxels (their points join ``cells``); returns the boundary points and their
    outward normals, inner singular surfaces dropped and sheets given both normals."""
    found_p, found_n = [np.empty((0, 3))], [np.empty((0, 3))]
    for round_ in range(RAY_ROUNDS):
        band, outward = _band(cells.keys)
        todo = band & (np.linalg.norm(outward, axis=1) >= MIN_OUTWARD)
        if round_ > 0:  # only voxels still without a boundary point nearby
            todo &= ~_near(cells.keys, grid.keys(np.concatenate(found_p)))
        seeds, direction = cells.q[todo], outward[todo] / np.linalg.norm(outward[todo], axis=1)[:, None]
        for start in range(0, len(seeds), chunk):
            sel = slice(start, start + chunk)
            path_q, path_p, bp, bn = _cast_rays(
                robot.chain, robot.lower, robot.upper, seeds[sel], direction[sel], grid.h, reach
            )
            cells.add(grid.keys(path_p), path_q, path_p)
            found_p.append(bp)
            found_n.append(bn)
        cells.flush()
    surf_p, surf_n = np.concatenate(found_p), np.concatenate(found_n)
    inner = _member(cells.keys, grid.keys(surf_p + 1.5 * grid.h * surf_n))  # occupied beyond the stall
    surf_p, surf_n = surf_p[~inner], surf_n[~inner]
    sheet = ~_member(cells.keys, grid.keys(surf_p - grid.h * surf_n))  # nothing behind: bounded both ways
    return np.concatenate([surf_p, surf_p[sheet]]), np.concatenate([surf_n, -surf_n[sheet]])


def _check_real(value: object, what: str, lo: float, hi: float) -> float:
    """``value`` as a float in [lo, hi]; bools, strings, NaN and out-of-range numbers are refused."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real) or not lo <= float(value) <= hi:
        raise UnknownOptionError(f"{what} must be a number in [{lo:g}, {hi:g}], got {short_repr(value)}")
    return float(value)


# ------------------------------------------------------------------------------------------------ kinematics
# Positions are taken relative to joint 1's point (translation does not change a volume, and a base far from the
# origin would otherwise cost the voxel indices their precision).


def _tool_positions(chain: Chain, q: Array) -> Array:
    """Tool origins ``(m, 3)`` for ``q (m, n)`` relative to joint 1's point: the zero-configuration tool point moved
    by each joint's screw, last joint first (product of exponentials); a fifth of the cost of ``robot.fk``."""
    ref = chain.points[0]
    tool = chain.points[-1] + chain.P[-1] - ref
    x, y, z = (np.full(len(q), tool[i]) for i in range(3))
    for i in range(chain.n_joints - 1, -1, -1):
        kx, ky, kz = chain.H[i]
        t = q[:, i]
        if chain.revolute[i]:
            cx, cy, cz = chain.points[i] - ref
            vx, vy, vz = x - cx, y - cy, z - cz
            c, s = np.cos(t), np.sin(t)
            kv = (kx * vx + ky * vy + kz * vz) * (1.0 - c)
            x = cx + vx * c + (ky * vz - kz * vy) * s + kx * kv
            y = cy + vy * c + (kz * vx - kx * vz) * s + ky * kv
            z = cz + vz * c + (kx * vy - ky * vx) * s + kz * kv
        else:
            x, y, z = x + kx * t, y + ky * t, z + kz * t
    return np.stack([x, y, z], axis=-1)


def _positions_and_jacobians(chain: Chain, q: Array) -> tuple[Array, Array]:
    """Tool origins ``(m, 3)`` (as :func:`_tool_positions`) and position Jacobians ``(m, 3, n)`` for ``q (m, n)``.

    Forward pass with the rotation kept as ``(3, 3, m)`` (batch last: the small products stay vectorised);
    column i is ``axis_i x (p - point_i)`` for a revolute joint, ``axis_i`` for a prismatic one.
    """
    m, n = q.shape
    ref = chain.points[0]
    R = np.broadcast_to(np.eye(3)[:, :, None], (3, 3, m))
    t = np.zeros((3, m))
    axes, points = np.empty((n, 3, m)), np.empty((n, 3, m))
    for i in range(n):
        k, c = chain.H[i], chain.points[i] - ref
        axes[i] = np.einsum("ijm,j->im", R, k)
        points[i] = np.einsum("ijm,j->im", R, c) + t
        if chain.revolute[i]:
            K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
            s, co = np.sin(q[:, i]), 1.0 - np.cos(q[:, i])
            rot = np.eye(3)[:, :, None] + K[:, :, None] * s + (K @ K)[:, :, None] * co
            t = t - np.einsum("ijm,j->im", R, K @ c) * s - np.einsum("ijm,j->im", R, K @ K @ c) * co
            R = np.einsum("ijm,jkm->ikm", R, rot)
        else:
            t = t + axes[i] * q[:, i]
    p = np.einsum("ijm,j->im", R, chain.points[-1] + chain.P[-1] - ref) + t
    J = np.where(chain.revolute[:, None, None], np.cross(axes, p - points, axis=1), axes)
    return p.T.copy(), np.ascontiguousarray(J.transpose(2, 1, 0))


def _reach_bound(chain: Chain, lo: Array, hi: Array) -> float:
    """A radius around joint 1's point holding every tool position: the links plus the prismatic travel."""
    travel = np.where(chain.revolute, 0.0, np.maximum(np.abs(lo), np.abs(hi)))
    return float(np.sum(np.linalg.norm(chain.P[1:], axis=1)) + np.sum(travel))


def _cast_rays(
    chain: Chain, lo: Array, hi: Array, q0: Array, d: Array, h: float, reach: float
) -> tuple[Array, Array, Array, Array]:
    """Drive the tool point from ``q0 (m, n)`` along unit directions ``d (m, 3)`` until it stalls (see the module
    docstring): returns the configurations and positions visited, and the boundary points with their normals.

    Jacobian columns are weighted by a joint's typical motion (1 rad; a prismatic joint's travel, at most
    ``reach``) so that revolute and prismatic joints compare in length units.
    """
    span = hi - lo
    weight = np.where(chain.revolute, np.minimum(span, 1.0), np.minimum(span, reach))
    max_dq = np.where(chain.revolute, np.minimum(0.1 * span, 0.5), 0.1 * span)
    q = q0.copy()
    p, J = _positions_and_jacobians(chain, q)
    step = np.full(len(q), h)
    run = np.arange(len(q))  # rays still moving
    visited_q, visited_p = [], []
    for _ in range(RAY_STEPS):
        qr, dr, sr = q[run], d[run], step[run]
        Jf = _free_jacobian(J[run], qr, dr, lo, hi) * weight
        A = Jf @ np.swapaxes(Jf, 1, 2)
        damping = 1e-6 * np.trace(A, axis1=1, axis2=2) + 1e-12 * h * h
        x = np.linalg.solve(A + damping[:, None, None] * np.eye(3), (sr[:, None] * dr)[..., None])[..., 0]
        dq = np.einsum("mij,mi->mj", Jf, x) * weight
        with np.errstate(divide="ignore", invalid="ignore"):  # joints that do not move (locked, held) set no bound
            scale = np.minimum(1.0, np.min(np.where(dq != 0.0, max_dq / np.abs(dq), np.inf), axis=1))
        q_new = np.clip(qr + dq * scale[:, None], lo, hi)
        p_new, J_new = _positions_and_jacobians(chain, q_new)
        visited_q.append(q_new)  # inside the limits: reachable whether or not the ray advanced
        visited_p.append(p_new)
        ok = np.einsum("mi,mi->m", p_new - p[run], dr) > 0.1 * sr
        q[run[ok]], p[run[ok]], J[run[ok]] = q_new[ok], p_new[ok], J_new[ok]
        step[run] = np.where(ok, np.minimum(2.0 * sr, h), 0.2 * sr)
        run = run[step[run] > RAY_STALL * h]
        if not len(run):
            break
    stalled = np.ones(len(q), dtype=bool)
    stalled[run] = False
    Jf = _free_jacobian(J, q, d, lo, hi) * weight
    w, V = np.linalg.eigh(Jf @ np.swapaxes(Jf, 1, 2))  # ascending squared singular values
    normal = V[:, :, 0] * np.where(np.einsum("mi,mi->m", V[:, :, 0], d) < 0.0, -1.0, 1.0)[:, None]
    boundary = stalled & (w[:, 0] < RANK_GAP**2 * w[:, 1]) & (w[:, 1] > RANK_MIN**2 * w[:, 2])
    boundary &= np.einsum("mi,mi->m", normal, d) > 0.05
    return np.concatenate(visited_q), np.concatenate(visited_p), p[boundary], normal[boundary]


def _free_jacobian(J: Array, q: Array, d: Array, lo: Array, hi: Array) -> Array:
    """``J`` with the columns of joints held at a limit (moving them along ``d`` would cross it) set to zero."""
    g = np.einsum("mij,mi->mj", J, d)
    held = ((q <= lo) & (g < 0.0)) | ((q >= hi) & (g > 0.0))
    return np.where(held[:, None, :], 0.0, J)


# ------------------------------------------------------------------------------------------------ voxels


class _Grid:
    """Voxels of edge ``h``: voxel (i, j, k) spans ``origin + h * ([i, i+1) x [j, j+1) x [k, k+1))``."""

    def __init__(self, h: float, origin: Array) -> None:
        self.h, self.origin = h, origin

    def keys(self, p: Array) -> IntArray:
        return _pack(np.floor((p - self.origin) / self.h).astype(np.int64))

    def corners(self, keys: IntArray) -> Array:
        return np.asarray(_unpack(keys) * self.h + self.origin, dtype=np.float64)

    def coarsened(self) -> _Grid:
        return _Grid(2.0 * self.h, self.origin)


def _pack(idx: IntArray) -> IntArray:
    u = idx + _HALF
    return np.asarray((u[:, 0] << (2 * _BITS)) | (u[:, 1] << _BITS) | u[:, 2], dtype=np.int64)


def _unpack(keys: IntArray) -> IntArray:
    return np.stack([(keys >> (2 * _BITS)) & _MASK, (keys >> _BITS) & _MASK, keys & _MASK], axis=-1) - _HALF


def _voxel_edge(p: Array, n: int, samples: float, reach: float) -> float:
    """Voxel edge for ``n`` samples, from pilot positions ``p``: occupied voxels get about ``samples`` each.

    The pilot's volume is estimated at its own density (inside voxels plus half the boundary ones) and the edge
    scaled to ``n``; never below the edge that keeps voxel indices within 2**20 of the pilot's first point.
    """
    extent = np.ptp(p, axis=0)
    scale = float(extent.max())
    floor = 4.0 * max(reach, scale, 1e-300) / _HALF
    if scale <= 1e-12 * max(reach, 1e-300):  # a single point: any voxel will do
        return max(1e-3 * reach, floor)
    h = float((np.prod(np.maximum(extent, 1e-3 * scale)) * samples / len(p)) ** (1.0 / 3.0))
    volume = 0.0
    for _ in range(4):
        keys = np.unique(_pack(np.floor((p - p[0]) / h).astype(np.int64)))
        band, _ = _band(keys)
        volume = (len(keys) - 0.5 * float(band.sum())) * h**3
        h = float((samples * volume / len(p)) ** (1.0 / 3.0))
    return max(float((samples * volume / n) ** (1.0 / 3.0)), floor)


class _Cells:
    """Occupied voxels: sorted ``keys``, sample ``counts``, one configuration ``q`` and position ``p`` per voxel (to
    cast rays from), and the bounding box of each voxel's samples (for voxels no ray reached).

    ``add`` queues; ``flush`` merges the queue into the table (also done whenever the queue outgrows the table, so
    the cost stays proportional to the number of voxels times a logarithm, not to the number of chunks).
    """

    def __init__(self, n_joints: int) -> None:
        self.keys = np.empty(0, dtype=np.int64)
        self.counts = np.empty(0, dtype=np.int64)
        self.q = np.empty((0, n_joints))
        self.p = np.empty((0, 3))
        self.box_lo = np.empty((0, 3))
        self.box_hi = np.empty((0, 3))
        self._queue: list[tuple[IntArray, IntArray, Array, Array, Array, Array]] = []
        self._queued = 0

    def add(self, keys: IntArray, q: Array, p: Array) -> None:
        if not len(keys):
            return
        order = np.argsort(keys, kind="stable")
        keys, q, p = keys[order], q[order], p[order]
        uk, first, counts = np.unique(keys, return_index=True, return_counts=True)
        lo, hi = np.minimum.reduceat(p, first, axis=0), np.maximum.reduceat(p, first, axis=0)
        self._queue.append((uk, counts, q[first], p[first], lo, hi))
        self._queued += len(uk)
        if self._queued > max(len(self.keys), 1 << 18):
            self.flush()

    def flush(self) -> None:
        if not self._queue:
            return
        parts = [(self.keys, self.counts, self.q, self.p, self.box_lo, self.box_hi), *self._queue]
        keys, counts, q, p, lo, hi = (np.concatenate(column) for column in zip(*parts, strict=True))
        self._queue, self._queued = [], 0
        order = np.argsort(keys, kind="stable")  # earlier voxels first: they keep their configuration
        uk, first = np.unique(keys[order], return_index=True)
        self.keys = uk
        self.counts = np.add.reduceat(counts[order], first)
        self.q, self.p = q[order][first], p[order][first]
        self.box_lo = np.minimum.reduceat(lo[order], first, axis=0)
        self.box_hi = np.maximum.reduceat(hi[order], first, axis=0)

    def coarsened(self) -> _Cells:
        """The same samples in voxels twice as large (same grid origin)."""
        out = _Cells(self.q.shape[1])
        out._queue = [(_pack(_unpack(self.keys) // 2), self.counts, self.q, self.p, self.box_lo, self.box_hi)]
        out.flush()
        return out


def _member(keys: IntArray, query: IntArray) -> BoolArray:
    if not len(keys):
        return np.zeros(len(query), dtype=bool)
    pos = np.minimum(np.searchsorted(keys, query), len(keys) - 1)
    return np.asarray(keys[pos] == query)


def _band(keys: IntArray) -> tuple[BoolArray, Array]:
    """Boundary voxels (an empty one among the 26 neighbours) and the mean direction of their empty neighbours."""
    outward = np.zeros((len(keys), 3))
    n_empty = np.zeros(len(keys), dtype=np.int64)
    for shift, unit in zip(_SHIFTS, _UNITS, strict=True):
        empty = ~_member(keys, keys + shift)
        outward += empty[:, None] * unit
        n_empty += empty
    band = n_empty > 0
    outward[band] /= n_empty[band, None]
    return band, outward


def _near(keys: IntArray, point_keys: IntArray) -> BoolArray:
    """Voxels ``keys`` with a point (voxel ``point_keys``) in their 3x3x3 neighbourhood."""
    pk = np.unique(point_keys)
    out = np.zeros(len(keys), dtype=bool)
    for shift in _SHIFTS27:
        out |= _member(pk, keys + shift)
    return out


# ------------------------------------------------------------------------------------------------ fill


def _estimate(
    cells: _Cells, grid: _Grid, surf_p: Array, surf_n: Array, rng: np.random.Generator
) -> tuple[float, float, float, float]:
    """``(volume, lower, upper, error)`` on ``grid``: inside voxels whole, boundary voxels by their fill."""
    v = grid.h**3
    holes = _holes(cells.keys)
    keys = np.concatenate([cells.keys, holes])
    box = np.concatenate(
        [np.prod(np.clip((cells.box_hi - cells.box_lo) / grid.h, 0.0, 1.0), axis=1), np.ones(len(holes))]
    )
    order = np.argsort(keys)
    keys, box = keys[order], box[order]
    band, _ = _band(keys)
    fill, alt, has = _fill(keys[band], grid, surf_p, surf_n, rng)
    guess = np.minimum(0.5, box[band])
    fill = np.where(has, fill, guess)
    lower = float((~band).sum()) * v
    volume = lower + float(fill.sum()) * v
    err = float(guess[~has].sum() + 0.5 * np.abs(alt - fill)[has].sum() + HOLE_DOUBT * len(holes)) * v
    err += math.sqrt(float(np.sum(fill * (1.0 - fill))) / FILL_POINTS_PER_AXIS**3) * v
    return volume, lower, len(keys) * v, err


def _holes(keys: IntArray) -> IntArray:
    """Empty voxels with at least ``HOLE_FACES`` of their 6 face neighbours occupied (or found holes), the gaps
    uniform sampling leaves where the density is low; a voxel outside the workspace has at most 4 (in a groove
    one voxel wide)."""
    faces = [shift for shift, o in zip(_SHIFTS, _OFFSETS, strict=True) if np.abs(o).sum() == 1]
    found = np.empty(0, dtype=np.int64)
    for _ in range(2):  # a second pass fills pairs of adjacent holes
        occupied = np.union1d(keys, found)
        cand = np.setdiff1d(np.concatenate([occupied + f for f in faces]), occupied)
        count = sum((_member(occupied, cand + f).astype(np.int64) for f in faces), np.zeros(len(cand), np.int64))
        found = np.union1d(found, cand[count >= HOLE_FACES])
    return found


def _nearest_points(bk: IntArray, grid: _Grid, sp: Array) -> IntArray:
    """``(len(bk), NEAREST_PLANES)``: indices of the boundary points ``sp`` in each voxel's 3x3x3 neighbourhood,
    nearest to its centre first, -1 where there are fewer."""
    sk = grid.keys(sp)
    order = np.argsort(sk, kind="stable")
    uk, start, count = np.unique(sk[order], return_index=True, return_counts=True)
    cell_of, point_of = [], []
    for shift in _SHIFTS27:
        query = bk + shift
        pos = np.minimum(np.searchsorted(uk, query), len(uk) - 1)
        hit = np.flatnonzero(uk[pos] == query)
        c = count[pos[hit]]
        cell_of.append(np.repeat(hit, c))
        point_of.append(order[np.repeat(start[pos[hit]] - np.cumsum(c) + c, c) + np.arange(c.sum())])
    cell, point = np.concatenate(cell_of), np.concatenate(point_of)
    dist = np.sum((sp[point] - grid.corners(bk)[cell] - 0.5 * grid.h) ** 2, axis=1)
    order = np.lexsort((dist, cell))
    cell, point = cell[order], point[order]
    rank = np.arange(len(cell)) - np.searchsorted(cell, cell)
    keep = rank < NEAREST_PLANES
    out = np.full((len(bk), NEAREST_PLANES), -1, dtype=np.int64)
    out[cell[keep], rank[keep]] = point[keep]
    return out


def _fill(
    bk: IntArray, grid: _Grid, sp: Array, sn: Array, rng: np.random.Generator, block: int = 2048
) -> tuple[Array, Array, BoolArray]:
    """Inside fraction of each voxel ``bk`` by the tangent planes of the nearest boundary points (``fill``, see the
    module docstring), the same by the second-nearest plane alone (``alt``, for the uncertainty), and whether any
    boundary point was near (``has``)."""
    nb = len(bk)
    fill, alt = np.zeros(nb), np.zeros(nb)
    if not len(sp) or not nb:
        return fill, alt, np.zeros(nb, dtype=bool)
    cand = _nearest_points(bk, grid, sp)
    m = FILL_POINTS_PER_AXIS
    strata = np.stack(np.meshgrid(*(np.arange(m),) * 3, indexing="ij"), axis=-1).reshape(-1, 3)
    corners = grid.corners(bk)
    s_n, s_sq = np.einsum("pi,pi->p", sp, sn), np.einsum("pi,pi->p", sp, sp)
    cos_edge = math.cos(math.radians(EDGE_ANGLE_DEG))
    for b0 in range(0, nb, block):
        c = cand[b0 : b0 + block]
        x = corners[b0 : b0 + block, None, :] + grid.h * (strata + rng.uniform(0.0, 1.0, (len(c), len(strata), 3))) / m
        d2 = np.where(c[:, None, :] >= 0, s_sq[c][:, None, :] - 2.0 * np.einsum("bli,bki->blk", x, sp[c]), np.inf)
        behind = np.einsum("bli,bki->blk", x, sn[c]) <= s_n[c][:, None, :]
        k1 = np.argmin(d2, axis=2)[..., None]
        np.put_along_axis(d2, k1, np.inf, axis=2)
        k2 = np.argmin(d2, axis=2)[..., None]
        two = np.isfinite(np.take_along_axis(d2, k2, axis=2)[..., 0])
        k2 = np.where(two[..., None], k2, k1)
        in1 = np.take_along_axis(behind, k1, axis=2)[..., 0]
        in2 = np.take_along_axis(behind, k2, axis=2)[..., 0]
        i1, i2 = (
            np.take_along_axis(c[:, None, :], k1, axis=2)[..., 0],
            np.take_along_axis(c[:, None, :], k2, axis=2)[..., 0],
        )
        edge = np.einsum("bli,bli->bl", sn[i1], sn[i2]) < cos_edge
        tol = EDGE_TOL * grid.h  # a point on the other's plane (a sheet seen from both sides) counts as behind it
        a = np.einsum("bli,bli->bl", sn[i1], sp[i2] - sp[i1]) <= tol  # the second point behind the first plane
        b = np.einsum("bli,bli->bl", sn[i2], sp[i1] - sp[i2]) <= tol
        inside = np.where(edge & a & b, in1 & in2, np.where(edge & ~a & ~b, in1 | in2, in1))
        fill[b0 : b0 + block] = inside.mean(axis=1)
        alt[b0 : b0 + block] = in2.mean(axis=1)
    return fill, alt, cand[:, 0] >= 0
