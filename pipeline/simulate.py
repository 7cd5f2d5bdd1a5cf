"""One scene end to end: recordings -> taxel signals -> spike trains -> frames -> accuracy.

Each arrow is a pure function of another module; this module only composes them and times each
stage (wall seconds, ``time.perf_counter``). Stages:

``load``       read or generate the recordings
``front_end``  fit the dataset-level scaling (section 4.1)
``taxels``     fractional-delay taxel signals of every recording
``readout``    TRUE and REAL spike trains (an ideal scene encodes once and reuses the train)
``metrics``    SSNR, STE, event and data rates
``coding``     rate-coded frames
``train_<m>``  stratified k-fold cross-validation of model ``m``
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from pipeline.coding import frames, resolve_n_windows
from pipeline.frontend import FrontEnd, fit_front_end
from pipeline.grid import DatasetFacts, check_scene_fits
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
from pipeline.scene import DatasetSpec, Model, Scene
from pipeline.spikes import Encoded, SpikeTrains
from pipeline.taxels import taxel_delays_s, taxel_signals
from pipeline.training import CrossValidation, cross_validate


@dataclass(frozen=True, eq=False)
class SceneResult:
    """Everything ``eskin run`` reports for one scene."""

    scene: Scene
    n_recordings: int
    n_classes: int
    n_windows: int
    dropped_spikes: int
    metrics: SpikeMetrics
    accuracy: dict[Model, CrossValidation]
    timings_s: dict[str, float] = field(default_factory=dict)


class Stopwatch:
    """Accumulates wall seconds per stage and reports each stage the first time it starts."""

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


def stage_names(scene: Scene) -> tuple[str, ...]:
    """The stages :func:`run_scene` reports, in order."""
    trained = tuple(f"train_{m.value}" for m in scene.training.models)
    return ("load", "front_end", "taxels", "readout", "metrics", "coding", *trained)


def encode(
    recordings: Recordings,
    front_end: FrontEnd,
    scene: Scene,
    *,
    stopwatch: Stopwatch | None = None,
) -> Encoded:
    """TRUE and REAL spike trains of every taxel of every recording.

    Taxels that see the same signal share one TRUE train; an ideal readout returns the TRUE
    trains as the REAL ones without encoding again.
    """
    watch = stopwatch or Stopwatch(None)
    delays = taxel_delays_s(scene.array)
    fs = recordings.fs_hz
    theta = scene.readout.threshold_v
    true_trains, real_trains, durations = [], [], []
    for index, signal in enumerate(recordings.signals):
        with watch.stage("taxels"):
            array = taxel_signals(front_end.apply(signal), fs, delays)
        with watch.stage("readout"):
            per_row = [level_crossings(row, fs, theta) for row in array.signals]
            true = [per_row[row] for row in array.taxel_row]
            true_trains.extend(true)
            durations.append((array.n_samples - 1) / fs)
            if scene.readout.is_ideal:
                continue
            real_trains.extend(
                real_train(
                    array.taxel(taxel),
                    fs,
                    scene.readout,
                    seed=scene.seed,
                    taxel=taxel,
                    recording=index,
                )
                for taxel in range(array.n_taxels)
            )
    n_taxels = scene.array.n_taxels
    true_set = SpikeTrains.concatenate(true_trains, n_taxels, np.asarray(durations))
    if scene.readout.is_ideal:
        return Encoded(true_set, true_set)
    return Encoded(true_set, SpikeTrains.concatenate(real_trains, n_taxels, true_set.duration_s))


def spike_metrics(encoded: Encoded, scene: Scene) -> SpikeMetrics:
    """Scene-level SSNR (pooled), STE (mean over trains), rates and resolution."""
    return SpikeMetrics(
        ssnr_db=pooled_ssnr_db(encoded.true.count, encoded.real.count),
        ste_s2=float(ste_per_train(encoded.true, encoded.real, "paper").mean()),
        ste_sign_safe_s2=float(ste_per_train(encoded.true, encoded.real, "sign_safe").mean()),
        event_rate_hz=event_rate_hz(encoded.real),
        data_rate_bps=data_rate_bps(encoded.real),
        equivalent_bits=equivalent_bits(scene.readout.full_scale_v, scene.readout.threshold_v),
    )


def rate_frames(real: SpikeTrains, scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """Rate-coded frames of the REAL trains: ``counts`` int64 (n_rec, C, taxels, windows), and
    ``dropped`` int64 (n_rec, taxels); the number of windows is resolved for these recordings."""
    n_windows = resolve_n_windows(scene.coding, real.duration_s)
    return frames(real, scene.coding.window_s, n_windows, scene.coding.polarity)


def classify(
    counts: np.ndarray,
    labels: np.ndarray,
    scene: Scene,
    class_names: tuple[str, ...],
    *,
    stopwatch: Stopwatch | None = None,
) -> dict[Model, CrossValidation]:
    """Cross-validate every model the scene names on the same frames."""
    watch = stopwatch or Stopwatch(None)
    accuracy = {}
    for model in scene.training.models:
        with watch.stage(f"train_{model.value}"):
            accuracy[model] = cross_validate(
                counts, labels, model, scene.training, class_names=class_names
            )
    return accuracy


def prepare(
    dataset: DatasetSpec, full_scale_v: float, *, stopwatch: Stopwatch | None = None
) -> tuple[Recordings, FrontEnd]:
    """Load the recordings and fit their front end to ``full_scale_v``."""
    watch = stopwatch or Stopwatch(None)
    with watch.stage("load"):
        recordings = load_recordings(dataset)
    with watch.stage("front_end"):
        front_end = fit_front_end(recordings, full_scale_v)
    return recordings, front_end


def run_scene(
    scene: Scene,
    *,
    on_stage: Callable[[str], None] | None = None,
) -> SceneResult:
    """Simulate and classify one scene.

    Parameters
    ----------
    scene : Scene
        What to simulate.
    on_stage : callable, optional
        Called with each stage name (:func:`stage_names`) as it starts, for progress display.

    Raises
    ------
    SceneError
        The scene does not fit its recordings (:func:`pipeline.grid.check_scene_fits`): taxel
        delays that use up the shortest recording, windows that do not fit it, classes smaller
        than the folds. Checked right after loading, before any simulation.
    """
    watch = Stopwatch(on_stage)
    recordings, front_end = prepare(scene.dataset, scene.readout.full_scale_v, stopwatch=watch)
    # Before the long stages, and naming the recording: the taxel and coding stages would only
    # fail deep inside, on whichever recording came first.
    check_scene_fits(scene, DatasetFacts.of(recordings))
    encoded = encode(recordings, front_end, scene, stopwatch=watch)
    with watch.stage("metrics"):
        metrics = spike_metrics(encoded, scene)
    with watch.stage("coding"):
        counts, dropped = rate_frames(encoded.real, scene)
    accuracy = classify(counts, recordings.labels, scene, recordings.class_names, stopwatch=watch)
    return SceneResult(
        scene=scene,
        n_recordings=recordings.n_recordings,
        n_classes=recordings.n_classes,
        n_windows=counts.shape[-1],
        dropped_spikes=int(dropped.sum()),
        metrics=metrics,
        accuracy=accuracy,
        timings_s=watch.seconds,
    )
