"""The ``sweepik`` command line: ``main`` (the entry point) and one module per command."""

from sweepik.cli.app import main

__all__ = ["main"]
