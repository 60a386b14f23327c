"""``SolutionBatch``: the solutions of many poses, held in columns.

``solve_many`` of a million poses should not build a million Python objects unless asked: the solver keeps each
chunk's solutions as stacked arrays (``Block``), and a batch is a sequence of blocks. Indexing or iterating a
batch builds the :class:`~sweepik.solutions.Solutions` of the poses asked for; the column attributes
(``offsets``, ``q``, ``error``, ...) give every solution of every pose at once, pose ``i``'s solutions being the
rows ``offsets[i]:offsets[i + 1]``.
"""

from __future__ import annotations

import bisect
import operator
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, overload

import numpy as np
from numpy.typing import NDArray

from .solutions import Family, Solutions

if TYPE_CHECKING:
    from .robot import Robot

Array = NDArray[np.float64]

__all__ = ["SolutionBatch", "Block"]

UNREACHABLE = "unreachable: no configuration of the arm reaches this pose"


def no_solution_reason(n_reachable: int) -> str:
    """Why a pose has no solution (nor family), given how many solutions it has before the joint limits."""
    if n_reachable > 0:
        return f"out of joint limits: {n_reachable} solution(s) reach the pose but violate the limits"
    return UNREACHABLE


@dataclass(frozen=True, eq=False)
class Block:
    """The solutions of a chunk of ``n`` poses, rows sorted by pose: pose ``i`` owns rows
    ``bounds[i]:bounds[i + 1]``. ``families`` maps a pose to its self-motion families (most poses have none);
    ``n_reachable[i]`` counts its solutions before the joint limits were applied (for the no-solution reason);
    ``empty_reason``, if set, is the reason given to every pose without solutions (the paper's strategy)."""

    robot: Robot
    poses: Array
    bounds: NDArray[np.intp]
    q: Array
    error: Array
    error_geodesic: Array
    within_limits: NDArray[np.bool_]
    multiplicity: NDArray[np.intp]
    families: dict[int, tuple[Family, ...]]
    n_reachable: NDArray[np.intp]
    empty_reason: str | None = None

    @property
    def n(self) -> int:
        return int(self.poses.shape[0])

    def reason(self, i: int) -> str | None:
        """Why pose ``i`` has no solution (None when it has some, or a family)."""
        if self.bounds[i + 1] > self.bounds[i] or self.families.get(i):
            return None
        if self.empty_reason is not None:
            return self.empty_reason
        return no_solution_reason(int(self.n_reachable[i]))

    def solutions(self, i: int, copy: bool = True) -> Solutions:
        """The :class:`Solutions` of pose ``i``: arrays copied (the block stays as it is), or views of the block's
        (``copy=False``, for a block made for this one result)."""
        s, e = int(self.bounds[i]), int(self.bounds[i + 1])
        take = np.copy if copy else np.asarray
        return Solutions(
            q=take(self.q[s:e]),
            error=take(self.error[s:e]),
            error_geodesic=take(self.error_geodesic[s:e]),
            within_limits=take(self.within_limits[s:e]),
            multiplicity=take(self.multiplicity[s:e]),
            families=self.families.get(i, ()),
            reason=self.reason(i),
            pose=take(self.poses[i]),
            robot=self.robot,
        )

    def __iter__(self) -> Iterator[Solutions]:
        return (self.solutions(i) for i in range(self.n))


class SolutionBatch(Sequence[Solutions]):
    """The solutions of a batch of ``N`` poses (what ``solve_many`` returns).

    A sequence of :class:`Solutions` (``len``, indexing, slicing, iteration; each built when asked for), and
    the same data in columns, every pose's solutions stacked (``K`` rows in all):

    * ``offsets (N + 1,)``: pose ``i``'s solutions are rows ``offsets[i]:offsets[i + 1]``; ``counts (N,)``;
    * ``pose_index (K,)``: the pose of each row;
    * ``q (K, n)``, ``error (K,)``, ``error_geodesic (K,)``, ``within_limits (K,)``, ``multiplicity (K,)``: as in
      :class:`Solutions`;
    * ``n_reachable (N,)``: each pose's solutions before the joint limits were applied;
    * ``families``: ``{pose index: families}`` for the few poses that have self-motion families;
    * ``reason(i)``: why pose ``i`` has no solution (None if it has some).
    """

    def __init__(self, robot: Robot, blocks: Sequence[Block]) -> None:
        self.robot = robot
        self._blocks = list(blocks)
        self._starts = np.concatenate([[0], np.cumsum([b.n for b in self._blocks])]).astype(np.intp)

    def __len__(self) -> int:
        return int(self._starts[-1])

    @property
    def blocks(self) -> list[Block]:
        """The solver's chunks, in order (each a :class:`Block` of consecutive poses)."""
        return list(self._blocks)

    def _locate(self, i: int) -> tuple[Block, int]:
        n = len(self)
        if not -n <= i < n:
            raise IndexError(f"pose index {i} out of range for a batch of {n} poses")
        i %= n
        k = bisect.bisect_right(self._starts, i) - 1
        return self._blocks[k], i - int(self._starts[k])

    @overload
    def __getitem__(self, i: int) -> Solutions: ...

    @overload
    def __getitem__(self, i: slice) -> list[Solutions]: ...

    def __getitem__(self, i: int | slice) -> Solutions | list[Solutions]:
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        block, j = self._locate(operator.index(i))
        return block.solutions(j)

    def __iter__(self) -> Iterator[Solutions]:
        for block in self._blocks:
            yield from block

    def __repr__(self) -> str:
        return f"SolutionBatch({len(self)} poses, {int(self.offsets[-1])} solutions)"

    def __eq__(self, other: object) -> bool:
        """Element by element with a list or tuple (an empty batch equals ``[]``). :class:`Solutions` compare by
        identity and a batch builds them anew on each access, so a non-empty batch equals no list, and two batches
        are equal only if they are the same object."""
        if isinstance(other, SolutionBatch):
            return other is self
        if isinstance(other, list | tuple):
            return len(other) == len(self) and all(a == b for a, b in zip(self, other, strict=True))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # mutable-sequence semantics, as a list

    def reason(self, i: int) -> str | None:
        """Why pose ``i`` has no solution (None when it has some, or a family)."""
        block, j = self._locate(operator.index(i))
        return block.reason(j)

    def _stack(self, name: str, shape: tuple[int, ...], dtype: type) -> NDArray:
        parts = [getattr(b, name) for b in self._blocks]
        return np.concatenate(parts) if parts else np.zeros(shape, dtype=dtype)

    @cached_property
    def offsets(self) -> NDArray[np.intp]:
        counts = self.counts
        return np.concatenate([[0], np.cumsum(counts)]).astype(np.intp)

    @cached_property
    def counts(self) -> NDArray[np.intp]:
        if not self._blocks:
            return np.zeros(0, dtype=np.intp)
        return np.concatenate([np.diff(b.bounds) for b in self._blocks]).astype(np.intp)

    @cached_property
    def pose_index(self) -> NDArray[np.intp]:
        return np.repeat(np.arange(len(self)), self.counts).astype(np.intp)

    @cached_property
    def q(self) -> Array:
        return self._stack("q", (0, self.robot.n_joints), np.float64)

    @cached_property
    def error(self) -> Array:
        return self._stack("error", (0,), np.float64)

    @cached_property
    def error_geodesic(self) -> Array:
        return self._stack("error_geodesic", (0,), np.float64)

    @cached_property
    def within_limits(self) -> NDArray[np.bool_]:
        return self._stack("within_limits", (0,), np.bool_)

    @cached_property
    def multiplicity(self) -> NDArray[np.intp]:
        return self._stack("multiplicity", (0,), np.intp)

    @cached_property
    def n_reachable(self) -> NDArray[np.intp]:
        """``(N,)`` each pose's solutions before the joint limits were applied (``counts`` is after)."""
        return self._stack("n_reachable", (0,), np.intp).astype(np.intp)

    @cached_property
    def families(self) -> dict[int, tuple[Family, ...]]:
        out: dict[int, tuple[Family, ...]] = {}
        for start, block in zip(self._starts, self._blocks, strict=False):
            out.update({int(start) + i: f for i, f in block.families.items() if f})
        return out
