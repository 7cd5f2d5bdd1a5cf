"""The stage registry: every level of a scene's simulation, declared once, in data-flow order.

Data flows one way::

    recordings -> taxel signals -> spike trains -> rate matrices -> accuracy

and :data:`LEVELS` holds one :class:`Level` per kept result of that flow:

==============  =========================================  =====================  =================
level           reads (scene parts)                        after (levels)         timed steps
==============  =========================================  =====================  =================
``recordings``  ``dataset``                                --                     ``load``
``front_end``   ``readout.full_scale_v``                   recordings             ``front_end``
``spikes``      ``array``, ``readout``, ``seed`` (only     recordings, front_end  ``setup``,
                when a named effect draws random numbers)                         ``taxels``,
                                                                                  ``readout``,
                                                                                  ``metrics``
``rates``       ``coding`` (+ ``training.snn`` when the    spikes, recordings     ``coding``
                scene trains the ``snn``)
``results``     ``training``                               rates                  ``train_<model>``
==============  =========================================  =====================  =================

Taxel signals are made inside ``spikes``, one recording at a time, and never kept (they are as
large as the recordings times the taxels). ``recordings``, ``front_end`` and ``rates`` live in
memory (a Dask worker keeps a few of each); ``spikes`` and ``results`` are the cache levels,
whose outputs the sweep store keeps as entries of the same names. Rate matrices are not kept:
coding a point's trains takes milliseconds, while its matrix is as large as its trains, and a
sweep of many points would pay for them in files and bytes more than it saves in time. Spike
trains are kept: encoding a high-density array takes seconds, and every window length and
training seed of a sweep reuses one train. A level's cache policy (:attr:`Level.kept`) says which
of its entries the store keeps: the spike entries of scenes that simulate chips are not (their
chip trains cost little more to encode again than to read back, and only a later point of
another coding or training would read them).

A level's cache key (:meth:`Level.key`, :func:`cache_key`) hashes
:data:`pipeline.design.scene.MODEL_REVISION`, the level's name and the canonical form of the parts
it and every level before it read: ``recordings`` hashes ``dataset``; ``spikes`` ``dataset``,
``array``, ``readout`` (and ``seed`` if a named effect draws random numbers); ``rates`` those
and ``coding``; ``results`` those and ``training``. Its compute function is called with exactly
those parts, by keyword (the last name of each: ``dataset``, ``full_scale_v``, ``seed``, ...),
the outputs of the levels it runs after (by level name) and a
:class:`~pipeline.run.stopwatch.Stopwatch` ``watch``, never with the whole scene: it cannot use a
field its key leaves out.
A part read only under a condition (the seed) is passed as None when the condition fails.

A stored level's entry holds the seconds of its own steps, of every stored level upstream of it
(their entries' seconds) and of the in-memory levels upstream of it that no such stored level
covers: a result entry holds every step of its point, which is all a cube reads.

Seconds come in two kinds (:class:`~pipeline.run.stopwatch.Stopwatch`). *Work* seconds are what
each step's work took, whichever point it was done for (the entries' ``seconds``). *Paid* seconds
are what a worker spent computing for one point, each second charged to exactly one point
(:class:`~pipeline.run.records.Charge`): ``own`` for the point's own work, ``shared`` for work the
worker's later points reuse: the steps a level declares :attr:`Level.shared` (``load``,
``front_end``) and the one-off :data:`~pipeline.run.stopwatch.SETUP_STEP` (importing numba, torch
and scikit-learn; loading or compiling the numba kernels, wherever it happens), so that summed over
a sweep's distinct points they count each second once.

The spikes level's compute is :mod:`pipeline.run.encoding`; chips and decisions, which a
point's entries keep beside its trains and accuracy, have their own modules
(:mod:`pipeline.run.chips`, :mod:`pipeline.run.decisions`), joined to the levels' records here.

Adding a stage: write its compute function (keyword-only arguments as above; it times each of
its steps with ``watch.stage(step)``) and add one :class:`Level` to :data:`LEVELS`, after the
levels it needs. To keep its output in the sweep store, give it a
:class:`~pipeline.run.records.Record`: its variables (dims, dtypes, units), its entry type, and how
its output becomes that entry and back. The levels after a stored level get its output in a run
and its entry in a sweep, so they read only what both hold. :func:`pipeline.run.simulate.run_scene`,
the cache keys, the store's batches, the sweep's work on Dask workers and the stages of a
cube's ``seconds`` follow from the registry.
"""

from __future__ import annotations

import functools
import hashlib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np

from pipeline.chain.frontend import FrontEnd, fit_front_end
from pipeline.design import fields
from pipeline.design import scene as scene_module
from pipeline.design.scene import (
    CanonicalMemo,
    DatasetSpec,
    Model,
    Scene,
)
from pipeline.recordings.sources import Recordings, load_recordings
from pipeline.run.chips import chip_results
from pipeline.run.decisions import decisions_of
from pipeline.run.decoding import classify, code_rates, reads_steps
from pipeline.run.encoding import Spikes, encode_spikes
from pipeline.run.entries import (
    RESULT_VARIABLES,
    SPIKE_VARIABLES,
    OutOfFold,
    RecordingsInfo,
    ResultEntry,
    SpikeEntry,
    decode_result_entry,
    decode_spike_entry,
    encode_result_entry,
    encode_spike_entry,
)
from pipeline.run.records import (
    Charge,
    Record,
    StepSeconds,
)
from pipeline.run.stopwatch import SETUP_STEP, Stopwatch

if TYPE_CHECKING:
    from pipeline.chain.training import CrossValidation

# pipeline.chain.training (torch, scikit-learn) is imported by the results level only when it runs:
# the sweep's coordinator imports this registry (cache keys, cube stages) and never trains.

__all__ = [
    "FRONT_END",
    "LEVELS",
    "RATES",
    "RECORDINGS",
    "RESULTS",
    "SETUP_STEP",
    "SPIKES",
    "Level",
    "Read",
    "cache_key",
    "interval_generator",
    "level_named",
    "shared_steps",
    "stage_fields",
    "step_charge",
    "steps_of",
    "steps_through",
    "stored_levels",
]


# ---------------------------------------------------------------------------------------------
# Outputs


# ---------------------------------------------------------------------------------------------
# Compute functions: one per level, keyword-only, given exactly what their level declares


def load(*, dataset: DatasetSpec, watch: Stopwatch) -> Recordings:
    """Read or generate the recordings."""
    with watch.stage("load"):
        return load_recordings(dataset)


def fit(*, recordings: Recordings, full_scale_v: float, watch: Stopwatch) -> FrontEnd:
    """Fit one dataset-wide scaling to ``full_scale_v`` (:mod:`pipeline.chain.frontend`)."""
    with watch.stage("front_end"):
        return fit_front_end(recordings, full_scale_v)


# ---------------------------------------------------------------------------------------------
# The registry


def _draws_random_numbers(scene: Scene) -> bool:
    return scene.readout.is_random


def _simulates_chips(scene: Scene) -> bool:
    return scene.chips.simulated


@dataclass(frozen=True)
class Read:
    """One scene part a level reads.

    Attributes
    ----------
    path : str
        A top-level scene part (``"dataset"``, ``"seed"``) or one field of one (dotted,
        ``"readout.full_scale_v"``); the compute function gets it as its last name.
    when : callable or None
        Read (passed, and hashed into the key) only for scenes where ``when(scene)`` holds;
        otherwise passed as None. None (the default): read for every scene.
    """

    path: str
    when: Callable[[Scene], bool] | None = None

    @property
    def argument(self) -> str:
        """The keyword the compute function gets the part as, the last name of ``path``."""
        return self.path.rsplit(".", 1)[-1]

    def applies(self, scene: Scene) -> bool:
        """Whether ``scene`` reads the part (``when`` holds, or there is no ``when``)."""
        return self.when is None or self.when(scene)

    def value(self, scene: Scene) -> Any:
        """The part's value in ``scene`` (a value object or a field's value), or None where it
        does not apply."""
        return fields.get(scene, self.path) if self.applies(scene) else None


def keep_every_entry(entry: Any) -> bool:
    """The default cache policy of a stored level (:attr:`Level.kept`): keep every entry."""
    return True


@dataclass(frozen=True, eq=False)
class Level:
    """One level of the data flow: what it reads, what it runs after, how it is computed.

    Attributes
    ----------
    name : str
        Names its output: the argument later levels get it as, the tag of its cache key and,
        for a stored level, its entry kind in the sweep store (``record.name``).
    reads : tuple of Read
        The scene parts its compute function reads.
    after : tuple of Level
        The levels whose outputs its compute function takes, each declared before it.
    compute : callable
        ``compute(**outputs_of_after, **parts_read, watch=stopwatch) -> output``.
    steps : tuple of str
        The steps it times, in order; ``{model}`` stands for each model the scene trains.
    record : ~pipeline.run.records.Record or None
        What the sweep store keeps of its output (a cache level); None: workers keep its output
        in memory.
    shared : tuple of str
        Its steps whose work serves every later point of a worker that needs the same output
        (a load, a front-end fit, a warm-up): their seconds are charged ``shared`` to
        the point that paid them (:func:`step_charge`); the others' ``own``.
    kept : callable
        The cache policy of a stored level: ``kept(entry)`` says whether the sweep store keeps
        an entry (one it does not keep is computed again where a later task needs it): kept
        when reading it back is cheaper than computing it again.
    """

    name: str
    reads: tuple[Read, ...]
    after: tuple[Level, ...]
    compute: Callable[..., Any]
    steps: tuple[str, ...]
    record: Record | None = None
    shared: tuple[str, ...] = ()
    kept: Callable[[Any], bool] = keep_every_entry

    def __repr__(self) -> str:
        return f"Level({self.name!r})"

    @property
    def stored(self) -> bool:
        """Whether the sweep store keeps its output."""
        return self.record is not None

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

    def key(self, scene: Scene, memo: CanonicalMemo | None = None) -> str:
        """SHA-256 (hex, 32 chars) of :data:`pipeline.design.scene.MODEL_REVISION`, the level's name
        and the canonical form of exactly :meth:`key_parts`; ``memo`` as for
        :meth:`pipeline.design.scene.Scene.canonical` (the key does not depend on it)."""
        canonical = scene.canonical(self.key_parts(scene), memo)
        text = f"r{scene_module.MODEL_REVISION}:{self.name}:" + canonical
        return hashlib.sha256(text.encode()).hexdigest()[:32]

    def step_names(self, scene: Scene) -> tuple[str, ...]:
        """The steps this level times for ``scene``, in order."""
        return self.steps_for([m.value for m in scene.training.models])

    def steps_for(self, models: Sequence[str]) -> tuple[str, ...]:
        """The steps this level times for a scene training ``models`` (names), in order."""
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


# ---------------------------------------------------------------------------------------------
# How the stored levels' outputs become entries (see pipeline.run.records for their codecs)


def _spike_entry(output: Spikes, seconds: StepSeconds, made: Callable[[str], Any]) -> SpikeEntry:
    return SpikeEntry(
        output.encoded, output.metrics, seconds.work, seconds.paid, seconds.point, output.chips
    )


def _result_entry(
    accuracy: dict[Model, CrossValidation],
    seconds: StepSeconds,
    made: Callable[[str], Any],
) -> ResultEntry:
    """A point's result: all a cube reads of it, so it also carries its spike metrics, what its
    recordings were and the number of windows its frames had."""
    recordings = made(RECORDINGS.name)
    by_name = {model.value: cv for model, cv in accuracy.items()}
    return ResultEntry(
        fold_accuracy={model: cv.fold_accuracy for model, cv in by_name.items()},
        seconds=seconds.work,
        metrics=made(SPIKES.name).metrics,
        recordings=RecordingsInfo.of(recordings),
        out_of_fold=OutOfFold(
            recording_names=tuple(recordings.names),
            labels=recordings.labels,
            predicted={model: cv.predicted for model, cv in by_name.items()},
            test_fold=next(iter(accuracy.values())).test_fold,
        ),
        n_windows_used=int(made(RATES.name).counts.shape[-1]),
        paid=seconds.paid,
        chips=chip_results(by_name, made(SPIKES.name).chips),
        decisions=decisions_of(by_name),
    )


#: Reads or generates the recordings (``dataset``); workers keep them in memory.
RECORDINGS = Level(
    name="recordings",
    reads=(Read("dataset"),),
    after=(),
    compute=load,
    steps=("load",),
    shared=("load",),
)
#: Fits one dataset-wide front-end scaling to ``readout.full_scale_v``; kept in memory.
FRONT_END = Level(
    name="front_end",
    reads=(Read("readout.full_scale_v"),),
    after=(RECORDINGS,),
    compute=fit,
    steps=("front_end",),
    shared=("front_end",),
)
#: Encodes every taxel of every recording (TRUE and REAL trains) and measures the trains; the
#: sweep store keeps its output.
SPIKES = Level(
    name="spikes",
    reads=(
        Read("array"),
        Read("readout"),
        Read("seed", when=_draws_random_numbers),
        Read("chips.count", when=_simulates_chips),
        Read("chips.deployment", when=_simulates_chips),
    ),
    after=(RECORDINGS, FRONT_END),
    compute=encode_spikes,
    steps=(SETUP_STEP, "taxels", "readout", "metrics"),
    shared=(SETUP_STEP,),
    # Measured on the paper grid's 100-chip points: a point's chip trains (18 million events)
    # take 35 MB and 1-4 s to read back against 5 s to encode, and they are read back only by a
    # later point of another coding or training, which then trains 100 chips' classifiers
    # anyway; the result entry keeps all a cube needs of them. Not kept: the root holds 35 MB
    # less per chip point.
    kept=lambda entry: entry.chips is None,
    record=Record(
        name="spikes",
        entry_type=SpikeEntry,
        variables=SPIKE_VARIABLES,
        make=_spike_entry,
        encode=encode_spike_entry,
        decode=decode_spike_entry,
    ),
)
#: Rate-codes the REAL trains (``coding``), labelled by the recordings' classes, and for the
#: ``snn`` counts them per step (``training.snn``, read only by scenes that train it); kept in
#: memory.
RATES = Level(
    name="rates",
    reads=(Read("coding"), Read("training.snn", when=reads_steps)),
    after=(SPIKES, RECORDINGS),
    compute=code_rates,
    steps=("coding",),
)
#: Cross-validates every model ``training`` names on the same frames; the sweep store keeps its
#: output, the point's result, with all a cube reads of it.
RESULTS = Level(
    name="results",
    reads=(Read("training"),),
    after=(RATES,),
    compute=classify,
    steps=("train_{model}",),
    record=Record(
        name="results",
        entry_type=ResultEntry,
        variables=RESULT_VARIABLES,
        make=_result_entry,
        encode=encode_result_entry,
        decode=decode_result_entry,
    ),
)


def _checked(*levels: Level) -> tuple[Level, ...]:
    """The registry, refused at import if a level could not run in this order."""
    names: set[str] = set()
    steps: set[str] = set()
    for level in levels:
        problems = []
        if level.name in names:
            problems.append("its name is taken")
        if level.record is not None and level.record.name != level.name:
            problems.append(f"its record is named {level.record.name!r}")
        problems += [
            f"runs after {b.name!r}, declared later" for b in level.after if b.name not in names
        ]
        arguments = [b.name for b in level.after] + [r.argument for r in level.reads]
        if len(set(arguments)) != len(arguments) or "watch" in arguments:
            problems.append(f"its compute arguments clash: {arguments}")
        if not set(level.shared) <= set(level.steps):
            undeclared = sorted(set(level.shared) - set(level.steps))
            problems.append(f"shared steps {undeclared} are not among its steps")
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


def stored_levels() -> tuple[Level, ...]:
    """The levels of :data:`LEVELS` whose outputs the sweep store keeps, in order."""
    return tuple(level for level in LEVELS if level.stored)


def steps_of(models: Sequence[str]) -> tuple[str, ...]:
    """Every step of :data:`LEVELS`, in order, for scenes training ``models`` (names, in the
    order given): the ``stage`` coordinate of a cube."""
    return tuple(step for level in LEVELS for step in level.steps_for(models))


def shared_steps() -> frozenset[str]:
    """The steps whose work every later point of a worker reuses (:attr:`Level.shared`)."""
    return frozenset(step for level in LEVELS for step in level.shared)


def step_charge(step: str) -> Charge:
    """The charge of a step's work: ``shared`` for :func:`shared_steps`, else own."""
    return Charge.SHARED if step in shared_steps() else Charge.OWN


def stage_fields(scene: Scene, stage: str) -> tuple[str, ...]:
    """The scene parts the output of ``stage`` depends on (:meth:`Level.key_parts`)."""
    return level_named(stage).key_parts(scene)


def cache_key(scene: Scene, stage: str, memo: CanonicalMemo | None = None) -> str:
    """The cache key of ``stage``'s output for ``scene`` (:meth:`Level.key`)."""
    return level_named(stage).key(scene, memo)


def interval_generator(result_key: str, model: str) -> np.random.Generator:
    """The generator of the bootstrap interval of ``model``'s accuracy at the point whose result
    key is ``result_key``: seeded from the key and the model's name alone, so that a design gets
    one interval wherever it is computed (any sweep, any grid position, ``eskin run``)."""
    return np.random.default_rng([int(result_key, 16), *model.encode()])


def steps_through(name: str) -> tuple[str, ...]:
    """The steps of level ``name`` and of every level it needs, in data-flow order.

    Only for levels whose steps do not depend on the scene (no ``{model}``).
    """
    level = level_named(name)
    steps = tuple(step for each in (*level.upstream(), level) for step in each.steps)
    if any("{model}" in step for step in steps):
        raise ValueError(f"the steps of stage {name!r} depend on the scene's models")
    return steps
