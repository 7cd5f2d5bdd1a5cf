"""The answer to the designer's question: the cheapest design as accurate as the best one.

For each model, over every distinct design of the run (:mod:`pipeline.report.designs`):

1. The *best* design is the one with the highest accuracy (``accuracy_mean``; ties go to the lower
   data rate, then to the first met).
2. Every other design ``d`` is compared with the best by a paired test on the same recordings
   (:meth:`pipeline.report.evidence.Evidence.compare`: ``accuracy(d) - accuracy(best)``, its 95 %
   interval, exact McNemar p for one repeat). The ``m`` p-values are Holm-corrected over those
   ``m`` comparisons (:func:`pipeline.results.stats.holm`). ``d`` is *significantly below* the best
   when its adjusted p is below ``ALPHA`` (0.05) and its difference is negative.
3. The designs not significantly below the best (the best included) are *as accurate as the
   best* as far as this run can tell; among them the cheapest by address-event data rate and the
   cheapest by estimated readout power (:func:`pipeline.results.hardware.event_power_w`) are the
   answer
   (ties go to the more accurate, then to the first met). Designs that cannot be compared with the
   best (no per-recording results, or no recording in common) are never chosen.

Each answer is set against the frame-based readout of the same array (``rows * cols`` taxels,
``bits`` per sample at ``rate_hz``): its data rate ``n * bits * rate_hz`` and its power
(:func:`pipeline.results.hardware.frame_power_w`), as ``frame / event`` ratios.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from dataclasses import dataclass

from pipeline.report import paper
from pipeline.report.designs import Accuracy, Cost, Design, FrameReadout, cost
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.report.panels import REPEATS
from pipeline.report.text import (
    NO_INTERVAL_WHY,
    comparison,
    fold_spread,
    pct_interval,
    rate,
    si,
    times,
)
from pipeline.results.hardware import EnergyModel
from pipeline.results.stats import PairedComparison, holm


@dataclass(frozen=True)
class Candidate:
    """One design for one model, measured against the model's best design.

    ``versus_best`` is ``accuracy(design) - accuracy(best)`` (None for the best itself and for a
    design that cannot be compared); ``holm_p`` its Holm-adjusted p-value. Frame figures are None
    when the frame readout or the array size is unknown.
    """

    design: Design
    accuracy: Accuracy
    versus_best: PairedComparison | None
    holm_p: float | None
    data_rate_bps: float
    power_w: float
    frame_data_rate_bps: float | None
    frame_power_w: float | None

    @property
    def below_best(self) -> bool:
        """Significantly below the best (Holm-adjusted p < ALPHA and a negative difference)."""
        return (
            self.versus_best is not None
            and self.holm_p is not None
            and self.holm_p < ALPHA
            and self.versus_best.difference < 0
        )

    @property
    def data_rate_ratio(self) -> float:
        """Frame readout's data rate over this design's (inf when it sends nothing)."""
        return _ratio(self.frame_data_rate_bps, self.data_rate_bps)

    @property
    def power_ratio(self) -> float:
        return _ratio(self.frame_power_w, self.power_w)


@dataclass(frozen=True)
class ModelAnswer:
    """The answer for one model.

    ``by_data_rate``/``by_power`` are None when no comparison with the best can be made
    (``can_compare`` False: the best has no per-recording results, a run that predates them) or
    no design states that cost; ``comparisons`` is the size ``m`` of the Holm family,
    ``untested`` the designs that could not be compared.
    """

    model: str
    can_compare: bool
    best: Candidate
    by_data_rate: Candidate | None
    by_power: Candidate | None
    comparisons: int
    untested: int
    candidates: tuple[Candidate, ...]

    @property
    def as_accurate(self) -> tuple[Candidate, ...]:
        """The best and every design compared with it and not significantly below it."""
        return tuple(
            c for c in self.candidates if c is self.best or (c.versus_best and not c.below_best)
        )


def design_answers(
    designs: Sequence[Design],
    evidence: Evidence,
    energy: EnergyModel,
    frame: FrameReadout | None,
) -> tuple[ModelAnswer, ...]:
    """One :class:`ModelAnswer` per model that any design trained, in the order first met."""
    models = list(dict.fromkeys(m for d in designs for m in d.accuracy))
    return tuple(
        answer
        for model in models
        if (answer := model_answer(designs, evidence, model, energy, frame)) is not None
    )


def model_answer(
    designs: Sequence[Design],
    evidence: Evidence,
    model: str,
    energy: EnergyModel,
    frame: FrameReadout | None,
) -> ModelAnswer | None:
    """The answer for ``model`` (see the module docstring); None if no design trained it."""
    mine = [d for d in designs if model in d.accuracy]
    if not mine:
        return None

    def rank(d: Design) -> tuple[float, float]:
        rate_bps = d.data_rate_bps if math.isfinite(d.data_rate_bps) else math.inf
        return (-d.accuracy[model].mean, rate_bps)

    best = min(mine, key=rank)  # min is stable: the first met among equals
    others = [d for d in mine if d is not best]
    tests = [evidence.compare(d.key, best.key, model) for d in others]
    tested = [t for t in tests if t is not None]
    adjusted = iter(holm([t.p_value for t in tested]))
    holm_ps = [None if t is None else float(next(adjusted)) for t in tests]

    def candidate(d: Design, test: PairedComparison | None, holm_p: float | None) -> Candidate:
        n = d.n_taxels
        known = frame is not None and n is not None
        return Candidate(
            design=d,
            accuracy=d.accuracy[model],
            versus_best=test,
            holm_p=holm_p,
            data_rate_bps=cost(d, model, Cost.DATA_RATE, energy),
            power_w=cost(d, model, Cost.POWER, energy),
            frame_data_rate_bps=frame.data_rate_bps(n) if known else None,
            frame_power_w=frame.power_w(n, energy) if known else None,
        )

    top = candidate(best, None, None)
    rest = [candidate(d, t, p) for d, t, p in zip(others, tests, holm_ps, strict=True)]
    candidates = (top, *rest)
    eligible = [top, *(c for c in rest if c.versus_best is not None and not c.below_best)]
    can_tell = evidence.has(best.key, model)
    return ModelAnswer(
        model=model,
        can_compare=can_tell,
        best=top,
        by_data_rate=_cheapest(eligible, "data_rate_bps") if can_tell else None,
        by_power=_cheapest(eligible, "power_w") if can_tell else None,
        comparisons=len(tested),
        untested=len(tests) - len(tested),
        candidates=candidates,
    )


def answer_sentences(answer: ModelAnswer, frame: FrameReadout | None) -> Iterator[str]:
    """The answer for one model in a few sentences: the chosen designs, then how they were found."""
    name = answer.model.upper()
    best = answer.best
    best_text = f"{pct_interval(best.accuracy.mean, best.accuracy.low, best.accuracy.high)}"
    if not answer.can_compare:
        yield (
            f"{name}: the most accurate design is {best.design.label} at {best_text}. Which "
            f"cheaper designs are as accurate cannot be told: {NO_INTERVAL_WHY}."
        )
        return
    same = answer.by_data_rate is answer.by_power
    choices = (
        ((answer.by_data_rate, ("data rate", "readout power")),)
        if same
        else ((answer.by_data_rate, ("data rate",)), (answer.by_power, ("readout power",)))
    )
    for chosen, whats in choices:
        by = " and by ".join(whats)
        if chosen is None:
            yield f"{name}: no design as accurate as the best states its {' or '.join(whats)}."
            continue
        costs = "; ".join(_cost_text(chosen, what) for what in whats)
        if chosen is best:
            yield (
                f"{name}, by {by}: the most accurate design, {best.design.label}, is also the "
                f"cheapest of those not significantly below it: {best_text}; {costs}."
            )
        else:
            accuracy = pct_interval(chosen.accuracy.mean, chosen.accuracy.low, chosen.accuracy.high)
            yield (
                f"{name}, by {by}: the cheapest design not significantly below the best is "
                f"{chosen.design.label}: {accuracy} against the best's {best_text} "
                f"({best.design.label}; difference "
                f"{comparison(chosen.versus_best, chosen.holm_p)}); {costs}."  # type: ignore[arg-type]
            )
            caution = _caution(chosen.versus_best)
            if caution:
                yield f"{name}, by {by}: {caution}"
    if not answer.comparisons and not answer.untested:
        yield f"{name}: this run has no other design to compare with the best."
        return
    n_as = len(answer.as_accurate) - 1
    untested = (
        f"; {answer.untested} design(s) could not be compared (no per-recording results in "
        "common) and are not chosen"
        if answer.untested
        else ""
    )
    yield (
        f"{name}: each of the {answer.comparisons} other designs was compared with the best by a "
        "paired test on the same recordings (exact McNemar for one repeat, bootstrap otherwise); "
        f"the p-values are Holm-corrected over these {answer.comparisons} comparisons (alpha "
        f"{ALPHA:g}), and {n_as} of them are not significantly below the best{untested}."
    )


def _caution(versus_best: PairedComparison | None) -> str:
    """What "not significantly below" leaves open: it is not "as accurate".

    Said when the uncorrected test or the interval already hints at a loss, so a reader does not
    take a Holm-protected choice for a proven equivalence.
    """
    if versus_best is None or versus_best.low >= 0:
        return ""
    hint = (
        f"its uncorrected test does find it less accurate (p = {versus_best.p_value:.2g}); "
        if versus_best.significant(ALPHA)
        else ""
    )
    return (
        f"not significantly below is not the same as as accurate: {hint}this run cannot rule "
        f"out a loss of up to {-100 * versus_best.low:.1f} points against the best (more "
        f"recordings per class, or {REPEATS}, narrow that bound)."
    )


def frame_sentence(frame: FrameReadout | None) -> str:
    """What the frame-based readout the answer compares with is."""
    if frame is None:
        return (
            "The frame-based readout is unknown (the cubes do not state the recordings' sampling "
            "rate; give --adc-rate-hz), so no design is compared with it."
        )
    return (
        f"The frame-based readout of the same array samples every taxel with a {frame.bits}-bit "
        f"ADC at {frame.rate_hz:g} Hz and sends every sample: taxels x {frame.bits} bit x "
        f"{frame.rate_hz:g} Hz. The paper finds {paper.CLAIMS['frame_ratio']}."
    )


ANSWER_COLUMNS = (
    "model",
    "design",
    "swept settings",
    "accuracy [95 % interval]",
    "difference to best [95 % interval], p",
    "data rate",
    "frame readout / event readout (data rate)",
    "readout power (frame readout's)",
    "fold std (secondary)",
)


def answer_rows(answer: ModelAnswer) -> tuple[tuple[str, ...], ...]:
    """Table rows: the best design, the cheapest by data rate and by power (merged if the same)."""
    roles: dict[int, list[str]] = {}
    for chosen, role in (
        (answer.best, "best"),
        (answer.by_data_rate, "cheapest by data rate"),
        (answer.by_power, "cheapest by readout power"),
    ):
        if chosen is not None:
            roles.setdefault(id(chosen), []).append(role)
    rows = []
    for chosen in (answer.best, answer.by_data_rate, answer.by_power):
        if chosen is None or id(chosen) not in roles:
            continue
        a = chosen.accuracy
        rows.append(
            (
                answer.model.upper(),
                "; ".join(roles.pop(id(chosen))),
                chosen.design.label,
                pct_interval(a.mean, a.low, a.high),
                "-"
                if chosen.versus_best is None
                else comparison(chosen.versus_best, chosen.holm_p),
                rate(chosen.data_rate_bps, "bit/s"),
                "unknown" if chosen.frame_data_rate_bps is None else times(chosen.data_rate_ratio),
                si(chosen.power_w, "W")
                + ("" if chosen.frame_power_w is None else f" ({si(chosen.frame_power_w, 'W')})"),
                fold_spread(a.fold_std),
            )
        )
    return tuple(rows)


def _cost_text(chosen: Candidate, what: str) -> str:
    if what == "data rate":
        own = rate(chosen.data_rate_bps, "bit/s")
        frame, ratio = chosen.frame_data_rate_bps, chosen.data_rate_ratio
        frame_text = None if frame is None else rate(frame, "bit/s")
    else:
        own = si(chosen.power_w, "W")
        frame, ratio = chosen.frame_power_w, chosen.power_ratio
        frame_text = None if frame is None else si(frame, "W")
    if frame_text is None:
        return f"{what} {own} (frame readout unknown)"
    if math.isinf(ratio):
        return f"{what} {own}, against {frame_text} for the frame-based readout of the same array"
    relation = "below" if ratio >= 1 else "above"
    factor = ratio if ratio >= 1 else 1 / ratio if ratio > 0 else math.inf
    return (
        f"{what} {own}, {times(factor)} {relation} the frame-based readout of the same array "
        f"({frame_text}, {_taxels(chosen.design.n_taxels)})"
    )


def _cheapest(eligible: Sequence[Candidate], attribute: str) -> Candidate | None:
    priced = [c for c in eligible if math.isfinite(getattr(c, attribute))]
    if not priced:
        return None
    return min(priced, key=lambda c: (getattr(c, attribute), -c.accuracy.mean))


def _ratio(frame: float | None, event: float) -> float:
    if frame is None or not math.isfinite(event) or not math.isfinite(frame):
        return math.nan
    if event <= 0:
        return math.inf if frame > 0 else math.nan
    return frame / event


def _taxels(n: int | None) -> str:
    return "unknown taxels" if n is None else f"{n} taxel{'' if n == 1 else 's'}"
