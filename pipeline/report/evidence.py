"""Per-recording results of a whole run, and the paired tests the report runs on them.

Every point of a run evaluated on the same dataset sees the same recordings and the same folds,
so any two points, of one cube or of two, can be compared recording by recording. A point is
identified across cubes by its ``result_key``; a recording by its name and class (and the
dataset's ``dataset.kind`` and ``dataset.path``, so that recordings of two datasets that happen to
share a name are never paired). The run's recordings are the union over all cubes.

For a point and a model, ``correct`` is int8 (repeats, n_run_recordings): 1 right, 0 wrong, -1
no prediction (a recording the point did not hold, a repeat or model it did not run). A paired
comparison of points ``a`` and ``b`` uses the repeats both ran and, among those, the recordings
both predicted in every such repeat; then :func:`pipeline.results.stats.compare_paired` gives
``accuracy(a) - accuracy(b)`` on them, its 95 % interval (paired stratified bootstrap over
recordings) and its p-value (exact McNemar for one repeat, bootstrap otherwise). A trend along
several points (:func:`pipeline.results.stats.trend`) uses the recordings all of them predicted.

Points of several chips (:mod:`pipeline.report.chip_population`) hold ``correct`` per chip, int8
(chips, repeats, n_run_recordings), in ``per_chip``; ``correct`` holds their chips as repeats. Two
such points are compared by a bootstrap over chips and recordings together
(:func:`pipeline.results.stats.compare_over_chips`): the mean over chips by
:meth:`Evidence.compare`, the 5th percentile over chips (the yield) by
:meth:`Evidence.compare_yield`.

Seeds: every bootstrap draws from its own generator (:func:`pipeline.report.seeds.rng_for`), so a
comparison gives the same interval wherever the report shows it and in whatever order the report
computes it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from pipeline.report.cubes import field_values, point_keys, sweep_dims
from pipeline.report.panels import DATASET_KIND, DATASET_PATH
from pipeline.report.seeds import rng_for
from pipeline.results.stats import (
    PairedComparison,
    Trend,
    compare_over_chips,
    compare_paired,
    trend,
)
from pipeline.results.variables import (
    CORRECT,
    LABEL,
    MODEL_DIM,
    RECORDING_DIM,
    REPEAT_DIM,
    RESULT_KEY,
)

RESAMPLES = 2000
"""Bootstrap resamples of every paired comparison and trend the report tests."""
ALPHA = 0.05
"""Significance level of every test the report judges a claim or a design by."""


@dataclass(frozen=True, eq=False)
class Evidence:
    """The run's per-recording results.

    Attributes
    ----------
    labels : int64 (n,)
        Class of each of the run's ``n`` recordings.
    correct : dict
        ``(result key, model)`` -> int8 ``(repeats, n)``: 1 right, 0 wrong, -1 no prediction;
        only points that kept predictions are here (a point of several chips: its chips'
        repeats, chip-major).
    per_chip : dict
        ``(result key, model)`` -> int8 ``(chips, repeats, n)`` of the points of several chips.
    """

    labels: np.ndarray
    correct: Mapping[tuple[str, str], np.ndarray]
    _memo: dict = field(default_factory=dict, repr=False)
    per_chip: Mapping[tuple[str, str], np.ndarray] = field(default_factory=dict)

    def has(self, key: str, model: str) -> bool:
        """Whether the point holds per-recording results for ``model``."""
        return (key, model) in self.correct

    def compare(self, a: str, b: str, model: str) -> PairedComparison | None:
        """``accuracy(a) - accuracy(b)`` of ``model`` on the recordings both predicted, with its
        interval and p-value; None when either point has no predictions or they share none."""
        memo = ("compare", a, b, model)
        if memo not in self._memo:
            self._memo[memo] = self._compare(a, b, model)
        return self._memo[memo]

    def trend(self, keys: Sequence[str], x: Sequence[float], model: str) -> Trend | None:
        """Least-squares slope of ``model``'s accuracy on ``x`` over the points ``keys`` (paired
        bootstrap); None when a point has no predictions, the points share no recording, or
        ``x`` has fewer than 2 distinct values."""
        x = np.asarray(x, dtype=np.float64)
        if len(keys) < 2 or np.unique(x).size < 2 or not all(self.has(k, model) for k in keys):
            return None
        arrays = [self.correct[(k, model)] for k in keys]
        repeats = min(a.shape[0] for a in arrays)
        stack = np.stack([a[:repeats] for a in arrays])  # (levels, repeats, n)
        rows = (stack >= 0).any(axis=2).all(axis=0)
        stack = stack[:, rows]
        cols = (stack >= 0).all(axis=(0, 1))
        if not rows.any() or not cols.any():
            return None
        return trend(
            stack[:, :, cols] == 1,
            x,
            self.labels[cols],
            rng=rng_for("trend", model, *keys),
            resamples=RESAMPLES,
        )

    def compare_yield(self, a: str, b: str, model: str) -> PairedComparison | None:
        """``yield(a) - yield(b)`` of ``model``, the yield being the 5th percentile of the
        chips' accuracies (:func:`pipeline.report.chip_population.chip_quantile`), with the
        interval and p-value of a bootstrap over chips and recordings; None unless both points
        hold several chips' predictions on common recordings."""
        from pipeline.report.chip_population import chip_quantile

        memo = ("yield", a, b, model)
        if memo not in self._memo:
            self._memo[memo] = self._over_chips(a, b, model, chip_quantile, "yield")
        return self._memo[memo]

    def _over_chips(
        self, a: str, b: str, model: str, statistic, what: str
    ) -> PairedComparison | None:
        if (a, model) not in self.per_chip or (b, model) not in self.per_chip:
            return None
        ca, cb = self.per_chip[(a, model)], self.per_chip[(b, model)]
        repeats = min(ca.shape[1], cb.shape[1])
        ca, cb = ca[:, :repeats], cb[:, :repeats]
        # The chips that ran (a point pads its chips beyond its count with -1), and the
        # repeats every chip of both ran.
        ca, cb = ca[(ca >= 0).any(axis=(1, 2))], cb[(cb >= 0).any(axis=(1, 2))]
        rows = (ca >= 0).any(axis=2).all(axis=0) & (cb >= 0).any(axis=2).all(axis=0)
        ca, cb = ca[:, rows], cb[:, rows]
        cols = (ca >= 0).all(axis=(0, 1)) & (cb >= 0).all(axis=(0, 1))
        if not len(ca) or not len(cb) or not rows.any() or not cols.any():
            return None
        return compare_over_chips(
            ca[:, :, cols] == 1,
            cb[:, :, cols] == 1,
            self.labels[cols],
            statistic=statistic,
            rng=rng_for(what, a, b, model),
            resamples=RESAMPLES,
        )

    def differences(self, a: str, b: str, model: str) -> np.ndarray | None:
        """float64 (n,): per recording both predicted, ``(s_i(a) - s_i(b)) / R``, the share of
        the ``R`` common repeats (chips' repeats included) it is right in ``a`` less that in
        ``b``; None when no paired comparison can be made."""
        paired = self._paired(a, b, model) if self.has(a, model) and self.has(b, model) else None
        if paired is None:
            return None
        ca, cb, _ = paired
        return (ca.astype(np.float64) - cb).mean(axis=0)

    def _compare(self, a: str, b: str, model: str) -> PairedComparison | None:
        if not (self.has(a, model) and self.has(b, model)):
            return None
        if (a, model) in self.per_chip and (b, model) in self.per_chip:
            from pipeline.report.chip_population import chip_mean

            return self._over_chips(a, b, model, chip_mean, "mean")
        paired = self._paired(a, b, model)
        if paired is None:
            return None
        ca, cb, labels = paired
        return compare_paired(ca, cb, labels, rng=rng_for(a, b, model), resamples=RESAMPLES)

    def _paired(self, a: str, b: str, model: str) -> tuple[np.ndarray, ...] | None:
        """bool ``(repeats, n)`` of ``a`` and ``b`` on the repeats and recordings both
        predicted, and those recordings' labels; None when they share none."""
        ca, cb = self.correct[(a, model)], self.correct[(b, model)]
        chipped = ((a, model) in self.per_chip, (b, model) in self.per_chip)
        if chipped[0] != chipped[1]:
            # One design of several chips, one of one: the one chip's repeats stand beside
            # every chip of the other, so that the chips' mean is compared with the one chip
            # (on the recordings; that one chip is a given, not a draw).
            many, one = (ca, cb) if chipped[0] else (cb, ca)
            n_chips = self.per_chip[(a, model) if chipped[0] else (b, model)].shape[0]
            one = np.tile(one[: many.shape[0] // n_chips], (n_chips, 1))
            ca, cb = (many, one) if chipped[0] else (one, many)
        repeats = min(ca.shape[0], cb.shape[0])
        ca, cb = ca[:repeats], cb[:repeats]
        rows = (ca >= 0).any(axis=1) & (cb >= 0).any(axis=1)
        ca, cb = ca[rows], cb[rows]
        cols = (ca >= 0).all(axis=0) & (cb >= 0).all(axis=0)
        if not rows.any() or not cols.any():
            return None
        return ca[:, cols] == 1, cb[:, cols] == 1, self.labels[cols]


def gather_evidence(cubes: Mapping[str, xr.Dataset]) -> Evidence:
    """The per-recording results of every point of every cube that kept them."""
    from pipeline.report.chip_population import CHIP_DIM, CHIP_REPEAT, PER_CHIP, pooled

    index: dict[tuple[str, str, int], int] = {}
    found: dict[tuple[str, str], tuple[np.ndarray, np.ndarray]] = {}
    chips: dict[tuple[str, str], np.ndarray] = {}
    for cube in cubes.values():
        if CORRECT not in cube:
            continue
        cube = pooled(cube)
        if PER_CHIP in cube:
            layout = (*sweep_dims(cube), MODEL_DIM, CHIP_DIM, CHIP_REPEAT, RECORDING_DIM)
            by_chip = cube[PER_CHIP].transpose(*layout).values
            by_chip = by_chip.reshape(-1, *by_chip.shape[len(layout) - 4 :])
            for p, key in enumerate(point_keys(cube)):
                for m, model in enumerate(str(v) for v in cube[MODEL_DIM].values):
                    chips.setdefault((key, model), by_chip[p, m])
        dims = sweep_dims(cube)
        names = [str(n) for n in cube[RECORDING_DIM].values]
        labels = [int(v) for v in cube[LABEL].values]
        datasets = _dataset_ids(cube)
        correct = cube[CORRECT].transpose(*dims, MODEL_DIM, REPEAT_DIM, RECORDING_DIM).values
        correct = correct.reshape(-1, *correct.shape[len(dims) :])
        for p, key in enumerate(point_keys(cube)):
            columns = np.array(
                [
                    index.setdefault((datasets[p], name, label), len(index))
                    for name, label in zip(names, labels, strict=True)
                ],
                dtype=np.int64,
            )
            for m, model in enumerate(str(v) for v in cube[MODEL_DIM].values):
                values = correct[p, m]
                if (key, model) in found or not (values >= 0).any():
                    continue
                found[(key, model)] = (columns, values)
    n = len(index)
    labels = np.zeros(n, dtype=np.int64)
    for (_, _, label), i in index.items():
        labels[i] = label
    arrays, per_chip = {}, {}
    for (key, model), (columns, values) in found.items():
        full = np.full((values.shape[0], n), -1, dtype=np.int8)
        full[:, columns] = values
        arrays[(key, model)] = full
        if (key, model) in chips:
            values = chips[(key, model)]
            full = np.full((*values.shape[:2], n), -1, dtype=np.int8)
            full[:, :, columns] = values
            per_chip[(key, model)] = full
    return Evidence(labels=labels, correct=arrays, per_chip=per_chip)


def _dataset_ids(cube: xr.Dataset) -> list[str]:
    """Which recordings each point saw (``dataset.kind`` and ``dataset.path``), in point order."""
    found = (field_values(cube, name) for name in (DATASET_KIND, DATASET_PATH))
    parts = [values.ravel() for values in found if values is not None]
    size = cube[RESULT_KEY].size
    return ["|".join(str(p[i]) for p in parts) for i in range(size)]


PointRef = str | tuple[str, Mapping[str, object]]
"""A point of a run: its result key, or ``(sweep name, {dimension: value})`` in that sweep."""


def compare_points(
    cubes: Mapping[str, xr.Dataset], model: str, a: PointRef, b: PointRef
) -> PairedComparison:
    """Paired comparison of ``model``'s accuracy at two points of a run, recording by recording.

    Parameters
    ----------
    cubes
        The run's cubes (:func:`~storage.store.open_results`).
    model
        ``"ffnn"`` or ``"cnn"``.
    a, b
        Each a result key (the cubes' ``result_key`` coordinate) or ``(sweep, {dim: value})``,
        e.g. ``("threshold", {"threshold_v": 0.09})``; the points may lie in different cubes.

    Returns
    -------
    PairedComparison
        ``accuracy(a) - accuracy(b)`` on the recordings (and repeats) both predicted, its 95 %
        interval (paired, class-stratified bootstrap over recordings), the exact McNemar p-value
        (one repeat; a bootstrap p-value for several) and the discordant counts; the same numbers
        the report shows for these two points.

    Raises
    ------
    KeyError
        A sweep, dimension value or result key that the cubes do not hold.
    ValueError
        A point without per-recording results for ``model`` (a run that predates them), or two
        points that share no recording.
    """
    key_a, key_b = _result_key(cubes, a), _result_key(cubes, b)
    evidence = gather_evidence(cubes)
    missing = [str(ref) for ref, key in ((a, key_a), (b, key_b)) if not evidence.has(key, model)]
    if missing:
        raise ValueError(
            f"no per-recording {model} results at {', '.join(missing)}: re-run the sweep"
        )
    comparison = evidence.compare(key_a, key_b, model)
    if comparison is None:
        raise ValueError(f"{a} and {b} share no recording")
    return comparison


def _result_key(cubes: Mapping[str, xr.Dataset], ref: PointRef) -> str:
    if isinstance(ref, str):
        if not any(ref in point_keys(cube) for cube in cubes.values()):
            raise KeyError(f"no point has result key {ref!r}")
        return ref
    sweep, at = ref
    if sweep not in cubes:
        raise KeyError(f"no sweep {sweep!r} (the run has {', '.join(sorted(cubes))})")
    cube = cubes[sweep]
    dims = sweep_dims(cube)
    if set(at) != set(dims):
        raise KeyError(f"sweep {sweep!r} needs a value for each of {list(dims)}, got {sorted(at)}")
    try:
        return str(cube[RESULT_KEY].sel(dict(at)).item())
    except KeyError:
        raise KeyError(f"sweep {sweep!r} has no point at {dict(at)}") from None
