"""Does searching pay? The hypervolume a search finds with 10 % and 25 % of a grid's cost.

The space (:data:`SPACE`) is small enough to grid exhaustively: 8 thresholds x 3 windows x 4
taxel rows x 2 columns = 192 points, on a smaller built-in dataset and short training (10
touches per class of 2 s, 5 folds, FFNN only, 5 epochs) so that the grid computes in under a
minute on 2 cores; every dimension is discrete, so every trial is a grid point. (With 4
touches per class the accuracies are so noisy that every sampler, random search included,
found about 0.9 of the exhaustive hypervolume at 25 %: there was no structure to find.)

The grid is swept once into a store (``runs/bench/search``, kept between runs; ``--root`` names
another), and its cost is counted as a search's is (:func:`flows.search.spent_seconds`: the stage
seconds the workers paid, each point once, so a shared spike train, load or set-up once; a store
swept before paid seconds were kept counts work seconds, each spike train once). Then each
sampler (TPE, the default; NSGA-II; random search) searches the space with a budget of 10 % and
25 % of those stage seconds, for 10 seeds, with :func:`flows.search.run_optimize` on that store
(batches of 2 trials, as 2 workers would take): nothing is computed, and the stage seconds a
trial would have cost are counted from the store.

Hypervolume: of the trials' (accuracy, data rate) costs ``(-accuracy, log10(1 + data_rate_bps))``,
each scaled to [0, 1] over the exhaustive grid, against the reference point (1.1, 1.1)
(:func:`pipeline.report.trials.hypervolume`). Rows: each budget's median hypervolume (over seeds)
over the exhaustive one (target >= 0.95 at 25 %), and the default sampler's over random search's
at each budget (target > 1); the table behind them has every sampler.

``run(tiny=True)`` does the same for :data:`TINY_SPACE` (8 points of 4 short touches per class,
one epoch) in a temporary root, with one seed.

``python -m benchmarks.search [--root DIR] [--seeds N]`` runs this suite alone and prints its
table.
"""

from __future__ import annotations

import argparse
import dataclasses
import itertools
import statistics
import sys
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.sweep import REPO
from flows.run import run_sweep
from flows.search import run_optimize, spent_seconds, trials_cube
from pipeline.design.space import Sampler, Space, objective_values
from pipeline.report.trials import hypervolume
from storage.search_log import SearchJournal

WORKERS = 2
SEEDS = 10
FRACTIONS = (0.10, 0.25)
TARGET_SHARE = 0.95
REFERENCE = 1.1
SPACE = {
    "name": "bench",
    "base": {
        "name": "bench",
        "dataset": {"kind": "synthetic", "recordings_per_class": 10, "duration_s": 2.0},
        "array": {"rows": 1, "cols": 1},
        "training": {"models": ["ffnn"], "epochs": 5, "folds": 5},
    },
    "space": {
        "readout.threshold_v": {"choices": [0.02, 0.03, 0.045, 0.065, 0.09, 0.13, 0.19, 0.28]},
        "coding.window_s": {"choices": [0.05, 0.1, 0.2]},
        "array.rows": {"low": 1, "high": 4},
        "array.cols": {"low": 1, "high": 2},
    },
    "objectives": {"accuracy.ffnn": "max", "data_rate_bps": "min"},
}
#: The space of ``run(tiny=True)``: 2 thresholds x 2 windows x 2 taxel rows, seconds to grid.
TINY_SPACE = {
    **SPACE,
    "base": {
        **SPACE["base"],
        "dataset": {"kind": "synthetic", "recordings_per_class": 4, "duration_s": 1.5},
        "training": {"models": ["ffnn"], "epochs": 1, "folds": 4},
    },
    "space": {
        "readout.threshold_v": {"choices": [0.045, 0.13]},
        "coding.window_s": {"choices": [0.1, 0.2]},
        "array.rows": {"low": 1, "high": 2},
    },
}


def grid_params(space: Space) -> list[dict[str, Any]]:
    """Every point of the exhaustive grid as trial values."""
    values = [d.grid_values(10) for d in space.dimensions]
    return [dict(zip(space.fields, combo, strict=True)) for combo in itertools.product(*values)]


def scaled_costs(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(accuracy, data rate) rows as costs ``(-accuracy, log10(1 + rate))`` scaled by the
    exhaustive grid's range (``low``, ``high`` of those costs)."""
    costs = np.column_stack([-values[:, 0], np.log10(1.0 + values[:, 1])])
    return (costs - low) / np.where(high > low, high - low, 1.0)


def measure(root: Path, seeds: int = SEEDS, spec: dict[str, Any] = SPACE) -> dict[str, Any]:
    space = Space.from_dict(spec)
    grid = space.exhaustive_grid(10)
    run_sweep(grid, root, workers=WORKERS)
    params = grid_params(space)
    cube = trials_cube(space, root, params, list(range(len(params))))
    exhaustive_s = spent_seconds(space, params, cube)
    values = objective_values(cube, space.objectives)
    raw = np.column_stack([-values[:, 0], np.log10(1.0 + values[:, 1])])
    low, high = raw.min(axis=0), raw.max(axis=0)
    reference = np.full(2, REFERENCE)
    full = hypervolume(scaled_costs(values, low, high), reference)
    for old in root.glob("search-bench-*.jsonl"):
        old.unlink()  # each measurement searches afresh
    found: dict[tuple[str, float], list[tuple[float, float]]] = {}
    for sampler, fraction, seed in itertools.product(Sampler, FRACTIONS, range(seeds)):
        name = f"bench-{sampler.value}-{round(100 * fraction)}-{seed}"
        searched = dataclasses.replace(space, name=name, seed=seed, sampler=sampler)
        summary = run_optimize(searched, root, budget_s=fraction * exhaustive_s, workers=WORKERS)
        journal = SearchJournal.open(root, name, searched.fingerprint())
        told = np.array(list(journal.values.values()), dtype=np.float64)
        share = hypervolume(scaled_costs(told, low, high), reference) / full
        spent = summary["search_seconds"] / exhaustive_s
        found.setdefault((sampler.value, fraction), []).append((share, spent))
    return {"points": len(params), "exhaustive_s": exhaustive_s, "found": found}


def table(result: dict[str, Any]) -> str:
    lines = [
        "| sampler | budget (share of the grid's stage seconds) | hypervolume / exhaustive, "
        "median (min-max) over seeds | stage seconds spent, median |",
        "| --- | ---: | ---: | ---: |",
    ]
    for (sampler, fraction), runs in result["found"].items():
        shares = [s for s, _ in runs]
        lines.append(
            f"| {sampler} | {100 * fraction:.0f} % | {statistics.median(shares):.3f} "
            f"({min(shares):.3f}-{max(shares):.3f}) | "
            f"{100 * statistics.median(spent for _, spent in runs):.1f} % |"
        )
    return "\n".join(lines)


def rows(result: dict[str, Any]) -> list[dict[str, Any]]:
    def median(sampler: Sampler, fraction: float) -> float:
        return statistics.median(s for s, _ in result["found"][(sampler.value, fraction)])

    seeds = len(result["found"][(Sampler.TPE.value, FRACTIONS[0])])
    detail = (
        f"{result['points']} grid points, {result['exhaustive_s']:.0f} stage seconds; "
        f"medians of {seeds} seeds"
    )
    out = []
    for fraction in FRACTIONS:
        out.append(
            {
                "benchmark": f"search hypervolume at {100 * fraction:.0f} % of the grid's cost "
                "/ exhaustive",
                "ratio": median(Sampler.TPE, fraction),
                "target": f">= {TARGET_SHARE}" if fraction == max(FRACTIONS) else "-",
                "detail": detail,
            }
        )
        out.append(
            {
                "benchmark": f"search / random search hypervolume at {100 * fraction:.0f} %",
                "ratio": median(Sampler.TPE, fraction) / median(Sampler.RANDOM, fraction),
                "target": "> 1",
                "detail": f"NSGA-II: {median(Sampler.NSGA2, fraction):.3f} of exhaustive",
            }
        )
    out[-1]["table"] = table(result)
    return out


def default_root() -> Path:
    return REPO / "runs" / "bench" / "search"


def run(root: Path | None = None, seeds: int = SEEDS, tiny: bool = False) -> list[dict[str, Any]]:
    """The rows; ``tiny``: :data:`TINY_SPACE` in a temporary root, one seed."""
    if tiny:
        with tempfile.TemporaryDirectory(prefix="eskin-bench-search-") as folder:
            return rows(measure(Path(folder), 1, TINY_SPACE))
    return rows(measure(root or default_root(), seeds))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=default_root())
    parser.add_argument("--seeds", type=int, default=SEEDS)
    args = parser.parse_args()
    found = rows(measure(args.root, args.seeds))
    for r in found:
        print(f"{r['benchmark']}  {r['ratio']:.3f}  {r['target']}; {r['detail']}")
    print(found[-1]["table"], file=sys.stdout)


if __name__ == "__main__":
    main()
