"""The public API: every name in ``sweepik.__all__`` exists, and the docstring examples run."""

from __future__ import annotations

import doctest
import importlib
import pkgutil
from importlib.metadata import version

import pytest

import sweepik


def test_all_names_importable() -> None:
    assert sweepik.__all__, "sweepik.__all__ is empty"
    missing = [name for name in sweepik.__all__ if not hasattr(sweepik, name)]
    assert not missing, f"names in sweepik.__all__ but not in sweepik: {missing}"
    for name in sweepik.__all__:
        exec(f"from sweepik import {name}", {})  # the form users write


def test_all_has_no_duplicates() -> None:
    dupes = sorted({n for n in sweepik.__all__ if sweepik.__all__.count(n) > 1})
    assert not dupes, f"duplicated in sweepik.__all__: {dupes}"


def test_contract_names_are_public() -> None:
    # Named in DESIGN.md's public surface; extend, never rename.
    for name in ("load_robot", "Robot", "Joint", "SweepikError"):
        assert name in sweepik.__all__


def test_import_leaves_the_tools_a_solve_does_not_need_unloaded() -> None:
    import subprocess
    import sys

    lazy = ("sweepik.experiments.design", "sweepik.distributed", "sweepik.io.urdf", "sweepik.experiments.workspace")
    code = f"import sys, sweepik; print([m for m in {lazy!r} if m in sys.modules])"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
    assert sweepik.solve_dask.__module__ == "sweepik.distributed"  # and they load on first use


def test_dir_is_all_and_dunders() -> None:
    """``dir(sweepik)`` lists the public names and the module's dunders, nothing of the engine (its subpackages are
    imported by name: ``sweepik.engine``, ``sweepik.reductions``, ...), and every error lives in ``sweepik.errors``."""
    extra = [n for n in dir(sweepik) if n not in sweepik.__all__ and not (n.startswith("__") and n.endswith("__"))]
    assert extra == []
    assert set(sweepik.__all__) <= set(dir(sweepik))
    errors = importlib.import_module("sweepik.errors")
    for name in sweepik.__all__:
        obj = getattr(sweepik, name)
        if isinstance(obj, type) and issubclass(obj, Exception):
            assert issubclass(obj, sweepik.SweepikError) and obj.__module__ == "sweepik.errors", name
            assert name in errors.__all__


@pytest.mark.parametrize(
    ("name", "home"),
    [("CArmD1", "sweepik.reductions"), ("get_reduction", "sweepik.reductions"), ("STRATEGIES", "sweepik.solving")],
)
def test_engine_names_once_public_still_work_with_a_warning(name: str, home: str) -> None:
    """Names ``sweepik`` exported before its packages were layered are served from their package, with a
    DeprecationWarning that says where; an unknown name is an AttributeError."""
    with pytest.warns(DeprecationWarning, match=home):
        obj = getattr(sweepik, name)
    assert obj is getattr(importlib.import_module(home), name)
    with pytest.raises(AttributeError):
        sweepik.no_such_name  # noqa: B018


def test_version_matches_metadata() -> None:
    assert sweepik.__version__ == version("sweepik")


# Every module of the package (``__main__`` excluded: importing it would run the command).
MODULES = sorted(
    m.name for m in pkgutil.walk_packages(sweepik.__path__, prefix="sweepik.") if not m.name.endswith("__main__")
)


@pytest.mark.parametrize("module_name", MODULES)
def test_docstring_examples_run(module_name: str) -> None:
    if module_name == "sweepik.experiments.plot":
        pytest.importorskip("matplotlib")
    module = importlib.import_module(module_name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE, verbose=False)
    assert result.failed == 0, f"{result.failed} of {result.attempted} doctest examples failed in {module_name}"
