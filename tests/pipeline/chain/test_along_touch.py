"""Training for decisions along the touch (``training.decisions``): the decision columns drawn
cover every column, each decoder's along-touch loss reads what it reads at decision time, the
``full_touch`` choice reproduces the code before the choice existed (computed floats within a
stated tolerance), and the choice keys the results as declared."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import torch
from hypothesis import given, settings
from hypothesis import strategies as st

from pipeline.chain.decoders import Preparation, decoder_of
from pipeline.chain.folded import fold_loss, on_prefixes, prefix
from pipeline.chain.models import fold_generator
from pipeline.chain.training import _decision_columns, cross_validate, fit_folds
from pipeline.design.scene import (
    DecisionTraining,
    Model,
    Scene,
    SNNInputs,
    SNNSpec,
    SNNTimeConstants,
    TrainingSpec,
)
from pipeline.run.stages import cache_key


def separable(shape, n_classes=4, per_class=10, seed=0, contrast=6.0):
    """Poisson counts, rate 1 plus ``contrast`` on the cells ``== k mod n_classes`` of class k."""
    rng = np.random.default_rng(seed)
    cell = np.arange(math.prod(shape)).reshape(shape)
    rates = 1.0 + contrast * (cell[None] % n_classes == np.arange(n_classes).reshape(-1, 1, 1, 1))
    labels = np.repeat(np.arange(n_classes), per_class)
    return rng.poisson(rates[labels]).astype(np.int64), labels.astype(np.int64)


@settings(max_examples=40, deadline=None)
@given(
    sizes=st.lists(st.integers(1, 30), min_size=1, max_size=4),
    epochs=st.integers(1, 4),
    n_columns=st.integers(1, 12),
    seed=st.integers(0, 2**63 - 1),
)
def test_every_decision_column_is_drawn_equally_often_in_every_epoch(
    sizes, epochs, n_columns, seed
):
    n_train = np.array(sizes, dtype=np.int64)
    folds = list(range(len(sizes)))
    ends = _decision_columns(seed, folds, n_train, epochs, n_columns, DecisionTraining.ALONG_TOUCH)
    assert ends.shape == (epochs, len(sizes), max(sizes)) and ends.dtype == torch.int64
    for epoch in range(epochs):
        for i, n in enumerate(sizes):
            counts = np.bincount(ends[epoch, i, :n].numpy(), minlength=n_columns)
            assert len(counts) == n_columns
            # every column when there are as many samples as columns; evenly spread always
            assert counts.max() - counts.min() <= 1
            assert counts.sum() == n
    assert (
        _decision_columns(seed, folds, n_train, epochs, n_columns, DecisionTraining.FULL_TOUCH)
        is None
    )


def test_the_drawn_columns_are_the_folds_own():
    """A fold's columns depend on its seed and index only, not on the folds trained with it."""
    n_train = np.array([9, 8], dtype=np.int64)
    both = _decision_columns(5, [0, 3], n_train, 2, 4, DecisionTraining.ALONG_TOUCH)
    alone = _decision_columns(5, [3], n_train[1:], 2, 4, DecisionTraining.ALONG_TOUCH)
    assert torch.equal(both[:, 1, :8], alone[:, 0, :8])


@pytest.mark.parametrize("model", [Model.FFNN, Model.CNN])
def test_a_rate_decoder_is_trained_on_the_frame_as_at_its_decision_time(model):
    """Its along-touch loss of a sample is the full-touch loss of the frame read up to the drawn
    column, as :func:`on_prefixes` reads it, blind to the later columns."""
    decoder = decoder_of(model)
    gens = [fold_generator(0, f, "init") for f in range(2)]
    net = decoder.build((1, 3, 6), 3, gens, 8, None)
    x = torch.randn(2, 5, 1, 3, 6, generator=torch.Generator().manual_seed(1))
    targets = torch.randint(0, 3, (2, 5), generator=torch.Generator().manual_seed(2))
    weights = torch.full((2, 5), 0.2)
    ends = torch.tensor([[0, 1, 2, 5, 3], [5, 4, 0, 2, 1]])
    along = decoder.loss(net, x, targets, weights, ends)
    # the prefix read at decision time, sample by sample
    logits, _ = on_prefixes(decoder.logits_and_operations, net, x)  # (F, B, W, n_classes)
    at_ends = logits.gather(2, ends.reshape(2, 5, 1, 1).expand(-1, -1, 1, 3)).squeeze(2)
    torch.testing.assert_close(along, fold_loss(at_ends, targets, weights))
    # blind to what comes after its column, not to its column
    later = x + (torch.arange(6) > ends.reshape(2, 5, 1, 1, 1)).to(x.dtype) * 7.0
    torch.testing.assert_close(decoder.loss(net, later, targets, weights, ends), along)
    at = x + (torch.arange(6) == ends.reshape(2, 5, 1, 1, 1)).to(x.dtype) * 7.0
    assert not torch.allclose(decoder.loss(net, at, targets, weights, ends), along)
    # the full touch is the prefix ending at the last column
    last = torch.full((2, 5), 5)
    torch.testing.assert_close(
        decoder.loss(net, x, targets, weights, last), decoder.loss(net, x, targets, weights)
    )
    assert torch.equal(prefix(x, last), x)


def test_the_snn_is_trained_on_its_decision_at_every_step():
    decoder = decoder_of(Model.SNN)
    spec = SNNSpec(step_s=0.01, hidden_neurons=6, tau_mem_s=0.05, threshold=0.5)
    net = decoder.build((2, 3, 7), 3, [fold_generator(0, f, "init") for f in range(2)], 0, spec)
    x = torch.poisson(torch.full((2, 4, 2, 3, 7), 2.0), generator=torch.Generator().manual_seed(3))
    targets = torch.tensor([[0, 1, 2, 0], [2, 2, 1, 0]])
    weights = torch.full((2, 4), 0.25)
    ends = torch.zeros((2, 4), dtype=torch.int64)
    along = decoder.loss(net, x, targets, weights, ends)
    logits = net.decision_logits(x)
    per_step = [fold_loss(logits[:, :, t], targets, weights) for t in range(7)]
    torch.testing.assert_close(along, torch.stack(per_step).mean(dim=0))
    torch.testing.assert_close(decoder.loss(net, x, targets, weights), per_step[-1])
    # and its gradient reaches the first layer through the early steps too
    (grad,) = torch.autograd.grad(along.sum(), net.w1)
    assert torch.isfinite(grad).all() and grad.abs().sum() > 0


def test_every_loss_of_along_touch_training_gets_its_columns():
    """fit_folds hands every mini-batch's drawn columns to the decoder's loss: over an epoch,
    every sample once, every column."""
    seen = []

    class Spy(type(decoder_of(Model.FFNN))):
        def loss(self, net, x, targets, weights, ends=None):
            seen.append(ends)
            return super().loss(net, x, targets, weights, ends)

    frames, labels = separable((1, 3, 5), per_class=6)
    x = frames.astype(np.float32)
    training = TrainingSpec(
        epochs=2, batch_size=4, hidden_units=4, decisions=DecisionTraining.ALONG_TOUCH
    )
    fit_folds([x], [labels], [0], Spy(), 4, training, 0)
    assert len(seen) == 2 * 6 and all(e is not None for e in seen)
    first_epoch = torch.cat([e.reshape(-1) for e in seen[:6]])
    assert len(first_epoch) == 24 and set(first_epoch.tolist()) == set(range(5))
    seen.clear()
    fit_folds(
        [x],
        [labels],
        [0],
        Spy(),
        4,
        training.__class__(
            epochs=2, batch_size=4, hidden_units=4, decisions=DecisionTraining.FULL_TOUCH
        ),
        0,
    )
    assert seen == [None] * 12


#: The arrays of the cross-validations below as the code gave them before training along the
#: touch existed (commit efff840's parent, one torch thread, an Intel Xeon with AVX-512), under
#: "<model>/<field>".
BEFORE = Path(__file__).resolve().parents[2] / "data" / "full_touch_before.npz"
#: Floats are computed by reductions whose order the CPU's kernels choose (torch's, MKL's and
#: oneDNN's SIMD paths), so they are compared within this relative tolerance (and
#: :data:`FLOAT_ATOL` near zero): torch's generic kernels against its AVX-512 ones, and MKL's
#: SSE4.2 path against its AVX-512 one, moved them by at most 2.3e-6 (measured with
#: ``ATEN_CPU_CAPABILITY=default`` and ``MKL_ENABLE_INSTRUCTIONS=SSE4_2``). Integers (the
#: predictions, the folds) are compared exactly. The spiking decoder trains for one epoch here:
#: its thresholds turn a last-bit difference into a spike more or less, which after two epochs
#: moved its confidences by 2e-3 on MKL's other path (after one, by nothing).
FLOAT_RTOL = 1e-5
FLOAT_ATOL = 1e-7
FIELDS = (
    "fold_accuracy",
    "train_loss",
    "predicted",
    "test_fold",
    "decision_s",
    "decision_predicted",
    "decision_confidence",
    "operations",
)


def same_arrays(got: dict[str, np.ndarray], want: dict[str, np.ndarray]) -> list[str]:
    """The fields of ``got`` that differ from ``want``: integers exactly, floats beyond
    :data:`FLOAT_RTOL` and :data:`FLOAT_ATOL`."""
    differ = []
    for field in FIELDS:
        a, b = got[field], want[field]
        if a.shape != b.shape or a.dtype != b.dtype:
            differ.append(field)
        elif a.dtype.kind == "f":
            if not np.allclose(a, b, rtol=FLOAT_RTOL, atol=FLOAT_ATOL, equal_nan=True):
                differ.append(field)
        elif not np.array_equal(a, b):
            differ.append(field)
    return differ


@pytest.mark.parametrize("model", [Model.FFNN, Model.CNN, Model.SNN])
def test_full_touch_reproduces_the_code_before_the_choice(model, request):
    threads = torch.get_num_threads()
    request.addfinalizer(lambda: torch.set_num_threads(threads))
    torch.set_num_threads(1)  # as the arrays were taken (and as the workers train)
    frames, labels = separable((2 if model is Model.SNN else 1, 3, 8))
    # the spiking decoder as it was first built: counts, at training.learning_rate, one shared
    # time constant
    spec = SNNSpec(
        step_s=0.01,
        hidden_neurons=6,
        tau_mem_s=0.05,
        epochs=1,
        inputs=SNNInputs.COUNTS,
        learning_rate=None,
        time_constants=SNNTimeConstants.SHARED,
    )
    common = dict(epochs=6, learning_rate=0.01, batch_size=8, folds=4, hidden_units=16, seed=3)
    training = TrainingSpec(
        models=(model,), repeats=2, snn=spec, decisions=DecisionTraining.ALONG_TOUCH, **common
    )
    full = training.__class__(
        models=(model,), repeats=2, snn=spec, decisions=DecisionTraining.FULL_TOUCH, **common
    )
    with np.load(BEFORE) as stored:
        before = {field: stored[f"{model.value}/{field}"] for field in FIELDS}
    arrays = {}
    for name, t in (("full", full), ("along", training)):
        cv = cross_validate(frames, labels, model, t, frame_s=0.01)
        arrays[name] = {field: np.asarray(getattr(cv, field)) for field in FIELDS}
    assert same_arrays(arrays["full"], before) == []
    assert same_arrays(arrays["along"], before) != []  # along the touch trains otherwise


def test_the_choice_keys_the_results_and_full_touch_keeps_the_old_keys():
    paper = Scene.paper()
    assert paper.training.decisions is DecisionTraining.ALONG_TOUCH  # the default
    full = paper.replace(**{"training.decisions": "full_touch"})
    assert "decisions" not in full.canonical(("training",))
    assert '"decisions":"along_touch"' in paper.canonical(("training",)).replace(" ", "")
    assert cache_key(full, "rates") == cache_key(paper, "rates")
    assert cache_key(full, "results") != cache_key(paper, "results")
    # the snn's inputs as first built, counts, keep their keys too
    snn = paper.replace(**{"training.models": ["snn"]})
    counts = snn.replace(**{"training.snn.inputs": "counts"})
    assert "inputs" not in counts.canonical(("training",))
    assert '"inputs":"standardized"' in snn.canonical(("training",)).replace(" ", "")
    assert cache_key(counts, "results") != cache_key(snn, "results")


def test_the_snn_prepares_its_counts_as_its_inputs_field_says():
    train = np.array([[0, 1, 3]], dtype=np.int64)
    test = np.array([[7, 0, 0]], dtype=np.int64)
    snn = decoder_of(Model.SNN)
    for inputs, preparation in (
        (SNNInputs.COUNTS, Preparation.COUNTS),
        (SNNInputs.LOG_COUNTS, Preparation.LOG_COUNTS),
        (SNNInputs.STANDARDIZED, Preparation.STANDARDIZED),
    ):
        training = TrainingSpec(snn=SNNSpec(inputs=inputs))
        got = snn.prepare(train, test, training)
        want = preparation.apply(train, test)
        for a, b in zip(got, want, strict=True):
            assert a.dtype == np.float32
            np.testing.assert_array_equal(a, b)
    np.testing.assert_allclose(
        Preparation.LOG_COUNTS.apply(train, test)[1], np.log1p([[7.0, 0.0, 0.0]]), rtol=1e-7
    )


def test_the_snn_has_a_learning_rate_of_its_own_unless_unset():
    assert decoder_of(Model.SNN).learning_rate(TrainingSpec(learning_rate=0.002)) == 0.01
    training = TrainingSpec(learning_rate=0.002, snn=SNNSpec(learning_rate=None))
    assert decoder_of(Model.SNN).learning_rate(training) == 0.002
    assert decoder_of(Model.FFNN).learning_rate(training) == 0.002
    own = TrainingSpec(learning_rate=0.002, snn=SNNSpec(learning_rate=0.05))
    assert decoder_of(Model.SNN).learning_rate(own) == 0.05
    assert decoder_of(Model.CNN).learning_rate(own) == 0.002
    snn = Scene.paper().replace(**{"training.models": ["snn"]})
    assert '"learning_rate":0.01' in snn.canonical(("training.snn",)).replace(" ", "")
    slower = snn.replace(**{"training.snn.learning_rate": 0.001})
    assert cache_key(slower, "results") != cache_key(snn, "results")
