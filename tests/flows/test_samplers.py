"""What a search's sampler is: the auto rule, ordered choices, transformed objectives, start-up
trials (:mod:`flows.samplers`)."""

import dataclasses

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from flows.samplers import (
    GP_MAX_TRIALS,
    Encoding,
    Proposer,
    SpaceFillingStart,
    distributions,
    resolve_sampler,
    startup_trials,
    unit_value,
)
from pipeline.design.scene import Scene
from pipeline.design.space import TRANSFORMS, Metric, Sampler, Space
from pipeline.design.transforms import Transform

#: The smoke scene with a decaying encoder's floor below every threshold the spaces try: a space
#: is checked at every combination of its choices, and 0.03 V (the default) is above 0.02 V.
BASE = Scene.load("smoke").replace(**{"readout.decay.theta_min_v": 0.01}).to_dict()


def space(sampler: str = "auto", **dimensions) -> Space:
    return Space.from_dict(
        {
            "name": "s",
            "base": BASE,
            "sampler": sampler,
            "space": dimensions
            or {
                "readout.threshold_v": {"choices": [0.09, 0.02, 0.045]},
                "coding.window_s": {"low": 0.05, "high": 0.2},
                "readout.encoder": {"choices": ["lcs", "decaying"]},
            },
            "objectives": {"accuracy.ffnn": "max", "data_rate_bps": "min"},
        }
    )


def test_auto_takes_gp_for_a_short_search_of_mostly_ordered_dimensions():
    ordered = space()  # one unordered dimension of three
    assert resolve_sampler(ordered, budget=None) is Sampler.GP  # a budget in seconds
    assert resolve_sampler(ordered, budget=GP_MAX_TRIALS) is Sampler.GP
    assert resolve_sampler(ordered, budget=GP_MAX_TRIALS + 1) is Sampler.TPE
    categorical = space(
        **{
            "readout.encoder": {"choices": ["lcs", "decaying"]},
            "coding.polarity": {"choices": ["merged", "split"]},
            "array.rows": {"low": 1, "high": 2},
        }
    )
    assert resolve_sampler(categorical, budget=20) is Sampler.TPE
    for kind in (Sampler.TPE, Sampler.GP, Sampler.NSGA2, Sampler.RANDOM):
        assert resolve_sampler(dataclasses.replace(ordered, sampler=kind), 10_000) is kind
    assert (
        Space.from_dict({**_plain(), "sampler": "auto"}).sampler
        is Space.from_dict(_plain()).sampler
    )  # auto is the default


def _plain() -> dict:
    return {
        "name": "s",
        "base": "smoke",
        "space": {"array.rows": {"low": 1, "high": 2}},
        "objectives": {"accuracy.ffnn": "max", "data_rate_bps": "min"},
    }


def test_startup_trials_follow_the_budget():
    assert startup_trials(3) == 4
    assert startup_trials(5, budget=100) == 6
    assert startup_trials(5, budget=12) == 3  # a quarter of the budget
    assert startup_trials(5, budget=3) == 2


def test_numeric_choices_are_ordered_positions_and_strings_stay_categorical():
    from optuna.distributions import CategoricalDistribution, IntDistribution

    s = space()
    found = distributions(s)
    assert found["readout.threshold_v"] == IntDistribution(0, 2)
    assert isinstance(found["readout.encoder"], CategoricalDistribution)
    encoding = Encoding(s.dimensions)
    params = {"readout.threshold_v": 0.045, "coding.window_s": 0.1, "readout.encoder": "lcs"}
    seen = encoding.encode(params)
    assert seen["readout.threshold_v"] == 1  # 0.02 < 0.045 < 0.09, whatever the file's order
    assert encoding.decode(seen) == params
    assert encoding.decode({**seen, "readout.threshold_v": 2})["readout.threshold_v"] == 0.09


def test_every_metric_declares_a_transform_the_sampler_is_told_through():
    assert set(TRANSFORMS) == set(Metric)
    proposer = Proposer(space("tpe"), seed=0)
    trial, params = proposer.ask()
    proposer.tell(trial, [0.5, 99.0])
    assert proposer.study.trials[0].values == pytest.approx([0.5, 2.0])  # log10(1 + 99)
    proposer.add(params, [0.5, -5.0])  # a value the transform does not define: failed
    assert proposer.study.trials[1].state.name == "FAIL"


@settings(max_examples=60, deadline=None)
@given(
    st.sampled_from(sorted(set(TRANSFORMS.values()), key=str)),
    st.lists(st.floats(0, 1e12, allow_nan=False), min_size=2, max_size=20),
)
def test_transforms_are_strictly_increasing(transform: Transform, values: list[float]):
    x = np.unique(np.asarray(values))
    y = transform.apply(x)
    assert np.isfinite(y).all()
    assert (np.diff(y) >= 0).all()
    # Strictly increasing wherever float64 can tell the values apart after the floor is added.
    apart = np.diff(x) > 1e-9 * (x[:-1] + (transform.floor or 0.0))
    assert (np.diff(y)[apart] > 0).all()


def _distributions() -> list:
    from optuna.distributions import (
        CategoricalDistribution,
        FloatDistribution,
        IntDistribution,
    )

    return [
        CategoricalDistribution(["lcs", "decaying"]),
        IntDistribution(0, 2),
        IntDistribution(1, 8),
        IntDistribution(2, 64, log=True),
        IntDistribution(1, 9, step=4),
        FloatDistribution(0.0, 0.3, step=0.1),
        FloatDistribution(0.01, 0.5, log=True),
        FloatDistribution(0.05, 0.2),
    ]


@settings(max_examples=300, deadline=None)
@given(st.sampled_from(_distributions()), st.floats(0.0, 1.0, exclude_max=True))
def test_a_unit_coordinate_becomes_a_value_the_sampler_may_ask(distribution, u: float):
    value = unit_value(distribution, u)
    assert distribution._contains(distribution.to_internal_repr(value))


def test_the_start_puts_equal_shares_of_trials_in_equal_slices_of_every_dimension():
    s = space(
        **{
            "readout.encoder": {"choices": ["lcs", "decaying"]},
            "array.rows": {"low": 1, "high": 4},
            "readout.threshold_v": {"choices": [0.02, 0.03, 0.045, 0.065, 0.09, 0.13, 0.19, 0.28]},
        }
    )
    for seed in range(5):
        start = SpaceFillingStart(distributions(s), seed)
        points = [start.next() for _ in range(8)]
        # A scrambled Sobol' sequence's first 2**3 points: one in each eighth of every axis.
        assert sorted(p["readout.threshold_v"] for p in points) == list(range(8))
        assert sorted(p["array.rows"] for p in points) == [1, 1, 2, 2, 3, 3, 4, 4]
        assert sorted(p["readout.encoder"] for p in points) == ["decaying"] * 4 + ["lcs"] * 4
    firsts = {
        SpaceFillingStart(distributions(s), seed).next()["readout.threshold_v"] for seed in range(5)
    }
    assert len(firsts) > 1  # seeded scrambles differ


def test_a_model_based_sampler_asks_the_start_until_enough_trials_are_told():
    s = space("gp")
    proposer = Proposer(s, seed=3)
    expected = SpaceFillingStart(distributions(s), 3)
    for i in range(proposer.startup):
        trial, params = proposer.ask()
        assert proposer.encoding.encode(params) == expected.next()
        proposer.tell(trial, [0.1 * i, 10.0 + i])
    # Resumed with enough told trials, the sampler models from the first ask.
    resumed = Proposer(s, seed=4)
    for t in proposer.study.trials:
        resumed.add(proposer.encoding.decode(t.params), [0.5, 20.0])
    resumed.ask()
    assert resumed.start.points == []  # no start-up point was drawn
    assert Proposer(space("random"), seed=0).start is None
