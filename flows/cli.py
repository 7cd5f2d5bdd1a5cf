"""The ``eskin`` command line.

``eskin run [--scene NAME|FILE] [--dataset NAME|PATH] [--json]`` simulates one scene and prints a
summary (or, with ``--json``, one JSON object on stdout). Errors in the user's input print one line
``eskin: error: ...`` on stderr and exit with status 2.

JSON numbers that are infinite (an SSNR of a REAL train equal to its TRUE train) are written as the
strings ``"inf"`` and ``"-inf"``: JSON has no infinity, and ``float("inf")`` reads them back.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import signal
import sys
import time
from pathlib import Path
from typing import Any, NoReturn

from pipeline.errors import EskinError

EXIT_USER_ERROR = 2


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's error format: one line on stderr, exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USER_ERROR, f"eskin: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="eskin",
        description="Neuromorphic e-skin design sweeps: spiking taxel readout to texture accuracy.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser(
        "run",
        help="simulate one scene and print its accuracy, spike metrics and stage timings",
        description="Simulate one scene end to end and print a summary.",
    )
    run.add_argument(
        "--scene",
        default="paper",
        metavar="NAME|FILE",
        help="a built-in scene (paper, smoke) or a scene TOML file (default: paper)",
    )
    run.add_argument(
        "--dataset",
        metavar="NAME|PATH",
        help="override the scene's recordings: 'synthetic', a VibTac-12 folder (X/Y/Z.csv) "
        "or a folder dataset (dataset.toml)",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    run.set_defaults(handler=_run)

    sweep = commands.add_parser(
        "sweep",
        help="sweep a grid of scenes on Dask and write labelled result cubes",
        description="Run the Prefect flow 'sweep': compute the grid's cache misses on Dask "
        "workers and write one xarray cube per sweep under the root.",
    )
    sweep.add_argument(
        "--grid",
        required=True,
        metavar="NAME|FILE",
        help="a built-in grid (paper, smoke) or a grid TOML file",
    )
    sweep.add_argument(
        "--root", metavar="DIR", help="where the store goes (default: runs/<grid name>)"
    )
    where = sweep.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=int,
        default=2,
        metavar="N",
        help="local Dask workers, 1 thread each (default 2)",
    )
    where.add_argument(
        "--address", metavar="tcp://HOST:PORT", help="use an existing Dask scheduler instead"
    )
    sweep.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    sweep.set_defaults(handler=_sweep)

    serve = commands.add_parser(
        "serve",
        help="serve the 'sweep' flow as the deployment sweep/default on a Prefect server",
        description="Serve the flow 'sweep' as deployment 'default' (needs PREFECT_API_URL). "
        "Start sweeps with: prefect deployment run sweep/default --param grid=smoke "
        "--param root=DIR",
    )
    serve.add_argument(
        "--grid", default="smoke", metavar="NAME|FILE", help="default grid of the deployment"
    )
    serve.set_defaults(handler=_serve)

    report = commands.add_parser(
        "report",
        help="turn a sweep's cubes into the paper's figures and Table I, and the cost of accuracy",
        description="Write figures (PNG, SVG), report.md and a self-contained report.html from "
        "the result cubes of a run root, and print the path of report.html.",
    )
    report.add_argument("--root", required=True, metavar="DIR", help="the run root of a sweep")
    report.add_argument(
        "--out", metavar="DIR", help="the report folder (default: <root>/report; replaced whole)"
    )
    report.add_argument(
        "--adc-bits",
        type=int,
        default=12,
        metavar="N",
        help="resolution of the frame-based ADC readout Table I compares with (default 12)",
    )
    report.add_argument(
        "--adc-rate-hz",
        type=float,
        metavar="HZ",
        help="its frame rate per taxel (default: the recordings' sampling rate)",
    )
    report.set_defaults(handler=_report)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except EskinError as exc:
        print(f"eskin: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("eskin: interrupted", file=sys.stderr)
        return 130


def _run(args: argparse.Namespace) -> int:
    from flows.environment import tune_allocator
    from pipeline.recordings import resolve_dataset_argument
    from pipeline.scene import Scene
    from pipeline.simulate import run_scene, stage_names

    tune_allocator()
    scene = Scene.load(args.scene)
    if args.dataset is not None:
        override = resolve_dataset_argument(args.dataset)
        scene = scene.replace(**{f"dataset.{k}": v for k, v in override.items()})
    progress = _StageProgress(stage_names(scene), enabled=not args.json)
    try:
        result = run_scene(scene, on_stage=progress.advance)
    finally:
        progress.close()
    summary = result_summary(result)
    if args.json:
        print(json.dumps(_json_safe(summary), indent=2))
    else:
        print(format_summary(summary))
    return 0


def _sweep(args: argparse.Namespace) -> int:
    from flows.cluster import probe_scheduler
    from flows.environment import hermetic_environment
    from pipeline.grid import load_grid
    from storage import SweepStore

    if args.workers < 1:
        raise EskinError(f"--workers {args.workers}: need at least 1")
    grid = load_grid(args.grid)
    # Every check runs before the store is created and Prefect imported: bad input writes nothing.
    from flows.orchestrate import check_grid, default_root

    check_grid(grid)
    if args.address is not None:
        probe_scheduler(args.address)
    root = Path(args.root) if args.root else default_root(grid)
    store = SweepStore.open_or_create(root)
    # SIGTERM unwinds like Ctrl-C, so the local Dask cluster and Prefect's temporary server
    # are stopped (the default action would kill this process alone and orphan the server).
    signal.signal(signal.SIGTERM, _interrupt)
    start = time.perf_counter()
    # Refuse a second sweep on this root before Prefect starts; the flow's own lock nests in it.
    with store.lock():
        hermetic_environment(store.root)
        if args.json:
            os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
        from flows.sweep import guard_temporary_server, sweep

        guard_temporary_server()
        summary = sweep(
            grid=args.grid,
            root=str(store.root),
            workers=args.workers,
            address=args.address,
            show_progress=not args.json,
        )
    # The whole sweep as the user waits for it, Prefect's temporary server included.
    summary["seconds"] = time.perf_counter() - start
    _log_sweep(store.root, {**summary, "grid": grid.name})
    if args.json:
        print(json.dumps(_json_safe(summary), indent=2))
    else:
        print(format_sweep_summary(summary))
    return 0


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


def format_sweep_summary(summary: dict[str, Any]) -> str:
    from storage import open_results

    cubes = open_results(summary["root"])
    lines = [
        f"{summary['points']} points ({summary['cache_hits']} cached, {summary['computed']} "
        f"computed) in {summary['seconds']:.1f} s",
        f"{'sweep':12s} {'dims':28s} {'model':6s} best accuracy (mean over folds)",
    ]
    for name in summary["cubes"]:
        cube = cubes[name]
        dims = ", ".join(f"{d}={cube.sizes[d]}" for d in cube["accuracy"].dims[:-2])
        mean = cube["accuracy"].mean("fold")
        for model in cube["model"].values:
            per_model = mean.sel(model=model)
            best = per_model.where(per_model == per_model.max(), drop=True)
            at = ", ".join(f"{d}={best[d].values.ravel()[0]:g}" for d in per_model.dims)
            lines.append(
                f"{name:12s} {dims:28s} {model:6s} {100 * float(per_model.max()):5.1f} % at {at}"
            )
    lines.append(f"cubes: {Path(summary['root']) / 'store.zarr' / 'cubes'}")
    lines.append(f"open with: storage.open_results({str(summary['root'])!r})")
    return "\n".join(lines)


def _log_sweep(root: Path, summary: dict[str, Any]) -> None:
    """Record the sweep's cache hits and wall time for ``eskin report``; never fail the sweep."""
    from storage.runlog import append_sweep_run

    try:
        append_sweep_run(root, summary)
    except OSError as error:
        print(f"eskin: warning: sweep not logged in {root}: {error}", file=sys.stderr)


def _report(args: argparse.Namespace) -> int:
    from contextlib import suppress

    from flows.environment import hermetic_environment
    from storage import SweepStore, open_results

    problems = []
    if args.adc_bits < 1:
        problems.append(f"--adc-bits {args.adc_bits}: need at least 1")
    if args.adc_rate_hz is not None and not (
        math.isfinite(args.adc_rate_hz) and args.adc_rate_hz > 0
    ):
        problems.append(f"--adc-rate-hz {args.adc_rate_hz:g}: need a number > 0")
    if problems:
        raise EskinError("; ".join(problems))
    store = SweepStore.open(args.root)
    cubes = open_results(store.root)
    if not cubes:
        raise EskinError(f"no result cubes in {store.root}: run 'eskin sweep' on it first")
    with suppress(OSError):  # a read-only root still gets its report elsewhere (--out)
        hermetic_environment(store.root, prefect=False)
    from pipeline.figures import draw_report
    from pipeline.report import FrameReadout, build_report, recording_facts
    from storage.report import write_report
    from storage.runlog import read_sweep_runs

    try:
        facts = recording_facts(next(iter(cubes.values())))
    except (EskinError, OSError) as error:
        print(f"eskin: warning: recordings not readable, classes unknown: {error}", file=sys.stderr)
        facts = None
    rate_hz = args.adc_rate_hz or (facts.fs_hz if facts else None)
    frame = FrameReadout(args.adc_bits, rate_hz) if rate_hz else None
    report = build_report(cubes, facts=facts, frame=frame, runs=read_sweep_runs(store.root))
    out = Path(args.out) if args.out else store.root / "report"
    print(write_report(out, report, draw_report(report), show_progress=True))
    return 0


def _serve(args: argparse.Namespace) -> int:
    if not os.environ.get("PREFECT_API_URL"):
        raise EskinError(
            "eskin serve needs a Prefect server: start one with 'prefect server start --host "
            "127.0.0.1' and set PREFECT_API_URL=http://127.0.0.1:4200/api"
        )
    from pipeline.grid import load_grid

    load_grid(args.grid)
    from flows.sweep import sweep

    sweep.serve(name="default", parameters={"grid": args.grid})
    return 0


class _StageProgress:
    """A tqdm bar over a run's stages, on stderr, shown only on a terminal."""

    def __init__(self, stages: tuple[str, ...], enabled: bool):
        from tqdm import tqdm

        self.bar = tqdm(
            total=len(stages),
            unit="stage",
            file=sys.stderr,
            disable=None if enabled else True,
            leave=False,
        )
        self.started = 0

    def advance(self, stage: str) -> None:
        if self.started:
            self.bar.update(1)
        self.started += 1
        self.bar.set_description(stage)

    def close(self) -> None:
        self.bar.close()


def result_summary(result: Any) -> dict[str, Any]:
    """The JSON object of ``eskin run --json`` (ARCHITECTURE section 7)."""
    scene = result.scene
    m = result.metrics
    return {
        "scene": scene.name,
        "dataset": scene.dataset.kind.value,
        "n_recordings": result.n_recordings,
        "n_classes": result.n_classes,
        "chance": 1.0 / result.n_classes,
        "taxels": scene.array.n_taxels,
        "threshold_v": scene.readout.threshold_v,
        "window_s": scene.coding.window_s,
        "n_windows": result.n_windows,
        "dropped_spikes": result.dropped_spikes,
        "accuracy": {
            model.value: {
                "mean": cv.mean,
                "std": cv.std,
                "folds": [float(a) for a in cv.fold_accuracy],
            }
            for model, cv in result.accuracy.items()
        },
        "ssnr_db": m.ssnr_db,
        "ste_s2": m.ste_s2,
        "ste_sign_safe_s2": m.ste_sign_safe_s2,
        "event_rate_hz": m.event_rate_hz,
        "data_rate_bps": m.data_rate_bps,
        "equivalent_bits": m.equivalent_bits,
        "timings_s": dict(result.timings_s),
    }


def format_summary(s: dict[str, Any]) -> str:
    lines = [
        f"scene {s['scene']!r} on {s['dataset']} data: {s['n_recordings']} recordings, "
        f"{s['n_classes']} classes (chance {100 * s['chance']:.1f} %)",
        f"  {s['taxels']} taxels, threshold {s['threshold_v']:g} V "
        f"({s['equivalent_bits']:.2f} equivalent bits), "
        f"{s['n_windows']} windows of {s['window_s']:g} s",
    ]
    for model, acc in s["accuracy"].items():
        lines.append(
            f"  {model.upper():5s} accuracy {100 * acc['mean']:5.1f} % "
            f"+- {100 * acc['std']:.1f} % over {len(acc['folds'])} folds"
        )
    ssnr = "inf (REAL = TRUE)" if math.isinf(s["ssnr_db"]) else f"{s['ssnr_db']:.2f}"
    lines += [
        f"  SSNR {ssnr} dB, STE {s['ste_s2']:.3g} s^2 (sign-safe {s['ste_sign_safe_s2']:.3g})",
        f"  event rate {s['event_rate_hz']:.4g} spikes/s, "
        f"data rate {s['data_rate_bps']:.4g} bit/s (address-event)",
        "  seconds: "
        + ", ".join(f"{stage} {sec:.2f}" for stage, sec in s["timings_s"].items())
        + f" (total {sum(s['timings_s'].values()):.1f})",
    ]
    return "\n".join(lines)


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else "-inf" if value < 0 else "nan"
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_safe(v) for v in value]
    return value


if __name__ == "__main__":
    sys.exit(main())
