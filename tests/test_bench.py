"""``sweepik bench``'s measurements (``sweepik.experiments.bench``) measure what they say."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from sweepik.experiments.bench import bench_memory


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="the child's own peak is read from /proc (Linux)")
def test_memory_is_the_childs_own_peak_not_the_parents() -> None:
    """A parent grown to ~1.5 GiB starts the memory benchmark's child: the child reports its own peak (a few hundred
    MiB at most for 500 C-Arm poses), not the parent's resident set that ``ru_maxrss`` carries over fork and exec."""
    grown = np.ones((200, 1024, 1024))  # 1.6 GB, resident (written)
    result = bench_memory(500)
    assert grown.sum() > 0  # (alive until here)
    assert result["poses"] == 500
    assert 20 < result["peak_rss_mib"] < 800, result
