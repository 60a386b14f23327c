"""``GeometricReduction``: a reduction derived from the arm's geometry, run by the generic compiled engine.

It holds a :class:`Plan` (which family, which joint is theta*, which position case, forward or reversed chain)
and turns chain poses into the family's parameter rows (``geometric.LAYOUT``). Nothing in it is specific to an
arm: :mod:`.decompose` finds the plans of a robot.
"""

from __future__ import annotations

from functools import cached_property
from typing import Any

import numpy as np
from numpy.typing import NDArray

from sweepik.engine import parallel
from sweepik.engine.settings import N_SAMPLES, PARALLEL_MIN
from sweepik.model.chain import Chain
from sweepik.model.robot import Robot
from sweepik.reductions import decoupled, geometric
from sweepik.reductions.base import Array, EdgeSearch, IntArray, Reduction
from sweepik.reductions.plan import Plan, plans
from sweepik.reductions.position import CASES, FINAL_JOINTS, STEP_JOINTS

#: A candidate where a step's amplitude (``amplitude`` of ``geometric.case_kernels``) is below this fraction of the
#: step's typical amplitude leaves that step's joint free (``continuum_joints``): the tracer follows it where it can
#: (a numerical continuum) and gives nothing where it cannot. On the C-Arm's theta2 self-motion the first step's
#: amplitude is 1e-12 to 1e-8 mm at the candidates, against 30 to 700 mm at random poses; carm_swapped with its elbow
#: folded 1e-7 rad short of its self-motion holds stretches of numerical continuum along theta2 whose candidates'
#: amplitudes lie above 1e-7 (with that threshold, 3 of 40 such configurations came back as none of 8 isolated
#: solutions, each 0.002 to 0.1 rad away).
CONTINUUM_AMPLITUDE = 1e-5

#: Twin branches: residuals compared at this many random poses and theta* values, equal to this (absolute; the
#: residual is a difference of cosines).
TWIN_POSES = 12
TWIN_SAMPLES = 24
TWIN_TOL = 1e-12


def _chain_rows(chain: Chain) -> Array:
    row = np.zeros(geometric.N_PARAMS)
    L = geometric.LAYOUT
    row[L["H"] : L["H"] + 18] = chain.H.reshape(-1)
    row[L["P"] : L["P"] + 21] = chain.P.reshape(-1)
    row[L["rev"] : L["rev"] + 6] = chain.revolute
    return row


class GeometricReduction(Reduction):
    """A reduction from a :class:`Plan`: the family's compiled kernels over the generic parameter row."""

    #: Set per instance (the family's pair, its all-branch residual or configurations); declared here so that
    #: ``uses_kernel`` and the engine see this class as their owner.
    kernel: tuple[Any, Any] | None = None
    kernel_residuals: Any = None
    kernel_configurations: Any = None

    def __init__(self, robot: Robot, plan: Plan) -> None:
        super().__init__(robot, plan.free_joint, plan.branches)
        self.plan = plan
        self._margins_key = _PlanKey()  # (see _Margins)
        self.name = f"{plan.family}-{robot.joint_names[plan.free_joint]}" if plan.family == "pair" else "closed-form"
        self.closed_form = plan.closed_form
        chain = robot.chain.reversed() if plan.reversed else robot.chain
        self._chain = chain
        L = geometric.LAYOUT
        row = _chain_rows(chain)
        row[L["W"] : L["W"] + 3] = plan.W
        row[L["O"] : L["O"] + 3] = plan.meet
        row[L["free"]] = plan.free
        row[L["case"]] = CASES.index(plan.case) if plan.case in CASES else -1
        row[L["reversed"]] = float(plan.reversed)
        row[L["pos_branches"]] = plan.branches // 2 if plan.closed_form else plan.branches
        row[L["need"]] = 3.0  # (both first-step branches, every step: see _params)
        row[L["need_margin"]] = 7.0
        row[L["need_amplitude"]] = 7.0
        self._row = row
        self._last_params: tuple[Array, Array] | None = None
        self._last_range: tuple[Array, Array] | None = None
        self._last_singular: tuple[Array, NDArray[np.bool_], NDArray[np.bool_]] | None = None
        # the wrist centre in the tool frame (the last joints do not move it)
        p_end = chain.P.sum(axis=0)
        self._w_tool = chain.R_end.T @ (np.asarray(plan.W) - p_end)
        # the pair and wrist families' kernels are made for the arm's position case (geometric.case_kernels)
        self._case = (
            None
            if plan.family in ("parallel", "decoupled")
            else geometric.case_kernels(int(row[L["case"]]), plan.free, tuple(bool(r) for r in chain.revolute[:4]))
        )
        self._kernels: tuple[Any, Any]
        if plan.family == "parallel":
            self._kernels = (geometric.wrist_residual, geometric.parallel_configuration)
            self.kernel_configurations = geometric.parallel_configurations
        elif plan.family == "decoupled":
            self._kernels = (geometric.wrist_residual, decoupled.configuration)
            self.kernel_configurations = decoupled.configurations
        elif plan.family == "pair":
            self._kernels = (self._case_kernels.pair_residual, self._case_kernels.pair_configuration)
            self.kernel_residuals = self._case_kernels.pair_residuals
        else:
            assert plan.family == "wrist", plan.family
            self._kernels = (geometric.wrist_residual, self._case_kernels.wrist_configuration)
            self.kernel_configurations = self._case_kernels.wrist_configurations
        self.kernel = self._kernels

    @cached_property
    def twins(self) -> tuple[tuple[int, ...], ...]:  # type: ignore[override]
        """Classes of branches with identical residuals (probed; none for a closed form). Found when first asked
        for, not when the reduction is made: a closed form's fallback is made for every batch, and probing it
        compiles the pair family's kernels (seconds on a fresh install) that only degenerate poses need."""
        if self.plan.closed_form:
            return ()
        return tuple(tuple(c) for c in _classes(self._probe(self._kernels[0], self.n_branches)) if len(c) > 1)

    @property
    def _case_kernels(self) -> geometric.CaseKernels:
        """The kernels of the arm's position case (the pair and wrist families)."""
        assert self._case is not None, "the parallel family has no position case"
        return self._case

    def _probe(self, fn: Any, count: int) -> Array:
        """``fn(params, theta*, k)`` for k < count at random poses and theta* values: ``(poses, samples, count)``."""
        robot = self.robot
        rng = np.random.default_rng(0)
        lo = np.where(robot.is_revolute, np.maximum(robot.lower, -np.pi), robot.lower)
        hi = np.where(robot.is_revolute, np.minimum(robot.upper, np.pi), robot.upper)
        # (limits that lie outside (-pi, pi) altogether, e.g. [200, 300] deg: the range as given)
        lo, hi = np.where(hi > lo, lo, robot.lower), np.where(hi > lo, hi, robot.upper)
        q = rng.uniform(lo, hi, size=(TWIN_POSES, robot.n_joints))
        params = self._params(robot.T_base_world @ robot.fk(q) @ robot.T_tool_flange, probing=True)
        j = self.free_joint
        a, b = (-np.pi, np.pi) if self.periodic else (float(robot.lower[j]), float(robot.upper[j]))
        if not b - a < 1e6 * robot.length_scale:  # no practical end: around the arm
            a, b = -robot.length_scale, robot.length_scale
        x = rng.uniform(a, b, size=TWIN_SAMPLES)
        pose = np.repeat(np.arange(TWIN_POSES), TWIN_SAMPLES * count).astype(np.int64)
        th = np.tile(np.repeat(x, count), TWIN_POSES)
        k = np.tile(np.arange(count), TWIN_POSES * TWIN_SAMPLES).astype(np.int64)
        out = np.empty(pose.size)
        geometric.evaluate(fn, params, pose, th, k, out)
        return out.reshape(TWIN_POSES, TWIN_SAMPLES, count)

    @cached_property
    def _steps(self) -> tuple[list[int], list[int]]:
        """The margins and the amplitudes (``pair_margin``, ``amplitude`` of ``geometric.case_kernels``: k = 0, 1, 2;
        then the final step's gaps, k = 3 ... 6) worth sweeping: not constant (a step with one solution, or a circle
        that always meets its plane; no final step, or a slide) and not the twin of an earlier one."""
        m = self._probe(self._case_kernels.pair_margin, 3)
        a = self._probe(self._case_kernels.amplitude, 7)
        margins = [c[0] for c in _classes(m) if not np.all(m[..., c[0]] == 1.0)]
        steps = [c[0] for c in _classes(a[..., :3]) if not np.all(np.isinf(a[..., c[0]]))]
        gaps = [3 + c[0] for c in _classes(a[..., 3:]) if np.isfinite(a[..., 3 + c[0]]).any()]
        return margins, steps + gaps

    @cached_property
    def _step_scales(self) -> Array:
        """The typical amplitude of each step ``k = 0, 1, 2`` (as ``amplitude`` numbers them), then the final step's
        gap (``amplitude``'s k = 3 .. 6, the position branches): each its median over random poses and theta* values;
        inf for a step with one solution, or no final step."""
        a = np.abs(self._probe(self._case_kernels.amplitude, 7)).reshape(-1, 7)
        cols = [a[:, 0], a[:, 1], a[:, 2], a[:, 3:].ravel()]
        return np.array([np.median(c[np.isfinite(c)]) if np.isfinite(c).any() else np.inf for c in cols])

    @cached_property
    def _step_joints(self) -> tuple[int, int, int]:
        """The robot joints that the position case's first and second two-solution steps turn, and the one its final
        step turns (``FINAL_JOINTS``); -1: no such step."""
        others = [i for i in range(4) if i != self.plan.free]
        letters = (*STEP_JOINTS[self.plan.case], FINAL_JOINTS[self.plan.case])
        return tuple(-1 if x is None else self.plan.joint(others["abc".index(x)]) for x in letters)  # type: ignore[return-value]

    @cached_property
    def _continuum_thresholds(self) -> Array:
        """Below these amplitudes (steps ``k = 0, 1, 2``, then the final step's gap) a step leaves its joint free
        (``CONTINUUM_AMPLITUDE``)."""
        return np.ascontiguousarray(CONTINUUM_AMPLITUDE * self._step_scales)

    @cached_property
    def _continuum_args(self) -> tuple[int, int, Array, NDArray[np.int64]]:
        """``geometric.continuum_rows``'s arguments that do not change: the amplitude kernel's address, the branches
        per position branch (2 for the wrist family), the thresholds, the steps' joints."""
        from sweepik.reductions.kernels import RESIDUAL_SIG, address_of

        address = address_of(self._case_kernels.amplitude, RESIDUAL_SIG)
        joints = np.array(self._step_joints, dtype=np.int64)
        return address, 2 if self.plan.closed_form else 1, self._continuum_thresholds, joints

    def continuum_kernel(self) -> tuple[int, int, Array, NDArray[np.int64]] | None:
        """The swept pair and wrist families' ``_continuum_args`` (a closed form sweeps nothing; the parallel family's
        steps have no amplitudes)."""
        return None if self._case is None or self.plan.closed_form else self._continuum_args

    def singular_kernel(self) -> tuple[int, Array] | None:
        """A closed form's ``_singular`` kernel (the wrist singular: ``degenerate``; a step's amplitude low: where
        ``continuum_joints`` may flag a branch) and its thresholds; None for a sweep."""
        if not self.plan.closed_form:
            return None
        from sweepik.reductions.kernels import SINGULAR_SIG, address_of

        if self.plan.family == "parallel":
            return address_of(geometric.parallel_singular_flags, SINGULAR_SIG), np.zeros(4)
        if self.plan.family == "decoupled":
            return address_of(decoupled.singular_flags, SINGULAR_SIG), np.zeros(4)
        return address_of(self._case_kernels.wrist_singular, SINGULAR_SIG), self._continuum_thresholds

    def continuum_joints(
        self, poses: Array, pose: IntArray, theta: Array, branch: IntArray, error: Array | None = None, tol: float = 0.0
    ) -> IntArray | None:
        """The pair and wrist families: a candidate where a position step's amplitude vanishes (its equation no longer
        involves its joint, ``CONTINUUM_AMPLITUDE``) gives that step's joint; the first step's before the second's.
        None when no candidate does (almost always). (The wrist family's continua where its wrist is singular are its
        fallback's, ``degenerate``.)"""
        if self.plan.family == "decoupled" and pose.size:
            return self._decoupled_continua(poses, pose, branch, error, tol)
        if self._case is None or pose.size == 0:  # (the parallel family: its steps have no amplitudes)
            return None
        if self.plan.closed_form and not self._singular(poses)[1].any():  # (a pose's amplitudes: theta* moves nothing)
            return None
        # (writable arrays of the kernel's types: copies only where the candidates' are not)
        p, b = (a if a.dtype == np.int64 and a.flags.writeable else np.array(a, dtype=np.int64) for a in (pose, branch))
        th = theta if theta.flags.writeable else np.array(theta)
        err = np.zeros(pose.size) if error is None else error if error.flags.writeable else np.array(error)
        address, div, thr, joints = self._continuum_args
        out, params = np.empty(pose.size, dtype=np.int64), self.kernel_params(poses)
        flagged = geometric.continuum_rows(address, params, p, th, b, err, tol, div, thr, joints, out)
        return out.astype(np.intp) if flagged else None

    @cached_property
    def _continua(self) -> GeometricReduction | None:
        """For a closed form: a pair plan sweeping a joint that moves along the continuum of a singular wrist (joint
        4 preferred, then joint 6; for the parallel family also joints 2, 3), which solves the poses at or near it
        and reports the continuum as a family (the closed form would give one member, and near it loses digits).
        None when the arm has no such plan (the slide-first parallel arm with an offset wrist)."""
        if not self.plan.closed_form:
            return None
        moving = [3, 5] + ([1, 2] if self.plan.family == "parallel" else [])
        pairs = [p for p in plans(self.robot) if p.family == "pair" and not p.conditional]
        for j in moving:
            for p in pairs:
                if p.free_joint == self.plan.joint(j):
                    return GeometricReduction(self.robot, p)
        return None

    @cached_property
    def _shoulder_continua(self) -> GeometricReduction | None:
        """For the parallel family: a pair plan sweeping joint 6, then 1 (each turns whole turns along the continuum
        where joint 6's point lies on joint 1's axis, ``geometric.parallel_shoulder``; joint 4 barely moves along it,
        and a sweep of joint 4 places that point with joint 1, which it leaves free). None without one."""
        if not self.plan.closed_form or self.plan.family != "parallel":
            return None
        pairs = [p for p in plans(self.robot) if p.family == "pair" and not p.conditional]
        for j in (5, 0):
            for p in pairs:
                if p.free_joint == self.plan.joint(j):
                    return GeometricReduction(self.robot, p)
        return None

    @property
    def fallback(self) -> Reduction | None:  # type: ignore[override]
        return self._continua

    def degenerate_fallbacks(self, poses: Array) -> list[tuple[str | Reduction, NDArray[np.bool_]]]:
        """The parallel family's degenerate poses whose joint 1 turns freely go to ``_shoulder_continua``, the others
        (and every family's) to ``fallback``."""
        out = super().degenerate_fallbacks(poses)
        shoulder = self._shoulder_continua
        if not out or shoulder is None:
            return out

        by, deg = out[0]
        free = np.zeros(poses.shape[0], dtype=np.bool_)
        parallel.run(geometric.parallel_shoulder, poses.shape[0], 2 * PARALLEL_MIN, self.kernel_params(poses), free)
        free &= deg
        if not free.any():
            return out
        return [(by, deg & ~free), (shoulder, free)] if (deg & ~free).any() else [(shoulder, free)]

    def _decoupled_continua(
        self, poses: Array, pose: IntArray, branch: IntArray, error: Array | None, tol: float
    ) -> IntArray | None:
        """``continuum_joints`` of the decoupled family: joint a where the orientation is singular (joint a turns with
        joint c); where the slides are dependent, the slide moving most along their null direction (the arm's
        Jacobian's slide columns at the candidate)."""
        singular, dependent = self._singular(poses)
        orient, slides = singular[pose], dependent[pose]
        if error is not None:
            orient, slides = orient & (error <= tol), slides & (error <= tol)
        if not (orient.any() or slides.any()):
            return None
        out = np.where(orient, self.plan.joint(self._decoupled_first), -1).astype(np.intp)
        rows = np.flatnonzero(slides & ~orient)
        if rows.size:
            zero = np.zeros((rows.size, 1))
            q = self.solve_rest(poses[pose[rows]], zero, np.asarray(branch)[rows][:, None])[:, 0]
            ok = np.all(np.isfinite(q), axis=-1)
            rows, q = rows[ok], q[ok]
            slide = np.flatnonzero(~self.robot.is_revolute)
            J = self.robot.jacobian(q)[:, :3, slide]  # (the slides' directions, columns)
            null = np.linalg.svd(J)[2][:, -1, :]
            out[rows] = slide[np.argmax(np.abs(null), axis=1)]
        return out if (out >= 0).any() else None

    @cached_property
    def _decoupled_first(self) -> int:
        """The decoupled family's first revolute joint (in the solved chain's order)."""
        return int(np.flatnonzero(self._chain.revolute)[0])

    def degenerate(self, poses: Array) -> NDArray[np.bool_] | None:
        """Closed form: poses where a branch's wrist is singular or nearly so (``geometric.WRIST_SINGULAR``): the
        solver answers them with the fallback sweep (the decoupled family has none: ``continuum_joints``)."""
        if not self.plan.closed_form or poses.shape[0] == 0 or self.plan.family == "decoupled":
            return None
        return self._singular(poses)[0]

    def _singular(self, poses: Array) -> tuple[NDArray[np.bool_], NDArray[np.bool_]]:
        """A closed form's ``degenerate`` poses and, computed in the same pass (the wrist family), those where a step
        of the position case leaves its joint free (``continuum_joints``). The last chunk's are kept: the solver asks
        for both."""
        last = self._last_singular
        if last is not None and last[0] is poses:
            return last[1], last[2]

        N = poses.shape[0]
        out, low = np.zeros(N, dtype=np.bool_), np.zeros(N, dtype=np.bool_)
        params = self.kernel_params(poses)
        if self.plan.family == "parallel":
            parallel.run(geometric.parallel_singular, N, 2 * PARALLEL_MIN, params, out)
        elif self.plan.family == "decoupled":
            parallel.run(decoupled.singular_flags, N, 2 * PARALLEL_MIN, params, np.zeros(4), out, low)
        else:
            singular = self._case_kernels.wrist_singular
            parallel.run(singular, N, 2 * PARALLEL_MIN, params, self._continuum_thresholds, out, low)
        self._last_singular = (poses, out, low)
        return out, low

    def search_range(self, poses: Array) -> Array | None:
        """A prismatic theta*: the travel that can hold a solution, joint limits aside, ``(N, 2)``: the wrist centre
        W lies within R (the lengths of the segments from the slide to W, summed, plus the travel of any other slide
        among them, as far as its limits reach) of the point the slide moves,
        so along a first joint's fixed direction h: ``h . (t - P0) +- R``; deeper in the chain (its direction
        turns with the joints before it) ``|x| <= |t - P0| + R``. The solver sweeps this interval with and without
        limits, so that ``limits=False`` keeps (and flags) solutions beyond the limits."""
        if self.periodic or self.closed_form:
            return None
        last = self._last_range
        if last is not None and last[0] is poses:  # (asked for by the solver and again by the hints)
            return last[1]
        out = self._search_range(poses)
        out.setflags(write=False)
        self._last_range = (poses, out)
        return out

    @cached_property
    def _reach(self) -> float:
        """R of ``search_range``."""
        chain, f = self._chain, self.plan.free
        o3 = chain.P[:4].sum(axis=0)
        R = float(np.linalg.norm(chain.P[1:4], axis=1).sum() + np.linalg.norm(np.asarray(self.plan.W) - o3))
        # the other slides among the first four joints lengthen the chain by up to their travel (Stanford's d3)
        n = self.robot.n_joints
        for j in range(4):
            k = n - 1 - j if self.plan.reversed else j
            if j != f and not chain.revolute[j]:
                R += max(abs(float(self.robot.lower[k])), abs(float(self.robot.upper[k])))
        return R

    def _search_range(self, poses: Array) -> Array:
        chain, R = self._chain, self._reach
        L = geometric.LAYOUT
        t = self.kernel_params(poses)[:, L["t"] : L["t"] + 3] - chain.P[0]
        out = np.empty((poses.shape[0], 2))
        if self.plan.free == 0:
            mid = t @ chain.H[0]
            out[:, 0], out[:, 1] = mid - R, mid + R
        else:
            reach = np.linalg.norm(t, axis=1) + R
            out[:, 0], out[:, 1] = -reach, reach
        return out

    def sample_hints(self, poses: Array) -> Array | None:
        """Samples where the residual can change faster than the grid resolves: windows where a step's angle
        swings (``geometric.swing_hints``). The theta* values where a branch's domain begins or ends come from
        ``edge_reduction``."""
        if self.closed_form or poses.shape[0] == 0:
            return None
        lo, hi = self._range(poses)
        swings = np.full((poses.shape[0], geometric.SWING_PER_POSE), np.nan)
        ks = np.asarray(self._steps[1], dtype=np.int64)
        params = self.kernel_params(poses)
        geometric.swing_hints(
            params,
            lo,
            hi,
            N_SAMPLES,
            self.periodic,
            ks,
            swings,
            self._case_kernels.amplitude,
            self._case_kernels.amplitudes,
        )
        keep = np.any(np.isfinite(swings), axis=0)
        return swings[:, keep]

    def edge_reduction(self, poses: Array, hints: Array | None) -> tuple[Reduction, Array, Array] | None:
        """The zeros of the steps' margins ``1 - c^2`` (``pair_margin`` of ``geometric.case_kernels``), where a
        branch's domain begins or ends, found by the engine's sweep with the swing windows (``hints``) as samples: a
        root at or next to a domain edge is bracketed only if the edge is a sample, and a domain narrower than the
        grid step is found as a pair of close margin zeros."""
        if self.closed_form or poses.shape[0] == 0:
            return None
        lo, hi = self._range(poses)
        return _Margins(self, np.zeros((poses.shape[0], 0)) if hints is None else hints, poses), lo, hi

    def edge_search(self) -> Any:
        """``sample_hints`` as the engine finds them in the same compiled pass as the search
        (``EdgeSearch``, ``Reduction.edge_search``); None for a closed form (no sweep)."""
        if self.closed_form:
            return None
        from sweepik.reductions.kernels import RESIDUAL_SIG, RESIDUALS_SIG, SWING_SIG, address_of

        ck = self._case_kernels
        L, row = geometric.LAYOUT, self._solving_row
        every = row[L["pos_branches"]] == 4 and row[L["need"]] == 3  # (pair_every's plans: both first steps)
        return EdgeSearch(
            margins=_Margins(self, np.empty((0, 0))),
            swing=address_of(geometric.swing, SWING_SIG),
            amplitude=address_of(ck.amplitude, RESIDUAL_SIG),
            amplitudes=address_of(ck.amplitudes, RESIDUALS_SIG),
            steps=np.asarray(self._steps[1], dtype=np.int64),
            n_swing=geometric.SWING_PER_POSE,
            n_samples=N_SAMPLES,
            hint_range=GeometricReduction._range,
            every=address_of(ck.pair_every, RESIDUALS_SIG) if every else 0,
        )

    def _range(self, poses: Array) -> tuple[Array, Array]:
        """theta*'s sweep range for chain ``poses (N, 4, 4)`` (as the solver's: the circle, or ``search_range``)."""
        n = poses.shape[0]
        if self.periodic:
            return np.full(n, -np.pi), np.full(n, np.pi)
        rng = self.search_range(poses)
        assert rng is not None
        return rng[:, 0], rng[:, 1]

    def kernel_params(self, poses: Array) -> Array:
        """Parameter rows ``(N, N_PARAMS)`` of chain poses ``(N, 4, 4)``. A solve asks for the rows of one chunk
        several times (the sweep, its hints, the margins' sweep, certification): the last chunk's are kept."""
        last = self._last_params
        if last is not None and last[0] is poses:
            return last[1]
        out = self._params(poses)
        self._last_params = (poses, out)
        return out

    def _params(self, poses: Array, probing: bool = False) -> Array:
        """The rows; ``probing``: for ``_probe``, which finds the twins and steps that the rows' ``need`` fields
        name (all of them there). Compiled (``geometric.pose_rows``); ``_params_numpy`` is the same in NumPy."""
        out = np.empty((poses.shape[0], geometric.N_PARAMS))
        base, tool, reverse, r_end, w_tool, row = self._pose_row_args(self._row if probing else self._solving_row)
        geometric.pose_rows(np.ascontiguousarray(poses, dtype=np.float64), base, tool, reverse, r_end, w_tool, row, out)
        return out

    def pose_row_args(self) -> tuple[Any, ...]:
        return self._pose_row_args(self._solving_row)

    def _pose_row_args(self, row: Array) -> tuple[Any, ...]:
        robot = self.robot
        return robot.T_world_base, robot.T_flange_tool, bool(self.plan.reversed), self._chain.R_end, self._w_tool, row

    def _params_numpy(self, poses: Array, probing: bool = False) -> Array:
        """``_params`` with NumPy (a test's reference)."""
        robot = self.robot
        world = poses
        if not robot.base_is_identity:
            world = robot.T_world_base @ world
        if not robot.tool_is_identity:
            world = world @ robot.T_flange_tool
        if self.plan.reversed:
            R = np.swapaxes(world[:, :3, :3], -1, -2)
            p = -np.einsum("nij,nj->ni", R, world[:, :3, 3])
        else:
            R, p = world[:, :3, :3], world[:, :3, 3]
        L = geometric.LAYOUT
        out = np.empty((poses.shape[0], geometric.N_PARAMS))
        out[:] = self._row if probing else self._solving_row
        out[:, L["M"] : L["M"] + 9] = (R @ self._chain.R_end.T).reshape(-1, 9)
        out[:, L["t"] : L["t"] + 3] = p + R @ self._w_tool
        return out

    @cached_property
    def _solving_row(self) -> Array:
        """The row's pose-independent part, with the ``need`` fields of the twins and steps (once probed)."""
        row = self._row.copy()
        if self.plan.family == "pair":
            L = geometric.LAYOUT
            row[L["need"]] = sum(1 << b1 for b1 in {b // 2 for b in self.search_branches})
            row[L["need_margin"]] = sum(1 << k for k in self._steps[0])
            row[L["need_amplitude"]] = sum(1 << k for k in self._steps[1])
        return row

    def _flat(
        self,
        poses: Array,
        theta: Array,
        branch: IntArray | None,
        n_branches: int | None = None,
        rows: IntArray | None = None,
    ) -> tuple[Array, IntArray, Array, IntArray]:
        """The kernels' flat arguments for ``theta (N, M)`` of chain poses ``poses`` (``rows``: of ``poses[rows]``,
        from the parameters of ``poses``, kept for the last ``poses``: a search without its kernel asks for rows of
        the same poses over and over)."""
        N, M = theta.shape
        params = self.kernel_params(poses)
        index = np.arange(N) if rows is None else np.asarray(rows)
        if branch is None:
            B = self.n_branches if n_branches is None else n_branches
            pose = np.repeat(index, M * B)
            th = np.repeat(theta.reshape(-1), B)
            br = np.tile(np.arange(B), N * M)
        else:
            pose = np.repeat(index, M)
            th = theta.reshape(-1)
            br = np.broadcast_to(branch, theta.shape).reshape(-1)
        return params, pose.astype(np.int64), np.ascontiguousarray(th, dtype=np.float64), br.astype(np.int64)

    def _evaluate(
        self,
        fn: Any,
        poses: Array,
        theta: Array,
        branch: IntArray | None,
        n_branches: int,
        rows: IntArray | None = None,
    ) -> Array:
        """Compiled scalar ``fn(params, theta*, branch)`` over ``theta (N, M)``: ``(N, M, B)``, or ``(N, M)``
        with ``branch`` (``rows``: of ``poses[rows]``, see ``_flat``)."""
        params, pose, th, br = self._flat(poses, theta, branch, n_branches, rows)
        out = np.empty(th.shape[0])
        geometric.evaluate(fn, params, pose, th, br, out)
        return out.reshape(theta.shape if branch is not None else (*theta.shape, n_branches))

    def residual(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array | None:
        return self._evaluate(self._kernels[0], poses, theta, branch, self.n_branches)

    def residual_rows(self, poses: Array, rows: IntArray, theta: Array, branch: IntArray) -> Array | None:
        if type(self).residual is not GeometricReduction.residual:  # (a subclass's own residual)
            return super().residual_rows(poses, rows, theta, branch)
        return self._evaluate(self._kernels[0], poses, theta, branch, self.n_branches, rows)

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        params, pose, th, br = self._flat(poses, theta, branch)
        out = np.empty((th.shape[0], 6))
        geometric.configure(self._kernels[1], params, pose, th, br, out)
        shape = theta.shape if branch is not None else (*theta.shape, self.n_branches)
        return out.reshape(*shape, 6)


def _classes(f: Array) -> list[list[int]]:
    """Classes of the last axis of ``f`` whose values agree to ``TWIN_TOL`` (NaN where the other is NaN), with
    enough finite values to tell."""
    classes: list[list[int]] = []
    for br in range(f.shape[-1]):
        for cls in classes:
            g, h = f[..., cls[0]], f[..., br]
            same_domain = np.array_equal(np.isnan(g), np.isnan(h)) and np.isfinite(g).sum() >= TWIN_SAMPLES
            if same_domain and np.nanmax(np.abs(np.where(g == h, 0.0, g - h)), initial=0.0) <= TWIN_TOL:
                cls.append(br)
                break
        else:
            classes.append([br])
    return classes


class _PlanKey:
    """A pair plan's key to the engine's cached plan of its margins (``search._plan``): a fresh ``_Margins``
    is made for each call, so the plan cannot be kept with it."""

    __slots__ = ("__weakref__",)


class _Margins(Reduction):
    """The margins ``1 - c^2`` of a pair plan's branch domains, as a residual with three branches (the first
    step's, and the second step's on either branch of the first), so that the sweep finds their zeros."""

    name = "margins"
    kernel: tuple[Any, Any] | None = None
    kernel_residuals: Any = None

    @property
    def search_branches(self) -> list[int]:
        return self.red._steps[0]

    def __init__(self, red: GeometricReduction, swings: Array, poses: Array | None = None) -> None:
        super().__init__(red.robot, red.free_joint, 3)
        self.red = red
        self.swings = swings  # (the swing samples of the chain poses ``poses``, row by row)
        self.poses = poses
        # the engine's plan (kernels, branches, limits) is the pair plan's, not the call's: kept with the plan
        self.plan_key = red._margins_key
        self.kernel = (red._case_kernels.pair_margin, red._case_kernels.pair_configuration)
        self.kernel_residuals = red._case_kernels.pair_margins

    def sample_hints(self, poses: Array) -> Array | None:
        # where a step's angle swings, the next step's margin changes as fast: a domain there can be narrow
        if not self.swings.shape[1]:
            return None
        if poses is self.poses or self.poses is None:
            return self.swings
        # some of the poses (the engine redoes those that overflow its buffers): their rows, found by value
        row = {p.tobytes(): i for i, p in enumerate(self.poses)}
        return self.swings[[row[p.tobytes()] for p in poses]]

    def kernel_params(self, poses: Array) -> Array:
        return self.red.kernel_params(poses)

    def residual(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array | None:
        return self.red._evaluate(self.red._case_kernels.pair_margin, poses, theta, branch, self.n_branches)

    def residual_rows(self, poses: Array, rows: IntArray, theta: Array, branch: IntArray) -> Array | None:
        return self.red._evaluate(self.red._case_kernels.pair_margin, poses, theta, branch, self.n_branches, rows)

    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        raise NotImplementedError("margins have no configurations")
