"""The spiking decoder: its neuron against plain autograd, fold batching, decisions in time."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import torch

from pipeline.chain.decoders import build_model, decoder_of
from pipeline.chain.models import fold_generator
from pipeline.chain.spiking import LeakyLayer
from pipeline.chain.training import cross_validate
from pipeline.design.scene import (
    DecisionTraining,
    Model,
    SNNAlongLoss,
    SNNInputs,
    SNNReadout,
    SNNSpec,
    SNNTimeConstants,
    TrainingSpec,
)


@pytest.fixture(autouse=True)
def one_thread():
    """One torch thread, as the workers train (several threads only contend on a busy CPU)."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    yield
    torch.set_num_threads(threads)


class _Spike(torch.autograd.Function):
    """Heaviside with the fast-sigmoid surrogate, as snnTorch's ``surrogate.fast_sigmoid``."""

    @staticmethod
    def forward(ctx, v, slope):
        ctx.save_for_backward(v)
        ctx.slope = slope
        return (v > 0).to(v.dtype)

    @staticmethod
    def backward(ctx, grad):
        (v,) = ctx.saved_tensors
        return grad / (1 + ctx.slope * v.abs()) ** 2, None


def _reference(current, beta, threshold, slope):
    """The module docstring's equations as a plain autograd loop over ``current (T, N)``."""
    u = torch.zeros(current.shape[1])
    s = torch.zeros(current.shape[1])
    out = []
    for step in current.unbind(0):
        u = beta * u + step - threshold * s.detach()
        s = _Spike.apply(u - threshold, slope)
        out.append(s)
    return torch.stack(out)


def test_the_kernel_neuron_is_the_autograd_neuron():
    g = torch.Generator().manual_seed(0)
    current = (torch.rand(60, 25, generator=g) * 1.5).requires_grad_()
    weight = torch.randn(60, 25, generator=g)
    rate_weight = torch.randn(25, generator=g)
    spikes, rate = LeakyLayer.apply(current.unsqueeze(0), 0.9, 1.0, 25.0)
    loss = (spikes[0] * weight).sum() + (rate[0] * rate_weight).sum()
    (grad,) = torch.autograd.grad(loss, current)
    expected = _reference(current, 0.9, 1.0, 25.0)
    expected_loss = (expected * weight).sum() + (expected.mean(dim=0) * rate_weight).sum()
    (expected_grad,) = torch.autograd.grad(expected_loss, current, retain_graph=True)
    assert 0.2 < float(spikes.detach().mean()) < 0.8  # both spiking and silent steps are exercised
    assert torch.equal(spikes[0], expected)
    torch.testing.assert_close(rate[0], expected.mean(dim=0).detach())
    torch.testing.assert_close(grad, expected_grad, rtol=1e-4, atol=1e-5)
    # Without the spikes kept (training reads only the rate): the same rate and gradient.
    _, alone = LeakyLayer.apply(current.unsqueeze(0), 0.9, 1.0, 25.0, False)
    (grad_alone,) = torch.autograd.grad((alone[0] * rate_weight).sum(), current)
    (expected_alone,) = torch.autograd.grad((expected.mean(dim=0) * rate_weight).sum(), current)
    torch.testing.assert_close(alone, rate)
    torch.testing.assert_close(grad_alone, expected_alone, rtol=1e-4, atol=1e-5)


def test_a_learned_decay_has_the_autograd_gradient():
    g = torch.Generator().manual_seed(2)
    current = (torch.rand(3, 50, 10, generator=g) * 1.5).requires_grad_()
    beta = (0.5 + 0.45 * torch.rand(3, 10, generator=g)).requires_grad_()
    weight = torch.randn(3, 50, 10, generator=g)
    spikes, rate = LeakyLayer.apply(current, beta, 1.0, 25.0)
    loss = (spikes * weight).sum() + rate.sum()
    grad_current, grad_beta = torch.autograd.grad(loss, (current, beta))
    expected = torch.stack([_reference(current[m], beta[m], 1.0, 25.0) for m in range(3)])
    expected_loss = (expected * weight).sum() + expected.mean(dim=1).sum()
    expected_current, expected_beta = torch.autograd.grad(expected_loss, (current, beta))
    assert torch.equal(spikes, expected)
    assert float(grad_beta.abs().min()) > 0  # every neuron's decay gets a gradient
    torch.testing.assert_close(grad_current, expected_current, rtol=1e-4, atol=1e-5)
    torch.testing.assert_close(grad_beta, expected_beta, rtol=1e-4, atol=1e-4)
    # A fixed decay given as a tensor that needs no gradient: the float's spikes.
    fixed, _ = LeakyLayer.apply(current[:1], torch.full((1, 10), 0.9), 1.0, 25.0)
    assert torch.equal(fixed, LeakyLayer.apply(current[:1], 0.9, 1.0, 25.0)[0])


def test_a_layer_stopped_at_a_step_is_the_mean_and_gradient_up_to_it():
    g = torch.Generator().manual_seed(6)
    current = (torch.rand(3, 30, 10, generator=g) * 1.5).requires_grad_()
    ends = torch.tensor([0, 11, 29])
    rate_weight = torch.randn(3, 10, generator=g)
    _, rate = LeakyLayer.apply(current, 0.9, 1.0, 25.0, False, ends)
    (grad,) = torch.autograd.grad((rate * rate_weight).sum(), current)
    for m, k in enumerate(ends.tolist()):
        expected = _reference(current[m], 0.9, 1.0, 25.0)[: k + 1].mean(dim=0)
        (expected_grad,) = torch.autograd.grad((expected * rate_weight[m]).sum(), current)
        torch.testing.assert_close(rate[m], expected.detach())
        torch.testing.assert_close(grad[m], expected_grad[m], rtol=1e-4, atol=1e-5)
        assert torch.all(grad[m, k + 1 :] == 0)


@pytest.mark.parametrize("readout", [SNNReadout.MEAN_CURRENT, SNNReadout.MAX_MEMBRANE])
def test_the_decision_at_a_drawn_step_is_that_steps_decision(readout):
    x = torch.poisson(torch.full((2, 3, 2, 3, 20), 0.5), generator=torch.Generator().manual_seed(7))
    spec = dataclasses.replace(SPEC, threshold=0.3, readout=readout)
    net = build_model(
        "snn", (2, 3, 20), 4, 0, 2, [fold_generator(0, f, "init") for f in (0, 1)], spec
    )
    ends = torch.tensor([[0, 5, 19], [3, 19, 7]])
    with torch.no_grad():
        every = net.decision_logits(x)
        expected = every[torch.arange(2).reshape(2, 1), torch.arange(3).reshape(1, 3), ends]
        torch.testing.assert_close(net.logits_at(x, ends), expected, rtol=1e-5, atol=1e-5)


SPEC = SNNSpec(step_s=0.01, hidden_neurons=8, tau_mem_s=0.05, epochs=40)


@pytest.mark.parametrize(
    ("hidden_layers", "time_constants", "loss"),
    [
        (1, SNNTimeConstants.SHARED, SNNAlongLoss.EVERY_STEP),
        (2, SNNTimeConstants.SHARED, SNNAlongLoss.EVERY_STEP),
        (1, SNNTimeConstants.LEARNED, SNNAlongLoss.EVERY_STEP),
        (1, SNNTimeConstants.SHARED, SNNAlongLoss.EARLY_STEPS),
    ],
)
def test_every_steps_loss_of_the_mean_readout_is_the_autograd_loss_of_every_decision(
    hidden_layers, time_constants, loss
):
    x = torch.poisson(torch.full((2, 3, 2, 3, 20), 0.5), generator=torch.Generator().manual_seed(8))
    spec = dataclasses.replace(
        SPEC,
        threshold=0.3,
        hidden_layers=hidden_layers,
        time_constants=time_constants,
        along_touch_loss=loss,
    )
    net = build_model(
        "snn", (2, 3, 20), 4, 0, 2, [fold_generator(0, f, "init") for f in (0, 1)], spec
    )
    targets = torch.tensor([[0, 1, 3], [2, 2, 1]])
    weights = torch.tensor([[0.5, 0.5, 0.0], [1 / 3, 1 / 3, 1 / 3]])  # padding weighs 0
    scale = torch.tensor([[1.0, -2.0, 3.0], [0.5, 1.0, 4.0]])  # every sample its own gradient
    losses = net.step_losses(x, targets)
    logits = net.decision_logits(x)  # (F, B, T, classes), in plain autograd
    every = torch.nn.functional.cross_entropy(
        logits.reshape(-1, 4), targets.unsqueeze(2).expand(-1, -1, 20).reshape(-1), reduction="none"
    )
    step = torch.arange(1.0, 21.0)
    weights_t = step**-0.5 if loss is SNNAlongLoss.EARLY_STEPS else torch.ones(20)
    expected = (every.reshape(2, 3, 20) * weights_t).sum(dim=2) / weights_t.sum()
    params = list(net.parameters())
    grads = torch.autograd.grad((losses * scale).sum(), params)
    expected_grads = torch.autograd.grad((expected * scale).sum(), params)
    spikes, _ = net.hidden_spikes(x)
    assert 0.05 < float(spikes.detach().mean()) < 0.95  # the loss reads spiking and silent steps
    torch.testing.assert_close(losses, expected, rtol=1e-5, atol=1e-6)
    for grad, want in zip(grads, expected_grads, strict=True):
        assert float(want.abs().max()) > 0
        torch.testing.assert_close(grad, want, rtol=1e-4, atol=1e-6)
    decoder = decoder_of(Model.SNN)
    ends = torch.zeros((2, 3), dtype=torch.int64)  # along the touch: every step is weighed
    torch.testing.assert_close(
        decoder.loss(net, x, targets, weights, ends), (expected * weights).sum(dim=1)
    )


def test_folds_are_independent_and_the_last_decision_is_the_forward_pass():
    x = torch.poisson(torch.full((3, 4, 2, 3, 20), 0.3), generator=torch.Generator().manual_seed(1))
    batch = build_model(
        "snn", (2, 3, 20), 4, 0, 3, [fold_generator(0, f, "init") for f in range(3)], SPEC
    )
    alone = build_model("snn", (2, 3, 20), 4, 0, 1, [fold_generator(0, 1, "init")], SPEC)
    with torch.no_grad():
        torch.testing.assert_close(batch(x)[1:2], alone(x[1:2]))
        every = batch.decision_logits(x)
        assert every.shape == (3, 4, 20, 4)
        torch.testing.assert_close(every[:, :, -1], batch(x))


def test_learned_time_constants_start_as_the_shared_one_and_get_a_gradient():
    x = torch.poisson(torch.full((2, 3, 2, 3, 20), 0.5), generator=torch.Generator().manual_seed(4))
    spec = dataclasses.replace(SPEC, threshold=0.3)
    nets = [
        build_model(
            "snn",
            (2, 3, 20),
            4,
            0,
            2,
            [fold_generator(0, f, "init") for f in (0, 1)],
            dataclasses.replace(spec, time_constants=choice),
        )
        for choice in SNNTimeConstants
    ]
    shared, learned = nets
    assert [n for n, _ in learned.named_parameters()] == ["w1", "b1", "w2", "b2", "log_tau_s"]
    torch.testing.assert_close(learned.log_tau_s, torch.full((2, 1, 8), np.log(0.05)))
    torch.testing.assert_close(learned(x), shared(x))  # same draw, same decays at the start
    (grad,) = torch.autograd.grad(learned(x).logsumexp(-1).sum(), learned.log_tau_s)
    assert grad.shape == (2, 1, 8) and int((grad != 0).sum()) >= 8


def test_a_second_layer_is_driven_by_the_first_layers_spikes():
    x = torch.poisson(torch.full((2, 3, 2, 3, 20), 0.5), generator=torch.Generator().manual_seed(5))
    spec = dataclasses.replace(SPEC, threshold=0.3)
    generators = [fold_generator(0, f, "init") for f in (0, 1)]
    one = build_model("snn", (2, 3, 20), 4, 0, 2, generators, spec)
    generators = [fold_generator(0, f, "init") for f in (0, 1)]
    two = build_model(
        "snn", (2, 3, 20), 4, 0, 2, generators, dataclasses.replace(spec, hidden_layers=2)
    )
    for name in ("w1", "b1", "w2", "b2"):  # the first layers are drawn as a one-layer decoder's
        assert torch.equal(getattr(one, name), getattr(two, name))
    assert two.wh.shape == (2, 1, 8, 8) and two.bh.shape == (2, 1, 8)
    with torch.no_grad():
        (first, _), (second, rate) = two.layer_spikes(x)
        assert torch.equal(first, one.hidden_spikes(x)[0])
        current = first @ two.wh[:, 0].unsqueeze(1) + two.bh[:, 0].reshape(2, 1, 1, 8)
        expected, _ = LeakyLayer.apply(current.reshape(6, 20, 8), two.beta, 0.3, 25.0)
        assert 0 < float(second.mean()) < 1
        assert torch.equal(second, expected.reshape(2, 3, 20, 8))
        torch.testing.assert_close(two(x), rate @ two.w2.unsqueeze(1)[:, 0] + two.b2.unsqueeze(1))
        torch.testing.assert_close(two.decision_logits(x)[:, :, -1], two(x))


@pytest.mark.parametrize("inputs", list(SNNInputs))
def test_only_event_counts_are_counted_as_events(inputs):
    spec = dataclasses.replace(SPEC, inputs=inputs)
    net = build_model("snn", (2, 3, 20), 4, 0, 1, [fold_generator(0, 0, "init")], spec)
    assert net.events_in is (inputs is SNNInputs.COUNTS)


@pytest.mark.parametrize("readout", list(SNNReadout))
def test_each_readout_is_its_equation_and_the_last_decision_is_the_forward_pass(readout):
    x = torch.poisson(torch.full((2, 3, 2, 3, 20), 0.5), generator=torch.Generator().manual_seed(3))
    spec = dataclasses.replace(SPEC, readout=readout, threshold=0.3)
    net = build_model(
        "snn", (2, 3, 20), 4, 0, 2, [fold_generator(0, f, "init") for f in (0, 1)], spec
    )
    with torch.no_grad():
        every = net.decision_logits(x)
        spikes, _ = net.hidden_spikes(x)
        out = spikes @ net.w2.unsqueeze(1) + net.b2.reshape(2, 1, 1, 4)  # (F, B, T, classes)
        assert float(spikes.mean()) > 0.05  # the readout reads spikes
        expected, membrane, peak = [], torch.zeros_like(out[:, :, 0]), None
        for t in range(20):
            membrane = net.beta * membrane + (1 - net.beta) * out[:, :, t]
            peak = membrane if peak is None else torch.maximum(peak, membrane)
            expected.append(
                {
                    SNNReadout.MEAN_CURRENT: out[:, :, : t + 1].mean(dim=2),
                    SNNReadout.LAST_MEMBRANE: membrane,
                    SNNReadout.MAX_MEMBRANE: peak,
                }[readout]
            )
        torch.testing.assert_close(every, torch.stack(expected, dim=2), rtol=1e-5, atol=1e-5)
        torch.testing.assert_close(net(x), every[:, :, -1], rtol=1e-5, atol=1e-5)


def _two_textures(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """20 recordings of 2 classes: ON events on taxel 0 or on taxel 1, Poisson per step."""
    labels = np.repeat([0, 1], 10)
    rate = np.full((20, 2, 2, 30), 0.05)
    rate[labels == 0, 0, 0] = 0.8
    rate[labels == 1, 0, 1] = 0.8
    return rng.poisson(rate), labels


@pytest.mark.parametrize("loss", list(SNNAlongLoss))
def test_the_snn_learns_along_the_touch_with_each_loss(loss):
    counts, labels = _two_textures(np.random.default_rng(2))
    spec = dataclasses.replace(SPEC, along_touch_loss=loss)
    training = TrainingSpec(
        models=(Model.SNN,),
        folds=4,
        batch_size=5,
        learning_rate=1e-2,
        snn=spec,
        decisions=DecisionTraining.ALONG_TOUCH,
    )
    cv = cross_validate(counts, labels, Model.SNN, training, frame_s=SPEC.step_s)
    assert cv.mean >= 0.9, cv.fold_accuracy


def test_the_snn_learns_and_decides_at_every_step():
    counts, labels = _two_textures(np.random.default_rng(0))
    # A larger step than the default 1e-3: 4 folds of 15 recordings take few steps per epoch.
    training = TrainingSpec(
        models=(Model.SNN,), folds=4, batch_size=5, learning_rate=1e-2, snn=SPEC
    )
    cv = cross_validate(counts, labels, Model.SNN, training, frame_s=SPEC.step_s)
    assert cv.mean >= 0.9, cv.fold_accuracy
    assert np.allclose(cv.decision_s, 0.01 * np.arange(1, 31))
    assert cv.decision_predicted.shape == cv.decision_confidence.shape == (1, 30, 20)
    assert np.array_equal(cv.decision_predicted[:, -1], cv.predicted)
    assert np.all((cv.decision_confidence >= 0.5) & (cv.decision_confidence <= 1))
    acs, macs, updates = cv.operations.T
    # Standardized inputs (the default) are real numbers: MACs in, the hidden spikes' ACs out.
    assert np.all(np.diff(acs) >= 0) and np.all(np.diff(macs) >= 0) and macs[-1] > 0
    assert np.array_equal(updates, np.arange(1, 31) * (8 + 2))


def test_rate_models_decide_on_prefixes_at_window_ends():
    counts, labels = _two_textures(np.random.default_rng(1))
    frames = counts.reshape(20, 2, 2, 6, 5).sum(axis=-1)  # 6 windows of 5 steps
    training = TrainingSpec(folds=4, epochs=30, batch_size=5, hidden_units=8)
    for model in (Model.FFNN, Model.CNN):
        cv = cross_validate(frames, labels, model, training, frame_s=0.05)
        plain = cross_validate(frames, labels, model, training)
        assert np.array_equal(cv.predicted, plain.predicted)  # reading decisions changes nothing
        assert np.allclose(cv.decision_s, 0.05 * np.arange(1, 7))
        assert np.array_equal(cv.decision_predicted[:, -1], cv.predicted)
        assert np.all(cv.operations[:, 0] == 0) and np.all(cv.operations[:, 1] > 0)
        assert np.all(np.diff(cv.operations[:, 1]) >= 0) or model is Model.CNN
