"""Arms by the names other libraries give them: robot_descriptions and example-robot-data.

* **robot_descriptions** (``load_robot("ur10e_description")``, ``"panda_mj_description"``, or with the prefix
  ``"robot_descriptions:"``): the package's module for that name says which git repository holds the description
  and where in it the URDF or MJCF file lies. Importing that module clones the repository when it is not in
  robot_descriptions' cache (``~/.cache/robot_descriptions``, or ``$ROBOT_DESCRIPTIONS_CACHE``); sweepik never
  downloads: it reads the module's paths without running it and opens the file in the cache, or says that the name
  needs a download and how to get it. A description given only as xacro is rendered to URDF by robot_descriptions
  itself (with ``xacrodoc``, into its cache), once its repository is cached.
* **example-robot-data** (``load_robot("example-robot-data:ur5")``, or a bare name that no bundled arm has, such as
  ``"panda"`` or ``"z1"``): the URDFs of the installed ``example-robot-data`` wheel (its ``share`` folder), or of
  ``$EXAMPLE_ROBOT_DATA_MODEL_DIR``; names as its loaders use them.
"""

from __future__ import annotations

import ast
import os
from dataclasses import dataclass
from importlib import metadata, util
from pathlib import Path

from sweepik.errors import UnknownRobotError

__all__ = ["CatalogueEntry", "find_in_catalogues", "catalogue_names"]

RD_PREFIX = "robot_descriptions:"
ERD_PREFIX = "example-robot-data:"


@dataclass(frozen=True)
class CatalogueEntry:
    """Where a catalogue keeps an arm: its file, its format (``"urdf"`` or ``"mjcf"``), the chain's default tip
    link (None: the file's own default) and which catalogue and folder it comes from (for messages)."""

    path: Path
    format: str
    tip_link: str | None
    origin: str


#: example-robot-data's arm names (as its Python loaders give them): file under ``robots/`` and the chain's tip.
ERD_ARMS: dict[str, tuple[str, str | None]] = {
    "ur3": ("ur_description/urdf/ur3_robot.urdf", None),
    "ur3_limited": ("ur_description/urdf/ur3_joint_limited_robot.urdf", None),
    "ur3_gripper": ("ur_description/urdf/ur3_gripper.urdf", None),
    "ur5": ("ur_description/urdf/ur5_robot.urdf", None),
    "ur5_limited": ("ur_description/urdf/ur5_joint_limited_robot.urdf", None),
    "ur5_gripper": ("ur_description/urdf/ur5_gripper.urdf", None),
    "ur10": ("ur_description/urdf/ur10_robot.urdf", None),
    "ur10_limited": ("ur_description/urdf/ur10_joint_limited_robot.urdf", None),
    "panda": ("panda_description/urdf/panda.urdf", "panda_hand"),
    "panda_collision": ("panda_description/urdf/panda_collision.urdf", "panda_hand"),
    "kinova": ("kinova_description/robots/kinova.urdf", None),
    "z1": ("z1_description/urdf/z1.urdf", None),
    "xarm7": ("xarm_description/urdf/xarm7.urdf", None),
    "so_arm100": ("so_arm_description/urdf/so100.urdf", None),
    "so_arm101": ("so_arm_description/urdf/so101.urdf", None),
}


def _erd_root() -> Path | None:
    """example-robot-data's ``robots`` folder: ``$EXAMPLE_ROBOT_DATA_MODEL_DIR``, else the installed wheel's."""
    env = os.environ.get("EXAMPLE_ROBOT_DATA_MODEL_DIR")
    if env:
        return Path(env)
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        return None
    root = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    return root if root.is_dir() else None


def _erd_entry(name: str) -> CatalogueEntry | None:
    if name not in ERD_ARMS:
        return None
    root = _erd_root()
    rel, tip = ERD_ARMS[name]
    if root is None:
        raise UnknownRobotError(
            f"{name!r} is an example-robot-data arm, but that package is not installed: pip install example-robot-data"
        )
    return CatalogueEntry(root / rel, "urdf", tip, f"example-robot-data ({root})")


def _rd_module_file(name: str) -> Path | None:
    """The source of robot_descriptions' module ``name`` (not imported: importing it may clone a repository)."""
    if util.find_spec("robot_descriptions") is None:
        return None
    spec = util.find_spec(f"robot_descriptions.{name}") if name.isidentifier() else None
    return None if spec is None or spec.origin is None else Path(spec.origin)


def _rd_paths(source: Path) -> tuple[str | None, dict[str, list[str]]]:
    """From a robot_descriptions module's source: the repository it clones, and each ``*_PATH`` assignment as the
    path parts below that repository (a part naming another assignment is replaced by its parts)."""
    repo: str | None = None
    paths: dict[str, list[str]] = {}
    for node in ast.parse(source.read_text(encoding="utf-8")).body:
        target = node.targets[0] if isinstance(node, ast.Assign) else getattr(node, "target", None)
        value = getattr(node, "value", None)
        if isinstance(target, ast.Name) and isinstance(value, ast.Name) and value.id in paths:
            paths[target.id] = paths[value.id]  # (an alias: PACKAGE_PATH = REPOSITORY_PATH)
            continue
        if not isinstance(target, ast.Name) or not isinstance(value, ast.Call):
            continue
        args = value.args
        if target.id == "REPOSITORY_PATH" and args and isinstance(args[0], ast.Constant):
            repo, paths["REPOSITORY_PATH"] = str(args[0].value), []
        elif target.id.endswith("_PATH"):
            parts: list[str] = []
            for a in args:
                if isinstance(a, ast.Name) and a.id in paths:
                    parts += paths[a.id]
                elif isinstance(a, ast.Constant) and isinstance(a.value, str):
                    parts.append(a.value)
                else:
                    break
            else:
                paths[target.id] = parts
    return repo, paths


def _rd_entry(name: str) -> CatalogueEntry | None:
    source = _rd_module_file(name)
    if source is None:
        return None
    repo, paths = _rd_paths(source)
    from robot_descriptions._repositories import REPOSITORIES  # (data only: no clone)

    fmt, key = ("urdf", "URDF_PATH") if "URDF_PATH" in paths else ("mjcf", "MJCF_PATH")
    if repo not in REPOSITORIES or (key not in paths and "XACRO_PATH" not in paths):
        raise UnknownRobotError(f"robot_descriptions' {name!r} names no URDF, xacro or MJCF file sweepik can find")
    cache = Path(os.path.expanduser(os.environ.get("ROBOT_DESCRIPTIONS_CACHE", "~/.cache/robot_descriptions")))
    folder = cache / REPOSITORIES[repo].cache_path
    if not folder.is_dir():
        raise UnknownRobotError(
            f"{name!r} is a robot_descriptions name whose repository {repo!r} is not in its cache ({folder}): "
            f"loading it needs a download, which sweepik does not do; with network access, run once "
            f"python -c 'import robot_descriptions.{name}' (it clones {REPOSITORIES[repo].url})"
        )
    origin = f"robot_descriptions ({folder})"
    if key in paths:
        return CatalogueEntry(folder.joinpath(*paths[key]), fmt, None, origin)
    return CatalogueEntry(_rendered_xacro(name), "urdf", None, origin)


def _rendered_xacro(name: str) -> Path:
    """The URDF robot_descriptions renders from a cached xacro description (with ``xacrodoc``, into its cache)."""
    import importlib

    try:
        module = importlib.import_module(f"robot_descriptions.{name}")
        from robot_descriptions._xacro import get_description_path

        return Path(get_description_path(module, "urdf"))
    except ModuleNotFoundError as exc:
        raise UnknownRobotError(
            f"robot_descriptions' {name!r} is a xacro description; rendering it needs {exc.name!r}: "
            f"pip install {exc.name}"
        ) from None
    except Exception as exc:  # noqa: BLE001 - git, xacro and file errors of another package, reported as one
        raise UnknownRobotError(f"robot_descriptions could not render {name!r}: {type(exc).__name__}: {exc}") from None


def find_in_catalogues(name: str) -> CatalogueEntry | None:
    """The catalogue file of ``name`` (with or without a catalogue prefix), None when no catalogue knows it;
    UnknownRobotError when a catalogue knows it but its file cannot be had here (not installed, not cached)."""
    if name.startswith(RD_PREFIX):
        entry = _rd_entry(name[len(RD_PREFIX) :])
        if entry is None:
            raise UnknownRobotError(f"{name!r}: robot_descriptions is not installed or has no such description")
        return entry
    if name.startswith(ERD_PREFIX):
        entry = _erd_entry(name[len(ERD_PREFIX) :])
        if entry is None:
            known = ", ".join(sorted(ERD_ARMS))
            raise UnknownRobotError(f"{name!r}: example-robot-data arms known to sweepik: {known}")
        return entry
    return _erd_entry(name) or (_rd_entry(name) if name.endswith("_description") else None)


def catalogue_names() -> list[str]:
    """Names the catalogues offer here (for "did you mean"): example-robot-data's arms and, if installed,
    robot_descriptions' descriptions."""
    names = list(ERD_ARMS)
    if util.find_spec("robot_descriptions") is not None:
        folder = Path(str(util.find_spec("robot_descriptions").origin)).parent  # type: ignore[union-attr]
        names += sorted(p.stem for p in folder.glob("*_description.py"))
    return names
