"""Orchestration: which work runs where and when, with Prefect and Dask; no science of its own.

The package is thin: it holds Prefect flows and tasks, the Dask work they submit, the cluster
and the local Prefect server, and the ``eskin`` command line, and it wires :mod:`pipeline`
(the science) to :mod:`storage` (every byte): it decides where a computation runs, the store
whether its output is already there.

It exports nothing itself. :mod:`flows.api` gathers every call ``eskin`` makes, for notebooks
and scripts, without Prefect; :mod:`flows.cli` is the command line; the Prefect flows are
:func:`flows.sweep.sweep` and :func:`flows.optimize.optimize`, and what they run on the Dask
workers is in :mod:`flows.work`.
"""
