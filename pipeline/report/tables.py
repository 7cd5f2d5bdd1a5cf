"""Table I: the paper's rows (:mod:`pipeline.report.paper`) beside this run's answer designs.

This run's rows are, per model, the cheapest design by data rate that is not significantly below
the model's best (:mod:`pipeline.report.answer`) and, if it is another design, the best one, in
the paper's columns. The data-rate cell shows both of this run's figures that the paper's
51.32 Hz could mean: the array's event rate (events/s) and its address-event data rate
``data_rate_bps`` (bit/s); the paper does not say which it counts. Chance is ``1 / n_classes``.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence

from pipeline.report import paper
from pipeline.report.answer import Candidate, ModelAnswer
from pipeline.report.designs import Design
from pipeline.report.paper import TableRow
from pipeline.report.text import fold_spread, pct_interval, rate

TABLE_COLUMNS = paper.TABLE_COLUMNS


def run_rows(
    answers: Sequence[ModelAnswer], dataset: str, n_classes: int | None
) -> tuple[TableRow, ...]:
    """This run's rows of Table I: per model, its answer design(s)."""
    return tuple(row for answer in answers for row in _model_rows(answer, dataset, n_classes))


def table_rows(run: Sequence[TableRow]) -> tuple[tuple[str, ...], ...]:
    """Every row of Table I as cells: this run's, then the paper's."""
    return tuple(tuple(vars(row).values()) for row in (*run, *paper.TABLE_ROWS))


def table_notes(run: Sequence[TableRow]) -> tuple[str, ...]:
    """What the table's rows are and which of this run's figures meets the paper's 51.32 Hz."""
    ours = (
        "This run's rows are, per model, the cheapest design by data rate whose accuracy is not "
        "significantly below the model's best design (see the answer above) and, where it is "
        "another design, the best one; accuracy with its 95 % interval, chance 1 / classes in "
        "parentheses and, as a secondary number, the standard deviation over folds."
        if run
        else "This run has no row: no design has an accuracy."
    )
    return (
        ours,
        "The other rows are the paper's Table I (the paper's numbers, as quoted in this "
        "project's summary of the paper; references in brackets are the paper's own).",
        f"The paper's {paper.DATA_RATE_HZ:g} Hz: the paper does not say whether it counts events "
        "per second of the array or bits per second. This run's rows therefore show both of its "
        "own figures: the event rate of the whole array (events/s), which is the one to set "
        f"beside {paper.DATA_RATE_HZ:g} Hz if the paper counts events, and the address-event "
        "data rate (bit/s: taxel address plus polarity per event), which is the one to set "
        "beside it if the paper counts bits, and the one to set beside the other rows' frame and "
        "link bit rates.",
    )


def _model_rows(answer: ModelAnswer, dataset: str, n_classes: int | None) -> Iterator[TableRow]:
    chosen = answer.by_data_rate
    if chosen is not None:
        role = "the best" if chosen is answer.best else "cheapest by data rate as accurate as best"
        yield _row(chosen, answer.model, role, dataset, n_classes)
    if chosen is not answer.best:
        yield _row(answer.best, answer.model, "best", dataset, n_classes)


def sensors_text(d: Design) -> str:
    """Table I's sensor cell: the real taxels read of a recorded array, or the grid of
    time-shifted copies of one recorded channel."""
    if d.taxels is not None:
        return (
            f"{d.taxels} real taxel{'' if d.taxels == 1 else 's'} (columns of the recorded array)"
        )
    if d.n_taxels is None:
        return "unknown"
    return f"{d.n_taxels} ({d.rows} x {d.cols} taxel{'' if d.n_taxels == 1 else 's'})"


def _row(chosen: Candidate, model: str, role: str, dataset: str, n_classes: int | None) -> TableRow:
    d = chosen.design
    bits = d.equivalent_bits
    chance = f" ({100 / n_classes:.2f} %)" if n_classes else " (chance unknown)"
    taxels = sensors_text(d)
    window = f"{d.window_s:g} s" if math.isfinite(d.window_s) else "? s"
    a = chosen.accuracy
    return TableRow(
        reference=f"this run ({dataset} data), {model.upper()}, {role}: {d.label}",
        readout="level-crossing spikes ("
        + (f"{bits:.2f} b equivalent" if math.isfinite(bits) else "resolution unknown")
        + ", variable)",
        hardware="simulated continuous-time level-crossing readout (eskin-sweep model)",
        sensors=taxels,
        data_rate=f"{rate(d.event_rate_hz, 'events/s')} (event rate); "
        f"{rate(d.data_rate_bps, 'bit/s')} (address-event data rate)",
        preprocessing=f"rate code, {d.n_windows} windows x {window}",
        classifier=model.upper(),
        classes=str(n_classes) if n_classes else "unknown (not stated in the cubes)",
        accuracy=pct_interval(a.mean, a.low, a.high)
        + chance
        + (f"; fold std {fold_spread(a.fold_std)}" if math.isfinite(a.fold_std) else ""),
    )
