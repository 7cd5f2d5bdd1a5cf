"""The ``eskin`` command line: it parses arguments, calls plain functions and prints.

``eskin run`` simulates one scene; ``eskin sweep`` runs the Prefect flow ``sweep`` on Dask;
``eskin optimize`` runs the flow ``optimize``, a search of a design space on the same machinery;
``eskin server`` starts, shows or stops the local Prefect server sweeps use; ``eskin serve``
serves the flow as a deployment; ``eskin report`` writes a run root's report; ``eskin power``
prints both readouts' power and data rate for an array and an event rate, without a sweep.

Exit status: 0 on success, 2 for bad input or usage (one line ``eskin: error: ...`` on stderr
naming what and where), 1 for a run that failed on good input (a point that failed more often
than Dask allows, a Prefect server that could not start) or a refused ``server stop``, 130 when
interrupted (Ctrl-C, SIGTERM).

A sweep or a search whose Prefect server stopped answering (stopped, killed, restarted) goes
on and ends as it would have: its results are complete, and if the server did not answer again
before the end it adds one line ``eskin: note: the Prefect record of this run is incomplete
(...)`` on stderr (``"prefect_record": "incomplete"`` with ``--json``). Its exit status is
still 0: the store, not Prefect, holds the results, and a script that goes on to the report
must not take complete results for a failure.

An interrupted run (Ctrl-C, SIGTERM) unwinds within seconds, stops what it started and exits
with status 130 (:mod:`flows.interrupts`).

JSON numbers that are infinite (an SSNR of a REAL train equal to its TRUE train) are written as the
strings ``"inf"`` and ``"-inf"``: JSON has no infinity, and ``float("inf")`` reads them back.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any, NoReturn

from flows import cluster, interrupts
from flows.report import DEFAULT_ADC_BITS, needs_report_folder
from flows.summaries import format_summary, format_sweep_summary, json_safe, result_summary
from pipeline.errors import EskinError
from pipeline.results.readout_power import MAX_BITS

if TYPE_CHECKING:
    from storage import SweepStore

EXIT_USER_ERROR = 2


_POWER_TEXT = {
    "help": "both readouts' power (static and dynamic) and data rate for an array and an event "
    "rate, without a sweep",
    "description": "Estimate the power and data rate of the event readout of an array of N "
    "taxels sending R events/s in all, and of a frame readout of the same array (a B-bit ADC "
    "sampling every taxel at F Hz), from the energy model (static bias of the front end and "
    "comparators, energy per event, per link bit and per ADC conversion).",
    "epilog": "The defaults are calibrated on the chip of Alea et al., IEEE TBioCAS 2024: "
    "--taxels 192 --event-rate-hz 2200 gives about 12.2 nW per taxel (the chip: 12.33).",
}


class _Parser(argparse.ArgumentParser):
    """argparse with the command line's error format: one line on stderr, exit status 2."""

    def error(self, message: str) -> NoReturn:
        self.exit(EXIT_USER_ERROR, f"eskin: error: {message} (see {self.prog} --help)\n")


def _workers(text: str) -> int:
    # The cluster's rule, reported as argparse reports a bad option (it names --workers).
    try:
        return cluster.check_workers(text)
    except cluster.ClusterError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def _positive(kind: type) -> Any:
    """An argparse type: a number of ``kind`` above zero."""

    def read(text: str) -> Any:
        try:
            value = kind(text)
        except ValueError:
            value = None
        if value is None or not value > 0 or value == float("inf"):
            raise argparse.ArgumentTypeError(f"expected a positive number, got {text!r}")
        return value

    return read


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("eskin-sweep")
    except PackageNotFoundError:
        return "unknown"


def _scene_fields_epilog() -> str:
    """Every scene field, one line each, from the schema's single declaration of it."""
    from pipeline.design.scene import scene_fields

    lines = (f"  {field.text()}" for field in scene_fields())
    return "Scene fields (scene files, a grid's base and its axes; dotted paths):\n" + "\n".join(
        lines
    )


def _add_cluster_options(command: argparse.ArgumentParser, workers: str) -> None:
    """``--workers N`` (``workers`` says what they are) or ``--address``, not both, and the
    ``--tls-*`` files of a ``tls://`` address (:data:`flows.cluster.TLS_OPTIONS`)."""
    where = command.add_mutually_exclusive_group()
    where.add_argument(
        "--workers",
        type=_workers,
        metavar="N",
        help=f"{workers} (default: the cores available, {cluster.available_cores()} here)",
    )
    where.add_argument(
        "--address",
        metavar="tcp|tls://HOST:PORT",
        help="use an existing Dask scheduler instead (tls:// with the three --tls-* files, or "
        "Dask's distributed.comm.tls settings)",
    )
    for option, what in (
        ("--tls-ca-file", "the CA certificate that signed the scheduler's certificate"),
        ("--tls-cert", "this client's certificate"),
        ("--tls-key", "this client's private key"),
    ):
        command.add_argument(option, metavar="FILE", help=f"{what} (PEM), for --address tls://")


def build_parser() -> argparse.ArgumentParser:
    """The ``eskin`` argument parser: its commands (``run``, ``sweep``, ``optimize``, ``server``,
    ``serve``, ``describe``, ``report``, ``power``) and their options, each command's handler set
    as ``handler`` on the parsed namespace. A usage error exits with status 2 and one line on
    stderr."""
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
        epilog=_scene_fields_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
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
        epilog=_scene_fields_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
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
        help="where the store goes, a folder or s3://bucket/prefix (default: runs/<grid name>, "
        "or runs/<grid name>-<dataset name> with --dataset)",
    )
    _add_cluster_options(sweep, "local Dask workers, 1 thread each")
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
    sweep.set_defaults(handler=_on_cluster(_sweep_checked))

    optimize = commands.add_parser(
        "optimize",
        parents=[common],
        help="search a design space (ranges over scene fields, two or three objectives) on the "
        "sweep's cache and cluster, and write its trials and front as cubes",
        description="Run the Prefect flow 'optimize': a multi-objective search (Optuna's GP or "
        "TPE, ask-and-tell, a trial started as each worker frees) whose trials are computed as "
        "sweep points, on Dask workers, through the "
        "root's cache. The search is kept in the root: run it again to resume or to continue "
        "it with a larger budget.",
        epilog=_scene_fields_epilog(),
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    optimize.add_argument(
        "--space",
        required=True,
        metavar="FILE",
        help="a space TOML file (see docs/how-to/search.md)",
    )
    optimize.add_argument(
        "--root", metavar="DIR", help="the store's folder, not s3:// (default: runs/<space name>)"
    )
    budget = optimize.add_mutually_exclusive_group()
    budget.add_argument(
        "--budget",
        type=_positive(int),
        metavar="N",
        help="trials in all, this run and earlier ones of the root (default 50)",
    )
    budget.add_argument(
        "--budget-s",
        type=_positive(float),
        metavar="SECONDS",
        help="stage seconds of the trials in all, each point and spike train counted once",
    )
    _add_cluster_options(optimize, "local Dask workers, 1 thread each: trials running at once")
    optimize.add_argument(
        "--report", action="store_true", help="write the report (<root>/report) at the end"
    )
    optimize.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    optimize.set_defaults(handler=_on_cluster(_optimize_checked))

    server = commands.add_parser(
        "server",
        parents=[common],
        help="start, show or stop the local Prefect server that sweeps use",
        description="Sweeps use the Prefect server named by PREFECT_API_URL, or else a local "
        "one (127.0.0.1, state in $ESKIN_SERVER_DIR, default runs/.prefect) that the first "
        "sweep starts and later sweeps reuse; it stops by itself after $ESKIN_SERVER_IDLE_S "
        "seconds (default 1800) without a sweep. It asks every client for the auth string "
        "in <state>/auth-string (only its owner may read it), which the UI asks for too.",
    )
    server.add_argument("action", choices=["start", "status", "stop"])
    server.add_argument(
        "--force",
        action="store_true",
        help="stop: stop the server even while sweeps or searches use it (refused otherwise, "
        "naming them); they go on computing and end with their Prefect record incomplete",
    )
    server.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    server.set_defaults(handler=_server)

    serve = commands.add_parser(
        "serve",
        parents=[common],
        help="serve the flows 'sweep' and 'optimize' as the deployments sweep/default and "
        "optimize/default on a Prefect server",
        description="Serve the flows 'sweep' and 'optimize' as deployments 'default' on the "
        "server of PREFECT_API_URL, or on the local one (started if need be, kept up while "
        "serving). Start sweeps with: prefect deployment run sweep/default --param grid=smoke "
        "--param root=DIR; searches with: prefect deployment run optimize/default --param "
        "space=FILE --param root=DIR --param budget=N",
    )
    serve.add_argument(
        "--grid",
        default="smoke",
        metavar="NAME|FILE",
        help="default grid of the deployment (default: smoke)",
    )
    serve.add_argument(
        "--space",
        metavar="FILE",
        help="default space of the optimize deployment (default: examples/design_space.toml "
        "of the serving process's folder)",
    )
    serve.set_defaults(handler=_serve)

    describe = commands.add_parser(
        "describe",
        parents=[common],
        help="is a dataset informative? its classes, durations and touch statistics beside real "
        "touches, with warnings",
        description="Describe a dataset before sweeping it: classes, touches per class, sampling "
        "rate, durations, the 0.1 s windows it holds, the statistics of real texture touches "
        "(envelope correlation within and between classes, contact transient, slow decay, level "
        "spread, spectra) beside their real values, and plain warnings.",
    )
    describe.add_argument(
        "--dataset",
        metavar="NAME|PATH",
        help="'synthetic' (the default: the built-in data eskin run uses), a VibTac-12 folder "
        "(X/Y/Z.csv) or a folder dataset (dataset.toml)",
    )
    describe.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object on stdout (a statistic the dataset cannot give, NaN or "
        "infinite, is null)",
    )
    describe.add_argument(
        "--export",
        metavar="DIR",
        help="also write the recordings as a folder dataset (dataset.toml, one sub-folder per "
        "class, one float64 .npy per recording) to DIR, a new or empty folder",
    )
    describe.set_defaults(handler=_describe)

    energy = _energy_options()
    report = commands.add_parser(
        "report",
        parents=[common, energy],
        help="turn a sweep's cubes into the cheapest design as accurate as the best, the paper's "
        "claims, figures and Table I, and the cost of accuracy",
        description="Write figures (PNG, SVG), report.md and a self-contained report.html from "
        "the result cubes of a run root, and print the path of report.html. The report opens "
        "with, per model, the cheapest design (by data rate and by estimated readout power) "
        "whose accuracy is not significantly below the run's best, against a frame-based ADC "
        "readout of the same array.",
    )
    report.add_argument(
        "--root", required=True, metavar="DIR", help="the run root of a sweep (or s3://...)"
    )
    report.add_argument(
        "--out",
        metavar="DIR",
        help="the report folder (default: <root>/report, required for s3://; replaced whole)",
    )
    report.add_argument(
        "--adc-bits",
        type=int,
        default=DEFAULT_ADC_BITS,
        metavar="N",
        help="resolution of the frame-based ADC readout the report compares with "
        f"(default {DEFAULT_ADC_BITS})",
    )
    report.add_argument(
        "--adc-rate-hz",
        type=float,
        metavar="HZ",
        help="its frame rate per taxel (default: the recordings' sampling rate)",
    )
    report.set_defaults(handler=_report)

    power = commands.add_parser("power", parents=[common, energy], **_POWER_TEXT)
    power.add_argument(
        "--taxels",
        required=True,
        type=_checked("--taxels", whole=True),
        metavar="N",
        help="taxels in the array",
    )
    power.add_argument(
        "--event-rate-hz",
        required=True,
        type=_checked("--event-rate-hz"),
        metavar="R",
        help="events per second of the whole array",
    )
    power.add_argument(
        "--bits",
        type=_checked("--bits", at_most=MAX_BITS),
        default=DEFAULT_ADC_BITS,
        metavar="B",
        help=f"resolution of the frame readout's ADC (default {DEFAULT_ADC_BITS})",
    )
    power.add_argument(
        "--sampling-rate-hz",
        type=_checked("--sampling-rate-hz", positive=True),
        metavar="F",
        help="samples per second per taxel of the frame readout (default: none; the frame "
        "readout is then unknown)",
    )
    power.add_argument(
        "--json",
        action="store_true",
        help="print one JSON object on stdout (an unknown figure is null)",
    )
    power.set_defaults(handler=_power)
    return parser


def _energy_options() -> argparse.ArgumentParser:
    """The energy model's constants as options, each declared once on its field."""
    from pipeline.results.readout_constants import PARAMETERS, EnergyModel

    parent = argparse.ArgumentParser(add_help=False)
    group = parent.add_argument_group(
        "energy model (defaults calibrated on the chip of Alea et al., IEEE TBioCAS 2024, and "
        "taken from the literature: see docs/how-to/report.md)"
    )
    defaults = EnergyModel()
    for name, p in PARAMETERS.items():
        group.add_argument(
            p.option,
            dest=name,
            type=_checked(p.option, whole=p.count),
            metavar=p.unit.split()[0].upper() if not p.count else "N",
            help=f"{p.what}, in {p.unit} (default {getattr(defaults, name) / p.scale:g})",
        )
    return parent


def _checked(
    option: str, *, whole: bool = False, positive: bool = False, at_most: float = math.inf
):
    """An argparse ``type``: a finite number >= 0 (a whole number >= 1, or > 0; at most
    ``at_most``), named in argparse's one-line error."""
    from pipeline.results.readout_constants import Parameter

    rule = Parameter(option, "", 1.0, "", "", count=whole)

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        problem = rule.problem(value)
        if problem is None and positive and value == 0:
            problem = f"{option} 0: need a number > 0"
        if problem is None and value > at_most:
            problem = f"{option} {value:g}: need at most {at_most:g}"
        if problem is not None:
            raise argparse.ArgumentTypeError(problem.removeprefix(f"{option} "))
        return int(value) if whole else value

    return parse


def _energy(args: argparse.Namespace):
    from pipeline.results.readout_constants import PARAMETERS, EnergyModel

    return EnergyModel.from_options({name: getattr(args, name) for name in PARAMETERS})


def main(argv: list[str] | None = None) -> int:
    """The ``eskin`` command: parse ``argv`` (default: ``sys.argv[1:]``) with
    :func:`build_parser`, run the command's handler and return its exit status (see the module
    docstring). An :class:`pipeline.errors.EskinError` prints one line ``eskin: error: ...`` on
    stderr and returns the error's exit status; an interrupt returns 130.
    """
    interrupts.as_program(argv is None)
    if interrupts.is_program():
        from flows.environment import skip_exit_collection

        skip_exit_collection()
    args = build_parser().parse_args(argv)
    status = _handled(args)
    if interrupts.is_program():
        interrupts.exit_after(interrupts.EXIT_GRACE_S, status)
    return status


def _handled(args: argparse.Namespace) -> int:
    """The handler's exit status; errors and interrupts as the module docstring says."""
    try:
        return args.handler(args)
    except EskinError as exc:
        if not interrupts.signalled.is_set():
            print(f"eskin: error: {exc}", file=sys.stderr)
            return exc.exit_status
    except Exception:
        if not interrupts.signalled.is_set():
            raise
    except (SystemExit, GeneratorExit):
        raise
    except BaseException:  # KeyboardInterrupt; Prefect's TerminationSignal for a SIGTERM
        pass
    # Interrupted: a SIGTERM that Prefect's handler saw may come out as another exception.
    print("eskin: interrupted", file=sys.stderr)
    if interrupts.is_program():
        # What it started is stopped, the store holds what was written, the record is closed:
        # nothing is left to wait for at exit (Prefect's flushes to a server that may be gone
        # took seconds there, past the deadline's reach once the interpreter finalizes).
        interrupts.stop_started_processes(grace_s=1.0)
        interrupts.exit_now(interrupts.EXIT_INTERRUPTED, quiet=True)
    return interrupts.EXIT_INTERRUPTED


def _run(args: argparse.Namespace) -> int:
    from flows.environment import tune_allocator
    from pipeline.design.scene import Scene
    from pipeline.recordings.sources import resolve_dataset_argument
    from pipeline.run.simulate import run_scene, stage_names

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
        print(json.dumps(json_safe(summary), indent=2))
    else:
        print(format_summary(summary))
    return 0


def _on_cluster(checked: Callable[[argparse.Namespace], int]) -> Callable[..., int]:
    """The handler of a command with :func:`_add_cluster_options`: ``checked(args)`` with the
    ``--tls-*`` files as Dask's own settings (the flow's client reads them as any Dask client
    does)."""

    def handler(args: argparse.Namespace) -> int:
        import dask

        files = {
            option: getattr(args, option.lstrip("-").replace("-", "_"))
            for option in cluster.TLS_OPTIONS
        }
        with dask.config.set(cluster.tls_config(args.address, files)):
            return checked(args)

    return handler


def _sweep_checked(args: argparse.Namespace) -> int:
    from flows.cluster import probe_scheduler
    from flows.dry_run import dry_run, format_dry_run
    from flows.planning import check_grid, default_root, load_sweep_grid
    from storage import SweepStore
    from storage.objects import run_root

    workers = args.workers or cluster.available_cores()
    # The grid is loaded and checked once, here, before the store is created and Prefect
    # imported (bad input writes nothing); the flow is handed the checked grid.
    grid = load_sweep_grid(args.grid, args.dataset)
    check_grid(grid)
    if args.address is not None:
        probe_scheduler(args.address)
    root = run_root(args.root) if args.root else default_root(grid, args.dataset)
    if args.report and (problem := needs_report_folder(root)):
        raise EskinError(f"--report: {problem}")
    if args.dry_run:
        plan = dry_run(grid, root, workers)
        print(
            json.dumps(json_safe(plan.to_json()), indent=2) if args.json else format_dry_run(plan)
        )
        return 0

    def run(store: SweepStore) -> dict[str, Any]:
        from flows.sweep import sweep

        return sweep(
            grid=grid,
            root=str(store.root),
            workers=workers,
            address=args.address,
            report=args.report,
            show_progress=not args.quiet,
        )

    return _run_flow(args, SweepStore.open_or_create(root), run, format_sweep_summary)


def _run_flow(
    args: argparse.Namespace,
    store: SweepStore,
    run: Callable[[SweepStore], dict[str, Any]],
    format_text: Callable[[dict[str, Any]], str],
) -> int:
    """Run a flow (``run(store)``) on ``store``'s root holding its lock, with the Prefect server
    up and the run's record active (:mod:`flows.record`), and print its summary
    (``format_text`` of it, or JSON with ``--json``), then the record's note if it is
    incomplete."""
    from flows.environment import hermetic_environment
    from flows.record import recording
    from flows.server import prefect_server

    interrupts.handle_interrupts()
    start = time.perf_counter()
    # Refuse a second run on this root before Prefect starts; the flow's own lock nests in it.
    with store.lock():
        hermetic_environment(store.root)
        if args.json or args.quiet:
            os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
        with (
            prefect_server(show_progress=not args.quiet) as api_url,
            recording(api_url) as record,
        ):
            summary = _outcome(record, run, store)
    # The whole run as the user waits for it, the server start included.
    summary["seconds"] = time.perf_counter() - start
    summary["prefect_record"] = "complete" if record.complete else "incomplete"
    if args.json:
        print(json.dumps(json_safe(summary), indent=2))
    else:
        print(format_text(summary))
    if not record.complete:
        print(record.incomplete_note(), file=sys.stderr)
    return 0


def _outcome(record: Any, run: Callable[[SweepStore], Any], store: SweepStore) -> Any:
    """``run(store)``'s result: the flow's, or, when Prefect failed to record the end of a
    flow whose body had ended, the body's own (the record's ``outcome``), its final
    state then left to the record. A run whose server answered busy before its body began is
    started again (:func:`flows.record.started`)."""
    from prefect.states import Completed, Failed, State

    from flows.record import started

    try:
        return started(record, lambda: run(store))
    except Exception as error:
        outcome = record.outcome
        if not outcome.done or error is outcome.error:
            raise  # the run's own failure, or Prefect's before the run began
        record.was_down = True
        if outcome.error is not None:
            record.final_state(Failed(message=str(outcome.error)))
            raise outcome.error from None
        if isinstance(outcome.value, State):  # a flow that ended so (a failed write)
            record.final_state(outcome.value)
            return outcome.value.result()
        record.final_state(Completed(message="recorded after the server answered again"))
        return outcome.value


def _optimize_checked(args: argparse.Namespace) -> int:
    from flows.cluster import probe_scheduler
    from flows.search import check_journal, check_search_root, check_space, default_search_root
    from flows.summaries import format_search_summary
    from pipeline.design.space import load_space
    from storage import SweepStore

    # The space is loaded and checked before the store is created and Prefect imported.
    space = load_space(args.space)
    check_space(space)
    if args.address is not None:
        probe_scheduler(args.address)

    def run(store: SweepStore) -> dict[str, Any]:
        from flows.optimize import optimize

        return optimize(
            space=space,
            root=str(store.root),
            budget=args.budget,
            budget_s=args.budget_s,
            workers=args.workers or cluster.available_cores(),
            address=args.address,
            report=args.report,
            show_progress=not args.quiet,
        )

    root = check_search_root(args.root) if args.root else default_search_root(space)
    check_journal(space, root)  # another search's journal, refused before Prefect starts
    return _run_flow(args, SweepStore.open_or_create(root), run, format_search_summary)


def _describe(args: argparse.Namespace) -> int:
    from flows.describe import (
        check_export_folder,
        dataset_spec,
        describe_source,
        export_folder,
        format_description,
    )
    from pipeline.recordings.describe import describe_dataset
    from pipeline.recordings.sources import load_recordings

    spec = dataset_spec(args.dataset)
    if args.export is not None:
        check_export_folder(args.export, spec)
    recordings = load_recordings(spec)
    description = describe_dataset(recordings)
    export = None
    if args.export is not None:
        export = export_folder(recordings, args.export, source=describe_source(spec))
    if args.json:
        out = description.to_json()
        if export is not None:
            out["export"] = export.to_json()
        print(json.dumps(out, indent=2, allow_nan=False))
    else:
        print(format_description(description, export))
    return 0


def _server(args: argparse.Namespace) -> int:
    from flows import server

    if args.action == "start":
        with server.prefect_server(show_progress=not args.quiet) as api_url:
            pass
        info = {"running": True, "api_url": api_url, "ui_url": api_url.removesuffix("/api")}
        if server.auth_file().is_file() and "PREFECT_API_URL" not in os.environ:
            info["auth_string_file"] = str(server.auth_file())
    elif args.action == "stop":
        if not args.force:
            server.check_stoppable()
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
            info["auth_string_file"] = str(server.auth_file())
    if args.json:
        print(json.dumps(info, indent=2))
    elif args.action == "stop":
        print("stopped the Prefect server" if info["stopped"] else "no Prefect server was running")
    elif info["running"]:
        print(
            f"Prefect server: {info['ui_url']}" + (f" (PID {info['pid']})" if "pid" in info else "")
        )
        if "auth_string_file" in info:
            print(f"The UI asks for the auth string in {info['auth_string_file']}")
    else:
        print(f"no Prefect server running (state in {info['state_dir']})")
    return 0


def _report(args: argparse.Namespace) -> int:
    from flows.report import write_run_report

    out = Path(args.out) if args.out else None
    from storage.objects import run_root

    path = write_run_report(
        run_root(args.root),
        out,
        adc_bits=args.adc_bits,
        adc_rate_hz=args.adc_rate_hz,
        energy=_energy(args),
        show_progress=not args.quiet,
    )
    print(path)
    return 0


def _power(args: argparse.Namespace) -> int:
    from flows.summaries import format_power
    from pipeline.results.readout_power import power_budget

    try:
        budget = power_budget(
            args.taxels, args.event_rate_hz, args.bits, args.sampling_rate_hz, _energy(args)
        )
    except ValueError as exc:
        raise EskinError(str(exc)) from None
    if args.json:
        print(json.dumps(budget.to_json(), indent=2, allow_nan=False))
    else:
        print(format_power(budget))
    return 0


def _serve(args: argparse.Namespace) -> int:
    from flows.planning import load_sweep_grid
    from flows.server import prefect_server

    load_sweep_grid(args.grid)
    search = {}
    if args.space is not None:
        from pipeline.design.space import load_space

        load_space(args.space)
        search["space"] = str(Path(args.space).resolve())
    with prefect_server(show_progress=not args.quiet) as api_url:
        from prefect import serve

        from flows.optimize import optimize
        from flows.sweep import sweep

        if not args.quiet:
            print(
                f"serving sweep/default and optimize/default on {api_url.removesuffix('/api')}",
                file=sys.stderr,
            )
        serve(
            sweep.to_deployment(name="default", parameters={"grid": args.grid}),
            optimize.to_deployment(name="default", parameters=search),
        )
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


if __name__ == "__main__":
    sys.exit(main())
