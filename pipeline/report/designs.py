"""The run's designs: its distinct points across all cubes, their accuracy and what they cost.

A *design* is one distinct point of the run (one ``result_key``; the operating point that several
sweeps share is one design). Its settings are the swept fields of every sweep it lies in, at
their values there; its accuracy per model is the cube's ``accuracy_mean`` with the 95 % interval
``accuracy_low``/``accuracy_high`` (NaN for points that predate per-recording results) and, as a
secondary number, the population standard deviation of the fold accuracies.

Costs of a design for model ``m`` (:class:`Cost`; lower is cheaper):

* address-event data rate ``data_rate_bps`` (bit/s) and event rate ``event_rate_hz`` (Hz), from
  the cube;
* equivalent bits ``log2(V_fs / theta)``;
* compute seconds: the work seconds (the cube's ``work_seconds``) of its spike and coding stages
  plus ``train_m``, as measured when each stage ran (a stage reused from the cache or shared with
  other points counts at its original cost); the shared stages (loading the recordings, fitting
  the front end, loading or compiling kernels: :func:`pipeline.run.stages.shared_steps`) are not
  the design's and are left out;
* readout power (W): static bias of the ``n = rows * cols`` taxels plus the dynamic power of
  its events and bits (:func:`pipeline.results.readout_power.event_power_w`, constants of an
  :class:`~pipeline.results.readout_constants.EnergyModel`), the two parts kept apart
  (:func:`readout_power`);
* energy per decision (J): that power times the seconds of touch the point observed,
  ``n_windows_used * window_s`` (the windows it really used, from the cube);
* array area (m^2): the comparators' matched gate area that the design's threshold mismatch
  demands by Pelgrom's law, ``n`` times :func:`pipeline.results.matched_area.taxel_area_m2` of its
  ``sigma_rel`` and ``threshold_v`` (NaN for a design that names no mismatch).

The frame-based readout of the same array (:class:`FrameReadout`) sends ``n * bits * rate_hz``
bit/s and draws :func:`pipeline.results.readout_power.frame_power_w`.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import xarray as xr

from pipeline.report.chip_population import ChipYield, chip_yields
from pipeline.report.cubes import (
    axis_coordinates,
    describe_coordinate,
    field_values,
    point_keys,
    sweep_dims,
)
from pipeline.report.panels import (
    COLS,
    MISMATCH_SIGMA_REL,
    N_WINDOWS,
    ROWS,
    TAXELS,
    THRESHOLD_V,
    WINDOW_S,
)
from pipeline.report.text import label
from pipeline.results.cube import work_seconds
from pipeline.results.hardware_constants import Constants
from pipeline.results.matched_area import (
    A_VT_PROCESS,
    A_VT_V_M,
    MATCHED_DEVICES_PER_TAXEL,
    array_area_m2,
    taxel_area_m2,
)
from pipeline.results.readout_constants import EnergyModel
from pipeline.results.readout_power import (
    ReadoutPower,
    event_dynamic_power_w,
    event_static_power_w,
    frame_data_rate_bps,
    frame_dynamic_power_w,
    frame_static_power_w,
)
from pipeline.results.variables import (
    ACCURACY,
    ACCURACY_HIGH,
    ACCURACY_LOW,
    ACCURACY_MEAN,
    MODEL_DIM,
    RESULT_KEY,
    STAGE_DIM,
)
from pipeline.run.stages import shared_steps


@dataclass(frozen=True)
class Accuracy:
    """Accuracy of one model at one design (fractions); ``low``/``high`` NaN: no interval."""

    mean: float
    low: float
    high: float
    fold_std: float

    @property
    def has_interval(self) -> bool:
        """Whether both ends of the 95 % interval are known (finite)."""
        return math.isfinite(self.low) and math.isfinite(self.high)


@dataclass(frozen=True)
class Setting:
    """One swept field of a design: dotted scene ``field``, its value as text, its units."""

    field: str
    value: str
    units: str

    @property
    def text(self) -> str:
        """``field = value units``, e.g. ``"readout.threshold_v = 0.09 V"``."""
        return f"{self.field} = {self.value}" + (f" {self.units}" if self.units else "")


@dataclass(frozen=True)
class Design:
    """One distinct point of the run (see the module docstring).

    ``rows``/``cols`` are None when the cube does not hold them, ``taxels`` (the real taxels
    read of a recorded array: ``array.taxels``, else all the cube's ``taxel_names``) for one
    channel; rates and bits are NaN when the point did not measure them; ``observation_s`` (s
    of touch per decision, ``n_windows_used * window_s``) is NaN when the cube does not state
    the windows used; ``seconds`` and ``accuracy`` hold the models the point trained.
    """

    key: str
    sweeps: tuple[str, ...]
    settings: tuple[Setting, ...]
    rows: int | None
    cols: int | None
    event_rate_hz: float
    data_rate_bps: float
    equivalent_bits: float
    window_s: float
    n_windows: str
    observation_s: float
    seconds: Mapping[str, float]
    accuracy: Mapping[str, Accuracy]
    threshold_v: float = math.nan
    mismatch_sigma_rel: float = math.nan
    yields: Mapping[str, ChipYield] = field(default_factory=dict)
    a_vt_v_m: float = A_VT_V_M
    taxels: int | None = None

    @property
    def taxel_area_m2(self) -> float:
        """Matched comparator gate area of one taxel (m^2, Pelgrom's law:
        :func:`~pipeline.results.matched_area.taxel_area_m2`); NaN without a mismatch to size
        for."""
        if not (self.mismatch_sigma_rel >= 0 and self.threshold_v >= 0):
            return math.nan
        return float(taxel_area_m2(self.mismatch_sigma_rel, self.threshold_v, self.a_vt_v_m))

    @property
    def array_area_m2(self) -> float:
        """:attr:`taxel_area_m2` times the taxels (m^2); NaN when either is unknown."""
        if self.n_taxels is None or not math.isfinite(self.taxel_area_m2):
            return math.nan
        return float(
            array_area_m2(self.n_taxels, self.mismatch_sigma_rel, self.threshold_v, self.a_vt_v_m)
        )

    @property
    def label(self) -> str:
        """The design's swept settings, e.g. ``readout.threshold_v = 0.09 V``."""
        return ", ".join(s.text for s in self.settings) or "the base design"

    @property
    def n_taxels(self) -> int | None:
        """The number of taxels of the array, the real taxels read (``taxels``) where the
        design sets them, else ``rows * cols`` (None when either is unknown)."""
        if self.taxels is not None:
            return self.taxels
        return None if self.rows is None or self.cols is None else self.rows * self.cols


class Cost(enum.Enum):
    """A cost of a design; the value is ``(figure stem, axis label, short name)``."""

    DATA_RATE = ("front_data_rate", "address-event data rate (bit/s)", "data rate")
    EVENT_RATE = ("front_event_rate", "event rate of the array (events/s)", "event rate")
    BITS = ("front_equivalent_bits", "equivalent bits log2(V_fs / theta) (bit)", "equivalent bits")
    COMPUTE = (
        "cost_pareto",
        "compute time per point: work of its own stages, shared stages left out (s)",
        "compute time",
    )
    POWER = ("front_power", "estimated readout power (W)", "readout power")
    AREA = (
        "front_area",
        "matched comparator gate area of the array, Pelgrom's law (um^2)",
        "array area",
    )

    @property
    def stem(self) -> str:
        """File stem of the figure of accuracy against this cost (``"front_data_rate"``)."""
        return self.value[0]

    @property
    def axis(self) -> str:
        """Label of that figure's cost axis, with the unit."""
        return self.value[1]

    @property
    def short(self) -> str:
        """Short name of the cost in sentences (``"data rate"``)."""
        return self.value[2]


@dataclass(frozen=True)
class FrameReadout:
    """A frame-based readout of the same array: one ``bits``-bit ADC sample per taxel per frame,
    ``rate_hz`` frames per second."""

    bits: int
    rate_hz: float

    def data_rate_bps(self, n_taxels: int) -> float:
        """Bits per second of this readout for an array of ``n_taxels`` taxels,
        ``n_taxels * rate_hz * bits``
        (:func:`~pipeline.results.readout_power.frame_data_rate_bps`)."""
        return float(frame_data_rate_bps(n_taxels, self.rate_hz, self.bits))

    def power(self, n_taxels: int, energy: EnergyModel) -> ReadoutPower:
        """Static and dynamic power of this readout for an array of ``n_taxels`` taxels under the
        constants ``energy`` (:func:`~pipeline.results.readout_power.frame_static_power_w`,
        :func:`~pipeline.results.readout_power.frame_dynamic_power_w`), in W."""
        return ReadoutPower(
            float(frame_static_power_w(n_taxels, energy)),
            float(frame_dynamic_power_w(n_taxels, self.rate_hz, self.bits, energy)),
        )


def area_sentence(constants: Constants | None = None) -> str:
    """What the array-area cost is and what it rests on, in one paragraph, with the A_VT of
    ``constants`` (default: the declared one) and its source."""
    constants = constants if constants is not None else Constants()
    process = "" if "a_vt_v_m" in constants.overrides else f" for {A_VT_PROCESS}"
    return (
        "Array area is the comparators' matched gate area that a design's threshold mismatch "
        "demands by Pelgrom's law: offset sigma = sigma_rel x threshold = A_VT / sqrt(W L) per "
        f"input transistor, {MATCHED_DEVICES_PER_TAXEL} of them per taxel (two comparators, a "
        f"differential pair each), with A_VT = {constants.a_vt_v_m * 1e9:g} mV um{process} "
        f"({constants.source('a_vt_v_m')}). It is a lower bound (wiring, the front end and the "
        "other devices are not counted); designs that name no mismatch assume perfect matching "
        "and have no area."
    )


def readout_power(design: Design, energy: EnergyModel) -> ReadoutPower | None:
    """The design's event readout power, static and dynamic; None when its array size or its
    rates are unknown."""
    rates = (design.event_rate_hz, design.data_rate_bps)
    if design.n_taxels is None or not all(math.isfinite(r) and r >= 0 for r in rates):
        return None
    return ReadoutPower(
        float(event_static_power_w(design.n_taxels, energy)),
        float(event_dynamic_power_w(*rates, energy)),
    )


def cost(design: Design, model: str, which: Cost, energy: EnergyModel) -> float:
    """The design's ``which`` cost for ``model`` (NaN when unknown)."""
    match which:
        case Cost.DATA_RATE:
            return design.data_rate_bps
        case Cost.EVENT_RATE:
            return design.event_rate_hz
        case Cost.BITS:
            return design.equivalent_bits
        case Cost.COMPUTE:
            return design.seconds.get(model, math.nan)
        case Cost.POWER:
            power = readout_power(design, energy)
            return math.nan if power is None else power.total_w
        case Cost.AREA:
            return design.array_area_m2
    raise ValueError(f"unknown cost {which}")


def gather_designs(
    cubes: Mapping[str, xr.Dataset], a_vt_v_m: float = A_VT_V_M
) -> tuple[Design, ...]:
    """Every distinct point of every cube, in the order first met; models all-NaN left out;
    their areas sized with Pelgrom's coefficient ``a_vt_v_m`` (V m)."""
    found: dict[str, dict[str, Any]] = {}
    for name, cube in cubes.items():
        dims = sweep_dims(cube)
        settings = _settings(cube)
        work = work_seconds(cube)
        stages = [str(s) for s in cube[STAGE_DIM].values] if work is not None else []
        models = [str(m) for m in cube[MODEL_DIM].values]
        mean = _flat(cube[ACCURACY_MEAN], dims)
        low, high = _flat(cube[ACCURACY_LOW], dims), _flat(cube[ACCURACY_HIGH], dims)
        folds = cube[ACCURACY].transpose(*dims, MODEL_DIM, ...).values
        folds = folds.reshape(mean.shape[0], len(models), -1)
        seconds = _flat(work, dims) if work is not None else None
        scalars = {
            v: _flat(cube[v], dims) if v in cube else np.full(mean.shape[0], np.nan)
            for v in ("event_rate_hz", "data_rate_bps", "equivalent_bits")
        }
        read = (ROWS, COLS, TAXELS, WINDOW_S, N_WINDOWS, THRESHOLD_V, MISMATCH_SIGMA_REL)
        fields = {f: field_values(cube, f) for f in read}
        fields = {f: None if v is None else v.ravel() for f, v in fields.items()}
        yields = chip_yields(cube)
        used = (
            _flat(cube["n_windows_used"], dims)
            if "n_windows_used" in cube
            else np.full(mean.shape[0], -1.0)
        )
        for p, key in enumerate(point_keys(cube)):
            entry = found.get(key)
            if entry is not None:
                entry["sweeps"].append(name)
                entry["settings"] += [s for s in settings[p] if s not in entry["settings"]]
                continue
            accuracy = {}
            for m, model in enumerate(models):
                if not math.isfinite(mean[p, m]):
                    continue
                with np.errstate(invalid="ignore"):
                    spread = folds[p, m][np.isfinite(folds[p, m])]
                accuracy[model] = Accuracy(
                    float(mean[p, m]),
                    float(low[p, m]),
                    float(high[p, m]),
                    float(np.std(spread)) if spread.size else math.nan,
                )
            found[key] = {
                "key": key,
                "a_vt_v_m": a_vt_v_m,
                "sweeps": [name],
                "settings": list(settings[p]),
                "rows": _int(fields[ROWS], p),
                "cols": _int(fields[COLS], p),
                "taxels": _int(fields[TAXELS], p) or _recorded_taxels(cube),
                **{v: float(values[p]) for v, values in scalars.items()},
                "window_s": math.nan if fields[WINDOW_S] is None else float(fields[WINDOW_S][p]),
                "n_windows": "?" if fields[N_WINDOWS] is None else label(fields[N_WINDOWS][p]),
                "observation_s": float(used[p]) * float(fields[WINDOW_S][p])
                if used[p] > 0 and fields[WINDOW_S] is not None
                else math.nan,
                "seconds": {}
                if seconds is None
                else {m: _model_seconds(seconds[p], stages, m) for m in accuracy},
                "accuracy": accuracy,
                "yields": {m: y for (q, m), y in yields.items() if q == p and m in accuracy},
                **{
                    name: _float(fields[f], p)
                    for name, f in (
                        ("threshold_v", THRESHOLD_V),
                        ("mismatch_sigma_rel", MISMATCH_SIGMA_REL),
                    )
                },
            }
    return tuple(
        Design(**(e | {"sweeps": tuple(e["sweeps"]), "settings": tuple(e["settings"])}))
        for e in found.values()
    )


def _settings(cube: xr.Dataset) -> list[tuple[Setting, ...]]:
    """The swept fields of every point of a cube, in point order."""
    dims = sweep_dims(cube)
    columns = []
    for dim in dims:
        for name in axis_coordinates(cube, dim):
            _, units = describe_coordinate(cube, name)
            values = cube[name].broadcast_like(cube[RESULT_KEY]).transpose(*dims).values.ravel()
            columns.append((str(cube[name].attrs["field"]), units, values))
    size = cube[RESULT_KEY].size
    return [
        tuple(Setting(f, label(values[i]), units) for f, units, values in columns)
        for i in range(size)
    ]


def _flat(variable: xr.DataArray, dims: tuple[str, ...]) -> np.ndarray:
    """Values with the sweep dimensions (C order) flattened into the first axis."""
    values = variable.transpose(*dims, ...).values
    size = int(np.prod([variable.sizes[d] for d in dims])) if dims else 1
    return values.reshape(size, *values.shape[len(dims) :]).astype(np.float64)


def _recorded_taxels(cube: xr.Dataset) -> int | None:
    """The taxels of the real array a cube's recordings hold (all are read where a design does
    not set ``array.taxels``); None for one channel."""
    names = cube.attrs.get("taxel_names")
    return len(names) if names else None


def _int(values: np.ndarray | None, p: int) -> int | None:
    if values is None:
        return None
    try:
        return int(values[p])
    except (TypeError, ValueError):
        return None


def _float(values: np.ndarray | None, p: int) -> float:
    if values is None:
        return math.nan
    try:
        return float(values[p])
    except (TypeError, ValueError):
        return math.nan


def _model_seconds(row: np.ndarray, stages: list[str], model: str) -> float:
    shared = shared_steps()
    keep = [
        s not in shared and (not s.startswith("train_") or s == f"train_{model}") for s in stages
    ]
    return float(np.nansum(row[keep]))
