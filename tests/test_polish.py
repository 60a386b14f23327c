"""Newton polish: the compiled steps (``certify.polish_rows``) and the NumPy reference (``oracles.numpy_engine``)
are the same method; both converge from near a solution, with joints held or not, and agree."""

from __future__ import annotations

import numpy as np
import pytest
from oracles import numpy_engine

from sweepik import load_robot
from sweepik.engine.polish import geodesic_errors, polish
from sweepik.model.units import orientation_weight


@pytest.mark.parametrize("name", ["ur5", "carm", "stanford", "kinova_jaco2"])
@pytest.mark.parametrize("held", [False, True])
def test_compiled_polish_is_the_numpy_polish(name: str, held: bool) -> None:
    robot = load_robot(name)
    rng = np.random.default_rng(5)
    lo = np.where(np.isfinite(robot.lower), robot.lower, -np.pi)
    hi = np.where(np.isfinite(robot.upper), robot.upper, np.pi)
    exact = rng.uniform(np.maximum(lo, -np.pi), np.minimum(hi, np.pi), (12, 6))
    target = robot.fk(exact)
    scale = np.where(robot.is_revolute, 1e-3, 1e-3 * robot.length_scale)
    start = exact + rng.normal(size=exact.shape) * scale
    fixed = None
    if held:  # one joint held at its exact value (as the continuation holds the traced joint)
        fixed = np.zeros(exact.shape, dtype=bool)
        fixed[np.arange(12), rng.integers(0, 6, 12)] = True
        start = np.where(fixed, exact, start)
    w = orientation_weight(robot.length_unit)
    compiled = polish(robot, start, target, w, fixed=fixed)
    numpy = numpy_engine.polished(robot, start, target, w, fixed=fixed)[0]
    tol = 1e-11 * robot.length_scale
    assert (geodesic_errors(robot, compiled, target, w) <= tol).all()
    assert (geodesic_errors(robot, numpy, target, w) <= tol).all()
    d = np.where(robot.is_revolute, compiled - numpy, (compiled - numpy) / robot.length_scale)
    assert np.abs(d).max() < 1e-8
    if fixed is not None:
        np.testing.assert_array_equal(compiled[fixed], start[fixed])
