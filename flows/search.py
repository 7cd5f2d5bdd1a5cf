"""A search of a design space (``eskin optimize``): Optuna asks, the sweep machinery evaluates.

The coordinator (this process) drives an in-memory Optuna study by ask-and-tell; no Optuna
storage is used, so workers never touch the study and its format never ties a run root to an
Optuna version. The run root keeps the search instead: its journal
(:class:`storage.search_log.SearchJournal`) records every trial asked and told, and a search
started again on the root replays it, told trials back into the sampler, asked ones never
told (a killed search's) asked again with their own values, and any point of a told trial the
store lost (a corrupt batch discarded) computed again. A larger budget continues it.

Trials are refilled as workers free (:func:`flows.refill.refill`): as many run at once as the
cluster has worker threads, and the moment one finishes it is told and a new one asked, the
running ones pending in the sampler. Each trial is a grid of one point
(:meth:`pipeline.design.space.Space.trial_grid`), planned and scheduled as any sweep
(:func:`flows.planning.plan_sweep`, :func:`flows.scheduling.submit_missing`) from a thread of
the coordinator that waits for it: the same store, cache keys and workers; a point already in
the store, from any sweep or search, costs nothing. A trial's missing spike train is a task of
its own, keyed by the train (``train_tasks`` of :func:`flows.scheduling.submit_missing`): a
trial that shares it with a running one (another window, other training) waits for that task
instead of computing the train again. Once its point is done, the trial cube of
every trial so far is built in memory (:func:`pipeline.results.cube.build_cube`, along
``trial``; each result read from the store once) and the trial's objective values are read
from it and told. The search's cubes ``<space>.trials`` and ``<space>.front``
(:func:`pipeline.report.trials.front_cube`; named by :func:`storage.search_log.search_cube_name`,
so a root keeps every search made in it) are written when the search ends or is stopped.

Sampler: the space's (:class:`pipeline.design.space.Sampler`; :mod:`flows.samplers` makes it and
says what it is told): by default ``auto``, a Gaussian process for a search of at most a few
hundred trials over mostly ordered dimensions and multi-objective TPE otherwise
(:func:`flows.samplers.resolve_sampler`), seeded from the space's seed and the trials already
asked. A search goes on with the sampler it began with: one begun before ``auto`` was the
default keeps ``tpe`` (:func:`resumed_space`). Numeric choices are told as ordered positions and
objectives through their declared monotone transforms. Cost accounting: a budget in seconds
(``budget_s``) is spent in the seconds the workers paid computing each distinct point, once
(:func:`pipeline.report.trials.search_seconds`): a spike train, a load or a worker's set-up that
trials share was paid by one of them and counts once, so a trial that shares the spike train of
an earlier one costs only its coding and training. A new trial is started while the seconds of
the trials told, plus those the running ones are expected to cost (the mean of the trials told
so far, beyond their workers' one-off load and set-up), stay below the budget; once one is
refused, none is started again.
"""

from __future__ import annotations

import concurrent.futures
import contextlib
import contextvars
import dataclasses
import sys
import threading
import time
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import xarray as xr

from flows.cluster import dask_client
from flows.environment import hermetic_environment
from flows.planning import DEFAULT_RUNS_DIR, SweepPlan, check_grid, plan_sweep
from flows.progress import SweepFailed, completed_points, failure_message
from flows.refill import refill
from flows.samplers import Proposer, seed_for
from flows.scheduling import submit_missing
from pipeline.design.space import TRIALS, Sampler, Space, load_space
from pipeline.errors import EskinError
from pipeline.report.trials import front_cube, search_seconds, trial_cube
from pipeline.results.objectives import objective_values
from pipeline.results.variables import MODEL_DIM, RESULT_KEY
from pipeline.run.grid_keys import keyed_points, unique_points
from pipeline.run.stages import RESULTS, SPIKES
from storage import StoreError, SweepStore
from storage.objects import is_object_url, run_root
from storage.search_log import (
    SearchJournal,
    journal_fingerprint,
    journal_path,
    search_cube_name,
)

#: Trials of a search without a budget.
DEFAULT_BUDGET = 50
#: Trials in a row at designs already told after which a search ends (its sampler has nothing
#: new to propose, and such trials cost no seconds, so a budget in seconds would never be spent).
MAX_REPEATS_IN_ROW = 10
FRONT = "front"
#: The sampler of a space that names none before the default became ``auto``
#: (:func:`resumed_space`).
FORMER_DEFAULT_SAMPLER = Sampler.TPE


class BudgetError(EskinError):
    """A budget that is not a positive number."""


@dataclass
class TrialsOutcome:
    """What trials told together did: their numbers, distinct points found in the store
    (``cache_hits``) and computed, and failures by trial."""

    trials: list[int]
    cache_hits: int = 0
    computed: int = 0
    failed: dict[int, str] = field(default_factory=dict)


class Search:
    """One search of ``space`` in the store at ``root``: its study, journal and trials.

    Open it holding the root's lock (:meth:`storage.store.SweepStore.lock`). ``fingerprint``:
    the one its journal holds (:func:`resumed_space`), by default the space's.
    """

    def __init__(
        self,
        space: Space,
        root: str | Path,
        budget: int | None = None,
        fingerprint: str | None = None,
    ):
        self.space = space
        self.root = str(root)
        self.journal = SearchJournal.open(root, space.name, fingerprint or space.fingerprint())
        # ``budget`` (trials in all; None for seconds) picks ``auto``'s sampler and the start-up;
        # a search begun by ``auto`` keeps the sampler it began with, whatever budget extends it.
        sampler = self.journal.sampler if space.sampler is Sampler.AUTO else None
        chosen = space if sampler is None else dataclasses.replace(space, sampler=Sampler(sampler))
        self.proposer = Proposer(chosen, seed_for(space.seed, len(self.journal.params)), budget)
        for number in sorted(self.journal.params):
            params = self.journal.params[number]
            if number in self.journal.values:
                self.proposer.add(params, self.journal.values[number])
            elif number in self.journal.failed:
                self.proposer.add(params, None)
            else:
                self.proposer.enqueue(params)
        self._asked: dict[int, Any] = {}
        # The results of the trials' points as read from the store, each once.
        self.records: dict[str, Any] = {}
        self.cube: xr.Dataset | None = None  # see restore()

    @property
    def told(self) -> int:
        """Trials told (finished or failed)."""
        return len(self.journal.values) + len(self.journal.failed)

    def ask(self, n: int) -> list[int]:
        """The next ``n`` trials: a killed search's untold ones first, then new ones."""
        numbers = []
        pending = [p for p in self.journal.pending if p not in self._asked]
        for _ in range(n):
            trial, params = self.proposer.ask()
            if pending:
                number = pending.pop(0)
            else:
                number = max(self.journal.params, default=-1) + 1
                self.journal.asked(number, params, self.proposer.kind.value)
            self._asked[number] = trial
            numbers.append(number)
        return numbers

    def compute(
        self, numbers: Sequence[int], client_for: Callable[[], Any]
    ) -> tuple[SweepPlan, dict[str, str]]:
        """Plan the trials' points and compute those not in the store (``client_for()`` gives
        the Dask client, called only then); the plan, and why points failed by key."""
        params = [self.journal.params[n] for n in numbers]
        # Other trials' points may be being written: their partial batches are not leftovers.
        plan = plan_sweep(self.space.trial_grid(params), self.root, tidy=False)
        if not plan.missing:
            return plan, {}
        client = client_for()
        # A train that another running trial is computing is waited for, not computed again.
        futures = submit_missing(plan, client, train_tasks=True)
        return plan, {k: why for k, why in completed_points(client, futures) if why}

    def restore(self, client_for: Callable[[], Any]) -> int:
        """Build the cube of the trials told before (:attr:`cube`), computing again any of
        their points the store lost (a batch found corrupt and discarded); returns how many."""
        told = sorted(self.journal.values)
        computed = len(self.compute(told, client_for)[0].missing) if told else 0
        self.cube = self.build_cube()
        return computed

    def evaluate(self, numbers: list[int], client_for: Callable[[], Any]) -> TrialsOutcome:
        """Compute the trials' points (those not in the store) and tell the trials
        (:meth:`compute`, :meth:`tell`). ``client_for()`` gives the Dask client, called only if
        a point is missing."""
        return self.tell(numbers, *self.compute(numbers, client_for))

    def tell(
        self, numbers: list[int], plan: SweepPlan, failed_keys: Mapping[str, str]
    ) -> TrialsOutcome:
        """Tell the trials ``numbers``, whose points ``plan`` computed (:meth:`compute`; those
        in ``failed_keys`` failed), from the cube of every trial so far."""
        outcome = TrialsOutcome(numbers)
        outcome.cache_hits, outcome.computed = len(plan.cached), len(plan.missing)
        keys = [point.key for point in keyed_points(plan.grid)]
        for number, key in zip(numbers, keys, strict=True):
            if key in failed_keys:
                outcome.failed[number] = failed_keys[key]
                self.proposer.tell(self._asked.pop(number), None)
                self.journal.told_failed(number, failed_keys[key])
        done = [n for n in numbers if n not in outcome.failed]
        if not done:
            return outcome
        self.cube = self.build_cube(done)
        found = objective_values(self.cube.sel(trial=done), self.space.objectives)
        for number, row in zip(done, found, strict=True):
            values = [float(v) for v in row]
            self.proposer.tell(self._asked.pop(number), values)
            self.journal.told(number, values)
        return outcome

    def mean_trial_seconds(self) -> float:
        """The seconds a told trial cost on average beyond the one-off load and set-up of its
        worker (0 before any): what a running trial is expected to cost. The one-off seconds
        are left out because a running trial pays them only as its worker's first, and the
        first trials of a search are its workers' first: counted in, they made a short search
        expect every trial to cost a worker's start and stop with most of its budget unspent
        (a search of 5 % of a grid's seconds stopped after 3 trials and 4 % spent in the
        search benchmark)."""
        told = len(self.journal.values)
        return self.seconds_spent(shared=False) / told if told else 0.0

    def build_cube(self, finished: Sequence[int] = ()) -> xr.Dataset | None:
        """The cube of every told trial and of the ``finished`` ones (whose points are in the
        store), in memory; None before any trial."""
        numbers = sorted({*self.journal.values, *finished})
        if not numbers:
            return None
        params = [self.journal.params[n] for n in numbers]
        return trials_cube(self.space, self.root, params, numbers, self.records)

    def write_cubes(self) -> None:
        """Write the trial cube (:attr:`cube`) and its front into the store."""
        if self.cube is None:
            return
        store = SweepStore.open(self.root)
        store.write_cube(self.cube_name(TRIALS), self.cube)
        store.write_cube(self.cube_name(FRONT), front_cube(self.cube, self.space.objectives))

    def cube_name(self, kind: str) -> str:
        """The name of this search's cube ``kind`` (``trials`` or ``front``) in its root."""
        return search_cube_name(self.space.name, kind)

    def seconds_spent(self, *, shared: bool = True) -> float:
        """Stage seconds of the finished trials (:func:`spent_seconds`; ``shared=False``: their
        own charge alone)."""
        if self.cube is None:
            return 0.0
        params = [self.journal.params[int(n)] for n in self.cube["trial"].values]
        return spent_seconds(self.space, params, self.cube, shared=shared)

    def front_rows(self) -> list[dict[str, Any]]:
        """The front's trials: number, searched values, objective values, on the front or only
        indistinguishable from it."""
        if self.cube is None:
            return []
        front = front_cube(self.cube, self.space.objectives)
        rows = []
        for i, number in enumerate(int(n) for n in front["trial"].values):
            values = front["objective_value"].isel(trial=i).values
            rows.append(
                {
                    "trial": number,
                    "params": self.journal.params[number],
                    "objectives": {
                        o.name: float(v) for o, v in zip(self.space.objectives, values, strict=True)
                    },
                    "on_front": bool(front["on_front"].values[i]),
                }
            )
        return rows


def trials_cube(
    space: Space,
    root: str | Path,
    params: Sequence[Mapping[str, Any]],
    numbers: Sequence[int],
    records: dict[str, Any] | None = None,
) -> xr.Dataset:
    """The cube of trials ``numbers`` at ``params`` along ``trial``
    (:func:`pipeline.report.trials.trial_cube`), from the results of their points in the store
    at ``root``. ``records`` (result entries by key) is a cache: those it lacks are read and
    added to it.

    Raises
    ------
    StoreError
        A trial's point has no result in the store.
    """
    from pipeline.results.cube import build_cube

    grid = space.trial_grid(params)
    records = {} if records is None else records
    wanted = [key for key in unique_points(grid) if key not in records]
    if wanted:
        records |= SweepStore.open(root).read_many(RESULTS.record, wanted, discard_corrupt=False)
    missing = [key for key in wanted if key not in records]
    if missing:
        raise StoreError(f"{len(missing)} trial point(s) have no result in {root}: {missing[0]}")
    return trial_cube(build_cube(grid, grid.sweeps[0], records), numbers, grid.name)


def spent_seconds(
    space: Space, params: Sequence[Mapping[str, Any]], cube: xr.Dataset, *, shared: bool = True
) -> float:
    """The stage seconds paid for trials at ``params`` whose cube is ``cube``, each point once
    (:func:`pipeline.report.trials.search_seconds`, with its ``shared``)."""
    spike_keys = [SPIKES.key(p.scene) for p in space.trial_grid(params).points()]
    models = [str(m) for m in cube[MODEL_DIM].values]
    return search_seconds(cube, spike_keys, SPIKES.steps_for(models), shared=shared)


def resumed_space(space: Space, root: str | Path) -> tuple[Space, str, str | None]:
    """The search of ``space`` that ``root`` holds: the space it goes on with (``space``, or
    ``space`` with the sampler its journal was begun with), the fingerprint its journal holds
    (the space's if it has none yet) and a note for the user when the sampler differs.

    The rule: a search is one study, so its journal is replayed only into the space it was
    begun in, sampler included (:meth:`pipeline.design.space.Space.fingerprint`): another
    sampler would propose the remaining trials from another model, and a budget extended in
    steps would no longer ask the trials one larger budget asks. But a space that names no
    sampler, or names ``auto`` (which leaves the choice to the tool: the same space), had
    ``tpe`` (``FORMER_DEFAULT_SAMPLER``) before the default became ``auto``, and the searches
    of such spaces were journalled under its fingerprint with ``tpe``. Such a space whose
    journal holds that fingerprint is that search: it goes on with the sampler it began with
    (one note says so) rather than being refused, or switched to another sampler mid-way.
    Journals written before fingerprints took the base's canonical form hold it with every
    field of the base (``every_field``): they are the same search, and go on under the
    fingerprint they hold. A space that names another sampler, or differs in anything else, is
    another search: it is left as it is, and the journal refuses it
    (:meth:`storage.search_log.SearchJournal.open`).
    """
    found = journal_fingerprint(root, space.name)
    samplers = [space.sampler]
    if space.sampler is Sampler.AUTO:
        samplers.append(FORMER_DEFAULT_SAMPLER)
    for sampler in samplers if found is not None else ():
        for every_field in (False, True):
            if found != space.fingerprint(sampler, every_field=every_field):
                continue
            if sampler is space.sampler:
                return space, found, None
            note = (
                f"eskin: note: {journal_path(root, space.name)} was begun with sampler "
                f"{sampler.value!r}, the default before 'auto': the search goes on with "
                f"{sampler.value!r} (name a sampler in the space file and give another --root "
                "to start a new search)"
            )
            return dataclasses.replace(space, sampler=sampler), found, note
    return space, space.fingerprint(), None


def check_journal(space: Space, root: str | Path) -> None:
    """Refuse, before any work, a root whose journal of ``space``'s name holds another search
    (:func:`resumed_space`); the search checks it again, holding the root's lock.

    Raises
    ------
    StoreError
        As :meth:`storage.search_log.SearchJournal.open`.
    """
    SearchJournal.open(root, space.name, resumed_space(space, root)[1])


def default_search_root(space: Space) -> Path:
    """``runs/<space name>``: the run root of a search given no ``--root``."""
    return DEFAULT_RUNS_DIR / space.name


def check_search_root(root: str | Path) -> Path:
    """``root`` as a search's run root, a folder.

    Raises
    ------
    StoreError
        ``root`` is an object root (``s3://...``): the search's journal is appended to in
        place, which an object cannot be.
    """
    if is_object_url(root):
        raise StoreError(
            f"root {run_root(root)}: a search needs a folder root (its journal is appended to "
            "in place, which an object root cannot do); sweep to s3:// roots, search in a folder"
        )
    return Path(root)


def check_space(space: Space) -> None:
    """Check the space's extremes against its recordings (:func:`flows.planning.check_grid` of
    its corners: every bound and choice of each field, with the others at theirs), before any
    work; raise :class:`pipeline.errors.SceneError` listing every misfit."""
    check_grid(space.exhaustive_grid(2))


def check_budget(budget: int | None, budget_s: float | None) -> tuple[int | None, float | None]:
    """``(budget, budget_s)`` checked: at most one given, positive; default
    :data:`DEFAULT_BUDGET` trials."""
    if budget is not None and budget_s is not None:
        raise BudgetError("give a budget in trials or in seconds, not both")
    if budget is not None and (
        isinstance(budget, bool) or not isinstance(budget, int) or budget < 1
    ):
        raise BudgetError(f"--budget: expected a positive number of trials, got {budget!r}")
    if budget_s is not None and not (isinstance(budget_s, int | float) and budget_s > 0):
        raise BudgetError(f"--budget-s: expected a positive number of seconds, got {budget_s!r}")
    if budget is None and budget_s is None:
        budget = DEFAULT_BUDGET
    return budget, budget_s


@contextlib.contextmanager
def lazy_client(
    root: str | Path, client: Any = None, workers: int | None = None, address: str | None = None
) -> Iterator[Callable[[], Any]]:
    """A function giving the Dask client: ``client``, or a local cluster (or ``address``) made
    on the first call and closed at the end; no cluster starts for a search with nothing to
    compute."""
    with contextlib.ExitStack() as stack:
        made: list[Any] = [client] if client is not None else []
        making = threading.Lock()  # the threads of running trials ask for it at once

        def get() -> Any:
            with making:
                if not made:
                    hermetic_environment(Path(root), prefect=False)
                    made.append(stack.enter_context(dask_client(workers, address)))
            return made[0]

        yield get


def trial_slots(client: Any, workers: int | None) -> int:
    """Trials running at once: the cluster's worker threads (the local cluster's
    ``workers``)."""
    if client is not None:
        return max(1, sum(client.nthreads().values()))
    from flows.cluster import available_cores

    return workers or available_cores()


def committed_seconds(spent_s: float, mean_trial_s: float, running: int) -> float:
    """The seconds a search weighs against its budget in seconds: those spent plus those its
    ``running`` trials are expected to cost, ``mean_trial_s`` each."""
    return spent_s + running * mean_trial_s


def wants_trial(search: Search, budget: int | None, budget_s: float | None, running: int) -> bool:
    """Whether a search with ``running`` trials under way starts another: fewer than
    ``budget`` trials told and running, or the seconds spent (:meth:`Search.seconds_spent`)
    plus those the running trials are expected to cost (:meth:`Search.mean_trial_seconds`
    each, :func:`committed_seconds`) below ``budget_s``."""
    if budget is not None:
        return search.told + running < budget
    spent_s, mean_trial_s = search.seconds_spent(), search.mean_trial_seconds()
    return committed_seconds(spent_s, mean_trial_s, running) < budget_s


@dataclass
class StopRule:
    """When a search stops asking for trials: its budget is spent (``within_budget()`` is
    false, asked only while nothing else stops it), ``slots`` trials in a row failed (the next
    would too, spending nothing) or :data:`MAX_REPEATS_IN_ROW` trials in a row were of designs
    told before. Once it refuses it never asks again: the trials still running finish and the
    search ends, even if they cost less than expected, so that a search with a smaller budget
    asks exactly the trials a larger one asks up to that point.
    """

    slots: int
    failures_in_row: int = 0
    repeats_in_row: int = 0
    stopped: bool = False

    def asks(self, within_budget: Callable[[], bool]) -> bool:
        """Whether the search asks one more trial now."""
        if not self.stopped:
            self.stopped = (
                self.failures_in_row >= self.slots
                or self.repeats_in_row >= MAX_REPEATS_IN_ROW
                or not within_budget()
            )
        return not self.stopped

    def told(self, *, repeat: bool, failed: bool) -> None:
        """Count a trial told: of a design told before (``repeat``), failed or not."""
        self.repeats_in_row = self.repeats_in_row + 1 if repeat else 0
        self.failures_in_row = self.failures_in_row + 1 if failed else 0


def run_optimize(
    space: str | Path | Space,
    root: str | Path | None = None,
    *,
    budget: int | None = None,
    budget_s: float | None = None,
    client: Any = None,
    workers: int | None = None,
    address: str | None = None,
    on_told: Callable[[Search, TrialsOutcome], None] | None = None,
    compute: Callable[[Search, list[int], Callable[[], Any]], tuple[SweepPlan, dict[str, str]]]
    | None = None,
    on_note: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Search ``space`` (a file or a :class:`~pipeline.design.space.Space`) into the store at
    ``root``, without Prefect.

    Holds the root's lock, replays the root's journal of this space (with the sampler it was
    begun with, :func:`resumed_space`), asks trials
    until ``budget`` trials (default :data:`DEFAULT_BUDGET`) or ``budget_s`` stage seconds
    are spent, keeping one trial running per worker thread (:func:`flows.refill.refill`), and
    returns :func:`search_summary`. ``client`` (left open), or a local cluster of ``workers``
    processes, or the scheduler at ``address``, made only if a point is missing.
    ``on_told`` is called after each trial is told (with its outcome); ``compute`` replaces
    :meth:`Search.compute` (the Prefect flow runs it as a task), called from a thread per
    running trial. ``on_note`` is given each note for the user (one line); by default they are
    printed on stderr.

    Raises
    ------
    EskinError
        A bad space, budget or root, before anything is written.
    SweepFailed
        Some trials' points failed (the others are told and kept).
    """
    start = time.perf_counter()
    budget, budget_s = check_budget(budget, budget_s)
    if not isinstance(space, Space):
        space = load_space(space)
    check_space(space)
    store = SweepStore.open_or_create(check_search_root(root or default_search_root(space)))
    cache_hits = computed = 0
    failed: dict[int, str] = {}
    with store.lock():
        store.clean_partials()
        space, fingerprint, note = resumed_space(space, store.root)
        if note is not None:
            (on_note or _print_note)(note)
        search = Search(space, store.root, budget, fingerprint)
        told_before = len(search.journal.values)
        # The cubes are written at the end, or when the search is stopped; the journal, written
        # as trials are told, is what a killed search resumes from.
        try:
            with lazy_client(store.root, client, workers, address) as client_for:
                slots = trial_slots(client_for() if address else client, workers)
                computed += search.restore(client_for)
                counts = _run_trials(search, budget, budget_s, slots, client_for, on_told, compute)
                cache_hits, computed, failed = counts[0], computed + counts[1], counts[2]
        finally:
            search.write_cubes()
    if failed:
        raise SweepFailed(failure_message(list(failed.values()), len(failed), store.root))
    return search_summary(
        search,
        new_trials=len(search.journal.values) - told_before,
        cache_hits=cache_hits,
        computed=computed,
        seconds=time.perf_counter() - start,
    )


def _print_note(note: str) -> None:
    print(note, file=sys.stderr)


def _run_trials(
    search: Search,
    budget: int | None,
    budget_s: float | None,
    slots: int,
    client_for: Callable[[], Any],
    on_told: Callable[[Search, TrialsOutcome], None] | None,
    compute: Callable[[Search, list[int], Callable[[], Any]], tuple[SweepPlan, dict[str, str]]]
    | None,
) -> tuple[int, int, dict[int, str]]:
    """Ask, compute and tell trials, ``slots`` running at once, until the :class:`StopRule`
    refuses (the budget spent, :func:`wants_trial`; failures or repeats in a row);
    (cache hits, points computed, failures by trial)."""
    compute = compute or Search.compute
    pool = concurrent.futures.ThreadPoolExecutor(slots, thread_name_prefix="eskin-trial")
    seen: set[str] = set()
    told = set() if search.cube is None else {str(k) for k in search.cube[RESULT_KEY].values}
    cache_hits = computed = 0
    failed: dict[int, str] = {}
    rule = StopRule(slots)

    def ask(running: int) -> int | None:
        if not rule.asks(lambda: wants_trial(search, budget, budget_s, running)):
            return None
        return search.ask(1)[0]

    def start(number: int) -> concurrent.futures.Future:
        # The copied context carries the Prefect flow run to a task the hook calls.
        run = contextvars.copy_context().run
        return pool.submit(run, compute, search, [number], client_for)

    def finish(number: int, future: concurrent.futures.Future) -> None:
        nonlocal cache_hits, computed
        plan, failed_keys = future.result()
        keys = {point.key for point in keyed_points(plan.grid)}
        repeat = keys <= told
        told.update(keys)
        outcome = search.tell([number], plan, failed_keys)
        # Two trials of one design, running together, computed their point once (Dask holds
        # one task per key): it counts once.
        outcome.computed = len(set(plan.missing) - seen)
        seen.update(plan.missing)
        outcome.cache_hits = len(plan.cached)
        cache_hits += outcome.cache_hits
        computed += outcome.computed
        failed.update(outcome.failed)
        rule.told(repeat=repeat, failed=bool(outcome.failed))
        if on_told is not None:
            on_told(search, outcome)

    try:
        refill(slots, ask, start, finish)
    finally:
        # Stopped (an error, an interrupt): running trials are not waited for; their points
        # are stored as they finish and a resumed search finds them.
        pool.shutdown(wait=False, cancel_futures=True)
    return cache_hits, computed, failed


def search_summary(
    search: Search, new_trials: int, cache_hits: int, computed: int, seconds: float
) -> dict[str, Any]:
    """What ``eskin optimize --json`` prints: ``root``, ``space``, ``trials`` (finished, all
    runs), ``sampler`` (the one that asked this run's trials, ``auto`` resolved),
    ``new_trials``, ``cache_hits`` and ``computed`` (distinct points of this run's
    trials), ``seconds`` (wall), ``search_seconds`` (stage seconds of every finished trial,
    :meth:`Search.seconds_spent`), ``cubes`` (where the search's ``trials`` and ``front`` cubes
    are) and ``front`` (:meth:`Search.front_rows`)."""
    return {
        "root": search.root,
        "space": search.space.name,
        "trials": len(search.journal.values),
        "sampler": search.proposer.kind.value,
        "new_trials": new_trials,
        "cache_hits": cache_hits,
        "computed": computed,
        "seconds": seconds,
        "search_seconds": search.seconds_spent(),
        "cubes": {
            kind: SweepStore(search.root).cube_location(search.cube_name(kind))
            for kind in (TRIALS, FRONT)
        },
        "front": search.front_rows(),
    }
