"""One scene end to end: recordings -> taxel signals -> spike trains -> frames -> accuracy.

:func:`run_scene` runs the levels of :data:`pipeline.run.stages.LEVELS` in order, in memory, and
times each stage (wall seconds, ``time.perf_counter``). Stages:

``load``       read or generate the recordings
``front_end``  fit one scaling for the whole dataset (:mod:`pipeline.chain.frontend`)
``setup``      import numba, torch, scikit-learn; load (or compile) the kernels: once a process
``taxels``     fractional-delay taxel signals of every recording
``readout``    TRUE and REAL spike trains (an ideal scene encodes once and reuses the train)
``metrics``    SSNR, STE, event and data rates
``coding``     rate-coded frames
``train_<m>``  stratified k-fold cross-validation of model ``m``
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pipeline.chain.frontend import FrontEnd
from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.spikes import Encoded
from pipeline.chain.training import CrossValidation
from pipeline.design.scene import DatasetSpec, Model, Scene
from pipeline.recordings.sources import Recordings
from pipeline.run import stages
from pipeline.run.encoding import encode_trains
from pipeline.run.fit import DatasetLimits, check_scene_fits
from pipeline.run.stages import LEVELS, RATES, RECORDINGS, RESULTS, SPIKES
from pipeline.run.stopwatch import Stopwatch

__all__ = [
    "SceneResult",
    "Stopwatch",
    "encode",
    "prepare",
    "run_scene",
    "stage_names",
]


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
    labels: np.ndarray | None = None
    """int64 ``(n_recordings,)``: class of each recording, for intervals of the accuracy."""


def stage_names(scene: Scene) -> tuple[str, ...]:
    """The stages :func:`run_scene` reports, in order."""
    return tuple(step for level in LEVELS for step in level.step_names(scene))


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
        The scene does not fit its recordings (:func:`pipeline.run.fit.check_scene_fits`): taxel
        delays that use up the shortest recording, windows that do not fit it, classes smaller
        than the folds. Checked right after loading, before any simulation.
    """
    watch = Stopwatch(on_stage)
    outputs: dict[str, Any] = {}
    for level in LEVELS:
        if level is SPIKES:
            # Before the long stages, and naming the recording: the taxel and coding stages
            # would only fail deep inside, on whichever recording came first.
            check_scene_fits(scene, DatasetLimits.of(outputs[RECORDINGS.name]))
        outputs[level.name] = level.run(scene, outputs, watch)
    recordings: Recordings = outputs[RECORDINGS.name]
    rates = outputs[RATES.name]
    return SceneResult(
        scene=scene,
        n_recordings=recordings.n_recordings,
        n_classes=recordings.n_classes,
        n_windows=rates.counts.shape[-1],
        dropped_spikes=int(rates.dropped.sum()),
        metrics=outputs[SPIKES.name].metrics,
        accuracy=outputs[RESULTS.name],
        timings_s=_paid_by_stage(watch, stage_names(scene)),
        labels=recordings.labels,
    )


def _paid_by_stage(watch: Stopwatch, names: tuple[str, ...]) -> dict[str, float]:
    """The wall seconds of every stage, in order: its work, and under ``setup`` every one-off
    second (an import, a kernel load or compile), wherever it happened (they sum to the run's
    time in its stages)."""
    paid = watch.paid_total()
    return {name: paid.get(name, 0.0) for name in names}


# -- single stages on a whole scene, for callers that time one of them (the benchmarks) ---------


def prepare(
    dataset: DatasetSpec, full_scale_v: float, *, stopwatch: Stopwatch | None = None
) -> tuple[Recordings, FrontEnd]:
    """Load the recordings and fit their front end to ``full_scale_v``."""
    watch = stopwatch or Stopwatch(None)
    recordings = stages.load(dataset=dataset, watch=watch)
    return recordings, stages.fit(recordings=recordings, full_scale_v=full_scale_v, watch=watch)


def encode(
    recordings: Recordings,
    front_end: FrontEnd,
    scene: Scene,
    *,
    stopwatch: Stopwatch | None = None,
) -> Encoded:
    """TRUE and REAL spike trains of every taxel of every recording of ``scene``."""
    watch = stopwatch or Stopwatch(None)
    return encode_trains(recordings, front_end, scene.array, scene.readout, scene.seed, watch)
