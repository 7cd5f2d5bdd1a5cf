"""Write a run root's report: the plain function behind ``eskin report`` and the flow's report task.

It wires three layers together: :mod:`pipeline.report` turns the cubes into curves, claims and
tables, :mod:`pipeline.figures` draws them, and :mod:`storage.report` writes the folder whole.
"""

from __future__ import annotations

import math
import sys
from contextlib import suppress
from pathlib import Path

from pipeline.errors import EskinError

DEFAULT_ADC_BITS = 12


def write_run_report(
    root: Path,
    out: Path | None = None,
    *,
    adc_bits: int = DEFAULT_ADC_BITS,
    adc_rate_hz: float | None = None,
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
        The frame-based ADC readout that Table I compares with: bits per sample and frame rate
        per taxel in Hz (default: the recordings' sampling rate).

    Raises
    ------
    EskinError
        Bad ADC figures, a root that is not a sweep store, or a store with no cubes.
    """
    from flows.environment import hermetic_environment
    from storage import SweepStore, open_results

    problems = []
    if adc_bits < 1:
        problems.append(f"--adc-bits {adc_bits}: need at least 1")
    if adc_rate_hz is not None and not (math.isfinite(adc_rate_hz) and adc_rate_hz > 0):
        problems.append(f"--adc-rate-hz {adc_rate_hz:g}: need a number > 0")
    if problems:
        raise EskinError("; ".join(problems))
    store = SweepStore.open(root)
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
    rate_hz = adc_rate_hz or (facts.fs_hz if facts else None)
    frame = FrameReadout(adc_bits, rate_hz) if rate_hz else None
    report = build_report(cubes, facts=facts, frame=frame, runs=read_sweep_runs(store.root))
    folder = out if out is not None else store.root / "report"
    return Path(write_report(folder, report, draw_report(report), show_progress=show_progress))
