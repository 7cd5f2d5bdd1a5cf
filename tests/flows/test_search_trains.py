"""Trials of a search that run at once and share a spike train (the same threshold and array,
another window) compute it once, and it is paid once."""

import concurrent.futures
import threading
import tomllib

import pytest

import flows.search as search_module
from flows.api import Space
from flows.scheduling import submit_missing
from flows.search import Search, spent_seconds, trials_cube
from pipeline.run import encoding as encoding_module
from pipeline.run import stages
from pipeline.run.records import Charge
from storage import SweepStore
from tests.flows.helpers import in_process_client
from tests.flows.test_optimize import SPACE

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def two_threads():
    """A Dask client on an in-process cluster of one worker with two threads: two trials run
    at once."""
    with in_process_client(threads=2) as client:
        yield client


def test_two_running_trials_that_share_a_train_compute_it_once(two_threads, tmp_path, monkeypatch):
    space = Space.from_dict(tomllib.loads(SPACE))
    root = SweepStore.open_or_create(tmp_path / "run").root
    search = Search(space, root)
    params = [
        {"readout.threshold_v": 0.05, "coding.window_s": window_s, "array.rows": 1}
        for window_s in (0.1, 0.2)
    ]
    for number, values in enumerate(params):
        search.journal.asked(number, values)
    # The trains are encoded (in-process workers: counted here) only once both trials were
    # submitted, so that the two are under way together whatever the machine's load.
    submitted: list[object] = []
    both = threading.Event()
    encoded: list[int] = []

    def submitting(plan, client, *args, **kwargs):
        futures = submit_missing(plan, client, *args, **kwargs)
        submitted.append(plan)
        if len(submitted) == 2:
            both.set()
        return futures

    def encoding(*args, **kwargs):
        encoded.append(1)
        both.wait(120)
        return stages_encode_trains(*args, **kwargs)

    stages_encode_trains = encoding_module.encode_trains
    monkeypatch.setattr(search_module, "submit_missing", submitting)
    monkeypatch.setattr(encoding_module, "encode_trains", encoding)
    with concurrent.futures.ThreadPoolExecutor(2) as pool:
        computed = list(pool.map(lambda n: search.compute([n], lambda: two_threads), (0, 1)))

    assert len(submitted) == 2 and [failed for _, failed in computed] == [{}, {}]
    assert len(encoded) == 1, "the shared spike train was computed by both trials"
    keys = [plan.missing[0] for plan, _ in computed]
    assert len(set(keys)) == 2
    entries = SweepStore.open(root).read_many(stages.RESULTS.record, keys, discard_corrupt=False)
    # One trial paid the train, the other only its coding and training; the search counts the
    # train once.
    payers = [key for key in keys if "readout" in entries[key].paid[Charge.OWN]]
    assert len(payers) == 1
    # Training is always a point's own; its rate matrices may come from the memory of the
    # in-process worker, which an earlier test's trial at the same design left there.
    assert all(entries[key].paid[Charge.OWN]["train_ffnn"] > 0 for key in keys)
    paid = sum(v for key in keys for steps in entries[key].paid.values() for v in steps.values())
    cube = trials_cube(space, root, params, [0, 1])
    assert spent_seconds(space, params, cube) == pytest.approx(paid, rel=1e-9)


def test_a_trial_whose_train_fails_is_failed_with_the_reason(two_threads, tmp_path, monkeypatch):
    space = Space.from_dict(tomllib.loads(SPACE))
    root = SweepStore.open_or_create(tmp_path / "run").root
    search = Search(space, root)
    search.journal.asked(0, {"readout.threshold_v": 0.07, "coding.window_s": 0.1, "array.rows": 1})

    def failing(*args, **kwargs):
        raise MemoryError("no room for the trains")

    monkeypatch.setattr(encoding_module, "encode_trains", failing)
    plan, failed = search.compute([0], lambda: two_threads)
    assert list(failed) == plan.missing and len(failed) == 1
    assert "MemoryError: no room for the trains" in failed[plan.missing[0]]
