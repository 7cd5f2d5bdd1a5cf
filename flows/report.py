"""Write a run root's report: the plain function behind ``eskin report`` and the flow's report task.

It wires three layers together: :mod:`pipeline.report` turns the cubes into the design answer,
claims, tables and fronts (:mod:`pipeline.report.analysis`), draws them
(:mod:`pipeline.report.figures`) and renders the files of the report
(:mod:`pipeline.report.document`), and :mod:`storage.report` writes the folder whole. The command
line's frame-readout options become a :class:`~pipeline.report.designs.FrameReadout` here, checked
before anything is read or written; its hardware constants (``--constants FILE`` and the energy
options) arrive as :class:`~pipeline.results.hardware_constants.Constants`.
"""

from __future__ import annotations

import sys
from contextlib import suppress
from pathlib import Path
from typing import TYPE_CHECKING

from pipeline.errors import EskinError

if TYPE_CHECKING:
    from collections.abc import Mapping

    import xarray as xr
    from matplotlib.figure import Figure

    from pipeline.report import FrameReadout, Report
    from pipeline.report.answer import ModelAnswer
    from pipeline.results.hardware_constants import Constants
    from pipeline.results.readout_constants import EnergyModel

DEFAULT_ADC_BITS = 12


def write_run_report(
    root: str | Path,
    out: Path | None = None,
    *,
    adc_bits: int = DEFAULT_ADC_BITS,
    adc_rate_hz: float | None = None,
    energy: EnergyModel | None = None,
    constants: Constants | None = None,
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
    energy
        The readout power estimate's constants (default: those of ``constants``).
    constants
        The hardware constants, a designer's overrides among them
        (:func:`pipeline.results.hardware_constants.load_constants` of ``eskin report
        --constants FILE``); default: every constant as declared. The report lists them.

    Raises
    ------
    EskinError
        Bad ADC figures (before anything is read or written), a root that is not a
        sweep store, or a store with no cubes.
    """
    from flows.environment import hermetic_environment
    from storage import SweepStore, open_results

    problems = _adc_problems(adc_bits, adc_rate_hz)
    if out is None and (problem := needs_report_folder(root)):
        problems.append(problem)
    if problems:
        raise EskinError("; ".join(problems))
    store = SweepStore.open(root)
    cubes = open_results(store.root)
    if not cubes:
        raise EskinError(f"no result cubes in {store.root}: run 'eskin sweep' on it first")
    with suppress(OSError):  # a read-only root still gets its report elsewhere (--out)
        hermetic_environment(store.root, prefect=False)
    from pipeline.report import build_report
    from pipeline.report.cost import sweep_runs
    from pipeline.report.figures import draw_report
    from storage.report import check_report_folder
    from storage.runlog import read_sweep_records

    frame = _frame_readout(cubes, adc_bits, adc_rate_hz)
    report = build_report(
        cubes,
        frame=frame,
        energy=energy,
        runs=sweep_runs(read_sweep_records(store.root)),
        constants=constants,
    )
    if frame is None:
        print(
            "eskin: warning: the cubes do not state the recordings' sampling rate; the report "
            "compares with no frame readout (give --adc-rate-hz)",
            file=sys.stderr,
        )
    folder = out if out is not None else store.root / "report"
    check_report_folder(folder)  # before the figures: a refused folder costs nothing
    return write_report(folder, report, draw_report(report), show_progress=show_progress)


def report_answers(
    cubes: Mapping[str, xr.Dataset],
    *,
    adc_bits: int = DEFAULT_ADC_BITS,
    adc_rate_hz: float | None = None,
    energy: EnergyModel | None = None,
    constants: Constants | None = None,
) -> tuple[ModelAnswer, ...]:
    """The report's answer, one per model, from a run's cubes: the most accurate design and the
    cheapest designs (by data rate, by readout power) whose accuracy is not significantly below
    it, as the report's first section gives them.

    Parameters
    ----------
    cubes
        ``{sweep name: cube}`` as :func:`storage.store.open_results` returns them.
    adc_bits, adc_rate_hz, energy, constants
        As for :func:`write_run_report`: the frame readout the answer compares with, the
        power estimate's constants and the hardware constants.

    Returns
    -------
    tuple of pipeline.report.answer.ModelAnswer
        In the order of the cubes' models.

    Raises
    ------
    EskinError
        Bad ADC figures, or cubes too old to hold ``accuracy_mean``.
    """
    from pipeline.report import build_report

    if problems := _adc_problems(adc_bits, adc_rate_hz):
        raise EskinError("; ".join(problems))
    frame = _frame_readout(cubes, adc_bits, adc_rate_hz)
    return tuple(build_report(cubes, frame=frame, energy=energy, constants=constants).answers)


def _adc_problems(adc_bits: int, adc_rate_hz: float | None) -> list[str]:
    """What is wrong with the frame readout's figures, named as the command line's options."""
    from pipeline.numbers import positive_number
    from pipeline.results.readout_power import MAX_BITS

    problems = []
    if not 1 <= adc_bits <= MAX_BITS:
        problems.append(f"--adc-bits {adc_bits}: need 1 to {MAX_BITS}")
    if adc_rate_hz is not None and positive_number(adc_rate_hz) is None:
        problems.append(f"--adc-rate-hz {adc_rate_hz:g}: need a number > 0")
    return problems


def _frame_readout(
    cubes: Mapping[str, xr.Dataset], adc_bits: int, adc_rate_hz: float | None
) -> FrameReadout | None:
    """The frame readout to compare with: ``adc_bits`` at ``adc_rate_hz`` per taxel, by default
    the recordings' sampling rate as the cubes state it; None where neither says a rate."""
    from pipeline.report import FrameReadout, sampling_rate_hz

    rate_hz = adc_rate_hz or sampling_rate_hz(cubes)
    return FrameReadout(adc_bits, rate_hz) if rate_hz else None


def needs_report_folder(root: str | Path) -> str | None:
    """Why the report of ``root`` needs a folder given (``--out``), or None: an object root
    holds no report, which is a local folder."""
    from storage.objects import is_object_url

    if not is_object_url(root):
        return None
    return (
        f"run root {root} is on object storage: write its report to a local folder with "
        f"eskin report --root {root} --out DIR"
    )


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
