"""The ``optimize`` Prefect flow: a design-space search with one task per batch of trials.

The flow runs :func:`flows.search.run_optimize` and makes it visible: each batch of trials is a
task (``trials-<first>-<last>``) that submits the batch's missing points to Dask, waits for them
and tells the trials; after each batch the current front is a table artifact
(``<space>-front``), the trials told so far a progress artifact against the budget, and a
run-logger line says what the batch computed and found cached. Prefect runs only in this
process; the Dask workers run the plain functions of :mod:`flows.work`, as in a sweep.
"""

from __future__ import annotations

import math
import sys
from typing import Any

from prefect import flow, get_run_logger, task
from prefect.artifacts import (
    create_progress_artifact,
    create_table_artifact,
    update_progress_artifact,
)
from prefect.cache_policies import NO_CACHE

from flows.search import BatchOutcome, Search, check_budget, run_optimize
from flows.sweep import artifact_key, flow_run_url
from pipeline.design.space import Space


@task(name="trials", cache_policy=NO_CACHE, task_run_name="trials-{first}-{last}")
def batch_task(search: Search, numbers: list[int], client_for: Any, first: int, last: int) -> Any:
    """Evaluate one batch of trials (:meth:`flows.search.Search.evaluate`)."""
    return search.evaluate(numbers, client_for)


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
    progress: dict[str, Any] = {}

    def evaluate(search: Search, numbers: list[int], client_for: Any) -> BatchOutcome:
        from prefect.utilities.annotations import quote

        run = batch_task.submit(quote(search), numbers, quote(client_for), numbers[0], numbers[-1])
        return run.result()

    def on_batch(search: Search, outcome: BatchOutcome) -> None:
        name = search.space.name
        done = search.told / budget if budget else min(1.0, search.seconds_spent() / budget_s)
        if "artifact" not in progress:
            progress["artifact"] = create_progress_artifact(
                progress=100 * done,
                key=artifact_key(name, "progress"),
                description=f"Budget of search {name!r} spent (trials or stage seconds).",
            )
        else:
            update_progress_artifact(artifact_id=progress["artifact"], progress=100 * done)
        rows = [
            {
                "trial": row["trial"],
                "on_front": row["on_front"],
                **{k: _rounded(v) for k, v in row["objectives"].items()},
                **{k: _rounded(v) for k, v in row["params"].items()},
            }
            for row in search.front_rows()
        ]
        create_table_artifact(
            key=artifact_key(name, "front"),
            table=rows,
            description=f"The current front of search {name!r} after {search.told} trials "
            "(on_front false: off the front, but a paired test cannot tell it from it).",
        )
        logger.info(
            "trials %d-%d: %d points computed, %d found in the store, %d failed; %d told, "
            "front of %d",
            outcome.trials[0],
            outcome.trials[-1],
            outcome.computed,
            outcome.cache_hits,
            len(outcome.failed),
            search.told,
            sum(r["on_front"] for r in rows),
        )

    summary = run_optimize(
        space,
        root,
        budget=budget,
        budget_s=budget_s,
        workers=workers,
        address=address,
        on_batch=on_batch,
        evaluate=evaluate,
    )
    summary["flow_run_url"] = url
    if report:
        from flows.sweep import report_task

        summary["report"] = report_task(summary["root"])
    return summary


def _rounded(value: Any) -> Any:
    return round(value, 6) if isinstance(value, float) and math.isfinite(value) else value
