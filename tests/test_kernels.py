"""A reduction's compiled kernels (sweepik.reductions.kernels): the one the engine runs is the reduction's own,
all-branch and hints kernels bit for bit the one-branch ones, signatures checked."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from conftest import carm_stress_configurations

import sweepik
from sweepik import load_robot
from sweepik.engine import chunk, search

CARM = load_robot("carm")


def test_subclass_overriding_the_residual_does_not_run_the_parents_kernel() -> None:
    arm = sweepik.load_robot("carm")

    class NoResidual(sweepik.reductions.CArmD1):
        def residual(self, poses, theta, branch=None):  # type: ignore[no-untyped-def]
            return None

    class Renamed(sweepik.reductions.CArmD1):
        name = "renamed"

    assert sweepik.reductions.CArmD1(arm).uses_kernel and Renamed(arm).uses_kernel
    assert not NoResidual(arm).uses_kernel
    q = np.array([700.0, 0.4, 0.3, -0.5, 0.6, 0.2])
    sols = sweepik.solve(arm, arm.fk(q), reduction=NoResidual(arm))
    assert np.abs(sols.nearest(q) - q).max() < 1e-6


def test_all_branch_kernel_is_bitwise_the_branch_kernel() -> None:
    """carm-d1's all-branch residual kernel (used for the uniform samples) gives exactly, bit for bit, what the
    one-branch kernel gives: same roots, same extrema, same families as branch-by-branch evaluation."""
    from sweepik.reductions import kernels

    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    q = carm_stress_configurations(400, seed=11)
    q[:20, 0] = 800.0  # with theta2 = 0 below: the wrist on joint 2's axis at d1 = Pz (r = 0)
    q[:20, 1] = 0.0
    chain = CARM.fk(q)
    params = red.kernel_params(chain)
    hints = red.sample_hints(chain)
    rng = np.random.default_rng(5)
    lo, hi = red.search_range(chain).T
    out = np.empty(4)
    for i in range(len(q)):
        thetas = np.concatenate([hints[i], rng.uniform(lo[i], hi[i], 40), [chain[i, 2, 3]]])
        for th in thetas[np.isfinite(thetas)]:
            kernels.carm_d1_residuals(params[i], float(th), out)
            one = np.array([kernels.carm_d1_residual(params[i], float(th), b) for b in range(4)])
            np.testing.assert_array_equal(out, one)
    assert search._kernel_residuals(red) is kernels.carm_d1_residuals

    class OwnKernel(sweepik.reductions.CArmD1):
        kernel = (kernels.carm_theta2_residual, kernels.carm_theta2_configuration)

    assert search._kernel_residuals(OwnKernel(CARM)) is None


def test_carm_d1_twin_branches_have_the_same_residual_bit_for_bit() -> None:
    """carm-d1 declares branches (sigma, eps) and (-sigma, -eps) twins (the engine searches one of each pair and
    hands its roots to the other): their residuals agree bit for bit, in the NumPy reference and in the kernels,
    also with the wrist on joint 2's axis (r = 0), outside the elbow's domain (NaN) and at range ends; their
    configurations differ."""
    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    assert red.twins == ((0, 3), (1, 2)) and red.search_branches == [0, 1]
    q = carm_stress_configurations(300, seed=12)
    q[:20, 0], q[:20, 1] = 800.0, 0.0  # the wrist on joint 2's axis at d1 = Pz
    chain = CARM.fk(q)
    lo, hi = red.search_range(chain).T
    rng = np.random.default_rng(8)
    theta = np.concatenate([lo[:, None] + (hi - lo)[:, None] * rng.random((len(q), 30)), chain[:, 2, 3, None],
                            lo[:, None], hi[:, None]], axis=1)  # fmt: skip
    f = red.residual(chain, theta)
    assert np.isnan(f).any() and np.isfinite(f).any()
    for a, b in red.twins:
        np.testing.assert_array_equal(f[..., a], f[..., b])
        cfg_a = red.solve_rest(chain, theta, np.full(theta.shape, a))
        cfg_b = red.solve_rest(chain, theta, np.full(theta.shape, b))
        both = np.all(np.isfinite(cfg_a), axis=-1) & np.all(np.isfinite(cfg_b), axis=-1)
        assert both.any() and np.all(np.any(cfg_a[both] != cfg_b[both], axis=-1))
    from sweepik.reductions import kernels

    params = red.kernel_params(chain)
    for i in range(0, len(q), 7):
        for th in theta[i]:
            for a, b in red.twins:
                fa = kernels.carm_d1_residual(params[i], float(th), a)
                fb = kernels.carm_d1_residual(params[i], float(th), b)
                assert fa == fb or (np.isnan(fa) and np.isnan(fb))


def test_carm_d1_hints_kernel_is_bitwise_sample_hints() -> None:
    """carm-d1's compiled hints (with them the engine builds a pose's samples in one pass) are exactly what
    ``sample_hints`` gives: where Px is tiny (snapped to 0 in the kernel parameters, not in the hints), where the
    wrist is out of every rail position's reach (NaN), and on random poses. A subclass that overrides
    ``sample_hints`` is not bypassed by the kernel."""
    from sweepik.reductions import kernels

    red = sweepik.reductions.get_reduction(CARM, "carm-d1")
    chain = CARM.fk(carm_stress_configurations(300, seed=12))
    chain[:10, 0, 3] = [0.0, -0.0, 1e-14, -1e-14, 1e-9, 3e-12, -3e-12, 1e-300, 5.0, -5.0]
    chain[10:20, :2, 3] *= 50.0  # out of reach of the outer circle
    params = red.kernel_params(chain)
    assert params[2, 0] == 0.0 and params[2, 17] == 1e-14  # (the snap, and the value as given)
    ref = red.sample_hints(chain)
    assert np.isnan(ref[10:20, :4]).all()
    out = np.empty(kernels.N_D1_HINTS)
    for i in range(len(chain)):
        kernels.carm_d1_hints(params[i], out)
        np.testing.assert_array_equal(out, ref[i])
    assert search._hints_kernel(red) is kernels.carm_d1_hints

    class OwnHints(sweepik.reductions.CArmD1):
        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return super().sample_hints(poses)[:, :5]

    assert search._hints_kernel(OwnHints(CARM)) is None


def test_hints_kernel_of_a_periodic_theta_is_wrapped_as_sample_hints() -> None:
    """A reduction's own hints kernel over a revolute theta* (hints beyond +-pi, NaN, on the grid, repeated): the
    compiled samples are the reference's, the hints wrapped into [-pi, pi] the same way."""
    import numba
    from oracles import numpy_sweep as sweep

    from sweepik.reductions import kernels

    values = np.array([0.3, 4.0, -7.5, np.nan, np.pi, -np.pi, 0.3, 1e3])

    def hints_row(p, out):
        for k in range(values.size):
            out[k] = values[k] + 0.0 * p[0]

    class OwnHints(sweepik.reductions.CArmTheta2):
        kernel = sweepik.reductions.CArmTheta2.kernel
        kernel_hints = numba.njit(kernels.HINTS_SIG)(hints_row)
        n_kernel_hints = values.size

        def sample_hints(self, poses: np.ndarray) -> np.ndarray:
            return np.broadcast_to(values, (poses.shape[0], values.size)).copy()

    red = OwnHints(CARM)
    assert red.periodic and search._hints_kernel(red) is OwnHints.kernel_hints
    chain = CARM.fk(carm_stress_configurations(50, seed=13))
    lo, hi = chunk.theta_range(CARM, red, chain)
    ref = sweep.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
    grid, count = search.sample_grid(red, chain, lo, hi, sweep.N_SAMPLES)
    np.testing.assert_array_equal(grid, ref)  # (a hints kernel's NaN hint is a spare sample, as in the reference)
    assert (count == ref.shape[1]).all()


def test_a_kernel_of_the_wrong_signature_is_refused_and_one_without_is_compiled_for_the_engine() -> None:
    """A reduction's kernel is called through its address: one compiled for another signature (here a float32
    result) would read its arguments wrong and is refused with a clear error; a plain Python function too. A Numba
    function not yet compiled for the engine's signature is compiled for it and used."""
    import numba

    from sweepik.reductions import kernels

    pose = CARM.fk(np.array([800.0, 0.3, 0.2, -0.4, 0.5, 0.1]))

    @numba.njit("float32(float64[::1], float64, int64)")
    def wrong(p, x, b):
        return 0.0

    @numba.njit
    def lazy(p, x, b):
        return kernels._carm_d1(p, x, b)

    class Wrong(sweepik.reductions.CArmD1):
        kernel = (wrong, kernels.carm_d1_configuration)

    class Plain(sweepik.reductions.CArmD1):
        kernel = (lambda p, x, b: 0.0, kernels.carm_d1_configuration)

    class Lazy(sweepik.reductions.CArmD1):
        kernel = (lazy, kernels.carm_d1_configuration)

    for red, match in ((Wrong(CARM), "compiled for"), (Plain(CARM), "must be a Numba function")):
        with pytest.raises(sweepik.UnknownOptionError, match=match):
            sweepik.solve(CARM, pose, reduction=red)
    got, ref = sweepik.solve(CARM, pose, reduction=Lazy(CARM)), sweepik.solve(CARM, pose, reduction="carm-d1")
    np.testing.assert_array_equal(got.q, ref.q)
    assert len(ref) > 0

    class Uncounted(sweepik.reductions.CArmD1):
        kernel = sweepik.reductions.CArmD1.kernel
        kernel_hints = kernels.carm_d1_hints

    with pytest.raises(sweepik.UnknownOptionError, match="n_kernel_hints"):
        sweepik.solve(CARM, pose, reduction=Uncounted(CARM))


def test_residual_rows_is_the_residual_of_those_rows() -> None:
    """``Reduction.residual_rows`` (the NumPy engine's residual of poses picked by index, from parameters kept for
    the poses) gives what ``residual`` gives on the picked poses, value for value: a generic sweep, its margins,
    and a subclass with a residual of its own (which must be the one called)."""
    from sweepik.reductions.generic import GeometricReduction, _Margins

    robot = load_robot("fanuc_crx10ia")
    red = sweepik.reductions.get_reduction(robot, None)
    assert isinstance(red, GeometricReduction)
    rng = np.random.default_rng(3)
    poses = robot.fk(rng.uniform(robot.lower, robot.upper, (12, 6)))
    rows = rng.integers(0, 12, 30)
    theta = rng.uniform(-np.pi, np.pi, (30, 5))
    branch = rng.integers(0, red.n_branches, 30)[:, None]
    margins = _Margins(red, np.zeros((12, 0)), poses)
    for r, b in ((red, branch), (margins, branch % 3)):
        want = r.residual(poses[rows], theta, np.broadcast_to(b, theta.shape))
        got = r.residual_rows(poses, rows, theta, np.broadcast_to(b, theta.shape))
        assert got is not None and want is not None and np.isfinite(want).any()
        np.testing.assert_array_equal(got, want)

    class Shifted(GeometricReduction):
        def residual(self, poses: Any, theta: Any, branch: Any = None) -> Any:
            out = super().residual(poses, theta, branch)
            return None if out is None else out + 1.0

    shifted = Shifted(robot, red.plan)
    got = shifted.residual_rows(poses, rows, theta, np.broadcast_to(branch, theta.shape))
    np.testing.assert_array_equal(got, red.residual(poses[rows], theta, np.broadcast_to(branch, theta.shape)) + 1.0)


def test_a_lazy_kernels_unchecked_entry_answers_as_its_dispatcher() -> None:
    """``LazyKernel.unchecked`` (the compiled entry point the single-pose paths call, without type resolution) gives
    what the kernel called through its dispatcher gives, on the signature's types; a kernel whose dispatcher has no
    entry point for its signature falls back to the dispatcher."""
    from numba import float64

    from sweepik.reductions.kernels import LazyKernel, lazy_njit

    @lazy_njit((float64[:, ::1], float64), cache=False)
    def scaled_sum(a, s):  # pragma: no cover
        return a.sum() * s, a * s

    a = np.random.default_rng(0).standard_normal((3, 4))
    want = scaled_sum(a, 2.5)
    got = scaled_sum.unchecked(a, 2.5)
    assert got[0] == want[0]
    np.testing.assert_array_equal(got[1], want[1])
    assert scaled_sum.unchecked is not scaled_sum.dispatcher

    kernel = LazyKernel(scaled_sum.py_func, (float64[:, ::1], float64))
    kernel.dispatcher.overloads.clear()  # (no overload: what Numba would give without an entry point)
    assert kernel.unchecked is kernel.dispatcher
