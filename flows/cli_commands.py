"""The body of each ``eskin`` command: read its parsed arguments, call plain functions, print.

One ``handle_<command>`` per command of :func:`flows.cli_parser.build_parser`, which sets it as
the parsed namespace's ``handler``; each returns the exit status (:mod:`flows.cli`). What they
print is formatted in :mod:`flows.summaries` and :mod:`flows.cli_output`.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

from flows import cluster, interrupts
from flows.cli_output import (
    AUTH_STRING_FILE,
    StageProgress,
    format_server_info,
    print_out,
    with_record_access,
)
from flows.report import needs_report_folder
from flows.summaries import format_summary, format_sweep_summary, result_summary
from pipeline.errors import EskinError
from pipeline.results.hardware_constants import Constants, load_constants
from pipeline.results.readout_constants import PARAMETERS, EnergyModel

if TYPE_CHECKING:
    from storage import SweepStore

__all__ = [
    "handle_describe",
    "handle_optimize",
    "handle_power",
    "handle_report",
    "handle_run",
    "handle_serve",
    "handle_server",
    "handle_sweep",
]


def handle_run(args: argparse.Namespace) -> int:
    """``eskin run``: simulate one scene and print its summary."""
    from flows.environment import tune_allocator
    from pipeline.design.scene import Scene
    from pipeline.recordings.sources import resolve_dataset_argument
    from pipeline.run.simulate import run_scene, stage_names

    tune_allocator()
    scene = Scene.load(args.scene)
    if args.dataset is not None:
        override = resolve_dataset_argument(args.dataset)
        scene = scene.replace(**{f"dataset.{k}": v for k, v in override.items()})
    progress = StageProgress(stage_names(scene), enabled=not (args.json or args.quiet))
    try:
        result = run_scene(scene, on_stage=progress.advance)
    finally:
        progress.close()
    summary = result_summary(result)
    print_out(args.json, summary, format_summary)
    return 0


@contextlib.contextmanager
def _tls_settings(args: argparse.Namespace) -> Iterator[None]:
    """The ``--tls-*`` files of a command on a cluster as Dask's own settings, while it runs
    (the flow's client reads them as any Dask client does)."""
    import dask

    files = {
        option: getattr(args, option.lstrip("-").replace("-", "_"))
        for option in cluster.TLS_OPTIONS
    }
    with dask.config.set(cluster.tls_config(args.address, files)):
        yield


def handle_sweep(args: argparse.Namespace) -> int:
    """``eskin sweep``: the flow ``sweep`` on the grid, or its dry run."""
    with _tls_settings(args):
        return _sweep(args)


def _sweep(args: argparse.Namespace) -> int:
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
        print_out(args.json, plan.to_json(), lambda _: format_dry_run(plan))
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
    from flows.server import auth_file, prefect_server

    interrupts.handle_interrupts()
    start = time.perf_counter()
    # Refuse a second run on this root before Prefect starts; the flow's own lock nests in it.
    with store.lock():
        hermetic_environment(store.root)
        if args.json or args.quiet:
            os.environ.setdefault("PREFECT_LOGGING_LEVEL", "WARNING")
        local = "PREFECT_API_URL" not in os.environ  # else the user's server, and login
        with (
            prefect_server(show_progress=not args.quiet) as api_url,
            recording(api_url) as record,
        ):
            summary = _outcome(record, run, store)
    # The whole run as the user waits for it, the server start included.
    summary["seconds"] = time.perf_counter() - start
    summary["prefect_record"] = "complete" if record.complete else "incomplete"
    if local:
        summary[AUTH_STRING_FILE] = str(auth_file())
    print_out(args.json, summary, lambda s: with_record_access(format_text(s), s))
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


def handle_optimize(args: argparse.Namespace) -> int:
    """``eskin optimize``: the flow ``optimize``, a search of the design space."""
    with _tls_settings(args):
        return _optimize(args)


def _optimize(args: argparse.Namespace) -> int:
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


def handle_describe(args: argparse.Namespace) -> int:
    """``eskin describe``: is a dataset informative? Optionally export it as a folder dataset."""
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
    out = description.to_json()
    if export is not None:
        out["export"] = export.to_json()
    print_out(args.json, out, lambda _: format_description(description, export), strict=True)
    return 0


def handle_server(args: argparse.Namespace) -> int:
    """``eskin server start|status|stop``: the local Prefect server."""
    from flows import server

    if args.action == "start":
        with server.prefect_server(show_progress=not args.quiet) as api_url:
            pass
        info = {"running": True, "api_url": api_url, "ui_url": api_url.removesuffix("/api")}
        if server.auth_file().is_file() and "PREFECT_API_URL" not in os.environ:
            info[AUTH_STRING_FILE] = str(server.auth_file())
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
            info[AUTH_STRING_FILE] = str(server.auth_file())
    print_out(args.json, info, format_server_info)
    return 0


def handle_report(args: argparse.Namespace) -> int:
    """``eskin report``: write a run root's report and print the path of its HTML."""
    from flows.report import write_run_report

    out = Path(args.out) if args.out else None
    from storage.objects import run_root

    path = write_run_report(
        run_root(args.root),
        out,
        adc_bits=args.adc_bits,
        adc_rate_hz=args.adc_rate_hz,
        constants=_constants(args),
        show_progress=not args.quiet,
    )
    print(path)
    return 0


def handle_power(args: argparse.Namespace) -> int:
    """``eskin power``: both readouts' power and data rate, without a sweep."""
    from flows.summaries import format_power
    from pipeline.results.readout_power import power_budget

    try:
        budget = power_budget(
            args.taxels,
            args.event_rate_hz,
            args.bits,
            args.sampling_rate_hz,
            _constants(args).energy_model(),
        )
    except ValueError as exc:
        raise EskinError(str(exc)) from None
    print_out(args.json, budget.to_json(), lambda _: format_power(budget), strict=True)
    return 0


def handle_serve(args: argparse.Namespace) -> int:
    """``eskin serve``: the flows as deployments on a Prefect server, until stopped."""
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


def _constants(args: argparse.Namespace) -> Constants:
    """The hardware constants of ``--constants FILE`` (every constant as declared without it),
    each ``--<constant>`` option given overriding its constant on top."""
    constants = load_constants(args.constants) if args.constants else Constants()
    given = EnergyModel.from_options({name: getattr(args, name) for name in PARAMETERS})
    for name, p in PARAMETERS.items():
        if getattr(args, name) is not None:
            constants = constants.overriding(
                name, getattr(given, name), f"set on the command line ({p.option})"
            )
    return constants
