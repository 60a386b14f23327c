"""The Reduction protocol: "given the value of one joint theta*, solve the other joints in closed form".

A reduction turns the 6-D IK problem into a 1-D search over theta*. The sweep engine samples theta*, asks the
reduction for the other joints (every closed-form branch) and, if the reduction offers one, for a signed
residual whose zeros are exactly the IK solutions.

Poses handed to a reduction are chain poses ``(N, 4, 4)``: the flange in the base frame of the DH chain,
i.e. ``inv(T_world_base) @ T_world_tool @ inv(T_flange_tool)``. The engine does that conversion.

Writing your own reduction: subclass :class:`Reduction`, set ``free_joint`` and ``n_branches``, implement
``solve_rest`` (and, for speed and for double roots, ``residual``); pass an instance to ``sweepik.solve``::

    class MyReduction(Reduction):
        name = "my-arm-q1"
        def __init__(self, robot):
            super().__init__(robot, free_joint=0, n_branches=4)
        def solve_rest(self, poses, theta, branch=None):
            ...  # (N, M, 4, n) configurations, NaN where a branch does not exist

See docs/reductions.md for a complete example.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from functools import cache
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from sweepik.model.robot import Robot
from sweepik.reductions.kernels import kernel_owner

Array = NDArray[np.float64]
IntArray = NDArray[np.intp]


@cache
def overridden_below_kernel(cls: type, names: tuple[str, ...]) -> bool:
    """A class of ``cls``'s MRO below the one that sets ``kernel`` defines one of ``names`` (a Python method that the
    compiled kernels would silently bypass). A property of the class: cached, as a solve asks for it several times."""
    mro = cls.__mro__
    below = mro[: mro.index(kernel_owner(cls))]
    return any(name in vars(c) for c in below for name in names)


class EdgeSearch(NamedTuple):
    """A reduction whose sample hints are the zeros of its margins (a generic sweep: the edges of its branch
    domains, ``generic._Margins``) sampled with its swing samples (``geometric.swing_hints``), which are hints too:
    what the engine's search (:mod:`sweepik.engine.search`) needs to find them and the candidates in one compiled pass
    per pose (``Reduction.edge_search``;
    its ``sample_hints`` must give the same samples, the reference's and ``sample_grid``'s way)."""

    margins: object  # the margins' reduction (its engine plan: kernels, branches, residual noise)
    swing: int  # the address of the swing kernel (``kernels.SWING_SIG``)
    amplitude: int  # ... of the amplitude kernels it takes
    amplitudes: int
    steps: NDArray[np.int64]  # the steps whose amplitudes it examines
    n_swing: int  # the samples it writes per pose, at most
    n_samples: int  # its grid's samples (the sweep's default: ``settings.N_SAMPLES``)
    hint_range: Any  # ``hint_range(reduction, poses) -> (lo, hi)``: theta*'s range its hints are sought over
    # (a function, not a bound method: the engine keeps its plan while the reduction lives, and no longer)
    # the address of a kernel computing the residuals and the margins at once (``kernels.RESIDUALS_SIG``: the
    # reduction's ``n_branches`` residuals, then the margins' 3), for the uniform samples that both searches take
    # (used where the margins have an all-branch kernel of 3); 0: none, each search evaluates its own
    every: int = 0


class Reduction(ABC):
    """Base class of reductions. Shapes: ``poses (N, 4, 4)``, ``theta (N, M)`` in theta*'s unit.

    Attributes:
        robot: the robot this reduction solves.
        free_joint: index of theta* in the configuration vector.
        n_branches: number B of closed-form branches for a given theta*.
        name: registry name (e.g. ``"carm-d1"``).
    """

    name: str = "custom"
    #: Known blind spots, for the docs and ``sweepik solve --reduction`` help.
    blind_spots: str = ""
    #: Rounding noise of ``residual`` (absolute). A residual extremum that dips below zero by less than this
    #: is treated as one double root. 1e-14 suits residuals built from O(1) sines, cosines and unit vectors.
    residual_noise: float = 1e-14
    #: Registry name of a reduction that also solves poses where this one cannot describe the solution set
    #: (``degenerate``: e.g. a continuum along a joint other than theta*) or where its closed form is
    #: ill-conditioned (a candidate that even a Newton polish cannot certify); its solutions are merged in.
    fallback: str | Reduction | None = None
    #: Compiled scalar kernels ``(residual, configuration)`` with the signatures ``reductions.kernels.RESIDUAL_SIG``
    #: and ``CONFIGURATION_SIG`` over rows of ``kernel_params(poses)`` (None: the engine calls ``residual`` back,
    #: :mod:`sweepik.engine.callback`).
    kernel: tuple[Any, Any] | None = None
    #: Optional compiled kernel ``residuals(params, theta, out)`` (signature ``reductions.kernels.RESIDUALS_SIG``)
    #: writing every branch's residual at theta* into ``out (n_branches,)``, bit for bit what ``kernel[0]`` gives
    #: branch by branch, at less than ``n_branches`` times its cost (the branches share most of the work). The
    #: engine uses it for the uniform samples; it is ignored unless set by the class that sets ``kernel``.
    kernel_residuals: Any = None
    #: Optional compiled kernel ``configurations(params, theta, out)`` (signature ``reductions.kernels.
    #: CONFIGURATIONS_SIG``) writing every branch's configuration at theta* into ``out (n_branches, n_joints)``, bit
    #: for bit what ``kernel[1]`` gives branch by branch (NaN rows where a branch does not exist). A closed form's
    #: certification uses it (every branch is a candidate); ignored unless set by the class that sets ``kernel``.
    kernel_configurations: Any = None
    #: Optional compiled kernel ``hints(params, out)`` (signature ``reductions.kernels.HINTS_SIG``) writing a pose's
    #: ``sample_hints`` into ``out (n_kernel_hints,)``, value for value: the engine then builds a pose's samples in
    #: one compiled pass (for a single pose, the NumPy steps of ``sample_hints`` cost more than its search). Ignored
    #: unless set by the class that sets ``kernel``, with ``n_kernel_hints``, and unless a subclass below that class
    #: overrides ``sample_hints``.
    kernel_hints: Any = None
    n_kernel_hints: int = 0
    #: Optional method ``edge_search(self) -> EdgeSearch | None``: the hints are zeros of another residual
    #: (the generic sweeps' margins), which the engine then finds in the same compiled pass as the candidates, pose
    #: by pose. Ignored unless set by the class that sets ``kernel`` and unless a subclass below that class
    #: overrides ``sample_hints``.
    edge_search: Any = None
    #: No sweep: every branch of ``solve_rest`` (at any theta*) is a candidate (a closed-form decomposition).
    closed_form: bool = False
    #: A second reduction whose solutions the solver joins to this one's (:mod:`sweepik.engine.companion`): set by the
    #: automatic decomposition on an arm with a near-structure, None otherwise.
    companion: Reduction | None = None
    #: Classes of branches whose residuals are identical (they differ in the configuration only, e.g. by a
    #: symmetry of the arm): the engine searches the first of each class and hands its roots to the others.
    twins: tuple[tuple[int, ...], ...] = ()

    @property
    def search_branches(self) -> list[int]:
        """The branches the engine searches: all, or the first of each class of ``twins``."""
        others = {b for cls in self.twins for b in cls[1:]}
        return [b for b in range(self.n_branches) if b not in others]

    @property
    def uses_kernel(self) -> bool:
        """The compiled kernel computes this reduction's residual: it has a ``kernel``, and no subclass below the
        class that set it overrides ``residual`` or ``solve_rest`` (a subclass that changes the residual in
        Python must not silently run its parent's compiled kernel)."""
        if self.kernel is None:
            return False
        return not overridden_below_kernel(type(self), ("residual", "solve_rest"))

    def kernel_params(self, poses: Array) -> Array:
        """Per-pose parameters ``(N, P)`` of the compiled kernels (only with ``kernel``)."""
        raise NotImplementedError

    def release(self, poses: Array) -> None:
        """Forget what was kept for the chain poses ``poses`` while their chunk was solved (the engine calls it
        when the chunk is done; default: nothing is kept). A later call with the same poses works them out anew, so
        a benchmark that solves the same poses again times the solve, not a lookup."""
        return None

    def __init__(self, robot: Robot, free_joint: int, n_branches: int) -> None:
        self.robot = robot
        self.free_joint = int(free_joint)
        self.n_branches = int(n_branches)

    @property
    def periodic(self) -> bool:
        """True when theta* is a revolute joint (the sweep wraps around the circle)."""
        return bool(self.robot.is_revolute[self.free_joint])

    @abstractmethod
    def solve_rest(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array:
        """Full configurations for each theta*: ``(N, M, B, n)``, or ``(N, M, n)`` when ``branch`` is given.

        ``branch`` (int array broadcastable to ``theta``) selects one branch per sample. Entries of branches
        that do not exist at that theta* are NaN.
        """

    def residual(self, poses: Array, theta: Array, branch: IntArray | None = None) -> Array | None:
        """Signed residual ``(N, M, B)`` (``(N, M)`` with ``branch``), continuous in theta* on each branch,
        zero exactly at IK solutions, NaN where the branch does not exist. ``None``: not provided, the
        engine then works on the pose error (local minima only).
        """
        return None

    def residual_rows(self, poses: Array, rows: IntArray, theta: Array, branch: IntArray) -> Array | None:
        """``residual(poses[rows], theta, branch)`` ``(K, M)``: the residual of chain poses picked by index, one branch
        per sample. A search without a compiled kernel asks for a row of the same poses over and over (refinements); a
        reduction that derives per-pose parameters from them can keep those rather than derive them each time."""
        return self.residual(poses[rows], theta, branch)

    def sample_hints(self, poses: Array) -> Array | None:
        """Extra theta* samples ``(N, K)`` (NaN-padded): branch-domain edges, branch swaps, places where the
        residual bends sharply. Roots next to a domain edge are only bracketed if the edge is a sample.
        """
        return None

    def edge_reduction(self, poses: Array, hints: Array | None) -> tuple[Reduction, Array, Array] | None:
        """Where a branch's domain begins or ends, as a reduction whose zeros over ``[lo, hi]`` (``(N,)`` each) the
        engine finds with its sweep and samples before ``hints`` (this reduction's ``sample_hints(poses)``): a root at
        or next to a domain edge is bracketed only if the edge is a sample. None: no such samples."""
        return None

    def blind_spot(self, poses: Array) -> tuple[IntArray, Reduction, Array] | None:
        """The poses (indices into ``poses``) where this reduction is blind or ill-conditioned somewhere along
        theta*, a reduction that sees them and its sweep range ``(K, 2)``: the engine sweeps it on those poses and
        hands the configurations to ``blind_spot_kept``, whose are added to ``special_solutions``. None: none."""
        return None

    def blind_spot_kept(self, q: Array) -> NDArray[np.bool_]:
        """Which configurations ``q (K, n)`` that the ``blind_spot`` reduction found this reduction keeps (those in
        its blind slice: the others it finds itself)."""
        return np.ones(q.shape[0], dtype=bool)

    def special_solutions(self, poses: Array) -> Array | tuple[Array, IntArray] | None:
        """Candidate configurations ``(N, K, n)`` (NaN-padded) at theta* values where the reduction itself
        degenerates (its blind spots), optionally with their multiplicities ``(N, K)`` (else 1). The engine
        certifies them by forward kinematics like any other.
        """
        return None

    def degenerate(self, poses: Array) -> NDArray[np.bool_] | None:
        """``(N,)`` True where this reduction cannot describe the pose's solutions (``fallback`` solves them)."""
        return None

    def degenerate_fallbacks(self, poses: Array) -> list[tuple[str | Reduction, NDArray[np.bool_]]]:
        """The poses ``degenerate`` gives, split by the reduction that solves them: ``[(fallback, mask (N,))]``
        (``fallback`` for all of them, unless a reduction's blind spots differ in kind)."""
        deg = self.degenerate(poses)
        if self.fallback is None or deg is None or not deg.any():
            return []
        return [(self.fallback, deg)]

    def continuum_poses(self, poses: Array) -> NDArray[np.bool_] | None:
        """``(N,)`` the poses where ``continuum_joints`` may flag a candidate, told from the pose alone (a reduction
        that can tell: its poses elsewhere take the one compiled call, ``one_pose``, without a continuum kernel);
        None: it cannot tell without the candidates."""
        return None

    def continuum_joints(
        self, poses: Array, pose: IntArray, theta: Array, branch: IntArray, error: Array | None = None, tol: float = 0.0
    ) -> IntArray | None:
        """For candidates ``(pose[k], theta[k], branch[k])`` of chain ``poses`` (with ``error``, only those whose pose
        error is at most ``tol``): ``(K,)`` a joint other than theta* that the closed form leaves free at the
        candidate (a continuum of solutions may run along it, which a sweep of theta* cannot see), -1 for none; None
        when there is none. The solver traces such continua (:mod:`sweepik.engine.continuation`). The base class cannot
        tell (a reduction then needs ``fallback`` and ``degenerate`` for its blind spots)."""
        return None

    def continuum_kernel(self) -> tuple[int, int, Array, NDArray[np.int64]] | None:
        """``continuum_joints`` of a sweep's candidates as the arguments of ``geometric.continuum_rows`` that do not
        change (the amplitude kernel's address, branches per position branch, thresholds, joints), for a compiled
        caller (``one_pose.settle_one``); None where it finds none for them. A class that overrides
        ``continuum_joints`` and not this one has its candidates checked in Python (the general path)."""
        return None

    def pose_row_args(self) -> tuple[Any, ...] | None:
        """For a compiled caller (``engine.closed_pose``): the arguments of ``geometric.pose_rows`` after the poses
        and before the output (``base, tool, reverse, r_end, w_tool, row``) when ``kernel_params`` is that kernel's
        rows, ``geometric.N_PARAMS`` wide; None: ``kernel_params`` is the reduction's own (the Python path)."""
        return None

    def singular_kernel(self) -> tuple[int, Array] | None:
        """For a compiled caller (``one_pose.settle_closed``): a closed form's ``degenerate`` poses and those where
        ``continuum_joints`` may flag a branch, in one kernel: the address of ``(params, thr, out, low, start, stop)``
        (``kernels.SINGULAR_SIG``), which sets ``out[i]`` or ``low[i]`` for such a pose i, and its ``thr``. None:
        the solver asks ``degenerate`` and ``continuum_joints`` in Python (also where a class overrides either of
        them and not this one)."""
        return None

    def search_range(self, poses: Array) -> Array | None:
        """``(N, 2)`` theta* interval that holds every solution, for a prismatic theta* searched without
        joint limits (``limits=False``). ``None``: the joint limits are used.
        """
        return None
