"""Batch kernels on threads (sweepik.engine.parallel): every item once, in parts, serial for small batches or one
thread."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from sweepik.engine import chunk, parallel


def _record(out, seen, start, stop):
    seen.append((start, stop, threading.get_ident()))
    out[start:stop] += 1


@pytest.mark.parametrize("n", [0, 1, 2, 7, 63, 64, 65, 1000])
def test_every_item_once(n):
    out = np.zeros(n, dtype=np.int64)
    seen: list[tuple[int, int, int]] = []
    parallel.run(_record, n, 64, out, seen)
    assert np.all(out == 1)
    if n < 64 or parallel.threads() == 1:
        assert seen == [(0, n, threading.get_ident())]  # in the calling thread, one part
    else:
        assert len(seen) == min(n, parallel.threads() * parallel.PARTS_PER_THREAD)
        assert all(t != threading.get_ident() for _, _, t in seen)


def test_kernel_error_is_raised():
    def fail(start, stop):
        if stop == 1000:  # (the last part, on a thread or, with one thread allowed, the whole batch)
            raise ValueError("boom")

    with pytest.raises(ValueError, match="boom"):
        parallel.run(fail, 1000, 1)


def test_numba_thread_setting_is_honoured():
    import numba

    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        assert parallel.threads() == 1
        out = np.zeros(500, dtype=np.int64)
        seen: list[tuple[int, int, int]] = []
        parallel.run(_record, 500, 1, out, seen)
        assert seen == [(0, 500, threading.get_ident())] and np.all(out == 1)
    finally:
        numba.set_num_threads(before)


@pytest.mark.parametrize("n", [0, 1, 2, 5])
def test_in_order_yields_every_result_in_order(n):
    seen: list[int] = []

    def work(k):
        seen.append(threading.get_ident())
        return k * k

    assert list(parallel.in_order(work, range(n))) == [k * k for k in range(n)]
    if n < 2 or parallel.threads() == 1:
        assert all(t == threading.get_ident() for t in seen)  # (nothing to overlap: in the calling thread)


def test_in_order_raises_where_the_result_is_due():
    def work(k):
        if k == 3:
            raise ValueError("chunk 3")
        return k

    results = parallel.in_order(work, range(6))
    assert [next(results) for _ in range(3)] == [0, 1, 2]
    with pytest.raises(ValueError, match="chunk 3"):
        next(results)


def test_in_order_threads_see_the_callers_setting():
    n = parallel.threads()
    assert list(parallel.in_order(lambda _: parallel.threads(), range(4))) == [n] * 4
    assert parallel.threads() == n  # (the setting is the chunk threads' own)


def test_in_order_with_one_thread_runs_in_the_calling_thread():
    import numba

    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        idents = list(parallel.in_order(lambda _: threading.get_ident(), range(4)))
        assert idents == [threading.get_ident()] * 4
    finally:
        numba.set_num_threads(before)


def test_in_order_nested_in_a_chunk_runs_in_that_chunks_thread():
    """A chunk that itself solves in chunks (``fn`` calling ``in_order``) must not wait on the pool it runs on."""

    def inner(k):
        return threading.get_ident()

    def outer(k):
        me = threading.get_ident()
        return all(t == me for t in parallel.in_order(inner, range(3)))

    assert all(parallel.in_order(outer, range(4)))


@pytest.mark.parametrize(("name", "split"), [("fanuc_crx10ia", True), ("carm", False), ("ur5", False)])
def test_a_generic_sweeps_small_batch_is_split_in_two(name: str, split: bool, monkeypatch: pytest.MonkeyPatch) -> None:
    """A generic sweep's batch of at most ``IN_FLIGHT`` chunks is split evenly into IN_FLIGHT chunks solved side by
    side, each on its share of the threads (``solving._chunking``); the solutions are one chunk's, bit for bit (each
    pose is solved on its own). Not below ``IN_FLIGHT x SPLIT_MIN`` poses, nor for a cheaper search (the C-Arm's
    hints kernel, a closed form), nor on one thread (nothing to overlap)."""
    import numba

    import sweepik
    from sweepik import solving

    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("one thread: nothing to split for")
    robot = sweepik.load_robot(name)
    n = 3 * solving.SPLIT_MIN + 1
    T = robot.fk(np.random.default_rng(3).uniform(robot.lower, robot.upper, (n, 6)))
    seen: list[tuple[int, int]] = []
    real = chunk.solve_chunk

    def spy(r: object, red: object, P: np.ndarray, *a: object) -> object:
        seen.append((len(P), parallel.threads()))
        return real(r, red, P, *a)

    monkeypatch.setattr(solving, "solve_chunk", spy)
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = sweepik.solve_many(robot, T)
        assert seen == [(n, 1)]
        numba.set_num_threads(2)
        seen.clear()
        both = sweepik.solve_many(robot, T)
        assert sorted(seen) == ([(n // 2, 1), (n - n // 2, 1)] if split else [(n, 2)])
        seen.clear()
        sweepik.solve_many(robot, T[: solving.SPLIT_MIN * parallel.IN_FLIGHT - 1])
        assert seen == [(solving.SPLIT_MIN * parallel.IN_FLIGHT - 1, 2)]
    finally:
        numba.set_num_threads(before)
    for column in ("q", "error", "error_geodesic", "multiplicity", "within_limits", "offsets"):
        np.testing.assert_array_equal(getattr(both, column), getattr(one, column))
