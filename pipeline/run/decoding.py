"""The decoding levels of a scene: its spike trains coded as its decoders read them, and every
model it trains cross-validated on them.

``rates`` (:func:`code_rates`) rate-codes the REAL trains in ``coding.window_s`` windows
(:func:`rate_frames`) and codes them as well in every other way the scene's decoders read them
(:class:`pipeline.chain.decoders.Reads`: per step of ``training.snn.step_s``, ON and OFF apart,
for the ``snn``), over the same span, for the scene's chip and, for a scene of chips, every
chip and the deployment's reference. ``results`` (:func:`classify`) cross-validates every model
``training`` names on what its decoder reads (:func:`pipeline.chain.deployment.validate_input`).
The registry, :mod:`pipeline.run.stages`, declares both levels; neither asks which model it
handles: the decoder registry (:mod:`pipeline.chain.decoders`) answers.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from pipeline import jit
from pipeline.chain.chips import ChipTrains
from pipeline.chain.coding import resolve_n_windows
from pipeline.chain.decoders import DecoderInput, Reads, decoder_of, reads_of
from pipeline.chain.spikes import SpikeTrains
from pipeline.design.scene import CodingSpec, Model, Scene, SNNSpec, TrainingSpec
from pipeline.recordings.sources import Recordings
from pipeline.run.encoding import Spikes
from pipeline.run.stopwatch import Stopwatch

if TYPE_CHECKING:
    from pipeline.chain.training import CrossValidation

__all__ = ["Rates", "classify", "code_rates", "rate_frames", "reads_steps"]


@dataclass(frozen=True, eq=False)
class Rates:
    """Output of the ``rates`` level, kept in memory by the workers (not in the store).

    Attributes
    ----------
    inputs : Mapping[Reads, DecoderInput]
        What the scene's decoders read, by kind (:class:`~pipeline.chain.decoders.Reads`):
        always the windows, and every other kind a decoder of the scene reads; each with every
        chip's and the reference's for a scene of chips.
    dropped : int64
        REAL spikes outside every window, shape ``(n_recordings, n_taxels)``.
    labels : int64
        Class index of each recording, into ``class_names``, shape ``(n_recordings,)``.
    class_names : tuple[str, ...]
        Class names.
    """

    inputs: Mapping[Reads, DecoderInput]
    dropped: np.ndarray
    labels: np.ndarray
    class_names: tuple[str, ...]

    @property
    def counts(self) -> np.ndarray:
        """int64 ``(n_recordings, channels, n_taxels, n_windows)``: REAL spikes per window."""
        return self.inputs[Reads.WINDOWS].frames


def rate_frames(real: SpikeTrains, coding: CodingSpec) -> tuple[np.ndarray, np.ndarray]:
    """Rate-coded frames of the REAL trains: ``counts`` int64 (n_rec, C, taxels, windows), and
    ``dropped`` int64 (n_rec, taxels); the number of windows is resolved for these recordings."""
    n_windows = resolve_n_windows(coding, real.duration_s)
    return Reads.WINDOWS.code(real, coding, None, n_windows)


def reads_steps(scene: Scene) -> bool:
    """Whether a decoder of ``scene`` reads step counts (then the ``rates`` level reads, and
    keys, ``training.snn``)."""
    return Reads.STEPS in reads_of(scene.training.models)


def code_rates(
    *,
    spikes: Spikes,
    recordings: Recordings,
    coding: CodingSpec,
    snn: SNNSpec | None,
    watch: Stopwatch,
) -> Rates:
    """Code the REAL trains (step ``coding``) as the scene's decoders read them, labelled by the
    recordings' classes: in windows, and per step of ``snn.step_s`` when a decoder reads steps
    (``snn`` is given to such scenes only, :func:`reads_steps`), over the windows' span.

    ``spikes`` is the ``spikes`` level's output (its ``encoded`` trains and, for a scene of
    chips, its ``chips``).
    """
    with watch.stage("coding"):
        real = spikes.encoded.real
        n_windows = resolve_n_windows(coding, real.duration_s)
        read = [reads for reads in Reads if reads.column_s(coding, snn) is not None]
        coded = {reads: reads.code(real, coding, snn, n_windows) for reads in read}
        inputs = {
            reads: DecoderInput(
                frames,
                reads.column_s(coding, snn),
                *_chip_frames(reads, spikes.chips, coding, snn, n_windows),
            )
            for reads, (frames, _) in coded.items()
        }
    dropped = coded[Reads.WINDOWS][1]
    return Rates(inputs, dropped, recordings.labels, recordings.class_names)


def _chip_frames(
    reads: Reads, chips: ChipTrains | None, coding: CodingSpec, snn: SNNSpec | None, n_windows: int
) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Every chip's frames ``(n_chips, n_recordings, C, taxels, columns)`` and the reference's
    (:class:`~pipeline.chain.chips.ChipTrains`); None for a scene of one chip (``chips`` None)
    and for the reference of a ``per_chip`` deployment."""
    if chips is None:
        return None, None
    tested = reads.code(chips.real, coding, snn, n_windows)[0]
    tested = tested.reshape(chips.n_chips, -1, *tested.shape[1:])
    if chips.reference is None:
        return tested, None
    return tested, reads.code(chips.reference, coding, snn, n_windows)[0]


def classify(
    *, rates: Rates, training: TrainingSpec, watch: Stopwatch
) -> dict[Model, CrossValidation]:
    """Cross-validate every model ``training`` names (steps ``train_<m>``) on what its decoder
    reads: a :class:`~pipeline.chain.training.CrossValidation` per model."""
    accuracy = {}
    for model in training.models:
        with watch.stage(f"train_{model.value}"):
            with jit.one_off():  # torch and scikit-learn: once per process
                from pipeline.chain.deployment import validate_input
            accuracy[model] = validate_input(
                rates.inputs[decoder_of(model).reads],
                rates.labels,
                model,
                training,
                class_names=rates.class_names,
            )
    return accuracy
