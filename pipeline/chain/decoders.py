r"""The decoder registry: one frozen class per model (:class:`~pipeline.design.scene.Model`) that
declares everything the rest of the chain asks of a decoder.

A :class:`Decoder` says

* what it reads of a recording's REAL spike trains (:class:`Reads`): rate-coded counts per
  ``coding.window_s`` window (the FFNN and CNN), or counts per ``training.snn.step_s`` step,
  ON and OFF events apart (the ``snn``); the run layer codes, for a scene, the inputs its
  models read (:mod:`pipeline.run.decoding`);
* how its inputs are prepared (:class:`Preparation`): standardized per feature with the
  statistics of a fold's training recordings (:func:`standardize`), or fed as the counts they
  are, or as ``log(1 + count)`` (the ``snn``'s, as ``training.snn.inputs`` says);
* how it is built (:meth:`Decoder.build`, the fold-batched modules of
  :mod:`pipeline.chain.models` and :mod:`pipeline.chain.spiking`) and how long it trains
  (:meth:`Decoder.epochs`);
* what its training minimizes (:meth:`Decoder.loss`), as ``training.decisions`` says
  (:class:`~pipeline.design.scene.DecisionTraining`): with ``full_touch``, the cross-entropy
  :math:`\mathrm{CE}(z_W, y)` of the decision at the end of the touch; with ``along_touch``,
  that of decisions along it: the FFNN and CNN see each training sample, in each epoch, as at
  one decision time ``k`` (its columns after ``k`` set as :meth:`Decoder.decide` sets them),
  the ``k`` of an epoch's samples spread evenly over the ``W`` columns (drawn by
  :func:`pipeline.chain.training.fit_folds`), so the loss is
  :math:`\mathrm{CE}(z_k, y)` with :math:`k` uniform on the columns; the ``snn``, whose one
  pass gives its decision at every step, minimizes :math:`\frac{1}{T} \sum_t
  \mathrm{CE}(z_t, y)`, the mean over its steps;
* how it decides along the touch (:meth:`Decoder.decide`): the logits and the operations of a
  decision read at the end of every frame column, the ``snn``'s at every step, the FFNN's and
  CNN's on the frame's prefixes (its later windows set to their training mean, 0 once
  standardized);
* how its operations are counted (:meth:`Decoder.count_operations`,
  :mod:`pipeline.chain.operations`).

Training (:mod:`pipeline.chain.training`), deployment over chips
(:mod:`pipeline.chain.deployment`), the operation counter (:func:`count_operations`) and the
run layer ask :func:`decoder_of` and never branch on the model themselves. Adding a decoder is
one class here (and its ``Model`` member in :mod:`pipeline.design.scene`); the registry refuses
at import a model without its decoder.

This module imports no torch: the sweep's coordinating process asks it what a scene's models
read (for cache keys) and never trains. The methods that build, train or read a network import
what they need when called.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from enum import Enum
from types import MappingProxyType
from typing import TYPE_CHECKING, ClassVar

import numpy as np

from pipeline.chain.coding import frames
from pipeline.chain.spikes import SpikeTrains
from pipeline.design.scene import CodingSpec, Model, Polarity, SNNSpec, TrainingSpec

if TYPE_CHECKING:
    import torch
    from torch import nn

    from pipeline.chain.operations import Operations

__all__ = [
    "DECODERS",
    "CNNDecoder",
    "Decoder",
    "DecoderInput",
    "FFNNDecoder",
    "Preparation",
    "Reads",
    "SNNDecoder",
    "WindowsDecoder",
    "build_model",
    "count_operations",
    "decoder_of",
    "reads_of",
    "standardize",
]


class Reads(Enum):
    """What a decoder reads of a recording's REAL spike trains: frames ``(C, taxels, columns)``
    of spike counts (:func:`pipeline.chain.coding.frames`), over the span of the
    ``n_windows`` rate-coding windows."""

    WINDOWS = "windows"
    """Counts per ``coding.window_s`` window, channels as ``coding.polarity`` says."""
    STEPS = "steps"
    """Counts per ``training.snn.step_s`` step, ON (+1) then OFF (-1) events (2 channels)."""

    def column_s(self, coding: CodingSpec, snn: SNNSpec | None) -> float | None:
        """Seconds of touch per frame column; None for ``STEPS`` of a scene without the
        ``snn``'s part (no decoder of the scene reads steps)."""
        if self is Reads.WINDOWS:
            return coding.window_s
        return None if snn is None else snn.step_s

    def code(
        self, trains: SpikeTrains, coding: CodingSpec, snn: SNNSpec | None, n_windows: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """Frames of ``trains`` over the span of ``n_windows`` windows: int64 ``counts
        (n_recordings, C, taxels, columns)`` and int64 ``dropped (n_recordings, taxels)``, the
        spikes outside every column."""
        column_s = self.column_s(coding, snn)
        if column_s is None:
            raise ValueError(f"{self.value} need the snn's part (training.snn)")
        if self is Reads.WINDOWS:
            return frames(trains, column_s, n_windows, coding.polarity)
        n_steps = round(n_windows * coding.window_s / column_s)
        return frames(trains, column_s, n_steps, Polarity.SPLIT)


def standardize(train: np.ndarray, test: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Standardize features with statistics of the training samples only.

    Parameters
    ----------
    train
        ``(n_train, *feature_shape)`` numbers (counts, int or float), ``n_train >= 1``.
    test
        ``(n_test, *feature_shape)``; its values never enter the statistics.

    Returns
    -------
    train_z, test_z
        float32 arrays of the input shapes: ``(x - mean) / std`` per feature, where ``mean`` and
        ``std`` (population, ``ddof=0``) are computed in float64 over the training samples. A
        feature whose training std is 0 or not finite gets std 1 (a constant feature maps to 0).
    """
    train64 = np.asarray(train, dtype=np.float64)
    test64 = np.asarray(test, dtype=np.float64)
    mean = train64.mean(axis=0)
    std = train64.std(axis=0)
    std = np.where(np.isfinite(std) & (std > 0), std, 1.0)
    mean = np.where(np.isfinite(mean), mean, 0.0)
    return (
        ((train64 - mean) / std).astype(np.float32),
        ((test64 - mean) / std).astype(np.float32),
    )


class Preparation(Enum):
    """How a decoder's frames become its float32 inputs, fold by fold (the values of
    :class:`~pipeline.design.scene.SNNInputs` name members)."""

    STANDARDIZED = "standardized"
    """Per feature, with the fold's training statistics (:func:`standardize`)."""
    COUNTS = "counts"
    """The counts themselves as float32, so events stay events."""
    LOG_COUNTS = "log_counts"
    """``log(1 + count)`` as float32, so 0 stays 0 and a burst weighs less than its events."""

    @property
    def keeps_events(self) -> bool:
        """Whether the inputs are the event counts (spikes to deliver, not real numbers)."""
        return self is Preparation.COUNTS

    def apply(self, train: np.ndarray, test: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """float32 inputs of a fold's training and test frames (shapes kept)."""
        if self is Preparation.STANDARDIZED:
            return standardize(train, test)
        if self is Preparation.LOG_COUNTS:
            return np.log1p(train).astype(np.float32), np.log1p(test).astype(np.float32)
        return np.asarray(train, dtype=np.float32), np.asarray(test, dtype=np.float32)


@dataclass(frozen=True, eq=False)
class DecoderInput:
    """What one decoder reads of a scene's recordings (:class:`Reads`).

    Attributes
    ----------
    frames
        int64 ``(n_recordings, C, taxels, columns)``: the scene's REAL trains coded.
    column_s
        Seconds of touch per column (a decision read after column ``k`` comes
        ``(k + 1) * column_s`` into the touch).
    chips
        int64 ``(n_chips, n_recordings, C, taxels, columns)``: every chip's, for a scene that
        simulates chips; else None.
    reference
        The frames of the reference a ``shared`` or ``robust`` classifier trains on, shaped as
        ``frames``; else None (one chip, or ``per_chip``).
    """

    frames: np.ndarray
    column_s: float
    chips: np.ndarray | None = None
    reference: np.ndarray | None = None


@dataclass(frozen=True)
class Decoder(ABC):
    """One model's decoder (see the module docstring); subclasses declare the class
    attributes and implement :meth:`build` and :meth:`count_operations`."""

    model: ClassVar[Model]
    """The scene's name for it (``training.models``)."""
    reads: ClassVar[Reads]
    """What it reads of the spike trains."""
    preparation: ClassVar[Preparation]
    """How its frames become its inputs, unless its
    :meth:`~pipeline.chain.decoders.Decoder.prepare` reads the scene's choice."""

    def prepare(
        self, train: np.ndarray, test: np.ndarray, training: TrainingSpec
    ) -> tuple[np.ndarray, np.ndarray]:
        """float32 inputs of a fold's training and test frames (:attr:`preparation`)."""
        return self.preparation.apply(train, test)

    @abstractmethod
    def build(
        self,
        input_shape: tuple[int, int, int],
        n_classes: int,
        generators: Sequence[torch.Generator],
        hidden_units: int,
        snn: SNNSpec | None,
    ) -> nn.Module:
        """``len(generators)`` fold-batched copies (checked arguments: :func:`build_model`)."""

    def epochs(self, training: TrainingSpec) -> int:
        """Training epochs: ``training.epochs``."""
        return training.epochs

    def learning_rate(self, training: TrainingSpec) -> float:
        """Adam's learning rate: ``training.learning_rate``."""
        return training.learning_rate

    def loss(
        self,
        net: nn.Module,
        x: torch.Tensor,
        targets: torch.Tensor,
        weights: torch.Tensor,
        ends: torch.Tensor | None = None,
    ) -> torch.Tensor:
        """float32 ``(F,)``: each fold's training loss on a mini-batch ``x`` (float32
        ``(F, B, C, H, W)``), the weighted cross-entropy (:func:`pipeline.chain.folded.fold_loss`)
        of the decision at the end of the touch (``ends`` None: ``full_touch``), or, trained
        along the touch, of each sample's decision at its column ``ends[f, b]`` (int64
        ``(F, B)``): its frame with the later columns set to 0, the training mean of a
        standardized input, as :meth:`decide` reads it (:func:`pipeline.chain.folded.prefix`)."""
        from pipeline.chain.folded import fold_loss, prefix

        return fold_loss(net(x if ends is None else prefix(x, ends)), targets, weights)

    def decide(self, net: nn.Module, x: torch.Tensor) -> tuple[torch.Tensor, np.ndarray]:
        """Decisions read at the end of every frame column of ``x`` (float32
        ``(F, B, C, H, W)``): logits float32 ``(F, B, W, n_classes)`` and operations float64
        ``(F, B, W, 3)`` (:mod:`pipeline.chain.operations`).

        By default those of the trained model on the frame whose columns after ``k`` are 0, the
        training mean of a standardized input (:func:`pipeline.chain.folded.on_prefixes`), as
        its training along the touch saw them (:meth:`loss`); a full-touch model is read on
        its prefixes so."""
        from pipeline.chain.folded import on_prefixes

        return on_prefixes(self.logits_and_operations, net, x)

    def logits_and_operations(
        self, net: nn.Module, x: torch.Tensor
    ) -> tuple[torch.Tensor, np.ndarray]:
        """Logits float32 ``(F, B, n_classes)`` and operations float64 ``(F, B, 3)`` of one
        forward pass."""
        return net(x), self.count_operations(net, x).stacked()[:, :, 0]

    @abstractmethod
    def count_operations(self, net: nn.Module, x: torch.Tensor) -> Operations:
        """Operations of ``net`` on ``x`` (float32 ``(F, B, C, H, W)``): ``(F, B, D)`` counts,
        ``D`` the decision times one forward pass gives."""


@dataclass(frozen=True)
class WindowsDecoder(Decoder):
    """A decoder of rate-coded windows, standardized, read along the touch on the prefixes of
    its frames (:meth:`Decoder.decide`): the paper's FFNN and CNN."""

    reads: ClassVar[Reads] = Reads.WINDOWS
    preparation: ClassVar[Preparation] = Preparation.STANDARDIZED


@dataclass(frozen=True)
class FFNNDecoder(WindowsDecoder):
    """The paper's FFNN (:class:`pipeline.chain.models.FoldFFNN`)."""

    model: ClassVar[Model] = Model.FFNN

    def build(self, input_shape, n_classes, generators, hidden_units, snn):
        from pipeline.chain.models import FoldFFNN

        return FoldFFNN(input_shape, n_classes, hidden_units, generators)

    def count_operations(self, net, x):
        from pipeline.chain.operations import ffnn_operations

        return ffnn_operations(net, x)


@dataclass(frozen=True)
class CNNDecoder(WindowsDecoder):
    """The paper's CNN (:class:`pipeline.chain.models.FoldCNN`); its features are computed once
    for its logits and its count."""

    model: ClassVar[Model] = Model.CNN

    def logits_and_operations(self, net, x):
        from pipeline.chain.operations import cnn_operations

        features = net.features(x)
        return net.head(features[-1]), cnn_operations(net, x, *features).stacked()[:, :, 0]

    def count_operations(self, net, x):
        from pipeline.chain.operations import cnn_operations

        return cnn_operations(net, x, *net.features(x))

    def build(self, input_shape, n_classes, generators, hidden_units, snn):
        from pipeline.chain.models import FoldCNN

        return FoldCNN(input_shape, n_classes, generators)


@dataclass(frozen=True)
class SNNDecoder(Decoder):
    """The spiking decoder (:class:`pipeline.chain.spiking.FoldSNN`) on step counts (prepared
    as ``training.snn.inputs`` says), trained ``training.snn.epochs`` epochs; its decision at
    every step is its own output there."""

    model: ClassVar[Model] = Model.SNN
    reads: ClassVar[Reads] = Reads.STEPS
    preparation: ClassVar[Preparation] = Preparation.COUNTS

    def build(self, input_shape, n_classes, generators, hidden_units, snn):
        from pipeline.chain.spiking import FoldSNN

        if snn is None:
            raise ValueError("the snn needs its hyper-parameters (snn=SNNSpec)")
        return FoldSNN(
            input_shape,
            n_classes,
            snn.hidden_neurons,
            generators,
            step_s=snn.step_s,
            tau_mem_s=snn.tau_mem_s,
            threshold=snn.threshold,
            surrogate_slope=snn.surrogate_slope,
            time_constants=snn.time_constants,
            readout=snn.readout,
            events_in=Preparation(snn.inputs.value).keeps_events,
            hidden_layers=snn.hidden_layers,
            along_touch_loss=snn.along_touch_loss,
        )

    def epochs(self, training: TrainingSpec) -> int:
        """``training.snn.epochs``."""
        return training.snn.epochs

    def learning_rate(self, training: TrainingSpec) -> float:
        """``training.snn.learning_rate``, or ``training.learning_rate`` when not set."""
        rate = training.snn.learning_rate
        return training.learning_rate if rate is None else rate

    def prepare(self, train, test, training):
        """Its step counts as ``training.snn.inputs`` says (:class:`Preparation`)."""
        return Preparation(training.snn.inputs.value).apply(train, test)

    def loss(self, net, x, targets, weights, ends=None):
        """The cross-entropy of its decision at the last step (``ends`` None), or, trained
        along the touch, as ``training.snn.along_touch_loss`` says (the net's
        ``along_touch_loss``): the sum over the steps of each step's decision's, weighed
        equally or toward the early steps (:meth:`~pipeline.chain.spiking.FoldSNN.step_losses`;
        one pass gives them all, so every step is weighed, not the drawn ``ends``), or that of
        each sample's decision at its drawn step ``ends[f, b]``, as the FFNN's and CNN's (the
        same loss in expectation over the draws, at the cost of one decision per sample)."""
        from pipeline.chain.folded import fold_loss
        from pipeline.design.scene import SNNAlongLoss

        if ends is None:
            return fold_loss(net(x), targets, weights)
        if net.along_touch_loss is SNNAlongLoss.DRAWN_STEP:
            return fold_loss(net.logits_at(x, ends), targets, weights)
        return (net.step_losses(x, targets) * weights).sum(dim=1)

    def decide(self, net, x):
        """Its outputs at every step (:meth:`~pipeline.chain.spiking.FoldSNN.decision_logits`),
        each step's operations cumulative since the touch began."""
        return net.decision_logits(x), self.count_operations(net, x).stacked()

    def count_operations(self, net, x):
        from pipeline.chain.operations import snn_operations

        return snn_operations(net, x)


def _registry(*decoders: Decoder) -> Mapping[Model, Decoder]:
    """The registry, refused at import unless every model has exactly one decoder."""
    by_model = {decoder.model: decoder for decoder in decoders}
    missing = [m.value for m in Model if m not in by_model]
    if missing or len(by_model) != len(decoders):
        raise ValueError(f"decoder registry: models {missing} lack a decoder, or one has two")
    return MappingProxyType(by_model)


#: Every model's decoder.
DECODERS: Mapping[Model, Decoder] = _registry(FFNNDecoder(), CNNDecoder(), SNNDecoder())


def decoder_of(model: Model | str) -> Decoder:
    """The decoder of ``model`` (a :class:`~pipeline.design.scene.Model` or its name)."""
    return DECODERS[Model(model)]


def reads_of(models: Sequence[Model]) -> tuple[Reads, ...]:
    """What the decoders of ``models`` read, each kind once, in :class:`Reads` order."""
    wanted = {decoder_of(model).reads for model in models}
    return tuple(reads for reads in Reads if reads in wanted)


def build_model(
    model: Model | str,
    input_shape: tuple[int, int, int],
    n_classes: int,
    hidden_units: int,
    n_folds: int,
    generator: torch.Generator | Sequence[torch.Generator],
    snn: SNNSpec | None = None,
) -> nn.Module:
    """Build ``n_folds`` independent copies of a classifier as one fold-batched module.

    Parameters
    ----------
    model
        The model (:func:`decoder_of` builds it).
    input_shape
        One sample's frame ``(C, H, W)``: channels, taxels (rows), windows (columns); for the
        SNN, polarities, taxels and steps.
    n_classes
        Number of classes (logits per sample), ``>= 2``.
    hidden_units
        Hidden ReLU units of the FFNN (ignored by the others).
    n_folds
        ``F``, the number of independent models.
    generator
        Either one generator per fold (a sequence of length ``n_folds``; fold ``f`` draws its
        parameters from ``generator[f]`` only, so its weights do not depend on the other folds;
        use :func:`pipeline.chain.models.fold_generator`), or a single generator from which the
        folds draw in order.
    snn
        The SNN's hyper-parameters (required for it; its hidden neurons replace
        ``hidden_units``).

    Returns
    -------
    torch.nn.Module
        Float32 module; ``forward(x: float32 (F, B, C, H, W)) -> float32 (F, B, n_classes)``.
    """
    import torch

    if isinstance(generator, torch.Generator):
        generators = [generator] * n_folds
    else:
        generators = list(generator)
    if len(generators) != n_folds or n_folds < 1:
        raise ValueError(f"need one generator per fold ({n_folds}), got {len(generators)}")
    if len(input_shape) != 3 or min(input_shape) < 1:
        raise ValueError(f"input_shape must be (C, H, W) with sides >= 1, got {input_shape}")
    if n_classes < 2:
        raise ValueError(f"n_classes must be >= 2, got {n_classes}")
    return decoder_of(model).build(input_shape, n_classes, generators, hidden_units, snn)


def count_operations(model: Model | str, net: nn.Module, x: torch.Tensor) -> Operations:
    """The operations of ``model``'s fold-batched ``net`` on inputs ``x`` (float32
    ``(F, B, C, H, W)``: its prepared frames), by its decoder (:mod:`pipeline.chain.operations`):
    ``(F, B, D)`` counts, ``D = T`` cumulative per step for the SNN, ``D = 1`` otherwise."""
    import torch

    with torch.no_grad():
        return decoder_of(model).count_operations(net, x)
