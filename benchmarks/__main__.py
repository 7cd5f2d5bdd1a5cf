"""``python -m benchmarks``: run every benchmark and print one table of medians and ratios."""

from __future__ import annotations

import os
import platform
import sys

from tqdm import tqdm

from benchmarks import coding, encoder, planning, scale, sweep, training


def main() -> None:
    quick = "--quick" in sys.argv  # skips the scale runs and the paper-grid sweeps (~25 minutes)
    suites = [encoder, coding, training, planning] + ([] if quick else [scale, sweep])
    rows = []
    for suite in tqdm(suites, desc="benchmarks", unit="suite", file=sys.stderr):
        rows += suite.run()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    width = max(len(r["benchmark"]) for r in rows)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in rows:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
