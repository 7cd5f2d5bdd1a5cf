r"""Chips as a population: the REAL trains of ``chips.count`` chips built from one design.

A design is built into many chips. Each chip ``k = 0 .. N-1`` draws every *fixed* random effect
of the readout (:data:`pipeline.design.effects.FIXED_EFFECTS`: amplifier and comparator offsets,
threshold mismatch) once, from the scene seed and ``k``
(:func:`pipeline.chain.readout_effects.effect_rng` with ``chip=k``); per-sample noise belongs to the
recording and is the same on every chip. Chip 0 is the chip a scene of one chip simulates, draw
for draw.

Common random numbers: chip ``k`` draws standard normals ``z`` from a stream that depends on the
seed, ``k``, the effect and the taxel only, and scales them by the design's sigma
(``theta_k = theta * (1 + sigma_rel * z)``), so chip ``k`` of any two designs holds the same
``z``: a comparison between designs is paired, chip by chip.

Besides the tested chips, a deployment of one classifier trains it on a *reference* encoding of
the recordings (:mod:`pipeline.chain.deployment`):

``shared``
    the nominal chip: no fixed effect at all (every one exactly 0), noise kept. The classifier
    is what a designer trains on the design as drawn, before any chip exists; it is none of the
    tested chips, so no chip is favoured by having been trained on (chip 0 would be tested on
    its own fixed pattern) and the reference is the same whatever ``N`` and, for a readout whose
    only fixed effect is the mismatch, whatever its sigma: designs differ in their chips alone.
``robust``
    one *training chip* per recording: recording ``r`` is encoded by chip ``r`` of a pool drawn
    apart from the tested chips (``pool=1``), so the classifier sees as many distinct chips as
    it has training recordings (108 at the paper point), none of them tested, and learns what
    does not change from chip to chip. One chip per recording keeps the training set, and so the
    training time, that of one chip (:data:`ROBUST_CHIPS_PER_RECORDING`).

Layout: the tested chips' REAL trains are one :class:`~pipeline.chain.spikes.SpikeTrains` whose
rows are ``(chip, recording)`` pairs, chip-major (row ``k * n_recordings + r``), with each
recording's duration repeated per chip, so they are stored and rate-coded as any other trains.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from contextlib import AbstractContextManager
from dataclasses import dataclass

import numpy as np

from pipeline.chain.frontend import FrontEnd
from pipeline.chain.metrics import SpikeMetrics
from pipeline.chain.readout_effects import real_train
from pipeline.chain.spikes import Encoded, SpikeTrains
from pipeline.chain.taxels import recording_taxels
from pipeline.design.scene import ArraySpec, Deployment, ReadoutSpec
from pipeline.recordings.recording_set import Recordings

__all__ = ["ROBUST_CHIPS_PER_RECORDING", "ChipTrains", "encode_chips", "stack_chips"]

#: Training chips per training recording of a ``robust`` deployment (see the module docstring).
ROBUST_CHIPS_PER_RECORDING = 1
#: The chip pool of a ``robust`` deployment's training chips (pool 0 is the tested chips).
ROBUST_POOL = 1


@dataclass(frozen=True, eq=False)
class ChipTrains:
    """The REAL trains of every chip of a design and the reference its classifier trains on.

    Attributes
    ----------
    real : SpikeTrains
        ``N * n_recordings`` rows, chip-major (row ``k * n_recordings + r``), ``duration_s``
        repeated per chip.
    metrics : tuple of SpikeMetrics
        Each chip's spike metrics against the TRUE trains, chip by chip: one per chip, so their
        number is the chip count ``N`` (:attr:`n_chips`).
    reference : SpikeTrains or None
        ``(n_recordings, taxels)`` REAL trains the classifier of a ``shared`` (nominal chip) or
        ``robust`` (training chips) deployment trains on; None for ``per_chip``.
    """

    real: SpikeTrains
    metrics: tuple[SpikeMetrics, ...]
    reference: SpikeTrains | None = None

    @property
    def n_chips(self) -> int:
        """``N``, the number of chips."""
        return len(self.metrics)

    @property
    def n_recordings(self) -> int:
        """Recordings per chip."""
        return self.real.n_recordings // self.n_chips

    def chip(self, k: int) -> SpikeTrains:
        """The ``(n_recordings, taxels)`` REAL trains of chip ``k`` (views)."""
        n = self.n_recordings
        count = self.real.count[k * n : (k + 1) * n]
        first = int(self.real.start[k * n, 0]) if count.size else 0
        last = first + int(count.sum())
        return SpikeTrains(
            self.real.times_s[first:last],
            self.real.polarity[first:last],
            count,
            self.real.duration_s[k * n : (k + 1) * n],
        )


def stack_chips(chips: list[SpikeTrains]) -> SpikeTrains:
    """The trains of several chips (each ``(n_recordings, taxels)``) as one chip-major set."""
    return SpikeTrains(
        np.concatenate([c.times_s for c in chips]),
        np.concatenate([c.polarity for c in chips]),
        np.concatenate([c.count for c in chips]),
        np.concatenate([c.duration_s for c in chips]),
    )


def encode_chips(
    recordings: Recordings,
    front_end: FrontEnd,
    array: ArraySpec,
    readout: ReadoutSpec,
    seed: int | None,
    count: int,
    deployment: Deployment,
    encoded: Encoded,
    measure: Callable[[Encoded], SpikeMetrics],
    stage: Callable[[str], AbstractContextManager[object]],
) -> ChipTrains:
    """Encode chips ``1 .. count-1`` (chip 0 is ``encoded.real``) and the deployment's reference.

    Parameters
    ----------
    recordings, front_end, array, readout, seed
        As for the scene's own encoding (:func:`pipeline.run.encoding.encode_trains`).
    count, deployment
        ``chips.count`` and ``chips.deployment``.
    encoded
        The scene's TRUE trains and chip 0's REAL trains.
    measure
        The spike metrics of TRUE and REAL trains (:func:`pipeline.run.encoding.spike_metrics`).
    stage
        ``stage(step)`` a context manager timing ``step`` (``taxels``, ``readout``, ``metrics``).

    The recordings and taxels are walked as the scene's own encoding walks them
    (:func:`pipeline.chain.taxels.recording_taxels`).
    """
    fs = recordings.fs_hz
    n_taxels = encoded.true.n_taxels  # the taxels read: a real array's or the grid's
    per_chip: list[list[tuple[np.ndarray, np.ndarray]]] = [[] for _ in range(count - 1)]
    reference: list[tuple[np.ndarray, np.ndarray]] = []
    for index, taxels in recording_taxels(recordings, front_end, array, stage):
        with stage("readout"):
            rows = [taxels.taxel(taxel) for taxel in range(n_taxels)]
            chip = functools.partial(_chip_trains, rows, fs, readout, seed, index)
            for k in range(1, count):
                per_chip[k - 1].extend(chip(k))
            if deployment is Deployment.SHARED:
                reference.extend(chip(None))
            elif deployment is Deployment.ROBUST:
                reference.extend(chip(index, ROBUST_POOL))
    duration = encoded.true.duration_s
    with stage("readout"):
        chips = [encoded.real] + [
            SpikeTrains.concatenate(trains, n_taxels, duration) for trains in per_chip
        ]
        ref = SpikeTrains.concatenate(reference, n_taxels, duration) if reference else None
    with stage("metrics"):
        metrics = tuple(measure(Encoded(encoded.true, chip)) for chip in chips)
    return ChipTrains(stack_chips(chips), metrics, ref)


def _chip_trains(rows, fs_hz, readout, seed, recording, chip, pool=0):
    """The REAL trains of every taxel (signals ``rows``) of one recording on one chip."""
    return [
        real_train(v, fs_hz, readout, seed=seed, taxel=t, recording=recording, chip=chip, pool=pool)
        for t, v in enumerate(rows)
    ]
