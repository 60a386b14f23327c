"""The layout docs/architecture.md describes, measured from the source (ast only): no import cycles between modules
(function-local imports count), no function over 100 lines, at most 8 modules directly in ``src/sweepik``, and
imports that run downward: the model imports nothing above it, the subproblems only the model, the reductions
nothing of the engine but its thread runner and constants (a reduction never runs the sweep), the engine nothing
of the solver's public layer."""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

import sweepik

ROOT = Path(sweepik.__file__).parent


def _modules() -> dict[str, Path]:
    out = {}
    for p in ROOT.rglob("*.py"):
        parts = ("sweepik", *p.relative_to(ROOT).with_suffix("").parts)
        name = ".".join(parts[:-1] if parts[-1] == "__init__" else parts)
        out[name] = p
    return out


MODULES = _modules()


def _imports(name: str) -> set[str]:
    """The sweepik modules ``name`` imports (anywhere in it), each resolved to the module it names."""
    path = MODULES[name]
    is_pkg = path.name == "__init__.py"
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        targets: list[str] = []
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                pkg = name.split(".") if is_pkg else name.split(".")[:-1]
                base = ".".join(pkg[: len(pkg) - node.level + 1] + ([base] if base else []))
            targets = [f"{base}.{a.name}" for a in node.names] + [base]
        for t in targets:
            while t and t not in MODULES:
                t = t.rpartition(".")[0]
            if t and t != name and not (t == "sweepik" and name != "sweepik"):
                out.add(t)
                break
    return out


EDGES = {m: _imports(m) for m in MODULES}


def test_no_import_cycles() -> None:
    """Depth-first search for a module that reaches itself through the imports."""
    state: dict[str, int] = {}

    def visit(m: str, path: list[str]) -> None:
        state[m] = 1
        for n in EDGES[m]:
            if state.get(n) == 1:
                pytest.fail("import cycle: " + " -> ".join([*path[path.index(n) :], n]))
            if n not in state:
                visit(n, [*path, n])
        state[m] = 2

    for m in sorted(MODULES):
        if m not in state:
            visit(m, [m])


def test_functions_are_short_and_the_top_level_is_small() -> None:
    long = [
        f"{p.relative_to(ROOT)}:{n.lineno} {n.name}"
        for p in MODULES.values()
        for n in ast.walk(ast.parse(p.read_text()))
        if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef) and n.end_lineno - n.lineno + 1 > 100
    ]
    assert long == []
    flat = [p.name for p in ROOT.glob("*.py") if p.name not in ("__init__.py", "__main__.py")]
    assert len(flat) <= 8, flat


@pytest.mark.parametrize(
    ("package", "allowed"),
    [
        ("sweepik.model", {"sweepik.model", "sweepik.errors", "sweepik._jit"}),
        ("sweepik.subproblems", {"sweepik.subproblems", "sweepik._jit"}),
        (
            "sweepik.reductions",
            {
                "sweepik.reductions",
                "sweepik.subproblems",
                "sweepik.model",
                "sweepik.errors",
                "sweepik._jit",
                "sweepik.io.robot_file",
                "sweepik.engine.parallel",
                "sweepik.engine.settings",
            },
        ),
        (
            "sweepik.engine",
            {
                "sweepik.engine",
                "sweepik.reductions",
                "sweepik.subproblems",
                "sweepik.model",
                "sweepik.errors",
                "sweepik._jit",
                "sweepik.results",
            },
        ),
    ],
)
def test_imports_run_downward(package: str, allowed: set[str]) -> None:
    for m, deps in EDGES.items():
        if m == package or m.startswith(package + "."):
            up = sorted(d for d in deps if not any(d == a or d.startswith(a + ".") for a in allowed))
            assert up == [], f"{m} imports {up}"


def test_every_engine_module_has_its_test_file_and_no_numpy_twin_is_left() -> None:
    """Tests mirror the engine (``tests/test_<module>.py`` for each of its modules), and the NumPy references of
    compiled steps live in ``tests/oracles``, not in ``src``: no engine module switches to a NumPy path on a flag
    (``AVAILABLE``, ``SWEEPIK_DISABLE_NUMBA``)."""
    tests = Path(__file__).parent
    engine = sorted(n.rsplit(".", 1)[1] for n in MODULES if n.startswith("sweepik.engine.") and "__init__" not in n)
    assert [m for m in engine if not (tests / f"test_{m}.py").exists()] == []
    for name, path in MODULES.items():
        text = path.read_text()
        assert "SWEEPIK_DISABLE_NUMBA" not in text and "engine.sweep" not in text, name
        if name != "sweepik.reductions.lapack":  # (SciPy's LAPACK interface, not an engine switch)
            assert not any(isinstance(n, ast.Name) and n.id == "AVAILABLE" for n in ast.walk(ast.parse(text))), name
