"""The vectorised bracketed root finder of the NumPy reference sweep (tests/oracles/rootfind.py)."""

from __future__ import annotations

import numpy as np
from oracles.rootfind import find_roots


def test_find_roots_vectorised_to_full_precision() -> None:
    c = np.linspace(-0.9, 0.9, 101)

    def f(x: np.ndarray, idx: np.ndarray) -> np.ndarray:
        return np.sin(x) - c[idx]

    a, b = np.full(c.size, -1.5), np.full(c.size, 1.5)
    x = find_roots(f, a, b, f(a, np.arange(c.size)), f(b, np.arange(c.size)), 1e-15)
    np.testing.assert_allclose(x, np.arcsin(c), rtol=0, atol=4e-16)
