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
    distributions,
    resolve_sampler,
    startup_trials,
)
from pipeline.design.space import TRANSFORMS, Metric, Sampler, Space
from pipeline.design.transforms import Transform


def space(sampler: str = "auto", **dimensions) -> Space:
    return Space.from_dict(
        {
            "name": "s",
            "base": "smoke",
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
