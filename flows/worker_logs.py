"""What the local cluster's workers do not log.

Closing a local cluster closes its scheduler, in the sweep's process, while a worker's heartbeat
may be on its way; the worker then logs the closed connection with a traceback, which would end
a sweep that stopped with one clear line (a full disk, an interrupt). A local worker outlives
its scheduler only at that close (the scheduler lives as long as the sweep), so the record tells
the user nothing. Workers of an existing scheduler do not get this plugin: there a lost
scheduler is news.
"""

from __future__ import annotations

import logging

from distributed.diagnostics.plugin import WorkerPlugin


def heartbeat_to_a_closed_scheduler(record: logging.LogRecord) -> bool:
    """False for a worker's report that a heartbeat found its scheduler's connection closed."""
    return not str(record.msg).startswith("Failed to communicate with scheduler during heartbeat")


class QuietHeartbeatAtClose(WorkerPlugin):
    """Drops :func:`heartbeat_to_a_closed_scheduler` records in each worker it is set up on."""

    name = "eskin-quiet-heartbeat"

    def setup(self, worker: object) -> None:
        logging.getLogger("distributed.worker").addFilter(heartbeat_to_a_closed_scheduler)
