"""``python -m benchmarks``: run every benchmark and print one table of medians and ratios."""

from __future__ import annotations

import os
import platform

from benchmarks import encoder, training


def main() -> None:
    rows = encoder.run() + training.run()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    width = max(len(r["benchmark"]) for r in rows)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in rows:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
