"""The answer to the designer's question: the cheapest design as accurate as the best one.

For each model, over every distinct design of the run (:mod:`pipeline.report.designs`):

1. The *best* design is the one with the highest accuracy (``accuracy_mean``; ties go to the lower
   data rate, then to the first met).
2. Every other design ``d`` is compared with the best by a paired test on the same recordings
   (:meth:`pipeline.report.evidence.Evidence.compare`: ``accuracy(d) - accuracy(best)``, its 95 %
   interval, exact McNemar p for one repeat). The ``m`` p-values are Holm-corrected over those
   ``m`` comparisons (:func:`pipeline.results.stats.holm`). ``d`` is *significantly below* the best
   when its adjusted p is below ``ALPHA`` (0.05) and its difference is negative.
3. The designs not significantly below the best (the best included) are *as accurate as the best* as
   far as this run can tell; among them the cheapest by address-event data rate and the cheapest by
   estimated readout power (:func:`pipeline.results.readout_power.event_power_w`) are the answer
   (ties go to the more accurate, then to the first met). Designs that cannot be compared with the
   best (no per-recording results, or no recording in common) are never chosen.

Each answer is set against the frame-based readout of the same array (``rows * cols`` taxels,
``bits`` per sample at ``rate_hz``): its data rate ``n * bits * rate_hz`` and its power
(:func:`pipeline.results.readout_power.frame_power_w`), as ``frame / event`` ratios. Power is kept
as its static and dynamic parts (:class:`~pipeline.results.readout_power.ReadoutPower`); energy per
decision is power times the seconds of touch the design observed. Where the cubes count the
decoder's operations, the decoder's energy per decision at the full touch stands beside it, a band
(:func:`pipeline.results.decoder_energy.decoder_energy_j`; the small table gains its column).

By yield, for runs whose designs are simulated as several chips each
(:mod:`pipeline.report.chip_population`): per model, the design with the highest 5th percentile of
accuracy over its chips (``accuracy_p05``, the share of chips a designer can sign off on) is the
*best by yield*; every other design of several chips is compared with it by a bootstrap over
chips and recordings together (:meth:`pipeline.report.evidence.Evidence.compare_yield`),
Holm-corrected; the smallest array (by the matched comparator gate area its mismatch demands,
:mod:`pipeline.results.matched_area`) and the cheapest by power not significantly below it are
the answer by yield (:func:`yield_answers`, which keeps the cheapest by data rate too), said in
one sentence beside the answer above (:func:`yield_sentence`). Mismatch is bought with area: a
design that names no mismatch assumes perfect matching, has no finite area and is never the
smallest array.

What the report shows of it: per model a small table (:func:`glance_rows`) and one sentence on
how sure it is (:func:`how_sure`); then, once, the method (:func:`method_sentences`) and every
comparison with the best (:func:`comparison_rows`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from pipeline.report import paper
from pipeline.report.chip_population import ChipYield
from pipeline.report.designs import Accuracy, Cost, Design, FrameReadout, cost, readout_power
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.report.panels import REPEATS
from pipeline.report.text import (
    NO_INTERVAL_WHY,
    area_text,
    comparison,
    fold_spread,
    pct,
    pct_interval,
    rate,
    si,
    times,
)
from pipeline.results.decoder_energy import EnergyBand
from pipeline.results.readout_constants import CHIP, CHIP_EVENT_RATE_HZ, CHIP_TAXELS, EnergyModel
from pipeline.results.readout_power import ReadoutPower, power_budget
from pipeline.results.stats import PairedComparison, holm


@dataclass(frozen=True)
class Candidate:
    """One design for one model, measured against the model's best design.

    ``versus_best`` is ``accuracy(design) - accuracy(best)`` (None for the best itself and for a
    design that cannot be compared); ``holm_p`` its Holm-adjusted p-value. ``power`` is None when
    the array size or the rates are unknown; frame figures are None when the frame readout or the
    array size is unknown. ``decoder_energy`` is the decoder's energy per decision at the full
    touch, a band (None where the cubes count no operations); ``decides_after_s`` the earliest
    decision not significantly below the full touch (:mod:`pipeline.report.decision_time`; None
    where the cubes keep no decisions).
    """

    design: Design
    accuracy: Accuracy
    versus_best: PairedComparison | None
    holm_p: float | None
    data_rate_bps: float
    power: ReadoutPower | None
    frame_data_rate_bps: float | None
    frame_power: ReadoutPower | None
    decoder_energy: EnergyBand | None = None
    decides_after_s: float | None = None

    @property
    def power_w(self) -> float:
        """Event readout power, static plus dynamic, in W (NaN when unknown)."""
        return math.nan if self.power is None else self.power.total_w

    @property
    def frame_power_w(self) -> float | None:
        """Frame readout's power for this design's array, static plus dynamic, in W (None when
        unknown)."""
        return None if self.frame_power is None else self.frame_power.total_w

    @property
    def energy_per_decision_j(self) -> float:
        """Readout energy of one decision in J, power times the seconds observed (NaN when
        unknown)."""
        return self.power_w * self.design.observation_s

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
        """Frame readout's power over this design's (NaN when either is unknown, inf when this
        design draws none)."""
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
    decoder: Mapping[tuple[str, str], EnergyBand] | None = None,
    decides_after: Mapping[tuple[str, str], float] | None = None,
) -> tuple[ModelAnswer, ...]:
    """One :class:`ModelAnswer` per model that any design trained, in the order first met.

    ``decoder`` gives the decoder's energy per decision at the full touch by (result key,
    model), where the cubes count its operations, ``decides_after`` the earliest decision (s)
    where they keep decisions (:mod:`pipeline.report.decision_time`).
    """
    models = list(dict.fromkeys(m for d in designs for m in d.accuracy))
    found = (
        model_answer(designs, evidence, m, energy, frame, decoder, decides_after) for m in models
    )
    return tuple(answer for answer in found if answer is not None)


def model_answer(
    designs: Sequence[Design],
    evidence: Evidence,
    model: str,
    energy: EnergyModel,
    frame: FrameReadout | None,
    decoder: Mapping[tuple[str, str], EnergyBand] | None = None,
    decides_after: Mapping[tuple[str, str], float] | None = None,
) -> ModelAnswer | None:
    """The answer for ``model`` (see the module docstring); None if no design trained it."""
    mine = [d for d in designs if model in d.accuracy]
    if not mine:
        return None

    best, others, tests, tested, holm_ps = _against_best(
        mine, lambda d: d.accuracy[model].mean, lambda d, b: evidence.compare(d, b, model)
    )

    def candidate(d: Design, test: PairedComparison | None, holm_p: float | None) -> Candidate:
        n = d.n_taxels
        known = frame is not None and n is not None
        return Candidate(
            design=d,
            accuracy=d.accuracy[model],
            versus_best=test,
            holm_p=holm_p,
            data_rate_bps=cost(d, model, Cost.DATA_RATE, energy),
            power=readout_power(d, energy),
            frame_data_rate_bps=frame.data_rate_bps(n) if known else None,
            frame_power=frame.power(n, energy) if known else None,
            decoder_energy=(decoder or {}).get((d.key, model)),
            decides_after_s=(decides_after or {}).get((d.key, model)),
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


#: Headers of the small table's columns after the first, the model's name (:func:`glance_header`).
GLANCE_COLUMNS = (
    "design",
    "accuracy [95 % interval]",
    "data rate",
    "power (static share)",
    "energy per decision",
    "frame readout / this: data rate, power",
)


#: The small table's column of the decoder's energy, where the cubes count its operations.
DECODER_COLUMN = "decoder energy per decision"
#: The small table's column of the earliest decision, after the accuracy, where the cubes keep
#: decisions.
DECIDES_COLUMN = "decides after"


def glance_header(answer: ModelAnswer) -> tuple[str, ...]:
    """The small table's header: the model's name, then :data:`GLANCE_COLUMNS` (and
    :data:`DECODER_COLUMN` after the energy per decision, where the cubes count operations, and
    :data:`DECIDES_COLUMN` after the accuracy, where they keep decisions)."""
    columns = list(GLANCE_COLUMNS)
    if decides(answer):
        columns.insert(columns.index("accuracy [95 % interval]") + 1, DECIDES_COLUMN)
    if has_decoder_energy(answer):
        columns.insert(columns.index("energy per decision") + 1, DECODER_COLUMN)
    return (answer.model.upper(), *columns)


def has_decoder_energy(answer: ModelAnswer) -> bool:
    """Whether any design of the answer states its decoder's energy per decision."""
    return any(c.decoder_energy is not None for c in answer.candidates)


def decides(answer: ModelAnswer) -> bool:
    """Whether any design of the answer states its earliest decision."""
    return any(c.decides_after_s is not None for c in answer.candidates)


def decoder_energy_text(band: EnergyBand | None) -> str:
    """A decoder energy band as ``12.7 nJ to 23.6 nJ``; "unknown" when not stated."""
    if band is None or not (math.isfinite(band.low_j) and math.isfinite(band.high_j)):
        return "unknown"
    return f"{si(band.low_j, 'J')} to {si(band.high_j, 'J')}"


def glance_rows(answer: ModelAnswer) -> tuple[tuple[str, ...], ...]:
    """The small table: the best design, the cheapest not significantly below it by data rate
    and by power (one row with both roles when they are the same design)."""
    rows = []
    decoder, early = has_decoder_energy(answer), decides(answer)
    for chosen, roles in _roles(answer):
        a = chosen.accuracy
        power = chosen.power
        share = "" if power is None else f" ({_share(power.static_share)} static)"
        rows.append(
            (
                ", ".join(roles),
                chosen.design.label,
                pct_interval(a.mean, a.low, a.high),
                *((_decides_text(chosen.decides_after_s),) if early else ()),
                rate(chosen.data_rate_bps, "bit/s"),
                f"{si(chosen.power_w, 'W')}{share}",
                _energy(chosen),
                *((decoder_energy_text(chosen.decoder_energy),) if decoder else ()),
                "unknown"
                if chosen.frame_power is None
                else f"{times(chosen.data_rate_ratio)}, {times(chosen.power_ratio)}",
            )
        )
    return tuple(rows)


def _decides_text(seconds: float | None) -> str:
    return "unknown" if seconds is None else f"{seconds:.3g} s"


def how_sure(answer: ModelAnswer) -> str:
    """One sentence: how many designs the answer was chosen among, and what it may lose."""
    name = answer.model.upper()
    if not answer.can_compare:
        return f"{name}: which cheaper designs are as accurate cannot be told ({NO_INTERVAL_WHY})."
    if not answer.comparisons and not answer.untested:
        return f"{name}: this run has no other design to compare with the best."
    n_as = len(answer.as_accurate) - 1
    text = (
        f"{name}: {n_as} of the {answer.comparisons} other designs are not significantly below "
        "the best"
    )
    if answer.untested:
        text += f" ({answer.untested} could not be compared)"
    chosen = [c for c in (answer.by_data_rate, answer.by_power) if c is not None]
    losses = [-c.versus_best.low for c in chosen if c.versus_best is not None]
    if not losses:
        return text + "; the best is also the cheapest."
    worst = max(losses)
    if worst <= 0:
        return text + "; the cheapest is at least as accurate as the best (95 % interval)."
    return text + (
        f"; the cheapest may still lose up to {100 * worst:.1f} points of accuracy against the "
        "best (95 % interval)."
    )


def method_sentences(
    n_designs: int, frame: FrameReadout | None, energy: EnergyModel
) -> tuple[str, ...]:
    """How the answer was found, said once for every model."""
    chip = power_budget(CHIP_TAXELS, CHIP_EVENT_RATE_HZ, bits=0, model=energy)
    return (
        f"Over the run's {n_designs} distinct design{'' if n_designs == 1 else 's'}, per model: "
        "the most accurate design, and the cheapest designs (by address-event "
        "data rate and by estimated readout power) whose accuracy is not significantly below it.",
        "Each other design is compared with the best by a paired test on the same recordings "
        "(exact McNemar for one repeat, bootstrap otherwise); the p-values are Holm-corrected over "
        f"the model's comparisons (alpha {ALPHA:g}). Not significantly below is not the same as "
        "as accurate: the lower end of the difference's 95 % interval bounds what a choice may "
        f"lose (more recordings per class, or {REPEATS}, narrow it).",
        frame_sentence(frame),
        "Readout power is static bias (every taxel's front end and comparators; for the frame "
        "readout the front ends and the ADCs) plus dynamic power (per event and per bit sent; "
        "per conversion and per bit for the frame readout). The event readout's constants are "
        f"calibrated on the chip of {CHIP}: fed that array, these constants give "
        f"{si(chip.event.total_w / chip.n_taxels, 'W')} per taxel. "
        "Energy per decision is that power times the seconds of touch the design observed (the "
        "windows it used times the window length). The constants (set them with the options of "
        "eskin report, e.g. --front-end-nw):",
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


COMPARISON_COLUMNS = (
    "model",
    "design",
    "accuracy [95 % interval]",
    "difference to best [95 % interval], p",
    "not significantly below the best?",
    "data rate",
    "power (static)",
    "energy per decision",
    "fold std (secondary)",
)


def comparison_rows(answer: ModelAnswer) -> tuple[tuple[str, ...], ...]:
    """Every design of the model against the best, the best first, then by readout power."""
    rest = sorted(
        (c for c in answer.candidates if c is not answer.best),
        key=lambda c: (not math.isfinite(c.power_w), c.power_w),
    )
    rows = []
    for c in (answer.best, *rest):
        a = c.accuracy
        if c is answer.best:
            difference, verdict = "-", "the best"
        elif c.versus_best is None:
            difference, verdict = "not compared", "-"
        else:
            difference = comparison(c.versus_best, c.holm_p)
            verdict = "no: significantly below" if c.below_best else "yes"
        rows.append(
            (
                answer.model.upper(),
                c.design.label,
                pct_interval(a.mean, a.low, a.high),
                difference,
                verdict,
                rate(c.data_rate_bps, "bit/s"),
                si(c.power_w, "W") + ("" if c.power is None else f" ({si(c.power.static_w, 'W')})"),
                _energy(c),
                fold_spread(a.fold_std),
            )
        )
    return tuple(rows)


def _against_best(
    designs: Sequence[Design],
    score: Callable[[Design], float],
    compare: Callable[[str, str], PairedComparison | None],
) -> tuple[
    Design, list[Design], list[PairedComparison | None], list[PairedComparison], list[float | None]
]:
    """The best of ``designs`` by ``score`` (ties to the lower data rate, then the first met),
    the others, each one's comparison with it (``compare(key, best key)``, None: not made), the
    comparisons made, and their Holm-adjusted p-values (None where not made)."""

    def rank(d: Design) -> tuple[float, float]:
        rate_bps = d.data_rate_bps if math.isfinite(d.data_rate_bps) else math.inf
        return (-score(d), rate_bps)

    best = min(designs, key=rank)  # min is stable: the first met among equals
    others = [d for d in designs if d is not best]
    tests = [compare(d.key, best.key) for d in others]
    tested = [t for t in tests if t is not None]
    adjusted = iter(holm([t.p_value for t in tested]))
    holm_ps = [None if t is None else float(next(adjusted)) for t in tests]
    return best, others, tests, tested, holm_ps


def _roles(answer: ModelAnswer) -> list[tuple[Candidate, list[str]]]:
    roles: dict[int, tuple[Candidate, list[str]]] = {}
    for chosen, role in (
        (answer.best, "best"),
        (answer.by_data_rate, "cheapest by data rate"),
        (answer.by_power, "by power"),
    ):
        if chosen is not None:
            roles.setdefault(id(chosen), (chosen, []))[1].append(role)
    return list(roles.values())


def _share(fraction: float) -> str:
    return "unknown" if not math.isfinite(fraction) else f"{100 * fraction:.0f} %"


def _energy(chosen: Candidate) -> str:
    seconds = chosen.design.observation_s
    if not math.isfinite(chosen.energy_per_decision_j):
        return "unknown"
    return f"{si(chosen.energy_per_decision_j, 'J')} ({seconds:g} s)"


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


@dataclass(frozen=True)
class YieldCandidate:
    """One design of several chips for one model, against the model's best design by yield.

    ``versus_best`` is ``yield(design) - yield(best)`` (None for the best itself and for a design
    that cannot be compared), ``holm_p`` its Holm-adjusted p-value; the costs are NaN when
    unknown (``area_m2``, the array's matched comparator gate area, for every design that names
    no mismatch: :mod:`pipeline.results.matched_area`).
    """

    design: Design
    chips: ChipYield
    versus_best: PairedComparison | None
    holm_p: float | None
    data_rate_bps: float
    power_w: float
    area_m2: float = math.nan

    @property
    def below_best(self) -> bool:
        """Significantly below the best by yield (Holm-adjusted p < ALPHA, a negative
        difference)."""
        return (
            self.versus_best is not None
            and self.holm_p is not None
            and self.holm_p < ALPHA
            and self.versus_best.difference < 0
        )


@dataclass(frozen=True)
class YieldAnswer:
    """The answer by yield for one model: the ``best`` design by yield and the cheapest by data
    rate, by power and by array area not significantly below it (None when no design states
    that cost: a design without an area is never the smallest); ``comparisons`` the size of the
    Holm family, ``untested`` the designs not compared; ``candidates`` every design of several
    chips, the best first."""

    model: str
    best: YieldCandidate
    by_data_rate: YieldCandidate | None
    by_power: YieldCandidate | None
    comparisons: int
    untested: int
    candidates: tuple[YieldCandidate, ...] = ()
    by_area: YieldCandidate | None = None


def yield_answers(
    designs: Sequence[Design], evidence: Evidence, energy: EnergyModel
) -> tuple[YieldAnswer, ...]:
    """One :class:`YieldAnswer` per model that a design of several chips states a yield for."""
    models = list(dict.fromkeys(m for d in designs for m in d.yields))
    return tuple(
        answer
        for model in models
        if (answer := yield_answer(designs, evidence, model, energy)) is not None
    )


def yield_answer(
    designs: Sequence[Design], evidence: Evidence, model: str, energy: EnergyModel
) -> YieldAnswer | None:
    """The answer by yield for ``model`` (see the module docstring); None when no design
    states a finite yield for it."""
    mine = [d for d in designs if model in d.yields and math.isfinite(d.yields[model].p05)]
    if not mine:
        return None

    best, others, tests, tested, holm_ps = _against_best(
        mine, lambda d: d.yields[model].p05, lambda d, b: evidence.compare_yield(d, b, model)
    )

    def candidate(d: Design, test: PairedComparison | None, p: float | None) -> YieldCandidate:
        return YieldCandidate(
            design=d,
            chips=d.yields[model],
            versus_best=test,
            holm_p=p,
            data_rate_bps=cost(d, model, Cost.DATA_RATE, energy),
            power_w=cost(d, model, Cost.POWER, energy),
            area_m2=cost(d, model, Cost.AREA, energy),
        )

    top = candidate(best, None, None)
    rest = [candidate(d, t, p) for d, t, p in zip(others, tests, holm_ps, strict=True)]
    eligible = [top, *(c for c in rest if c.versus_best is not None and not c.below_best)]

    def cheapest(attribute: str) -> YieldCandidate | None:
        priced = [c for c in eligible if math.isfinite(getattr(c, attribute))]
        if not priced:
            return None
        return min(priced, key=lambda c: (getattr(c, attribute), -c.chips.p05))

    return YieldAnswer(
        model=model,
        best=top,
        by_data_rate=cheapest("data_rate_bps"),
        by_power=cheapest("power_w"),
        comparisons=len(tested),
        untested=len(tests) - len(tested),
        candidates=(top, *rest),
        by_area=cheapest("area_m2"),
    )


def yield_sentence(answer: YieldAnswer) -> str:
    """The answer by yield in one sentence (see the module docstring): the best design by yield,
    and among the designs not significantly below it the smallest array (by matched comparator
    area) and the cheapest by power. A design that names no mismatch states no area (perfect
    matching needs an infinite one), so it is never the smallest; when it is the best, the
    sentence says so."""
    best = answer.best
    text = (
        f"{answer.model.upper()} by yield (the 5th percentile of accuracy over a design's "
        f"{_chips(best.chips)}): the best is {best.design.label}, "
        f"{_yield(best.chips)}"
    )
    unbuildable = (
        ""
        if math.isfinite(best.area_m2)
        else " The best names no threshold mismatch: it assumes perfect matching, "
        "which no finite comparator gives (Pelgrom's law), so it is never the smallest array."
    )
    if not answer.comparisons and not answer.untested:
        return text + "; no other design of several chips to compare it with." + unbuildable
    roles: dict[int, tuple[YieldCandidate, list[str]]] = {}
    for c, role in (
        (answer.by_area, "the smallest array"),
        (answer.by_power, "the cheapest by power"),
    ):
        if c is not None:
            roles.setdefault(id(c), (c, []))[1].append(role)
    named = []
    if answer.by_area is None:
        named.append("none states an array area (none names a threshold mismatch)")
    for c, found in roles.values():
        which = " and ".join(found)
        area = (
            f" ({area_text(c.area_m2)} of matched comparator gate area)"
            if "the smallest array" in found
            else ""
        )
        if c is best:
            named.append(f"it is also {which}{area}")
        elif c.versus_best is not None:
            named.append(
                f"{which} is {c.design.label}{area}, {_yield(c.chips)}, "
                f"{comparison(c.versus_best, c.holm_p if answer.comparisons > 1 else None)}"
            )
    family = (
        f"Holm-corrected over {answer.comparisons} comparisons"
        if answer.comparisons > 1
        else "one comparison"
    )
    return (
        text
        + "; of the designs whose 5th percentile is not significantly below it (bootstrap over "
        + f"chips and recordings, {family}), "
        + "; ".join(named)
        + "."
        + unbuildable
    )


def _chips(chips: ChipYield) -> str:
    return f"{chips.n_chips} chips" + (f", deployed {chips.deployment}" if chips.deployment else "")


def _yield(chips: ChipYield) -> str:
    share = (
        f", {pct(chips.share)} of chips at or above {pct(chips.target)}"
        if math.isfinite(chips.share) and math.isfinite(chips.target)
        else ""
    )
    if not math.isfinite(chips.p05_low) and math.isfinite(chips.p05_high):
        # Fewer than 59 chips give no lower bound from order statistics, only an upper one.
        interval = f"{pct(chips.p05)} [-, {100 * chips.p05_high:.1f}]"
    else:
        interval = pct_interval(chips.p05, chips.p05_low, chips.p05_high)
    return f"5th percentile {interval}{share}"
