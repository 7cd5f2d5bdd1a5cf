"""The stage registry: every level of a scene's simulation, declared once, in data-flow order.

Data flows one way::

    recordings -> taxel signals -> spike trains -> rate matrices -> accuracy

and :data:`LEVELS` holds one :class:`Level` per kept result of that flow:

==============  ========================================  =====================  =================
level           reads (scene parts)                       after (levels)         timed steps
==============  ========================================  =====================  =================
``recordings``  ``dataset``                               --                     ``load``
``front_end``   ``readout.full_scale_v``                  recordings             ``front_end``
``spikes``      ``array``, ``readout``, ``seed`` (only    recordings, front_end  ``taxels``,
                when a named effect draws random numbers)                        ``readout``,
                                                                                 ``metrics``
``rates``       ``coding``                                spikes, recordings     ``coding``
``results``     ``training``                              rates                  ``train_<model>``
==============  ========================================  =====================  =================

Taxel signals are made inside ``spikes``, one recording at a time, and never kept (they are as
large as the recordings times the taxels). ``recordings``, ``front_end`` and ``rates`` live in
memory (a Dask worker keeps a few of each); ``spikes`` and ``results`` are the cache levels,
whose outputs the sweep store keeps as entries of the same names. Rate matrices are not kept:
coding a point's trains takes milliseconds, while its matrix is as large as its trains, and a
sweep of many points would pay for them in files and bytes more than it saves in time. Spike
trains are kept: encoding a high-density array takes seconds, and every window length and
training seed of a sweep reuses one train.

A level's cache key (:meth:`Level.key`) hashes :data:`pipeline.scene.MODEL_REVISION`, the level's
name and the canonical form of the parts it and every level before it read: ``recordings`` hashes
``dataset``; ``spikes`` ``dataset``, ``array``, ``readout`` (and ``seed`` if a named effect draws
random numbers); ``rates`` those and ``coding``; ``results`` those and ``training``. Its compute
function is called with exactly those parts, by keyword (the last name of each: ``dataset``,
``full_scale_v``, ``seed``, ...), the outputs of the levels it runs after (by level name) and a
:class:`Stopwatch` ``watch``, never with the whole scene: it cannot use a field its key leaves out.
A part read only under a condition (the seed) is passed as None when the condition fails.

Adding a stage: write its compute function (keyword-only arguments as above; it times each of
its steps with ``watch.stage(step)``) and add one :class:`Level` to :data:`LEVELS`, after the
levels it needs. :func:`pipeline.simulate.run_scene`, its stage names, the cache keys, the sweep's
work on Dask workers and the stages of a cube's ``seconds`` follow from the registry. A level whose
output the sweep store keeps (``stored=True``) also needs its entry layout in
:mod:`storage.store` (write and read) and the line of :mod:`flows.work` that turns its output
into that entry.
"""

from __future__ import annotations

import functools
import hashlib
import time
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pipeline import fields
from pipeline import scene as scene_module
from pipeline.coding import frames, resolve_n_windows
from pipeline.frontend import FrontEnd, fit_front_end
from pipeline.metrics import (
    SpikeMetrics,
    data_rate_bps,
    equivalent_bits,
    event_rate_hz,
    pooled_ssnr_db,
    ste_per_train,
)
from pipeline.readout import level_crossings, real_train
from pipeline.recordings import Recordings, load_recordings
from pipeline.scene import (
    ArraySpec,
    CodingSpec,
    DatasetSpec,
    Model,
    ReadoutSpec,
    Scene,
    TrainingSpec,
)
from pipeline.spikes import Encoded, SpikeTrains
from pipeline.taxels import taxel_delays_s, taxel_signals

if TYPE_CHECKING:
    from pipeline.training import CrossValidation

# pipeline.training (torch, scikit-learn) is imported by the results level only when it runs:
# the sweep's coordinator imports this registry (cache keys, cube stages) and never trains.

__all__ = [
    "FRONT_END",
    "LEVELS",
    "RATES",
    "RECORDINGS",
    "RESULTS",
    "SPIKES",
    "Level",
    "Rates",
    "Read",
    "Spikes",
    "Stopwatch",
    "level_named",
    "steps_through",
]


class Stopwatch:
    """Accumulates wall seconds per step and reports each step the first time it starts."""

    def __init__(self, on_stage: Callable[[str], None] | None):
        self.seconds: dict[str, float] = {}
        self.on_stage = on_stage

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        if self.on_stage is not None and name not in self.seconds:
            self.on_stage(name)
        start = time.perf_counter()
        try:
            yield
        finally:
            self.seconds[name] = self.seconds.get(name, 0.0) + time.perf_counter() - start


# ---------------------------------------------------------------------------------------------
# Outputs


@dataclass(frozen=True, eq=False)
class Spikes:
    """Output of the ``spikes`` level (the store's ``SpikeEntry`` has the same fields).

    Attributes
    ----------
    encoded : Encoded
        TRUE and REAL trains of every taxel of every recording; ``real is true`` for an ideal
        readout.
    metrics : SpikeMetrics
        Scene-level SSNR, STE, rates and resolution.
    """

    encoded: Encoded
    metrics: SpikeMetrics


@dataclass(frozen=True, eq=False)
class Rates:
    """Output of the ``rates`` level, kept in memory by the workers (not in the store).

    Attributes
    ----------
    counts : int64 (n_recordings, channels, n_taxels, n_windows)
        REAL spikes per window.
    dropped : int64 (n_recordings, n_taxels)
        REAL spikes outside every window.
    labels : int64 (n_recordings,)
        Class index of each recording, into ``class_names``.
    class_names : tuple[str, ...]
        Class names.
    """

    counts: np.ndarray
    dropped: np.ndarray
    labels: np.ndarray
    class_names: tuple[str, ...]


# ---------------------------------------------------------------------------------------------
# Compute functions: one per level, keyword-only, given exactly what their level declares


def load(*, dataset: DatasetSpec, watch: Stopwatch) -> Recordings:
    """Read or generate the recordings."""
    with watch.stage("load"):
        return load_recordings(dataset)


def fit(*, recordings: Recordings, full_scale_v: float, watch: Stopwatch) -> FrontEnd:
    """Fit one scaling for the whole dataset to ``full_scale_v`` (:mod:`pipeline.frontend`)."""
    with watch.stage("front_end"):
        return fit_front_end(recordings, full_scale_v)


def encode_trains(
    recordings: Recordings,
    front_end: FrontEnd,
    array: ArraySpec,
    readout: ReadoutSpec,
    seed: int | None,
    watch: Stopwatch,
) -> Encoded:
    """TRUE and REAL spike trains of every taxel of every recording (steps ``taxels``, ``readout``).

    Taxels that see the same signal share one TRUE train; an ideal readout returns the TRUE
    trains as the REAL ones without encoding again. ``seed`` seeds the readout's random effects
    (None if it names none).
    """
    delays = taxel_delays_s(array)
    fs = recordings.fs_hz
    theta = readout.threshold_v
    true_trains, real_trains, durations = [], [], []
    for index, signal in enumerate(recordings.signals):
        with watch.stage("taxels"):
            taxels = taxel_signals(front_end.apply(signal), fs, delays)
        with watch.stage("readout"):
            per_row = [level_crossings(row, fs, theta) for row in taxels.signals]
            true = [per_row[row] for row in taxels.taxel_row]
            true_trains.extend(true)
            durations.append((taxels.n_samples - 1) / fs)
            if readout.is_ideal:
                continue
            real_trains.extend(
                real_train(
                    taxels.taxel(taxel),
                    fs,
                    readout,
                    seed=seed,
                    taxel=taxel,
                    recording=index,
                )
                for taxel in range(taxels.n_taxels)
            )
    n_taxels = array.n_taxels
    true_set = SpikeTrains.concatenate(true_trains, n_taxels, np.asarray(durations))
    if readout.is_ideal:
        return Encoded(true_set, true_set)
    return Encoded(true_set, SpikeTrains.concatenate(real_trains, n_taxels, true_set.duration_s))


def spike_metrics(encoded: Encoded, readout: ReadoutSpec) -> SpikeMetrics:
    """Scene-level SSNR (pooled), STE (mean over trains), rates and resolution."""
    return SpikeMetrics(
        ssnr_db=pooled_ssnr_db(encoded.true.count, encoded.real.count),
        ste_s2=float(ste_per_train(encoded.true, encoded.real, "paper").mean()),
        ste_sign_safe_s2=float(ste_per_train(encoded.true, encoded.real, "sign_safe").mean()),
        event_rate_hz=event_rate_hz(encoded.real),
        data_rate_bps=data_rate_bps(encoded.real),
        equivalent_bits=equivalent_bits(readout.full_scale_v, readout.threshold_v),
    )


def encode_spikes(
    *,
    recordings: Recordings,
    front_end: FrontEnd,
    array: ArraySpec,
    readout: ReadoutSpec,
    seed: int | None,
    watch: Stopwatch,
) -> Spikes:
    """Encode every taxel of every recording, then measure the trains (step ``metrics``)."""
    encoded = encode_trains(recordings, front_end, array, readout, seed, watch)
    with watch.stage("metrics"):
        return Spikes(encoded, spike_metrics(encoded, readout))


def rate_frames(real: SpikeTrains, coding: CodingSpec) -> tuple[np.ndarray, np.ndarray]:
    """Rate-coded frames of the REAL trains: ``counts`` int64 (n_rec, C, taxels, windows), and
    ``dropped`` int64 (n_rec, taxels); the number of windows is resolved for these recordings."""
    n_windows = resolve_n_windows(coding, real.duration_s)
    return frames(real, coding.window_s, n_windows, coding.polarity)


def code_rates(
    *, spikes: Spikes, recordings: Recordings, coding: CodingSpec, watch: Stopwatch
) -> Rates:
    """Rate-code the REAL trains (step ``coding``), labelled by the recordings' classes."""
    with watch.stage("coding"):
        counts, dropped = rate_frames(spikes.encoded.real, coding)
    return Rates(counts, dropped, recordings.labels, recordings.class_names)


def classify(
    *, rates: Rates, training: TrainingSpec, watch: Stopwatch
) -> dict[Model, CrossValidation]:
    """Cross-validate every model ``training`` names on the same frames (steps ``train_<m>``)."""
    from pipeline.training import cross_validate

    accuracy = {}
    for model in training.models:
        with watch.stage(f"train_{model.value}"):
            accuracy[model] = cross_validate(
                rates.counts, rates.labels, model, training, class_names=rates.class_names
            )
    return accuracy


# ---------------------------------------------------------------------------------------------
# The registry


def _draws_random_numbers(scene: Scene) -> bool:
    return scene.readout.is_random


@dataclass(frozen=True)
class Read:
    """One scene part a level reads.

    Attributes
    ----------
    path : str
        A top-level scene part (``"dataset"``, ``"seed"``) or one field of one (dotted,
        ``"readout.full_scale_v"``); the compute function gets it as its last name.
    when : callable, optional
        Read (passed, and hashed into the key) only for scenes where ``when(scene)`` holds;
        otherwise passed as None.
    """

    path: str
    when: Callable[[Scene], bool] | None = None

    @property
    def argument(self) -> str:
        return self.path.rsplit(".", 1)[-1]

    def applies(self, scene: Scene) -> bool:
        return self.when is None or self.when(scene)

    def value(self, scene: Scene) -> Any:
        return fields.get(scene, self.path) if self.applies(scene) else None


@dataclass(frozen=True, eq=False)
class Level:
    """One level of the data flow: what it reads, what it runs after, how it is computed.

    Attributes
    ----------
    name : str
        Names its output: the argument later levels get it as, the tag of its cache key and,
        for a stored level, its entry kind in the sweep store.
    reads : tuple of Read
        The scene parts its compute function reads.
    after : tuple of Level
        The levels whose outputs its compute function takes, each declared before it.
    compute : callable
        ``compute(**outputs_of_after, **parts_read, watch=stopwatch) -> output``.
    steps : tuple of str
        The steps it times, in order; ``{model}`` stands for each model the scene trains.
    stored : bool
        Whether the sweep store keeps its output (a cache level), or workers keep it in memory.
    """

    name: str
    reads: tuple[Read, ...]
    after: tuple[Level, ...]
    compute: Callable[..., Any]
    steps: tuple[str, ...]
    stored: bool

    def __repr__(self) -> str:
        return f"Level({self.name!r})"

    def upstream(self) -> tuple[Level, ...]:
        """Every level this one needs, directly or through others, each once, inputs first."""
        return self._upstream

    @functools.cached_property
    def _upstream(self) -> tuple[Level, ...]:
        found: dict[str, Level] = {}
        for before in self.after:
            for level in (*before.upstream(), before):
                found.setdefault(level.name, level)
        return tuple(found.values())

    @functools.cached_property
    def _all_reads(self) -> tuple[Read, ...]:
        return tuple(read for level in (*self.upstream(), self) for read in level.reads)

    @functools.cached_property
    def _parts_by_condition(self) -> dict[tuple[bool, ...], tuple[str, ...]]:
        # The parts depend on the scene only through which conditional reads apply: computed
        # once per such combination, as a grid asks for the keys of many scenes.
        return {}

    def key_parts(self, scene: Scene) -> tuple[str, ...]:
        """The scene parts this level's output depends on: what it and its upstream read.

        A field whose whole part is read too is left to the part (``readout.full_scale_v``
        within ``readout``).
        """
        reads = self._all_reads
        applies = tuple(read.applies(scene) for read in reads if read.when is not None)
        parts = self._parts_by_condition.get(applies)
        if parts is None:
            conditions = iter(applies)
            paths: dict[str, None] = {}
            for read in reads:
                if read.when is None or next(conditions):
                    paths.setdefault(read.path, None)
            parts = tuple(p for p in paths if not any(p.startswith(f"{q}.") for q in paths))
            self._parts_by_condition[applies] = parts
        return parts

    def key(self, scene: Scene, memo: scene_module.CanonicalMemo | None = None) -> str:
        """SHA-256 (hex, 32 chars) of :data:`pipeline.scene.MODEL_REVISION`, the level's name
        and the canonical form of exactly :meth:`key_parts`; ``memo`` as for
        :meth:`pipeline.scene.Scene.canonical` (the key does not depend on it)."""
        canonical = scene.canonical(self.key_parts(scene), memo)
        text = f"r{scene_module.MODEL_REVISION}:{self.name}:" + canonical
        return hashlib.sha256(text.encode()).hexdigest()[:32]

    def step_names(self, scene: Scene) -> tuple[str, ...]:
        """The steps this level times for ``scene``, in order."""
        models = [m.value for m in scene.training.models]
        return tuple(
            name
            for step in self.steps
            for name in ([step.format(model=m) for m in models] if "{model}" in step else [step])
        )

    def run(self, scene: Scene, outputs: Mapping[str, Any], watch: Stopwatch) -> Any:
        """Compute this level's output for ``scene`` from the ``outputs`` of its inputs (by
        level name; other entries are ignored), timing its steps on ``watch``.

        Raises
        ------
        RuntimeError
            The compute function timed other steps than the level declares (a programming
            error: a cube would miss them).
        """
        arguments = {before.name: outputs[before.name] for before in self.after}
        for read in self.reads:
            arguments[read.argument] = read.value(scene)
        timed_before = set(watch.seconds)
        output = self.compute(**arguments, watch=watch)
        timed = set(watch.seconds) - timed_before
        declared = set(self.step_names(scene))
        if timed != declared:
            raise RuntimeError(
                f"level {self.name!r} timed steps {sorted(timed)}, declared {sorted(declared)}"
            )
        return output


RECORDINGS = Level(
    name="recordings",
    reads=(Read("dataset"),),
    after=(),
    compute=load,
    steps=("load",),
    stored=False,
)
FRONT_END = Level(
    name="front_end",
    reads=(Read("readout.full_scale_v"),),
    after=(RECORDINGS,),
    compute=fit,
    steps=("front_end",),
    stored=False,
)
SPIKES = Level(
    name="spikes",
    reads=(Read("array"), Read("readout"), Read("seed", when=_draws_random_numbers)),
    after=(RECORDINGS, FRONT_END),
    compute=encode_spikes,
    steps=("taxels", "readout", "metrics"),
    stored=True,
)
RATES = Level(
    name="rates",
    reads=(Read("coding"),),
    after=(SPIKES, RECORDINGS),
    compute=code_rates,
    steps=("coding",),
    stored=False,
)
RESULTS = Level(
    name="results",
    reads=(Read("training"),),
    after=(RATES,),
    compute=classify,
    steps=("train_{model}",),
    stored=True,
)


def _checked(*levels: Level) -> tuple[Level, ...]:
    """The registry, refused at import if a level could not run in this order."""
    names: set[str] = set()
    steps: set[str] = set()
    for level in levels:
        problems = []
        if level.name in names:
            problems.append("its name is taken")
        problems += [
            f"runs after {b.name!r}, declared later" for b in level.after if b.name not in names
        ]
        arguments = [b.name for b in level.after] + [r.argument for r in level.reads]
        if len(set(arguments)) != len(arguments) or "watch" in arguments:
            problems.append(f"its compute arguments clash: {arguments}")
        if steps & set(level.steps):
            problems.append(f"steps {sorted(steps & set(level.steps))} are timed by another level")
        if problems:
            raise ValueError(f"stage registry: level {level.name!r}: {'; '.join(problems)}")
        names.add(level.name)
        steps.update(level.steps)
    return levels


#: Every level, in data-flow order (each after the levels it needs).
LEVELS: tuple[Level, ...] = _checked(RECORDINGS, FRONT_END, SPIKES, RATES, RESULTS)


def level_named(name: str) -> Level:
    """The level of :data:`LEVELS` called ``name``."""
    for level in LEVELS:
        if level.name == name:
            return level
    known = ", ".join(level.name for level in LEVELS)
    raise ValueError(f"no stage {name!r} (known: {known})")


def steps_through(name: str) -> tuple[str, ...]:
    """The steps of level ``name`` and of every level it needs, in data-flow order.

    Only for levels whose steps do not depend on the scene (no ``{model}``).
    """
    level = level_named(name)
    steps = tuple(step for each in (*level.upstream(), level) for step in each.steps)
    if any("{model}" in step for step in steps):
        raise ValueError(f"the steps of stage {name!r} depend on the scene's models")
    return steps
