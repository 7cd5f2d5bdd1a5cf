"""Statistics for comparing readouts: against SciPy and hand computations, and every edge case."""

import math
import warnings

import numpy as np
import pytest
import scipy.stats
from hypothesis import given
from hypothesis import strategies as st

from pipeline.results.stats import (
    _bootstrap_weights,
    accuracy_interval,
    compare_over_chips,
    compare_paired,
    holm,
    trend,
    wilson_interval,
)


def rng(seed=0):
    return np.random.default_rng(seed)


def with_k_correct(k, n):
    """bool (1, n): the first k recordings right."""
    return (np.arange(n) < k)[np.newaxis]


# Accuracy intervals


@pytest.mark.parametrize(
    ("k", "n"), [(0, 1), (1, 1), (0, 12), (12, 12), (7, 12), (1, 120), (95, 120), (120, 120)]
)
@pytest.mark.parametrize("confidence", [0.95, 0.9])
def test_single_repeat_interval_is_scipys_wilson_interval(k, n, confidence):
    expected = scipy.stats.binomtest(k, n).proportion_ci(confidence, method="wilson")
    labels = np.arange(n) % 3
    result = accuracy_interval(with_k_correct(k, n), labels, rng=rng(), confidence=confidence)
    assert result.estimate == k / n
    assert result.low == pytest.approx(expected.low, abs=1e-15)
    assert result.high == pytest.approx(expected.high, abs=1e-15)
    assert result.method == "Wilson score"
    assert result.confidence == confidence
    assert result.low <= result.estimate <= result.high


def wilson_cases():
    """(k, n) pairs: every k for small n (n = 1 among them), the ends and a spread for larger."""
    pairs = [(k, n) for n in range(1, 25) for k in range(n + 1)]
    for n in (60, 119, 120, 121, 1000, 4096, 10**6):
        pairs += [(k, n) for k in {0, 1, 2, n // 3, n // 2, n - 1, n, *range(0, n + 1, n // 17)}]
    return np.array(pairs).T


@pytest.mark.parametrize("confidence", [0.95, 0.9, 0.5, 0.999])
def test_vectorized_wilson_interval_is_scipys_for_every_proportion(confidence):
    k, n = wilson_cases()
    low, high = wilson_interval(k, n, confidence)
    assert low.dtype == high.dtype == np.float64 and low.shape == k.shape
    expected = np.array(
        [
            (ci.low, ci.high)
            for ci in (
                scipy.stats.binomtest(int(a), int(b)).proportion_ci(confidence, method="wilson")
                for a, b in zip(k, n, strict=True)
            )
        ]
    )
    np.testing.assert_allclose(low, expected[:, 0], rtol=0, atol=1e-12)
    np.testing.assert_allclose(high, expected[:, 1], rtol=0, atol=1e-12)
    assert np.all(low[k == 0] == 0.0) and np.all(high[k == n] == 1.0)


def test_vectorized_wilson_interval_broadcasts_and_matches_accuracy_interval():
    k = np.array([[0, 3, 7], [1, 5, 12]])
    low, high = wilson_interval(k, 12)
    assert low.shape == high.shape == (2, 3)
    for (i, j), successes in np.ndenumerate(k):
        one = accuracy_interval(with_k_correct(successes, 12), np.arange(12) % 3, rng=rng())
        assert (low[i, j], high[i, j]) == pytest.approx((one.low, one.high), abs=1e-12)


@pytest.mark.parametrize(
    ("k", "n", "confidence", "message"),
    [
        (3, 2, 0.95, "k must lie in"),
        (-1, 2, 0.95, "k must lie in"),
        (0, 0, 0.95, "n must be >= 1"),
        (1.0, 2, 0.95, "k must be integers"),
        (1, 2.0, 0.95, "n must be integers"),
        ([1, 2], [3, 4, 5], 0.95, "do not broadcast"),
        (1, 2, 1.0, "confidence"),
        (1, 2, True, "confidence"),
    ],
)
def test_vectorized_wilson_interval_refuses_bad_input(k, n, confidence, message):
    with pytest.raises(ValueError, match=message):
        wilson_interval(k, n, confidence)


def test_repeated_interval_is_a_bootstrap_that_brackets_the_estimate():
    generator = rng(1)
    correct = generator.random((5, 60)) < 0.7
    labels = np.repeat(np.arange(4), 15)
    result = accuracy_interval(correct, labels, rng=rng(2), resamples=500)
    assert result.estimate == correct.mean()
    assert result.low < result.estimate < result.high
    assert result.method == "stratified bootstrap over recordings (500 resamples, percentile)"


def test_repeats_of_one_recording_are_not_counted_as_independent_trials():
    # Five identical repeats carry the information of one: the bootstrap interval must be as wide
    # as the normal-approximation interval for n recordings, not sqrt(5) times narrower.
    n, k = 200, 140
    correct = np.repeat(with_k_correct(k, n), 5, axis=0)
    result = accuracy_interval(correct, np.zeros(n, dtype=int), rng=rng(3), resamples=4000)
    half_width = 1.959964 * math.sqrt(0.7 * 0.3 / n)
    assert result.estimate == 0.7
    assert result.low == pytest.approx(0.7 - half_width, abs=0.01)
    assert result.high == pytest.approx(0.7 + half_width, abs=0.01)


def test_stratification_keeps_every_class_count():
    labels = np.array([2, 0, 0, 1, 2, 2, 0, 2, 2])
    weights = _bootstrap_weights(labels, 300, rng(4))
    assert weights.shape == (300, labels.size)
    assert np.array_equal(weights, np.round(weights))
    for cls in (0, 1, 2):
        assert np.all(weights[:, labels == cls].sum(axis=1) == np.sum(labels == cls))
    assert weights[:, labels == 1].min() == 1  # the lone recording of class 1 is always drawn
    assert weights[:, labels != 1].std(axis=0).min() > 0  # larger classes are resampled


def test_stratified_interval_is_exact_when_each_class_is_all_right_or_all_wrong():
    # Without stratification a resample could draw more of one class and move the accuracy.
    labels = np.repeat([0, 1, 2, 3], [10, 5, 3, 2])
    correct = np.repeat((labels % 2 == 0)[np.newaxis], 3, axis=0)
    result = accuracy_interval(correct, labels, rng=rng(5), resamples=200)
    assert (result.estimate, result.low, result.high) == (13 / 20, 13 / 20, 13 / 20)


def test_bool_like_integers_give_the_same_result_as_bools():
    correct = rng(6).random((3, 40)) < 0.6
    labels = np.arange(40) % 2
    as_bool = accuracy_interval(correct, labels, rng=rng(7))
    as_int = accuracy_interval(correct.astype(np.int8), labels, rng=rng(7))
    assert as_bool == as_int


def test_results_are_deterministic_given_the_generator():
    a = rng(8).random((4, 50)) < 0.8
    b = rng(9).random((4, 50)) < 0.6
    labels = np.arange(50) % 5
    first = compare_paired(a, b, labels, rng=rng(10))
    assert compare_paired(a, b, labels, rng=rng(10)) == first
    assert compare_paired(a, b, labels, rng=rng(11)) != first


# Paired comparisons


def test_single_repeat_p_value_is_the_exact_mcnemar_test():
    # 9 recordings right in a only, 2 in b only, 12 in both, 7 in neither.
    a = np.array([1] * 9 + [0] * 2 + [1] * 12 + [0] * 7, dtype=bool)[np.newaxis]
    b = np.array([0] * 9 + [1] * 2 + [1] * 12 + [0] * 7, dtype=bool)[np.newaxis]
    labels = np.arange(30) % 3
    result = compare_paired(a, b, labels, rng=rng())
    assert (result.only_a, result.only_b) == (9, 2)
    assert result.difference == pytest.approx(7 / 30, abs=1e-15)
    # Two-sided exact binomial: 2 * P(X >= 9 | 11, 1/2) = 2 * (55 + 11 + 1) / 2048.
    assert result.p_value == pytest.approx(134 / 2048, rel=1e-12)
    assert result.p_value == scipy.stats.binomtest(9, 11, 0.5).pvalue
    assert result.low <= result.difference <= result.high
    assert result.method.endswith("; exact McNemar test")
    assert not result.significant()
    assert result.significant(alpha=0.1)


@pytest.mark.parametrize(("only_a", "only_b"), [(1, 0), (0, 1), (5, 5), (3, 10), (20, 0)])
def test_mcnemar_matches_scipy_for_hand_made_discordant_counts(only_a, only_b):
    n = only_a + only_b + 4
    a = np.zeros(n, dtype=bool)
    b = np.zeros(n, dtype=bool)
    a[:only_a] = True
    b[only_a : only_a + only_b] = True
    a[-2:] = b[-2:] = True  # concordant right; the remaining two concordant wrong
    result = compare_paired(a[np.newaxis], b[np.newaxis], np.arange(n) % 2, rng=rng())
    assert (result.only_a, result.only_b) == (only_a, only_b)
    assert result.p_value == scipy.stats.binomtest(only_a, only_a + only_b, 0.5).pvalue


@pytest.mark.parametrize("repeats", [1, 4])
def test_no_discordant_pair_gives_p_one_and_a_zero_interval(repeats):
    correct = rng(12).random((repeats, 25)) < 0.5
    result = compare_paired(correct, correct.copy(), np.arange(25) % 3, rng=rng())
    assert (result.difference, result.low, result.high, result.p_value) == (0.0, 0.0, 0.0, 1.0)
    assert (result.only_a, result.only_b) == (0, 0)
    assert not result.significant()


def test_repeated_comparison_uses_the_bootstrap_p_value():
    a = np.ones((3, 40), dtype=bool)
    b = np.tile(np.arange(40) % 2 == 0, (3, 1))
    labels = np.arange(40) % 4
    result = compare_paired(a, b, labels, rng=rng(), resamples=999)
    assert result.difference == 0.5
    assert (result.only_a, result.only_b) == (60, 0)
    assert result.low > 0
    # Every resampled difference is > 0: p = 2 * (0 + 1) / (999 + 1).
    assert result.p_value == pytest.approx(0.002, rel=1e-12)
    assert result.method.endswith("; two-sided bootstrap test")
    assert result.significant()


def test_bootstrap_p_value_is_large_for_a_difference_within_noise():
    generator = rng(13)
    a = generator.random((5, 80)) < 0.7
    b = generator.random((5, 80)) < 0.7
    result = compare_paired(a, b, np.arange(80) % 4, rng=rng(14))
    assert result.low < 0 < result.high
    assert result.p_value > 0.05


# Holm-Bonferroni


def test_holm_on_a_hand_computed_example():
    raw = [0.01, 0.04, 0.03, 0.005]
    # Sorted: 0.005 * 4 = 0.02, 0.01 * 3 = 0.03, 0.03 * 2 = 0.06, 0.04 * 1 = 0.04 -> 0.06
    # (monotone).
    np.testing.assert_allclose(holm(raw), [0.03, 0.06, 0.06, 0.02], rtol=1e-12)


def test_holm_caps_at_one_keeps_ties_and_handles_trivial_inputs():
    np.testing.assert_array_equal(holm([0.5, 0.6]), [1.0, 1.0])
    np.testing.assert_allclose(holm([0.02, 0.02, 0.02]), [0.06, 0.06, 0.06], rtol=1e-12)
    assert holm([0.3]).tolist() == [0.3]
    empty = holm([])
    assert empty.shape == (0,)
    assert empty.dtype == np.float64
    assert holm(np.array([0.0, 1.0])).tolist() == [0.0, 1.0]


@pytest.mark.parametrize("bad", [[0.1, -0.01], [1.5], [float("nan")], [[0.1, 0.2]]])
def test_holm_rejects_invalid_p_values(bad):
    with pytest.raises(ValueError, match="p_values"):
        holm(bad)


@given(st.lists(st.floats(min_value=0.0, max_value=1.0), max_size=30))
def test_holm_property_adjusted_between_raw_and_one_and_monotone(raw):
    adjusted = holm(raw)
    p = np.asarray(raw, dtype=np.float64)
    assert adjusted.shape == p.shape
    assert np.all(adjusted >= p)
    assert np.all(adjusted <= 1.0)
    order = np.argsort(p, kind="stable")
    assert np.all(np.diff(adjusted[order]) >= 0)


# Trends


def test_decreasing_accuracy_has_a_negative_slope_with_interval_below_zero():
    n, x = 100, np.array([0.0, 0.05, 0.1, 0.15, 0.2])  # e.g. threshold_v
    counts = [90, 80, 70, 60, 50]
    order = rng(15).permutation(n)  # which recordings are right differs between levels
    correct = np.stack([(order < k)[np.newaxis] for k in counts])
    labels = np.arange(n) % 4
    result = trend(correct, x, labels, rng=rng(16), resamples=999)
    expected = scipy.stats.linregress(x, np.array(counts) / n).slope
    assert result.slope == pytest.approx(expected, rel=1e-12)
    assert result.slope == pytest.approx(-2.0, rel=1e-12)  # -0.1 accuracy per 0.05 V
    assert result.low <= result.slope <= result.high < 0
    assert result.p_value == pytest.approx(2 / 1000, rel=1e-12)


def test_flat_accuracy_has_an_interval_around_zero():
    # Same accuracy at every level, but different recordings right at each: a real spread.
    base = rng(17).random(60) < 0.6
    correct = np.stack([np.roll(base, 7 * level)[np.newaxis] for level in range(4)])
    result = trend(correct, np.array([1.0, 2.0, 4.0, 8.0]), np.arange(60) % 3, rng=rng(18))
    assert result.slope == 0.0
    assert result.low < 0 < result.high
    assert result.p_value == 1.0


def test_trend_with_repeats_matches_the_slope_of_mean_accuracies():
    correct = rng(19).random((3, 4, 30)) < np.array([0.9, 0.7, 0.5])[:, None, None]
    x = np.array([10.0, 20.0, 40.0])
    result = trend(correct, x, np.arange(30) % 2, rng=rng(20), resamples=300)
    expected = scipy.stats.linregress(x, correct.mean(axis=(1, 2))).slope
    assert result.slope == pytest.approx(expected, rel=1e-12)
    assert result.low <= result.slope <= result.high
    assert 0 < result.p_value <= 1


@pytest.mark.parametrize("x", [[1.0, 1.0, 1.0], [2.0]])
def test_trend_needs_two_distinct_values(x):
    correct = np.ones((len(x), 1, 5), dtype=bool)
    with pytest.raises(ValueError, match="distinct"):
        trend(correct, np.array(x), np.zeros(5, dtype=int), rng=rng())


# Edge cases: finite, ordered, and silent


def edge_cases(repeats):
    """(name, a, b, labels) for the degenerate inputs callers can produce."""
    generator = rng(21)
    mixed = generator.random((repeats, 12)) < 0.5
    two_classes = np.arange(12) % 2
    return [
        ("equal predictions", mixed, mixed.copy(), two_classes),
        ("opposite predictions", mixed, ~mixed, two_classes),
        ("one class", mixed, generator.random((repeats, 12)) < 0.5, np.zeros(12, dtype=int)),
        ("all right vs all wrong", np.ones((repeats, 12)), np.zeros((repeats, 12)), two_classes),
        ("all right", np.ones((repeats, 12)), np.ones((repeats, 12)), two_classes),
        ("all wrong", np.zeros((repeats, 12)), np.zeros((repeats, 12)), two_classes),
        ("single recording right", np.ones((repeats, 1)), np.zeros((repeats, 1)), np.array([3])),
        ("single recording same", np.ones((repeats, 1)), np.ones((repeats, 1)), np.array([0])),
    ]


CASES = [(r, *case) for r in (1, 3) for case in edge_cases(r)]


@pytest.mark.parametrize(
    ("repeats", "name", "a", "b", "labels"), CASES, ids=[f"{c[1]}-R{c[0]}" for c in CASES]
)
def test_edge_cases_are_finite_ordered_and_warning_free(repeats, name, a, b, labels):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        for side in (a, b):
            interval = accuracy_interval(side, labels, rng=rng(), resamples=200)
            values = [interval.estimate, interval.low, interval.high]
            assert all(math.isfinite(v) for v in values), name
            assert 0.0 <= interval.low <= interval.estimate <= interval.high <= 1.0, name
        comparison = compare_paired(a, b, labels, rng=rng(), resamples=200)
        values = [comparison.difference, comparison.low, comparison.high, comparison.p_value]
        assert all(math.isfinite(v) for v in values), name
        assert -1.0 <= comparison.low <= comparison.difference <= comparison.high <= 1.0, name
        assert 0.0 < comparison.p_value <= 1.0, name
        slope = trend(
            np.stack([a, b, a]), np.array([0.0, 1.0, 3.0]), labels, rng=rng(), resamples=200
        )
        values = [slope.slope, slope.low, slope.high, slope.p_value]
        assert all(math.isfinite(v) for v in values), name
        assert slope.low <= slope.slope <= slope.high, name
        assert 0.0 < slope.p_value <= 1.0, name


def test_opposite_predictions_differ_by_the_accuracy_gap():
    a = np.array([[1, 1, 1, 0]], dtype=bool)
    result = compare_paired(a, ~a, np.array([0, 0, 1, 1]), rng=rng())
    assert (result.only_a, result.only_b) == (3, 1)
    assert result.difference == 0.5
    assert result.p_value == scipy.stats.binomtest(3, 4, 0.5).pvalue


def test_a_single_recording_gives_a_degenerate_bootstrap_interval():
    result = accuracy_interval(np.array([[1], [0], [1], [1]]), np.array([0]), rng=rng())
    assert (result.estimate, result.low, result.high) == (0.75, 0.75, 0.75)


# The bootstraps against the weight-matrix formula, bit for bit


def reference_weights(labels, resamples, generator):
    """float64 (resamples, n): how often each recording is drawn, as the formula states it.

    One ``integers`` call per class in ascending label order, then one count over all resamples
    and recordings; the functions must draw the same and give the same bits without this matrix.
    """
    n = labels.size
    row_start = (np.arange(resamples, dtype=np.int64) * n)[:, np.newaxis]
    drawn = []
    for cls in np.unique(labels):
        members = np.flatnonzero(labels == cls)
        picks = generator.integers(0, members.size, size=(resamples, members.size))
        drawn.append((members[picks] + row_start).ravel())
    counts = np.bincount(np.concatenate(drawn), minlength=resamples * n)
    return counts.reshape(resamples, n).astype(np.float64)


def reference_bounds(estimate, boot, confidence):
    """The percentile interval of ``boot`` widened to contain ``estimate``."""
    tail = (1.0 - confidence) / 2.0
    low, high = np.quantile(boot, [tail, 1.0 - tail])
    return min(float(low), estimate), max(float(high), estimate)


def reference_p(observed, boot):
    if observed == 0.0:
        return 1.0
    extreme = min(np.count_nonzero(boot <= 0.0), np.count_nonzero(boot >= 0.0))
    return min(1.0, 2.0 * (extreme + 1) / (boot.size + 1))


def bits(*values):
    """The float64 bytes of ``values``: equal only if equal to the last bit (and sign of 0)."""
    return np.array(values, dtype=np.float64).tobytes()


def bootstrap_case(seed):
    """Random inputs: 1-150 recordings in 1-5 classes (half the time one more class of a single
    recording), 2-5 repeats, all right, all wrong or mixed, 2-4 trend levels."""
    generator = rng(seed)
    n = int(generator.integers(1, 151))
    labels = generator.integers(0, int(generator.integers(1, 6)), n)
    if seed % 2:
        labels[generator.integers(n)] = -1
    repeats = int(generator.integers(2, 6))
    rate = [0.0, 1.0, generator.random()][seed % 3]
    a = generator.random((repeats, n)) < rate
    b = generator.random((repeats, n)) < generator.random()
    levels = int(generator.integers(2, 5))
    correct = generator.random((levels, repeats, n)) < generator.random((levels, 1, 1))
    x = generator.normal(size=levels)
    settings = {
        "resamples": int(generator.choice([1, 7, 400, 2000])),
        "confidence": float(generator.choice([0.95, 0.8])),
    }
    return labels, a, b, correct, x, settings, int(generator.integers(2**32))


@pytest.mark.parametrize("seed", range(40))
def test_bootstraps_equal_the_weight_matrix_formula_bit_for_bit(seed):
    labels, a, b, correct, x, settings, draws = bootstrap_case(seed)
    resamples, confidence = settings["resamples"], settings["confidence"]
    repeats, n = a.shape
    expected_rng = rng(draws)
    weights = reference_weights(labels, resamples, expected_rng)

    generator = rng(draws)
    result = accuracy_interval(a, labels, rng=generator, **settings)
    assert generator.bit_generator.state == expected_rng.bit_generator.state
    estimate = int(a.sum()) / (n * repeats)
    boot = weights @ a.sum(axis=0).astype(np.float64) / (n * repeats)
    expected = (estimate, *reference_bounds(estimate, boot, confidence))
    assert bits(result.estimate, result.low, result.high) == bits(*expected)

    for r in (repeats, 1):  # one repeat: McNemar's p, but the same bootstrap interval
        generator = rng(draws)
        result = compare_paired(a[:r], b[:r], labels, rng=generator, **settings)
        assert generator.bit_generator.state == expected_rng.bit_generator.state
        difference = (int(a[:r].sum()) - int(b[:r].sum())) / (n * r)
        per_recording = a[:r].sum(axis=0) - b[:r].sum(axis=0)
        boot = weights @ per_recording.astype(np.float64) / (n * r)
        expected = (difference, *reference_bounds(difference, boot, confidence))
        assert bits(result.difference, result.low, result.high) == bits(*expected)
        if r > 1:
            assert bits(result.p_value) == bits(reference_p(difference, boot))

    generator = rng(draws)
    result = trend(correct, x, labels, rng=generator, **settings)
    assert generator.bit_generator.state == expected_rng.bit_generator.state
    counts = correct.sum(axis=1).T
    centred_x = x - x.mean()
    scale = n * repeats * float(centred_x @ centred_x)
    per_recording = (counts - counts[:, :1]).astype(np.float64) @ centred_x
    slope = float(per_recording.sum() / scale)
    boot = weights @ per_recording / scale
    expected = (slope, *reference_bounds(slope, boot, confidence), reference_p(slope, boot))
    assert bits(result.slope, result.low, result.high, result.p_value) == bits(*expected)

    assert _bootstrap_weights(labels, resamples, rng(draws)).tobytes() == weights.tobytes()


# Input validation


def bad_calls():
    ok = np.ones((2, 6), dtype=bool)
    labels = np.arange(6) % 2
    return [
        ("1-D correct", lambda: accuracy_interval(np.ones(6), labels, rng=rng()), "correct"),
        ("no recording", lambda: accuracy_interval(np.ones((1, 0)), labels[:0], rng=rng()), ">= 1"),
        ("no repeat", lambda: accuracy_interval(np.ones((0, 6)), labels, rng=rng()), ">= 1"),
        ("values 0/1", lambda: accuracy_interval(ok * 2, labels, rng=rng()), "0/1"),
        ("NaN entries", lambda: accuracy_interval(ok * np.nan, labels, rng=rng()), "0/1"),
        ("text", lambda: accuracy_interval(np.full((2, 6), "x"), labels, rng=rng()), "dtype"),
        ("label length", lambda: accuracy_interval(ok, labels[:5], rng=rng()), "labels"),
        ("2-D labels", lambda: accuracy_interval(ok, labels[np.newaxis], rng=rng()), "labels"),
        ("float labels", lambda: accuracy_interval(ok, labels * 1.0, rng=rng()), "labels"),
        ("confidence 0", lambda: accuracy_interval(ok, labels, rng=rng(), confidence=0), "(0, 1)"),
        (
            "confidence 1",
            lambda: accuracy_interval(ok, labels, rng=rng(), confidence=1.0),
            "(0, 1)",
        ),
        (
            "confidence NaN",
            lambda: accuracy_interval(ok, labels, rng=rng(), confidence=math.nan),
            "confidence",
        ),
        ("resamples 0", lambda: accuracy_interval(ok, labels, rng=rng(), resamples=0), "resamples"),
        (
            "resamples float",
            lambda: accuracy_interval(ok, labels, rng=rng(), resamples=2.5),
            "resamples",
        ),
        (
            "paired shapes",
            lambda: compare_paired(ok, ok[:1], labels, rng=rng()),
            "same shape",
        ),
        ("trend 2-D", lambda: trend(ok, np.array([0.0, 1.0]), labels, rng=rng()), "levels"),
        (
            "trend x length",
            lambda: trend(ok[np.newaxis].repeat(3, 0), np.array([0.0, 1.0]), labels, rng=rng()),
            "x must have shape",
        ),
        (
            "trend x NaN",
            lambda: trend(ok[np.newaxis].repeat(2, 0), np.array([0.0, np.nan]), labels, rng=rng()),
            "finite",
        ),
    ]


BAD = bad_calls()


@pytest.mark.parametrize(("name", "call", "message"), BAD, ids=[b[0] for b in BAD])
def test_invalid_input_raises_a_value_error_naming_the_problem(name, call, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
        call()


def test_rng_must_be_a_generator():
    with pytest.raises(TypeError, match="Generator"):
        accuracy_interval(np.ones((1, 3)), np.zeros(3, dtype=int), rng=np.random.RandomState(0))


def _p05(accuracy):
    return np.quantile(accuracy, 0.05, axis=-1)


def test_over_one_chip_the_chip_bootstrap_is_the_paired_one():
    rng = np.random.default_rng(3)
    labels = np.arange(60) % 4
    a = rng.random((1, 2, 60)) < 0.7
    b = rng.random((1, 2, 60)) < 0.5
    paired = compare_paired(a[0], b[0], labels, rng=np.random.default_rng(7), resamples=500)
    chips = compare_over_chips(
        a,
        b,
        labels,
        statistic=lambda x: x.mean(axis=-1),
        rng=np.random.default_rng(7),
        resamples=500,
    )
    assert chips.difference == pytest.approx(paired.difference, abs=1e-12)
    assert (chips.low, chips.high) == pytest.approx((paired.low, paired.high), abs=1e-12)
    assert chips.p_value == pytest.approx(paired.p_value)
    assert (chips.only_a, chips.only_b) == (paired.only_a, paired.only_b)


def test_the_chip_bootstrap_sees_the_spread_over_chips():
    # 40 chips, 120 recordings: a's chips are all right on 70 % of the recordings; b's chips
    # average 70 % too, but half of them are right on only 50 %. Their means are equal, their
    # 5th percentiles are not.
    labels = np.arange(120) % 12
    a = np.zeros((40, 1, 120), dtype=bool)
    a[:, :, :84] = True
    b = np.zeros((40, 1, 120), dtype=bool)
    b[::2, :, :108] = True
    b[1::2, :, :60] = True
    mean = compare_over_chips(
        a,
        b,
        labels,
        statistic=lambda x: x.mean(axis=-1),
        rng=np.random.default_rng(1),
        resamples=400,
    )
    assert mean.difference == pytest.approx(0.0) and mean.p_value == 1.0
    low = compare_over_chips(
        a, b, labels, statistic=_p05, rng=np.random.default_rng(1), resamples=400
    )
    assert low.difference == pytest.approx(0.7 - 0.5)
    assert low.low > 0 and low.p_value < 0.05
    assert low.low <= low.difference <= low.high
    # Different chip counts are drawn independently; the statistic is still theirs.
    other = compare_over_chips(
        a[:10], b, labels, statistic=_p05, rng=np.random.default_rng(1), resamples=50
    )
    assert other.difference == pytest.approx(0.2) and (other.only_a, other.only_b) == (0, 0)
    with pytest.raises(ValueError, match="share"):
        compare_over_chips(a[:, :, :60], b, labels, statistic=_p05, rng=np.random.default_rng(1))
