"""Taxel arrays from one channel: delays, fractional interpolation, cutting (never wrapping)."""

import numpy as np
import pytest

import pipeline.chain.taxels as taxels
from pipeline.chain.taxels import cut_samples, taxel_delays_s, taxel_signals
from pipeline.design.scene import ArraySpec, ScanDirection

FS = 2000.0


def test_delays_follow_rows_for_a_scan_along_y():
    delays = taxel_delays_s(ArraySpec(rows=3, cols=3, pitch_mm=1.0, speed_mm_s=20.0))
    np.testing.assert_allclose(delays, [0, 0, 0, 0.05, 0.05, 0.05, 0.1, 0.1, 0.1])


def test_delays_for_x_and_diagonal_scans():
    x = taxel_delays_s(ArraySpec(rows=2, cols=2, direction=ScanDirection.X))
    np.testing.assert_allclose(x, [0, 0.05, 0, 0.05])
    xy = taxel_delays_s(ArraySpec(rows=2, cols=2, direction=ScanDirection.XY))
    np.testing.assert_allclose(xy, np.array([0, 1, 1, 2]) * np.sqrt(0.5) * 0.05)


def test_single_taxel_builds_no_delay_machinery(monkeypatch):
    signal = np.random.default_rng(0).standard_normal(100)

    def forbidden(*args, **kwargs):
        raise AssertionError("a 1x1 array must not interpolate")

    monkeypatch.setattr(taxels, "cut_samples", forbidden)
    monkeypatch.setattr(taxels.np, "multiply", forbidden)
    out = taxel_signals(signal, FS, taxel_delays_s(ArraySpec(rows=1, cols=1)))
    assert out.n_taxels == 1
    assert np.shares_memory(out.signals, signal)
    np.testing.assert_array_equal(out.taxel(0), signal)


def test_whole_sample_delays_are_exact_copies_and_the_unseen_part_is_cut():
    signal = np.arange(1000, dtype=float) ** 1.5
    delays = taxel_delays_s(ArraySpec(rows=3, cols=2))  # 0, 0.05, 0.1 s = 0, 100, 200 samples
    out = taxel_signals(signal, FS, delays)
    assert out.n_samples == 800
    assert out.signals.shape == (3, 800)  # one row per distinct delay
    np.testing.assert_array_equal(out.taxel(0), signal[200:])  # undelayed: sees x from 0.1 s
    np.testing.assert_array_equal(out.taxel(2), signal[100:900])
    np.testing.assert_array_equal(out.taxel(5), signal[:800])  # most delayed: from the start
    np.testing.assert_array_equal(out.taxel_row, [0, 0, 1, 1, 2, 2])


def test_fractional_delays_interpolate_linearly_without_wrapping():
    rng = np.random.default_rng(1)
    signal = rng.standard_normal(500)
    delays = np.array([0.0, 0.3 / FS, 2.75 / FS])
    out = taxel_signals(signal, FS, delays)
    assert out.n_samples == 500 - 3
    t = np.arange(out.n_samples) / FS + delays.max()  # common output time axis
    for taxel, tau in enumerate(delays):
        reference = np.interp(t - tau, np.arange(500) / FS, signal)
        np.testing.assert_allclose(out.taxel(taxel), reference, rtol=0, atol=1e-12)
    # Never wrapped: the most delayed taxel starts with the recording's first sample.
    assert out.taxel(2)[0] == signal[0]


def test_decimal_delays_that_are_whole_samples_are_not_interpolated():
    # 0.05 s * 2 kHz is 100.00000000000001 in floating point.
    assert cut_samples(np.array([0.0, 0.05]), FS) == 100
    signal = np.random.default_rng(2).standard_normal(300)
    out = taxel_signals(signal, FS, np.array([0.0, 0.05]))
    np.testing.assert_array_equal(out.taxel(1), signal[:200])


def test_delays_longer_than_the_recording_are_an_error():
    with pytest.raises(ValueError, match="leave 0 samples of a 100-sample recording"):
        taxel_signals(np.zeros(100), FS, np.array([0.0, 1.0]))
