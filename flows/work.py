"""Work that runs on Dask workers: plain functions, no Prefect.

Each function opens the run's store, computes only the entries that are missing, and writes each
entry complete (storage marks it complete only after its data is written). Work is keyed by the
stage cache keys, so two points that share a spike train (a window sweep at one threshold) reuse
it, and a worker that dies mid-task leaves nothing a later run trusts.

Torch runs one intra-op thread per worker: Dask already runs one task per worker thread, and
oversubscribing two cores made training 37x slower. The C allocator keeps training's tensors on
the heap (:func:`flows.environment.tune_allocator`), whatever the nanny set.
"""

from __future__ import annotations

import functools
import json
from typing import TYPE_CHECKING, Any

from flows.environment import tune_allocator
from pipeline.scene import Scene, cache_key
from storage import EntryKind, RateEntry, ResultEntry, SpikeEntry, SweepStore

if TYPE_CHECKING:
    from pipeline.frontend import FrontEnd
    from pipeline.recordings import Recordings

# pipeline.simulate (torch, scikit-learn) is imported inside the functions: the coordinator
# imports this module only to name the functions it submits, and never trains anything.


@functools.lru_cache(maxsize=4)
def _prepared(
    dataset_json: str, full_scale_v: float
) -> tuple[Recordings, FrontEnd, dict[str, float]]:
    """Recordings and front end of a dataset, kept per worker process (they are immutable)."""
    from pipeline.simulate import Stopwatch, prepare

    dataset = Scene.from_dict({"dataset": json.loads(dataset_json)}).dataset
    watch = Stopwatch(None)
    recordings, front_end = prepare(dataset, full_scale_v, stopwatch=watch)
    return recordings, front_end, watch.seconds


def _recordings(scene: Scene) -> tuple[Recordings, FrontEnd, dict[str, float]]:
    """Recordings keyed by exactly what they depend on: the dataset and the full scale."""
    dataset_json = json.dumps(scene.to_dict()["dataset"], sort_keys=True)
    return _prepared(dataset_json, scene.readout.full_scale_v)


def compute_spikes(root: str, scene_data: dict[str, Any]) -> str:
    """Encode the TRUE and REAL trains of a scene unless the store has them; return the key."""
    scene = Scene.from_dict(scene_data)
    store = SweepStore.open(root)
    key = cache_key(scene, "spikes")
    if store.has(EntryKind.SPIKES, key):
        return key
    from pipeline.simulate import Stopwatch, encode, spike_metrics

    recordings, front_end, seconds = _recordings(scene)
    watch = Stopwatch(None)
    watch.seconds.update(seconds)
    encoded = encode(recordings, front_end, scene, stopwatch=watch)
    with watch.stage("metrics"):
        metrics = spike_metrics(encoded, scene)
    store.write_spikes(key, SpikeEntry(encoded, metrics, dict(watch.seconds)))
    return key


def compute_point(root: str, scene_data: dict[str, Any], *after: Any) -> str:
    """Rate-code and cross-validate one point unless the store has it; return its result key.

    ``after`` carries the futures this point waits for (its spike trains); their values are
    not used. The result entry holds everything a cube needs of the point: fold accuracies,
    spike metrics and the seconds of every stage (as measured when each was computed).
    """
    import torch

    from pipeline.simulate import Stopwatch, classify, rate_frames

    torch.set_num_threads(1)
    tune_allocator()
    scene = Scene.from_dict(scene_data)
    store = SweepStore.open(root)
    result_key = cache_key(scene, "results")
    if store.has(EntryKind.RESULTS, result_key):
        return result_key
    spikes_key = cache_key(scene, "spikes")
    spikes = store.read_valid(EntryKind.SPIKES, spikes_key)
    if spikes is None:
        compute_spikes(root, scene_data)
        spikes = store.read_spikes(spikes_key)
    rates_key = cache_key(scene, "rates")
    rates = store.read_valid(EntryKind.RATES, rates_key)
    if rates is None:
        recordings, _, _ = _recordings(scene)
        watch = Stopwatch(None)
        with watch.stage("coding"):
            counts, dropped = rate_frames(spikes.encoded.real, scene)
        rates = RateEntry(
            counts, dropped, recordings.labels, recordings.class_names, dict(watch.seconds)
        )
        store.write_rates(rates_key, rates)
    watch = Stopwatch(None)
    accuracy = classify(rates.counts, rates.labels, scene, rates.class_names, stopwatch=watch)
    store.write_result(
        result_key,
        ResultEntry(
            fold_accuracy={m.value: cv.fold_accuracy for m, cv in accuracy.items()},
            seconds={**spikes.seconds, **rates.seconds, **watch.seconds},
            metrics=spikes.metrics,
        ),
    )
    return result_key
