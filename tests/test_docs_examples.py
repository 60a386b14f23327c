"""Every fenced example of README.md and docs/*.md runs as written, from a copy of the repository's ``examples/``
(the files the examples name): each document's Python blocks in order in one namespace (run as a script:
``__name__ == "__main__"``), and each ``sweepik ...`` line of its shell blocks through the CLI's ``main`` (exit 0).

Adjusted or left out, and why (each is run by its own tests):
- ``sweepik sample ... 1000000``: 2,000 poses instead of a million (the same command; the solve lines after it then
  solve 2,000 poses, on Dask too);
- ``sweepik bench`` (minutes; tests/test_bench*), ``sweepik view`` (serves until Ctrl-C; tests/test_viewer.py),
  ``sweepik verify`` without ``--strategy precise`` (both strategies, about a minute each; tests/test_verify.py);
- lines that install or run the test suite (``pip``, ``python -m ...``, ``.venv/bin/...``).
"""

from __future__ import annotations

import contextlib
import io
import re
import shlex
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]
FENCE = re.compile(r"^```(\w*)\n(.*?)^```", re.S | re.M)
SKIP = {"bench": "minutes", "view": "serves until Ctrl-C"}

pytestmark = pytest.mark.skipif(not (ROOT / "examples").is_dir(), reason="not run from a clone of the repository")


def _blocks(path: Path, lang: str) -> list[str]:
    return [body for kind, body in FENCE.findall(path.read_text(encoding="utf-8")) if kind == lang]


def _commands(path: Path) -> list[str]:
    lines = []
    for body in _blocks(path, "bash"):
        for raw in body.splitlines():
            line = raw.split(" #")[0].strip() if not raw.lstrip().startswith("#") else ""
            if line.startswith("sweepik "):
                lines.append(line)
    return lines


@pytest.fixture
def workdir(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    return tmp_path


DOCS_WITH_PYTHON = [p for p in DOCS if _blocks(p, "python")]
DOCS_WITH_COMMANDS = [p for p in DOCS if _commands(p)]


@pytest.mark.parametrize("doc", DOCS_WITH_PYTHON, ids=lambda p: p.name)
def test_python_examples_run(doc: Path, workdir: Path) -> None:
    env: dict[str, object] = {"__name__": "__main__"}
    for k, body in enumerate(_blocks(doc, "python")):
        with contextlib.redirect_stdout(io.StringIO()):
            exec(compile(body, f"{doc.name} python block {k + 1}", "exec"), env)


def _skipped(argv: list[str]) -> str | None:
    if argv[0] in SKIP:
        return SKIP[argv[0]]
    if argv[0] == "verify" and "precise" not in argv:
        return "both strategies: about a minute"
    return None


@pytest.mark.parametrize("doc", DOCS_WITH_COMMANDS, ids=lambda p: p.name)
def test_command_line_examples_run(doc: Path, workdir: Path, capsys: pytest.CaptureFixture[str]) -> None:
    from sweepik.cli.app import main

    ran = 0
    for line in _commands(doc):
        argv = shlex.split(line.replace(" 1000000 ", " 2000 "))[1:]
        if _skipped(argv):
            continue
        target = None
        if ">" in argv:
            argv, target = argv[: argv.index(">")], argv[argv.index(">") + 1]
        code = main(argv)
        out, err = capsys.readouterr()
        assert code == 0, f"{doc.name}: {line!r} exited {code}: {err[-500:]}"
        if target is not None:
            Path(target).write_text(out)
        ran += 1
    assert ran > 0
