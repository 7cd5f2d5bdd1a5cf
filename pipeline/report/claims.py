"""The paper's claims beside what this run's cubes say about them, one sentence each.

Along a sweep the optimum is ``x* = argmax a(x)``; the paper's value ``x_p`` *holds* when
``a(x_p) >= a(x*) - s(x*)``, i.e. it is within one fold standard deviation of the best
(differences smaller than that are fold-to-fold noise).

Taxel gain from ``n1`` to ``n2`` taxels: ``g = a(n2) / a(n1) - 1`` (the paper: +63 % from 1 to 16,
then saturation); the array *rises* when ``a(n2) - a(n1) > s(n2)`` and *saturates* after 16 when
``|a(25) - a(16)| <= s(25)``.

Trend with mismatch: the least-squares line of ``a`` on ``sigma_rel`` over the sweep's points
(:func:`scipy.stats.linregress`), its slope and two-sided p-value. SSNR should correlate
positively and STE negatively with accuracy (the cube's Pearson r, p < :data:`SIGNIFICANCE`).
"""

from __future__ import annotations

import enum
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from pipeline.report.curves import Curve, MetricFit
from pipeline.report.panels import PANEL_TITLES, Panel
from pipeline.report.text import pct, pct_pm

PAPER_THRESHOLD_V = 0.09
PAPER_WINDOW_S = 0.1
PAPER_TAXEL_GAIN = 0.63  # from 1 to 16 taxels
PAPER_TAXELS = (1, 16)
SATURATION_TAXELS = 25
SIGNIFICANCE = 0.05

_METRIC_NAMES = {"ssnr_db": "SSNR", "ste_s2": "STE"}


class Verdict(enum.StrEnum):
    """How this run's cube compares with one of the paper's claims."""

    AGREES = "agrees"
    PARTLY = "agrees only in part"
    DISAGREES = "disagrees"
    UNCLEAR = "can neither confirm nor refute it"
    ABSENT = "not in this run"


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims beside what this run's cube says about it."""

    panel: Panel
    paper: str
    finding: str
    verdict: Verdict

    @property
    def sentence(self) -> str:
        if self.verdict is Verdict.ABSENT:
            return f"The paper finds {self.paper}; {self.finding}."
        return f"The paper finds {self.paper}; here {self.finding}, so this run {self.verdict}."


def optimum_claim(
    panel: Panel, curves: Sequence[Curve], reference: float, unit: str, paper: str
) -> Claim:
    """Is the paper's optimum ``reference`` within one fold std of each model's best?"""
    if not curves:
        return Claim(panel, paper, f"{PANEL_TITLES[panel]} is not in this run", Verdict.ABSENT)
    parts, holds = [], []
    for curve in curves:
        b = curve.best
        at = f"{curve.model.upper()} is best at {curve.x[b]:g} {unit} ({pct_pm(curve, b)})"
        ref = curve.index(reference)
        close = int(np.sum(curve.mean >= curve.mean[b] - curve.std[b]))
        if ref is None:
            parts.append(f"{at}, {reference:g} {unit} was not swept")
            continue
        holds.append(bool(curve.mean[ref] >= curve.mean[b] - curve.std[b]))
        within = "within" if holds[-1] else "outside"
        parts.append(
            f"{at} and {reference:g} {unit} ({pct(curve.mean[ref])}) is {within} one fold "
            f"standard deviation of it, as are {close} of {curve.x.size} points"
        )
    return Claim(panel, paper, "; ".join(parts), _tally(holds))


def taxel_claim(curves: Sequence[Curve]) -> Claim:
    """The paper's +63 % from 1 to 16 taxels and the saturation after it."""
    paper = "accuracy rising by 63 % from 1 to 16 taxels, then saturating"
    usable = [c for c in curves if all(c.index(n) is not None for n in PAPER_TAXELS)]
    if not usable:
        swept = sorted({int(x) for c in curves for x in c.x})
        what = f"only {swept} taxels were swept" if curves else "no taxel sweep is in this run"
        return Claim(Panel.TAXELS, paper, what, Verdict.ABSENT if not curves else Verdict.UNCLEAR)
    parts, rises, saturates = [], [], []
    for curve in usable:
        i1, i16 = (curve.index(n) for n in PAPER_TAXELS)
        gain = curve.mean[i16] / curve.mean[i1] - 1.0
        rises.append(bool(curve.mean[i16] - curve.mean[i1] > curve.std[i16]))
        text = (
            f"{curve.model.upper()} ({curve.sweep}) goes from {pct(curve.mean[i1])} to "
            f"{pct_pm(curve, i16)} ({gain:+.0%})"
        )
        i25 = curve.index(SATURATION_TAXELS)
        if i25 is not None:
            saturates.append(bool(abs(curve.mean[i25] - curve.mean[i16]) <= curve.std[i25]))
            text += f" and then {pct(curve.mean[i25])} at {SATURATION_TAXELS}"
        parts.append(text)
    verdict = _tally([r and s for r, s in zip(rises, saturates, strict=False)] or rises)
    if not any(rises):
        verdict = Verdict.DISAGREES
    return Claim(Panel.TAXELS, paper, "; ".join(parts), verdict)


def metric_claim(fits: Sequence[MetricFit]) -> Claim:
    """SSNR should correlate positively with accuracy and STE negatively (Pearson, p < 0.05)."""
    paper = "SSNR correlating positively and STE negatively with accuracy"
    if not fits:
        return Claim(
            Panel.SPIKE_METRICS, paper, "no correlate sweep is in this run", Verdict.ABSENT
        )
    parts, ok = [], []
    for fit in fits:
        sign = 1.0 if fit.metric == "ssnr_db" else -1.0
        ok.append(bool(sign * fit.r > 0 and fit.p < SIGNIFICANCE))
        parts.append(
            f"{_METRIC_NAMES[fit.metric]} gives r = {fit.r:+.2f} (p = {fit.p:.2g}) for the "
            f"{fit.model.upper()}"
        )
    return Claim(Panel.SPIKE_METRICS, paper, "; ".join(parts), _tally(ok))


def mismatch_claim(curves: Sequence[Curve]) -> Claim:
    """Does accuracy fall with threshold mismatch (least-squares slope < 0, p < 0.05)?"""
    from scipy import stats

    paper = "accuracy falling as threshold mismatch grows"
    if not curves:
        return Claim(Panel.MISMATCH, paper, "no mismatch sweep is in this run", Verdict.ABSENT)
    parts, verdicts = [], []
    for curve in curves:
        if curve.x.size < 3:
            parts.append(f"{curve.model.upper()} has only {curve.x.size} mismatch levels")
            verdicts.append(Verdict.UNCLEAR)
            continue
        fit = stats.linregress(curve.x, curve.mean)
        direction = "falls" if fit.slope < 0 else "rises"
        parts.append(
            f"{curve.model.upper()} accuracy {direction} ({pct(curve.mean[0])} at "
            f"{curve.x[0]:.0%} to {pct(curve.mean[-1])} at {curve.x[-1]:.0%}; slope "
            f"{fit.slope * 0.1:+.1%} per 10 % mismatch, p = {fit.pvalue:.2g})"
        )
        if fit.pvalue >= SIGNIFICANCE:
            verdicts.append(Verdict.UNCLEAR)
        else:
            verdicts.append(Verdict.AGREES if fit.slope < 0 else Verdict.DISAGREES)
    if len(set(verdicts)) == 1:
        verdict = verdicts[0]
    elif Verdict.AGREES in verdicts:
        verdict = Verdict.PARTLY
    else:
        verdict = Verdict.DISAGREES if Verdict.DISAGREES in verdicts else Verdict.UNCLEAR
    return Claim(Panel.MISMATCH, paper, "; ".join(parts), verdict)


def _tally(holds: Sequence[bool]) -> Verdict:
    if not holds:
        return Verdict.UNCLEAR
    if all(holds):
        return Verdict.AGREES
    return Verdict.PARTLY if any(holds) else Verdict.DISAGREES
