"""The parts every fold-batched classifier shares: the loss each fold trains on."""

from __future__ import annotations

import torch

from pipeline.chain.folded import fold_loss


def test_loss_is_finite_for_huge_logits():
    logits = torch.tensor([[[1e30, -1e30, 0.0], [-1e30, 1e30, 1e30]]], requires_grad=True)
    targets = torch.tensor([[1, 0]])
    weights = torch.full((1, 2), 0.5)
    loss = fold_loss(logits, targets, weights)
    (grad,) = torch.autograd.grad(loss.sum(), [logits])
    assert torch.isfinite(loss).all() and loss.item() > 1e29
    assert torch.isfinite(grad).all()
    # Softmax gradient of a confident wrong sample: -w at the target, +w at the argmax.
    torch.testing.assert_close(grad[0, 0], torch.tensor([0.5, -0.5, 0.0]))


def test_loss_is_per_fold_batch_mean_and_ignores_padding():
    gen = torch.Generator().manual_seed(0)
    logits = torch.randn(2, 4, 3, generator=gen, requires_grad=True)
    targets = torch.tensor([[0, 1, 2, 0], [2, 2, 1, 0]])
    weights = torch.tensor([[1 / 3, 1 / 3, 1 / 3, 0.0], [0.25, 0.25, 0.25, 0.25]])
    loss = fold_loss(logits, targets, weights)
    ce = torch.nn.functional.cross_entropy
    torch.testing.assert_close(loss[0], ce(logits[0, :3], targets[0, :3]))
    torch.testing.assert_close(loss[1], ce(logits[1], targets[1]))
    (grad,) = torch.autograd.grad(loss.sum(), [logits])
    assert torch.count_nonzero(grad[0, 3]) == 0
