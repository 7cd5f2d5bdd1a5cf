"""Cross-validation: splits, training-fold-only statistics, loss and optimizer, batched training
equal to fold-by-fold training, learning, degenerate inputs and errors."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from pipeline.chain.decoders import build_model
from pipeline.chain.models import fold_generator
from pipeline.chain.training import (
    CrossValidation,
    FoldAdam,
    cross_validate,
    repeat_seed,
    stratified_folds,
)
from pipeline.design.scene import Model, TrainingSpec
from pipeline.errors import SimulationError

#: The rate-coded classifiers (the snn has tests of its own, tests/pipeline/chain/test_spiking.py).
RATE_MODELS = [Model.FFNN, Model.CNN]

SMALL = TrainingSpec(epochs=30, learning_rate=0.01, batch_size=16, folds=5, hidden_units=16, seed=3)


def separable(n_classes=4, per_class=10, shape=(1, 3, 8), seed=0, extra=0, contrast=6.0):
    """Poisson counts: rate 1 everywhere plus ``contrast`` on the cells (raster index)
    ``== k mod n_classes`` for class k: disjoint patterns, well separated by default."""
    rng = np.random.default_rng(seed)
    cell = np.arange(math.prod(shape)).reshape(shape)
    rates = 1.0 + contrast * (cell[None] % n_classes == np.arange(n_classes).reshape(-1, 1, 1, 1))
    labels = np.r_[np.repeat(np.arange(n_classes), per_class), np.arange(extra) % n_classes]
    return rng.poisson(rates[labels]).astype(np.int64), labels.astype(np.int64)


# --------------------------------------------------------------------------------------------
# optimizer


def _quadratic_grads(params, targets):
    return [2 * (p - t) for p, t in zip(params, targets, strict=True)]


def test_fold_adam_matches_torch_adam():
    gen = torch.Generator().manual_seed(0)
    params = [torch.randn(1, 5, 3, generator=gen), torch.randn(1, 3, generator=gen)]
    targets = [torch.randn(p.shape, generator=gen) for p in params]
    reference = [p[0].clone().requires_grad_(True) for p in params]
    adam = torch.optim.Adam(reference, lr=0.01)
    ours = FoldAdam(params, lr=0.01)
    for _ in range(25):
        ours.step(_quadratic_grads(params, targets))
        adam.zero_grad(set_to_none=True)
        for r, g in zip(
            reference, _quadratic_grads(reference, [t[0] for t in targets]), strict=True
        ):
            r.grad = g.detach()
        adam.step()
    for p, r in zip(params, reference, strict=True):
        torch.testing.assert_close(p[0], r.detach(), rtol=1e-6, atol=1e-6)


def test_fold_adam_skipped_fold_is_untouched_and_others_unaffected():
    gen = torch.Generator().manual_seed(1)
    both = [torch.randn(2, 4, generator=gen)]
    alone = [both[0][1:].clone()]
    targets = [torch.zeros(2, 4)]
    opt_both, opt_alone = FoldAdam(both, lr=0.1), FoldAdam(alone, lr=0.1)
    for step in range(6):
        skip = step in (2, 3)
        before = both[0][0].clone()
        opt_both.step(_quadratic_grads(both, targets), [not skip, True])
        opt_alone.step(_quadratic_grads(alone, [targets[0][1:]]))
        if skip:
            assert torch.equal(both[0][0], before)
    assert opt_both.steps.tolist() == [4, 6]
    assert torch.equal(both[0][1], alone[0][0])


def test_fold_adam_moves_parameters_into_its_buffer_and_steps_them_in_place():
    net = build_model(
        Model.CNN, (1, 3, 8), 4, 4, 3, [fold_generator(0, f, "init") for f in range(3)]
    )
    params = list(net.parameters())
    before = [p.detach().clone() for p in params]
    optimizer = FoldAdam(params, lr=0.01)
    assert all(p is q for p, q in zip(params, net.parameters(), strict=True))
    for p, b in zip(params, before, strict=True):
        assert torch.equal(p, b)  # same values and shape, now a view of the buffer
    x = torch.randn(3, 2, 1, 3, 8, generator=torch.Generator().manual_seed(0))
    grads = torch.autograd.grad(net(x).square().sum(), params)
    optimizer.step(grads, [True, False, True])
    for p, b in zip(params, before, strict=True):
        assert torch.equal(p[1], b[1])  # the skipped fold
        assert not torch.equal(p[0], b[0]) and not torch.equal(p[2], b[2])
        # Adam's first step moves every element with a non-zero gradient by lr.
        torch.testing.assert_close((p - b)[0].abs().max(), torch.tensor(0.01), rtol=1e-4, atol=0)


# --------------------------------------------------------------------------------------------
# cross-validation


def test_stratified_folds_partition_and_stratify():
    labels = np.repeat(np.arange(3), 7)
    splits = stratified_folds(labels, 5, seed=0)
    tests = np.concatenate([te for _, te in splits])
    assert sorted(tests.tolist()) == list(range(21))
    for train, test in splits:
        assert set(train).isdisjoint(test)
        assert np.bincount(labels[test], minlength=3).max() <= 2  # 7 per class over 5 folds
    again = stratified_folds(labels, 5, seed=0)
    assert all(np.array_equal(a[1], b[1]) for a, b in zip(splits, again, strict=True))
    assert stratified_folds(labels, 5, seed=2**40)  # seeds beyond 32 bits are accepted


@pytest.mark.parametrize("model", RATE_MODELS)
def test_learns_separable_classes(model):
    frames, labels = separable()
    cv = cross_validate(frames, labels, model, SMALL)
    assert isinstance(cv, CrossValidation)
    assert cv.fold_accuracy.shape == (1, 5) and cv.fold_accuracy.dtype == np.float64
    assert cv.mean > 0.9, cv.fold_accuracy
    assert cv.seconds > 0
    assert np.isfinite(cv.train_loss).all()


@pytest.mark.parametrize("model", RATE_MODELS)
def test_out_of_fold_predictions_agree_with_fold_accuracy(model):
    """Every recording is tested once per repeat; its fold's accuracy is the fraction of that
    fold's recordings whose out-of-fold prediction equals the label."""
    frames, labels = separable(extra=1, contrast=0.7)  # hard enough for errors
    labels = np.array([3, 7, 42, 50])[labels]  # predictions are in the caller's labels
    spec = TrainingSpec(epochs=4, batch_size=8, folds=5, hidden_units=8, seed=5, repeats=2)
    cv = cross_validate(frames, labels, model, spec)
    assert cv.predicted.shape == cv.test_fold.shape == (2, len(labels))
    assert set(np.unique(cv.predicted)) <= {3, 7, 42, 50}
    for repeat in range(2):
        splits = stratified_folds(
            np.unique(labels, return_inverse=True)[1], 5, repeat_seed(5, repeat)
        )
        for fold, (_, test) in enumerate(splits):
            np.testing.assert_array_equal(
                np.flatnonzero(cv.test_fold[repeat] == fold), np.sort(test)
            )
            correct = cv.predicted[repeat, test] == labels[test]
            assert cv.fold_accuracy[repeat, fold] == correct.mean()
    assert not np.array_equal(cv.test_fold[0], cv.test_fold[1])  # a fresh split per repeat


def test_first_repeat_is_the_single_cross_validation():
    """Repeat 0 uses the training seed itself: ``repeats = 1`` is the paper's procedure, and
    more repeats only add rows."""
    frames, labels = separable(seed=2)
    one = TrainingSpec(epochs=3, batch_size=8, folds=5, hidden_units=8, seed=11)
    three = TrainingSpec(**{**vars(one), "repeats": 3})
    a = cross_validate(frames, labels, Model.FFNN, one)
    b = cross_validate(frames, labels, Model.FFNN, three)
    assert b.fold_accuracy.shape == (3, 5)
    np.testing.assert_array_equal(a.fold_accuracy[0], b.fold_accuracy[0])
    np.testing.assert_array_equal(a.predicted[0], b.predicted[0])
    assert repeat_seed(11, 0) == 11
    assert len({repeat_seed(11, r) for r in range(50)}) == 50
    assert all(0 <= repeat_seed(2**63 - 1, r) < 2**63 for r in range(5))


def test_label_shuffled_noise_is_near_chance():
    rng = np.random.default_rng(5)
    frames = rng.poisson(3.0, size=(40, 1, 3, 8))
    labels = rng.permutation(np.repeat(np.arange(4), 10))
    cv = cross_validate(frames, labels, Model.FFNN, SMALL)
    # Chance is 0.25; 40 test predictions in all, so 0.5 is > 3 standard deviations away.
    assert cv.mean < 0.5, cv.fold_accuracy


@pytest.mark.parametrize("model", RATE_MODELS)
def test_batched_equals_sequential_with_unequal_fold_sizes(model):
    """41 recordings in 5 folds: training sets of 32 and 33, i.e. 2 and 3 mini-batches of 16, so
    the batched run pads fold 0 with a whole empty mini-batch that it must skip.

    Measured: FFNN gives bit-identical results; the CNN's grouped convolutions sum in another
    order than single-fold convolutions, so its last-epoch losses differ by ~1e-7. Asserted:
    fold accuracies exactly equal, losses within 1e-5."""
    frames, labels = separable(extra=1, contrast=0.7)  # hard enough for errors
    sizes = [len(train) for train, _ in stratified_folds(labels, 5, SMALL.seed)]
    assert sorted(sizes) == [32, 33, 33, 33, 33]
    batched = cross_validate(frames, labels, model, SMALL)
    sequential = cross_validate(frames, labels, model, SMALL, batched=False)
    assert batched.mean < 1  # the comparison is not trivially 1 == 1
    np.testing.assert_array_equal(batched.fold_accuracy, sequential.fold_accuracy)
    np.testing.assert_array_equal(batched.predicted, sequential.predicted)
    np.testing.assert_allclose(batched.train_loss, sequential.train_loss, rtol=0, atol=1e-5)


def test_same_seed_same_result_other_seed_other_result():
    frames, labels = separable(seed=2)
    spec = TrainingSpec(epochs=5, batch_size=8, folds=5, hidden_units=8, seed=11)
    a = cross_validate(frames, labels, Model.FFNN, spec)
    b = cross_validate(frames, labels, Model.FFNN, spec)
    np.testing.assert_array_equal(a.fold_accuracy, b.fold_accuracy)
    np.testing.assert_array_equal(a.train_loss, b.train_loss)
    c = cross_validate(frames, labels, Model.FFNN, TrainingSpec(**{**vars(spec), "seed": 12}))
    assert not np.array_equal(a.train_loss, c.train_loss)


CROSS_PROCESS = """
import json, sys, torch
torch.set_num_threads(1)
sys.path.insert(0, {tests!r})
from test_training import separable
from pipeline.design.scene import Model, TrainingSpec
from pipeline.chain.training import cross_validate
frames, labels = separable(extra=1, contrast=0.7)
spec = TrainingSpec(epochs=4, batch_size=8, folds=5, hidden_units=8, seed=5)
out = {{}}
for model in (Model.FFNN, Model.CNN):
    cv = cross_validate(frames, labels, model, spec)
    out[model.value] = [cv.fold_accuracy.tolist(), cv.train_loss.tolist()]
print(json.dumps(out))
"""


@pytest.fixture
def one_thread():
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


def test_same_seed_bit_identical_in_another_process(one_thread):
    """One torch thread, as the workers run: another process gives the very same floats."""
    code = CROSS_PROCESS.format(tests=str(Path(__file__).parent))
    other = subprocess.run(
        [sys.executable, "-c", code], check=True, capture_output=True, text=True
    ).stdout
    frames, labels = separable(extra=1, contrast=0.7)
    spec = TrainingSpec(epochs=4, batch_size=8, folds=5, hidden_units=8, seed=5)
    for model, (accuracy, loss) in json.loads(other).items():
        cv = cross_validate(frames, labels, Model(model), spec)
        assert cv.fold_accuracy.tolist() == accuracy  # JSON round-trips float64 exactly
        assert cv.train_loss.tolist() == loss


@pytest.mark.parametrize("model", RATE_MODELS)
def test_zero_spike_frames_train_without_nan(model):
    frames = np.zeros((20, 1, 1, 3), dtype=np.int64)  # one taxel, three windows, no spikes
    labels = np.repeat(np.arange(2), 10)
    spec = TrainingSpec(epochs=10, batch_size=4, folds=5, hidden_units=4, seed=0)
    cv = cross_validate(frames, labels, model, spec)
    assert np.isfinite(cv.fold_accuracy).all()
    assert ((cv.fold_accuracy >= 0) & (cv.fold_accuracy <= 1)).all()
    assert np.isfinite(cv.train_loss).all()
    assert np.all(np.abs(cv.train_loss - math.log(2)) < 0.2)  # nothing to learn but the prior


def test_class_with_too_few_recordings_is_named():
    frames, labels = separable(n_classes=3, per_class=6)
    labels = labels.copy()
    labels[np.flatnonzero(labels == 1)[:3]] = 0  # class 1 keeps 3 recordings < 5 folds
    spec = TrainingSpec(folds=5)
    with pytest.raises(SimulationError, match=r"'felt' \(3\) has fewer recordings than") as err:
        cross_validate(frames, labels, Model.FFNN, spec, class_names=["cork", "felt", "silk"])
    assert "\n" not in str(err.value)
    with pytest.raises(SimulationError, match=r"class 1 \(3\)"):
        cross_validate(frames, labels, Model.FFNN, spec)


def test_fewer_than_two_classes_is_an_error():
    frames = np.zeros((10, 1, 2, 2))
    with pytest.raises(SimulationError, match="at least 2 classes, got 1 \\('cork'\\)"):
        cross_validate(
            frames, np.zeros(10, dtype=np.int64), Model.FFNN, SMALL, class_names=["cork"]
        )


def test_arbitrary_integer_labels_and_float_frames():
    frames, labels = separable(n_classes=3)
    labels = np.array([3, 7, 42])[labels]
    cv = cross_validate(frames.astype(np.float64), labels, Model.FFNN, SMALL)
    assert cv.fold_accuracy.shape == (1, 5)


def test_bad_shapes_are_rejected():
    frames, labels = separable()
    with pytest.raises(ValueError, match="frames must be"):
        cross_validate(frames[:, 0], labels, Model.FFNN, SMALL)
    with pytest.raises(ValueError, match="labels must be"):
        cross_validate(frames, labels[:-1], Model.FFNN, SMALL)


def test_cross_validation_summary():
    cv = CrossValidation(Model.CNN, np.array([0.5, 1.0, 0.75, 0.75]), 1.0)
    assert cv.fold_accuracy.shape == (1, 4)  # one fold row is one repeat
    assert cv.mean == pytest.approx(0.75)
    assert cv.std == pytest.approx(np.sqrt(0.125 / 4))  # population std, ddof=0
    with pytest.raises(ValueError):
        cv.fold_accuracy[0] = 0.0


def test_training_does_not_touch_global_rng():
    torch.manual_seed(123)
    expected = torch.rand(3)
    torch.manual_seed(123)
    frames, labels = separable()
    cross_validate(frames, labels, Model.CNN, TrainingSpec(epochs=2, folds=5, hidden_units=4))
    build_model(Model.FFNN, (1, 3, 8), 4, 4, 2, [fold_generator(0, f, "init") for f in range(2)])
    assert torch.equal(torch.rand(3), expected)
