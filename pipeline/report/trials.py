"""The front of a search: the Pareto-optimal trials over two or three objectives, and hypervolume.

Objectives are turned into costs to minimise (``sign * value``,
:attr:`~pipeline.design.space.Objective.sign`). Trial ``a`` *dominates* ``b`` when it is no worse
in every objective and better in one; the *front* is the trials no other trial dominates
(:func:`pareto_mask`; two trials of one design, the same result key, are one point). A trial off
the front is compared with the front trial dominating it that is best in the first accuracy
objective, by the report's paired test on the same recordings
(:meth:`pipeline.report.evidence.Evidence.compare`, one unadjusted test per trial, alpha 0.05);
one the test cannot tell from it is *indistinguishable* and kept beside the front, as the
report's hardware fronts do.

The *hypervolume* of a front (:func:`hypervolume`) is the volume of objective space, in costs,
that its points dominate and that a reference point bounds: ``lambda(U_p [p, r])``. It is
computed exactly by slicing along the last objective (fronts of a search hold tens of points).

The front cube (:func:`front_cube`) is the trial cube restricted to the front and the trials
indistinguishable from it, with ``objective_value`` (trial, objective), ``on_front`` (trial, bool)
and ``dominated_by`` (trial: the trial number of the front trial compared with, -1 on the front).
The report shows every search of a run by its front cube (:func:`search_fronts`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import xarray as xr

from pipeline.design.space import TRIAL_DIM, Metric, Objective
from pipeline.report.evidence import ALPHA, gather_evidence
from pipeline.results.cube import paid_seconds, work_seconds
from pipeline.results.objectives import objective_values
from pipeline.results.variables import CHARGE_DIM, RESULT_KEY, STAGE_DIM
from pipeline.run.records import Charge

OBJECTIVE_ATTRS = {"units": "1", "long_name": "objective"}
VALUE_ATTRS = {"units": "1", "long_name": "value of the objective (its own units)"}


def pareto_mask(costs: np.ndarray) -> np.ndarray:
    """bool (n,): the rows of ``costs`` (float64 (n, d), minimised) no other row dominates.

    Rows with a NaN are never on the front; equal rows are all on it or all off it.
    """
    costs = np.asarray(costs, dtype=np.float64)
    usable = np.isfinite(costs).all(axis=1)
    on = usable.copy()
    for i in np.flatnonzero(usable):
        others = costs[usable]
        dominated = (others <= costs[i]).all(axis=1) & (others < costs[i]).any(axis=1)
        on[i] = not dominated.any()
    return on


def hypervolume(costs: np.ndarray, reference: np.ndarray) -> float:
    """Volume that the rows of ``costs`` (float64 (n, d), minimised) dominate below
    ``reference`` (d,); rows not strictly below it in every objective add nothing."""
    costs = np.asarray(costs, dtype=np.float64)
    reference = np.asarray(reference, dtype=np.float64)
    inside = costs[np.isfinite(costs).all(axis=1) & (costs < reference).all(axis=1)]
    if inside.size == 0:
        return 0.0
    if reference.size == 1:
        return float(reference[0] - inside[:, 0].min())
    inside = inside[np.argsort(inside[:, -1], kind="stable")]
    volume = 0.0
    for i in range(len(inside)):
        top = inside[i + 1, -1] if i + 1 < len(inside) else reference[-1]
        if top > inside[i, -1]:
            volume += hypervolume(inside[: i + 1, :-1], reference[:-1]) * (top - inside[i, -1])
    return volume


def trial_costs(cube: xr.Dataset, objectives: Sequence[Objective]) -> np.ndarray:
    """float64 (trials, objectives): each objective of each trial as a cost (minimised)."""
    signs = np.array([o.sign for o in objectives])
    return objective_values(cube, objectives) * signs


def front_cube(trials: xr.Dataset, objectives: Sequence[Objective]) -> xr.Dataset:
    """The front of a trial cube (dimension :data:`~pipeline.design.space.TRIAL_DIM`), with the
    indistinguishable trials beside it (see the module docstring)."""
    values = objective_values(trials, objectives)
    costs = values * np.array([o.sign for o in objectives])
    keys = [str(k) for k in trials[RESULT_KEY].values]
    on = pareto_mask(costs)
    accuracy = next((o for o in objectives if o.metric is Metric.ACCURACY), None)
    evidence = gather_evidence({"trials": trials}) if accuracy is not None else None
    dominated_by = np.full(len(keys), -1, dtype=np.int64)
    kept = on.copy()
    front = np.flatnonzero(on)
    numbers = trials[TRIAL_DIM].values
    for i in np.flatnonzero(~on & np.isfinite(costs).all(axis=1)):
        above = [j for j in front if (costs[j] <= costs[i]).all() and (costs[j] < costs[i]).any()]
        if not above or evidence is None or accuracy is None:
            continue
        j = min(above, key=lambda j: costs[j][objectives.index(accuracy)])
        dominated_by[i] = numbers[j]
        test = evidence.compare(keys[i], keys[j], accuracy.model or "")
        kept[i] = test is not None and not test.significant(ALPHA)
    names = [o.name for o in objectives]
    marked = trials.assign(
        objective_value=((TRIAL_DIM, "objective"), values, VALUE_ATTRS),
        on_front=(TRIAL_DIM, on, {"units": "1", "long_name": "on the Pareto front"}),
        dominated_by=(
            TRIAL_DIM,
            dominated_by,
            {"units": "1", "long_name": "trial of the front it is compared with (-1: none)"},
        ),
    ).assign_coords(objective=("objective", names, OBJECTIVE_ATTRS))
    return marked.isel({TRIAL_DIM: np.flatnonzero(kept)})


def trial_cube(cube: xr.Dataset, numbers: Sequence[int], space_name: str) -> xr.Dataset:
    """A trial grid's cube (:meth:`pipeline.design.space.Space.trial_grid`) along
    :data:`~pipeline.design.space.TRIAL_DIM`, the trials' ``numbers`` its coordinate; the searched
    fields stay coordinates along it (attribute ``field``), as every other scene field does."""
    (dim,) = cube[RESULT_KEY].dims
    renamed = cube.rename_dims({dim: TRIAL_DIM}).drop_indexes(dim)
    attrs = {"units": "1", "long_name": "trial of the search, in the order asked"}
    numbered = renamed.assign_coords({TRIAL_DIM: (TRIAL_DIM, np.asarray(numbers), attrs)})
    return numbered.assign_attrs(space=space_name)


def search_seconds(
    cube: xr.Dataset,
    spike_keys: Sequence[str],
    spike_stages: Sequence[str],
    *,
    shared: bool = True,
) -> float:
    """The stage seconds a search's trials cost: the seconds paid computing each distinct point,
    once (the cube's paid ``seconds``, both charges: a spike train, a load or a kernel compile
    that trials share was paid by one point and counts once), as paid when each point was
    computed, whether this search or an earlier run computed it. ``shared=False``: the ``own``
    charge alone, what the points cost beyond the one-off load and set-up their workers paid.

    A point stored before paid seconds were kept counts its work seconds, with the
    ``spike_stages`` of each spike train (``spike_keys``, per trial) once, so that a trial
    sharing the train of an earlier one costs only its coding and training.
    """
    stages = [str(s) for s in cube[STAGE_DIM].values]
    spike = np.array([s in spike_stages for s in stages])
    paid, work = paid_seconds(cube), work_seconds(cube)
    paid_rows = None if paid is None else paid.transpose(TRIAL_DIM, STAGE_DIM, CHARGE_DIM).values
    work_rows = None if work is None else work.transpose(TRIAL_DIM, STAGE_DIM).values
    own = None if paid is None else [str(c) for c in paid[CHARGE_DIM].values].index(Charge.OWN)
    seen_points: set[str] = set()
    seen_trains: set[str] = set()
    total = 0.0
    for i, key in enumerate(str(k) for k in cube[RESULT_KEY].values):
        if key in seen_points:
            continue
        seen_points.add(key)
        if paid_rows is not None and np.isfinite(paid_rows[i]).all():
            total += float(paid_rows[i].sum() if shared else paid_rows[i][:, own].sum())
            if paid_rows[i][spike].sum() > 0:
                seen_trains.add(spike_keys[i])
            continue
        if work_rows is None:
            continue
        keep = ~spike if spike_keys[i] in seen_trains else np.ones_like(spike)
        seen_trains.add(spike_keys[i])
        total += float(np.nansum(work_rows[i][keep]))
    return total


@dataclass(frozen=True)
class SearchFront:
    """One search of a run as the report shows it: the space's ``name``, the trials told
    (``n_trials``; None if its trial cube is not in the run), the ``objectives`` by name and its
    front cube's trials as ``(trial, on the front, objective values in that order)``."""

    name: str
    n_trials: int | None
    objectives: tuple[str, ...]
    rows: tuple[tuple[int, bool, tuple[float, ...]], ...]


def search_fronts(cubes: Mapping[str, xr.Dataset]) -> tuple[SearchFront, ...]:
    """Every search among a run's cubes (``{name: cube}``), by its front cube (one holding
    ``on_front`` and ``objective_value``), in the mapping's order; a search's name is its
    cubes' attribute ``space``."""
    found = []
    for name, cube in cubes.items():
        if "on_front" not in cube or "objective_value" not in cube:
            continue
        space = str(cube.attrs.get("space", name))
        trials = [
            other.sizes[TRIAL_DIM]
            for other in cubes.values()
            if TRIAL_DIM in other.dims
            and "on_front" not in other
            and other.attrs.get("space") == space
        ]
        values = cube["objective_value"].transpose(TRIAL_DIM, "objective").values
        rows = tuple(
            (int(trial), bool(on), tuple(float(v) for v in row))
            for trial, on, row in zip(
                cube[TRIAL_DIM].values, cube["on_front"].values, values, strict=True
            )
        )
        objectives = tuple(str(o) for o in cube["objective"].values)
        found.append(SearchFront(space, trials[0] if len(trials) == 1 else None, objectives, rows))
    return tuple(found)
