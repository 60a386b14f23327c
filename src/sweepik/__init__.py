"""sweepik: every inverse-kinematics solution of 6-DOF serial arms, by a one-joint sweep.

Public API: robots (``load_robot`` for bundled arms, TOML robot files and URDF; ``Robot``, ``Joint``;
``read_urdf``, ``urdf_text``, ``robot_to_toml``), pose helpers and error metrics, and the solvers ``solve``,
``solve_many`` and ``iter_solve`` (``locked=`` for arms with more than six joints), ``solve_dask`` (on a Dask
cluster, optionally into an on-disk store) and ``load_solutions``; design tools: ``compare_designs`` (what
``sweepik design`` runs), ``gravity_torques`` (statics) and ``workspace_volume``. See the README and
docs/conventions.md for units and conventions.
"""

from typing import TYPE_CHECKING, Any

from . import plan_check as _plan_check  # noqa: F401 (registers the automatic decomposition's check)
from .analysis import analyze
from .batch import SolutionBatch
from .errors import (
    InvalidPoseError,
    LockedJointError,
    NonFiniteError,
    NoReductionError,
    PoseFileError,
    RobotDefinitionError,
    RobotFileError,
    ShapeError,
    SweepikError,
    UnknownOptionError,
    UnknownRobotError,
    UrdfError,
)
from .pose import (
    matrix_from_zyz,
    pose_error_geodesic,
    pose_error_paper,
    pose_from_xyz_zyz,
    rotation_angle,
    wrap_angle,
    xyz_zyz_from_pose,
    zyz_from_matrix,
)
from .reductions import REDUCTIONS, CArmD1, CArmTheta2, GeometricReduction, Plan, Reduction, get_reduction
from .robot import Joint, Robot
from .robot_file import bundled_robots, load_robot, robot_from_dict, robot_to_toml
from .solutions import Family, Solutions
from .solver import STRATEGIES, iter_solve, solve, solve_many
from .statics import gravity_torques
from .store import StoreError, load_solutions

if TYPE_CHECKING:
    from .design import DesignComparison, compare_designs
    from .distributed import solve_dask
    from .urdf import read_urdf, urdf_text
    from .workspace import WorkspaceVolume, workspace_volume

    __version__: str

#: Names imported on first use (PEP 562): a solve should not pay for the design tools, Dask's entry point, the URDF
#: reader or the package metadata (~100 ms of ``import sweepik`` together).
_LAZY = {
    "compare_designs": "design",
    "DesignComparison": "design",
    "solve_dask": "distributed",
    "read_urdf": "urdf",
    "urdf_text": "urdf",
    "workspace_volume": "workspace",
    "WorkspaceVolume": "workspace",
}


if not TYPE_CHECKING:  # (hidden from type checkers: a module __getattr__ would make every misspelt name Any)

    def __getattr__(name: str) -> Any:
        if name == "__version__":
            from importlib.metadata import PackageNotFoundError, version

            try:
                value = version("sweepik")
            except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
                value = "0.0.0"
        elif name in _LAZY:
            import importlib

            value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        else:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
        globals()[name] = value
        return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | {"__version__"})


__all__ = [
    "__version__",
    "Joint",
    "Robot",
    "load_robot",
    "bundled_robots",
    "robot_from_dict",
    "robot_to_toml",
    "read_urdf",
    "urdf_text",
    "solve",
    "solve_many",
    "iter_solve",
    "solve_dask",
    "load_solutions",
    "Solutions",
    "SolutionBatch",
    "Family",
    "STRATEGIES",
    "Reduction",
    "CArmD1",
    "CArmTheta2",
    "REDUCTIONS",
    "get_reduction",
    "GeometricReduction",
    "Plan",
    "analyze",
    "compare_designs",
    "DesignComparison",
    "gravity_torques",
    "workspace_volume",
    "WorkspaceVolume",
    "zyz_from_matrix",
    "matrix_from_zyz",
    "pose_from_xyz_zyz",
    "xyz_zyz_from_pose",
    "wrap_angle",
    "rotation_angle",
    "pose_error_paper",
    "pose_error_geodesic",
    "SweepikError",
    "RobotDefinitionError",
    "RobotFileError",
    "UnknownRobotError",
    "ShapeError",
    "NonFiniteError",
    "InvalidPoseError",
    "UnknownOptionError",
    "PoseFileError",
    "NoReductionError",
    "LockedJointError",
    "UrdfError",
    "StoreError",
]
