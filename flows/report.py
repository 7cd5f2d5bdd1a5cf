"""Write a run root's report: the plain function behind ``eskin report`` and the flow's report task.

It wires three layers together: :mod:`pipeline.report` turns the cubes into the design answer,
claims, tables and fronts (:mod:`pipeline.report.analysis`), draws them
(:mod:`pipeline.report.figures`) and renders the files of the report
(:mod:`pipeline.report.document`), and :mod:`storage.report` writes the folder whole. The command
line's frame-readout and energy options become a :class:`~pipeline.report.FrameReadout` and a
:class:`~pipeline.results.hardware.EnergyModel` here, checked before anything is read or written.
"""

from __future__ import annotations

import argparse
import math
import sys
from collections.abc import Callable
from contextlib import suppress
from pathlib import Path
from typing import TYPE_CHECKING

from pipeline.errors import EskinError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

    from pipeline.report import Report
    from pipeline.results.hardware import EnergyModel

DEFAULT_ADC_BITS = 12
# The energy options, in the units the command line takes them, and the EnergyModel field (in
# SI units) each sets: option -> (field, factor to SI).
ENERGY_OPTIONS = {
    "--event-energy-pj": ("event_energy_j", 1e-12),
    "--adc-fom-fj": ("adc_fom_j_per_step", 1e-15),
    "--link-energy-pj-per-bit": ("link_energy_j_per_bit", 1e-12),
}


def energy_problem(option: str, value: float) -> str | None:
    """Why ``value`` is not a valid ``option`` (one of :data:`ENERGY_OPTIONS`), or None."""
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"{option} {value!r}: need a number >= 0"
    if not math.isfinite(value) or value < 0:
        return f"{option} {value:g}: need a finite number >= 0"
    return None


def energy_argument(option: str) -> Callable[[str], float]:
    """An argparse ``type`` for an energy option: a finite number >= 0 (argparse names the
    option in its one-line error)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
        problem = energy_problem(option, value)
        if problem is not None:
            raise argparse.ArgumentTypeError(problem.removeprefix(f"{option} "))
        return value

    return parse


def energy_model(
    event_energy_pj: float | None = None,
    adc_fom_fj: float | None = None,
    link_energy_pj_per_bit: float | None = None,
) -> EnergyModel:
    """The energy model of the command line's options (None: the default of that constant).

    Raises
    ------
    EskinError
        A value is not a finite number >= 0; the message names every such option.
    """
    from pipeline.results.hardware import EnergyModel

    given = dict(
        zip(ENERGY_OPTIONS, (event_energy_pj, adc_fom_fj, link_energy_pj_per_bit), strict=True)
    )
    problems = [
        problem
        for option, value in given.items()
        if value is not None and (problem := energy_problem(option, value)) is not None
    ]
    if problems:
        raise EskinError("; ".join(problems))
    return EnergyModel(
        **{
            ENERGY_OPTIONS[option][0]: value * ENERGY_OPTIONS[option][1]
            for option, value in given.items()
            if value is not None
        }
    )


def write_run_report(
    root: Path,
    out: Path | None = None,
    *,
    adc_bits: int = DEFAULT_ADC_BITS,
    adc_rate_hz: float | None = None,
    event_energy_pj: float | None = None,
    adc_fom_fj: float | None = None,
    link_energy_pj_per_bit: float | None = None,
    show_progress: bool = False,
) -> Path:
    """Write the report of the sweep store at ``root``; return the path of its ``report.html``.

    Parameters
    ----------
    root
        A run root written by a sweep.
    out
        The report folder (default ``<root>/report``), replaced whole; a folder that is not an
        earlier report is refused.
    adc_bits, adc_rate_hz
        The frame-based ADC readout the answer, Table I and the fronts compare with: bits per
        sample and frame rate per taxel in Hz (default: the recordings' sampling rate, as the
        cubes state it).
    event_energy_pj, adc_fom_fj, link_energy_pj_per_bit
        The readout power estimate's constants: energy per event (pJ), the ADC's Walden figure
        of merit (fJ per conversion step), energy per link bit (pJ); None takes the default of
        :class:`pipeline.results.hardware.EnergyModel`.

    Raises
    ------
    EskinError
        Bad ADC or energy figures (before anything is read or written), a root that is not a
        sweep store, or a store with no cubes.
    """
    from flows.environment import hermetic_environment
    from pipeline.numbers import positive_number
    from pipeline.results.hardware import MAX_BITS
    from storage import SweepStore, open_results

    problems = []
    if not 1 <= adc_bits <= MAX_BITS:
        problems.append(f"--adc-bits {adc_bits}: need 1 to {MAX_BITS}")
    if adc_rate_hz is not None and positive_number(adc_rate_hz) is None:
        problems.append(f"--adc-rate-hz {adc_rate_hz:g}: need a number > 0")
    try:
        energy = energy_model(event_energy_pj, adc_fom_fj, link_energy_pj_per_bit)
    except EskinError as exc:
        problems.append(str(exc))
    if problems:
        raise EskinError("; ".join(problems))
    store = SweepStore.open(root)
    cubes = open_results(store.root)
    if not cubes:
        raise EskinError(f"no result cubes in {store.root}: run 'eskin sweep' on it first")
    with suppress(OSError):  # a read-only root still gets its report elsewhere (--out)
        hermetic_environment(store.root, prefect=False)
    from pipeline.report import FrameReadout, build_report, sampling_rate_hz
    from pipeline.report.cost import sweep_runs
    from pipeline.report.figures import draw_report
    from storage.report import check_report_folder
    from storage.runlog import read_sweep_records

    rate_hz = adc_rate_hz or sampling_rate_hz(cubes)
    frame = FrameReadout(adc_bits, rate_hz) if rate_hz else None
    report = build_report(
        cubes, frame=frame, energy=energy, runs=sweep_runs(read_sweep_records(store.root))
    )
    if rate_hz is None:
        print(
            "eskin: warning: the cubes do not state the recordings' sampling rate; the report "
            "compares with no frame readout (give --adc-rate-hz)",
            file=sys.stderr,
        )
    folder = out if out is not None else store.root / "report"
    check_report_folder(folder)  # before the figures: a refused folder costs nothing
    return write_report(folder, report, draw_report(report), show_progress=show_progress)


def write_report(
    out: str | Path,
    report: Report,
    figures: dict[str, Figure],
    *,
    show_progress: bool = False,
) -> Path:
    """Render ``report`` and its ``figures`` (by file stem) and write the folder ``out`` whole;
    return the path of its ``report.html``.

    Raises
    ------
    StoreError
        ``out`` is a file, or a non-empty folder that is not a report; or it cannot be written.
    """
    from importlib import metadata

    from tqdm import tqdm

    from pipeline.report.document import report_files
    from storage.report import check_report_folder, write_report_folder

    check_report_folder(out)
    with tqdm(
        total=len(figures), unit="figure", desc="report", disable=None if show_progress else True
    ) as bar:
        files = report_files(
            report, figures, version=metadata.version("eskin-sweep"), on_figure=bar.update
        )
    return write_report_folder(out, files) / "report.html"
