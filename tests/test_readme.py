"""The README's library example runs as written and its claims hold."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

README = Path(__file__).resolve().parents[1] / "README.md"


@pytest.mark.skipif(not README.exists(), reason="README not next to the tests (installed elsewhere)")
def test_readme_library_block_runs() -> None:
    block = re.search(r"## Library\n```python\n(.*?)```", README.read_text(), re.S)
    assert block is not None
    env: dict = {}
    exec(compile(block.group(1), "README.md", "exec"), env)
    sols, q = env["sols"], env["q"]
    np.testing.assert_allclose(sols.nearest(q), q, atol=1e-9)
    assert len(env["many"]) == 1000
    # the strategies shown return solutions (the paper's one with its own J threshold)
    import sweepik

    arm, T = env["arm"], env["T"]
    assert len(sweepik.solve(arm, T, strategy="paper")) >= 1
    assert len(sweepik.solve(arm, T, reduction="carm-theta2", limits=False)) >= len(sols)
