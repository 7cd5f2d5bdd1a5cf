"""The sampler of a search and what it is told: Optuna's samplers, ordered choices, the auto
rule, start-up trials.

What the sampler sees (:class:`Proposer`):

* **Ordered choices.** A dimension whose ``choices`` are all numbers (``[0.02, 0.03, 0.045]``)
  is told to the sampler as the position of its value among them in increasing order, an
  integer dimension ``0 .. n - 1``: the Gaussian process's kernel and TPE's Parzen estimators
  then know that 0.03 lies between 0.02 and 0.045 and that its neighbours resemble it, where a
  categorical dimension (what Optuna makes of ``choices``) holds them unrelated. Choices of
  strings or booleans stay categorical. The journal and the cubes keep the values themselves.
* **Transformed objectives.** Each objective's values go through its declared monotone
  transform (:attr:`pipeline.design.space.Objective.transform`; ``log10(1 + rate)`` for a data
  rate) before they are told; a value the transform does not define makes the trial failed to
  the sampler, as a NaN does.

The samplers (:func:`make_sampler`): a Gaussian process (``GPSampler``: Matern 5/2 kernel with a
length scale per dimension, log expected hypervolume improvement for two or three objectives,
the running trials taken at its predicted values, Optuna's kriging believer; told that the
objectives are deterministic, as a design's are: its scene seeds every draw and the store
computes it once, so a design told again costs nothing and teaches nothing, and a GP with a
noise term kept proposing its best corner again until the search ended on repeats),
multi-objective TPE (multivariate, with a constant liar for the running trials), NSGA-II and
random search. Both model-based samplers start with :func:`startup_trials` trials spread over
the space (:class:`SpaceFillingStart`).

The auto rule (:func:`resolve_sampler`): GP when the search is expected to be short and the
space is mostly ordered; TPE otherwise.

* A Gaussian process needs few trials to learn which dimensions matter and how smoothly the
  objectives vary along each. Replayed on the benchmark's spaces (``benchmarks/search.py``,
  the performance page), it found at least as much of the exhaustive front as TPE and random
  search at 5 and 10 % of the grid's paid seconds (at 10 %: 0.950 against 0.926 and 0.812 of
  the hypervolume on 3 dimensions; 0.960 against 0.929 and 0.921 on 5), while TPE was
  slightly ahead at 25 % on 3 dimensions (0.988 against 0.984; 46-60 trials). Its ask costs
  up to seconds (0.2-1 s on average over searches of up to 160 trials on a shared 2-core
  machine; TPE's milliseconds) and grows with the cube of the trials told
  (its fit factorises their covariance); :data:`GP_MAX_TRIALS` is a judgment, not a
  measurement, of where that and TPE's lead on long searches outweigh the GP's start.
* Unordered choices are where a kernel over positions helps least (Optuna's GP measures them
  only as equal or different); a space whose dimensions are mostly categorical goes to TPE.

So: ``gp`` when the budget is at most :data:`GP_MAX_TRIALS` trials (a budget in seconds counts
as small: its trials are the costly kind) and at most half of the dimensions are unordered
categorical; ``tpe`` otherwise.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.design.space import Dimension, DimensionKind, Objective, Sampler, Space

#: The most trials a search may be budgeted for and still get ``gp`` from ``auto``.
GP_MAX_TRIALS = 300


def is_ordered(dimension: Dimension) -> bool:
    """True for a range, or for choices that are all numbers (not booleans): values with an
    order the sampler is told."""
    if dimension.kind is not DimensionKind.CATEGORICAL:
        return True
    return all(isinstance(c, int | float) and not isinstance(c, bool) for c in dimension.choices)


def ordered_choices(dimension: Dimension) -> tuple[Any, ...]:
    """The choices of an ordered categorical dimension in increasing order."""
    return tuple(sorted(dimension.choices))


def resolve_sampler(space: Space, budget: int | None = None) -> Sampler:
    """The sampler a search of ``space`` uses: the space's, or for ``auto`` GP or TPE by the
    rule of the module docstring. ``budget``: the trials the search may tell in all (None: a
    budget in seconds)."""
    if space.sampler is not Sampler.AUTO:
        return space.sampler
    unordered = sum(not is_ordered(d) for d in space.dimensions)
    small = budget is None or budget <= GP_MAX_TRIALS
    return Sampler.GP if small and 2 * unordered <= len(space.dimensions) else Sampler.TPE


def startup_trials(n_dimensions: int, budget: int | None = None) -> int:
    """Start-up trials (:class:`SpaceFillingStart`) before a model-based sampler proposes:
    ``n_dimensions + 1`` (as few points as span the space, one length scale per dimension to
    fit), at most a quarter of a budget in trials, at least 2."""
    wanted = n_dimensions + 1
    if budget is not None:
        wanted = min(wanted, budget // 4)
    return max(2, wanted)


def make_sampler(kind: Sampler, seed: int, n_dimensions: int, budget: int | None = None) -> Any:
    """The Optuna sampler of ``kind`` (not ``auto``: :func:`resolve_sampler` first), seeded."""
    import optuna

    startup = startup_trials(n_dimensions, budget)
    match kind:
        case Sampler.GP:
            import torch

            # The coordinator fits the GP while the workers compute: one thread, as a worker
            # has (two threads on a busy 2-core machine made each ask several times slower).
            torch.set_num_threads(1)
            # Optuna marks the argument experimental; the warning would reach the user each search.
            warnings.filterwarnings(
                "ignore",
                "Argument ``deterministic_objective``",
                optuna.exceptions.ExperimentalWarning,
            )
            return optuna.samplers.GPSampler(
                seed=seed,
                n_startup_trials=startup,
                deterministic_objective=True,
                warn_independent_sampling=False,
            )
        case Sampler.TPE:
            return optuna.samplers.TPESampler(
                multivariate=True,
                constant_liar=True,
                n_startup_trials=startup,
                seed=seed,
            )
        case Sampler.NSGA2:
            return optuna.samplers.NSGAIISampler(seed=seed)
        case Sampler.RANDOM:
            return optuna.samplers.RandomSampler(seed=seed)
    raise ValueError(f"no Optuna sampler for {kind!r}")


def distributions(space: Space) -> dict[str, Any]:
    """Optuna's distribution of each dimension as the sampler sees it, by field: ordered
    choices as positions (:func:`is_ordered`)."""
    from optuna.distributions import (
        CategoricalDistribution,
        FloatDistribution,
        IntDistribution,
    )

    found: dict[str, Any] = {}
    for d in space.dimensions:
        if d.kind is DimensionKind.CATEGORICAL:
            if is_ordered(d):
                found[d.field] = IntDistribution(0, len(d.choices) - 1)
            else:
                found[d.field] = CategoricalDistribution(d.choices)
        elif d.kind is DimensionKind.INT:
            found[d.field] = IntDistribution(int(d.low), int(d.high), step=int(d.step), log=d.log)
        else:
            found[d.field] = FloatDistribution(d.low, d.high, step=d.step, log=d.log)
    return found


@dataclass(frozen=True)
class Encoding:
    """Trial values to and from what the sampler sees (:func:`distributions`)."""

    dimensions: tuple[Dimension, ...]

    def encode(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """Scene values -> the sampler's (an ordered choice -> its position)."""
        out = dict(params)
        for d in self.dimensions:
            if d.kind is DimensionKind.CATEGORICAL and is_ordered(d):
                out[d.field] = _position(ordered_choices(d), params[d.field])
        return out

    def decode(self, params: Mapping[str, Any]) -> dict[str, Any]:
        """The sampler's values -> scene values, in the dimensions' order."""
        out = {}
        for d in self.dimensions:
            value = params[d.field]
            if d.kind is DimensionKind.CATEGORICAL and is_ordered(d):
                value = ordered_choices(d)[int(value)]
            out[d.field] = value
        return out


def _position(choices: Sequence[Any], value: Any) -> int:
    for i, choice in enumerate(choices):
        if choice == value and type(choice) is type(value):
            return i
    for i, choice in enumerate(choices):  # 1 and 1.0, as a journal's JSON may give them
        if choice == value:
            return i
    raise ValueError(f"{value!r} is not one of the choices {list(choices)}")


def told_values(objectives: Sequence[Objective], values: Sequence[float]) -> list[float] | None:
    """The values the sampler is told for a trial's objective ``values``, each through its
    objective's transform; None when one is not finite (the trial is failed to the sampler)."""
    told = [float(o.transform.apply(v)) for o, v in zip(objectives, values, strict=True)]
    return told if all(math.isfinite(v) for v in told) else None


class SpaceFillingStart:
    """The start-up trials of a model-based sampler: a scrambled Sobol' sequence over the
    space as the sampler sees it (:func:`distributions`), point after point.

    Independent random start-up trials clump and leave gaps: with six trials over five
    dimensions, a dimension of three ordered values is left untried at one of them once in six
    searches, and pairs of dimensions much more often. The first ``2**k`` points of a Sobol'
    sequence put one point in each of ``2**k`` equal slices of every dimension (and of many
    pairs), and any prefix of it is nearly as even, so the start spans the space whatever
    the number of start-up trials; its scrambling (seeded) keeps searches of different seeds
    apart. A unit coordinate ``u`` becomes the value in the ``floor(u * n)``-th of a
    dimension's ``n`` values (choices, positions, integers or float steps), or
    ``low + u * (high - low)`` for a continuous float (in logarithms for a log range).
    """

    #: How many points are drawn at once, a power of two (a Sobol' sequence's balanced size)
    #: and more than any start-up needs; the next as many are drawn if ever needed.
    BLOCK = 64

    def __init__(self, distributions: Mapping[str, Any], seed: int):
        from scipy.stats import qmc

        self.distributions = dict(distributions)
        self.sequence = qmc.Sobol(len(self.distributions), scramble=True, seed=seed)
        self.points: list[np.ndarray] = []

    def next(self) -> dict[str, Any]:
        """The next start-up point, as the sampler's values by field."""
        if not self.points:
            self.points = list(self.sequence.random(self.BLOCK))
        unit = self.points.pop(0)
        return {
            name: unit_value(d, float(u))
            for (name, d), u in zip(self.distributions.items(), unit, strict=True)
        }


def unit_value(distribution: Any, u: float) -> Any:
    """The value of an Optuna ``distribution`` at unit coordinate ``u`` in [0, 1)
    (:class:`SpaceFillingStart`)."""
    from optuna.distributions import CategoricalDistribution, IntDistribution

    def nth(n: int) -> int:
        return min(int(u * n), n - 1)

    if isinstance(distribution, CategoricalDistribution):
        return distribution.choices[nth(len(distribution.choices))]
    low, high, step = distribution.low, distribution.high, distribution.step
    if distribution.log:
        value = math.exp(math.log(low) + u * (math.log(high) - math.log(low)))
        if isinstance(distribution, IntDistribution):
            return min(max(round(value), low), high)
        return min(max(value, low), high)
    if isinstance(distribution, IntDistribution):
        return low + step * nth((high - low) // step + 1)
    if step is not None:
        return min(low + step * nth(round((high - low) / step) + 1), high)
    return low + u * (high - low)


class Proposer:
    """An in-memory Optuna study of a space: asks trials as scene values and is told raw
    objective values (:class:`Encoding`, :func:`told_values`).

    ``kind`` is the sampler (``auto`` resolved with ``budget``, :func:`resolve_sampler`),
    ``seed`` seeds it. Trials asked and not yet told stay running in the study: TPE's constant
    liar and the GP's pending points keep new trials away from them.
    """

    def __init__(self, space: Space, seed: int, budget: int | None = None):
        import optuna

        optuna.logging.set_verbosity(optuna.logging.WARNING)
        self.space = space
        self.kind = resolve_sampler(space, budget)
        self.encoding = Encoding(space.dimensions)
        self.distributions = distributions(space)
        self.study = optuna.create_study(
            directions=[o.direction.verb for o in space.objectives],
            sampler=make_sampler(self.kind, seed, len(space.dimensions), budget),
        )
        self.startup = startup_trials(len(space.dimensions), budget)
        modelled = self.kind in (Sampler.GP, Sampler.TPE)
        self.start = SpaceFillingStart(self.distributions, seed) if modelled else None

    def add(self, params: Mapping[str, Any], values: Sequence[float] | None) -> None:
        """Replay a trial told before: finished with ``values`` (raw), or failed (None)."""
        import optuna

        told = None if values is None else told_values(self.space.objectives, values)
        self.study.add_trial(
            optuna.trial.create_trial(
                params=self.encoding.encode(params),
                distributions=self.distributions,
                values=told,
                state=optuna.trial.TrialState.COMPLETE if told else optuna.trial.TrialState.FAIL,
            )
        )

    def enqueue(self, params: Mapping[str, Any]) -> None:
        """Have the next ask give ``params`` (a killed search's trial, asked again)."""
        self.study.enqueue_trial(self.encoding.encode(params), skip_if_exists=False)

    def ask(self) -> tuple[Any, dict[str, Any]]:
        """A new trial: Optuna's trial (to tell) and its scene values. While a model-based
        sampler has too few trials told to model, the trial is the next point of the
        space-filling start (:class:`SpaceFillingStart`)."""
        import optuna

        if self.start is not None and not self.study.get_trials(
            deepcopy=False, states=(optuna.trial.TrialState.WAITING,)
        ):
            told = self.study.get_trials(deepcopy=False, states=(optuna.trial.TrialState.COMPLETE,))
            if len(told) < self.startup:
                self.study.enqueue_trial(self.start.next(), skip_if_exists=False)
        trial = self.study.ask(self.distributions)
        return trial, self.encoding.decode(trial.params)

    def tell(self, trial: Any, values: Sequence[float] | None) -> None:
        """Tell ``trial`` its raw objective ``values``, or that it failed (None)."""
        import optuna

        told = None if values is None else told_values(self.space.objectives, values)
        if told is None:
            self.study.tell(trial, state=optuna.trial.TrialState.FAIL)
        else:
            self.study.tell(trial, told)


def seed_for(space_seed: int, asked_before: int) -> int:
    """The sampler's seed: from the space's seed and the trials already asked, so that a
    resumed search samples afresh rather than repeating its first run's start-up trials."""
    return int(np.random.SeedSequence([space_seed, asked_before]).generate_state(1)[0])
