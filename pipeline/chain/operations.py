r"""Operations a decoder spends on one decision, counted alike for every model (NeuroBench style).

A layer's *effective synaptic operations* are its nonzero inputs times their fan-out (the
outputs each input reaches); a zero input costs nothing, as on event-driven hardware, where it
is never sent. They are *accumulates* (ACs) where the inputs are spike events, which add a
weight to a target, and *multiply-accumulates* (MACs) where the inputs are real numbers. An
input that counts :math:`c` events in one step (a spike count of the input layer of the ``snn``)
is :math:`c` accumulates per target: each event is delivered on its own. *Neuron updates* are
state updates of stateful neurons, one per neuron and step (a leaky membrane, the readout's
integrator); the FFNN's and CNN's units hold no state and update none. Max-pooling
(comparisons) and biases (one per output, part of its update) are not synaptic operations and
are not counted.

Per model, for one sample:

FFNN
    MACs :math:`= n_{\ne 0}(x) \cdot h + n_{\ne 0}(\mathrm{relu}(W_1^\top x + b_1)) \cdot K`
    (``h`` hidden units, ``K`` classes).
CNN
    a 3x3 convolution with padding 1 (stride 1) sends input pixel :math:`(i, j)` to
    :math:`r(i) \cdot r'(j) \cdot C_\mathrm{out}` outputs, :math:`r(i)` the output rows
    within one of row :math:`i` (3 inside, 2 on an edge, 1 when the side is 1); MACs are the
    sum of that fan-out over the nonzero input pixels of both convolutions (every channel),
    plus the nonzero flattened features times ``K``.
SNN
    cumulative over steps :math:`1..t`: ACs :math:`= h \sum_{t' \le t} \sum x_{t'} + K
    \sum_{t' \le t} n(s_{t'})` (input events to the hidden layer, hidden spikes to the
    readout), neuron updates :math:`= t (h + K)`; with :math:`L` hidden layers, each layer's
    spikes after the first reach :math:`h` neurons of the next, and the updates are
    :math:`t (L h + K)`; on inputs that are not event counts
    (``training.snn.inputs`` standardized or ``log_counts``: real numbers), the input layer's
    are MACs, :math:`h \sum_{t' \le t} n_{\ne 0}(x_{t'})`, and only the hidden spikes' ACs.

One counter per model (:func:`ffnn_operations`, :func:`cnn_operations`, :func:`snn_operations`),
each the one its decoder declares (:meth:`pipeline.chain.decoders.Decoder.count_operations`;
:func:`pipeline.chain.decoders.count_operations` asks the registry), returns counts per decision
time: the SNN's at every step; the FFNN's and CNN's for the one forward pass of the frame given
(a decision at an earlier window boundary is that of the frame with the later windows left out,
:meth:`pipeline.chain.decoders.Decoder.decide`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import torch

from pipeline.chain.models import CNN_CHANNELS, FoldCNN, FoldFFNN
from pipeline.chain.spiking import FoldSNN

__all__ = ["Operations", "cnn_operations", "conv3x3_fan_out", "ffnn_operations", "snn_operations"]


@dataclass(frozen=True, eq=False)
class Operations:
    """Operations per sample and decision time.

    Attributes
    ----------
    acs, macs, neuron_updates
        float64 ``(F, B, D)``: accumulates, multiply-accumulates and neuron updates that a
        decision read at each of the ``D`` decision times has cost since the touch began, for
        sample ``b`` of fold ``f``.
    """

    acs: np.ndarray
    macs: np.ndarray
    neuron_updates: np.ndarray

    def stacked(self) -> np.ndarray:
        """float64 ``(F, B, D, 3)``: the three counts in
        :data:`~pipeline.chain.operation_kinds.OPERATIONS` order."""
        return np.stack([self.acs, self.macs, self.neuron_updates], axis=-1)


def conv3x3_fan_out(height: int, width: int, channels_out: int) -> np.ndarray:
    """float64 ``(height, width)``: outputs that input pixel ``(i, j)`` of a 3x3 convolution
    with padding 1 and stride 1 reaches (``channels_out`` per covered output position)."""

    def covered(n: int) -> np.ndarray:
        index = np.arange(n)
        return np.minimum(index + 1, n - 1) - np.maximum(index - 1, 0) + 1

    return np.outer(covered(height), covered(width)).astype(np.float64) * channels_out


def _fanned(x: torch.Tensor, fan: np.ndarray) -> np.ndarray:
    """float64 ``(F, B)``: the nonzero entries of ``x`` (``(F, B, C, H, W)``) weighted by the
    fan-out of their position ``fan`` (``(H, W)``), summed."""
    nonzero = (x != 0).sum(dim=2, dtype=torch.int32).to(torch.float64)  # (F, B, H, W)
    return torch.einsum("fbhw,hw->fb", nonzero, torch.from_numpy(fan)).numpy()


@torch.no_grad()
def cnn_operations(
    model: FoldCNN, x: torch.Tensor, pooled: torch.Tensor, flat: torch.Tensor
) -> Operations:
    """The CNN's operations on its inputs ``x`` (float32 ``(F, B, C, H, W)``, standardized
    frames), given its features on ``x`` (:meth:`~pipeline.chain.models.FoldCNN.features`, so
    that a caller that needs its logits too computes them once): ``(F, B, 1)``
    multiply-accumulates of one forward pass."""
    c1, c2 = CNN_CHANNELS
    n_folds, batch, _, height, width = x.shape
    _, _, h1, w1 = pooled.shape
    pooled = pooled.reshape(batch, n_folds, c1, h1, w1).transpose(0, 1)
    macs = _fanned(x, conv3x3_fan_out(height, width, c1))
    macs = macs + _fanned(pooled, conv3x3_fan_out(h1, w1, c2))
    macs = macs + _nonzero(flat, (2,)) * model.n_classes
    zeros = np.zeros((n_folds, batch, 1))
    return Operations(zeros, macs[..., None], zeros)


def _nonzero(x: torch.Tensor, dims: tuple[int, ...]) -> np.ndarray:
    return (x != 0).sum(dim=dims).to(torch.float64).numpy()


@torch.no_grad()
def ffnn_operations(model: FoldFFNN, x: torch.Tensor) -> Operations:
    """The FFNN's operations on its inputs ``x`` (float32 ``(F, B, C, H, W)``, standardized
    frames): ``(F, B, 1)`` multiply-accumulates of one forward pass."""
    n_folds, batch = x.shape[:2]
    zeros = np.zeros((n_folds, batch, 1))
    hidden, n_classes = model.w2.shape[1:]
    flat = x.reshape(n_folds, batch, -1)
    h = torch.relu(torch.baddbmm(model.b1.unsqueeze(1), flat, model.w1))
    macs = _nonzero(flat, (2,)) * hidden + _nonzero(h, (2,)) * n_classes
    return Operations(zeros, macs[..., None], zeros)


@torch.no_grad()
def snn_operations(model: FoldSNN, x: torch.Tensor) -> Operations:
    """The SNN's operations on its spike counts ``x`` (float32 ``(F, B, C, H, T)``, ``T``
    steps): ``(F, B, T)`` accumulates and neuron updates, cumulative over the steps."""
    hidden, n_classes = model.hidden_neurons, model.n_classes
    # (F, B, T) per step: input events, or nonzero real inputs (the module docstring)
    inputs = (x if model.events_in else (x != 0)).to(torch.float64).sum(dim=(2, 3))
    spikes = [s.sum(dim=3).to(torch.float64) for s, _ in model.layer_spikes(x)]  # (F, B, T)
    fan_out = [hidden] * (len(spikes) - 1) + [n_classes]
    sent = sum(s * f for s, f in zip(spikes, fan_out, strict=True))
    acs = torch.cumsum(inputs * hidden * model.events_in + sent, dim=2).numpy()
    macs = torch.cumsum(inputs * hidden * (not model.events_in), dim=2).numpy()
    n_steps = x.shape[-1]
    per_step = len(spikes) * hidden + n_classes
    updates = np.broadcast_to(
        np.arange(1, n_steps + 1, dtype=np.float64) * per_step, acs.shape
    ).copy()
    return Operations(acs, macs, updates)
