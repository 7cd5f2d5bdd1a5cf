"""Stored records: how a stored level (:mod:`pipeline.run.stages`) declares what it keeps of one
scene, and the codecs its entries share.

A level whose output the sweep store keeps declares a :class:`Record`: its variables (name,
entry-level dims, dtype, units, long name; a variable may be optional), its entry type and three
functions: ``make`` turns the level's output (and what the levels before it made) into its
entry, ``encode`` turns an entry into named arrays plus JSON attributes, ``decode`` turns them back.
The store (:mod:`storage`) writes and reads any declared record by its declaration alone: it casts
each array to the declared dtype, checks its dims, refuses undeclared or missing variables and
JSON attributes that are not finite, and knows no record by name.

The entries of the two stored levels are in :mod:`pipeline.run.entries`; a feature's variables
beside its own entry module (:mod:`pipeline.run.chips`, :mod:`pipeline.run.decisions`). This
module holds what they share: ragged trains as four variables (:func:`train_variables`,
:func:`train_values`, :func:`read_trains`: train ``(r, t)`` of prefix ``p`` is
``p_times_s[p_start[r, t] : p_start[r, t] + p_count[r, t]]``), spike metrics as one float64
array (:data:`METRICS_VARIABLE`: one value per :class:`~pipeline.chain.metrics.SpikeMetrics`
field in its order; they may be +-inf or NaN, which JSON attributes cannot hold) and step
seconds as JSON attributes.

Every entry's attributes hold ``seconds`` (step name -> wall seconds of the step's work for the
entry's point, as measured when each step ran, one-off work (imports, kernel loads) left out;
finite floats)
and, in entries written since they were kept apart, ``paid_seconds`` (charge, ``own`` or
``shared``, -> step name -> wall seconds): what the worker spent computing the entry, each second
charged to one point only (:class:`Charge`); a spike entry also holds ``paid_for``, the result key
of the point its paid seconds are charged to.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import TIME_RESOLUTION_S, SpikeTrains, train_starts

__all__ = [
    "METRICS_VARIABLE",
    "Charge",
    "Record",
    "StepSeconds",
    "Ticks",
    "Variable",
    "metric_values",
    "paid_attr",
    "read_metrics",
    "read_paid",
    "read_seconds",
    "read_trains",
    "seconds_attr",
    "train_values",
    "train_variables",
]

#: Arrays and JSON attributes of one entry, as :attr:`Record.encode` gives and
#: :attr:`Record.decode` takes them.
Values = dict[str, np.ndarray]
Attrs = dict[str, Any]


class Charge(enum.StrEnum):
    """Whom the seconds a worker paid were for (the ``charge`` dimension of a cube's ``seconds``).

    ``own``: work for the point itself (its spike train, frames, training). ``shared``: work
    that later points of the same worker reuse without paying it again: loading the recordings,
    fitting the front end (the steps :attr:`pipeline.run.stages.Level.shared` declares) and a
    worker's one-off work, importing numba, torch and scikit-learn and loading or compiling the
    numba kernels (step :data:`pipeline.run.stopwatch.SETUP_STEP`, wherever it happens). Either is
    charged to the point whose computation paid it, and to no other: a point that found the
    work done pays nothing for it.
    """

    OWN = "own"
    SHARED = "shared"


# Paid wall seconds by charge, then step name.
Paid = dict[Charge, dict[str, float]]


@dataclass(frozen=True)
class StepSeconds:
    """The seconds a new entry accounts for, as :attr:`Record.make` gets them.

    Attributes
    ----------
    work : dict[str, float]
        Wall seconds of each step's work for the point, as measured when the step ran (one-off
        work, imports and kernel loads, left out): of its own level's steps and of the levels
        upstream that the entry accounts for.
    paid : dict[Charge, dict[str, float]]
        Wall seconds the worker spent computing the entry for the point, by charge and step:
        what the point's own computation ran (nothing for an output it found made).
    point : str
        The result key of the point the paid seconds are charged to.
    """

    work: dict[str, float]
    paid: Paid
    point: str


@dataclass(frozen=True)
class Ticks:
    """How the store keeps a variable of event times: as whole ticks of ``resolution_s``
    (the values must be such multiples), delta-coded within each train (the trains' lengths are
    the variable ``runs``, in order), with the +-1 variable ``sign`` folded into each delta's
    low bit (``2 * delta + (sign > 0)``) instead of stored apart."""

    resolution_s: float
    runs: str
    sign: str


@dataclass(frozen=True)
class Variable:
    """One stored variable of a record.

    Attributes
    ----------
    name : str
        Its name in the entry (and in the store).
    dims : tuple of str
        Entry-level dimension names (``()`` for a scalar).
    dtype : str
        A numpy dtype name (``"float64"``, ``"int8"``) or ``"str"`` for strings.
    units, long_name : str
        CF ``units`` ("1" for dimensionless numbers and labels) and a prose description.
    optional : bool
        Whether an entry may lack it.
    ticks : Ticks or None
        For event times: how the store keeps them (:class:`Ticks`); None: as ``dtype``.
    """

    name: str
    dims: tuple[str, ...]
    dtype: str
    units: str
    long_name: str
    optional: bool = False
    ticks: Ticks | None = None

    def attrs(self) -> dict[str, str]:
        """``units`` and ``long_name``."""
        return {"units": self.units, "long_name": self.long_name}


@dataclass(frozen=True, eq=False)
class Record:
    """What a stored level keeps of one scene: see the module docstring.

    Attributes
    ----------
    name : str
        The level's name: the kind of its entries in the store.
    entry_type : type
        The type of its entries; every entry has ``seconds`` (dict[str, float]).
    variables : tuple of Variable
        Every variable an entry may hold.
    make : callable
        ``make(output, seconds, made) -> entry``: the level's output as its entry, given the
        :class:`StepSeconds` the entry accounts for and ``made(level_name)``, the output (or
        entry) of an upstream level of the same scene.
    encode : callable
        ``encode(entry) -> (values, attrs)``: named arrays (the declared variables; optional
        ones may be left out) and JSON attributes; raises ValueError for inconsistent entries.
    decode : callable
        ``decode(values, attrs) -> entry``: the inverse, given arrays already checked against
        the declaration (strings as ``<U``); raises for inconsistent ones.
    """

    name: str
    entry_type: type
    variables: tuple[Variable, ...]
    make: Callable[[Any, StepSeconds, Callable[[str], Any]], Any]
    encode: Callable[[Any], tuple[Values, Attrs]]
    decode: Callable[[Mapping[str, np.ndarray], Mapping[str, Any]], Any]

    def variable(self, name: str) -> Variable:
        """The declared variable ``name``."""
        for variable in self.variables:
            if variable.name == name:
                return variable
        raise KeyError(f"record {self.name!r} declares no variable {name!r}")


# ---------------------------------------------------------------------------------------------
# Codecs the entries share

_METRICS = tuple(f.name for f in dataclasses.fields(SpikeMetrics))
#: The spike metrics of an entry, one float64 per :class:`~pipeline.chain.metrics.SpikeMetrics`
#: field in its order (+-inf and NaN kept, which JSON attributes cannot hold).
METRICS_VARIABLE = Variable(
    "metrics", ("metric",), "float64", "1", "spike metrics in SpikeMetrics field order"
)


def train_variables(
    prefix: str, optional: bool = False, grid: tuple[str, str] = ("recording", "taxel")
) -> tuple[Variable, ...]:
    """The four variables of one set of ragged trains (``true`` or ``real``), trains on
    ``grid``; the times stored as ticks of :data:`~pipeline.chain.spikes.TIME_RESOLUTION_S`."""
    event = (f"{prefix}_event",)
    what = prefix.upper()
    ticks = Ticks(TIME_RESOLUTION_S, f"{prefix}_count", f"{prefix}_polarity")
    return (
        Variable(
            f"{prefix}_times_s", event, "float64", "s", f"{what} spike times", optional, ticks
        ),
        Variable(f"{prefix}_polarity", event, "int8", "1", f"{what} spike polarity", optional),
        Variable(f"{prefix}_start", grid, "int64", "1", f"first {what} event", optional),
        Variable(f"{prefix}_count", grid, "int64", "1", f"{what} spikes per train", optional),
    )


def train_values(prefix: str, trains: SpikeTrains) -> Values:
    """Flat arrays of one set of ragged trains, checked for consistency."""
    times, polarity = np.asarray(trains.times_s), np.asarray(trains.polarity)
    count = np.asarray(trains.count)
    if count.ndim != 2:
        raise ValueError(f"{prefix} count: {count.ndim} dimensions, expected (recording, taxel)")
    if times.ndim != 1 or polarity.shape != times.shape:
        raise ValueError(f"{prefix} times_s and polarity must be 1-D of equal length")
    if (count < 0).any() or int(count.sum()) != times.size:
        raise ValueError(f"{prefix} count: must be >= 0 and sum to the {times.size} events")
    return {
        f"{prefix}_times_s": times,
        f"{prefix}_polarity": polarity,
        f"{prefix}_start": train_starts(count),
        f"{prefix}_count": count,
    }


def read_trains(values: Mapping[str, np.ndarray], prefix: str, duration: np.ndarray) -> SpikeTrains:
    """The trains ``prefix`` of an entry (the inverse of :func:`train_values`), each recording's
    ``duration`` theirs; refused where counts and starts do not match the events."""
    times, polarity = values[f"{prefix}_times_s"], values[f"{prefix}_polarity"]
    count, start = values[f"{prefix}_count"], values[f"{prefix}_start"]
    flat = count.ravel()
    if (flat < 0).any() or int(flat.sum()) != times.size:
        raise ValueError(f"{prefix}_count does not match {prefix}_times_s")
    if not np.array_equal(start, train_starts(count)):
        raise ValueError(f"{prefix}_start is not the running sum of {prefix}_count")
    return SpikeTrains(times_s=times, polarity=polarity, count=count, duration_s=duration)


def seconds_attr(seconds: Mapping[str, float]) -> dict[str, float]:
    """Step seconds as an entry attribute; refused unless finite (JSON cannot hold others)."""
    out = {str(stage): float(value) for stage, value in seconds.items()}
    bad = [stage for stage, value in out.items() if not math.isfinite(value)]
    if bad:
        raise ValueError(f"seconds: not finite for {bad} (JSON attributes cannot hold them)")
    return out


def read_seconds(attrs: Mapping[str, Any]) -> dict[str, float]:
    """The step seconds of an entry's ``seconds`` attribute."""
    seconds = attrs["seconds"]
    if not isinstance(seconds, dict):
        raise TypeError("attribute 'seconds' is not a mapping")
    return {str(stage): float(value) for stage, value in seconds.items()}


def paid_attr(paid: Paid) -> dict[str, dict[str, float]]:
    """Paid seconds as an entry attribute: every charge, each refused unless finite."""
    return {str(charge): seconds_attr(paid.get(charge, {})) for charge in Charge}


def read_paid(attrs: Mapping[str, Any]) -> Paid | None:
    """The paid seconds of an entry; None for one written before they were kept."""
    paid = attrs.get("paid_seconds")
    if paid is None:
        return None
    if not isinstance(paid, dict) or set(paid) - {str(c) for c in Charge}:
        raise TypeError("attribute 'paid_seconds' is not a mapping of charges")
    return {charge: read_seconds({"seconds": paid.get(str(charge), {})}) for charge in Charge}


def metric_values(metrics: SpikeMetrics) -> np.ndarray:
    """The metrics as one float64 array (attributes are JSON, which cannot hold +-inf)."""
    return np.array([np.asarray(getattr(metrics, name)) for name in _METRICS])


def read_metrics(values: Mapping[str, np.ndarray]) -> SpikeMetrics:
    """The spike metrics of an entry's ``metrics`` array (the inverse of :func:`metric_values`)."""
    metrics = values["metrics"]
    if metrics.shape != (len(_METRICS),):
        raise ValueError(f"metrics: {metrics.shape[0]} values, expected {len(_METRICS)}")
    return SpikeMetrics(*(float(value) for value in metrics))
