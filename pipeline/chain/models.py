"""The paper's texture classifiers, batched over cross-validation folds.

Two models classify one recording's frame, an image ``(channels, taxels, windows)`` of spike
counts with the taxels as rows in raster order, as :func:`pipeline.chain.coding.frames` builds it:

FFNN
    ``flatten -> Linear(C*H*W, hidden_units) -> ReLU -> Linear(hidden_units, n_classes)``.
CNN
    ``Conv2d 3x3 (C -> 16, padding 1) -> ReLU -> MaxPool -> Conv2d 3x3 (16 -> 32, padding 1)
    -> ReLU -> MaxPool -> flatten -> Linear(-> n_classes)``. Each max-pool has kernel and
    stride ``min(2, side)`` on each side and ``ceil_mode=True``: a side of length 1 (a single
    taxel, or a single window) is not pooled, and an odd side keeps its last row/column
    (``side -> ceil(side / 2)``), so any frame of at least 1x1 is accepted.

Both return logits (no softmax); the loss is cross-entropy on logits. The spiking decoder
(``snn``, :mod:`pipeline.chain.spiking`) reads spike counts per time step instead and returns
logits at every step. The decoder registry (:mod:`pipeline.chain.decoders`) builds each model
(:func:`pipeline.chain.decoders.build_model`) and says what it reads and how it is trained.

Fold-batched models
-------------------
A k-fold cross-validation trains ``F`` independent copies of one model. Here they are ONE module
whose parameters carry a leading fold dimension ``F`` and whose ``forward`` maps
``x: float32 (F, B, C, H, W)`` to ``logits: float32 (F, B, n_classes)``; fold ``f`` of the output
depends only on fold ``f`` of the input and of the parameters. Linear layers use
:func:`torch.baddbmm`; convolutions are grouped convolutions with the fold folded into the
channel dimension (``groups=F``) on ``channels_last`` feature maps. Measured on a 2-core CPU, one
thread, F=10 folds, 16 frames of 1x9x40, forward + backward: grouped 9.8 ms, a Python loop over
folds 20 ms, :func:`torch.func.vmap` over ``conv2d`` 27 ms (vmap cannot use ``channels_last``;
NCHW max-pooling alone costs 4.8 ms per call on this CPU). Summing the folds' losses gives every
fold exactly its own gradient.

Measured at one thread on the paper's frames: one training step of ten folds costs
about 6 ms, of which the two convolutions (oneDNN, forward and backward) take about 55 % and
max-pooling, ReLU and the zero-filled pooling gradients most of the rest; the FLOP rate of the
second convolution is already close to the CPU's. Tried and dropped, being no faster: an
im2col + ``bmm`` convolution (3x slower), per-fold convolutions in a loop, the second ReLU after
the flatten, :func:`torch.compile` (20 s to compile one shape, then 2x slower per step).

Initialization is PyTorch's default for ``Linear``/``Conv2d`` (``kaiming_uniform_(a=sqrt(5))``
for weights, which is ``U(-1/sqrt(fan_in), 1/sqrt(fan_in))``, and the same bound for biases),
drawn per fold from that fold's own :class:`torch.Generator`: fold ``f`` gets the same initial
weights whether it is built in a batch of ten or alone (see :func:`fold_generator`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
import torch
import torch.nn.functional as F
from torch import nn

from pipeline.chain.folded import FoldModel, two_layers, uniform

CNN_CHANNELS = (16, 32)
"""Output channels of the CNN's two convolutions (the paper's)."""

_STREAMS = {"init": 0, "shuffle": 1, "decisions": 2}


def fold_generator(seed: int, fold: int, purpose: str) -> torch.Generator:
    """A :class:`torch.Generator` for one fold and one purpose, independent of all others.

    Parameters
    ----------
    seed
        The training seed (``TrainingSpec.seed``), ``0 <= seed < 2**63``.
    fold
        Fold index, ``>= 0``.
    purpose
        ``"init"`` (initial weights), ``"shuffle"`` (mini-batch order) or ``"decisions"`` (the
        decision times of training along the touch).

    Returns
    -------
    torch.Generator
        A CPU generator seeded from ``numpy.random.SeedSequence([seed, fold, purpose])``.
    """
    entropy = np.random.SeedSequence([seed, fold, _STREAMS[purpose]])
    state = int(entropy.generate_state(1, dtype=np.uint64)[0])
    return torch.Generator().manual_seed(state)


def pool_kernel(height: int, width: int) -> tuple[int, int]:
    """Kernel (= stride) of a CNN max-pool on a ``height x width`` map: ``min(2, side)``."""
    return min(2, height), min(2, width)


def pooled_size(height: int, width: int) -> tuple[int, int]:
    """Size after one CNN max-pool with ``ceil_mode=True``: ``ceil(side / kernel)``."""
    kh, kw = pool_kernel(height, width)
    return -(-height // kh), -(-width // kw)


class FoldFFNN(FoldModel):
    """FFNN batched over folds: ``Linear(C*H*W, hidden) -> ReLU -> Linear(hidden, n_classes)``.

    Parameters (float32): ``w1 (F, C*H*W, hidden)``, ``b1 (F, hidden)``,
    ``w2 (F, hidden, n_classes)``, ``b2 (F, n_classes)``. Weights are stored ``(in, out)`` so the
    forward pass is ``x @ w + b`` per fold.
    """

    def __init__(
        self,
        input_shape: tuple[int, int, int],
        n_classes: int,
        hidden_units: int,
        generators: Sequence[torch.Generator],
    ):
        super().__init__(input_shape, n_classes, len(generators))
        two_layers(self, math.prod(self.input_shape), hidden_units, n_classes, generators)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Logits ``float32 (F, B, n_classes)`` for ``x: float32 (F, B, C, H, W)``."""
        self._check(x)
        h = x.reshape(x.shape[0], x.shape[1], -1)
        h = torch.relu(torch.baddbmm(self.b1.unsqueeze(1), h, self.w1))
        return torch.baddbmm(self.b2.unsqueeze(1), h, self.w2)


class FoldCNN(FoldModel):
    """CNN batched over folds with grouped convolutions (``groups=F``).

    Parameters (float32): ``conv1_w (F, 16, C, 3, 3)``, ``conv1_b (F, 16)``,
    ``conv2_w (F, 32, 16, 3, 3)``, ``conv2_b (F, 32)``, ``fc_w (F, 32*H''*W'', n_classes)``,
    ``fc_b (F, n_classes)``, where ``H'' x W''`` is the map size after the two pools
    (:func:`pooled_size` applied twice). The flatten order per fold is ``(channel, row, col)``,
    as ``nn.Flatten`` on a ``(B, 32, H'', W'')`` map.
    """

    def __init__(
        self,
        input_shape: tuple[int, int, int],
        n_classes: int,
        generators: Sequence[torch.Generator],
    ):
        super().__init__(input_shape, n_classes, len(generators))
        c, h, w = self.input_shape
        c1, c2 = CNN_CHANNELS
        self.pool1 = pool_kernel(h, w)
        h1, w1 = pooled_size(h, w)
        self.pool2 = pool_kernel(h1, w1)
        h2, w2 = pooled_size(h1, w1)
        n_flat = c2 * h2 * w2
        per_fold = [
            [
                uniform(g, (c1, c, 3, 3), c * 9),
                uniform(g, (c1,), c * 9),
                uniform(g, (c2, c1, 3, 3), c1 * 9),
                uniform(g, (c2,), c1 * 9),
                uniform(g, (n_flat, n_classes), n_flat),
                uniform(g, (n_classes,), n_flat),
            ]
            for g in generators
        ]
        stacked = [torch.stack(p) for p in zip(*per_fold, strict=True)]
        self.conv1_w, self.conv1_b = nn.Parameter(stacked[0]), nn.Parameter(stacked[1])
        self.conv2_w, self.conv2_b = nn.Parameter(stacked[2]), nn.Parameter(stacked[3])
        self.fc_w, self.fc_b = nn.Parameter(stacked[4]), nn.Parameter(stacked[5])

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        """Logits ``float32 (F, B, n_classes)`` for ``x: float32 (F, B, C, H, W)``.

        Feature maps are kept ``channels_last`` and ReLU is applied after each max-pool
        (``relu(maxpool(z)) == maxpool(relu(z))``, ReLU being monotone; gradients agree too):
        both are about twice as fast on CPU as the textbook order in NCHW layout.
        """
        return self.head(self.features(x)[-1])

    def features(self, x: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        """The inputs of the second convolution and of the linear layer: float32
        ``(B, F*16, H', W')`` (``channels_last``) and ``(F, B, 32*H''*W'')``."""
        self._check(x)
        n_folds, batch, c, h, w = x.shape
        # Fold F into channels: (B, F*C, H, W); group f of every conv sees fold f only. Copied
        # into a tensor allocated channels_last, which has channel stride 1 even when F*C == 1
        # (``.contiguous(memory_format=channels_last)`` leaves such a tensor in NCHW strides, the
        # convolutions then take the NCHW path and max-pooling is ~10x slower).
        z = torch.empty(
            (batch, n_folds * c, h, w), dtype=x.dtype, memory_format=torch.channels_last
        )
        z.copy_(x.transpose(0, 1).reshape(batch, n_folds * c, h, w))
        z = F.conv2d(
            z,
            self.conv1_w.reshape(-1, c, 3, 3),
            self.conv1_b.reshape(-1),
            padding=1,
            groups=n_folds,
        )
        z = torch.relu(F.max_pool2d(z, self.pool1, self.pool1, ceil_mode=True))
        pooled = z
        z = F.conv2d(
            z,
            self.conv2_w.reshape(-1, CNN_CHANNELS[0], 3, 3),
            self.conv2_b.reshape(-1),
            padding=1,
            groups=n_folds,
        )
        z = torch.relu(F.max_pool2d(z, self.pool2, self.pool2, ceil_mode=True))
        z = z.reshape(batch, n_folds, -1).transpose(0, 1)  # (F, B, 32*H''*W''), (c, row, col)
        return pooled, z

    def head(self, z: torch.Tensor) -> torch.Tensor:
        """Logits ``(F, B, n_classes)`` from the flattened features ``(F, B, 32*H''*W'')``."""
        return torch.baddbmm(self.fc_b.unsqueeze(1), z, self.fc_w)
