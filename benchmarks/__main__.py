"""``python -m benchmarks``: run every benchmark and print one table of medians and ratios."""

from __future__ import annotations

import os
import platform
import sys

from benchmarks import encoder, sweep, training


def main() -> None:
    quick = "--quick" in sys.argv  # skips the paper-grid sweeps (about 20 minutes)
    rows = encoder.run() + training.run() + ([] if quick else sweep.run())
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    width = max(len(r["benchmark"]) for r in rows)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in rows:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
