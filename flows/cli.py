"""The ``eskin`` command line: it parses arguments, calls plain functions and prints.

The entry point :func:`main` (``eskin = "flows.cli:main"``, and ``python -m flows.cli``); the
parser is :mod:`flows.cli_parser`, each command's body :mod:`flows.cli_commands`, what they print
:mod:`flows.cli_output`.

``eskin run`` simulates one scene; ``eskin sweep`` runs the Prefect flow ``sweep`` on Dask;
``eskin optimize`` runs the flow ``optimize``, a search of a design space on the same machinery;
``eskin server`` starts, shows or stops the local Prefect server sweeps use; ``eskin serve``
serves the flow as a deployment; ``eskin report`` writes a run root's report; ``eskin power``
prints both readouts' power and data rate for an array and an event rate, without a sweep.

Exit status: 0 on success, 2 for bad input or usage (one line ``eskin: error: ...`` on stderr
naming what and where), 1 for a run that failed on good input (a point that failed more often
than Dask allows, a Prefect server that could not start) or a refused ``server stop``, 130 when
interrupted (Ctrl-C, SIGTERM).

A sweep or a search whose Prefect server stopped answering (stopped, killed, restarted) goes
on and ends as it would have: its results are complete, and if the server did not answer again
before the end it adds one line ``eskin: note: the Prefect record of this run is incomplete
(...)`` on stderr (``"prefect_record": "incomplete"`` with ``--json``). Its exit status is
still 0: the store, not Prefect, holds the results, and a script that goes on to the report
must not take complete results for a failure.

An interrupted run (Ctrl-C, SIGTERM) unwinds within seconds, stops what it started and exits
with status 130 (:mod:`flows.interrupts`).

JSON numbers that are infinite (an SSNR of a REAL train equal to its TRUE train) are written as the
strings ``"inf"`` and ``"-inf"`` (:mod:`flows.cli_output`): JSON has no infinity, and
``float("inf")`` reads them back.
"""

from __future__ import annotations

import argparse
import sys

from flows import interrupts
from flows.cli_parser import build_parser
from pipeline.errors import EskinError

__all__ = ["main"]


def main(argv: list[str] | None = None) -> int:
    """The ``eskin`` command: parse ``argv`` (default: ``sys.argv[1:]``) with
    :func:`build_parser`, run the command's handler and return its exit status (see the module
    docstring). An :class:`pipeline.errors.EskinError` prints one line ``eskin: error: ...`` on
    stderr and returns the error's exit status; an interrupt returns 130.
    """
    interrupts.as_program(argv is None)
    if interrupts.is_program():
        from flows.environment import skip_exit_collection

        skip_exit_collection()
    args = build_parser().parse_args(argv)
    status = _handled(args)
    if interrupts.is_program():
        interrupts.exit_after(interrupts.EXIT_GRACE_S, status)
    return status


def _handled(args: argparse.Namespace) -> int:
    """The handler's exit status; errors and interrupts as the module docstring says."""
    try:
        return args.handler(args)
    except EskinError as exc:
        if not interrupts.signalled.is_set():
            print(f"eskin: error: {exc}", file=sys.stderr)
            return exc.exit_status
    except Exception:
        if not interrupts.signalled.is_set():
            raise
    except (SystemExit, GeneratorExit):
        raise
    except BaseException:  # KeyboardInterrupt; Prefect's TerminationSignal for a SIGTERM
        pass
    # Interrupted: a SIGTERM that Prefect's handler saw may come out as another exception.
    if not interrupts.is_program():
        print("eskin: interrupted", file=sys.stderr)
        return interrupts.EXIT_INTERRUPTED
    # What it started is stopped, the store holds what was written, the record is closed:
    # nothing is left to wait for at exit (Prefect's flushes to a server that may be gone took
    # seconds there, past the deadline's reach once the interpreter finalizes). The line comes
    # after the stop, so that it is the last thing the command says.
    interrupts.stop_started_processes(grace_s=1.0)
    print("eskin: interrupted", file=sys.stderr)
    interrupts.exit_now(interrupts.EXIT_INTERRUPTED, quiet=True)


if __name__ == "__main__":
    sys.exit(main())
