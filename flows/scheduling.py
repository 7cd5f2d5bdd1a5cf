"""Scheduling a plan's missing points on Dask: the cost model, batches of points, their tasks.

Points are ordered by their estimated cost (:func:`pipeline.design.grid_cost.training_cost`),
largest first, batched into tasks of :func:`flows.work.ensure_entries` (:func:`submit_missing`), and
each point goes with its cache keys, computed here once, so that workers never hash a scene.
No cluster starts for a plan with nothing missing (:func:`sweep_client`).
"""

from __future__ import annotations

import collections
import contextlib
import hashlib
import math
from collections.abc import Iterator
from typing import Any

from flows.cluster import dask_client
from flows.environment import hermetic_environment
from flows.planning import SweepPlan
from pipeline.design.grid_cost import training_cost
from pipeline.design.scene import CanonicalMemo, Scene
from pipeline.run import stages
from pipeline.run.stages import RESULTS, SPIKES, Level
from storage import SweepStore

#: Tasks per worker thread a sweep's missing points are split into (see
#: :func:`default_points_per_task`).
TASKS_PER_THREAD = 8
#: The most points one task takes.
MAX_POINTS_PER_TASK = 500


def point_keys(scene: Scene, memo: CanonicalMemo | None = None) -> dict[str, str]:
    """The cache key of every level of the registry (:data:`pipeline.run.stages.LEVELS`, as it is at
    the call) for ``scene``, by level name.

    ``memo`` as for :meth:`pipeline.design.scene.Scene.canonical`: the points of a grid share scene
    parts, each written once for all their keys.
    """
    return {level.name: level.key(scene, memo) for level in stages.LEVELS}


@contextlib.contextmanager
def sweep_client(
    plan: SweepPlan,
    client: Any = None,
    workers: int | None = None,
    address: str | None = None,
) -> Iterator[Any]:
    """The Dask client that takes the plan's missing points, or None when none is missing.

    ``client``, when given, is used as it is and left open. Otherwise a fresh one is made
    (:func:`flows.cluster.dask_client` with ``workers`` or ``address``) and closed at the end.
    """
    if not plan.missing:
        yield None
    elif client is not None:
        yield client
    else:
        hermetic_environment(plan.root, prefect=False)
        with dask_client(workers, address) as fresh:
            yield fresh


def submit_missing(
    plan: SweepPlan,
    client: Any,
    points_per_task: int | None = None,
    *,
    train_tasks: bool = False,
) -> dict[str, Any]:
    """Submit every missing point in batches; return each point's future by result key.

    Points are ordered largest first (so that no long point starts last while the other workers
    idle), points that share a spike train are kept together, and consecutive points are
    batched into one task each (:func:`flows.work.ensure_entries`), every point with its cache
    keys (:func:`point_keys`): a task costs the scheduler and the store the same whatever its
    size, so cheap points are sent many at a time. Points of one task share its future. A
    spike train that points of several tasks share is computed first by a task of its own
    (before those tasks start); one already in the store is not computed at all. Task keys name
    the root as well as the work: Dask hands a task whose key it still holds the earlier
    result, so a sweep of another root on the same cluster would otherwise skip writing its
    entries.

    Parameters
    ----------
    points_per_task
        Points per task; default :func:`default_points_per_task` of the missing points and the
        cluster's worker threads.
    train_tasks
        Give every missing spike train a task of its own, keyed by that train and the root, not
        only the trains that several of this plan's tasks share. For plans submitted while
        others run on the same cluster (a search's trials, each a plan of one point): two that
        share a train under way submit one key, and Dask, holding one task per key, computes
        the train once, for the point that submitted it first (which is charged for it).
    """
    from flows import work

    store = SweepStore.open(plan.root)
    root = hashlib.sha256(store.identity().encode()).hexdigest()[:12]
    cost = {key: training_cost(plan.scenes[key]) for key in plan.missing}
    size = points_per_task or default_points_per_task(len(cost), sum(client.nthreads().values()))
    memo: CanonicalMemo = {}  # the points share scene parts: each is written once
    keys = {key: point_keys(plan.scenes[key], memo) for key in cost}
    by_train: dict[str, list[str]] = {}
    for key in sorted(cost, key=cost.__getitem__, reverse=True):
        by_train.setdefault(keys[key][SPIKES.name], []).append(key)
    batches = _batches(by_train, size)
    stored = store.complete_keys(SPIKES.name)
    spread = collections.Counter(train for batch in batches for train in {t for t, _ in batch})
    shared = [
        train for train, n in spread.items() if (n > 1 or train_tasks) and train not in stored
    ]
    # A train of its own task is keyed by it alone, so that other plans find it.
    trains_per_task = 1 if train_tasks else size

    def submit(level: Level, points: list[str], name: str, priority: int, *after: Any) -> Any:
        # One task of ensure_entries, keyed by the work it does and the root.
        return client.submit(
            work.ensure_entries,
            plan.root,
            level.name,
            [(plan.scenes[key], keys[key]) for key in points],
            *after,
            key=f"{name}-{root}",
            pure=False,
            priority=priority,
        )

    train_futures: dict[str, Any] = {}
    for start in range(0, len(shared), trains_per_task):
        trains = shared[start : start + trains_per_task]
        firsts = [by_train[t][0] for t in trains]
        name = f"spikes-{_digest_keys(trains)}"
        future = submit(SPIKES, firsts, name, max(cost.values()) + 1)
        train_futures.update(dict.fromkeys(trains, future))
    futures: dict[str, Any] = {}
    for batch in batches:
        points = [key for _, batch_keys in batch for key in batch_keys]
        after = list({id(f): f for t, _ in batch if (f := train_futures.get(t))}.values())
        priority = max(cost[key] for key in points)
        future = submit(RESULTS, points, f"points-{_digest_keys(points)}", priority, *after)
        futures.update(dict.fromkeys(points, future))
    return futures


def default_points_per_task(n_points: int, n_threads: int) -> int:
    """Points per task: about 8 tasks per worker thread, 1 to :data:`MAX_POINTS_PER_TASK`.

    Eight tasks per thread keep the workers evenly busy to the end when points differ in
    cost; a sweep of few, expensive points gets one point per task.
    """
    per_task = math.ceil(n_points / (TASKS_PER_THREAD * max(1, n_threads)))
    return max(1, min(MAX_POINTS_PER_TASK, per_task))


def _batches(by_train: dict[str, list[str]], size: int) -> list[list[tuple[str, list[str]]]]:
    """Points in batches of at most ``size``: (spike key, result keys) pairs, in order.

    The points of one train stay in one batch where they fit, so that the batch computes the
    train itself; a train with more points than ``size`` is spread over several batches.
    """
    batches: list[list[tuple[str, list[str]]]] = []
    current: list[tuple[str, list[str]]] = []
    room = size
    for train, keys in by_train.items():
        if len(keys) > room and current and len(keys) <= size:
            batches.append(current)
            current, room = [], size
        while keys:
            taken, keys = keys[:room], keys[room:]
            current.append((train, taken))
            room -= len(taken)
            if room == 0:
                batches.append(current)
                current, room = [], size
    if current:
        batches.append(current)
    return batches


def _digest_keys(keys: list[str]) -> str:
    return hashlib.sha256("".join(keys).encode()).hexdigest()[:32]
