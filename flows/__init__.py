"""Orchestration: where the science of :mod:`pipeline` runs and when :mod:`storage` is asked.

The package is thin: it holds Prefect flows and tasks, the Dask work they submit, the cluster
and the local Prefect server, and the ``eskin`` command line, and it wires :mod:`pipeline`
(the science) to :mod:`storage` (every byte) without computing anything of its own.

It exports nothing itself. :mod:`flows.api` gathers every call ``eskin`` makes, for notebooks
and scripts, without Prefect; :mod:`flows.cli` is the command line; the Prefect flows are
:func:`flows.sweep.sweep` and :func:`flows.optimize.optimize`, and what they run on the Dask
workers is in :mod:`flows.work`.
"""
