"""The ``optimize`` Prefect flow: a design-space search with one task per trial.

The flow runs :func:`flows.search.run_optimize` and makes it visible: each trial is a task
(``trial-<number>``, as many running at once as the cluster has worker threads) that submits
the trial's point to Dask if it is missing and waits for it; after each trial is told the
current front is a table artifact (``<space>-front``), the budget spent a progress artifact,
and a run-logger line says what the trial computed or found cached. Prefect runs only in this
process; the Dask workers run the plain functions of :mod:`flows.work`, as in a sweep. As a
sweep's, the search's artifacts and log lines go through the run's record
(:mod:`flows.record`): a Prefect server that stops answering does not stop the search.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.cache_policies import NO_CACHE

from flows.planning import SweepPlan
from flows.record import PrefectRecord, run_recorded
from flows.search import Search, TrialsOutcome, check_budget, default_search_root, run_optimize
from flows.sweep import artifact_key, flow_run_url
from pipeline.design.space import Space


@task(name="trial", cache_policy=NO_CACHE, task_run_name="trial-{number}")
def trial_task(search: Search, numbers: list[int], client_for: Any, number: int) -> Any:
    """Compute one trial's point if it is missing (:meth:`flows.search.Search.compute`)."""
    return search.compute(numbers, client_for)


@flow(name="optimize", log_prints=False)
def optimize(
    space: str | Space = "examples/design_space.toml",
    root: str | None = None,
    budget: int | None = None,
    budget_s: float | None = None,
    workers: int | None = None,
    address: str | None = None,
    report: bool = False,
    show_progress: bool = False,
) -> dict[str, Any]:
    """Search ``space`` (a space file or a checked :class:`~pipeline.design.space.Space`) into
    cubes under ``root``.

    As :func:`flows.search.run_optimize`, with ``budget`` trials or ``budget_s`` stage seconds;
    ``report`` writes the report under ``<root>/report`` at the end.
    """
    logger = get_run_logger()
    budget, budget_s = check_budget(budget, budget_s)
    url = flow_run_url()
    if show_progress and url:
        print(f"Prefect flow run: {url}", file=sys.stderr)

    def compute(
        search: Search, numbers: list[int], client_for: Any
    ) -> tuple[SweepPlan, dict[str, str]]:
        from prefect.utilities.annotations import quote

        return trial_task(quote(search), numbers, quote(client_for), numbers[0])

    def on_told(record: PrefectRecord, search: Search, outcome: TrialsOutcome) -> None:
        name = search.space.name
        done = search.told / budget if budget else min(1.0, search.seconds_spent() / budget_s)
        record.progress(
            artifact_key(name, "progress"),
            100 * done,
            f"Budget of search {name!r} spent (trials or stage seconds).",
        )
        rows = [
            {
                "trial": row["trial"],
                "on_front": row["on_front"],
                **{k: _rounded(v) for k, v in row["objectives"].items()},
                **{k: _rounded(v) for k, v in row["params"].items()},
            }
            for row in search.front_rows()
        ]
        record.table(
            artifact_key(name, "front"),
            rows,
            f"The current front of search {name!r} after {search.told} trials "
            "(on_front false: off the front, but a paired test cannot tell it from it).",
        )
        logger.info(
            "trial %d: %d point computed, %d found in the store, %d failed; %d told, front of %d",
            outcome.trials[0],
            outcome.computed,
            outcome.cache_hits,
            len(outcome.failed),
            search.told,
            sum(r["on_front"] for r in rows),
        )

    def on_note(note: str) -> None:
        # On the command line's stderr; a deployment's run has only its logger.
        if show_progress:
            print(note, file=sys.stderr)
        else:
            logger.info(note)

    def body(record: PrefectRecord) -> dict[str, Any]:
        summary = run_optimize(
            space,
            root,
            budget=budget,
            budget_s=budget_s,
            workers=workers,
            address=address,
            on_told=lambda search, outcome: on_told(record, search, outcome),
            compute=compute,
            on_note=on_note,
        )
        summary["flow_run_url"] = url
        if report:
            from flows.sweep import report_task

            summary["report"] = report_task(summary["root"])
        return summary

    shown = (
        root
        if root is not None
        else default_search_root(space)
        if isinstance(space, Space)
        else None
    )
    return run_recorded(body, what="search", root=str(shown or "its default root"))


def _rounded(value: Any) -> Any:
    return round(value, 6) if isinstance(value, float) and math.isfinite(value) else value
