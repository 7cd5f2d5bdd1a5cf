"""What accuracy costs in time, decision by decision: accuracy against decision time, the
earliest decision as accurate as the full touch, early exit and the decoder's energy.

Read from the cubes' decision variables (:mod:`pipeline.results.cube`): ``decision_s`` (the
times a decision can be read at), ``decision_correct`` and ``decision_confidence`` (axes...,
model, decision_s, repeat, recording) and the decoder's operation counts ``decoder_acs``,
``decoder_macs``, ``decoder_neuron_updates`` (axes..., model, decision_s). A cube without them
(written before decisions were kept, or of a run that kept none) adds nothing here.

For one design and model, the *decision times* are those at which the model decides for some
recording (the spiking decoder at every step, the rate-coded networks at window boundaries);
the *full touch* is the last of them. What the decoders were trained for is the point's
``training.decisions`` (:class:`~pipeline.design.scene.DecisionTraining`; a cube written before
the field, without its coordinate, was trained for the full touch): trained ``along_touch``, the
accuracy at ``t`` is that of a decoder trained to decide at ``t``; trained ``full_touch``, of
one trained for the end of the touch and read early, which places the earliest decision later
than the data need. The section says which.

* Accuracy at each decision time ``t``: the fraction of (recording, repeat) pairs right at ``t``
  over the recordings decided at ``t`` in every repeat, with its 95 % interval
  (:func:`pipeline.results.stats.accuracy_interval`: Wilson score for one repeat, stratified
  bootstrap over recordings for several).
* The earliest decision time not significantly below the full touch (:func:`earliest_not_below`),
  with decision times ``t_0 < ... < t_F`` (``t_F`` the full touch): for ``k = F-1, F-2, ..., 0``
  in turn, ``accuracy(t_k) - accuracy(t_F)`` is tested by the report's paired test on the
  (recording, repeat) pairs decided at both (:meth:`pipeline.report.evidence.Evidence.compare`:
  two-sided exact McNemar p for one repeat, paired stratified bootstrap p otherwise). The
  sequence stops at the first ``t_k`` with ``p < alpha`` (0.05) and a negative difference, or
  at one with no recording in common; the earliest decision is the last ``t_k`` tested before
  the stop that did not stop it, ``t_F`` when the first test stops it. A time before the stop is
  never chosen, even where it would not be significantly below on its own. Testing in a fixed
  order keeps the family-wise error at alpha without a correction (each hypothesis is tested
  only if every later one was not rejected), and unlike a Holm correction over all times it does
  not make a model with more decision times look earlier.
* Early exit (:func:`pipeline.results.early_exit.early_exit`) at each confidence threshold of
  :data:`~pipeline.results.early_exit.EXIT_THRESHOLDS`: the mean decision time and the accuracy.
* Energy per decision: the decoder's, a band from the operations counted up to the decision
  (:func:`pipeline.results.decoder_energy.decoder_energy_j`), beside the readout's, its power times
  the seconds of touch observed up to the decision, and the two together (the band's ends each
  plus the readout's).

The curves are drawn for each model's best design of the answer (:mod:`pipeline.report.answer`);
the answer's small table gives every design it names its earliest decision ("decides after",
:func:`earliest_decisions`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.design.scene import DecisionTraining, scene_field
from pipeline.report.answer import ModelAnswer, decoder_energy_text
from pipeline.report.blocks import Block, Figure, Heading, Items, Paragraph, Table
from pipeline.report.cubes import field_values, point_keys, sweep_dims
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.report.seeds import rng_for
from pipeline.report.text import comparison, pct, pct_interval, si
from pipeline.results.decision_cube import (
    DECISION_CONFIDENCE,
    DECISION_CORRECT,
    DECISION_DIM,
    DECODER_VARIABLES,
)
from pipeline.results.decoder_energy import DecoderEnergyModel, EnergyBand, decoder_energy_j
from pipeline.results.early_exit import EXIT_THRESHOLDS, early_exit, exit_energy_j
from pipeline.results.stats import PairedComparison, accuracy_interval
from pipeline.results.variables import LABEL, MODEL_DIM, RECORDING_DIM, REPEAT_DIM

#: The cube's decision variables, (axes..., model, decision_s, repeat, recording).
DECISION_VARIABLES = (DECISION_CORRECT, DECISION_CONFIDENCE)
#: The cube's operation counts, (axes..., model, decision_s), in
#: :func:`~pipeline.results.decoder_energy.decoder_energy_j`'s order.
OPERATION_VARIABLES = DECODER_VARIABLES
#: The stem of the latency figure.
LATENCY_STEM = "latency"
#: The scene field that says what the decoders were trained for.
DECISIONS_FIELD = scene_field("training.decisions")
#: What the decoders of a cube without :data:`DECISIONS_FIELD` were trained for (every cube
#: written before the choice).
BEFORE_THE_CHOICE = DecisionTraining.FULL_TOUCH


@dataclass(frozen=True)
class DesignDecisions:
    """One model's decisions at one design, at the times it decides.

    Attributes
    ----------
    decision_s
        float64 (times,): seconds of touch, ascending.
    correct
        int8 (times, repeats, recordings): 1 right, 0 wrong, -1 no decision.
    confidence
        float64 (times, repeats, recordings): softmax probability of the decided class, NaN
        where none.
    labels
        int64 (recordings,): class of each recording.
    operations
        float64 (3, times): mean accumulates, multiply-accumulates and neuron updates per
        decision, cumulative; NaN where the cube does not state them.
    trained
        What the decoder was trained for (the point's ``training.decisions``).
    """

    decision_s: np.ndarray
    correct: np.ndarray
    confidence: np.ndarray
    labels: np.ndarray
    operations: np.ndarray
    trained: DecisionTraining

    def energy(self, model: DecoderEnergyModel) -> EnergyBand:
        """The decoder's energy per decision at each time (float64 (times,) at both ends)."""
        return decoder_energy_j(*self.operations, model)


@dataclass(frozen=True)
class EarliestDecision:
    """The earliest decision time not significantly below the full touch (module docstring).

    ``versus_full`` is its accuracy minus the full touch's (None when it is the full touch);
    ``tested`` counts the comparisons made, ``stopped_by`` the first time found significantly
    below (None: none was).
    """

    decision_s: float
    index: int
    full_s: float
    versus_full: PairedComparison | None
    tested: int
    stopped_by: float | None


@dataclass(frozen=True)
class ExitRow:
    """Early exit at one confidence threshold: mean decision time (s), accuracy (fraction) and
    the mean energies per decision (J; decoder band, readout)."""

    threshold: float
    mean_decision_s: float
    accuracy: float
    decoder: EnergyBand
    readout_j: float


@dataclass(frozen=True)
class LatencyCurve:
    """Accuracy against decision time of one model at one design, and what a decision costs.

    ``mean``, ``low``, ``high`` float64 (times,) are the accuracy and its 95 % interval at each
    of ``decision_s``; ``decoder`` the decoder's energy per decision there (J, both ends);
    ``readout_power_w`` the design's readout power (NaN: unknown), so that a decision read at
    ``t`` cost the readout ``readout_power_w * t``; ``trained`` what the decoder was trained for.
    """

    model: str
    key: str
    label: str
    trained: DecisionTraining
    decision_s: np.ndarray
    mean: np.ndarray
    low: np.ndarray
    high: np.ndarray
    interval: str
    decoder: EnergyBand
    readout_power_w: float
    earliest: EarliestDecision | None
    exits: tuple[ExitRow, ...]

    @property
    def full(self) -> int:
        """Index of the full touch (the last decision time)."""
        return self.decision_s.size - 1

    def energy_at(self, index: int) -> EnergyBand:
        """The decoder's energy per decision at ``decision_s[index]`` (J, floats)."""
        return EnergyBand(float(self.decoder.low_j[index]), float(self.decoder.high_j[index]))

    def readout_j(self, index: int) -> float:
        """The readout's energy for a decision at ``decision_s[index]`` (J; NaN: unknown)."""
        return self.readout_power_w * float(self.decision_s[index])

    def together_at(self, index: int) -> EnergyBand:
        """Decoder and readout together for a decision at ``decision_s[index]`` (J, both ends;
        NaN where either is unknown)."""
        return together(self.energy_at(index), self.readout_j(index))


def together(decoder: EnergyBand, readout_j: float) -> EnergyBand:
    """The energy of a decision for decoder and readout together: each end of the decoder's
    band plus the readout's (J; NaN where either is unknown)."""
    return EnergyBand(float(decoder.low_j) + readout_j, float(decoder.high_j) + readout_j)


def gather_decisions(cubes: Mapping[str, xr.Dataset]) -> dict[tuple[str, str], DesignDecisions]:
    """Every (result key, model) whose cube holds decisions, at the times the model decides
    (the first cube met holding a point wins)."""
    found: dict[tuple[str, str], DesignDecisions] = {}
    for cube in cubes.values():
        if not all(v in cube.variables for v in (*DECISION_VARIABLES, DECISION_DIM, LABEL)):
            continue
        dims = sweep_dims(cube)
        order = (*dims, MODEL_DIM, DECISION_DIM, REPEAT_DIM, RECORDING_DIM)
        correct, confidence = (
            _points(cube[name].transpose(*order), dims) for name in DECISION_VARIABLES
        )
        operations = np.stack(
            [
                _points(cube[name].transpose(*dims, MODEL_DIM, DECISION_DIM), dims)
                if name in cube
                else np.full(correct.shape[:3], np.nan)
                for name in OPERATION_VARIABLES
            ],
            axis=-2,
        )  # (points, model, 3, times)
        times = cube[DECISION_DIM].values.astype(np.float64)
        labels = cube[LABEL].values.astype(np.int64)
        trained = field_values(cube, DECISIONS_FIELD)
        trained = [BEFORE_THE_CHOICE] * correct.shape[0] if trained is None else trained.ravel()
        for p, key in enumerate(point_keys(cube)):
            for m, model in enumerate(str(v) for v in cube[MODEL_DIM].values):
                decided = (correct[p, m] >= 0).any(axis=(-2, -1))
                if (key, model) in found or not decided.any():
                    continue
                found[(key, model)] = DesignDecisions(
                    decision_s=times[decided],
                    correct=correct[p, m][decided].astype(np.int8),
                    confidence=confidence[p, m][decided].astype(np.float64),
                    labels=labels,
                    operations=operations[p, m][:, decided].astype(np.float64),
                    trained=DecisionTraining(str(trained[p])),
                )
    return found


def _points(variable: xr.DataArray, dims: tuple[str, ...]) -> np.ndarray:
    """Values with the sweep dimensions flattened into the first axis (point order)."""
    values = variable.values
    return values.reshape(-1, *values.shape[len(dims) :])


def earliest_not_below(
    decisions: DesignDecisions, key: str, model: str, alpha: float = ALPHA
) -> EarliestDecision:
    """The earliest decision time not significantly below the full touch, by a fixed sequence
    of paired tests from the full touch backwards (see the module docstring)."""
    times = decisions.decision_s
    full = times.size - 1
    # Each time as a point of its own: the report's paired comparison (its recordings and
    # repeats in common, its test, its seeded generator) applies as it does between designs.
    names = [f"{key}@{t!r}s" for t in times]
    evidence = Evidence(
        labels=decisions.labels,
        correct={(name, model): decisions.correct[k] for k, name in enumerate(names)},
    )
    earliest, versus, tested, stopped = full, None, 0, None
    for k in range(full - 1, -1, -1):
        test = evidence.compare(names[k], names[full], model)
        if test is None:  # no recording in common: the sequence cannot go further
            break
        tested += 1
        if test.p_value < alpha and test.difference < 0:
            stopped = float(times[k])
            break
        earliest, versus = k, test
    return EarliestDecision(
        float(times[earliest]), earliest, float(times[full]), versus, tested, stopped
    )


def earliest_decisions(
    decisions: Mapping[tuple[str, str], DesignDecisions],
) -> dict[tuple[str, str], EarliestDecision]:
    """The earliest decision not significantly below the full touch (:func:`earliest_not_below`)
    of every (result key, model) that holds decisions."""
    return {
        (key, model): earliest_not_below(d, key, model) for (key, model), d in decisions.items()
    }


def accuracy_along(
    decisions: DesignDecisions, key: str, model: str
) -> tuple[np.ndarray, np.ndarray, np.ndarray, str]:
    """Accuracy (fraction) and its 95 % interval at each decision time, float64 (times,), and
    the interval's method(s); see the module docstring."""
    n = decisions.decision_s.size
    mean, low, high = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    methods = set()
    for k in range(n):
        cell = decisions.correct[k]
        ran = (cell >= 0).any(axis=-1)
        held = (cell[ran] >= 0).all(axis=0)
        if not held.any():
            continue
        interval = accuracy_interval(
            cell[ran][:, held] == 1,
            decisions.labels[held],
            rng=rng_for("decision", key, model, repr(float(decisions.decision_s[k]))),
        )
        mean[k], low[k], high[k] = interval.estimate, interval.low, interval.high
        methods.add(interval.method)
    return mean, low, high, "; ".join(sorted(methods))


def latency_curve(
    decisions: DesignDecisions,
    key: str,
    model: str,
    label: str,
    readout_power_w: float,
    energy: DecoderEnergyModel,
    thresholds: Sequence[float] = EXIT_THRESHOLDS,
    earliest: EarliestDecision | None = None,
) -> LatencyCurve:
    """Accuracy against decision time, the earliest time not below the full touch (``earliest``
    when already found), early exit and the energies per decision of one model at one design."""
    mean, low, high, interval = accuracy_along(decisions, key, model)
    exits = []
    for threshold in thresholds:
        found = early_exit(decisions.confidence, decisions.correct, decisions.decision_s, threshold)
        exits.append(
            ExitRow(
                threshold=float(threshold),
                mean_decision_s=float(found.mean_decision_s),
                accuracy=float(found.accuracy),
                decoder=exit_energy_j(found, *decisions.operations, energy),
                readout_j=readout_power_w * float(found.mean_decision_s),
            )
        )
    return LatencyCurve(
        model=model,
        key=key,
        label=label,
        trained=decisions.trained,
        decision_s=decisions.decision_s,
        mean=mean,
        low=low,
        high=high,
        interval=interval,
        decoder=decisions.energy(energy),
        readout_power_w=readout_power_w,
        earliest=earliest or earliest_not_below(decisions, key, model),
        exits=tuple(exits),
    )


def full_touch_energies(
    decisions: Mapping[tuple[str, str], DesignDecisions], energy: DecoderEnergyModel
) -> dict[tuple[str, str], EnergyBand]:
    """The decoder's energy per decision at the full touch, by (result key, model), where the
    cube states the operations (float J at both ends)."""
    bands = {}
    for found, d in decisions.items():
        band = decoder_energy_j(*d.operations[:, -1], energy)
        if math.isfinite(band.low_j) and math.isfinite(band.high_j):
            bands[found] = band
    return bands


def latency_curves(
    decisions: Mapping[tuple[str, str], DesignDecisions],
    answers: Sequence[ModelAnswer],
    energy: DecoderEnergyModel,
    earliest: Mapping[tuple[str, str], EarliestDecision] | None = None,
) -> tuple[LatencyCurve, ...]:
    """One :class:`LatencyCurve` per model whose best design (the answer's) holds decisions
    (``earliest``: their earliest decisions, where already found)."""
    curves = []
    for answer in answers:
        design = answer.best.design
        found = decisions.get((design.key, answer.model))
        if found is not None:
            curves.append(
                latency_curve(
                    found,
                    design.key,
                    answer.model,
                    design.label,
                    answer.best.power_w,
                    energy,
                    earliest=(earliest or {}).get((design.key, answer.model)),
                )
            )
    return tuple(curves)


# ---------------------------------------------------------------------------------------------
# The report's blocks


#: Title of the latency curve's sub-section and figure.
LATENCY_TITLE = "Accuracy against decision time"


def latency_blocks(
    curves: Sequence[LatencyCurve], decoder: DecoderEnergyModel, drawn: set[str]
) -> Iterator[Block]:
    """The time section's blocks on decisions: the curve, the earliest decision, early exit and
    the energies per decision; nothing when no cube keeps decisions."""
    if not curves:
        return
    yield Heading(3, LATENCY_TITLE)
    yield Paragraph(training_sentence(curves))
    methods = "; ".join(sorted({c.interval for c in curves if c.interval})) or "none"
    yield Paragraph(
        "Accuracy of a decision read after t seconds of touch, for each model at its best "
        "design (the answer's): every step of a spiking decoder, every window boundary of the "
        f"rate-coded networks. Bands and brackets are the 95 % interval ({methods}). The "
        "earliest decision not significantly below the full touch: each earlier decision time "
        "is compared with the full touch by a paired test on the same recordings and splits "
        "(exact McNemar for one repeat, paired bootstrap otherwise), in a fixed sequence from "
        "the full touch backwards; the first time significantly below it (p < "
        f"{ALPHA:g}, a loss) ends the sequence, and the earliest decision is the time tested "
        "just before it (the full touch when the first test ends it): no time before the end "
        "is chosen, even one that alone would not be below. Testing in a fixed order needs no "
        "correction "
        "for the number of times tested, so a model read more often does not look earlier for "
        "it. Not significantly below is not as accurate: the difference's interval bounds the "
        "loss."
    )
    if LATENCY_STEM in drawn:
        yield Figure(
            LATENCY_STEM,
            f"{LATENCY_TITLE}, each model at its best design. Bands: 95 % interval of accuracy; "
            "dotted lines: the earliest decision not significantly below the full touch.",
        )
    yield Table(
        (
            "model",
            "design",
            "full touch: accuracy [95 % interval]",
            "earliest not significantly below the full touch",
            "its accuracy [95 % interval]",
            "difference to the full touch [95 % interval], p",
        ),
        tuple(_earliest_row(c) for c in curves),
    )
    yield Heading(3, "Early exit")
    yield Paragraph(
        "Each recording is decided at the first time the model's confidence (the softmax "
        "probability of the class it decides) reaches the threshold, else at the full touch; "
        "the mean decision time and the accuracy are over every recording and repeat. The "
        "energies are means per decision up to each recording's exit: the decoder's (a band, "
        "below), the readout's (its power times the seconds of touch observed) and the two "
        "together."
    )
    yield Table(
        (
            "model",
            "confidence threshold",
            "mean decision time",
            "accuracy",
            "decoder energy per decision",
            "readout energy per decision",
            TOGETHER_COLUMN,
        ),
        tuple(
            (
                c.model.upper(),
                f"{row.threshold:g}",
                _seconds(row.mean_decision_s),
                pct(row.accuracy),
                decoder_energy_text(row.decoder),
                si(row.readout_j, "J"),
                decoder_energy_text(together(row.decoder, row.readout_j)),
            )
            for c in curves
            for row in c.exits
        ),
    )
    yield Heading(3, "Energy per decision")
    yield Paragraph(
        "The decoder's energy per decision counts its operations up to the decision, in the "
        "style of NeuroBench: effective synaptic operations (nonzero inputs times fan-out), as "
        "accumulates where the inputs are spikes and as multiply-accumulates where they are "
        "real numbers, and neuron updates; each operation is priced at both ends of its "
        "declared band, so the energy is a band. The readout's energy is its power times the "
        "seconds of touch observed up to the decision (the answer's energy model); together, "
        "each end of the decoder's band plus the readout's. The per-operation energies:"
    )
    yield Items(decoder.assumptions())
    rows = []
    for c in curves:
        picks = [("full touch", c.full)]
        if c.earliest is not None and c.earliest.index != c.full:
            picks.append(("earliest not significantly below", c.earliest.index))
        for name, k in picks:
            rows.append(
                (
                    c.model.upper(),
                    name,
                    _seconds(float(c.decision_s[k])),
                    pct_interval(c.mean[k], c.low[k], c.high[k]),
                    decoder_energy_text(c.energy_at(k)),
                    si(c.readout_j(k), "J"),
                    decoder_energy_text(c.together_at(k)),
                )
            )
    yield Table(
        (
            "model",
            "decision",
            "time",
            "accuracy [95 % interval]",
            "decoder energy per decision",
            "readout energy per decision",
            TOGETHER_COLUMN,
        ),
        tuple(rows),
    )


#: The time section's column of the energy per decision of decoder and readout together.
TOGETHER_COLUMN = "decoder and readout together"

#: What the time section says of decoders trained for each choice of ``training.decisions``.
TRAINED_TEXT = {
    DecisionTraining.ALONG_TOUCH: (
        "trained along the touch (training.decisions = along_touch): the accuracy at each "
        "decision time is that of a decoder trained to decide then"
    ),
    DecisionTraining.FULL_TOUCH: (
        "trained for the full touch alone (training.decisions = full_touch) and read early, "
        "the windows not yet seen set to their training mean: their early decisions are below "
        "what a decoder trained to decide then gets, so the earliest decision not "
        "significantly below the full touch comes later than the recordings need (train "
        "along_touch, the default, to answer how long a touch must last)"
    ),
}


def training_sentence(curves: Sequence[LatencyCurve]) -> str:
    """Which training the decoders of the curves had, in one sentence."""
    kinds = list(dict.fromkeys(c.trained for c in curves))
    if len(kinds) == 1:
        return f"The decoders were {TRAINED_TEXT[kinds[0]]}."
    return " ".join(
        f"{', '.join(c.model.upper() for c in curves if c.trained is kind)}: {TRAINED_TEXT[kind]}."
        for kind in kinds
    )


def _earliest_row(curve: LatencyCurve) -> tuple[str, ...]:
    full = curve.full
    found = curve.earliest
    at_full = pct_interval(curve.mean[full], curve.low[full], curve.high[full])
    if found is None or found.index == full:
        why = "" if found is None or found.stopped_by is None else " (an earlier one is below)"
        return (
            curve.model.upper(),
            curve.label,
            f"{at_full} at {_seconds(float(curve.decision_s[full]))}",
            f"the full touch{why}",
            at_full,
            "-",
        )
    k = found.index
    return (
        curve.model.upper(),
        curve.label,
        f"{at_full} at {_seconds(float(curve.decision_s[full]))}",
        _seconds(found.decision_s),
        pct_interval(curve.mean[k], curve.low[k], curve.high[k]),
        "-" if found.versus_full is None else comparison(found.versus_full),
    )


def _seconds(value: float) -> str:
    return f"{value:.3g} s" if math.isfinite(value) else "unknown"
