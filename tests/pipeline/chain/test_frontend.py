"""Tests of pipeline.chain.frontend: one scaling per dataset, from recording units to volts."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.chain.frontend import FrontEnd, fit_front_end, streaming_percentile
from pipeline.recordings.sources import Recordings


def make(signals, name="t") -> Recordings:
    signals = [np.asarray(s, dtype=np.float64) for s in signals]
    return Recordings(
        signals=tuple(signals),
        labels=np.arange(len(signals)) % 2,
        class_names=("a", "b"),
        fs_hz=100.0,
        names=tuple(f"r{i}" for i in range(len(signals))),
        units="N",
        name=name,
    )


def test_apply_is_gain_times_deviation():
    front = FrontEnd(offset=2.0, gain_v_per_unit=0.5)
    out = front.apply(np.array([2.0, 4.0, 0.0], dtype=np.float32))
    assert out.dtype == np.float64
    np.testing.assert_array_equal(out, [0.0, 1.0, -1.0])
    np.testing.assert_array_equal(front.apply(np.zeros((2, 3))), np.full((2, 3), -1.0))


def test_99_9th_percentile_maps_to_half_full_scale():
    rng = np.random.default_rng(0)
    rec = make([rng.normal(3.0, 2.0, size=n) for n in (1000, 2500, 700, 1800)])
    front = fit_front_end(rec, full_scale_v=1.0)
    samples = np.concatenate(rec.signals)
    assert front.offset == pytest.approx(samples.mean(), rel=1e-15)
    volts = front.apply(samples)
    assert np.percentile(np.abs(volts), 99.9) == pytest.approx(0.5, rel=1e-12)
    assert np.abs(volts).max() > 0.5  # not clipped here: saturation is a readout effect
    assert np.mean(np.abs(volts) > 0.5) == pytest.approx(0.001, abs=2e-4)
    doubled = fit_front_end(rec, full_scale_v=2.0)
    assert doubled.gain_v_per_unit == pytest.approx(2 * front.gain_v_per_unit, rel=1e-15)


def test_offset_is_the_dataset_mean_so_amplitude_and_level_differences_survive():
    t = np.linspace(0, 1, 400, endpoint=False)
    quiet = 10.0 + 0.1 * np.sin(2 * np.pi * 5 * t)
    loud = 10.0 + 1.0 * np.sin(2 * np.pi * 5 * t)
    shifted = 12.0 + 0.1 * np.sin(2 * np.pi * 5 * t)
    rec = make([quiet, loud, shifted])
    front = fit_front_end(rec, 1.0)
    # sample-weighted mean over all recordings, not per recording
    assert front.offset == pytest.approx((10.0 + 10.0 + 12.0) / 3, rel=1e-12)
    q, l_, s = (front.apply(x) for x in rec.signals)
    assert np.ptp(l_) == pytest.approx(10 * np.ptp(q), rel=1e-9)
    assert s.mean() - q.mean() == pytest.approx(2.0 * front.gain_v_per_unit, rel=1e-9)


def test_longer_recordings_weigh_more_in_the_mean():
    rec = make([np.zeros(300), np.full(100, 4.0)])
    assert fit_front_end(rec, 1.0).offset == 1.0


@pytest.mark.parametrize("value", [0.0, 0.1, -3.7, 1e300])
def test_constant_dataset_gets_unit_gain_and_zero_volts(value):
    rec = make([np.full(97, value), np.full(31, value)])
    front = fit_front_end(rec, 1.0)
    assert front.gain_v_per_unit == 1.0
    assert front.offset == value
    for signal in rec.signals:
        volts = front.apply(signal)
        assert np.isfinite(volts).all()
        np.testing.assert_array_equal(volts, 0.0)


def test_mostly_flat_dataset_uses_the_largest_deviation():
    signal = np.zeros(10_000)
    signal[:3], signal[3:6] = 1.0, -1.0  # 0.06 % of the samples off the (exact) mean 0
    front = fit_front_end(make([signal, np.zeros(10)]), 1.0)
    assert front.offset == 0.0
    assert front.gain_v_per_unit == 0.5


@pytest.mark.parametrize("full_scale", [0.0, -1.0, float("inf"), float("nan")])
def test_invalid_full_scale(full_scale):
    with pytest.raises(ValueError, match="full_scale_v"):
        fit_front_end(make([np.arange(3.0), np.arange(4.0)]), full_scale)


def test_front_end_rejects_invalid_parameters():
    with pytest.raises(ValueError):
        FrontEnd(offset=0.0, gain_v_per_unit=0.0)
    with pytest.raises(ValueError):
        FrontEnd(offset=float("nan"), gain_v_per_unit=1.0)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    scale=st.floats(1e-6, 1e6),
    shift=st.floats(-1e3, 1e3),
)
def test_scaling_the_raw_data_leaves_the_volts_unchanged(seed, scale, shift):
    rng = np.random.default_rng(seed)
    raw = [shift + rng.standard_t(3, size=n) for n in rng.integers(2, 200, size=4)]
    reference = fit_front_end(make(raw), 1.0)
    scaled = fit_front_end(make([scale * x for x in raw]), 1.0)
    for x in raw:
        np.testing.assert_allclose(
            scaled.apply(scale * x), reference.apply(x), rtol=1e-9, atol=1e-9 * 0.5
        )


@settings(max_examples=200, deadline=None)
@given(
    lengths=st.lists(st.integers(1, 400), min_size=1, max_size=5),
    scale=st.sampled_from([1e-6, 1.0, 1e9]),
    rounded=st.booleans(),
    percentile=st.sampled_from([0.0, 12.5, 50.0, 99.9, 100.0]),
    seed=st.integers(0, 2**32 - 1),
)
def test_streaming_percentile_equals_numpy_on_the_concatenation(
    lengths, scale, rounded, percentile, seed
):
    rng = np.random.default_rng(seed)
    signals = [rng.standard_normal(n) * scale for n in lengths]
    if rounded:  # many ties
        signals = [np.round(s / scale) for s in signals]
    samples = np.concatenate(signals)
    offset = float(samples.mean())
    deviation = np.abs(samples - offset)
    expected = np.percentile(deviation, percentile)
    assert streaming_percentile(signals, offset, percentile) == expected
