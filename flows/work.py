"""Work that runs on Dask workers: plain functions, no Prefect.

:func:`ensure_entries` is the one task: it makes sure the run's store holds one level's entries
for a batch of scenes (a level of :data:`pipeline.run.stages.LEVELS` that the store keeps), reading
what their inputs need from the store and computing only the entries that are missing, inputs
first. A batch of cheap points costs one Dask task instead of one each, and its entries are
written together: one batch per kind in the store (:mod:`storage.batches`) each time the task
flushes, which it does at its end and every :data:`FLUSH_S` seconds or :data:`FLUSH_BYTES`
bytes of pending entries, so that a killed worker loses at most that much work. Each batch is
written complete or not at all. Work is keyed by the levels' cache keys, so two points that
share a spike train (a window sweep at one threshold) reuse it. The levels the store does not
keep (the recordings, their front end, the rate matrices) stay in memory, a few per worker.

One failing point does not lose the others of its task: they are stored, and the task then
raises :class:`PointsFailed` naming the points that failed. A write that fails for want of
space or permission (:class:`storage.errors.StoreWriteError`) ends the task at once: the coordinator
stops the sweep and says so once, so the worker does not log it with its traceback.

What a task times: every level it runs for a point, on a :class:`pipeline.run.stopwatch.Stopwatch`;
each entry keeps the work seconds of its point's steps and the seconds the point paid, by charge
: a level whose output the point found (kept by the worker, in the store, made
for another point) costs it nothing, and the task's own set-up (importing torch, the first time
in the process) is charged to the first point it computes, as shared ``setup``. So the paid
seconds of a sweep's points sum to its workers' busy time but for the tasks' store reads and
writes.

Torch runs one intra-op thread per worker: Dask already runs one task per worker thread, and
oversubscribing two cores made training 37x slower. The C allocator keeps training's tensors on
the heap (:func:`flows.environment.tune_allocator`), whatever the nanny set.
"""

from __future__ import annotations

import functools
import logging
import threading
import time
from collections import OrderedDict
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np

from flows.environment import skip_exit_collection, tune_allocator
from pipeline.design.scene import Scene
from pipeline.run import stages
from pipeline.run.records import Charge, Paid, StepSeconds
from pipeline.run.stages import Level
from pipeline.run.stopwatch import Stopwatch
from storage import StoreWriteError, SweepStore

# pipeline.chain.training (torch, scikit-learn) is imported by the results level when it runs: the
# coordinator imports this module only to name the function it submits, and never trains.

# Outputs of the in-memory levels kept per worker process, by level and key (they are
# immutable, and every point of a dataset needs them), with the seconds they took when made.
_KEPT_PER_LEVEL = 4
_kept: dict[str, OrderedDict[str, tuple[Any, dict[str, float]]]] = {}
_kept_lock = threading.Lock()

#: A task writes its pending entries at least this often (s), so a killed worker loses at most
#: this much work: a batch per minute keeps the files few even when points take seconds.
FLUSH_S = 60.0
#: ... and once its pending entries hold this many bytes (mostly spike trains), to bound memory.
FLUSH_BYTES = 128 * 2**20


class PointsFailed(RuntimeError):
    """Some scenes of a task failed; every other one's entry is stored.

    ``failures`` maps the level key of each failed scene (the result key, for results) to one
    line saying why.
    """

    def __init__(self, failures: dict[str, str]):
        shown = "; ".join(f"{key}: {why}" for key, why in list(failures.items())[:3])
        more = f"; and {len(failures) - 3} more" if len(failures) > 3 else ""
        super().__init__(f"{len(failures)} point(s) failed: {shown}{more}")
        self.failures = dict(failures)

    def __reduce__(self) -> tuple[Any, ...]:  # Dask pickles it back to the coordinator
        return (PointsFailed, (self.failures,))


def ensure_entries(
    root: str, level: str, points: Sequence[tuple[Scene, Mapping[str, str]]], *after: Any
) -> list[str]:
    """Make sure the store at ``root`` holds ``level``'s entry of every point; return the keys.

    Nothing is computed for a scene whose entry is there. Otherwise the entries of the levels
    it runs after are read from the store (or from this task's own pending ones), or computed
    first, then its own. Entries are written in batches (see the module docstring).

    Parameters
    ----------
    root
        The run root.
    level
        The name of a level the store keeps (``"spikes"``, ``"results"``).
    points
        ``(scene, keys)`` pairs: a scene and the cache key of every level it needs, by level
        name (:func:`flows.scheduling.point_keys`), computed once by the caller. Scenes that
        share entries (the spike trains of a window sweep) are best given one after the other.
        Scenes of one grid share their part objects, and a list of them pickles those once, so
        sending them costs little.
    after
        Futures this task waits for (the spike trains its scenes share with other tasks); their
        values are not used.

    Returns
    -------
    list of str
        The level's key of each scene, in order.

    Raises
    ------
    ValueError
        ``level`` names no level the store keeps.
    PointsFailed
        Some scenes failed (after the others' entries were stored).
    """
    start = time.perf_counter()
    import torch  # a worker pays its import once, in its first task

    torch.set_num_threads(1)
    tune_allocator()
    skip_exit_collection()
    _quiet_write_failures()
    setup_s = time.perf_counter() - start
    wanted = stages.level_named(level)
    if not wanted.stored:
        raise ValueError(f"stage {level!r} is not kept in the store")
    task = _Task(SweepStore.open(root), setup_s)
    keys, failures = [], {}
    for scene, scene_keys in points:
        key = scene_keys[wanted.name]
        keys.append(key)
        try:
            if not task.holds(wanted, key):
                _Point(task, scene, scene_keys).made(wanted)
        except Exception as error:  # reported per point; the others go on
            failures[key] = " ".join(f"{type(error).__name__}: {error}".split())
        task.flush_if_due()
    task.flush()
    if failures:
        raise PointsFailed(failures)
    return keys


class _WriteFailureFilter(logging.Filter):
    """Drops a Dask worker's "Compute Failed" record (with its traceback) of a task that a
    :class:`storage.errors.StoreWriteError` ended: the coordinator reports that once."""

    def filter(self, record: logging.LogRecord) -> bool:
        marker = f"{StoreWriteError.__name__}("
        return not (
            str(record.msg).startswith("Compute Failed")
            and any(isinstance(arg, str) and arg.startswith(marker) for arg in record.args or ())
        )


@functools.cache
def _quiet_write_failures() -> None:
    """Install :class:`_WriteFailureFilter` on this worker process's Dask logger, once."""
    logging.getLogger("distributed.worker").addFilter(_WriteFailureFilter())


class _Task:
    """The entries one task made or read: pending ones written in batches, a few recent kept.

    The store is listed once per kind, when the task first asks: the entries a task needs from
    other tasks (shared spike trains) are written before it starts.
    """

    def __init__(self, store: SweepStore, setup_s: float = 0.0):
        self.store = store
        self.setup_s = setup_s
        self._stored: dict[str, frozenset[str]] = {}
        self._pending: dict[str, dict[str, Any]] = {}
        self._pending_bytes = 0
        self._recent: OrderedDict[tuple[str, str], Any] = OrderedDict()
        self._flushed = time.monotonic()

    def holds(self, level: Level, key: str) -> bool:
        """Whether the entry is pending here or was complete in the store at the listing."""
        return key in self._pending.get(level.name, {}) or key in self._listed(level)

    def entry(self, level: Level, key: str) -> Any:
        """The entry ``level/key`` if this task or the store has it (a corrupt one is
        discarded and recomputed), else None."""
        pending = self._pending.get(level.name, {})
        if key in pending:
            return pending[key]
        if (level.name, key) in self._recent:
            self._recent.move_to_end((level.name, key))
            return self._recent[level.name, key]
        if key not in self._listed(level):
            return None
        found = self.store.read_valid(level.record, key)
        if found is not None:
            self._remember(level.name, key, found)
        return found

    def add(self, level: Level, key: str, entry: Any) -> None:
        """Keep a new entry to write at the next flush."""
        self._pending.setdefault(level.name, {})[key] = entry
        self._pending_bytes += _entry_bytes(level, entry)
        self._remember(level.name, key, entry)

    def take_setup(self) -> float:
        """The task's one-off setup seconds (importing torch), to charge to the first point it
        computes; 0 after that."""
        setup_s, self.setup_s = self.setup_s, 0.0
        return setup_s

    def flush_if_due(self) -> None:
        """Flush when the pending entries are :data:`FLUSH_S` old or hold :data:`FLUSH_BYTES`."""
        if self._pending and (
            time.monotonic() - self._flushed >= FLUSH_S or self._pending_bytes >= FLUSH_BYTES
        ):
            self.flush()

    def flush(self) -> None:
        """Write the pending entries, one batch per level, inputs before the levels after."""
        for level in stages.stored_levels():
            entries = self._pending.pop(level.name, {})
            entries = {key: entry for key, entry in entries.items() if level.kept(entry)}
            if entries:
                self.store.write_entries(level.record, entries)
        self._pending_bytes = 0
        self._flushed = time.monotonic()

    def _listed(self, level: Level) -> frozenset[str]:
        if level.name not in self._stored:
            self._stored[level.name] = self.store.complete_keys(level.name)
        return self._stored[level.name]

    def _remember(self, kind: str, key: str, entry: Any) -> None:
        self._recent[kind, key] = entry
        while len(self._recent) > _KEPT_PER_LEVEL * len(stages.LEVELS):
            self._recent.popitem(last=False)


def _entry_bytes(level: Level, entry: Any) -> int:
    """Bytes of a pending entry's arrays, as its record stores them."""
    values, _ = level.record.encode(entry)
    return sum(np.asarray(value).nbytes for value in values.values())


class _Point:
    """The levels of one scene as one task needs them: each read, recalled or computed once.

    ``paid`` gathers the seconds this point's computation paid, by charge and step: every level
    it ran (an output it found, kept by the worker or stored, costs it nothing), and the paid
    seconds of a stored spike train made for it by another task (its ``paid_for``), so that
    each second a worker spent is charged to one point.
    """

    def __init__(self, task: _Task, scene: Scene, keys: Mapping[str, str]):
        self.task = task
        self.scene = scene
        self.keys = keys
        self.paid: Paid = {charge: {} for charge in Charge}
        self._made: dict[str, tuple[Any, dict[str, float]]] = {}

    def made(self, level: Level) -> tuple[Any, dict[str, float]]:
        """``level``'s output (its store entry, for a stored level) and the seconds it holds."""
        if level.name not in self._made:
            self._made[level.name] = self._make(level)
        return self._made[level.name]

    def _make(self, level: Level) -> tuple[Any, dict[str, float]]:
        if not level.stored:
            return self._in_memory(level)
        key = self.keys[level.name]
        point = self.keys[stages.RESULTS.name]
        entry = self.task.entry(level, key)
        if entry is None:
            self._pay({Charge.SHARED: {stages.SETUP_STEP: self.task.take_setup()}})
            watch = Stopwatch(None)
            output = level.run(self.scene, self._inputs(level), watch)
            self._pay(watch.paid(stages.step_charge))
            seconds = {
                step: value
                for before in _accounted(level)
                for step, value in self.made(before)[1].items()
            }
            upstream = {each.name: each for each in level.upstream()}
            entry = level.record.make(
                output,
                StepSeconds({**seconds, **watch.seconds}, _copy(self.paid), point),
                lambda name: self.made(upstream[name])[0],
            )
            self.task.add(level, key, entry)
        elif getattr(entry, "paid_for", None) == point and getattr(entry, "paid", None):
            self._pay(entry.paid)  # a train another task made for this point
        return entry, entry.seconds

    def _in_memory(self, level: Level) -> tuple[Any, dict[str, float]]:
        key = self.keys[level.name]
        with _kept_lock:
            kept = _kept.setdefault(level.name, OrderedDict())
            if key in kept:
                kept.move_to_end(key)
                return kept[key]
        self._pay({Charge.SHARED: {stages.SETUP_STEP: self.task.take_setup()}})
        watch = Stopwatch(None)
        made = (level.run(self.scene, self._inputs(level), watch), dict(watch.seconds))
        self._pay(watch.paid(stages.step_charge))
        with _kept_lock:
            kept[key] = made
            while len(kept) > _KEPT_PER_LEVEL:
                kept.popitem(last=False)
        return made

    def _inputs(self, level: Level) -> dict[str, Any]:
        return {before.name: self.made(before)[0] for before in level.after}

    def _pay(self, paid: Paid) -> None:
        for charge, steps in paid.items():
            mine = self.paid[charge]
            for step, value in steps.items():
                if value:
                    mine[step] = mine.get(step, 0.0) + value


def _copy(paid: Paid) -> Paid:
    return {charge: dict(steps) for charge, steps in paid.items()}


def _accounted(level: Level) -> tuple[Level, ...]:
    """The levels upstream of ``level`` whose seconds its entry holds besides its own steps.

    Those that no stored level upstream of it needs: a stored one's entry already holds the
    seconds of everything it needs (the recordings' and front end's are in the spike entry,
    and a result entry holds them through it).
    """
    upstream = level.upstream()
    covered = {each.name for s in upstream if s.stored for each in s.upstream()}
    return tuple(each for each in upstream if each.name not in covered)
