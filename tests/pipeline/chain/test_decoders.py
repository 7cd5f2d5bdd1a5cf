"""The decoder registry: every model has its decoder, what each reads and how it prepares its
inputs, the operation counter through it, and every model on every deployment over chips."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.chain.decoders import (
    DECODERS,
    Decoder,
    Preparation,
    Reads,
    build_model,
    count_operations,
    decoder_of,
    reads_of,
    standardize,
)
from pipeline.chain.deployment import validate_chips
from pipeline.chain.models import FoldCNN, FoldFFNN, fold_generator
from pipeline.chain.spiking import FoldSNN
from pipeline.chain.training import cross_validate
from pipeline.design.scene import Model, SNNSpec, TrainingSpec

SPEC = SNNSpec(step_s=0.01, hidden_neurons=6, tau_mem_s=0.05, epochs=3)


def test_the_registry_covers_every_model_once():
    assert set(DECODERS) == set(Model)
    for model, decoder in DECODERS.items():
        assert isinstance(decoder, Decoder) and decoder.model is model
        assert decoder_of(model) is decoder and decoder_of(model.value) is decoder
    with pytest.raises(ValueError, match="lsnn"):
        decoder_of("lsnn")


def test_what_each_decoder_reads_prepares_and_trains():
    training = TrainingSpec(epochs=7, snn=SNNSpec(epochs=11))
    expected = {
        Model.FFNN: (Reads.WINDOWS, Preparation.STANDARDIZED, 7, FoldFFNN),
        Model.CNN: (Reads.WINDOWS, Preparation.STANDARDIZED, 7, FoldCNN),
        Model.SNN: (Reads.STEPS, Preparation.COUNTS, 11, FoldSNN),
    }
    for model, (reads, preparation, epochs, net_type) in expected.items():
        decoder = decoder_of(model)
        assert (decoder.reads, decoder.preparation) == (reads, preparation)
        assert decoder.epochs(training) == epochs
        net = build_model(
            model, (2, 3, 4), 3, 5, 2, [fold_generator(0, f, "init") for f in (0, 1)], SPEC
        )
        assert type(net) is net_type and net.n_folds == 2
    assert reads_of([Model.SNN, Model.FFNN, Model.CNN]) == (Reads.WINDOWS, Reads.STEPS)
    assert reads_of([Model.CNN]) == (Reads.WINDOWS,)


def test_the_registry_imports_no_torch():
    code = "import sys, pipeline.chain.decoders, pipeline.run.stages; print('torch' in sys.modules)"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"


def test_counts_stay_counts_and_windows_are_standardized():
    train = np.array([[1, 4], [3, 0]])[:, None, None, :]
    test = np.array([[5, 2]])[:, None, None, :]
    counts = Preparation.COUNTS.apply(train, test)
    assert counts[0].dtype == np.float32 and np.array_equal(counts[1], test.astype(np.float32))
    prepared = Preparation.STANDARDIZED.apply(train, test)
    for got, want in zip(prepared, standardize(train, test), strict=True):
        assert np.array_equal(got, want)


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.integers(0, 50), min_size=8, max_size=8),
    st.lists(st.integers(0, 50), min_size=4, max_size=4),
)
def test_only_the_counts_stay_events_and_zero_stays_zero_but_standardized(train, test):
    train = np.array(train).reshape(2, 2, 1, 2)
    test = np.array(test).reshape(1, 2, 1, 2)
    for preparation in Preparation:
        got_train, got_test = preparation.apply(train, test)
        assert got_train.shape == train.shape and got_test.shape == test.shape
        assert got_train.dtype == got_test.dtype == np.float32
        assert preparation.keeps_events is (preparation is Preparation.COUNTS)
        if preparation is Preparation.STANDARDIZED:
            continue
        # counts and log counts: 0 stays 0 (no event, no input) and more events weigh more
        both, prepared = np.concatenate([train, test]), np.concatenate([got_train, got_test])
        assert np.array_equal(prepared == 0, both == 0)
        order = np.argsort(both, axis=None, kind="stable")
        assert np.all(np.diff(prepared.ravel()[order]) >= 0)
        if preparation is Preparation.COUNTS:
            assert np.array_equal(prepared, both.astype(np.float32))


def test_the_operation_counter_asks_each_models_decoder():
    x = torch.poisson(torch.full((1, 2, 2, 3, 4), 0.5), generator=torch.Generator().manual_seed(0))
    for model in Model:
        net = build_model(model, (2, 3, 4), 3, 5, 1, [fold_generator(0, 0, "init")], SPEC)
        ops = count_operations(model, net, x)
        assert ops.stacked().shape == (1, 2, 4 if model is Model.SNN else 1, 3)
        logits, decided_ops = decoder_of(model).decide(net, x)
        assert logits.shape == (1, 2, 4, 3) and decided_ops.shape == (1, 2, 4, 3)
        # The decision at the last column is the full-touch model's, at its full cost.
        torch.testing.assert_close(logits[:, :, -1], net(x))
        assert np.array_equal(decided_ops[:, :, -1], ops.stacked()[:, :, -1])


# --------------------------------------------------------------------------------------------
# standardize


def test_standardize_uses_training_statistics_only():
    rng = np.random.default_rng(0)
    train = rng.poisson(3.0, size=(20, 1, 2, 5))
    test = rng.poisson(3.0, size=(4, 1, 2, 5))
    huge = test.astype(np.float64).copy()
    huge[0] = 1e12
    train_z, test_z = standardize(train, test)
    train_z2, test_z2 = standardize(train, huge)
    assert train_z.dtype == np.float32 and test_z.dtype == np.float32
    np.testing.assert_array_equal(train_z, train_z2)
    np.testing.assert_array_equal(test_z[1:], test_z2[1:])
    mean, std = train.mean(axis=0), train.std(axis=0)
    np.testing.assert_allclose(test_z, (test - mean) / np.where(std > 0, std, 1), rtol=1e-6)
    np.testing.assert_allclose(train_z.mean(axis=0), 0, atol=1e-6)
    np.testing.assert_allclose(train_z.std(axis=0)[std > 0], 1, rtol=1e-5)


def test_standardize_constant_and_zero_features_give_zeros_not_nan():
    train = np.zeros((6, 1, 2, 3), dtype=np.int64)
    train[:, 0, 1, 2] = 5  # constant, non-zero feature
    test = np.zeros((2, 1, 2, 3), dtype=np.int64)
    train_z, test_z = standardize(train, test)
    assert np.all(train_z == 0)
    np.testing.assert_array_equal(test_z[:, 0, 1, 2], -5.0)  # (0 - 5) / 1
    assert np.isfinite(test_z).all()


# --------------------------------------------------------------------------------------------
# every model on every deployment


def _chips(n_chips=3, seed=0):
    """Step counts of 16 recordings of 2 classes on ``n_chips`` chips, and a reference."""
    rng = np.random.default_rng(seed)
    labels = np.repeat([0, 1], 8)
    rate = np.full((16, 2, 2, 10), 0.1)
    rate[labels == 0, 0, 0] = 0.9
    rate[labels == 1, 0, 1] = 0.9
    chips = rng.poisson(np.broadcast_to(rate, (n_chips, *rate.shape)))
    return chips, rng.poisson(rate), labels


@pytest.mark.parametrize("deployment", ["per_chip", "shared", "robust"])
def test_the_snn_decides_on_every_deployment(deployment):
    chips, reference, labels = _chips()
    training = TrainingSpec(
        models=(Model.SNN,), folds=4, batch_size=4, learning_rate=1e-2, repeats=2, snn=SPEC
    )
    cv = validate_chips(
        chips,
        None if deployment == "per_chip" else reference,
        labels,
        Model.SNN,
        training,
        frame_s=SPEC.step_s,
    )
    assert cv.model is Model.SNN
    assert cv.chip_accuracy.shape == (3, 2, 4) and cv.chip_predicted.shape == (3, 2, 16)
    assert np.array_equal(cv.fold_accuracy, cv.chip_accuracy[0])
    assert np.array_equal(cv.predicted, cv.chip_predicted[0])
    assert cv.train_loss.shape == (2, 4) and cv.test_fold.shape == (2, 16)
    # Chip 0's decisions at every step, the last its prediction.
    assert np.allclose(cv.decision_s, 0.01 * np.arange(1, 11))
    assert cv.decision_predicted.shape == cv.decision_confidence.shape == (2, 10, 16)
    assert np.array_equal(cv.decision_predicted[:, -1], cv.predicted)
    assert cv.operations.shape == (10, 3) and np.all(cv.operations[:, 2] > 0)
    for chip in range(3):  # accuracy per fold is the share of its recordings a chip got right
        right = cv.chip_predicted[chip] == labels
        for r in range(2):
            by_fold = [right[r, cv.test_fold[r] == f].mean() for f in range(4)]
            assert np.allclose(cv.chip_accuracy[chip, r], by_fold)


def test_a_deployed_classifier_tested_on_its_training_frames_is_the_plain_cross_validation():
    _, reference, labels = _chips(n_chips=1)
    training = TrainingSpec(folds=4, epochs=3, batch_size=4, hidden_units=4)
    for model in (Model.FFNN, Model.CNN):
        plain = cross_validate(reference, labels, model, training, frame_s=0.1)
        deployed = validate_chips(reference[None], reference, labels, model, training, frame_s=0.1)
        for name in (
            "fold_accuracy",
            "train_loss",
            "predicted",
            "decision_predicted",
            "operations",
        ):
            assert np.array_equal(getattr(plain, name), getattr(deployed, name)), name
