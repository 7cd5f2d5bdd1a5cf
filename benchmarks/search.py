"""Does searching pay? The hypervolume a search finds with a tenth of an exhaustive grid's cost.

Two spaces (:data:`SPACES`), each gridded exhaustively once:

* ``rows``, 3 dimensions: 8 thresholds x 3 windows x 1-8 taxel rows (192 points);
* ``encoder``, 5 dimensions: the encoder (fixed or decaying threshold) x 6 thresholds x
  3 windows x 1-4 taxel rows x threshold mismatch 0-0.3 in steps of 0.1 (576 points);

on the built-in data with enough recordings and training that the exhaustive front is a
measurement, not a draw (:data:`BASE`, for both: 80 touches per class of 2 s, 10 folds, FFNN,
40 epochs; the 95 % intervals of the front's accuracies are stated beside the accuracy range
the grid spans, :func:`noise`).
Objectives: FFNN accuracy (max) and data rate (min).

The exhaustive results are computed once and kept, small, in :data:`DATA`
(``python -m benchmarks.search --exhaustive``, a sweep of both grids on 2 workers into a run
root, about 13 minutes on a 2-core machine with nothing else running; measure the seconds
there, since a busy machine's contention is paid by some points and not others): per point
its objectives, the 95 % interval of its accuracy, and the seconds it paid
(:func:`exhaustive_arrays`). Searches are then replayed
offline against them (:func:`replay`): the real sampler (:class:`flows.samplers.Proposer`,
exactly as ``eskin optimize`` makes it) and the real refill loop (:func:`flows.refill.refill`)
on a simulated clock of 2 workers, each trial paying what its point paid in the exhaustive
run: its own training and coding, its spike train's stages unless a trial of the search
started on that train before (a train under way is waited for, not computed again: a search's
missing trains are Dask tasks of their own), and, for the first trial of each worker, a
worker's share of the one-off load and set-up (as a search on fresh workers pays them). The
grid's cost is what the exhaustive run paid: every point's own seconds and the shared ones. A
search stops asking when its seconds told plus those its running trials are expected to cost
reach the budget, or as its sampler proposes only designs told before: the search's own rule
(:class:`flows.search.StopRule`, :func:`flows.search.committed_seconds`) decides; the trials
running then finish and are counted.

A budget is a share of the grid's cost, counted two ways (:class:`Budget`): of everything
the grid paid (``paid``), and of its points' seconds beyond the workers' start, which a search
on fresh workers pays as the grid did (``beyond_start``). The benchmark's points cost a few
seconds each, so the start is a large part of a small ``paid`` budget; for trials that cost
hours the two are the same.

One replay per space, sampler and seed runs to the largest budget: a search with a smaller
budget asks the same trials up to the first ask that budget refuses (the sampler and the clock
are the same until then), so each budget's result is read from it. ``auto`` resolves to one
of GP and TPE (:func:`flows.samplers.resolve_sampler`); its rows are that sampler's replays.

Hypervolume: of the trials' costs ``(-accuracy, log10(1 + data_rate_bps))``, each scaled to
[0, 1] over the exhaustive grid, against the reference point (1.1, 1.1)
(:func:`pipeline.report.trials.hypervolume`), over the exhaustive grid's. Goals (medians over
10 seeds, at 10 % of the grid's paid seconds; each is also reported beyond the start): at
least 0.95 on ``rows``, 0.90 on ``encoder``, and the default (``auto``) never below random
search's median at any budget.

``run(tiny=True)`` replays one seed of each sampler on ``rows`` at 10 % from the kept data.
``python -m benchmarks.search [--seeds N]`` prints the table.
"""

from __future__ import annotations

import argparse
import dataclasses
import enum
import heapq
import itertools
import json
import statistics
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from benchmarks.sweep import REPO
from flows.refill import refill
from flows.samplers import Proposer, resolve_sampler, seed_for
from flows.search import StopRule, committed_seconds
from pipeline.design.scene import scene_field
from pipeline.design.space import Sampler, Space
from pipeline.report.trials import hypervolume
from pipeline.results.variables import (
    ACCURACY_HIGH,
    ACCURACY_LOW,
    ACCURACY_MEAN,
    MODEL_DIM,
    STAGE_DIM,
)

WORKERS = 2
SEEDS = 10
FRACTIONS = (0.05, 0.10, 0.25)
GOAL_FRACTION = 0.10
GOALS = {"rows": 0.95, "encoder": 0.90}
REFERENCE = 1.1
SAMPLERS = (Sampler.AUTO, Sampler.GP, Sampler.TPE, Sampler.RANDOM)
DATA = Path(__file__).parent / "data" / "search_exhaustive.npz"
COMMAND = "python -m benchmarks.search --exhaustive"
THRESHOLDS = [0.02, 0.03, 0.045, 0.065, 0.09, 0.13, 0.19, 0.28]
BASE = {
    "name": "bench",
    "dataset": {"kind": "synthetic", "recordings_per_class": 80, "duration_s": 2.0},
    "array": {"rows": 1, "cols": 1},
    "training": {"models": ["ffnn"], "epochs": 40, "folds": 10},  # the scene's default folds
}
OBJECTIVES = {"accuracy.ffnn": "max", "data_rate_bps": "min"}
SPACES: dict[str, dict[str, Any]] = {
    "rows": {
        "name": "rows",
        "base": BASE,
        "space": {
            "readout.threshold_v": {"choices": THRESHOLDS},
            "coding.window_s": {"choices": [0.05, 0.1, 0.2]},
            "array.rows": {"low": 1, "high": 8},
        },
        "objectives": OBJECTIVES,
    },
    "encoder": {
        "name": "encoder",
        "base": BASE,
        "space": {
            "readout.encoder": {"choices": ["lcs", "decaying"]},
            # From 0.045 V, which keeps the grid at 576 points (an exhaustive sweep of about
            # 9 minutes on 2 idle workers); the lower thresholds are the rows space's to explore.
            "readout.threshold_v": {"choices": THRESHOLDS[2:]},
            "coding.window_s": {"choices": [0.05, 0.1, 0.2]},
            "array.rows": {"low": 1, "high": 4},
            "readout.effects.threshold_mismatch.sigma_rel": {"low": 0.0, "high": 0.3, "step": 0.1},
        },
        "objectives": OBJECTIVES,
    },
}


def grid_params(space: Space) -> list[dict[str, Any]]:
    """Every point of the exhaustive grid as trial values, in the grid's order."""
    values = [d.grid_values(10) for d in space.dimensions]
    return [dict(zip(space.fields, combo, strict=True)) for combo in itertools.product(*values)]


def point_label(params: dict[str, Any]) -> str:
    """A trial's values as one string (rounded floats), to find its grid point."""
    return json.dumps(
        {k: round(v, 9) if isinstance(v, float) else v for k, v in params.items()},
        sort_keys=True,
    )


def costs_of(values: np.ndarray) -> np.ndarray:
    """(accuracy, data rate) rows as costs ``(-accuracy, log10(1 + rate))``."""
    return np.column_stack([-values[:, 0], np.log10(1.0 + values[:, 1])])


def scaled_costs(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """(accuracy, data rate) rows as costs ``(-accuracy, log10(1 + rate))`` scaled by the
    exhaustive grid's range (``low``, ``high`` of those costs)."""
    return (costs_of(values) - low) / np.where(high > low, high - low, 1.0)


# -- the exhaustive results ----------------------------------------------------------------------


def exhaustive_arrays(space: Space, root: Path) -> dict[str, np.ndarray]:
    """The exhaustive grid of ``space`` swept into ``root``, as arrays over its points (grid
    order): ``values`` (accuracy, data rate), ``accuracy_low``/``accuracy_high`` (95 %),
    ``own_s`` (seconds the point paid itself, spike stages apart), ``train_s`` (spike stages'
    seconds it paid, 0 when another point paid its train), ``train`` (its spike train's
    index), ``shared_s`` (the one-off load and set-up it paid: a worker's first point)."""
    from flows.run import run_sweep
    from flows.search import trials_cube
    from pipeline.results.cube import paid_seconds
    from pipeline.results.variables import CHARGE_DIM
    from pipeline.run.stages import SPIKES

    grid = space.exhaustive_grid(10)
    run_sweep(grid, root, workers=WORKERS)
    params = grid_params(space)
    cube = trials_cube(space, root, params, list(range(len(params))))
    paid = paid_seconds(cube)
    if paid is None:
        raise RuntimeError(f"{root}: the points hold no paid seconds")
    spike = [s for s in (str(x) for x in cube[STAGE_DIM].values) if s in SPIKES.steps_for(["ffnn"])]
    own, shared = paid.sel({CHARGE_DIM: "own"}), paid.sel({CHARGE_DIM: "shared"})
    trains = [SPIKES.key(p.scene) for p in space.trial_grid(params).points()]
    index = {key: i for i, key in enumerate(dict.fromkeys(trains))}
    model = {MODEL_DIM: "ffnn"}
    return {
        "values": np.column_stack(
            [cube[ACCURACY_MEAN].sel(model).values, cube["data_rate_bps"].values]
        ),
        ACCURACY_LOW: cube[ACCURACY_LOW].sel(model).values,
        ACCURACY_HIGH: cube[ACCURACY_HIGH].sel(model).values,
        "own_s": own.drop_sel({STAGE_DIM: spike}).sum(STAGE_DIM).values,
        "train_s": own.sel({STAGE_DIM: spike}).sum(STAGE_DIM).values,
        "train": np.array([index[k] for k in trains], dtype=np.int32),
        "shared_s": shared.sum(STAGE_DIM).values,
        "labels": np.array([point_label(p) for p in params]),
    }


def make_exhaustive(root: Path, names: tuple[str, ...] = tuple(SPACES), path: Path = DATA) -> None:
    """Sweep the grids of spaces ``names`` into ``root`` and keep their arrays in ``path``
    (beside those of other spaces kept there)."""
    arrays: dict[str, np.ndarray] = {}
    if path.is_file():
        with np.load(path, allow_pickle=False) as kept:
            arrays = {k: kept[k] for k in kept.files if k.split("/")[0] not in (*names, "about")}
    for name in names:
        spec = SPACES[name]
        start = time.perf_counter()
        found = exhaustive_arrays(Space.from_dict(spec), root / name)
        arrays |= {f"{name}/{k}": v for k, v in found.items()}
        print(f"{name}: {len(found['values'])} points, {time.perf_counter() - start:.0f} s wall")
    commit = subprocess.run(
        ["git", "rev-parse", "--short", "HEAD"], capture_output=True, text=True, cwd=REPO
    ).stdout.strip()
    about = {"command": COMMAND, "commit": commit, "spaces": SPACES, "workers": WORKERS}
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(path, about=np.array(json.dumps(about)), **arrays)


def load_exhaustive(name: str, path: Path = DATA) -> dict[str, np.ndarray]:
    """The kept arrays of space ``name`` (:func:`exhaustive_arrays`), checked against the
    space as the code declares it today."""
    with np.load(path, allow_pickle=False) as data:
        about = json.loads(str(data["about"]))
        arrays = {k.split("/", 1)[1]: data[k] for k in data.files if k.startswith(f"{name}/")}
    if about["spaces"][name] != json.loads(json.dumps(SPACES[name])):
        raise RuntimeError(f"{path}: space {name!r} changed since it was made; run {COMMAND}")
    return arrays


def noise(arrays: dict[str, np.ndarray]) -> dict[str, float]:
    """The exhaustive front's measurement noise against the grid's accuracy range: median and
    largest width of the front points' 95 % intervals, and the range of accuracies."""
    from pipeline.report.trials import pareto_mask

    values = arrays["values"]
    front = pareto_mask(costs_of(values))
    width = (arrays[ACCURACY_HIGH] - arrays[ACCURACY_LOW])[front]
    return {
        "front_points": int(front.sum()),
        "interval_median": float(np.median(width)),
        "interval_max": float(width.max()),
        "accuracy_low": float(values[:, 0].min()),
        "accuracy_high": float(values[:, 0].max()),
    }


MISMATCH = scene_field("readout.effects.threshold_mismatch.sigma_rel")


def oracle_share(
    arrays: dict[str, np.ndarray], over: str, draws: int = 2000, seed: int = 0
) -> tuple[float, float, float] | None:
    """What the grid's noise leaves to find along dimension ``over`` (one that hardly moves
    the objectives, as per-chip mismatch): an oracle knows the front of the designs' values
    averaged over ``over`` and tries each of its designs at one value of ``over`` drawn at
    random; the median and 5th-95th percentiles of its share of the exhaustive hypervolume
    over ``draws`` draws. None when the space has no such dimension."""
    from collections import defaultdict

    from pipeline.report.trials import pareto_mask

    labels = [json.loads(str(label)) for label in arrays["labels"]]
    if over not in labels[0]:
        return None
    values = arrays["values"]
    groups: dict[str, list[int]] = defaultdict(list)
    for i, label in enumerate(labels):
        groups[json.dumps({k: v for k, v in label.items() if k != over}, sort_keys=True)].append(i)
    members = list(groups.values())
    mean = np.array([values[m].mean(axis=0) for m in members])
    front = [members[i] for i in np.flatnonzero(pareto_mask(costs_of(mean)))]
    raw = costs_of(values)
    low, high = raw.min(axis=0), raw.max(axis=0)
    reference = np.full(2, REFERENCE)
    full = hypervolume(scaled_costs(values, low, high), reference)
    rng = np.random.default_rng(seed)
    shares = [
        hypervolume(scaled_costs(values[[rng.choice(m) for m in front]], low, high), reference)
        / full
        for _ in range(draws)
    ]
    median, p05, p95 = np.percentile(shares, [50, 5, 95])
    return float(median), float(p05), float(p95)


# -- replaying searches ----------------------------------------------------------------------


def grid_cost(arrays: dict[str, np.ndarray]) -> float:
    """The seconds the exhaustive run paid: every point's own, and the shared ones."""
    return float(arrays["own_s"].sum() + arrays["train_s"].sum() + arrays["shared_s"].sum())


def start_seconds(arrays: dict[str, np.ndarray]) -> float:
    """What a fresh worker paid once, on average over the exhaustive run's: the one-off seconds
    in all over the points that paid a worker's start (a tenth of the largest or more; others
    pay milliseconds of shared book-keeping)."""
    shared = arrays["shared_s"]
    starts = max(1, int((shared >= 0.1 * shared.max()).sum())) if shared.size else 1
    return float(shared.sum()) / starts


class Budget(enum.Enum):
    """How a share of the grid's cost becomes a search's budget in paid seconds.

    ``paid``: the share of everything the grid paid, ``f * (S + P)`` for the grid's one-off
    start ``S`` (its workers' load and set-up) and its points' seconds ``P``; a search on fresh
    workers pays the same start, so on a grid of cheap points the start takes much of a small
    budget. ``beyond_start``: the start both pay, then the share of the points' seconds,
    ``S + f * P``; what a search whose trials cost hours (the start a rounding error) sees.
    """

    PAID = "paid"
    BEYOND_START = "beyond_start"

    def seconds(self, fraction: float, arrays: dict[str, np.ndarray]) -> float:
        """The budget in paid seconds for ``fraction`` of the grid of ``arrays``."""
        if self is Budget.PAID:
            return fraction * grid_cost(arrays)
        one_off = float(arrays["shared_s"].sum())
        return WORKERS * start_seconds(arrays) + fraction * (grid_cost(arrays) - one_off)

    def spent(self, seconds: float, arrays: dict[str, np.ndarray]) -> float:
        """A search's ``seconds`` paid as the share of the grid its budgets are shares of."""
        if self is Budget.PAID:
            return seconds / grid_cost(arrays)
        one_off = float(arrays["shared_s"].sum())
        start = WORKERS * start_seconds(arrays)
        return (seconds - start) / (grid_cost(arrays) - one_off)


@dataclasses.dataclass
class Replay:
    """One search replayed to its budget: per trial asked, the grid point, the seconds it
    cost and what the search weighed against its budget when it was asked (seconds told plus
    those expected of the running trials, :func:`flows.search.committed_seconds`), and the wall
    seconds of the sampler's asks."""

    points: list[int] = dataclasses.field(default_factory=list)
    seconds: list[float] = dataclasses.field(default_factory=list)
    weighed: list[float] = dataclasses.field(default_factory=list)
    ask_s: float = 0.0


def replay(space: Space, arrays: dict[str, np.ndarray], budget_s: float) -> Replay:
    """Replay a search of ``space`` (its sampler and seed) against the exhaustive ``arrays``
    with a budget of ``budget_s`` paid seconds, on :data:`WORKERS` simulated workers."""
    proposer = Proposer(space, seed_for(space.seed, 0))
    where = {label: i for i, label in enumerate(arrays["labels"])}
    own, train_s, train = arrays["own_s"], arrays["train_s"], arrays["train"]
    # Each train's stages cost what the point that paid them paid.
    train_cost = np.bincount(train, weights=train_s)
    shared_per_worker = start_seconds(arrays)
    out = Replay()
    trials: dict[int, Any] = {}
    started_trains: dict[int, float] = {}  # train -> when it is ready
    paid: set[int] = set()  # points tried
    told_points: set[int] = set()
    rule = StopRule(WORKERS)
    clock = [0.0]
    events: list[tuple[float, int]] = []
    spent = [0.0]
    spent_own = [0.0]  # beyond the workers' one-off seconds (Search.mean_trial_seconds)

    def ask(running: int) -> int | None:
        told = len(out.points) - running
        weighed = committed_seconds(spent[0], spent_own[0] / told if told else 0.0, running)
        # The search's own rule; every point tried also ends a replay (the grid has no other).
        if not rule.asks(lambda: weighed < budget_s and len(paid) < len(own)):
            return None
        tick = time.perf_counter()
        trial, params = proposer.ask()
        out.ask_s += time.perf_counter() - tick
        number = len(out.points)
        trials[number] = trial
        out.points.append(where[point_label(params)])
        out.weighed.append(weighed)
        return number

    def start(number: int) -> tuple[float, int]:
        point = out.points[number]
        # A point tried before costs nothing again: it is in the store (as search_seconds
        # counts each point once).
        seconds = 0.0 if point in paid else float(own[point])
        paid.add(point)
        key = int(train[point])
        ready = started_trains.get(key)
        if seconds and ready is None:
            seconds += train_cost[key]
        one_off = shared_per_worker if number < WORKERS else 0.0
        seconds += one_off
        out.seconds.append(seconds)
        print(".", end="", file=sys.stderr, flush=True)
        if ready is None:
            started_trains[key] = clock[0] + one_off + train_cost[key]
        # A train under way is a Dask task of its own that this trial waits for
        # (flows.scheduling), not computed again.
        begin = clock[0] if ready is None else max(clock[0], ready)
        token = (begin + seconds, number)
        heapq.heappush(events, token)
        return token

    def wait(tokens: list[tuple[float, int]], return_when: Any = None) -> tuple[set, set]:
        first = heapq.heappop(events)
        clock[0] = first[0]
        return {first}, set(tokens) - {first}

    def finish(number: int, token: Any) -> None:
        point = out.points[number]
        rule.told(repeat=point in told_points, failed=False)
        told_points.add(point)
        spent[0] += out.seconds[number]
        spent_own[0] += out.seconds[number] - (shared_per_worker if number < WORKERS else 0.0)
        proposer.tell(trials.pop(number), arrays["values"][out.points[number]].tolist())

    refill(WORKERS, ask, start, finish, wait)
    return out


def at_budget(found: Replay, budget_s: float) -> list[int]:
    """The trials a search with ``budget_s`` (at most the replay's) asks: those asked before
    the first ask it refuses (a search asks nothing once it refused)."""
    refused = next((i for i, w in enumerate(found.weighed) if w >= budget_s), len(found.points))
    return list(range(refused))


def measure(
    seeds: int | Sequence[int] = SEEDS,
    names: tuple[str, ...] = tuple(SPACES),
    fractions: tuple[float, ...] = FRACTIONS,
    samplers: tuple[Sampler, ...] = SAMPLERS,
    path: Path = DATA,
) -> dict[str, Any]:
    """Replays of every space, sampler and seed; the share of the exhaustive hypervolume and
    of the grid's cost at each budget, of each :class:`Budget` kind. ``seeds``: how many (0 to
    n - 1), or which."""
    seeds = range(seeds) if isinstance(seeds, int) else seeds
    results: dict[str, Any] = {}
    for name in names:
        arrays = load_exhaustive(name, path)
        space = Space.from_dict(SPACES[name])
        values = arrays["values"]
        raw = costs_of(values)
        low, high = raw.min(axis=0), raw.max(axis=0)
        reference = np.full(2, REFERENCE)
        full = hypervolume(scaled_costs(values, low, high), reference)
        largest = max(kind.seconds(max(fractions), arrays) for kind in Budget)
        kinds = {s: resolve_sampler(dataclasses.replace(space, sampler=s)) for s in samplers}
        replays: dict[tuple[Sampler, int], Replay] = {}
        found: dict[tuple[str, float, str], list[tuple[float, float, int]]] = {}
        for sampler, seed in itertools.product(samplers, seeds):
            kind = kinds[sampler]
            if (kind, seed) not in replays:
                searched = dataclasses.replace(space, seed=seed, sampler=kind)
                replays[(kind, seed)] = replay(searched, arrays, largest)
            run = replays[(kind, seed)]
            for budget, fraction in itertools.product(Budget, fractions):
                trials = at_budget(run, budget.seconds(fraction, arrays))
                told = values[[run.points[t] for t in trials]]
                share = hypervolume(scaled_costs(told, low, high), reference) / full
                spent = budget.spent(sum(run.seconds[t] for t in trials), arrays)
                found.setdefault((sampler.value, fraction, budget.value), []).append(
                    (share, spent, len(trials))
                )
                print(
                    f"\n{name} {sampler.value} seed {seed} at {fraction} ({budget.value}): "
                    f"{share:.3f} ({len(trials)} trials, {100 * spent:.1f} %)",
                    file=sys.stderr,
                    flush=True,
                )
        asks = {
            k.value: sum(r.ask_s for (kk, _), r in replays.items() if kk is k)
            for k in kinds.values()
        }
        results[name] = {
            "points": len(values),
            "grid_s": grid_cost(arrays),
            "start_s": WORKERS * start_seconds(arrays),
            "found": found,
            "auto": kinds[Sampler.AUTO].value if Sampler.AUTO in kinds else "-",
            "noise": noise(arrays),
            "oracle": oracle_share(arrays, MISMATCH),
            "ask_s": asks,
        }
    return results


BUDGET_WORDS = {
    Budget.PAID: "of the grid's paid seconds",
    Budget.BEYOND_START: "of the grid's point seconds beyond the workers' start",
}


def table(name: str, result: dict[str, Any], budget: Budget) -> str:
    """Markdown: per sampler and budget, the median share of the exhaustive hypervolume
    (min-max; median trials; median share spent)."""
    found = {(s, f): runs for (s, f, b), runs in result["found"].items() if b == budget.value}
    fractions = sorted({f for _, f in found})
    head = " | ".join(f"{100 * f:.0f} %" for f in fractions)
    lines = [
        f"| {name} ({BUDGET_WORDS[budget]}): sampler | {head} |",
        "| --- |" + " ---: |" * len(fractions),
    ]
    for sampler in dict.fromkeys(s for s, _ in found):
        cells = []
        for fraction in fractions:
            runs = found[(sampler, fraction)]
            shares = [s for s, _, _ in runs]
            cells.append(
                f"{statistics.median(shares):.3f} ({min(shares):.3f}-{max(shares):.3f}; "
                f"{statistics.median(n for _, _, n in runs):.0f} trials, "
                f"{100 * statistics.median(p for _, p, _ in runs):.1f} %)"
            )
        label = f"auto ({result['auto']})" if sampler == Sampler.AUTO.value else sampler
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def rows(results: dict[str, Any]) -> list[dict[str, Any]]:
    out = []
    for name, result in results.items():
        found = result["found"]

        def median(sampler: Sampler, fraction: float, budget: Budget, found=found) -> float:
            return statistics.median(
                s for s, _, _ in found[(sampler.value, fraction, budget.value)]
            )

        fractions = sorted({f for _, f, _ in found})
        seeds = len(found[(Sampler.AUTO.value, fractions[0], Budget.PAID.value)])
        n = result["noise"]
        detail = (
            f"{result['points']} points, {result['grid_s']:.0f} paid seconds (the workers' "
            f"start {result['start_s']:.0f}); medians of {seeds} seeds; front's 95 % "
            f"intervals {100 * n['interval_median']:.1f} points (at most "
            f"{100 * n['interval_max']:.1f}) against accuracies "
            f"{100 * n['accuracy_low']:.0f}-{100 * n['accuracy_high']:.0f} %"
        )
        if result.get("oracle"):
            detail += (
                "; an oracle of the mismatch-averaged front at one random mismatch each finds "
                "{:.3f} ({:.3f}-{:.3f})".format(*result["oracle"])
            )
        goal = GOAL_FRACTION if GOAL_FRACTION in fractions else fractions[0]
        for budget in Budget:
            out.append(
                {
                    "benchmark": f"search {name}: hypervolume at {100 * goal:.0f} % "
                    f"{BUDGET_WORDS[budget]} / exhaustive (auto: {result['auto']})",
                    "ratio": median(Sampler.AUTO, goal, budget),
                    "target": f">= {GOALS.get(name, '-')}",
                    "detail": detail,
                }
            )
            worst = min(
                fractions,
                key=lambda f, b=budget: median(Sampler.AUTO, f, b) / median(Sampler.RANDOM, f, b),
            )
            out.append(
                {
                    "benchmark": f"search {name}: auto / random search hypervolume, worst "
                    f"budget {BUDGET_WORDS[budget]}",
                    "ratio": median(Sampler.AUTO, worst, budget)
                    / median(Sampler.RANDOM, worst, budget),
                    "target": ">= 1",
                    "detail": f"at {100 * worst:.0f} %",
                    "table": table(name, result, budget),
                }
            )
    return out


def run(seeds: int = SEEDS, tiny: bool = False) -> list[dict[str, Any]]:
    """The rows; ``tiny``: one seed of each sampler on ``rows`` at 10 %."""
    if tiny:
        return rows(measure(1, ("rows",), (GOAL_FRACTION,)))
    return rows(measure(seeds))


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=SEEDS)
    parser.add_argument("--space", choices=list(SPACES), action="append")
    parser.add_argument(
        "--exhaustive",
        action="store_true",
        help=f"sweep both grids into --root and write {DATA.relative_to(REPO)}",
    )
    parser.add_argument("--root", type=Path, default=REPO / "runs" / "bench" / "search")
    parser.add_argument("--fractions", type=float, nargs="+", default=list(FRACTIONS))
    args = parser.parse_args(argv)
    if args.exhaustive:
        make_exhaustive(args.root, tuple(args.space or SPACES))
        return
    found = rows(measure(args.seeds, tuple(args.space or SPACES), tuple(args.fractions)))
    for r in found:
        print(f"{r['benchmark']}  {r['ratio']:.3f}  {r['target']}; {r['detail']}")
        if "table" in r:
            print(r["table"], file=sys.stdout)


if __name__ == "__main__":
    main()
