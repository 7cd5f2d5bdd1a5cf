"""The paper's claims beside what this run's cubes say about them, each judged by a test.

Every claim is judged by a paired test on the same recordings
(:meth:`pipeline.report.evidence.Evidence.compare`, exact McNemar for one repeat, bootstrap
otherwise) or a trend test (:meth:`~pipeline.report.evidence.Evidence.trend`), at ``ALPHA`` =
0.05, never by the spread over folds. A claim over several comparisons Holm-corrects their
p-values (:func:`pipeline.results.stats.holm`) and says so.

Each test (one per model and sweep) goes the claim's way, against it, or neither; the claim's
:class:`Verdict` tallies them by one rule (:func:`tally`):

* *consistent*: every test goes the claim's way: a significant difference in the direction the
  claim predicts or, where the claim predicts none (the optimum's location, saturation), no
  significant difference;
* *in part*: some tests go the claim's way, the others cannot tell or go against it;
* *contradicts*: at least one test is significant against the claim, and none goes its way;
* *cannot tell*: no test is significant where the claim predicts a difference, or the run cannot
  test it (no per-recording results, a single swept value, the claim's sweep not in this run).

The report shows them as a table (:func:`claims_table`): per claim, the paper's figure, this
run's figure with its 95 % interval and the p-value that judged it (the difference the test
judged, in percentage points, Holm-adjusted where the claim makes several comparisons; a slope;
or a correlation's ``r`` and ``p``) and the verdict; each claim's sentence, with every test,
is below it.

* Optimum at the paper's value ``x_p`` (threshold 0.09 V, window 0.1 s), a "best of N" claim:
  every other swept value ``x_j`` is compared with ``x_p``; the run supports the claim when no
  ``x_j`` is significantly more accurate (Holm over the ``N - 1`` comparisons), and does not when
  one is.
* Loss on the sides of the optimum ``x*`` (lower thresholds; shorter and longer windows): the
  lowest (and highest) swept value against ``x*`` (Holm over the sides); supported when the side
  is significantly less accurate, not supported when the optimum is at that end of the sweep.
* Taxel gain from 1 to 16 taxels: 16 against 1 (relative gain ``a(16) / a(1) - 1`` beside the
  paper's +63 %); saturation: every count above 16 against 16 (Holm), supported when none differs
  significantly. Without 1 or 16 in the sweep: its smallest and largest counts, and its last step.
* SSNR and STE (Fig. 9): the cube's Pearson ``r`` and two-sided ``p`` of accuracy against the
  metric; SSNR should correlate positively and STE negatively (p < 0.05).
* Mismatch: the least-squares slope of accuracy on ``sigma_rel`` with its paired bootstrap interval
  and p-value; supported when significantly negative. Where the chips' deployment was swept
  (:mod:`pipeline.report.chip_population`), the claim is judged on the ``shared`` deployment alone
  (one classifier loaded into every chip, as chips are shipped uncalibrated), and the largest
  mismatch is compared with the smallest by a bootstrap over chips and recordings;
  :func:`deployment_note` sets every deployment side by side.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.report import paper
from pipeline.report.chip_population import CLAIM_DEPLOYMENT
from pipeline.report.curves import Curve, MetricFit
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.report.panels import PANEL_TITLES, Panel
from pipeline.report.text import (
    NO_INTERVAL,
    NO_INTERVAL_WHY,
    comparison,
    p_value,
    pct,
    pct_interval,
    signed_points,
)
from pipeline.results.stats import PairedComparison, holm

_METRIC_NAMES = {"ssnr_db": "SSNR", "ste_s2": "STE"}
_NOT_SIGNIFICANT = "no significant difference (the interval includes 0)"


class Verdict(enum.StrEnum):
    """How this run's cubes bear on one of the paper's claims (the rules: the module docstring,
    applied by :func:`tally`)."""

    CONSISTENT = "consistent"
    PARTLY = "in part"
    UNCLEAR = "cannot tell"
    CONTRADICTS = "contradicts"


_VERDICT_WORDS = {
    Verdict.CONSISTENT: "is consistent with it",
    Verdict.PARTLY: "is consistent with it only in part",
    Verdict.UNCLEAR: "cannot tell",
    Verdict.CONTRADICTS: "contradicts it",
}

#: The title of the claims' sentences, every test in words, folded under the claims table.
CLAIM_TESTS_TITLE = "The tests behind each verdict"
#: The claims table's columns (:func:`claims_table`).
CLAIMS_COLUMNS = ("claim", "the paper", "this run [95 % interval]", "verdict")


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims beside what this run's cubes say about it.

    ``key`` names the claim in ``pipeline.report.paper.CLAIMS``; ``finding`` is every test
    in words, ``figure`` this run's figures in short (the claims table's cell); ``in_run`` is
    False when the run holds no cube the claim is judged on (its verdict is then cannot tell).
    """

    panel: Panel
    key: str
    finding: str
    verdict: Verdict
    figure: str = ""
    in_run: bool = True

    @property
    def paper(self) -> str:
        """The claim, as the paper makes it."""
        return paper.CLAIMS[self.key]

    @property
    def sentence(self) -> str:
        """The claim and this run's finding in one sentence, with the verdict when the run has
        the claim's cubes."""
        if not self.in_run:
            return f"The paper finds {self.paper}; {self.finding}."
        words = _VERDICT_WORDS[self.verdict]
        return f"The paper finds {self.paper}; here {self.finding}, so this run {words}."


def claims_table(claims: Sequence[Claim]) -> tuple[tuple[str, ...], ...]:
    """One row per claim, in :data:`CLAIMS_COLUMNS`: the claim (with the paper's figure that
    makes it), the paper's figure, this run's figure [95 % interval] and the verdict."""
    rows = []
    for claim in claims:
        row = paper.CLAIM_ROWS[claim.key]
        rows.append(
            (
                f"{row.figure}: {row.claim}",
                row.value,
                claim.figure if claim.in_run else "not in this run",
                str(claim.verdict),
            )
        )
    return tuple(rows)


def optimum_claim(
    panel: Panel,
    curves: Sequence[Curve],
    evidence: Evidence,
    reference: float,
    unit: str,
    key: str,
) -> Claim:
    """Is no swept value significantly more accurate than the paper's optimum ``reference``?"""
    if not curves:
        return _absent(panel, key)
    parts, verdicts, figures = [], [], []
    for curve in curves:
        name = _name(curve, curves)
        b = curve.best
        at = f"{name} is most accurate at {curve.x[b]:g} {unit} ({_acc(curve, b)})"
        ref = curve.index(reference)
        best_at = f"{name} best at {curve.x[b]:g} {unit}"
        if ref is None:
            parts.append(f"{at}; {reference:g} {unit} was not swept")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{best_at}; {reference:g} {unit} not swept")
            continue
        others = [j for j in range(curve.x.size) if j != ref]
        if not others:
            parts.append(f"{at}; it is the only value swept")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{best_at}, the only value")
            continue
        tests = _holm_tests(curve, evidence, [(j, ref) for j in others])
        if tests is None:
            parts.append(f"{at}; {NO_INTERVAL_WHY}")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{best_at}; {NO_INTERVAL}")
            continue
        if ref == b:
            figures.append(f"{best_at} ({_acc(curve, b)})")
        else:  # the paper's value against the best, as the Holm family tested it
            t, p = _oriented(tests[others.index(b)], True)
            figures.append(
                f"{best_at}; {reference:g} {unit} against it: {_points(t, p, len(others))}"
            )
        better = [(j, t, p) for j, (t, p) in zip(others, tests, strict=True) if _up(t, p)]
        family = _family(len(others)).removeprefix(", ")
        if better:
            j, t, p = max(better, key=lambda item: item[1].difference)
            parts.append(
                f"{at}, and {curve.x[j]:g} {unit} is significantly more accurate than "
                f"{reference:g} {unit} ({_compared(t, p, len(others))}; {family})"
            )
            verdicts.append(Verdict.CONTRADICTS)
        else:
            parts.append(
                f"{at}, and no swept value is significantly more accurate than {reference:g} "
                f"{unit} ({_acc(curve, ref)}; {_others(len(others))} compared with it, {family})"
            )
            verdicts.append(Verdict.CONSISTENT)
    return _claim(panel, key, parts, verdicts, figures)


def sides_claim(
    panel: Panel,
    curves: Sequence[Curve],
    evidence: Evidence,
    sides: Sequence[str],
    unit: str,
    key: str,
) -> Claim:
    """Do the ``sides`` ("lower", "higher") of the sweep lose accuracy against its optimum?

    Each side's end of the sweep is compared with the optimum. When the optimum is itself that
    end, it is compared with its neighbour instead: significantly more accurate means accuracy
    rises towards that end (the claim is not supported), otherwise the run cannot tell. The
    comparisons of one curve are Holm-corrected together.
    """
    if not curves:
        return _absent(panel, key)
    parts, verdicts, figures = [], [], []
    for curve in curves:
        name = _name(curve, curves)
        b, last = curve.best, curve.x.size - 1
        if last == 0:
            parts.append(f"{name} has only one value")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: one value")
            continue
        pairs = []  # (side, index compared, index it is compared with)
        for side in sides:
            end = 0 if side == "lower" else last
            if end != b:
                pairs.append((side, end, b))
            else:
                pairs.append((side, b, b + 1 if side == "lower" else b - 1))
        # With two values both sides may be the same pair of points: tested once, read twice.
        distinct = list(dict.fromkeys((min(i, j), max(i, j)) for _, i, j in pairs))
        found = _holm_tests(curve, evidence, distinct)
        if found is None:
            parts.append(f"{name}: {NO_INTERVAL_WHY}")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: {NO_INTERVAL}")
            continue
        tests = [
            _oriented(found[distinct.index((min(i, j), max(i, j)))], i > j) for _, i, j in pairs
        ]
        family = _family(len(distinct))
        texts, mine = [], []
        figures += [
            f"{name} {curve.x[i]:g} against {curve.x[j]:g} {unit}: {_points(t, p, len(distinct))}"
            for (_, i, j), (t, p) in zip(pairs, tests, strict=True)
        ]
        for (side, i, j), (t, p) in zip(pairs, tests, strict=True):
            significant = p < ALPHA
            if i == b:
                word = "lowest" if side == "lower" else "highest"
                rises = significant and t.difference > 0
                state = "significantly more accurate" if rises else _NOT_SIGNIFICANT
                texts.append(
                    f"the optimum is the {word} value swept ({curve.x[b]:g} {unit}, "
                    f"{_acc(curve, b)}); against {curve.x[j]:g} {unit} next to it: {state} "
                    f"({_compared(t, p, len(distinct))}{family})"
                )
                mine.append(Verdict.CONTRADICTS if rises else Verdict.UNCLEAR)
                continue
            lost = significant and t.difference < 0
            state = "significantly less accurate" if lost else _NOT_SIGNIFICANT
            texts.append(
                f"{curve.x[i]:g} {unit} ({_acc(curve, i)}) against the optimum {curve.x[b]:g} "
                f"{unit}: {state} ({_compared(t, p, len(distinct))}{family})"
            )
            mine.append(Verdict.CONSISTENT if lost else Verdict.UNCLEAR)
        parts.append(f"{name}: " + "; ".join(texts))
        verdicts.append(tally(mine))
    return _claim(panel, key, parts, verdicts, figures)


def taxel_gain_claim(curves: Sequence[Curve], evidence: Evidence) -> Claim:
    """Accuracy rising from 1 to 16 taxels (the paper: +63 %): 16 against 1, paired."""
    if not curves:
        return _absent(Panel.TAXELS, "taxel_gain")
    parts, verdicts, figures = [], [], []
    for curve in curves:
        name = _name(curve, curves)
        if curve.x.size < 2:
            parts.append(f"{name} has only {curve.x[0]:g} taxels")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: one array")
            continue
        i1 = curve.index(paper.TAXELS[0])
        i2 = curve.index(paper.TAXELS[1])
        note = ""
        if i1 is None or i2 is None:
            i1, i2 = 0, curve.x.size - 1
            note = " (1 and 16 were not both swept: its smallest and largest arrays)"
        start = f"{name} goes from {_acc(curve, i1)} at {curve.x[i1]:g} to {_acc(curve, i2)} "
        start += f"at {curve.x[i2]:g} taxels{note}"
        gain = ""
        if curve.mean[i1] > 0:
            gain = f"{curve.mean[i2] / curve.mean[i1] - 1:+.0%}"
            start += f", {gain} (the paper: +63%)"
        tests = _holm_tests(curve, evidence, [(i2, i1)])
        pair = " ".join(filter(None, (name, gain)))
        pair += f" ({curve.x[i2]:g} against {curve.x[i1]:g} taxels: "
        if tests is None:
            parts.append(f"{start}; {NO_INTERVAL_WHY}")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{pair}{NO_INTERVAL})")
            continue
        ((t, p),) = tests
        figures.append(f"{pair}{_points(t, p, 1)})")
        if p < ALPHA:
            state = "a significant gain" if t.difference > 0 else "a significant loss"
            verdicts.append(Verdict.CONSISTENT if t.difference > 0 else Verdict.CONTRADICTS)
        else:
            state = _NOT_SIGNIFICANT
            verdicts.append(Verdict.UNCLEAR)
        parts.append(f"{start}: {state} ({_compared(t, p, 1)})")
    return _claim(Panel.TAXELS, "taxel_gain", parts, verdicts, figures)


def taxel_saturation_claim(curves: Sequence[Curve], evidence: Evidence) -> Claim:
    """No significant change above 16 taxels (or along the sweep's last step), Holm-corrected."""
    if not curves:
        return _absent(Panel.TAXELS, "taxel_saturation")
    parts, verdicts, figures = [], [], []
    for curve in curves:
        name = _name(curve, curves)
        ref = curve.index(paper.TAXELS[1])
        if ref is None or ref == curve.x.size - 1:
            if curve.x.size < 2:
                parts.append(f"{name} has only {curve.x[0]:g} taxels")
                verdicts.append(Verdict.UNCLEAR)
                figures.append(f"{name}: one array")
                continue
            ref = curve.x.size - 2  # no array above 16: the sweep's last step
        above = list(range(ref + 1, curve.x.size))
        tests = _holm_tests(curve, evidence, [(j, ref) for j in above])
        start = f"{name} at {curve.x[ref]:g} taxels: {_acc(curve, ref)}"
        if tests is None:
            parts.append(f"{start}; {NO_INTERVAL_WHY}")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: {NO_INTERVAL}")
            continue
        figures += [
            f"{name} {curve.x[j]:g} against {curve.x[ref]:g} taxels: {_points(t, p, len(above))}"
            for j, (t, p) in zip(above, tests, strict=True)
        ]
        family = _family(len(above))
        changes = [
            f"{curve.x[j]:g} taxels {_acc(curve, j)} ({_compared(t, p, len(above))}{family})"
            for j, (t, p) in zip(above, tests, strict=True)
        ]
        moved = [t for t, p in tests if p < ALPHA]
        if moved:
            way = "keeps rising" if all(t.difference > 0 for t in moved) else "changes"
            parts.append(f"{start}; it {way} significantly: " + "; ".join(changes))
            verdicts.append(Verdict.CONTRADICTS)
        else:
            parts.append(
                f"{start}; no significant change above it, consistent with saturation: "
                + "; ".join(changes)
            )
            verdicts.append(Verdict.CONSISTENT)
    return _claim(Panel.TAXELS, "taxel_saturation", parts, verdicts, figures)


def metric_claim(fits: Sequence[MetricFit]) -> Claim:
    """SSNR should correlate positively with accuracy and STE negatively (Pearson, p < 0.05)."""
    if not fits:
        return Claim(
            Panel.SPIKE_METRICS,
            "metrics",
            "no correlate sweep is in this run",
            Verdict.UNCLEAR,
            in_run=False,
        )
    parts, verdicts, figures = [], [], []
    for fit in fits:
        metric = _METRIC_NAMES[fit.metric]
        if not (math.isfinite(fit.r) and math.isfinite(fit.p)):
            parts.append(
                f"{metric} has no correlation for the {fit.model.upper()} (too few points)"
            )
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{fit.model.upper()} {metric}: too few points")
            continue
        sign = 1.0 if fit.metric == "ssnr_db" else -1.0
        if fit.p >= ALPHA:
            verdicts.append(Verdict.UNCLEAR)
        else:
            verdicts.append(Verdict.CONSISTENT if sign * fit.r > 0 else Verdict.CONTRADICTS)
        parts.append(
            f"{metric} gives Pearson r = {fit.r:+.2f} (p = {p_value(fit.p)}, n = {fit.x.size}) "
            f"for the {fit.model.upper()}"
        )
        figures.append(f"{fit.model.upper()} {metric} r = {fit.r:+.2f}, p = {p_value(fit.p)}")
    return _claim(Panel.SPIKE_METRICS, "metrics", parts, verdicts, figures)


def mismatch_claim(curves: Sequence[Curve], evidence: Evidence) -> Claim:
    """Does accuracy fall with threshold mismatch (trend test of the slope, p < 0.05)?"""
    if not curves:
        return _absent(Panel.MISMATCH, "mismatch")
    parts, verdicts, figures = [], [], []
    if any(c.group == CLAIM_DEPLOYMENT for c in curves):
        curves = [c for c in curves if c.group == CLAIM_DEPLOYMENT]
        parts.append(
            f"judged on the {CLAIM_DEPLOYMENT} deployment (one classifier loaded into every chip)"
        )
    for curve in curves:
        name = _name(curve, curves)
        span = (
            f"{name} {_acc(curve, 0)} at {curve.x[0]:.0%} to {_acc(curve, -1)} at "
            f"{curve.x[-1]:.0%} mismatch"
        )
        if np.unique(curve.x).size < 2:
            parts.append(f"{name} has only one mismatch level")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: one mismatch level")
            continue
        fit = evidence.trend(curve.keys, curve.x, curve.model)
        if fit is None:
            parts.append(f"{span}; {NO_INTERVAL_WHY}")
            verdicts.append(Verdict.UNCLEAR)
            figures.append(f"{name}: {NO_INTERVAL}")
            continue
        if fit.p_value >= ALPHA:
            state, verdict = _NOT_SIGNIFICANT.replace("difference", "trend"), Verdict.UNCLEAR
        elif fit.slope < 0:
            state, verdict = "a significant fall", Verdict.CONSISTENT
        else:
            state, verdict = "a significant rise", Verdict.CONTRADICTS
        per10 = 0.1  # the slope per 10 % mismatch (sigma_rel 0.1)
        figures.append(
            f"{name} {signed_points(per10 * fit.slope)} points per 10 % mismatch "
            f"[{signed_points(per10 * fit.low)}, {signed_points(per10 * fit.high)}], "
            f"p = {p_value(fit.p_value)}"
        )
        ends = ""
        if curve.chip_low is not None:
            test = evidence.compare(curve.keys[-1], curve.keys[0], curve.model)
            if test is not None:
                below = test.p_value < ALPHA and test.difference < 0
                ends = (
                    f"; at {curve.x[-1]:.0%} against {curve.x[0]:.0%}: "
                    f"{'significantly below' if below else _NOT_SIGNIFICANT} "
                    f"({comparison(test, None)}, over chips and recordings)"
                )
        parts.append(
            f"{span}: {state}, slope {signed_points(per10 * fit.slope)} points per 10 % mismatch "
            f"[{signed_points(per10 * fit.low)}, {signed_points(per10 * fit.high)}], bootstrap "
            f"p = {p_value(fit.p_value)}{ends}"
        )
        verdicts.append(verdict)
    return _claim(Panel.MISMATCH, "mismatch", parts, verdicts, figures)


def deployment_note(curves: Sequence[Curve], evidence: Evidence) -> str | None:
    """Fig. 10's deployments side by side: per model and deployment, the largest mismatch
    against the smallest (mean over chips, bootstrap over chips and recordings) and the yield
    there; None unless the curves hold several chips."""
    chipped = [c for c in curves if c.chip_low is not None and c.x.size >= 2]
    if not chipped:
        return None
    parts = []
    for curve in chipped:
        test = evidence.compare(curve.keys[-1], curve.keys[0], curve.model)
        change = "not compared" if test is None else comparison(test, None)
        parts.append(
            f"{curve.label}: {change}; yield (5th percentile over chips) "
            f"{pct(float(curve.chip_low[0]))} at {curve.x[0]:.0%}, "
            f"{pct(float(curve.chip_low[-1]))} at {curve.x[-1]:.0%}"
        )
    return (
        "Over chips, each deployment at its largest mismatch against its smallest (accuracy "
        "the mean over chips; the difference with its 95 % interval and p from a bootstrap over "
        "chips and recordings; the error bars are the test set's 95 % interval, the bands the "
        "chips' spread from the 5th to the 95th percentile): " + "; ".join(parts) + "."
    )


def _holm_tests(
    curve: Curve, evidence: Evidence, pairs: Sequence[tuple[int, int]]
) -> list[tuple] | None:
    """Paired comparisons ``a(i) - a(j)`` of the curve's points with Holm-adjusted p-values;
    None when any of them cannot be made (no per-recording results)."""
    tests = [evidence.compare(curve.keys[i], curve.keys[j], curve.model) for i, j in pairs]
    if any(t is None for t in tests):
        return None
    adjusted = holm([t.p_value for t in tests])  # type: ignore[union-attr]
    return [(t, float(p)) for t, p in zip(tests, adjusted, strict=True)]


def _family(m: int) -> str:
    """How the p-values of ``m`` comparisons are corrected, as a clause to append."""
    return f", Holm-corrected over {m} comparisons" if m > 1 else ", one comparison"


def _compared(test: PairedComparison, holm_p: float, m: int) -> str:
    """A comparison as text; the Holm-adjusted p only where ``m`` > 1 comparisons share it."""
    return comparison(test, holm_p if m > 1 else None)


def _others(m: int) -> str:
    return "the one other value" if m == 1 else f"each of the {m} others"


def _oriented(found: tuple, flip: bool) -> tuple:
    """A ``(comparison a - b, Holm p)`` as ``b - a`` when ``flip``."""
    test, p = found
    if not flip:
        return found
    flipped = dataclasses.replace(
        test,
        difference=-test.difference,
        low=-test.high,
        high=-test.low,
        only_a=test.only_b,
        only_b=test.only_a,
    )
    return flipped, p


def _up(test, holm_p: float) -> bool:
    return holm_p < ALPHA and test.difference > 0


def _acc(curve: Curve, i: int) -> str:
    return pct_interval(curve.mean[i], curve.low[i], curve.high[i])


def _name(curve: Curve, curves: Sequence[Curve]) -> str:
    several = len({c.sweep for c in curves}) > 1
    return curve.label + (f" ({curve.sweep})" if several else "")


def _absent(panel: Panel, key: str) -> Claim:
    return Claim(
        panel, key, f"{PANEL_TITLES[panel]} is not in this run", Verdict.UNCLEAR, in_run=False
    )


def _claim(
    panel: Panel, key: str, parts: Sequence[str], verdicts: Sequence[Verdict], figures: Sequence
) -> Claim:
    return Claim(panel, key, "; ".join(parts), tally(verdicts), "; ".join(figures))


def _points(test: PairedComparison, holm_p: float, m: int) -> str:
    """A difference with its 95 % interval and the p-value that judged it (Holm-adjusted in a
    family of ``m`` > 1), e.g. ``-2.5 points [-6.7, +1.7], p = 0.38``."""
    p = f"Holm p = {p_value(holm_p)}" if m > 1 else f"p = {p_value(test.p_value)}"
    return (
        f"{signed_points(test.difference)} points [{signed_points(test.low)}, "
        f"{signed_points(test.high)}], {p}"
    )


def tally(verdicts: Sequence[Verdict]) -> Verdict:
    """A claim's verdict from its tests' (one per model and sweep), by the rules of the module
    docstring: all alike, that verdict; any consistent (or in part) among others, in part; else
    contradicts if any test contradicts; else cannot tell (and cannot tell for no test)."""
    kinds = set(verdicts)
    if not kinds:
        return Verdict.UNCLEAR
    if len(kinds) == 1:
        return kinds.pop()
    if kinds & {Verdict.CONSISTENT, Verdict.PARTLY}:
        return Verdict.PARTLY
    return Verdict.CONTRADICTS if Verdict.CONTRADICTS in kinds else Verdict.UNCLEAR
