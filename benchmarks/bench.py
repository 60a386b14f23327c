"""Benchmark script: the same code as ``sweepik bench`` (see sweepik.experiments.bench); run from the repository root.

python benchmarks/bench.py            # full run (a)-(d), table
python benchmarks/bench.py --json     # machine-readable
"""

from __future__ import annotations

import argparse
import json

from sweepik.experiments.bench import format_bench, run_bench


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--json", action="store_true")
    parser.add_argument("--memory", type=int, default=100_000)
    args = parser.parse_args()
    result = run_bench(memory=args.memory)
    print(json.dumps(result, indent=2) if args.json else format_bench(result))


if __name__ == "__main__":
    main()
