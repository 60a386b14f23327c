"""The on-disk solution store: a :class:`~sweepik.results.SolutionBatch` written chunk by chunk, read back whole.

Format: **Zarr** (version 3, a directory). The solutions of a chunk of poses are a handful of numeric columns
of one dtype each (configurations ``(K, n)``, errors ``(K,)``, offsets ``(n + 1,)``, ...), written once and read
back whole: exactly what Zarr stores, one array per column, compressed, readable from any language with a Zarr
reader (zarr-python, TensorStore, zarr-java, ...). Parquet would fit a table of rows, but our rows nest
(``q`` is ``(K, n)``), the pose axis and the solution axis have different lengths, and a Parquet file is written
whole by one writer; a Zarr group gets one sub-group per chunk, written independently, in any order, and
replaced as a unit on resume.

Layout (``STORE_FORMAT`` 1)::

    store.zarr/                      root group; attributes:
        sweepik_store = 1              format version
        robot         = {...}          the Robot's exact content (JSON, floats exact: rebuilt bit for bit)
        robot_toml    = "..."          the same robot as a robot file (for people; not read back)
        options       = {...}          the solver options (reduction, free_joint, strategy, limits, n_samples, locked)
        n_poses, chunk_size, n_chunks  chunk k holds poses [k * chunk_size, min((k + 1) * chunk_size, n_poses))
        complete      = false / true   written last, atomically: true only once every chunk is stored
        summary       = {...}          with complete: poses, solutions, unreachable, out of limits, families
      chunks/00000000/ ...             one group per chunk; arrays:
          poses (n, 4, 4) float64, bounds (n + 1,) int64 (pose i owns rows bounds[i]:bounds[i + 1]),
          q (K, n_joints) float64, error (K,) float64 (the paper's J), error_geodesic (K,) float64,
          within_limits (K,) bool, multiplicity (K,) int64, n_reachable (n,) int64;
        attributes (the last write of a chunk, atomic): done = true, start, n, poses_sha256, empty_reason,
          families (below), stats (the chunk's part of the summary).

Self-motion families are stored as JSON records ``{pose, free_joint, interval, branch, chain_pose, reduction,
reduction_free_joint, held}``. A :class:`~sweepik.results.Family` also holds the reduction object that
generates its members; it is not pickled into the store (a store must not run code when read): on load the
reduction is rebuilt from the robot and the stored options, exactly as the solve built it (the solve's
reduction, or its fallback, named by ``reduction``), so ``Family.at`` gives the same members. A continuum the solve
traced (``reduction`` "traced", :mod:`sweepik.engine.continuation`) also stores its nodes ``traced = {theta, q, tol}``,
from
which its members are rebuilt.

The robot is stored as its exact content, not only as a robot file: ``robot_to_toml`` writes angles in degrees,
whose round trip can move a float by one unit in the last place, and a robot one ulp away is another robot (other
reductions, other rounding). JSON keeps every float exactly (Python writes the shortest repr that reads back).

Atomicity: Zarr's local store writes each file to a temporary name and renames it. A chunk is stored when its
``done`` attribute is (written after its arrays); the store is complete when the root's ``complete`` is (written
after every chunk). An interrupted run leaves ``complete = false`` and :func:`load_solutions` refuses it
(:class:`StoreError`); a run with ``resume`` rewrites only the chunks not ``done``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import os
import shutil
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from sweepik.engine.continuation import Traced
from sweepik.engine.families import certified_members
from sweepik.errors import StoreError, SweepikError
from sweepik.model.robot import Joint, Robot
from sweepik.results import Block, Family, SolutionBatch

if TYPE_CHECKING:
    from sweepik.reductions import Reduction

__all__ = ["StoreError", "load_solutions", "StoreWriter", "STORE_FORMAT"]

#: Version of the store layout (root attribute ``sweepik_store``).
STORE_FORMAT = 1
#: Name of the group holding one sub-group per chunk.
CHUNKS = "chunks"

Array = NDArray[np.float64]


def _zarr() -> Any:
    try:
        import zarr
    except ImportError as exc:  # pragma: no cover - depends on the environment
        raise SweepikError("the solution store needs zarr: pip install 'sweepik[dask]'") from exc
    return zarr


def _codec() -> Any:
    """The columns' compressor: Blosc (LZ4, byte shuffle). Solutions are mostly mantissa bits and compress little
    whatever the codec (x1.2 here, x1.45 with Zarr's default Zstandard); LZ4 costs almost nothing next to writing
    the bytes, where Zstandard doubled the client's time per chunk (~80 against ~40 ms for 16,384 C-Arm poses),
    time taken from the workers on a machine whose cores they use. Any Zarr reader decodes Blosc."""
    from zarr.codecs import BloscCodec

    return BloscCodec(cname="lz4", clevel=5, shuffle="shuffle")


# --------------------------------------------------------------------------------------------------
# Robot and options as exact JSON
# --------------------------------------------------------------------------------------------------


def robot_to_json(robot: Robot) -> dict[str, Any]:
    """The content of ``robot`` as JSON-able values (floats exact), read back by :func:`robot_from_json`."""
    return {
        "name": robot.name,
        "joints": [
            {
                "type": j.type,
                "a": j.a,
                "alpha": j.alpha,
                "d": j.d,
                "theta": j.theta,
                "lower": j.lower,
                "upper": j.upper,
                "name": j.name,
                "origin": None if j.origin is None else [list(row) for row in j.origin],
                "axis": list(j.axis),
                "mass": j.mass,
                "com": list(j.com),
            }
            for j in robot.joints
        ],
        "dh_convention": robot.dh_convention,
        "T_world_base": robot.T_world_base.tolist(),
        "T_flange_tool": robot.T_flange_tool.tolist(),
        "length_unit": robot.length_unit,
        "default_reduction": robot.default_reduction,
        "description": robot.description,
        "gravity": list(robot.gravity),
    }


def robot_from_json(data: Mapping[str, Any]) -> Robot:
    """The :class:`Robot` written by :func:`robot_to_json` (equal to it: same content, same hash)."""
    joints = []
    for jd in data["joints"]:
        origin = None if jd["origin"] is None else tuple(tuple(float(v) for v in row) for row in jd["origin"])
        fields = {k: jd[k] for k in ("type", "a", "alpha", "d", "theta", "lower", "upper", "name")}
        mass = {"mass": jd.get("mass", 0.0), "com": tuple(jd.get("com", (0.0, 0.0, 0.0)))}
        joints.append(Joint(**fields, origin=origin, axis=tuple(jd["axis"]), **mass))
    return Robot(
        name=data["name"],
        joints=tuple(joints),
        dh_convention=data["dh_convention"],
        T_world_base=np.array(data["T_world_base"], dtype=np.float64),
        T_flange_tool=np.array(data["T_flange_tool"], dtype=np.float64),
        length_unit=data["length_unit"],
        default_reduction=data["default_reduction"],
        description=data["description"],
        gravity=tuple(data.get("gravity", (0.0, 0.0, -1.0))),
    )


def options_to_json(options: Mapping[str, Any]) -> dict[str, Any]:
    """Solver options (checked ones: see ``distributed._checked_options``) as JSON-able values; ``locked`` as a
    list of ``[joint, value]`` pairs (a joint named or numbered, kept as given)."""
    out = dict(options)
    locked = out.get("locked")
    out["locked"] = None if not locked else [[k, float(v)] for k, v in locked.items()]
    return json.loads(json.dumps(out))


def options_from_json(data: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(data)
    out["locked"] = None if not out.get("locked") else {k: v for k, v in out["locked"]}
    return out


def poses_digest(poses: Array) -> str:
    """SHA-256 of poses ``(n, 4, 4)`` as float64 (how a resumed run recognises the poses of a stored chunk)."""
    return hashlib.sha256(np.ascontiguousarray(poses, dtype=np.float64).tobytes()).hexdigest()


# --------------------------------------------------------------------------------------------------
# Families
# --------------------------------------------------------------------------------------------------


def _family_record(i: int, fam: Family) -> dict[str, Any]:
    rec = {
        "pose": int(i),
        "free_joint": int(fam.free_joint),
        "interval": [float(fam.interval[0]), float(fam.interval[1])],
        "branch": int(fam.branch),
        "chain_pose": np.asarray(fam.chain_pose, dtype=np.float64).reshape(16).tolist(),
        "reduction": fam.reduction.name,
        "reduction_free_joint": int(fam.reduction.free_joint),
        "held": fam.held is not None,
    }
    red = fam.reduction
    if isinstance(red, Traced):  # a traced continuum: its nodes (data, not code) generate its members
        theta, q = red.nodes[fam.branch]
        rec["traced"] = {"theta": theta.tolist(), "q": q.tolist(), "tol": float(red.tol)}
    return rec


class _FamilyBuilder:
    """Rebuilds stored families: the reductions the solve used (its own and its fallback), from robot + options."""

    def __init__(self, robot: Robot, options: Mapping[str, Any]) -> None:
        self.robot, self.options = robot, options
        self._candidates: list[Reduction] | None = None

    def candidates(self) -> list[Reduction]:
        if self._candidates is None:
            from sweepik.reductions import get_reduction
            from sweepik.solving import held_joints, prepare

            o = self.options
            self.held = held_joints(self.robot, o["locked"])
            arm = self.robot if self.held is None else self.held.arm
            empty = np.zeros((0, 4, 4))
            red = prepare(
                arm, empty, o["reduction"], o["strategy"], o["limits"], o["n_samples"], 1, o["free_joint"], self.held
            )[0]
            self._candidates = [red]
            if red.fallback is not None:
                self._candidates.append(get_reduction(arm, red.fallback))
        return self._candidates

    def family(self, rec: Mapping[str, Any], where: str) -> Family:
        candidates = self.candidates()  # (also the held joints)
        red: Reduction
        if "traced" in rec:  # (its nodes, as the solve traced them)
            t = rec["traced"]
            nodes = {int(rec["branch"]): (np.array(t["theta"], dtype=np.float64), np.array(t["q"], dtype=np.float64))}
            arm = self.robot if self.held is None else self.held.arm
            red = Traced(arm, int(rec["reduction_free_joint"]), nodes, float(t["tol"]))
        else:
            for red in candidates:
                if red.name == rec["reduction"] and red.free_joint == rec["reduction_free_joint"]:
                    break
            else:
                raise StoreError(
                    f"{where}: a family was generated by reduction {rec['reduction']!r} (theta* = joint "
                    f"{rec['reduction_free_joint']}), which the stored robot and options do not give"
                )
        return Family(
            free_joint=int(rec["free_joint"]),
            interval=(float(rec["interval"][0]), float(rec["interval"][1])),
            reduction=red,
            chain_pose=np.array(rec["chain_pose"], dtype=np.float64).reshape(4, 4),
            branch=int(rec["branch"]),
            held=self.held if rec["held"] else None,
            members=certified_members,
        )


# --------------------------------------------------------------------------------------------------
# Writing
# --------------------------------------------------------------------------------------------------


def chunk_stats(block: Block) -> dict[str, int]:
    """A chunk's part of the summary: poses, solutions, poses with none (unreachable / only out of the joint
    limits) and poses with self-motion families."""
    counts = np.diff(block.bounds)
    with_family = np.zeros(block.n, dtype=bool)
    with_family[[i for i, f in block.families.items() if f]] = True
    empty = (counts == 0) & ~with_family
    return {
        "poses": block.n,
        "solutions": int(counts.sum()),
        "unreachable": int(np.sum(empty & (block.n_reachable == 0))),
        "out_of_limits": int(np.sum(empty & (block.n_reachable > 0))),
        "families": int(with_family.sum()),
    }


def _chunk_name(k: int) -> str:
    return f"{k:08d}"


class StoreWriter:
    """Writes a store chunk by chunk (one writer: the process that collects the chunks' results).

    ``StoreWriter(path, robot, options, n_poses, chunk_size, resume)`` creates the store, or with ``resume``
    opens the one there (StoreError if it was written for another robot, other options, another number of poses
    or another chunk size); without ``resume`` an existing path is refused. :meth:`done` lists the chunks stored,
    :meth:`check_poses` compares a stored chunk's poses with the ones given now, :meth:`write` stores a chunk,
    :meth:`finish` marks the store complete (only when every chunk is stored).
    """

    def __init__(
        self,
        path: str | os.PathLike[str],
        robot: Robot,
        options: Mapping[str, Any],
        n_poses: int,
        chunk_size: int,
        resume: bool = False,
    ) -> None:
        zarr = _zarr()
        self.path = Path(path)
        self.robot = robot
        self.n_poses, self.chunk_size = int(n_poses), int(chunk_size)
        self.n_chunks = -(-self.n_poses // self.chunk_size)
        opts = options_to_json(options)
        head = {
            "sweepik_store": STORE_FORMAT,
            "robot": robot_to_json(robot),
            "options": opts,
            "n_poses": self.n_poses,
            "chunk_size": self.chunk_size,
            "n_chunks": self.n_chunks,
        }
        if self.path.exists() or self.path.is_symlink():
            if not resume:
                raise StoreError(f"{self.path}: already exists; resume it (resume=True, --resume) or give a new path")
            self.root = _open_root(self.path, "r+")
            attrs = dict(self.root.attrs)
            from sweepik import __version__

            if attrs.get("sweepik_version") != __version__:
                raise StoreError(
                    f"{self.path}: cannot resume: the store was written by sweepik {attrs.get('sweepik_version')}, "
                    f"this is {__version__} (its solutions could differ): solve into a new store"
                )
            for key, what in (
                ("robot", "robot"),
                ("options", "solver options"),
                ("n_poses", "number of poses"),
                ("chunk_size", "chunk size"),
            ):
                if attrs.get(key) != head[key]:
                    raise StoreError(
                        f"{self.path}: cannot resume: the store was written with another {what} "
                        f"({_difference(attrs.get(key), head[key])})"
                    )
            _take_lock(self.path)
            _remove_partial_files(self.path)
            self.chunks = self.root.require_group(CHUNKS)
        else:
            if not self.path.parent.is_dir():
                raise StoreError(
                    f"{self.path}: cannot create the store: directory {str(self.path.parent)!r} is missing"
                )
            from sweepik import __version__
            from sweepik.io.robot_file import robot_to_toml

            attrs = {**head, "robot_toml": robot_to_toml(robot), "sweepik_version": __version__, "complete": False}
            # the root group is born with its attributes (one write): a reader never sees it without them
            self.root = zarr.create_group(str(self.path), overwrite=False, attributes=attrs, zarr_format=3)
            _take_lock(self.path)
            self.chunks = self.root.create_group(CHUNKS)

    @property
    def complete(self) -> bool:
        return bool(self.root.attrs.get("complete", False))

    def span(self, k: int) -> tuple[int, int]:
        """Poses ``[start, stop)`` of chunk ``k``."""
        start = k * self.chunk_size
        return start, min(start + self.chunk_size, self.n_poses)

    def done(self) -> dict[int, dict[str, Any]]:
        """Stored chunks: index -> its attributes (``done`` set: every array written)."""
        out: dict[int, dict[str, Any]] = {}
        for name, group in _groups(self.chunks):
            attrs = dict(group.attrs)
            if attrs.get("done") and name.isdecimal() and int(name) < self.n_chunks:
                out[int(name)] = attrs
        return out

    def check_poses(self, k: int, attrs: Mapping[str, Any], digest: str) -> None:
        """StoreError if stored chunk ``k`` (its ``attrs``) was solved for other poses than those of ``digest``."""
        if attrs.get("poses_sha256") != digest:
            start, stop = self.span(k)
            raise StoreError(
                f"{self.path}: cannot resume: the poses [{start}:{stop}] differ from the ones stored (another pose "
                "file, or the same file changed)"
            )

    def write(self, k: int, block: Block, digest: str | None = None) -> dict[str, int]:
        """Store chunk ``k`` (its arrays, then its ``done`` attribute); returns its stats."""
        start, stop = self.span(k)
        if block.n != stop - start:
            raise StoreError(f"{self.path}: chunk {k} holds {block.n} poses, expected {stop - start}")
        g = self.chunks.create_group(_chunk_name(k), overwrite=True)
        n_joints = self.robot.n_joints
        columns: dict[str, NDArray[Any]] = {
            "poses": np.asarray(block.poses, dtype=np.float64),
            "bounds": np.asarray(block.bounds, dtype=np.int64),
            "q": np.asarray(block.q, dtype=np.float64).reshape(-1, n_joints),
            "error": np.asarray(block.error, dtype=np.float64),
            "error_geodesic": np.asarray(block.error_geodesic, dtype=np.float64),
            "within_limits": np.asarray(block.within_limits, dtype=np.bool_),
            "multiplicity": np.asarray(block.multiplicity, dtype=np.int64),
            "n_reachable": np.asarray(block.n_reachable, dtype=np.int64),
        }
        codec = _codec()
        for name, data in columns.items():
            chunks = tuple(max(s, 1) for s in data.shape)  # one Zarr chunk per column (a zero-size one too)
            g.create_array(name, data=data, chunks=chunks, compressors=codec)
        families = [_family_record(i, f) for i, fams in sorted(block.families.items()) for f in fams]
        stats = chunk_stats(block)
        g.update_attributes(  # one write of the group's metadata, ``done`` with the rest
            {
                "start": start,
                "n": stop - start,
                "poses_sha256": digest if digest is not None else poses_digest(block.poses),
                "empty_reason": block.empty_reason,
                "families": families,
                "stats": stats,
                "done": True,
            }
        )
        return stats

    def discard(self) -> None:
        """Remove a store this writer created and wrote no chunk to (the run could not start): nothing is left
        behind that would make the same call, corrected, fail as 'already exists'."""
        if self.done():
            raise StoreError(f"{self.path}: holds solved chunks; not removed")  # pragma: no cover - caller's check
        shutil.rmtree(self.path, ignore_errors=True)

    def finish(self) -> dict[str, int]:
        """Mark the store complete (atomically, the last write); StoreError if a chunk is missing. The summary."""
        done = self.done()
        missing = [k for k in range(self.n_chunks) if k not in done]
        if missing:
            raise StoreError(f"{self.path}: {len(missing)} of {self.n_chunks} chunks are missing (first: {missing[0]})")
        summary = _sum_stats(done[k]["stats"] for k in range(self.n_chunks))
        self.root.update_attributes({"summary": summary, "complete": True})
        with contextlib.suppress(OSError):
            (self.path / LOCK_FILE).unlink()
        return summary


#: A run writing a store holds this file in it (process id and host), created exclusively: a second run on the
#: same store is refused while the first is alive (a stale one, of a process that is gone, is taken over).
LOCK_FILE = "sweepik.lock"


def _take_lock(path: Path) -> None:
    import socket

    lock = path / LOCK_FILE
    me = f"{os.getpid()} {socket.gethostname()}"
    for _ in range(3):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                pid_text, _, host = lock.read_text().partition(" ")
                pid = int(pid_text)
            except (OSError, ValueError):
                pid, host = -1, ""
            if host == socket.gethostname() and (pid == os.getpid() or not _alive(pid)):
                with contextlib.suppress(OSError):
                    lock.unlink()  # ours (an earlier call of this process) or a process that is gone
                continue
            raise StoreError(
                f"{path}: another run (process {pid} on {host or 'an unknown host'}) is writing this store; wait "
                f"for it to end, or delete {lock} if that run is gone"
            ) from None
        except OSError as exc:
            raise StoreError(f"{path}: cannot write the store: {exc}") from None
        with os.fdopen(fd, "w") as f:
            f.write(me)
        return
    raise StoreError(f"{path}: cannot take the store's lock {lock}")


def _alive(pid: int) -> bool:
    if pid <= 0:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def _difference(stored: Any, now: Any) -> str:
    """Where two JSON-like values first differ, readably (a robot's field, an option)."""
    if isinstance(stored, dict) and isinstance(now, dict):
        for key in sorted(set(stored) | set(now), key=str):
            if stored.get(key) != now.get(key):
                return f"{key}: {_short(stored.get(key))}, now {_short(now.get(key))}"
    return f"{_short(stored)}, now {_short(now)}"


def _groups(group: Any) -> list[tuple[str, Any]]:
    """The sub-groups of ``group`` (without Zarr's warning about a stray temporary file of an interrupted write)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=".*not recognized as a component of a Zarr hierarchy")
        return list(group.groups())


def _remove_partial_files(path: Path) -> None:
    """Delete the temporary files (``*.partial``) a write interrupted mid-file leaves in a local Zarr store."""
    for p in path.rglob("*.partial"):
        with contextlib.suppress(OSError):
            p.unlink()


def _sum_stats(parts: Any) -> dict[str, int]:
    total = {"poses": 0, "solutions": 0, "unreachable": 0, "out_of_limits": 0, "families": 0}
    for p in parts:
        for key in total:
            total[key] += int(p[key])
    return total


def _short(value: object, limit: int = 80) -> str:
    text = json.dumps(value, sort_keys=True)
    return text if len(text) <= limit else text[: limit - 3] + "..."


# --------------------------------------------------------------------------------------------------
# Reading
# --------------------------------------------------------------------------------------------------


def _open_root(path: Path, mode: str) -> Any:
    zarr = _zarr()
    if not path.is_dir():
        raise StoreError(f"{path}: no such solution store" if not path.exists() else f"{path}: not a solution store")
    try:
        root = zarr.open_group(str(path), mode=mode)
    except Exception as exc:  # zarr raises several types for a directory that is not a group
        raise StoreError(f"{path}: not a solution store ({type(exc).__name__}: {exc})") from None
    fmt = root.attrs.get("sweepik_store")
    if fmt != STORE_FORMAT:
        raise StoreError(
            f"{path}: not a sweepik solution store (format {fmt!r}, expected {STORE_FORMAT})"
            if fmt is not None
            else f"{path}: not a sweepik solution store (a Zarr group without sweepik's attributes)"
        )
    return root


def store_info(path: str | os.PathLike[str]) -> dict[str, Any]:
    """The root attributes of a store (robot, options, sizes, ``complete``, ``summary``) and ``stored``, the number
    of chunks stored; complete or not."""
    p = Path(path)
    root = _open_root(p, "r")
    info = dict(root.attrs)
    chunks = root[CHUNKS] if CHUNKS in root else None
    info["stored"] = 0 if chunks is None else sum(1 for _, g in _groups(chunks) if g.attrs.get("done"))
    return info


def load_solutions(path: str | os.PathLike[str]) -> SolutionBatch:
    """The :class:`~sweepik.results.SolutionBatch` stored at ``path`` by ``solve_dask(..., out=path)`` or
    ``sweepik solve --out``: the same poses, solutions (same order), errors, flags, multiplicities, reasons and
    self-motion families as ``solve_many`` gives for those poses, and the same robot (equal by value).

    Raises StoreError when ``path`` is not a sweepik store, is incomplete (an interrupted run: the message says how
    many chunks are stored; continue it with ``resume=True`` or ``--resume``), or is damaged.
    """
    p = Path(path)
    root = _open_root(p, "r")
    attrs = dict(root.attrs)
    if not attrs.get("complete"):
        info = store_info(p)
        raise StoreError(
            f"{p}: incomplete solution store ({info['stored']} of {attrs.get('n_chunks')} chunks stored, not marked "
            "complete): the run writing it was interrupted or is still going; continue it with "
            "solve_dask(..., out=path, resume=True) or 'sweepik solve ... --out PATH --resume'"
        )
    try:
        robot = robot_from_json(attrs["robot"])
        options = options_from_json(attrs["options"])
        n_chunks, chunk_size, n_poses = int(attrs["n_chunks"]), int(attrs["chunk_size"]), int(attrs["n_poses"])
    except (KeyError, TypeError, ValueError) as exc:
        raise StoreError(f"{p}: damaged solution store (root attributes: {exc})") from None
    builder = _FamilyBuilder(robot, options)
    chunks = root[CHUNKS]
    blocks = []
    for k in range(n_chunks):
        where = f"{p}: chunk {k}"
        try:
            g = chunks[_chunk_name(k)]
            ga = dict(g.attrs)
            cols = {name: g[name][...] for name in _COLUMNS}
        except (KeyError, FileNotFoundError) as exc:
            raise StoreError(f"{where} is missing or damaged ({exc})") from None
        n = int(ga["n"])
        if not ga.get("done") or n != min(chunk_size, n_poses - k * chunk_size) or cols["poses"].shape != (n, 4, 4):
            raise StoreError(f"{where} is damaged (not marked done, or holds the wrong number of poses)")
        families: dict[int, list[Family]] = {}
        for rec in ga["families"]:
            families.setdefault(int(rec["pose"]), []).append(builder.family(rec, where))
        blocks.append(
            Block(
                robot=robot,
                poses=cols["poses"].astype(np.float64),
                bounds=cols["bounds"].astype(np.intp),
                q=cols["q"].astype(np.float64),
                error=cols["error"].astype(np.float64),
                error_geodesic=cols["error_geodesic"].astype(np.float64),
                within_limits=cols["within_limits"].astype(np.bool_),
                multiplicity=cols["multiplicity"].astype(np.intp),
                families={i: tuple(f) for i, f in families.items()},
                n_reachable=cols["n_reachable"].astype(np.intp),
                empty_reason=ga.get("empty_reason"),
            )
        )
    return SolutionBatch(robot, blocks)


_COLUMNS = ("poses", "bounds", "q", "error", "error_geodesic", "within_limits", "multiplicity", "n_reachable")


def merge_blocks(blocks: list[Block]) -> Block:
    """One block holding the poses of ``blocks`` (consecutive chunks of one solve) in order."""
    if len(blocks) == 1:
        return blocks[0]
    first = blocks[0]
    starts = np.cumsum([0] + [b.n for b in blocks])
    rows = np.cumsum([0] + [int(b.bounds[-1]) for b in blocks])
    bounds = np.concatenate([[0]] + [b.bounds[1:] + r for b, r in zip(blocks, rows, strict=False)])
    families = {int(s) + i: f for b, s in zip(blocks, starts, strict=False) for i, f in b.families.items()}
    return dataclasses.replace(
        first,
        poses=np.concatenate([b.poses for b in blocks]),
        bounds=bounds.astype(np.intp),
        q=np.concatenate([b.q for b in blocks]),
        error=np.concatenate([b.error for b in blocks]),
        error_geodesic=np.concatenate([b.error_geodesic for b in blocks]),
        within_limits=np.concatenate([b.within_limits for b in blocks]),
        multiplicity=np.concatenate([b.multiplicity for b in blocks]),
        families=families,
        n_reachable=np.concatenate([b.n_reachable for b in blocks]),
    )
