"""A warm re-run of a grid (nothing to compute, the local server up) against the import floor.

The floor is what any sweep pays before it does anything: a fresh interpreter importing its
stack, ``python -c "import numpy, xarray, zarr, distributed, prefect"``. The warm re-run is
``eskin sweep --grid paper --json`` on a root that holds every point already, as a user re-runs
a finished sweep to get its cubes and summary: it plans, finds nothing missing and every cube
current (each file checked against its cube's manifest), starts no Dask cluster, and records
the flow run, its tasks and their artifacts on the local Prefect server (started once by this
suite, its state in a temporary folder). Both run as subprocesses, interleaved (floor, warm,
floor, ...) after one uncounted round each; the row quotes their medians and their ratio.

The root is cached between runs, ``runs/bench/<grid>`` by default (``--root`` or
``$ESKIN_BENCH_WARM_ROOT`` names another): the first run computes it (a cold ``paper`` sweep, a
few minutes on 2 cores), later runs find it complete and only re-run it.

``run(tiny=True)`` fills (on one worker) and re-runs :data:`benchmarks.sweep.TINY_GRID` in a
temporary root, one round (the floor not warmed up), on the local server ``$ESKIN_SERVER_DIR``
names if set.

``python -m benchmarks.warm_rerun [--grid paper] [--root DIR] [--repeat N]`` runs this suite
alone and prints its row.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
from pathlib import Path

from benchmarks.sweep import REPO, Run, local_server, local_sweep, run_command, tiny_grid

ROOT_ENV = "ESKIN_BENCH_WARM_ROOT"
DEFAULT_GRID = "paper"
WORKERS = 2
REPEAT = 5
TARGET_RATIO = 1.5
FLOOR = [sys.executable, "-c", "import numpy, xarray, zarr, distributed, prefect"]


def default_root(grid: str) -> Path:
    return Path(os.environ.get(ROOT_ENV) or REPO / "runs" / "bench" / Path(grid).stem)


def floor(env: dict[str, str]) -> Run:
    run = run_command(FLOOR, env)
    if run.status != 0:
        raise RuntimeError(f"the import floor failed, {run.failure()}")
    return run


def run(
    grid: str = DEFAULT_GRID, root: Path | None = None, repeat: int = REPEAT, tiny: bool = False
) -> list[dict]:
    """The row; ``tiny``: :data:`benchmarks.sweep.TINY_GRID` in a temporary root, one round,
    on a shared local server (:func:`benchmarks.sweep.local_server`)."""
    with tempfile.TemporaryDirectory(prefix="eskin-bench-warm-") as name:
        if tiny:
            grid, root, repeat = tiny_grid(Path(name)), Path(name) / "root", 1
        root = Path(root) if root is not None else default_root(grid)
        with local_server(Path(name), shared=tiny) as env:
            # Fills the root the first time (a tiny root on one worker: a second would add only
            # its start-up); afterwards, the uncounted warm-up round.
            filled = local_sweep(grid, root, 1 if tiny else WORKERS, env).summary()
            if not tiny:
                floor(env)
            floors, warms = [], []
            for _ in range(repeat):
                floors.append(floor(env))
                warms.append(local_sweep(grid, root, WORKERS, env))
    summary = warms[-1].summary()
    if summary["computed"]:
        raise RuntimeError(f"a warm re-run of {root} computed {summary['computed']} points")
    floor_s = statistics.median(r.wall_s for r in floors)
    warm_s = statistics.median(r.wall_s for r in warms)
    filling = f"; the root was filled now ({filled['computed']} points)" * bool(filled["computed"])
    return [
        {
            "benchmark": f"{Path(grid).stem} grid warm re-run / import floor",
            "ratio": warm_s / floor_s,
            "target": f"<= {TARGET_RATIO}",
            "detail": f"medians of {repeat}, interleaved: warm re-run {warm_s:.2f} s "
            f"(eskin sweep --json, local server up, {summary['cache_hits']} cache hits, "
            f"nothing computed) vs floor {floor_s:.2f} s ({FLOOR[-1]}){filling}",
        }
    ]


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.warm_rerun",
        description="Benchmark a warm re-run of a computed grid against the import floor.",
    )
    parser.add_argument("--grid", default=DEFAULT_GRID, help="a built-in grid or a grid TOML file")
    parser.add_argument(
        "--root",
        type=Path,
        help=f"the computed root to re-run, filled if need be (default: ${ROOT_ENV} or "
        "runs/bench/<grid>)",
    )
    parser.add_argument("--repeat", type=int, default=REPEAT, help="counted runs of each")
    args = parser.parse_args(argv)
    for r in run(args.grid, args.root, args.repeat):
        print(f"{r['benchmark']}  {r['ratio']:.2f}  {r['target']}; {r['detail']}")


if __name__ == "__main__":
    main()
