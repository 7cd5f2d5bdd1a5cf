"""The ``eskin`` command line's parser: every command and option, declared once.

:func:`build_parser` is what :func:`flows.cli.main` parses with and what the command-line page of
the docs reads (sphinx-argparse). Each command's body is in :mod:`flows.cli_commands`, set as
``handler`` on the parsed namespace. A usage error exits with status 2 and one line
``eskin: error: ...`` on stderr. The energy model's constants are options of ``eskin report`` and
``eskin power``, each declared once on its field
(:class:`pipeline.results.readout_constants.EnergyModel`), and both take a file of any declared
hardware constants (``--constants FILE``, :mod:`pipeline.results.hardware_constants`).
"""

from __future__ import annotations

import argparse
import math
from typing import Any, NoReturn

from flows import cluster
from flows.cli_commands import (
    handle_describe,
    handle_optimize,
    handle_power,
    handle_report,
    handle_run,
    handle_serve,
    handle_server,
    handle_sweep,
)
from flows.report import DEFAULT_ADC_BITS
from pipeline.results.readout_power import MAX_BITS

__all__ = ["EXIT_USER_ERROR", "build_parser"]

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
    run.set_defaults(handler=handle_run)

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
    sweep.set_defaults(handler=handle_sweep)

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
    optimize.set_defaults(handler=handle_optimize)

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
    server.set_defaults(handler=handle_server)

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
    serve.set_defaults(handler=handle_serve)

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
    describe.set_defaults(handler=handle_describe)

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
    report.set_defaults(handler=handle_report)

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
    power.set_defaults(handler=handle_power)
    return parser


def _energy_options() -> argparse.ArgumentParser:
    """The energy model's constants as options, each declared once on its field."""
    from pipeline.results.readout_constants import PARAMETERS, EnergyModel

    parent = argparse.ArgumentParser(add_help=False)
    group = parent.add_argument_group(
        "energy model (defaults calibrated on the chip of Alea et al., IEEE TBioCAS 2024, and "
        "taken from the literature: see docs/how-to/report.md)"
    )
    group.add_argument(
        "--constants",
        metavar="FILE",
        help="a TOML file of hardware constants overriding the declared ones (power model, "
        "Pelgrom's A_VT, the decoder's per-operation energies), each with its value, unit and "
        "source (see docs/how-to/constants.md); the options below override it in turn",
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

    rule = Parameter("", 1.0, "", "", option=option, count=whole)

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
