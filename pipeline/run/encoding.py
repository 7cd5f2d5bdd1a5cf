"""The spikes level's compute: every taxel of every recording encoded into TRUE and REAL spike
trains, and the trains measured (:data:`pipeline.run.stages.SPIKES`).

For each recording, its front-end-scaled signal becomes one signal per taxel
(:func:`pipeline.chain.taxels.recording_taxels`, step ``taxels``); each distinct taxel signal
gives a TRUE train, and a readout with named effects a REAL train per taxel (step ``readout``,
:mod:`pipeline.chain.readout`). The trains' metrics (step ``metrics``) are the pooled SSNR, the
mean STE, the event and data rates and the readout's resolution
(:mod:`pipeline.chain.metrics`). A scene that simulates chips encodes them too
(:func:`pipeline.run.chips.encode_chips`). Before all that, once per process and kind of readout,
the kernels are warmed up on a tiny signal (step ``setup``, :func:`warm_kernels`).
"""

from __future__ import annotations

import contextlib
import functools
from dataclasses import dataclass

import numpy as np

from pipeline import jit
from pipeline.chain import chips as chain_chips
from pipeline.chain.chips import ChipTrains
from pipeline.chain.frontend import FrontEnd
from pipeline.chain.metrics import (
    SpikeMetrics,
    data_rate_bps,
    equivalent_bits,
    event_rate_hz,
    pooled_ssnr_db,
    ste_per_train,
)
from pipeline.chain.readout_effects import real_train, true_trains
from pipeline.chain.spikes import Encoded, SpikeTrains
from pipeline.chain.taxels import recording_taxels, taxel_signals
from pipeline.design.scene import ArraySpec, Deployment, ReadoutSpec
from pipeline.recordings.sources import Recordings
from pipeline.run.chips import encode_chips
from pipeline.run.stopwatch import SETUP_STEP, Stopwatch

__all__ = ["Spikes", "encode_spikes", "encode_trains", "spike_metrics", "warm_kernels"]


@dataclass(frozen=True, eq=False)
class Spikes:
    """Output of the ``spikes`` level (its stored :class:`~pipeline.run.entries.SpikeEntry` has the
    same fields).

    Attributes
    ----------
    encoded : Encoded
        TRUE and REAL trains of every taxel of every recording; ``real is true`` for an ideal
        readout.
    metrics : SpikeMetrics
        Scene-level SSNR, STE, rates and resolution.
    chips : ChipTrains or None
        Every chip's REAL trains and metrics and the deployment's reference trains, for a scene
        that simulates chips (:attr:`pipeline.design.scene.ChipsSpec.simulated`); else None.
    """

    encoded: Encoded
    metrics: SpikeMetrics
    chips: ChipTrains | None = None


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
    fs = recordings.fs_hz
    true_per_taxel, real_per_taxel, durations = [], [], []
    for index, taxels in recording_taxels(recordings, front_end, array, watch.stage):
        with watch.stage("readout"):
            per_row = true_trains(taxels.signals, fs, readout)
            true = [per_row[row] for row in taxels.taxel_row]
            true_per_taxel.extend(true)
            durations.append((taxels.n_samples - 1) / fs)
            if readout.is_ideal:
                continue
            real_per_taxel.extend(
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
    n_taxels = len(true_per_taxel) // len(
        durations
    )  # the taxels read: a real array's or the grid's
    true_set = SpikeTrains.concatenate(true_per_taxel, n_taxels, np.asarray(durations))
    if readout.is_ideal:
        return Encoded(true_set, true_set)
    return Encoded(true_set, SpikeTrains.concatenate(real_per_taxel, n_taxels, true_set.duration_s))


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
    count: int | None,
    deployment: Deployment | None,
    watch: Stopwatch,
) -> Spikes:
    """Warm the kernels up (step ``setup``), encode every taxel of every recording, then measure
    the trains (step ``metrics``); for a scene that simulates chips (``count`` and
    ``deployment`` given), every chip and the deployment's reference too
    (:func:`pipeline.run.chips.encode_chips`)."""
    with watch.stage(SETUP_STEP):
        warm_kernels(readout)
    encoded = encode_trains(recordings, front_end, array, readout, seed, watch)
    with watch.stage("metrics"):
        metrics = spike_metrics(encoded, readout)
    encode = functools.partial(
        chain_chips.encode_chips,
        recordings,
        front_end,
        array,
        readout,
        seed,
        encoded=encoded,
        measure=functools.partial(spike_metrics, readout=readout),
        stage=watch.stage,
    )
    chips = encode_chips(count, deployment, encode)
    return Spikes(encoded, metrics, chips)


# A tiny signal (samples, Hz, cycles per second) to warm the kernels up on: a few crossings.
_WARM_SAMPLES, _WARM_FS_HZ, _WARM_HZ = 64, 1000.0, 25.0


def warm_kernels(readout: ReadoutSpec) -> None:
    """Run the kernels that a readout like ``readout`` calls (its encoder, the kernels of its
    effects, the spike metrics) once per process on a tiny signal, through the same functions
    and so with the same argument types as a point's encoding: loading or compiling them is
    paid here, once per process and kind of readout (encoder and named effects), and not inside
    the first point's ``readout`` and ``metrics`` steps. A warm-up that fails is given up
    (and not tried again): the point's own encoding reports any real problem."""
    kind = ("spikes", readout.encoder, tuple(sorted(str(effect) for effect in readout.effects)))
    jit.once(kind, functools.partial(_encode_tiny, readout))


def _encode_tiny(readout: ReadoutSpec) -> None:
    # Only a speed-up: whatever a tiny signal makes of this readout must not fail a point.
    with contextlib.suppress(Exception):
        _encode_tiny_signal(readout)


def _encode_tiny_signal(readout: ReadoutSpec) -> SpikeMetrics:
    t_s = np.arange(_WARM_SAMPLES) / _WARM_FS_HZ
    signal = 0.4 * readout.full_scale_v * np.sin(2 * np.pi * _WARM_HZ * t_s)
    taxels = taxel_signals(signal, _WARM_FS_HZ, np.zeros(1))
    duration = np.array([(taxels.n_samples - 1) / _WARM_FS_HZ])
    true = SpikeTrains.concatenate(true_trains(taxels.signals, _WARM_FS_HZ, readout), 1, duration)
    real = true
    if not readout.is_ideal:
        train = real_train(taxels.taxel(0), _WARM_FS_HZ, readout, seed=0, taxel=0, recording=0)
        real = SpikeTrains.concatenate([train], 1, duration)
    return spike_metrics(Encoded(true, real), readout)
