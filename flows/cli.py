"""The ``eskin`` command line: it parses arguments, calls plain functions and prints.

``eskin run`` simulates one scene; ``eskin sweep`` runs the Prefect flow ``sweep`` on Dask;
``eskin server`` starts, shows or stops the local Prefect server sweeps use; ``eskin serve``
serves the flow as a deployment; ``eskin report`` writes a run root's report.

Exit status: 0 on success, 2 for bad input or usage (one line ``eskin: error: ...`` on stderr
naming what and where), 1 for a run that failed on good input (a point that failed more often
than Dask allows, a Prefect server that could not start), 130 when interrupted (Ctrl-C,
SIGTERM).

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

from flows import cluster
from flows.report import DEFAULT_ADC_BITS
from pipeline.errors import EskinError

EXIT_USER_ERROR = 2


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's error format: one line on stderr, exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USER_ERROR, f"eskin: error: {message} (see {self.prog} --help)\n")


def _positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r}: need a whole number >= 1")
    return value


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("eskin-sweep")
    except PackageNotFoundError:
        return "unknown"


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(
        prog="eskin",
        description="Neuromorphic e-skin design sweeps: spiking taxel readout to texture accuracy.",
        epilog="Exit status: 0 success, 1 a run that failed, 2 bad input or usage, 130 "
        "interrupted.",
    )
    parser.add_argument("--version", action="version", version=f"eskin {_version()}")
    common = argparse.ArgumentParser(add_help=False)
    common.add_argument(
        "-q",
        "--quiet",
        action="store_true",
        help="no progress bars, log lines or notes on stderr (errors still print)",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser(
        "run",
        parents=[common],
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
        parents=[common],
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
        "--root",
        metavar="DIR",
        help="where the store goes (default: runs/<grid name>, or runs/<grid name>-<dataset "
        "name> with --dataset)",
    )
    where = sweep.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=_positive_int,
        metavar="N",
        help=f"local Dask workers, 1 thread each (default: the cores available, "
        f"{cluster.available_cores()} here)",
    )
    where.add_argument(
        "--address", metavar="tcp://HOST:PORT", help="use an existing Dask scheduler instead"
    )
    sweep.add_argument(
        "--dataset",
        metavar="NAME|PATH",
        help="sweep the grid on other recordings: 'synthetic', a VibTac-12 folder (X/Y/Z.csv) "
        "or a folder dataset (dataset.toml)",
    )
    sweep.add_argument(
        "--dry-run",
        action="store_true",
        help="show the points, how many are cached and the estimated cost of the rest; "
        "write nothing",
    )
    sweep.add_argument(
        "--report", action="store_true", help="write the report (<root>/report) at the end"
    )
    sweep.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    sweep.set_defaults(handler=_sweep)

    server = commands.add_parser(
        "server",
        parents=[common],
        help="start, show or stop the local Prefect server that sweeps use",
        description="Sweeps use the Prefect server named by PREFECT_API_URL, or else a local "
        "one (127.0.0.1, state in $ESKIN_SERVER_DIR, default runs/.prefect) that the first "
        "sweep starts and later sweeps reuse; it stops by itself after $ESKIN_SERVER_IDLE_S "
        "seconds (default 1800) without a sweep.",
    )
    server.add_argument("action", choices=["start", "status", "stop"])
    server.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    server.set_defaults(handler=_server)

    serve = commands.add_parser(
        "serve",
        parents=[common],
        help="serve the 'sweep' flow as the deployment sweep/default on a Prefect server",
        description="Serve the flow 'sweep' as deployment 'default' on the server of "
        "PREFECT_API_URL, or on the local one (started if need be, kept up while serving). "
        "Start sweeps with: prefect deployment run sweep/default --param grid=smoke "
        "--param root=DIR",
    )
    serve.add_argument(
        "--grid", default="smoke", metavar="NAME|FILE", help="default grid of the deployment"
    )
    serve.set_defaults(handler=_serve)

    report = commands.add_parser(
        "report",
        parents=[common],
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
        default=DEFAULT_ADC_BITS,
        metavar="N",
        help="resolution of the frame-based ADC readout Table I compares with "
        f"(default {DEFAULT_ADC_BITS})",
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
        return exc.exit_status
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
    progress = _StageProgress(stage_names(scene), enabled=not (args.json or args.quiet))
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
    from flows.orchestrate import check_grid, default_root, dry_run, format_dry_run, load_sweep_grid
    from flows.server import prefect_server
    from storage import SweepStore

    workers = args.workers or cluster.available_cores()
    grid = load_sweep_grid(args.grid, args.dataset)
    # Every check runs before the store is created and Prefect imported: bad input writes nothing.
    check_grid(grid)
    if args.address is not None:
        probe_scheduler(args.address)
    root = Path(args.root) if args.root else default_root(grid, args.dataset)
    if args.dry_run:
        plan = dry_run(grid, root, workers)
        print(
            json.dumps(_json_safe(plan.to_json()), indent=2) if args.json else format_dry_run(plan)
        )
        return 0
    store = SweepStore.open_or_create(root)
    # SIGTERM unwinds like Ctrl-C, so the local Dask cluster is stopped (the default action
    # would kill this process alone).
    signal.signal(signal.SIGTERM, _interrupt)
    start = time.perf_counter()
    # Refuse a second sweep on this root before Prefect starts; the flow's own lock nests in it.
    with store.lock():
        hermetic_environment(store.root)
        if args.json or args.quiet:
            os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
        with prefect_server(show_progress=not args.quiet):
            from flows.sweep import sweep

            summary = sweep(
                grid=args.grid,
                root=str(store.root),
                workers=workers,
                address=args.address,
                dataset=args.dataset,
                report=args.report,
                show_progress=not args.quiet,
            )
    # The whole sweep as the user waits for it, the server start included.
    summary["seconds"] = time.perf_counter() - start
    if args.json:
        print(json.dumps(_json_safe(summary), indent=2))
    else:
        print(format_sweep_summary(summary))
    return 0


def _server(args: argparse.Namespace) -> int:
    from flows import server

    if args.action == "start":
        with server.prefect_server(show_progress=not args.quiet) as api_url:
            pass
        info = {"running": True, "api_url": api_url, "ui_url": api_url.removesuffix("/api")}
    elif args.action == "stop":
        stopped = server.stop()
        info = {
            "running": False,
            "stopped": stopped is not None,
            "state_dir": str(server.server_dir()),
        }
    else:
        found = server.status()
        info = {"running": found is not None, "state_dir": str(server.server_dir())}
        if found is not None:
            info |= {"api_url": found.api_url, "ui_url": found.ui_url, "pid": found.pid}
    if args.json:
        print(json.dumps(info, indent=2))
    elif args.action == "stop":
        print("stopped the Prefect server" if info["stopped"] else "no Prefect server was running")
    elif info["running"]:
        print(
            f"Prefect server: {info['ui_url']}" + (f" (PID {info['pid']})" if "pid" in info else "")
        )
    else:
        print(f"no Prefect server running (state in {info['state_dir']})")
    return 0


def _interrupt(signum: int, frame: Any) -> None:
    raise KeyboardInterrupt(signal.Signals(signum).name)


def format_sweep_summary(summary: dict[str, Any]) -> str:
    from flows.orchestrate import best_points
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
        for row in best_points(cube):
            at = ", ".join(f"{d}={v:g}" for d, v in row["at"].items())
            lines.append(
                f"{name:12s} {dims:28s} {row['model']:6s} {100 * row['accuracy']:5.1f} % at {at}"
            )
    lines.append(f"cubes: {Path(summary['root']) / 'store.zarr' / 'cubes'}")
    lines.append(f"open with: storage.open_results({str(summary['root'])!r})")
    if summary.get("report"):
        lines.append(f"report: {summary['report']}")
    if summary.get("flow_run_url"):
        lines.append(f"Prefect flow run: {summary['flow_run_url']}")
    return "\n".join(lines)


def _report(args: argparse.Namespace) -> int:
    from flows.report import write_run_report

    out = Path(args.out) if args.out else None
    path = write_run_report(
        Path(args.root),
        out,
        adc_bits=args.adc_bits,
        adc_rate_hz=args.adc_rate_hz,
        show_progress=not args.quiet,
    )
    print(path)
    return 0


def _serve(args: argparse.Namespace) -> int:
    from flows.orchestrate import load_sweep_grid
    from flows.server import prefect_server

    load_sweep_grid(args.grid)
    with prefect_server(show_progress=not args.quiet) as api_url:
        from flows.sweep import sweep

        if not args.quiet:
            print(f"serving sweep/default on {api_url.removesuffix('/api')}", file=sys.stderr)
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
