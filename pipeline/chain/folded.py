"""The parts every fold-batched classifier shares (:mod:`pipeline.chain.models`,
:mod:`pipeline.chain.spiking`): the module that checks the fold-batched input shape, two
linear layers drawn per fold, and the read of a full-touch classifier on the prefixes of its
frames (:func:`~pipeline.chain.folded.on_prefixes`, :func:`~pipeline.chain.folded.prefix`).

Parameters carry a leading fold dimension ``F``; each fold's are drawn from that fold's own
:class:`torch.Generator` with PyTorch's default bounds for ``Linear``,
``U(-1/sqrt(fan_in), 1/sqrt(fan_in))`` for weights and biases alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np
import torch
import torch.nn.functional as F
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


def fold_loss(logits: torch.Tensor, targets: torch.Tensor, weights: torch.Tensor) -> torch.Tensor:
    """Each fold's weighted cross-entropy on logits.

    Parameters
    ----------
    logits
        float32 ``(F, B, n_classes)``.
    targets
        int64 ``(F, B)`` class indices.
    weights
        float32 ``(F, B)``; ``1 / n_real`` for the ``n_real`` real samples of a fold's batch and
        0 for padding, so each fold contributes its batch-mean loss.

    Returns
    -------
    torch.Tensor
        float32 ``(F,)``, in nats: ``sum_b weights[f, b] * CE(logits[f, b], targets[f, b])``.
        Uses :func:`torch.nn.functional.cross_entropy` (log-softmax with the maximum
        subtracted), finite for logits as large as ``1e30``; an entry of weight 0 contributes
        nothing to the loss or to any gradient. Training minimizes the sum over folds, which
        gives each fold exactly its own gradient.
    """
    n_folds, batch, n_classes = logits.shape
    losses = F.cross_entropy(logits.reshape(-1, n_classes), targets.reshape(-1), reduction="none")
    return (losses * weights.reshape(-1)).reshape(n_folds, batch).sum(dim=1)


def prefix(x: torch.Tensor, ends: torch.Tensor) -> torch.Tensor:
    """Frames ``x`` (float32 ``(F, B, C, H, W)``) as at decision time: sample ``[f, b]``'s
    columns after ``ends[f, b]`` (int64 ``(F, B)``, in ``[0, W)``) set to 0, the training mean
    of a standardized input, as :func:`on_prefixes` reads them."""
    column = torch.arange(x.shape[-1]).reshape(1, 1, -1)
    keep = (column <= ends.unsqueeze(-1)).to(x.dtype)  # (F, B, W)
    return x * keep.reshape(*ends.shape, 1, 1, x.shape[-1])


#: Most input cells (folds x samples x prefixes x frame cells) read at once by
#: :func:`on_prefixes`: bounds their memory (16 MB).
PREFIX_CELLS = 4_000_000


def on_prefixes(
    read: Callable[[nn.Module, torch.Tensor], tuple[torch.Tensor, np.ndarray]],
    net: nn.Module,
    x: torch.Tensor,
) -> tuple[torch.Tensor, np.ndarray]:
    """A full-touch classifier read on every prefix of its frames.

    ``read(net, frames)`` gives the logits float32 ``(F, B', n_classes)`` and operations float64
    ``(F, B', 3)`` of one forward pass; it is called on the frames ``x`` (float32
    ``(F, B, C, H, W)``) whose columns after ``k`` are 0, for every ``k < W``, in chunks of at
    most :data:`PREFIX_CELLS` cells. Returns logits ``(F, B, W, n_classes)`` and operations
    ``(F, B, W, 3)``, column ``k`` for the prefix ending there.
    """
    n_folds, batch = x.shape[:2]
    n_columns = x.shape[-1]
    cells = max(1, x[0, 0].numel() * n_folds * batch)
    chunk = max(1, PREFIX_CELLS // cells)
    column = torch.arange(n_columns)
    parts_logits, parts_operations = [], []
    for first in range(0, n_columns, chunk):
        ends = torch.arange(first, min(first + chunk, n_columns))
        keep = (column.reshape(1, -1) <= ends.reshape(-1, 1)).to(x.dtype)  # (L, W)
        prefixes = x.unsqueeze(2) * keep.reshape(1, 1, len(ends), 1, 1, n_columns)
        prefixes = prefixes.reshape(n_folds, batch * len(ends), *x.shape[2:])
        logits, operations = read(net, prefixes)
        parts_logits.append(logits.reshape(n_folds, batch, len(ends), -1))
        parts_operations.append(operations.reshape(n_folds, batch, len(ends), 3))
    return torch.cat(parts_logits, dim=2), np.concatenate(parts_operations, axis=2)
