"""``python -m benchmarks``: run every benchmark and print one table of medians and ratios.

A row may carry a ``table`` (markdown text) of the figures behind it: it is printed after the
summary table. ``--tiny`` runs every suite at its tiny size (``run(tiny=True)``: the same steps
on small data, once each), as the test suite does: it checks that each runs, in about a minute,
and its figures mean nothing.
"""

from __future__ import annotations

import os
import platform
import sys

from tqdm import tqdm

from benchmarks import (
    chips,
    coding,
    decisions,
    encoder,
    kernels,
    object_root,
    paid,
    planning,
    real_array,
    scale,
    search,
    snn,
    spike_store,
    sweep,
    sweep_scale,
    training,
    warm_rerun,
)

#: The suites of ``--quick``, then the slow ones.
QUICK = (
    encoder,
    coding,
    kernels,
    real_array,
    training,
    decisions,
    snn,
    planning,
    chips,
    spike_store,
)
SLOW = (scale, sweep, sweep_scale, warm_rerun, object_root, search, paid)


def main() -> None:
    # --quick skips the scale runs, the paper-grid sweeps (~25 minutes), the sweep machinery
    # up to 100,000 points (sweep_scale; ESKIN_BENCH_SCALE_SIZES picks fewer sizes), the warm
    # re-run of the paper grid (whose root, runs/bench/paper, the first run computes), the
    # warm re-run on an s3:// root against a folder root (smoke grid, both computed first, a
    # few minutes), the search against its exhaustive grid (runs/bench/search, computed by the
    # first run) and paid seconds against the workers' busy time. --tiny runs every suite at
    # its tiny size (seconds; the test suite does so).
    quick, tiny = "--quick" in sys.argv, "--tiny" in sys.argv
    suites = list(QUICK) + ([] if quick else list(SLOW))
    rows = []
    for suite in tqdm(suites, desc="benchmarks", unit="suite", file=sys.stderr):
        rows += suite.run(tiny=True) if tiny else suite.run()
    print(
        f"machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
    )
    width = max(len(r["benchmark"]) for r in rows)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in rows:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")
    for r in rows:
        if "table" in r:
            print(f"\n{r['benchmark']}:\n{r['table']}")


if __name__ == "__main__":
    main()
