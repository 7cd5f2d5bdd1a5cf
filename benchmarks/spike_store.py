"""Spike trains in the sweep store: bytes per event and read-back seconds, against the old layout.

One scene's spike entry (TRUE, REAL and, with chips, every chip's REAL trains) is written twice
in this process: as the store keeps it now (:mod:`storage.codec`: whole microsecond ticks,
delta-coded per train with the polarity in the low bit, one ``uint32`` per event, Blosc zstd
over byte-shuffled values) and as layout 2 kept it (``float64`` seconds and ``int8`` polarity,
Zarr's default zstd at level 0), both through :func:`storage.batches.write_batch`. Rows:

- bytes per stored event (the event arrays' files over the events), now, beside then; target
  at most 2. The detail gives the zero-order entropy of the folded deltas (bits per event / 8),
  the least any coder of one value at a time reaches, and the whole batch's bytes per event;
- seconds to read the entry back whole (:func:`storage.batches.read_batch`, its checksums, and
  for the new layout the decoding into float64 times), then against now, medians interleaved;
  target at least 1 (now as fast as then).

The scene: the paper's operating point with threshold mismatch (``sigma_rel`` 0.5) on 20 chips
shared, as a chip study stores them. ``run(tiny=True)``: the ``smoke`` scene, one chip, one
timing of each.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path
from unittest import mock

import numpy as np

from benchmarks.timing import median_seconds
from pipeline.design.scene import Scene
from pipeline.run.entries import SpikeEntry
from pipeline.run.records import StepSeconds
from pipeline.run.stages import FRONT_END, RECORDINGS, SPIKES, step_charge
from pipeline.run.stopwatch import Stopwatch
from storage import batches
from storage.batches import BatchEntry, read_batch, write_batch
from storage.codec import from_record, to_record

KEY = "0" * 32
CHIPS = 20


def scene(tiny: bool) -> Scene:
    if tiny:
        return Scene.builtin("smoke")
    return Scene.builtin("paper").replace(
        **{
            "readout.effects": {"threshold_mismatch": {"sigma_rel": 0.5}},
            "chips.count": CHIPS,
            "chips.deployment": "shared",
        }
    )


def spike_entry(point: Scene) -> SpikeEntry:
    """The spike entry of ``point``, computed through the stage registry."""
    watch = Stopwatch(None)
    outputs: dict = {}
    for level in (RECORDINGS, FRONT_END, SPIKES):
        outputs[level.name] = level.run(point, outputs, watch)
    seconds = StepSeconds(dict(watch.seconds), watch.paid(step_charge), KEY)
    return SPIKES.record.make(outputs[SPIKES.name], seconds, outputs.get)


def old_record(entry: SpikeEntry) -> BatchEntry:
    """The entry as layout 2 kept it: every declared variable as its dtype, times in seconds."""
    values, attrs = SPIKES.record.encode(entry)
    declared = {v.name: v for v in SPIKES.record.variables}
    return BatchEntry(
        KEY,
        {
            name: (declared[name].dims, np.asarray(value, declared[name].dtype), {})
            for name, value in values.items()
        },
        dict(attrs),
    )


def event_bytes(batch: Path) -> int:
    """Bytes of the files of a batch's event arrays (``*_times_s``, ``*_polarity``)."""
    return sum(
        f.stat().st_size
        for folder in batch.iterdir()
        if folder.name.endswith(("_times_s", "_polarity"))
        for f in folder.rglob("*")
        if f.is_file()
    )


def all_bytes(batch: Path) -> int:
    return sum(f.stat().st_size for f in batch.rglob("*") if f.is_file())


def entropy_bytes(record: BatchEntry) -> float:
    """Zero-order entropy of the stored folded deltas, bytes per event."""
    folded = np.concatenate(
        [values for name, (_, values, _) in record.variables.items() if name.endswith("_times_s")]
    )
    _, counts = np.unique(folded, return_counts=True)
    p = counts / counts.sum()
    return float(-(p * np.log2(p)).sum() / 8)


def run(repeat: int = 5, tiny: bool = False) -> list[dict]:
    entry = spike_entry(scene(tiny))
    new = to_record(SPIKES.record, KEY, entry)
    old = old_record(entry)
    events = sum(
        values.size for name, (_, values, _) in old.variables.items() if name.endswith("_times_s")
    )
    with tempfile.TemporaryDirectory(prefix="eskin-bench-spikes-") as name:
        new_path, old_path = Path(name) / "new", Path(name) / "old"
        write_batch(new_path, "spikes", [new])
        with mock.patch.object(batches, "_compressors", lambda values: {}):  # Zarr's default
            write_batch(old_path, "spikes", [old])
        new_bytes, old_bytes = event_bytes(new_path) / events, event_bytes(old_path) / events
        new_all, old_all = all_bytes(new_path) / events, all_bytes(old_path) / events

        def read_new() -> None:
            from_record(SPIKES.record, read_batch(new_path, "spikes")[0])

        def read_old() -> None:
            read_batch(old_path, "spikes")

        old_s, new_s = median_seconds(
            read_old, read_new, repeat=1 if tiny else repeat, warm_up=not tiny
        )
    entropy = entropy_bytes(new)
    size = f"{events:,} events ({'smoke' if tiny else f'paper, {CHIPS} chips shared'})"
    return [
        {
            "benchmark": "spike store: bytes per stored event",
            "ratio": new_bytes,
            "target": "<= 2 bytes per event",
            "detail": (
                f"{size}: {new_bytes:.3f} B now (1 us ticks, entropy of the folded deltas "
                f"{entropy:.3f} B), {old_bytes:.3f} B in layout 2; whole batch "
                f"{new_all:.3f} B against {old_all:.3f} B"
            ),
        },
        {
            "benchmark": "spike store: reading an entry back, layout 2 / now",
            "ratio": old_s / new_s if new_s > 0 else math.inf,
            "target": ">= 1",
            "detail": f"{size}: {new_s:.3f} s now, {old_s:.3f} s in layout 2 (medians)",
        },
    ]


if __name__ == "__main__":
    for row in run():
        print(row)
