"""Decaying-threshold encoder: contract, hard cases against closed forms and an independent
high-precision solve, properties, and the non-ideal effects it shares with the fixed encoder.

Tolerances: crossing times agree with the closed forms and with the independent solve (scipy's
``brentq`` at ``xtol=1e-15`` samples) to 1e-12 s, far inside the 1e-9 s the encoder promises;
the signal at a spike equals the crossed level to 1e-9 of the signal's scale.
"""

import math

import numpy as np
import pytest
import scipy.optimize
from hypothesis import example, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

from pipeline.chain.readout import decaying_crossings, level_crossings
from pipeline.chain.readout_effects import THRESHOLD_FLOOR_REL, effect_rng, real_train, true_train
from pipeline.design.effects import Effect
from pipeline.design.scene import Scene
from pipeline.errors import SimulationError

FS = 1000.0
TIME_TOL_S = 1e-12


def walk(n=4000, seed=0, step=0.02):
    return np.cumsum(np.random.default_rng(seed).standard_normal(n)) * step


def decaying_readout(theta0=0.1, theta_min=0.04, tau_s=0.01, **effects):
    return Scene.from_dict(
        {
            "readout": {
                "threshold_v": theta0,
                "encoder": "decaying",
                "decay": {"theta_min_v": theta_min, "tau_s": tau_s},
                "effects": effects,
            }
        }
    ).readout


def reference_decaying(v, fs_hz, theta0, theta_min, tau_s, grid=257):
    """The encoder solved independently: in each segment, the first sign change of either
    condition on a grid of ``grid`` points, refined by ``brentq`` to 1e-15 of a sample."""
    tau = tau_s * fs_hz
    r, t_last = float(v[0]), 0.0
    times, polarity = [], []
    for i in range(1, len(v)):
        a, b = float(v[i - 1]), float(v[i])
        lo = 0.0
        while True:
            found = None
            for sign in (1, -1):

                def gap(s, sign=sign, r=r, t_last=t_last, i=i, a=a, b=b):
                    theta = theta_min + (theta0 - theta_min) * math.exp(
                        -((i - 1 + s) - t_last) / tau
                    )
                    return sign * (a + (b - a) * s - r) - theta

                s_grid = np.linspace(lo, 1.0, grid)
                values = np.array([gap(s) for s in s_grid])
                if values[0] >= 0:
                    hit = lo
                else:
                    above = np.flatnonzero(values >= 0)
                    if not len(above):
                        continue
                    j = above[0]
                    hit = scipy.optimize.brentq(gap, s_grid[j - 1], s_grid[j], xtol=1e-15)
                if found is None or hit < found[0]:
                    found = (hit, sign)
            if found is None:
                break
            s, sign = found
            theta = theta_min + (theta0 - theta_min) * math.exp(-((i - 1 + s) - t_last) / tau)
            r += sign * theta
            t_last = i - 1 + s
            times.append(t_last / fs_hz)
            polarity.append(sign)
            lo = s
    return np.array(times), np.array(polarity, dtype=np.int8)


def assert_same_train(actual, expected, atol=TIME_TOL_S):
    np.testing.assert_array_equal(actual[1], expected[1])
    np.testing.assert_allclose(actual[0], expected[0], rtol=0, atol=atol)


# -- contract and hard cases ------------------------------------------------------------------


def test_contract_types():
    times, polarity = decaying_crossings(walk(), FS, 0.1, 0.04, 0.01)
    assert times.dtype == np.float64 and polarity.dtype == np.int8
    assert set(np.unique(polarity)) == {-1, 1}
    assert len(times) == len(polarity) > 0


def test_exact_touches_count_and_turn_back():
    # Equal thresholds: the fixed encoder's exact touches, at the samples themselves.
    times, polarity = decaying_crossings(np.array([0.0, 0.5, 0.0]), FS, 0.5, 0.5, 1.0)
    np.testing.assert_array_equal(polarity, [1, -1])
    np.testing.assert_allclose(times, [1 / FS, 2 / FS], rtol=1e-15)
    # A threshold decayed to theta_min (exp underflows to 0 after 2000 time constants): the
    # signal touches r + theta_min exactly at sample 2000 and turns back short of the next level.
    v = np.zeros(2003)
    v[2000], v[2001:] = 0.25, 0.1
    times, polarity = decaying_crossings(v, FS, 1.0, 0.25, 1 / FS)
    np.testing.assert_array_equal(polarity, [1])
    np.testing.assert_array_equal(times, [2000 / FS])


def test_a_long_flat_stretch_fires_when_the_threshold_has_decayed_to_the_gap():
    # A ramp to 0.3 V in the first sample, then flat: theta(t) = 0.25 + 0.75 exp(-t / tau)
    # reaches 0.3 V at t = tau * ln(15), once; the threshold then restarts at 1 V above 0.3 V.
    tau_s = 0.01
    v = np.full(500, 0.3)
    v[0] = 0.0
    times, polarity = decaying_crossings(v, FS, 1.0, 0.25, tau_s)
    np.testing.assert_array_equal(polarity, [1])
    np.testing.assert_allclose(times, [tau_s * math.log(15.0)], rtol=0, atol=TIME_TOL_S)


def test_a_step_across_many_levels_matches_the_independent_solve():
    v = np.array([0.0, 1.0, 1.0, -0.5])
    got = decaying_crossings(v, FS, 0.1, 0.05, 0.002)
    assert 10 <= np.sum(got[1] == 1) <= 20  # thresholds between 0.05 and 0.1 V on a 1 V step
    assert np.all(np.diff(got[0]) > 0)
    assert_same_train(got, reference_decaying(v, FS, 0.1, 0.05, 0.002))


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize(("theta_min", "tau_s"), [(0.04, 0.01), (0.02, 0.1), (0.08, 0.001)])
def test_crossing_times_match_an_independent_high_precision_solve(seed, theta_min, tau_s):
    v = walk(600, seed=seed)
    assert_same_train(
        decaying_crossings(v, FS, 0.1, theta_min, tau_s),
        reference_decaying(v, FS, 0.1, theta_min, tau_s),
    )


def test_noise_near_theta_min_matches_the_independent_solve():
    v = np.random.default_rng(4).normal(0.0, 0.03, 800)  # sample steps about theta_min
    got = decaying_crossings(v, FS, 0.1, 0.04, 0.005)
    assert len(got[0]) > 50
    assert_same_train(got, reference_decaying(v, FS, 0.1, 0.04, 0.005))


@pytest.mark.parametrize(
    ("theta_min", "tau_s"),
    [(0.1, 0.01), (0.1, 1e-9), (0.04, 1e12)],
    ids=["theta_min-equals-theta0", "equal-and-tiny-tau", "huge-tau"],
)
def test_equal_thresholds_or_a_huge_tau_are_the_fixed_encoder_at_theta0(theta_min, tau_s):
    v = walk(seed=2)
    assert_same_train(decaying_crossings(v, FS, 0.1, theta_min, tau_s), level_crossings(v, FS, 0.1))


def test_a_tiny_tau_is_the_fixed_encoder_at_theta_min():
    v = walk(seed=3)
    expected = level_crossings(v, FS, 0.04)
    got = decaying_crossings(v, FS, 0.1, 0.04, 1e-9)
    assert len(expected[0]) > 100
    assert_same_train(got, expected)
    # and a shorter time constant moves the train toward it
    counts = [len(decaying_crossings(v, FS, 0.1, 0.04, tau)[0]) for tau in (0.1, 0.01, 1e-4)]
    assert counts == sorted(counts) and counts[-1] <= len(expected[0])


def test_bad_parameters_are_refused_all_at_once_in_one_line():
    with pytest.raises(ValueError) as caught:
        decaying_crossings(np.array([0.0, np.nan, 1.0]), FS, 0.1, -0.01, 0.0)
    text = str(caught.value)
    assert "\n" not in text
    for culprit in ("non-finite sample (nan) at index 1", "theta_min_v", "tau_s"):
        assert culprit in text
    with pytest.raises(ValueError, match="theta_min_v .* above theta0_v"):
        decaying_crossings(walk(), FS, 0.1, 0.2, 0.01)
    for bad in (0.0, -1.0, math.inf, math.nan):
        with pytest.raises(ValueError, match="theta_min_v"):
            decaying_crossings(walk(), FS, 0.1, bad, 0.01)
        with pytest.raises(ValueError, match="tau_s"):
            decaying_crossings(walk(), FS, 0.1, 0.05, bad)


def test_a_runaway_train_is_refused():
    readout = decaying_readout(theta0=1e-3, theta_min=1e-4)
    with pytest.raises(SimulationError, match="at least"):
        true_train(np.array([0.0, 1.0]), FS, readout, max_spikes=100)


# -- properties ---------------------------------------------------------------------------------

THRESHOLDS = st.sampled_from([0.0937, 0.1731, 0.2519])
RATIOS = st.sampled_from([1.0, 0.61, 0.3])
TAUS = st.sampled_from([1e-4, 3.3e-3, 0.05])
SIGNALS = hnp.arrays(
    np.float64, st.integers(2, 80), elements=st.integers(-64, 64).map(lambda k: k / 17)
)


def replay(v, fs_hz, theta0, theta_min, tau_s, times, polarity):
    """Check the train against the definition: each spike on its level, no level reached at a
    sample between spikes. Tolerance 1e-9 of the signal's scale."""
    tol = 1e-9 * (np.max(np.abs(v)) + theta0)
    index = np.arange(len(v))
    r, t_last, k = v[0], 0.0, 0
    for i in index:
        while k < len(times) and times[k] <= i / fs_hz:
            theta = theta_min + (theta0 - theta_min) * math.exp(-(times[k] - t_last) / tau_s)
            level = r + polarity[k] * theta
            assert abs(np.interp(times[k] * fs_hz, index, v) - level) <= tol
            r, t_last, k = level, times[k], k + 1
        theta = theta_min + (theta0 - theta_min) * math.exp(-(i / fs_hz - t_last) / tau_s)
        if k == 0 or times[k - 1] < i / fs_hz:
            assert abs(v[i] - r) < theta + tol
    assert k == len(times)


@settings(max_examples=150, deadline=None)
@given(SIGNALS, THRESHOLDS, RATIOS, TAUS)
def test_every_train_follows_the_definition(v, theta0, ratio, tau_s):
    times, polarity = decaying_crossings(v, FS, theta0, theta0 * ratio, tau_s)
    assert times.dtype == np.float64 and polarity.dtype == np.int8
    assert set(polarity.tolist()) <= {-1, 1}
    assert np.all(np.diff(times) >= 0)
    assert np.all((times >= 0) & (times <= (len(v) - 1) / FS))
    replay(v, FS, theta0, theta0 * ratio, tau_s, times, polarity)


@settings(max_examples=100, deadline=None)
@given(SIGNALS, THRESHOLDS, RATIOS, TAUS)
def test_flipping_the_sign_flips_the_polarity_and_keeps_the_times(v, theta0, ratio, tau_s):
    times, polarity = decaying_crossings(v, FS, theta0, theta0 * ratio, tau_s)
    flipped_times, flipped_polarity = decaying_crossings(-v, FS, theta0, theta0 * ratio, tau_s)
    np.testing.assert_array_equal(flipped_times, times)  # the same arithmetic, negated
    np.testing.assert_array_equal(flipped_polarity, -polarity)


@settings(max_examples=100, deadline=None)
@given(
    SIGNALS, THRESHOLDS, st.sampled_from([0.61, 0.3]), TAUS, st.sampled_from([0.37, -5.0, 120.3])
)
def test_a_constant_offset_changes_nothing(v, theta0, ratio, tau_s, offset):
    # Rounding differs with the offset, so an exact touch could come or go: a fixed threshold
    # returning to its start is one, a decaying one (levels off the signal's 1/17 V grid) never.
    times, polarity = decaying_crossings(v, FS, theta0, theta0 * ratio, tau_s)
    moved = decaying_crossings(v + offset, FS, theta0, theta0 * ratio, tau_s)
    assert_same_train(moved, (times, polarity), atol=1e-9)


# -- the readout: the TRUE train and the non-ideal effects ----------------------------------------


def test_the_readout_uses_the_encoder_it_names():
    v = walk()
    decaying = decaying_readout()
    expected = decaying_crossings(v, FS, 0.1, 0.04, 0.01)
    for train in (
        true_train(v, FS, decaying),
        real_train(v, FS, decaying, seed=0, taxel=0, recording=0),
    ):
        assert_same_train(train, expected, atol=0)
    fixed = Scene.from_dict({"readout": {"threshold_v": 0.1}}).readout
    assert_same_train(true_train(v, FS, fixed), level_crossings(v, FS, 0.1), atol=0)


def test_threshold_mismatch_scales_both_ends_of_the_taxel_curve():
    v = walk()
    readout = decaying_readout(threshold_mismatch={"sigma_rel": 0.2})
    z = effect_rng(7, Effect.THRESHOLD_MISMATCH, 3).standard_normal()
    scale = 1.0 + 0.2 * z
    expected = decaying_crossings(v, FS, 0.1 * scale, 0.04 * scale, 0.01)
    assert_same_train(real_train(v, FS, readout, seed=7, taxel=3, recording=0), expected, atol=0)


def test_mismatch_is_floored_relative_to_theta_min():
    v = walk()
    readout = decaying_readout(threshold_mismatch={"sigma_rel": 100.0, "floor_rel": 0.5})
    z = effect_rng(0, Effect.THRESHOLD_MISMATCH, 0).standard_normal()
    scale = 1.0 + 100.0 * z
    floor = 0.5 * 0.04
    curve = (max(0.1 * scale, floor), max(0.04 * scale, floor))
    expected = decaying_crossings(v, FS, *curve, 0.01)
    assert_same_train(real_train(v, FS, readout, seed=0, taxel=0, recording=0), expected, atol=0)
    assert THRESHOLD_FLOOR_REL == 0.1  # the floor without mismatch, as for the fixed encoder


def _above(theta_v, ulps):
    for _ in range(ulps):
        theta_v = math.nextafter(theta_v, math.inf)
    return theta_v


@settings(max_examples=40, deadline=None)
@given(
    v=SIGNALS,
    theta_min=st.sampled_from([0.03, 0.0937, 0.1731]),
    above=st.sampled_from([("ulps", 0), ("ulps", 1), ("ulps", 2), ("ratio", 1.7)]),
    sigma_rel=st.floats(0.0, 3.0),
    floor_rel=st.sampled_from([0.1, 0.5, 1.0]),
    seed=st.integers(0, 2**32),
    chip_pool=st.sampled_from([(0, 0), (None, 0), (3, 0), (2, 1)]),
)
@example(  # the default lowest threshold as the first one: the fixed encoder, scaled per taxel
    v=np.array([0.0, 1.0, -0.5]),
    theta_min=0.03,
    above=("ulps", 0),
    sigma_rel=0.3,
    floor_rel=0.1,
    seed=0,
    chip_pool=(0, 0),
)
def test_every_taxel_curve_is_one_its_encoder_accepts(
    v, theta_min, above, sigma_rel, floor_rel, seed, chip_pool
):
    # threshold_v at or above decay.theta_min_v (equal, one or two ulps above, well above):
    # whatever a taxel's mismatch draw, its floored curve keeps theta_0 >= theta_min, so the
    # REAL train is the ideal decaying encoder's at that curve, which refuses any other order.
    # 16 taxels per example: a curve computed with other rounding than theta * scale would
    # come out inverted by an ulp for about one draw in 13 at theta_0 == theta_min.
    kind, amount = above
    theta0 = _above(theta_min, amount) if kind == "ulps" else theta_min * amount
    readout = decaying_readout(
        theta0=theta0,
        theta_min=theta_min,
        tau_s=0.01,
        threshold_mismatch={"sigma_rel": sigma_rel, "floor_rel": floor_rel},
    )
    chip, pool = chip_pool
    floor = floor_rel * theta_min
    for taxel in range(16):
        z = 0.0  # the nominal chip draws no fixed effect
        if chip is not None:
            rng = effect_rng(seed, Effect.THRESHOLD_MISMATCH, taxel, chip=chip, pool=pool)
            z = rng.standard_normal()
        scale = 1.0 + sigma_rel * z
        curve = (max(theta0 * scale, floor), max(theta_min * scale, floor))
        assert curve[1] <= curve[0]
        got = real_train(v, FS, readout, seed=seed, taxel=taxel, recording=0, chip=chip, pool=pool)
        assert_same_train(got, decaying_crossings(v, FS, *curve, 0.01), atol=0)


def test_silent_comparator_effects_give_the_ideal_train():
    v = walk()
    readout = decaying_readout(
        comparator_offset={"sigma_v": 0.0}, comparator_noise={"sigma_v": 0.0}
    )
    expected = decaying_crossings(v, FS, 0.1, 0.04, 0.01)
    assert_same_train(real_train(v, FS, readout, seed=0, taxel=0, recording=0), expected, atol=0)


def test_every_effect_at_once_is_deterministic_and_bounded():
    # Steps of about 0.2 V against thresholds of 0.04-0.1 V: a train longer than the first
    # buffer, so the kernel runs twice and must draw the same decision noise both times.
    v = 0.4 * np.sin(1.3 * np.arange(4000))
    readout = decaying_readout(**{e.value: {} for e in Effect})
    first = real_train(v, FS, readout, seed=5, taxel=2, recording=1)
    assert len(first[0]) > len(v) // 4
    assert_same_train(real_train(v, FS, readout, seed=5, taxel=2, recording=1), first, atol=0)
    assert np.all(np.diff(first[0]) >= 0)
    assert np.all((first[0] >= 0) & (first[0] <= (len(v) - 1) / FS))
