"""sweepik: every inverse-kinematics solution of 6-DOF serial arms, by a one-joint sweep.

Public API: robots (``load_robot`` for bundled arms, TOML robot files and URDF; ``Robot``, ``Joint``;
``read_urdf``, ``urdf_text``, ``robot_to_toml``), pose helpers and error metrics, and the solvers ``solve``,
``solve_many`` and ``iter_solve`` (``locked=`` for arms with more than six joints), ``solve_dask`` (on a Dask
cluster, optionally into an on-disk store) and ``load_solutions``; design tools: ``compare_designs`` (what
``sweepik design`` runs), ``gravity_torques`` (statics) and ``workspace_volume``. See the README and
docs/conventions.md for units and conventions.
"""

from typing import TYPE_CHECKING as _TYPE_CHECKING

from sweepik import plan_check as _plan_check  # registers the automatic decomposition's check
from sweepik.errors import (
    InvalidPoseError,
    LockedJointError,
    MjcfError,
    NonFiniteError,
    NoReductionError,
    PoseFileError,
    RobotDefinitionError,
    RobotFileError,
    SearchOverflowError,
    ShapeError,
    StoreError,
    SweepikError,
    UnknownOptionError,
    UnknownRobotError,
    UrdfError,
)
from sweepik.experiments.statics import gravity_torques
from sweepik.io.robot_file import bundled_robots, load_robot, robot_from_dict, robot_to_toml
from sweepik.io.store import load_solutions
from sweepik.model.pose import (
    matrix_from_zyz,
    pose_error_geodesic,
    pose_error_paper,
    pose_from_xyz_zyz,
    rotation_angle,
    wrap_angle,
    xyz_zyz_from_pose,
    zyz_from_matrix,
)
from sweepik.model.robot import Joint, Robot
from sweepik.reductions.analysis import analyze
from sweepik.results import Family, SolutionBatch, Solutions
from sweepik.solving import iter_solve, solve, solve_many

if _TYPE_CHECKING:
    from sweepik.distributed import solve_dask
    from sweepik.experiments.design import DesignComparison, compare_designs
    from sweepik.experiments.workspace import WorkspaceVolume, workspace_volume
    from sweepik.io.mjcf import read_mjcf
    from sweepik.io.urdf import read_urdf, urdf_text
    from sweepik.viewer.app import view

    __version__: str

del _plan_check

#: Names imported on first use (PEP 562): a solve should not pay for the design tools, Dask's entry point, the URDF
#: reader or the package metadata (~100 ms of ``import sweepik`` together).
_LAZY = {
    "compare_designs": "sweepik.experiments.design",
    "DesignComparison": "sweepik.experiments.design",
    "solve_dask": "sweepik.distributed",
    "read_urdf": "sweepik.io.urdf",
    "read_mjcf": "sweepik.io.mjcf",
    "view": "sweepik.viewer.app",
    "urdf_text": "sweepik.io.urdf",
    "workspace_volume": "sweepik.experiments.workspace",
    "WorkspaceVolume": "sweepik.experiments.workspace",
}
#: Engine names that ``sweepik`` exported before the packages were layered (issue 36): still served, with a
#: ``DeprecationWarning`` naming where each now lives; not in ``__all__`` nor ``dir(sweepik)``.
_MOVED = {
    "STRATEGIES": "sweepik.solving",
    "Reduction": "sweepik.reductions",
    "CArmD1": "sweepik.reductions",
    "CArmTheta2": "sweepik.reductions",
    "REDUCTIONS": "sweepik.reductions",
    "get_reduction": "sweepik.reductions",
    "GeometricReduction": "sweepik.reductions",
    "Plan": "sweepik.reductions",
}


if not _TYPE_CHECKING:  # (hidden from type checkers: a module __getattr__ would make every misspelt name valid)

    def __getattr__(name: str) -> object:
        import importlib

        if name == "__version__":
            from importlib.metadata import PackageNotFoundError, version

            try:
                value: object = version("sweepik")
            except PackageNotFoundError:  # pragma: no cover - running from a source tree without install
                value = "0.0.0"
        elif name in _LAZY:
            value = getattr(importlib.import_module(_LAZY[name]), name)
        elif name in _MOVED:
            import warnings

            warnings.warn(
                f"sweepik.{name} is deprecated: import it from {_MOVED[name]}", DeprecationWarning, stacklevel=2
            )
            return getattr(importlib.import_module(_MOVED[name]), name)
        else:
            raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
        globals()[name] = value
        return value


def __dir__() -> list[str]:
    """The public names (``__all__``) and the module's dunders: the subpackages are reached by importing them."""
    return sorted(set(__all__) | {k for k in globals() if k.startswith("__") and k.endswith("__")})


__all__ = [
    "__version__",
    # robots
    "Joint",
    "Robot",
    "load_robot",
    "bundled_robots",
    "robot_from_dict",
    "robot_to_toml",
    "read_urdf",
    "read_mjcf",
    "urdf_text",
    # solving
    "solve",
    "solve_many",
    "iter_solve",
    "solve_dask",
    "load_solutions",
    "analyze",
    "view",
    # results
    "Solutions",
    "SolutionBatch",
    "Family",
    # poses
    "zyz_from_matrix",
    "matrix_from_zyz",
    "pose_from_xyz_zyz",
    "xyz_zyz_from_pose",
    "wrap_angle",
    "rotation_angle",
    "pose_error_paper",
    "pose_error_geodesic",
    # design tools
    "compare_designs",
    "DesignComparison",
    "gravity_torques",
    "workspace_volume",
    "WorkspaceVolume",
    # errors
    "SweepikError",
    "RobotDefinitionError",
    "RobotFileError",
    "UrdfError",
    "MjcfError",
    "UnknownRobotError",
    "ShapeError",
    "NonFiniteError",
    "InvalidPoseError",
    "UnknownOptionError",
    "PoseFileError",
    "LockedJointError",
    "NoReductionError",
    "SearchOverflowError",
    "StoreError",
]
