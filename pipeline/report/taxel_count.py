r"""How many of a real array's taxels a design needs: accuracy against the number of taxels read.

A one-dimensional cube whose axis is ``array.taxels`` (a sweep over the number of a recorded
array's taxels that a design reads, :mod:`pipeline.chain.real_taxels`) gives, per model, the
accuracy at every count :math:`k` with its 95 % interval (the cube's), and a paired comparison
of every count with the most taxels the sweep reads, :math:`K = \max k`: the same recordings and
splits, exact McNemar for one repeat and a paired stratified bootstrap otherwise
(:meth:`pipeline.report.evidence.Evidence.compare`), the p-values Holm-adjusted over the counts
of one model (:func:`pipeline.results.stats.holm`). The fewest taxels *as accurate as* :math:`K`
is the smallest :math:`k` whose adjusted p is not below :data:`~pipeline.report.evidence.ALPHA`
or whose accuracy is not below that of :math:`K`; not significantly below is not as accurate,
and the difference's interval bounds the loss. Where the cube states the taxels' positions
(its ``taxel_positions_mm`` attribute), each count's pitch, the smallest distance between two
taxels read, is given beside it. The figure is the sweep's own curve
(:mod:`pipeline.report.sweeps`): accuracy with its interval against the taxels read.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.recordings.taxel_choice import chosen_taxels, taxel_pitch_mm
from pipeline.report.blocks import Block, Heading, Paragraph, Table
from pipeline.report.cubes import sweep_dims
from pipeline.report.curves import Curve, sweep_curves
from pipeline.report.evidence import ALPHA, Evidence
from pipeline.report.panels import TAXELS
from pipeline.report.sweeps import SweepPlot, safe_stem
from pipeline.report.text import comparison, pct_interval
from pipeline.results.stats import PairedComparison, holm

__all__ = ["TAXEL_COUNT_TITLE", "TaxelCount", "taxel_count_blocks", "taxel_counts"]

#: Title of the answer's sub-section.
TAXEL_COUNT_TITLE = "How many of the real array's taxels"


@dataclass(frozen=True)
class TaxelCount:
    """One model's accuracy along one sweep of ``array.taxels``.

    Attributes
    ----------
    curve : Curve
        Accuracy and its interval at each count read (``curve.x``), increasing.
    versus_most : tuple[PairedComparison | None, ...]
        Per count, its accuracy minus that of the most taxels read (None for the most itself,
        or where a point kept no per-recording results).
    holm_p : float64 (n,)
        Holm-adjusted p of each comparison (NaN where there is none).
    pitch_mm : float64 (n,) or None
        The pitch of the taxels read at each count (mm; NaN for one taxel), where the cube
        states the taxels' positions (:func:`pipeline.recordings.taxel_choice.taxel_pitch_mm`).
    """

    curve: Curve
    versus_most: tuple[PairedComparison | None, ...]
    holm_p: np.ndarray
    pitch_mm: np.ndarray | None = None

    def taxels_text(self, i: int) -> str:
        """Count ``i`` as text, with its pitch where known: ``"4 (pitch 3 mm)"``."""
        count = f"{self.curve.x[i]:g}"
        if self.pitch_mm is None or not math.isfinite(self.pitch_mm[i]):
            return count
        return f"{count} (pitch {self.pitch_mm[i]:.3g} mm)"

    @property
    def most(self) -> int:
        """Index of the most taxels read."""
        return int(np.argmax(self.curve.x))

    @property
    def fewest_as_accurate(self) -> int | None:
        """Index of the fewest taxels not significantly below the most (None without tests)."""
        if all(c is None for i, c in enumerate(self.versus_most) if i != self.most):
            return None
        for i in np.argsort(self.curve.x):
            found = self.versus_most[i]
            if i == self.most or (
                found is not None and (found.difference >= 0 or self.holm_p[i] >= ALPHA)
            ):
                return int(i)
        return self.most

    def sentence(self) -> str:
        """What the sweep says of this model, in one sentence."""
        c, most = self.curve, self.most
        head = (
            f"{c.model.upper()} (sweep {c.sweep}): all {self.taxels_text(most)} taxels read give "
            f"{pct_interval(c.mean[most], c.low[most], c.high[most])}"
        )
        fewest = self.fewest_as_accurate
        if fewest is None:
            return f"{head}; no count has per-recording results to compare it with."
        if fewest == most:
            return f"{head}; every fewer taxels read are significantly less accurate."
        return (
            f"{head}; the fewest taxels not significantly below them: {self.taxels_text(fewest)} "
            f"({pct_interval(c.mean[fewest], c.low[fewest], c.high[fewest])}, "
            f"{comparison(self.versus_most[fewest], float(self.holm_p[fewest]))})."
        )


def is_taxel_count(cube: xr.Dataset) -> bool:
    """Whether ``cube`` sweeps ``array.taxels`` along its one dimension."""
    dims = sweep_dims(cube)
    return len(dims) == 1 and cube[dims[0]].attrs.get("field") == TAXELS


def taxel_counts(cubes: Mapping[str, xr.Dataset], evidence: Evidence) -> tuple[TaxelCount, ...]:
    """Every model's :class:`TaxelCount` of every one-dimensional ``array.taxels`` sweep."""
    found = []
    for name, cube in cubes.items():
        if not is_taxel_count(cube):
            continue
        (dim,) = sweep_dims(cube)
        positions = cube.attrs.get("taxel_positions_mm")
        for curve in sweep_curves(name, cube, cube[dim].values.astype(np.float64)):
            found.append(_tested(curve, evidence, positions))
    return tuple(found)


def _pitches(x: np.ndarray, positions: Sequence | None) -> np.ndarray | None:
    """The pitch of the taxels read at each count ``x`` of an array at ``positions``."""
    if positions is None:
        return None
    where = np.asarray(positions, dtype=np.float64)
    return np.array([taxel_pitch_mm(where, chosen_taxels(len(where), int(k), where)) for k in x])


def _tested(curve: Curve, evidence: Evidence, positions: Sequence | None) -> TaxelCount:
    most = int(np.argmax(curve.x))
    versus = tuple(
        None if i == most else evidence.compare(key, curve.keys[most], curve.model)
        for i, key in enumerate(curve.keys)
    )
    tested = [i for i, c in enumerate(versus) if c is not None]
    holm_p = np.full(len(versus), math.nan)
    if tested:
        holm_p[tested] = holm([versus[i].p_value for i in tested])
    return TaxelCount(curve, versus, holm_p, _pitches(curve.x, positions))


def taxel_count_blocks(counts: Sequence[TaxelCount], plots: Sequence[SweepPlot]) -> Iterator[Block]:
    """The answer's sub-section on the taxels read: one sentence per model and sweep, a table of
    every count against the most; nothing for a run without such a sweep. ``plots`` are the
    report's sweep curves, where the figure of each sweep is."""
    if not counts:
        return
    yield Heading(3, TAXEL_COUNT_TITLE)
    figures = {p.sweep: p.title for p in plots}
    sweeps = list(dict.fromkeys(c.curve.sweep for c in counts))
    where = "; ".join(
        f"figure '{figures[s]}' (file {'sweep_' + safe_stem(s)})" for s in sweeps if s in figures
    )
    yield Paragraph(
        "Each count reads that many of the recorded array's taxels, spread evenly over their "
        "positions when the dataset gives them, else over their declared order "
        "(array.taxels). Every count is compared with the most taxels read by a paired test on "
        "the same recordings and splits, Holm-adjusted over the counts of each model."
        + (f" Accuracy against the taxels read: {where}." if where else "")
    )
    for count in counts:
        yield Paragraph(count.sentence())
    yield Table(
        (
            "model",
            "sweep",
            "taxels read",
            "accuracy [95 % interval]",
            "difference to the most taxels read [95 % interval], p",
        ),
        tuple(row for count in counts for row in _rows(count)),
    )


def _rows(count: TaxelCount) -> Iterator[tuple[str, ...]]:
    c = count.curve
    for i in np.argsort(c.x):
        found = count.versus_most[i]
        if i == count.most:
            versus = "(the most)"
        elif found is None:
            versus = "no per-recording results"
        else:
            versus = comparison(found, float(count.holm_p[i]))
        yield (
            c.model.upper(),
            c.sweep,
            count.taxels_text(int(i)),
            pct_interval(c.mean[i], c.low[i], c.high[i]),
            versus,
        )
