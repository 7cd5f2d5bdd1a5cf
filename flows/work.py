"""Work that runs on Dask workers: plain functions, no Prefect.

:func:`ensure_entry` is the one task: it makes sure the run's store holds one level's entry of a
scene (a level of :data:`pipeline.stages.LEVELS` that the store keeps), reading what its inputs
need from the store and computing only the entries that are missing, inputs first. Each entry is
written complete (storage marks it complete only after its data is written). Work is keyed by the
levels' cache keys, so two points that share a spike train (a window sweep at one threshold)
reuse it, and a worker that dies mid-task leaves nothing a later run trusts. The levels the store
does not keep (the recordings and their front end) stay in memory, a few per worker process.

Torch runs one intra-op thread per worker: Dask already runs one task per worker thread, and
oversubscribing two cores made training 37x slower. The C allocator keeps training's tensors on
the heap (:func:`flows.environment.tune_allocator`), whatever the nanny set.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable
from typing import Any

from flows.environment import tune_allocator
from pipeline.cube import OutOfFold, RecordingsInfo
from pipeline.scene import Scene
from pipeline.stages import RATES, RECORDINGS, RESULTS, SPIKES, Level, Stopwatch, level_named
from storage import RateEntry, ResultEntry, SpikeEntry, SweepStore

# pipeline.training (torch, scikit-learn) is imported by the results level when it runs: the
# coordinator imports this module only to name the function it submits, and never trains.

# Outputs of the in-memory levels kept per worker process, by level and key (they are
# immutable, and every point of a dataset needs them), with the seconds they took when made.
_KEPT_PER_LEVEL = 4
_kept: dict[str, OrderedDict[str, tuple[Any, dict[str, float]]]] = {}
_kept_lock = threading.Lock()

# A level of the same point, made once: its output (or entry) and the seconds that holds.
_Made = Callable[[Level], tuple[Any, dict[str, float]]]


def _result_entry(accuracy: Any, seconds: dict[str, float], made: _Made) -> ResultEntry:
    spikes, spike_seconds = made(SPIKES)
    _, rate_seconds = made(RATES)
    recordings, _ = made(RECORDINGS)
    return ResultEntry(
        fold_accuracy={model.value: cv.fold_accuracy for model, cv in accuracy.items()},
        seconds={**spike_seconds, **rate_seconds, **seconds},
        metrics=spikes.metrics,
        # The cube states what the point was computed on, without reloading the dataset.
        recordings=RecordingsInfo(recordings.name, recordings.class_names, recordings.fs_hz),
        out_of_fold=OutOfFold(
            recording_names=tuple(recordings.names),
            labels=recordings.labels,
            predicted={model.value: cv.predicted for model, cv in accuracy.items()},
            test_fold=next(iter(accuracy.values())).test_fold,
        ),
    )


# How each stored level's output becomes its store entry (the layouts are in storage.store), given
# the seconds the entry accounts for. A result is all a cube reads of a point, so it also carries
# the spike metrics and the seconds of the entries it was made from.
_ENTRIES: dict[str, Callable[[Any, dict[str, float], _Made], Any]] = {
    SPIKES.name: lambda out, seconds, made: SpikeEntry(out.encoded, out.metrics, seconds),
    RATES.name: lambda out, seconds, made: RateEntry(
        out.counts, out.dropped, out.labels, out.class_names, seconds
    ),
    RESULTS.name: _result_entry,
}


def ensure_entry(root: str, level: str, scene_data: dict[str, Any], *after: Any) -> str:
    """Make sure the store at ``root`` holds the entry of ``level`` for a scene; return its key.

    Nothing is computed if the entry is there. Otherwise the entries of the levels it runs after
    are read from the store, or computed and written first if missing, then its own.

    Parameters
    ----------
    root
        The run root.
    level
        The name of a level the store keeps (``"spikes"``, ``"rates"``, ``"results"``).
    scene_data
        The scene, as :meth:`pipeline.scene.Scene.to_dict` gives it.
    after
        Futures this task waits for (the spike trains of a point); their values are not used.

    Raises
    ------
    ValueError
        ``level`` names no level the store keeps.
    """
    import torch

    torch.set_num_threads(1)
    tune_allocator()
    wanted = level_named(level)
    if not wanted.stored:
        raise ValueError(f"stage {level!r} is not kept in the store")
    scene = Scene.from_dict(scene_data)
    store = SweepStore.open(root)
    key = wanted.key(scene)
    if not store.has(wanted.name, key):
        _Point(store, scene).made(wanted)
    return key


class _Point:
    """The levels of one scene as one task needs them: each read, recalled or computed once."""

    def __init__(self, store: SweepStore, scene: Scene):
        self.store = store
        self.scene = scene
        self._made: dict[str, tuple[Any, dict[str, float]]] = {}

    def made(self, level: Level) -> tuple[Any, dict[str, float]]:
        """``level``'s output (its store entry, for a stored level) and the seconds it holds."""
        if level.name not in self._made:
            self._made[level.name] = self._make(level)
        return self._made[level.name]

    def _make(self, level: Level) -> tuple[Any, dict[str, float]]:
        if not level.stored:
            return self._in_memory(level)
        key = level.key(self.scene)
        entry = self.store.read_valid(level.name, key)
        if entry is None:
            watch = Stopwatch(None)
            output = level.run(self.scene, self._inputs(level), watch)
            seconds = {
                step: value
                for upstream in _accounted(level)
                for step, value in self.made(upstream)[1].items()
            }
            entry = _ENTRIES[level.name](output, {**seconds, **watch.seconds}, self.made)
            self.store.write_entry(level.name, key, entry)
        return entry, entry.seconds

    def _in_memory(self, level: Level) -> tuple[Any, dict[str, float]]:
        key = level.key(self.scene)
        with _kept_lock:
            kept = _kept.setdefault(level.name, OrderedDict())
            if key in kept:
                kept.move_to_end(key)
                return kept[key]
        watch = Stopwatch(None)
        made = (level.run(self.scene, self._inputs(level), watch), dict(watch.seconds))
        with _kept_lock:
            kept[key] = made
            while len(kept) > _KEPT_PER_LEVEL:
                kept.popitem(last=False)
        return made

    def _inputs(self, level: Level) -> dict[str, Any]:
        return {before.name: self.made(before)[0] for before in level.after}


def _accounted(level: Level) -> tuple[Level, ...]:
    """The in-memory levels whose seconds ``level``'s entry holds besides its own steps.

    Those upstream of it that no stored level upstream of it needs as well: the seconds of the
    recordings and front end go into the spike entry, not again into the rate entry.
    """
    upstream = level.upstream()
    covered = {each.name for s in upstream if s.stored for each in (*s.upstream(), s)}
    return tuple(each for each in upstream if not each.stored and each.name not in covered)
