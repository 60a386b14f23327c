"""Benchmark script: the same code as ``sweepik bench`` (see sweepik.experiments.bench); run from the repository root.

python benchmarks/bench.py            # full run (a)-(d), table
python benchmarks/bench.py --json     # machine-readable
python benchmarks/bench.py --numpy    # the NumPy engine only (as without the 'fast' extra)
"""

from __future__ import annotations

import argparse
import json

from sweepik.engine import search
from sweepik.experiments.bench import format_bench, run_bench


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--numpy", action="store_true", help="disable the compiled (Numba) kernels")
    parser.add_argument("--memory", type=int, default=100_000)
    args = parser.parse_args()
    if args.numpy:
        search.AVAILABLE = False  # the solver then runs the NumPy reference engine
    result = run_bench(memory=0 if args.numpy else args.memory)
    print(json.dumps(result, indent=2) if args.json else format_bench(result))


if __name__ == "__main__":
    main()
