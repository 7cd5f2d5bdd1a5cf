r"""Chips as a population: reading cubes whose points simulate several chips of one design.

A design is fabricated as many chips; a sweep point with ``chips.count`` > 1 simulates ``N`` of
them, and its cube gains a ``chip`` dimension (coordinate 0..N-1; NaN and -1 pad a point with
fewer chips): ``accuracy`` (axes..., model, chip, repeat, fold), ``accuracy_mean``/``_low``/
``_high`` (axes..., model, chip), ``predicted``/``correct`` (axes..., model, chip, repeat,
recording) and the spike metrics (axes..., chip); the yield statistics (axes..., model) are
computed once, where the cube is built (``pipeline.results.yields``): ``accuracy_chip_mean``
(the mean over chips), ``accuracy_p05`` (the 5th percentile over chips) with its distribution-free
95 % interval ``accuracy_p05_low``/``_high`` (order statistics) and ``yield_share`` (the share of
chips at or above ``chips.yield_target``).

What the report makes of them, two kinds of chance kept apart:

* *The test set's noise* (which recordings happened to be recorded): the design's accuracy is
  the mean over its chips, :math:`\bar a = \frac{1}{N} \sum_c a_c`, with the 95 % interval of a
  stratified bootstrap over recordings, every chip and repeat of a recording drawn with it
  (:func:`pipeline.results.stats.accuracy_interval` of the chips' predictions taken as repeats):
  the error bars.
* *The spread over chips* (which chip a customer gets): the median and the 5th-95th percentile
  band of the chips' accuracies :math:`a_c`, drawn as a band around the curve, never merged into
  the error bars; and the yield, :math:`a_{(0.05)}`.

:func:`pooled` gives the rest of the report (curves, designs, fronts, Table I) a cube of the
familiar layout: no ``chip`` dimension, accuracy the mean over chips with the first interval, the
spike metrics the mean over chips; the per-chip accuracies kept as ``accuracy_per_chip``, their
predictions as ``correct_per_chip``. Comparisons of two designs of several chips resample chips
and recordings together (:func:`pipeline.results.stats.compare_over_chips`,
:meth:`pipeline.report.evidence.Evidence`).

Deployment (``chips.deployment``) is an ordinary swept field: ``per_chip`` (each chip calibrated:
its own classifier), ``shared`` (one classifier loaded into every chip) or ``robust`` (one
classifier trained across chips). Fig. 10 sets them side by side: a sweep of the mismatch and the
deployment together is split into one curve per deployment (:func:`deployment_of`), as are
several mismatch sweeps that differ only in their deployment, in the order the deployments are
declared (:func:`fill_groups`).
"""

from __future__ import annotations

import dataclasses
import math
import warnings
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.design.scene import Deployment, scene_field
from pipeline.report.curves import Curve, sweep_curves
from pipeline.report.panels import DEPLOYMENT
from pipeline.results.chip_cube import CHIP_DIM
from pipeline.results.variables import (
    ACCURACY_HIGH,
    ACCURACY_LOW,
    ACCURACY_MEAN,
    CORRECT,
    LABEL,
    MODEL_DIM,
    RECORDING_DIM,
    REPEAT_DIM,
    RESULT_KEY,
)
from pipeline.results.yields import (
    ACCURACY_CHIP_MEAN,
    ACCURACY_P05,
    ACCURACY_P05_HIGH,
    ACCURACY_P05_LOW,
    YIELD_SHARE,
    quantile_estimate_rank,
)
from pipeline.results.yields import QUANTILE as YIELD_QUANTILE

#: The dotted scene fields of the chips (declared by the scene's ``chips`` part).
CHIP_COUNT = scene_field("chips.count")
YIELD_TARGET = scene_field("chips.yield_target")
#: The deployment of a point that names none (one chip, its own classifier, the scene's default).
DEFAULT_DEPLOYMENT = Deployment.PER_CHIP.value
#: The deployment the paper's Fig. 10 claim is judged on (one classifier loaded into every chip,
#: the way chips are shipped without calibrating each).
CLAIM_DEPLOYMENT = Deployment.SHARED.value
#: The band of the chips' accuracies the figures draw around a curve (5th to 95th percentile).
SPREAD_QUANTILES = (0.05, 0.5, 0.95)
#: The chips' predictions a pooled cube keeps beside their pooling (axes..., model, chip,
#: chip_repeat, recording), int8 as ``correct``; ``chip_repeat`` is the cube's own ``repeat``.
PER_CHIP = "correct_per_chip"
CHIP_REPEAT = "chip_repeat"
#: The chips' accuracies a pooled cube keeps beside their mean (axes..., model, chip).
ACCURACY_PER_CHIP = "accuracy_per_chip"
#: The yield variables of a cube of several chips, (axes..., model).
YIELD_VARIABLES = (
    ACCURACY_CHIP_MEAN,
    ACCURACY_P05,
    ACCURACY_P05_LOW,
    ACCURACY_P05_HIGH,
    YIELD_SHARE,
)


def has_chips(cube: xr.Dataset) -> bool:
    """Whether the cube's points simulate several chips (its accuracy has a ``chip`` axis)."""
    return ACCURACY_MEAN in cube and CHIP_DIM in cube[ACCURACY_MEAN].dims


def chip_quantile(accuracy: np.ndarray) -> np.ndarray:
    """The yield statistic of chip accuracies float64 (..., chips) along the last axis: the
    order statistic of rank ``ceil(0.05 N)`` (at least 1) of the ``N`` chips, the estimate the
    cube's ``accuracy_p05`` is (``pipeline.results.yields.quantile_estimate_rank``), so that a
    bootstrap of it starts from the cube's own number."""
    values = np.sort(np.asarray(accuracy, dtype=np.float64), axis=-1)
    n = values.shape[-1]
    return values[..., quantile_estimate_rank(n, YIELD_QUANTILE) - 1]


def chip_mean(accuracy: np.ndarray) -> np.ndarray:
    """The mean of chip accuracies float64 (..., chips) along the last axis."""
    return np.mean(accuracy, axis=-1)


@dataclass(frozen=True)
class ChipYield:
    """Accuracy of one model at one design over its ``n_chips`` chips (fractions).

    ``p05`` is the 5th percentile over chips (the yield), ``p05_low``/``p05_high`` its
    distribution-free 95 % interval (NaN: too few chips for one); ``share`` the share of chips at
    or above ``target`` (NaN: unknown); ``low``/``median``/``high`` the 5th, 50th and 95th
    percentile of the chips' accuracies; ``deployment`` how the classifier was deployed ("" when
    the cube does not say).
    """

    n_chips: int
    mean: float
    p05: float
    p05_low: float
    p05_high: float
    share: float
    target: float
    low: float
    median: float
    high: float
    deployment: str


def pooled(cube: xr.Dataset) -> xr.Dataset:
    """The cube without its ``chip`` dimension, as the report reads one (see the module
    docstring); a cube without chips is returned as it is.

    The chips' predictions become repeats of one design (``correct``, ``predicted``: chip-major,
    ``repeat = chip * R + r``; ``test_fold`` the same splits for every chip), ``accuracy`` the
    chips' folds as repeats, ``accuracy_mean`` the mean over chips with the 95 % interval of a
    stratified bootstrap over recordings (seeded from the point's key and the model), every other
    variable along ``chip`` its mean over chips; ``accuracy_per_chip`` keeps the chips'
    accuracies (axes..., model, chip) and :data:`PER_CHIP` their predictions.
    """
    if not has_chips(cube):
        return cube
    from pipeline.report.seeds import rng_for
    from pipeline.results.stats import accuracy_interval

    per_chip = cube[ACCURACY_MEAN]
    n_chips = cube.sizes[CHIP_DIM]
    folded = [n for n, v in cube.data_vars.items() if CHIP_DIM in v.dims or REPEAT_DIM in v.dims]
    out = cube.drop_vars(folded)
    # The folded repeat axis is longer than the cube's: its coordinate no longer labels it.
    out = out.drop_vars([c for c in (REPEAT_DIM, CHIP_DIM) if c in out.coords])
    for name in folded:
        variable = cube[name]
        if name in (ACCURACY_MEAN, ACCURACY_LOW, ACCURACY_HIGH):
            continue
        if REPEAT_DIM in variable.dims and CHIP_DIM not in variable.dims:
            # The same splits for every chip (test_fold).
            variable = variable.expand_dims(
                {CHIP_DIM: n_chips}, axis=variable.dims.index(REPEAT_DIM)
            )
        if REPEAT_DIM in variable.dims:
            out[name] = _chips_as_repeats(variable)
        else:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # a padded chip of all NaN
                out[name] = variable.mean(CHIP_DIM, skipna=True, keep_attrs=True)
    mean = (
        cube[ACCURACY_CHIP_MEAN]
        if ACCURACY_CHIP_MEAN in cube
        else per_chip.mean(CHIP_DIM, skipna=True)
    )
    low, high = xr.full_like(mean, np.nan), xr.full_like(mean, np.nan)
    methods = set()
    if CORRECT in out and LABEL in cube.coords:
        dims = tuple(d for d in mean.dims if d != MODEL_DIM)
        correct = out[CORRECT].transpose(*dims, MODEL_DIM, REPEAT_DIM, RECORDING_DIM).values
        keys = cube[RESULT_KEY].transpose(*dims).values.ravel()
        labels = cube[LABEL].values
        cells = correct.reshape(len(keys), mean.sizes[MODEL_DIM], *correct.shape[-2:])
        values = mean.transpose(*dims, MODEL_DIM).values.reshape(cells.shape[:2])
        lows, highs = np.full(values.shape, np.nan), np.full(values.shape, np.nan)
        for p, key in enumerate(keys):
            for m, model in enumerate(mean[MODEL_DIM].values):
                cell = cells[p, m]
                ran = (cell >= 0).any(axis=1)
                held = (cell[ran] >= 0).all(axis=0)
                if not ran.any() or not held.any():
                    continue
                interval = accuracy_interval(
                    cell[ran][:, held] == 1,
                    labels[held],
                    rng=rng_for(str(key), str(model), CHIP_DIM),
                )
                values[p, m], lows[p, m], highs[p, m] = (
                    interval.estimate,
                    interval.low,
                    interval.high,
                )
                methods.add(f"{interval.method}, chips and repeats of a recording drawn with it")
        shape = mean.transpose(*dims, MODEL_DIM).shape
        mean = mean.transpose(*dims, MODEL_DIM).copy(data=values.reshape(shape))
        low = mean.copy(data=lows.reshape(shape))
        high = mean.copy(data=highs.reshape(shape))
    attrs = {"interval": "; ".join(sorted(methods)) or "none", "confidence": 0.95}
    out[ACCURACY_MEAN] = mean.assign_attrs(per_chip.attrs)
    out[ACCURACY_LOW] = low.assign_attrs(cube[ACCURACY_LOW].attrs | attrs)
    out[ACCURACY_HIGH] = high.assign_attrs(cube[ACCURACY_HIGH].attrs | attrs)
    out[ACCURACY_PER_CHIP] = per_chip
    if CORRECT in cube:
        per_chip_correct = cube[CORRECT].rename({REPEAT_DIM: CHIP_REPEAT})
        out[PER_CHIP] = per_chip_correct.drop_vars(
            [c for c in (CHIP_REPEAT, CHIP_DIM) if c in per_chip_correct.coords]
        )
    return out


def _chips_as_repeats(variable: xr.DataArray) -> xr.DataArray:
    """``variable`` (..., chip, repeat, ...) with chip and repeat folded into ``repeat``,
    chip-major."""
    order = [d for d in variable.dims if d not in (CHIP_DIM, REPEAT_DIM)]
    at = variable.dims.index(CHIP_DIM)
    moved = variable.transpose(*order[:at], CHIP_DIM, REPEAT_DIM, *order[at:])
    values = moved.values
    shape = (*values.shape[:at], values.shape[at] * values.shape[at + 1], *values.shape[at + 2 :])
    dims = (*order[:at], REPEAT_DIM, *order[at:])
    return xr.DataArray(values.reshape(shape), dims=dims, attrs=variable.attrs)


def chip_yields(cube: xr.Dataset) -> dict[tuple[int, str], ChipYield]:
    """``{(point index in C order over the sweep dimensions, model): ChipYield}`` of a cube of
    several chips, or of its :func:`pooled` view (empty for one without chips), read from its
    yield variables and its chips' accuracies."""
    if has_chips(cube):
        per_chip = cube[ACCURACY_MEAN]
    elif ACCURACY_PER_CHIP in cube:  # a pooled cube
        per_chip = cube[ACCURACY_PER_CHIP]
    else:
        return {}
    dims = tuple(d for d in per_chip.dims if d not in (MODEL_DIM, CHIP_DIM))
    models = [str(m) for m in per_chip[MODEL_DIM].values]
    chips = per_chip.transpose(*dims, MODEL_DIM, CHIP_DIM).values
    chips = chips.reshape(-1, len(models), chips.shape[-1])

    def flat(name: str) -> np.ndarray:
        if name not in cube:
            return np.full(chips.shape[:2], np.nan)
        return cube[name].transpose(*dims, MODEL_DIM).values.reshape(chips.shape[:2])

    found = {name: flat(name) for name in YIELD_VARIABLES}
    deployment = _point_values(cube, DEPLOYMENT, dims, chips.shape[0], "")
    target = _point_values(cube, YIELD_TARGET, dims, chips.shape[0], math.nan)
    yields = {}
    for p in range(chips.shape[0]):
        for m, model in enumerate(models):
            values = chips[p, m][np.isfinite(chips[p, m])]
            if not values.size:
                continue
            low, median, high = np.quantile(values, SPREAD_QUANTILES)
            p05 = found[ACCURACY_P05][p, m]
            yields[(p, model)] = ChipYield(
                n_chips=int(values.size),
                mean=_or(found[ACCURACY_CHIP_MEAN][p, m], float(np.mean(values))),
                p05=_or(p05, float(chip_quantile(values))),
                p05_low=float(found[ACCURACY_P05_LOW][p, m]),
                p05_high=float(found[ACCURACY_P05_HIGH][p, m]),
                share=float(found[YIELD_SHARE][p, m]),
                target=float(target[p]),
                low=float(low),
                median=float(median),
                high=float(high),
                deployment=str(deployment[p]),
            )
    return yields


def deployment_of(cube: xr.Dataset) -> str:
    """The deployment every point of a cube shares ("" when the cube does not say or its points
    differ)."""
    from pipeline.results.cube import field_coordinate

    name = field_coordinate(cube, DEPLOYMENT)
    if name is None or cube[name].ndim:
        return ""
    return str(cube[name].item())


def deployment_dim(cube: xr.Dataset) -> str | None:
    """The sweep dimension along which a cube varies the deployment, or None."""
    for coordinate in cube.coords.values():
        if coordinate.attrs.get("field") == DEPLOYMENT and coordinate.ndim == 1:
            return str(coordinate.dims[0])
    return None


def _point_values(
    cube: xr.Dataset, field: str, dims: tuple[str, ...], size: int, missing: object
) -> np.ndarray:
    from pipeline.results.cube import field_coordinate

    name = field_coordinate(cube, field)
    if name is None:
        return np.full(size, missing, dtype=object)
    like = cube[RESULT_KEY].transpose(*dims)
    return np.asarray(cube[name].broadcast_like(like).transpose(*dims).values).ravel()


def _or(value: float, fallback: float) -> float:
    return float(value) if math.isfinite(value) else fallback


def split_by_deployment(cube: xr.Dataset) -> list[tuple[str, xr.Dataset]]:
    """``[(deployment, one-dimensional cube)]``: a cube that sweeps the deployment beside one
    other axis, one part per deployment; any other cube as it is, with the deployment its points
    share ("" when it does not say)."""
    dim = deployment_dim(cube)
    if dim is None:
        return [(deployment_of(cube), cube)]
    return [(str(value), cube.sel({dim: value})) for value in cube[dim].values]


def with_chip_spread(curve: Curve, cube: xr.Dataset, x: np.ndarray, group: str) -> Curve:
    """``curve`` (of a one-dimensional cube, sorted by ``x`` as :func:`sweep_curves` sorts it)
    with its ``group`` and, for a pooled cube of several chips, the chips' spread at each
    point: the cube's ``accuracy_p05`` (the yield), the median and the 95th percentile of the
    chips' accuracies."""
    if ACCURACY_PER_CHIP not in cube:
        return dataclasses.replace(curve, group=group)
    (dim,) = tuple(d for d in cube[ACCURACY_MEAN].dims if d != MODEL_DIM)
    order = np.argsort(x, kind="stable")
    per_chip = cube[ACCURACY_PER_CHIP].sel({MODEL_DIM: curve.model}).transpose(dim, CHIP_DIM)
    values = per_chip.values[order]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a point with no chip: all NaN
        low, median, high = np.nanquantile(values, SPREAD_QUANTILES, axis=-1)
    if ACCURACY_P05 in cube:  # the yield as the cube states it, where it is computed once
        stated = cube[ACCURACY_P05].sel({MODEL_DIM: curve.model}).transpose(dim).values[order]
        low = np.where(np.isfinite(stated), stated, low)
    return dataclasses.replace(curve, group=group, chip_low=low, chip_median=median, chip_high=high)


def chip_curves(
    name: str, cube: xr.Dataset, x_of: Callable[[xr.Dataset], np.ndarray]
) -> tuple[Curve, ...]:
    """The curves of a (pooled) cube along its non-deployment axis, one per model and
    deployment, with the chips' spread; ``x_of`` gives a one-dimensional cube's abscissa."""
    curves = []
    for group, part in split_by_deployment(cube):
        x = x_of(part)
        curves += [with_chip_spread(c, part, x, group) for c in sweep_curves(name, part, x)]
    return tuple(curves)


def fill_groups(curves: Sequence[Curve]) -> tuple[Curve, ...]:
    """Curves of one figure where some state their deployment: those that do not are of the
    default one (:data:`DEFAULT_DEPLOYMENT`), and the deployments come in their declared order
    (:class:`~pipeline.design.scene.Deployment`), each one's curves in the order given, whatever
    the order of the sweeps (cubes by name) or of a swept deployment's values; curves none of
    which states one are returned as they are."""
    if not any(c.group for c in curves):
        return tuple(curves)
    filled = [c if c.group else dataclasses.replace(c, group=DEFAULT_DEPLOYMENT) for c in curves]
    return tuple(sorted(filled, key=lambda c: _DECLARED_ORDER.get(c.group, len(_DECLARED_ORDER))))


# Where each deployment comes in a figure's curves (a group that is none goes last).
_DECLARED_ORDER = {deployment.value: rank for rank, deployment in enumerate(Deployment)}


def method_sentence() -> str:
    """How designs of several chips are read and compared, said once with the answer's method."""
    return (
        "Designs simulated as several chips: a design's accuracy is the mean over its chips, its "
        "95 % interval the test set's (a bootstrap over recordings, every chip's prediction of a "
        "drawn recording drawn with it); two such designs are compared by a bootstrap over chips "
        "and recordings together (the same recordings and, the chips being common random "
        "numbers, the same chip indices for both), of the mean over chips or, for the answer by "
        "yield, of the 5th percentile over chips; a design of several chips against one of one "
        "chip compares the chips' mean with that chip on the recordings. The yield's 95 % "
        "interval is distribution-free, from order statistics: fewer than 59 chips give no "
        "lower bound."
    )
