"""Stratified k-fold cross-validation of the texture classifiers, all folds trained at once.

The procedure:

* Folds: :class:`sklearn.model_selection.StratifiedKFold` with ``n_splits = training.folds``,
  ``shuffle=True`` and ``random_state = training.seed`` (seeds of ``2**32`` and above, which
  scikit-learn does not accept, go through a ``RandomState`` seeded from
  ``numpy.random.SeedSequence(seed)``).
* Decoders: what a model reads, how its inputs are prepared, how it is built, how long it trains
  and how it decides along the touch is its decoder's (:mod:`pipeline.chain.decoders`); this
  module runs the same procedure for every decoder.
* Inputs: each fold's frames are prepared with that fold's TRAINING recordings only: the FFNN's
  and CNN's standardized per feature (one feature = one (channel, taxel, window) cell) with
  their mean and population standard deviation
  (:func:`pipeline.chain.decoders.standardize`; a zero or non-finite standard deviation is
  replaced by 1, so all-zero frames give zeros, never NaN), the SNN's as ``training.snn.inputs``
  says (standardized so by default).
  Inputs are float32.
* Training: PyTorch's default initialization per fold, Adam (``lr = training.learning_rate``;
  the SNN's ``training.snn.learning_rate`` when set,
  betas 0.9/0.999, eps 1e-8), mean cross-entropy on logits per mini-batch
  (:func:`pipeline.chain.folded.fold_loss`), the decoder's epochs (``training.epochs``; the SNN's
  ``training.snn.epochs``) of mini-batches of ``training.batch_size`` drawn in a fresh random
  order every epoch. The loss is the decoder's (:meth:`pipeline.chain.decoders.Decoder.loss`),
  of the decision at the end of the touch (``training.decisions = "full_touch"``) or of
  decisions along it (``"along_touch"``): then every training sample is, in each epoch, read
  at one decision column, the columns of an epoch's samples spread evenly over the frame's
  (a fresh random order per epoch, from the fold's own generator ``"decisions"``).
* Evaluation: accuracy of ``argmax(logits)`` on each fold's test recordings (as each chip gives
  them, for a classifier deployed on chips: :mod:`pipeline.chain.deployment`), and the
  out-of-fold prediction of every recording (each recording is tested in exactly one fold), so
  two designs evaluated on the same recordings can be compared recording by recording.
* Repeats: ``training.repeats`` independent cross-validations, each a fresh stratified split.
  Repeat 0 uses ``training.seed`` itself (one repeat is the paper's procedure); repeat ``r > 0``
  uses the seed :func:`repeat_seed` derives from ``(training.seed, r)``.

Randomness comes only from generators derived from ``(repeat seed, fold index)``
(:func:`pipeline.chain.models.fold_generator`), so a fold's result does not depend on which other
folds it is trained with.

Training the folds at once
--------------------------
All ``F`` folds train as one computation (``batched=True``): the fold-batched model
(:mod:`pipeline.chain.models`) takes ``(F, B, ...)`` inputs, the losses of the folds are summed, so
each fold's parameters receive exactly that fold's gradient, and the Adam update is elementwise with
per-fold step counts (:class:`FoldAdam`). Training sets may differ in size by one between folds;
each fold's epoch order is padded to the largest set, the padded positions get loss weight 0, and
a fold whose mini-batch holds only padding skips that optimizer step altogether (no moment decay,
no step count), exactly as if it had trained alone. ``batched=False`` runs the same code once per
fold with ``F = 1``. The two agree up to floating-point summation order.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import torch
from sklearn.model_selection import StratifiedKFold
from torch.optim.adam import adam as functional_adam

from pipeline.chain.decoders import Decoder, build_model, decoder_of
from pipeline.chain.models import fold_generator
from pipeline.design.scene import DecisionTraining, Model, TrainingSpec
from pipeline.errors import SimulationError

__all__ = [
    "CrossValidation",
    "FoldAdam",
    "cross_validate",
    "fit_folds",
    "predict_folds",
    "repeat_seed",
    "stratified_folds",
]


@dataclass(frozen=True, eq=False)
class CrossValidation:
    """Cross-validated accuracy of one model (compared by identity: it holds arrays).

    Attributes
    ----------
    model
        The classifier.
    fold_accuracy
        float64 ``(repeats, folds)``, read-only: fraction of each fold's test recordings
        classified correctly, in ``[0, 1]``; ``[r, f]`` is fold ``f`` of repeat ``r``'s split.
    seconds
        Wall time (s) of standardization, training and evaluation of all folds.
    train_loss
        float64 ``(repeats, folds)``, read-only, or ``None``: each fold's mean training
        cross-entropy (nats) over the mini-batches of its last epoch; a diagnostic
        (``log(n_classes)`` is the loss of a model that learned nothing but the class frequencies
        of a balanced set).
    predicted
        int64 ``(repeats, n_recordings)``, read-only, or ``None``: the label (as given in
        ``labels``) each recording got from the model of the fold that tested it.
    test_fold
        int64 ``(repeats, n_recordings)``, read-only, or ``None``: the fold that tested each
        recording.
    decision_s
        float64 ``(D,)``, read-only, or ``None``: the decision times (s of touch) at which
        decisions were read, the end of every frame column (window or step); ``None`` when
        :func:`cross_validate` was not told the column length.
    decision_predicted
        int64 ``(repeats, D, n_recordings)``, read-only, or ``None``: the label each recording
        got from its fold's model read at each decision time (the last is ``predicted``).
    decision_confidence
        float32 ``(repeats, D, n_recordings)``, read-only, or ``None``: the softmax probability
        of that label.
    operations
        float64 ``(D, 3)``, read-only, or ``None``: mean over recordings (and repeats) of the
        accumulates, multiply-accumulates and neuron updates a decision read at each decision
        time cost (:func:`pipeline.chain.decoders.count_operations`).
    chip_accuracy
        float64 ``(chips, repeats, folds)``, read-only, or ``None``: ``fold_accuracy`` of every
        chip of a scene that simulates chips (:mod:`pipeline.chain.deployment`);
        ``fold_accuracy`` is then chip 0's.
    chip_predicted
        int64 ``(chips, repeats, n_recordings)``, read-only, or ``None``: ``predicted`` of every
        chip.
    """

    model: Model
    fold_accuracy: np.ndarray
    seconds: float
    train_loss: np.ndarray | None = None
    predicted: np.ndarray | None = None
    test_fold: np.ndarray | None = None
    decision_s: np.ndarray | None = None
    decision_predicted: np.ndarray | None = None
    decision_confidence: np.ndarray | None = None
    operations: np.ndarray | None = None
    chip_accuracy: np.ndarray | None = None
    chip_predicted: np.ndarray | None = None

    def __post_init__(self) -> None:
        # (name, dtype, whether a 1-D array is one repeat's row)
        for name, dtype, rows in (
            ("fold_accuracy", np.float64, True),
            ("train_loss", np.float64, True),
            ("predicted", np.int64, True),
            ("test_fold", np.int64, True),
            ("decision_s", np.float64, False),
            ("decision_predicted", np.int64, False),
            ("decision_confidence", np.float32, False),
            ("operations", np.float64, False),
            ("chip_accuracy", np.float64, False),
            ("chip_predicted", np.int64, False),
        ):
            value = getattr(self, name)
            if value is not None:
                value = np.array(value, dtype=dtype)
                value = value.reshape(1, -1) if rows and value.ndim == 1 else value
                value.setflags(write=False)
                object.__setattr__(self, name, value)

    @property
    def mean(self) -> float:
        """Mean accuracy over repeats and folds."""
        return float(np.mean(self.fold_accuracy))

    @property
    def std(self) -> float:
        """Population standard deviation (``ddof=0``) of the accuracy over folds (and repeats)."""
        return float(np.std(self.fold_accuracy, ddof=0))


class FoldAdam:
    """Adam for fold-batched parameters, with a separate optimizer state per fold.

    Every parameter has a leading fold dimension ``F``. The values of fold ``f`` of all
    parameters are moved into row ``f`` of one float32 ``(F, P)`` buffer, and each row is
    stepped by PyTorch's fused Adam kernel (:func:`torch.optim.adam.adam` with ``fused=True``;
    PyTorch's default constants, no weight decay) as its own tensor: each fold has its own
    moments AND its own step count, so a step can be skipped for some folds (their parameters,
    moments and bias corrections stay exactly as they were). The parameters themselves are
    re-pointed (:meth:`torch.Tensor.set_`) at their slices of the buffer, so the step updates
    them in place with no copy back. The functional form is used instead of
    :class:`torch.optim.Adam` to avoid its per-step Python overhead (about 0.2 ms, as much as
    the kernel itself).

    Parameters
    ----------
    params
        Float32 tensors ``(F, ...)``, updated in place by :meth:`step`. On return their storage
        is the optimizer's buffer (same values and shapes; fold stride ``P``).
    lr
        Learning rate.
    betas, eps
        Adam's constants.
    """

    def __init__(
        self,
        params: Sequence[torch.Tensor],
        lr: float,
        betas: tuple[float, float] = (0.9, 0.999),
        eps: float = 1e-8,
    ):
        self.params = list(params)
        self.lr, (self.beta1, self.beta2), self.eps = float(lr), betas, float(eps)
        self.n_folds = int(self.params[0].shape[0])
        with torch.no_grad():
            self._values = torch.cat([p.reshape(self.n_folds, -1) for p in self.params], dim=1)
            start = 0
            for p in self.params:
                stop = start + p[0].numel()
                p.set_(self._values[:, start:stop].view(p.shape))
                start = stop
        self._grad = torch.empty_like(self._values)
        self._exp_avg = torch.zeros_like(self._values)
        self._exp_avg_sq = torch.zeros_like(self._values)
        # One list entry per fold: value, gradient, moments and step count of that fold.
        self._folds = list(
            zip(
                self._values.unbind(0),
                self._grad.unbind(0),
                self._exp_avg.unbind(0),
                self._exp_avg_sq.unbind(0),
                [torch.zeros((), dtype=torch.float32) for _ in range(self.n_folds)],
                strict=True,
            )
        )

    @property
    def steps(self) -> np.ndarray:
        """int64 ``(F,)``: optimizer steps taken by each fold."""
        return np.array([int(fold[4]) for fold in self._folds], dtype=np.int64)

    @torch.no_grad()
    def step(self, grads: Sequence[torch.Tensor], active: Sequence[bool] | None = None) -> None:
        """Apply one Adam step.

        Parameters
        ----------
        grads
            One gradient per parameter, same shapes as the parameters.
        active
            ``F`` flags: folds that take this step; ``None`` means all.
        """
        torch.cat([g.reshape(self.n_folds, -1) for g in grads], dim=1, out=self._grad)
        folds = self._folds
        if active is not None:
            folds = [fold for fold, on in zip(folds, active, strict=True) if on]
            if not folds:
                return
        values, grad, exp_avg, exp_avg_sq, steps = (list(x) for x in zip(*folds, strict=True))
        functional_adam(
            values,
            grad,
            exp_avg,
            exp_avg_sq,
            [],
            steps,
            fused=True,
            amsgrad=False,
            beta1=self.beta1,
            beta2=self.beta2,
            lr=self.lr,
            weight_decay=0.0,
            eps=self.eps,
            maximize=False,
        )


def repeat_seed(seed: int, repeat: int) -> int:
    """The training seed of cross-validation repeat ``repeat`` (``seed`` itself for repeat 0).

    Repeat ``r > 0`` takes ``SeedSequence([seed, r, 0x5EED])``'s first 63-bit state word, so
    repeats are independent of each other and of the fold streams drawn from each repeat's seed.
    """
    if repeat == 0:
        return int(seed)
    state = np.random.SeedSequence([seed, repeat, 0x5EED]).generate_state(1, dtype=np.uint64)
    return int(state[0] >> np.uint64(1))


def stratified_folds(
    labels: np.ndarray, n_folds: int, seed: int
) -> list[tuple[np.ndarray, np.ndarray]]:
    """Stratified, shuffled k-fold split.

    Parameters
    ----------
    labels
        int ``(n,)`` class labels.
    n_folds
        Number of folds ``k >= 2``; every class must have at least ``k`` samples.
    seed
        ``random_state`` of :class:`sklearn.model_selection.StratifiedKFold` (a seed
        ``>= 2**32`` is mapped through ``numpy.random.SeedSequence``).

    Returns
    -------
    list of (train_index, test_index)
        int64 index arrays, one pair per fold, in scikit-learn's order.
    """
    if seed < 2**32:
        state: int | np.random.RandomState = seed
    else:
        state = np.random.RandomState(np.random.MT19937(np.random.SeedSequence(seed)))
    splitter = StratifiedKFold(n_splits=n_folds, shuffle=True, random_state=state)
    return [
        (train.astype(np.int64), test.astype(np.int64))
        for train, test in splitter.split(np.zeros(len(labels)), labels)
    ]


def cross_validate(
    frames: np.ndarray,
    labels: np.ndarray,
    model: Model,
    training: TrainingSpec,
    *,
    class_names: Sequence[str] | None = None,
    batched: bool = True,
    frame_s: float | None = None,
    tested: np.ndarray | None = None,
) -> CrossValidation:
    """Stratified k-fold cross-validated accuracy of one classifier.

    Parameters
    ----------
    frames
        ``(n_recordings, C, H, W)`` spike counts (int64 or float) the classifier trains on: C
        channels (polarities), H taxels in raster order, W columns, the frames its decoder reads
        (:attr:`pipeline.chain.decoders.Decoder.reads`: windows, or for the SNN 2 polarities
        and steps), prepared fold by fold as it prepares them (standardized for the FFNN and
        CNN, as ``training.snn.inputs`` says for the SNN:
        :meth:`~pipeline.chain.decoders.Decoder.prepare`).
    labels
        int64 ``(n_recordings,)`` class of each recording (indices into ``class_names`` when
        given; any integers otherwise).
    model
        The classifier (:func:`pipeline.chain.decoders.decoder_of` says how it is built,
        trained and read).
    training
        Folds, epochs, batch size, learning rate, hidden units and seed.
    class_names
        Names of the classes, used in error messages.
    batched
        Train all folds as one batched computation (fast); ``False`` trains them one after the
        other with the same code. Both give the same result up to floating-point rounding.
    frame_s
        Seconds of touch per frame column (the window, or the SNN's step). When given, every
        test recording's decision is also read at the end of every column, with its confidence
        and its operations (:attr:`CrossValidation.decision_s`), by its decoder
        (:meth:`~pipeline.chain.decoders.Decoder.decide`): the SNN's output at every step; the
        FFNN's and CNN's on the frame's first ``k`` windows, the later ones set to their
        training mean (0 once standardized), for every ``k``.
    tested
        ``(n_chips, n_recordings, C, H, W)``: the frames every chip gives of the recordings,
        when the classifier trained on ``frames`` is tested on chips
        (:mod:`pipeline.chain.deployment`): each fold's model, trained once on its training
        recordings' ``frames``, is tested on its held-out recordings as every chip gives them,
        prepared with the training frames' statistics. None: tested on ``frames``.

    Returns
    -------
    CrossValidation
        Per-fold accuracy (``[r, f]``: fold ``f`` of :func:`stratified_folds` seeded with
        :func:`repeat_seed` ``(training.seed, r)``), every recording's out-of-fold prediction and
        test fold per repeat, and the wall time; with ``tested``, those of chip 0 and every
        chip's accuracy and predictions (``chip_accuracy``, ``chip_predicted``), the decisions
        chip 0's.

    Raises
    ------
    SimulationError
        Fewer than 2 classes, or a class with fewer recordings than ``training.folds``.
    ValueError
        ``frames`` is not 4-D, or ``frames`` and ``labels`` disagree in length, or ``tested``
        is not ``frames``' shape per chip, or the frames hold non-finite values.
    """
    start = time.perf_counter()
    frames = np.asarray(frames)
    labels = np.asarray(labels)
    if frames.ndim != 4:
        raise ValueError(f"frames must be (n_recordings, C, H, W), got shape {frames.shape}")
    if labels.shape != (frames.shape[0],):
        raise ValueError(f"labels must be ({frames.shape[0]},), got shape {labels.shape}")
    chips = frames[None] if tested is None else np.asarray(tested)
    if chips.ndim != 5 or chips.shape[1:] != frames.shape:
        raise ValueError(f"tested must be (chips, *{frames.shape}), got shape {chips.shape}")
    if not (np.all(np.isfinite(frames)) and np.all(np.isfinite(chips))):
        raise ValueError("frames hold non-finite values")
    decoder = decoder_of(model)
    classes, y = _checked_classes(labels, training.folds, class_names)
    decide = frame_s is not None
    n_chips, sample = chips.shape[0], frames.shape[1:]
    accuracy = np.zeros((n_chips, training.repeats, training.folds))
    predicted = np.zeros((n_chips, training.repeats, len(y)), dtype=np.int64)
    test_fold = np.zeros((training.repeats, len(y)), dtype=np.int64)
    train_loss = []
    n_decisions = frames.shape[-1]
    decided = np.zeros((training.repeats, n_decisions, len(y)), dtype=np.int64)
    confidence = np.zeros((training.repeats, n_decisions, len(y)), dtype=np.float32)
    operations = np.zeros((n_decisions, 3), dtype=np.float64)
    for repeat in range(training.repeats):
        seed = repeat_seed(training.seed, repeat)
        splits = stratified_folds(y, training.folds, seed)
        # Every chip's held-out frames of a fold (chip-major rows), prepared as its training
        # frames were; the decisions are read on chip 0's, the first rows.
        train_x, test_x = zip(
            *(
                decoder.prepare(frames[tr], chips[:, te].reshape(-1, *sample), training)
                for tr, te in splits
            ),
            strict=True,
        )
        groups = [list(range(len(splits)))] if batched else [[f] for f in range(len(splits))]
        fold_losses, fold_predicted, fold_decisions = [], [], []
        for group in groups:
            loss, guess, decisions = _train_and_evaluate(
                [train_x[f] for f in group],
                [y[splits[f][0]] for f in group],
                [test_x[f] for f in group],
                [len(splits[f][1]) for f in group],
                group,
                decoder,
                len(classes),
                training,
                seed,
                decide,
            )
            fold_losses.append(loss)
            fold_predicted.extend(guess)
            fold_decisions.extend(decisions)
        for f, (_, test) in enumerate(splits):
            guess = fold_predicted[f].reshape(n_chips, len(test))
            accuracy[:, repeat, f] = (guess == y[test]).mean(axis=1)
            predicted[:, repeat, test] = classes[guess]
            test_fold[repeat, test] = f
            if decide:
                guess_d, confidence_d, operations_d = fold_decisions[f]
                decided[repeat][:, test] = classes[guess_d]
                confidence[repeat][:, test] = confidence_d
                operations += operations_d.sum(axis=0)
        train_loss.append(np.concatenate(fold_losses))
    operations /= training.repeats * len(y)
    times = decision_times_s(frame_s, n_decisions) if decide else None
    decisions = (times, decided, confidence, operations) if decide else (None,) * 4
    return CrossValidation(
        decoder.model,
        accuracy[0],
        time.perf_counter() - start,
        np.stack(train_loss),
        predicted[0],
        test_fold,
        *decisions,
        chip_accuracy=None if tested is None else accuracy,
        chip_predicted=None if tested is None else predicted,
    )


def _checked_classes(
    labels: np.ndarray, n_folds: int, class_names: Sequence[str] | None
) -> tuple[np.ndarray, np.ndarray]:
    """The distinct labels and every recording's index into them, refused unless there are at
    least 2 classes of at least ``n_folds`` recordings each."""
    classes, y, counts = np.unique(labels, return_inverse=True, return_counts=True)

    def name(label: int) -> str:
        if class_names is not None and 0 <= label < len(class_names):
            return repr(class_names[label])
        return repr(int(label))

    if len(classes) < 2:
        found = ", ".join(name(c) for c in classes) or "none"
        raise SimulationError(
            f"cross-validation needs at least 2 classes, got {len(classes)} ({found})"
        )
    short = [f"{name(c)} ({k})" for c, k in zip(classes, counts, strict=True) if k < n_folds]
    if short:
        raise SimulationError(
            f"class{'es' if len(short) > 1 else ''} {', '.join(short)} "
            f"{'have' if len(short) > 1 else 'has'} fewer recordings than "
            f"training.folds = {n_folds}"
        )
    return classes, y


def decision_times_s(frame_s: float, n_columns: int) -> np.ndarray:
    """float64 ``(n_columns,)``: the end of every frame column, ``(k + 1) * frame_s``, rounded
    to the nanosecond so that the times of different columns that coincide (a window boundary
    and a step's end) compare equal."""
    return np.round((np.arange(n_columns, dtype=np.float64) + 1.0) * frame_s, 9)


def _stack_padded(
    arrays: Sequence[np.ndarray], dtype: torch.dtype
) -> tuple[torch.Tensor, np.ndarray]:
    """Stack ``(n_f, ...)`` arrays into a zero-padded ``(F, max n_f, ...)`` tensor; return sizes."""
    sizes = np.array([len(a) for a in arrays], dtype=np.int64)
    out = torch.zeros((len(arrays), int(sizes.max()), *arrays[0].shape[1:]), dtype=dtype)
    for f, a in enumerate(arrays):
        out[f, : len(a)] = torch.from_numpy(np.ascontiguousarray(a))
    return out, sizes


def _train_and_evaluate(
    train_x: Sequence[np.ndarray],
    train_y: Sequence[np.ndarray],
    test_x: Sequence[np.ndarray],
    n_decided: Sequence[int],
    folds: Sequence[int],
    decoder: Decoder,
    n_classes: int,
    training: TrainingSpec,
    seed: int,
    decide: bool = False,
) -> tuple[np.ndarray, list[np.ndarray], list[tuple[np.ndarray, ...]]]:
    """Train the given folds as one batch (``F = len(folds)``); return their loss, predictions
    and, with ``decide``, the decisions at every frame column (:func:`_decisions`; else ``[]``)
    of the first ``n_decided[i]`` test inputs of each.

    ``train_x[i]`` is float32 ``(n_i, C, H, W)``, ``train_y[i]`` int ``(n_i,)`` for fold
    ``folds[i]``, ``test_x[i]`` float32 ``(m_i, C, H, W)``; ``seed`` is the repeat's training
    seed. Returns float64 ``(F,)`` mean training loss of the last epoch, and per fold the int64
    ``(m_i,)`` predicted class indices of its test inputs, in order.
    """
    net, train_loss = fit_folds(train_x, train_y, folds, decoder, n_classes, training, seed)
    guesses = predict_folds(net, test_x)
    decisions = []
    if decide:
        decided_x = [x[:n] for x, n in zip(test_x, n_decided, strict=True)]
        decisions = _decisions(net, decoder, *_stack_padded(decided_x, torch.float32))
    return train_loss, guesses, decisions


def fit_folds(
    train_x: Sequence[np.ndarray],
    train_y: Sequence[np.ndarray],
    folds: Sequence[int],
    model: Model | Decoder,
    n_classes: int,
    training: TrainingSpec,
    seed: int,
) -> tuple[torch.nn.Module, np.ndarray]:
    """Train the given folds as one batch (``F = len(folds)``): the trained fold-batched net
    (in eval mode) and float64 ``(F,)`` mean training loss of the last epoch.

    ``train_x[i]`` is float32 ``(n_i, C, H, W)`` and ``train_y[i]`` int ``(n_i,)`` for fold
    ``folds[i]``, prepared as its decoder prepares them; ``model`` is the model or its decoder
    (:func:`pipeline.chain.decoders.decoder_of`), which builds the net, says how many epochs it
    trains and what loss (:meth:`~pipeline.chain.decoders.Decoder.loss`); ``seed`` is the repeat's
    training seed."""
    decoder = model if isinstance(model, Decoder) else decoder_of(model)
    n_folds = len(folds)
    sample_shape = tuple(train_x[0].shape[1:])
    x, n_train = _stack_padded(train_x, torch.float32)
    target, _ = _stack_padded([np.asarray(t, dtype=np.int64) for t in train_y], torch.int64)
    n_max = int(n_train.max())
    x_rows = x.reshape(n_folds * n_max, *sample_shape)
    target_rows = target.reshape(n_folds * n_max)

    net = build_model(
        decoder.model,
        sample_shape,
        n_classes,
        training.hidden_units,
        n_folds,
        [fold_generator(seed, f, "init") for f in folds],
        training.snn,
    )
    epochs = decoder.epochs(training)
    params = [p for p in net.parameters()]
    optimizer = FoldAdam(params, decoder.learning_rate(training))

    # Epoch orders: per fold, a fresh permutation of its own training set per epoch from its own
    # generator, padded with row 0 of the fold (weight 0) up to n_max; as flat row indices.
    order = torch.zeros(epochs, n_folds, n_max, dtype=torch.int64)
    for i, fold in enumerate(folds):
        shuffle = fold_generator(seed, fold, "shuffle")
        n = int(n_train[i])
        for epoch in range(epochs):
            order[epoch, i, :n] = torch.randperm(n, generator=shuffle)
    order += (torch.arange(n_folds) * n_max).reshape(1, n_folds, 1)
    ends = _decision_columns(seed, folds, n_train, epochs, sample_shape[-1], training.decisions)

    # Mini-batches cover positions [s, s + batch_size) of every fold's order. Loss weights make
    # each fold's contribution its mean over its real samples; folds without any real sample in
    # a batch skip the optimizer step.
    real = torch.arange(n_max).reshape(1, n_max) < torch.from_numpy(n_train).reshape(n_folds, 1)
    batches = []
    active_batches = torch.from_numpy(-(-n_train // training.batch_size)).to(torch.float32)
    for s in range(0, n_max, training.batch_size):
        stop = min(s + training.batch_size, n_max)
        in_batch = real[:, s:stop]
        count = in_batch.sum(dim=1, keepdim=True)
        weights = (in_batch / count.clamp(min=1)).to(torch.float32)
        active = count.reshape(n_folds) > 0
        batches.append((s, stop, weights, None if bool(active.all()) else active.tolist()))

    net.train()
    last_loss = torch.zeros(n_folds, dtype=torch.float32)
    for epoch in range(epochs):
        epoch_order = order[epoch]
        for s, stop, weights, active in batches:
            rows = epoch_order[:, s:stop].reshape(-1)
            xb = x_rows.index_select(0, rows).reshape(n_folds, stop - s, *sample_shape)
            yb = target_rows.index_select(0, rows).reshape(n_folds, stop - s)
            eb = None if ends is None else ends[epoch][:, s:stop]
            loss = decoder.loss(net, xb, yb, weights, eb)
            grads = torch.autograd.grad(loss.sum(), params)
            optimizer.step(grads, active)
            if epoch == epochs - 1:
                last_loss += loss.detach()

    net.eval()
    return net, (last_loss / active_batches).numpy().astype(np.float64)


def _decision_columns(
    seed: int,
    folds: Sequence[int],
    n_train: np.ndarray,
    epochs: int,
    n_columns: int,
    decisions: DecisionTraining,
) -> torch.Tensor | None:
    """The decision column each position of each fold's epoch order is trained at: int64
    ``(epochs, F, n_max)`` in ``[0, n_columns)``, or None for ``full_touch`` (no draw at all).

    Along the touch, fold ``f``'s ``n_f`` positions of an epoch take the columns
    ``permutation(n_f) mod n_columns`` from the fold's own generator (``"decisions"``): every
    column equally often in every epoch (up to one), in a fresh random order (padding: 0)."""
    if decisions is DecisionTraining.FULL_TOUCH:
        return None
    ends = torch.zeros(epochs, len(folds), int(n_train.max()), dtype=torch.int64)
    for i, fold in enumerate(folds):
        draw = fold_generator(seed, fold, "decisions")
        n = int(n_train[i])
        for epoch in range(epochs):
            ends[epoch, i, :n] = torch.randperm(n, generator=draw) % n_columns
    return ends


def predict_folds(net: torch.nn.Module, test_x: Sequence[np.ndarray]) -> list[np.ndarray]:
    """Each fold's predicted class indices: int64 ``(n_i,)`` for fold ``i``'s float32 inputs
    ``test_x[i]`` ``(n_i, C, H, W)``, by the fold-batched ``net`` of :func:`fit_folds`."""
    xt, n_test = _stack_padded(test_x, torch.float32)
    with torch.inference_mode():
        predicted = net(xt).argmax(dim=-1)
    return [predicted[i, : int(n)].numpy().astype(np.int64) for i, n in enumerate(n_test)]


@torch.inference_mode()
def _decisions(
    net: torch.nn.Module, decoder: Decoder, xt: torch.Tensor, n_test: np.ndarray
) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Every fold's decisions at the end of every frame column of its test inputs ``xt``
    (float32 ``(F, B, C, H, W)``, fold ``f``'s first ``n_test[f]`` rows real), as its decoder
    reads them (:meth:`~pipeline.chain.decoders.Decoder.decide`).

    Returns, per fold: int64 ``(W, n_test_f)`` class indices, float32 ``(W, n_test_f)`` their
    softmax probability, float64 ``(n_test_f, W, 3)`` operations (:mod:`pipeline.chain.operations`).
    """
    logits, operations = decoder.decide(net, xt)  # (F, B, W, n_classes), (F, B, W, 3)
    probability, decided = torch.softmax(logits, dim=-1).max(dim=-1)  # (F, B, W)
    return [
        (
            decided[f, : int(n)].T.numpy().astype(np.int64),
            probability[f, : int(n)].T.numpy().astype(np.float32),
            operations[f, : int(n)],
        )
        for f, n in enumerate(n_test)
    ]
