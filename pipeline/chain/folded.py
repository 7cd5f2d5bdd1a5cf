"""The parts every fold-batched classifier shares (:mod:`pipeline.chain.models`,
:mod:`pipeline.chain.spiking`): the module that checks the fold-batched input shape, and two
linear layers drawn per fold.

Parameters carry a leading fold dimension ``F``; each fold's are drawn from that fold's own
:class:`torch.Generator` with PyTorch's default bounds for ``Linear``,
``U(-1/sqrt(fan_in), 1/sqrt(fan_in))`` for weights and biases alike.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import torch
from torch import nn


def uniform(generator: torch.Generator, shape: tuple[int, ...], fan_in: int) -> torch.Tensor:
    """One float32 draw of ``U(-1/sqrt(fan_in), 1/sqrt(fan_in))`` of the given shape."""
    bound = 1.0 / math.sqrt(fan_in)
    return torch.rand(shape, generator=generator, dtype=torch.float32) * (2 * bound) - bound


def two_layers(
    module: nn.Module,
    n_in: int,
    hidden: int,
    n_classes: int,
    generators: Sequence[torch.Generator],
) -> None:
    """Give ``module`` the parameters of two fold-batched linear layers, float32 ``w1 (F, n_in,
    hidden)``, ``b1 (F, hidden)``, ``w2 (F, hidden, n_classes)``, ``b2 (F, n_classes)``, drawn
    per fold in that order from the fold's own generator (PyTorch's default bounds)."""
    per_fold = [
        [
            uniform(g, (n_in, hidden), n_in),
            uniform(g, (hidden,), n_in),
            uniform(g, (hidden, n_classes), hidden),
            uniform(g, (n_classes,), hidden),
        ]
        for g in generators
    ]
    w1, b1, w2, b2 = (torch.stack(p) for p in zip(*per_fold, strict=True))
    module.w1, module.b1 = nn.Parameter(w1), nn.Parameter(b1)
    module.w2, module.b2 = nn.Parameter(w2), nn.Parameter(b2)


class FoldModel(nn.Module):
    """Common part: fold count, input shape, class count, and the parameter draw order."""

    def __init__(self, input_shape: tuple[int, int, int], n_classes: int, n_folds: int):
        super().__init__()
        self.input_shape = tuple(int(s) for s in input_shape)
        self.n_classes = int(n_classes)
        self.n_folds = int(n_folds)

    def _check(self, x: torch.Tensor) -> None:
        if x.dim() != 5 or x.shape[0] != self.n_folds or tuple(x.shape[2:]) != self.input_shape:
            raise ValueError(
                f"expected input (F={self.n_folds}, B, *{self.input_shape}), got {tuple(x.shape)}"
            )
