"""Table I: this run's operating point beside a frame-based ADC readout and the paper's row.

The event readout's rate is the cube's ``data_rate_bps`` (address-event bits per second) at the
best threshold; a frame-based ADC readout of the same array sends ``taxels * bits * rate_hz``
bits per second. Equivalent bits ``b = log2(V_fs / theta)`` are the cube's
``readout.equivalent_bits``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.report.cubes import base_value, panel_x
from pipeline.report.curves import sweep_curves
from pipeline.report.panels import Panel
from pipeline.report.text import rate

NOT_STATED = "not stated here"

_CLASSIFIERS = {"ffnn": "FFNN ({h} hidden ReLU)", "cnn": "CNN (2 conv, 16/32 channels)"}


@dataclass(frozen=True)
class FrameReadout:
    """A frame-based readout of the same array: one ``bits``-bit ADC sample per taxel per frame."""

    bits: int
    rate_hz: float

    def data_rate_bps(self, n_taxels: int) -> float:
        return float(n_taxels * self.bits * self.rate_hz)


@dataclass(frozen=True)
class RunRow:
    """Table I for this run: the threshold sweep's best point (numbers, not text).

    The best threshold is the one where the most accurate model peaks; ``accuracy`` holds
    ``(model, mean, std)`` of every model at that threshold. ``frame_data_rate_bps`` is None when
    no frame readout is given; ``n_classes`` None when the cube does not state it (its points'
    results did not all say the same).
    """

    sweep: str
    threshold_v: float
    full_scale_v: float
    equivalent_bits: float
    rows: int
    cols: int
    event_rate_hz: float
    data_rate_bps: float
    frame: FrameReadout | None
    frame_data_rate_bps: float | None
    window_s: float
    n_windows: int | str
    polarity: str
    hidden_units: int
    accuracy: tuple[tuple[str, float, float], ...]
    dataset: str
    n_classes: int | None

    @property
    def n_taxels(self) -> int:
        return self.rows * self.cols


@dataclass(frozen=True)
class TableRow:
    """One row of Table I as text, in the order of :data:`TABLE_COLUMNS`."""

    source: str
    resolution: str
    taxels: str
    event_rate: str
    data_rate: str
    frame_data_rate: str
    preprocessing: str
    classifier: str
    classes: str
    accuracy: str


TABLE_COLUMNS = (
    "source",
    "readout resolution",
    "taxels",
    "event rate",
    "data rate (event readout)",
    "data rate (frame ADC readout)",
    "pre-processing",
    "classifier",
    "classes",
    "accuracy (chance)",
)

# Only what this project's issue and design state of the paper; every other cell says so.
PAPER_ROW = TableRow(
    source="paper (the paper's figures)",
    resolution="3.47 bit (threshold 0.09 V of 1 V)",
    taxels="9 (3 x 3)",
    event_rate=NOT_STATED,
    data_rate=NOT_STATED,
    frame_data_rate=NOT_STATED,
    preprocessing="rate coding, 40 windows x 0.1 s",
    classifier="FFNN (100 hidden ReLU), CNN (2 conv)",
    classes="12 (VibTac-12)",
    accuracy=NOT_STATED,
)


def run_row(name: str, cube: xr.Dataset, frame: FrameReadout | None) -> RunRow:
    """Table I for a threshold cube: its best threshold, where the most accurate model peaks.

    Every number is the cube's at that point; the class count is its ``n_classes`` attribute.
    """
    curves = sweep_curves(name, cube, panel_x(Panel.THRESHOLD, cube))
    leader = max(curves, key=lambda c: c.mean[c.best])
    threshold = float(leader.x[leader.best])
    x = panel_x(Panel.THRESHOLD, cube)
    point = cube.isel({cube["accuracy"].dims[0]: int(np.flatnonzero(x == threshold)[0])})
    rows, cols = int(base_value(point, "array.rows")), int(base_value(point, "array.cols"))
    n_classes = cube.attrs.get("n_classes")
    return RunRow(
        sweep=name,
        threshold_v=threshold,
        full_scale_v=float(base_value(point, "readout.full_scale_v")),
        equivalent_bits=float(base_value(point, "readout.equivalent_bits")),
        rows=rows,
        cols=cols,
        event_rate_hz=float(point["event_rate_hz"]),
        data_rate_bps=float(point["data_rate_bps"]),
        frame=frame,
        frame_data_rate_bps=None if frame is None else frame.data_rate_bps(rows * cols),
        window_s=float(base_value(point, "coding.window_s")),
        n_windows=base_value(point, "coding.n_windows"),
        polarity=str(base_value(point, "coding.polarity")),
        hidden_units=int(base_value(point, "training.hidden_units")),
        accuracy=tuple(
            (c.model, float(c.mean[c.index(threshold)]), float(c.std[c.index(threshold)]))
            for c in curves
        ),
        dataset=str(base_value(point, "dataset.kind")),
        n_classes=None if n_classes is None else int(n_classes),
    )


def table_row(row: RunRow) -> TableRow:
    """This run's row of Table I as text."""
    chance = f" (chance {1 / row.n_classes:.1%})" if row.n_classes else ""
    frame = NOT_STATED
    if row.frame is not None and row.frame_data_rate_bps is not None:
        frame = (
            f"{rate(row.frame_data_rate_bps)}it/s ({row.n_taxels} taxels x {row.frame.bits} bit "
            f"x {row.frame.rate_hz:g} Hz)"
        )
        frame += f", {row.frame_data_rate_bps / row.data_rate_bps:.0f}x the event readout"
    return TableRow(
        source=f"this run ({row.dataset} data)",
        resolution=f"{row.equivalent_bits:.2f} bit (best threshold {row.threshold_v:g} V of "
        f"{row.full_scale_v:g} V)",
        taxels=f"{row.n_taxels} ({row.rows} x {row.cols})",
        event_rate=f"{rate(row.event_rate_hz)}events/s",
        data_rate=f"{rate(row.data_rate_bps)}it/s (address-event)",
        frame_data_rate=frame,
        preprocessing=f"rate coding, {row.n_windows} windows x {row.window_s:g} s, "
        f"polarity {row.polarity}",
        classifier=", ".join(
            _CLASSIFIERS[m].format(h=row.hidden_units) for m, _, _ in row.accuracy
        ),
        classes=str(row.n_classes) if row.n_classes else "unknown (not stated in the cube)",
        accuracy="; ".join(
            f"{m.upper()} {100 * a:.1f} % +- {100 * s:.1f} %" for m, a, s in row.accuracy
        )
        + chance,
    )
