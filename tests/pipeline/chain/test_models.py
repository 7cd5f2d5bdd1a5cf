"""Fold-batched FFNN and CNN: shapes, per-fold initialization, fold independence, and equality
with the textbook single-model PyTorch layers."""

from __future__ import annotations

import math

import pytest
import torch
from torch import nn

from pipeline.chain.decoders import build_model
from pipeline.chain.models import fold_generator, pool_kernel, pooled_size
from pipeline.design.scene import Model

#: The rate-coded classifiers (the snn has tests of its own, tests/pipeline/chain/test_spiking.py).
RATE_MODELS = [Model.FFNN, Model.CNN]

SHAPES = [
    (1, 9, 40),  # the paper: 3x3 taxels, 40 windows
    (1, 1, 3),  # a single taxel
    (1, 9, 1),  # a single window
    (1, 1, 1),  # one taxel, one window
    (2, 4, 7),  # split polarity, odd side
]


def generators(folds, seed=0):
    return [fold_generator(seed, f, "init") for f in folds]


@pytest.mark.parametrize("model", RATE_MODELS)
@pytest.mark.parametrize("shape", SHAPES)
def test_output_shape_and_dtype(model, shape):
    net = build_model(
        model, shape, n_classes=5, hidden_units=7, n_folds=3, generator=generators(range(3))
    )
    x = torch.randn(3, 4, *shape, generator=torch.Generator().manual_seed(1))
    logits = net(x)
    assert logits.shape == (3, 4, 5)
    assert logits.dtype == torch.float32
    assert torch.isfinite(logits).all()


def test_pool_sizes_keep_single_rows_and_odd_edges():
    assert pool_kernel(9, 40) == (2, 2)
    assert pooled_size(9, 40) == (5, 20)
    assert pooled_size(5, 20) == (3, 10)
    assert pool_kernel(1, 3) == (1, 2)
    assert pooled_size(1, 3) == (1, 2)
    assert pooled_size(1, 1) == (1, 1)


@pytest.mark.parametrize("model", RATE_MODELS)
def test_fold_init_same_in_batch_and_alone(model):
    batch = build_model(model, (1, 9, 40), 12, 100, 4, generators(range(4), seed=7))
    for fold in (0, 2, 3):
        alone = build_model(model, (1, 9, 40), 12, 100, 1, generators([fold], seed=7))
        for (name, p_batch), p_alone in zip(
            batch.named_parameters(), alone.parameters(), strict=True
        ):
            assert torch.equal(p_batch[fold], p_alone[0]), name


@pytest.mark.parametrize("model", RATE_MODELS)
def test_init_is_pytorch_default_uniform(model):
    net = build_model(model, (1, 9, 40), 12, 100, 2, generators(range(2)))
    for name, p in net.named_parameters():
        # fan_in: Linear weights are stored (in, out), conv weights (out, in, kh, kw).
        if name in ("w1", "b1"):
            fan_in = 360
        elif name in ("w2", "b2"):
            fan_in = 100
        elif name.startswith("conv1"):
            fan_in = 1 * 9
        elif name.startswith("conv2"):
            fan_in = 16 * 9
        else:
            fan_in = 32 * 3 * 10
        bound = 1 / math.sqrt(fan_in)
        assert p.abs().max() <= bound, name
        if p[0].numel() >= 1000:  # uniform(-b, b) has std b / sqrt(3)
            assert p.std().item() == pytest.approx(bound / math.sqrt(3), rel=0.05), name
    # Different folds and seeds get different weights.
    other = build_model(model, (1, 9, 40), 12, 100, 2, generators(range(2), seed=1))
    first = next(net.parameters())
    assert not torch.equal(first[0], first[1])
    assert not torch.equal(first, next(other.parameters()))


@pytest.mark.parametrize("model", RATE_MODELS)
def test_folds_are_independent(model):
    net = build_model(model, (1, 9, 40), 12, 10, 3, generators(range(3)))
    x = torch.randn(3, 5, 1, 9, 40, generator=torch.Generator().manual_seed(2))
    y = net(x)
    x2 = x.clone()
    x2[1] = 1e3
    y2 = net(x2)
    assert torch.equal(y[0], y2[0]) and torch.equal(y[2], y2[2])
    assert not torch.equal(y[1], y2[1])
    # Gradients: the loss of fold 0 alone moves only fold 0's parameters.
    grads = torch.autograd.grad(y[0].sum(), list(net.parameters()))
    for g in grads:
        assert g[0].abs().sum() > 0
        assert torch.count_nonzero(g[1:]) == 0


@pytest.mark.parametrize("model", RATE_MODELS)
def test_batched_forward_equals_single_fold(model):
    batch = build_model(model, (1, 9, 40), 12, 100, 4, generators(range(4)))
    alone = build_model(model, (1, 9, 40), 12, 100, 1, generators([2]))
    x = torch.randn(4, 6, 1, 9, 40, generator=torch.Generator().manual_seed(3))
    torch.testing.assert_close(batch(x)[2], alone(x[2:3])[0], rtol=1e-5, atol=1e-5)


def test_ffnn_equals_textbook_layers():
    net = build_model(Model.FFNN, (1, 9, 40), 12, 100, 1, generators([0]))
    reference = nn.Sequential(nn.Flatten(), nn.Linear(360, 100), nn.ReLU(), nn.Linear(100, 12))
    with torch.no_grad():
        reference[1].weight.copy_(net.w1[0].T)
        reference[1].bias.copy_(net.b1[0])
        reference[3].weight.copy_(net.w2[0].T)
        reference[3].bias.copy_(net.b2[0])
    x = torch.randn(8, 1, 9, 40, generator=torch.Generator().manual_seed(4))
    torch.testing.assert_close(net(x[None])[0], reference(x), rtol=1e-5, atol=1e-5)


@pytest.mark.parametrize(("shape", "flat"), [((1, 9, 40), 32 * 3 * 10), ((1, 1, 3), 32 * 1 * 1)])
def test_cnn_equals_textbook_layers(shape, flat):
    """conv-ReLU-pool twice then Linear, in standard NCHW modules (ReLU before pool)."""
    net = build_model(Model.CNN, shape, 12, 100, 1, generators([0]))
    h, w = shape[1:]
    k1 = pool_kernel(h, w)
    k2 = pool_kernel(*pooled_size(h, w))
    reference = nn.Sequential(
        nn.Conv2d(shape[0], 16, 3, padding=1),
        nn.ReLU(),
        nn.MaxPool2d(k1, k1, ceil_mode=True),
        nn.Conv2d(16, 32, 3, padding=1),
        nn.ReLU(),
        nn.MaxPool2d(k2, k2, ceil_mode=True),
        nn.Flatten(),
        nn.Linear(flat, 12),
    )
    with torch.no_grad():
        reference[0].weight.copy_(net.conv1_w[0])
        reference[0].bias.copy_(net.conv1_b[0])
        reference[3].weight.copy_(net.conv2_w[0])
        reference[3].bias.copy_(net.conv2_b[0])
        reference[7].weight.copy_(net.fc_w[0].T)
        reference[7].bias.copy_(net.fc_b[0])
    x = torch.randn(8, *shape, generator=torch.Generator().manual_seed(5))
    torch.testing.assert_close(net(x[None])[0], reference(x), rtol=1e-5, atol=1e-5)


def test_single_generator_draws_folds_in_order():
    a = build_model(Model.FFNN, (1, 3, 4), 3, 5, 2, torch.Generator().manual_seed(0))
    b = build_model(Model.FFNN, (1, 3, 4), 3, 5, 1, torch.Generator().manual_seed(0))
    assert torch.equal(a.w1[0], b.w1[0])


def test_rejects_wrong_input_shape_and_generator_count():
    net = build_model(Model.CNN, (1, 9, 40), 12, 100, 2, generators(range(2)))
    with pytest.raises(ValueError, match="expected input"):
        net(torch.zeros(3, 4, 1, 9, 40))
    with pytest.raises(ValueError, match="one generator per fold"):
        build_model(Model.FFNN, (1, 9, 40), 12, 100, 3, generators(range(2)))


def test_fold_generator_streams_differ():
    draw = lambda g: torch.rand(4, generator=g)  # noqa: E731
    assert torch.equal(draw(fold_generator(0, 1, "init")), draw(fold_generator(0, 1, "init")))
    assert not torch.equal(draw(fold_generator(0, 1, "init")), draw(fold_generator(0, 2, "init")))
    assert not torch.equal(
        draw(fold_generator(0, 1, "init")), draw(fold_generator(0, 1, "shuffle"))
    )
    assert not torch.equal(draw(fold_generator(0, 1, "init")), draw(fold_generator(1, 1, "init")))
    fold_generator(2**63 - 1, 9, "shuffle")  # the largest scene seed is accepted
