"""``flows.api.run_optimize`` on a Dask client: budgets in stage seconds, one batch per worker
thread, no cluster for a search with nothing to compute."""

import pytest

from flows.api import Space, run_optimize
from tests.flows.test_optimize import SPACE

pytestmark = pytest.mark.slow


def test_a_budget_in_seconds_is_spent_batch_by_batch(client, tmp_path):
    import tomllib

    space = Space.from_dict(tomllib.loads(SPACE))
    root = tmp_path / "run"
    # Any point costs more than a microsecond: one batch of one trial (one worker thread).
    first = run_optimize(space, root, budget_s=1e-6, client=client)
    assert (first["trials"], first["computed"]) == (1, 1)
    assert first["search_seconds"] > 1e-6
    # Continued to a microsecond more than it spent: one more batch of one trial, which spends
    # the budget, and no batch after it.
    budget = first["search_seconds"] + 1e-6
    second = run_optimize(space, root, budget_s=budget, client=client)
    assert (second["trials"], second["new_trials"]) == (2, 1)
    assert second["search_seconds"] >= budget
    # Spent already: no trial, no cluster needed.
    third = run_optimize(space, root, budget_s=budget, workers=1)
    assert (third["new_trials"], third["computed"], third["cache_hits"]) == (0, 0, 0)
    assert third["front"] == second["front"]


def test_a_point_the_store_lost_is_computed_again(client, tmp_path):
    import tomllib

    from flows.planning import plan_sweep
    from storage import SweepStore, open_results
    from storage.search_log import SearchJournal

    space = Space.from_dict(tomllib.loads(SPACE))
    root = tmp_path / "run"
    run_optimize(space, root, budget=2, client=client)
    trials = open_results(root)["tiny.trials"]
    store = SweepStore.open(root)
    lost = str(trials["result_key"].values[0])
    assert store.discard("results", lost)  # as a batch found corrupt is discarded
    # The trial cube is written without a source: planning never takes it as current, so a
    # batch always finds which of its points are missing.
    journal = SearchJournal.open(root, space.name, space.fingerprint())
    plan = plan_sweep(space.trial_grid([journal.params[n] for n in (0, 1)]), root)
    assert plan.current == {} and plan.missing == [lost]
    again = run_optimize(space, root, budget=2, client=client)
    assert (again["trials"], again["new_trials"], again["computed"]) == (2, 0, 1)
    assert lost in store.complete_keys("results")
    assert (
        open_results(root)["tiny.trials"]["result_key"].values.tolist()
        == trials["result_key"].values.tolist()
    )


def test_decision_time_is_an_objective_of_decoders_trained_for_it(client, tmp_path):
    import tomllib

    import numpy as np

    from pipeline.results.objectives import objective_values
    from storage import open_results

    data = tomllib.loads(SPACE)
    data["objectives"] = {"accuracy.ffnn": "max", "decision_s.ffnn": "min"}
    space = Space.from_dict(data)
    root = tmp_path / "run"
    summary = run_optimize(space, root, budget=2, client=client)
    assert (summary["trials"], summary["computed"]) == (2, 2)
    trials = open_results(root)["tiny.trials"]
    assert set(np.ravel(trials["training.decisions"].values)) == {"along_touch"}
    decision_s = objective_values(trials, space.objectives)[:, 1]
    # Each trial's mean early-exit time: within its touch of 1.5 s, after its first window.
    assert np.all((decision_s >= 0.1) & (decision_s <= 1.5)), decision_s
