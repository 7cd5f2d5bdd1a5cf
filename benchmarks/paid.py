"""Do the seconds a sweep's points paid add up to its workers' busy time?

A grid (``smoke`` by default; ``--grid paper`` for the paper's) is swept into a new root on a
local cluster of :data:`WORKERS` single-thread workers (:func:`flows.run.run_sweep`, as
``eskin sweep`` runs it, without Prefect), with Dask's task stream recording every task. The
workers' busy time is the time their tasks computed, summed over tasks; the paid seconds are the
report's "sweep's own cost" (:func:`pipeline.report.cost.sweep_cost` over the root's cubes: each
distinct point's paid seconds, both charges). What the paid seconds leave out is the tasks'
work outside any point's stages: listing and reading the store, writing the entries. (A
worker's import of torch is paid, by the first point its task computes, as shared ``setup``.)

Row: paid seconds / busy time (1 would be all of it); the detail gives both, the shared part of
the paid seconds and the margin ``1 - paid / busy``.

``run(tiny=True)`` sweeps :data:`benchmarks.sweep.TINY_GRID` instead, on one worker.
``python -m benchmarks.paid [--grid NAME]`` runs this suite alone and prints its row.
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

from pipeline.results.variables import RESULT_KEY, STAGE_DIM, WORK_SECONDS

WORKERS = 2
DEFAULT_GRID = "smoke"
TARGET = 0.9


def measure(grid: str = DEFAULT_GRID, workers: int = WORKERS) -> dict:
    from distributed import get_task_stream

    from flows.cluster import dask_client
    from flows.environment import hermetic_environment
    from flows.run import run_sweep
    from pipeline.report.cost import sweep_cost
    from storage import open_results

    with tempfile.TemporaryDirectory(prefix="eskin-bench-paid-") as tmp:
        root = Path(tmp) / "run"
        hermetic_environment(Path(tmp), prefect=False)  # Dask, matplotlib state: under tmp
        with dask_client(workers) as client, get_task_stream(client) as stream:
            summary = run_sweep(grid, root, client=client)
        busy = sum(
            part["stop"] - part["start"]
            for task in stream.data
            for part in task["startstops"]
            if part["action"] == "compute"
        )
        cubes = open_results(root)
        cost = sweep_cost(cubes, [])
        # As the report summed them before paid seconds: each distinct point's work seconds,
        # shared work at every point that used it (one-off work, then inside the steps, apart).
        work: dict[str, dict[str, float]] = {}
        for cube in cubes.values():
            seconds = cube[WORK_SECONDS].transpose(*cube[RESULT_KEY].dims, STAGE_DIM)
            rows = seconds.values.reshape(-1, cube.sizes[STAGE_DIM])
            for key, row in zip(cube[RESULT_KEY].values.ravel(), rows, strict=True):
                stages = [str(s) for s in cube[STAGE_DIM].values]
                work.setdefault(str(key), dict(zip(stages, row.tolist(), strict=True)))
    by_stage: dict[str, float] = {}
    for row in work.values():
        for stage, value in row.items():
            if value == value:  # not NaN
                by_stage[stage] = by_stage.get(stage, 0.0) + value
    return {
        "work_by_stage": by_stage,
        "grid": grid,
        "points": cost.n_points,
        "paid_s": cost.total_s,
        "shared_s": cost.shared_s,
        "busy_s": busy,
        "wall_s": summary["seconds"],
        "workers": workers,
        "stages": cost.stages,
    }


def rows(result: dict) -> list[dict]:
    ratio = result["paid_s"] / result["busy_s"]
    return [
        {
            "benchmark": f"paid seconds / workers' busy time ({result['grid']} grid)",
            "ratio": ratio,
            "target": f">= {TARGET}",
            "detail": f"{result['points']} points: {result['paid_s']:.1f} s paid "
            f"({result['shared_s']:.1f} s shared) of {result['busy_s']:.1f} s busy, margin "
            f"{100 * (1 - ratio):.1f} %; {result['wall_s']:.1f} s wall on {result['workers']} "
            "workers",
        }
    ]


def run(grid: str = DEFAULT_GRID, tiny: bool = False) -> list[dict]:
    """The row; ``tiny``: :data:`benchmarks.sweep.TINY_GRID` for ``grid``, on one worker (a
    second would add only its start-up)."""
    if not tiny:
        return rows(measure(grid))
    from benchmarks.sweep import tiny_grid

    with tempfile.TemporaryDirectory(prefix="eskin-bench-paid-grid-") as folder:
        return rows(measure(tiny_grid(Path(folder)), workers=1))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--grid", default=DEFAULT_GRID)
    args = parser.parse_args()
    result = measure(args.grid)
    for r in rows(result):
        print(f"{r['benchmark']}  {r['ratio']:.3f}  {r['target']}; {r['detail']}")
    work = result["work_by_stage"]
    print(f"  {'stage':12s} {'own':>8s}   {'shared':>8s}   {'work, summed per point':>22s}")
    for s in result["stages"]:
        print(
            f"  {s.stage:12s} {s.own_s:8.2f} s {s.shared_s:8.2f} s {work.get(s.stage, 0.0):20.2f} s"
        )


if __name__ == "__main__":
    main()
