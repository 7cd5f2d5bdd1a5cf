"""The stopwatch a level's compute function times its steps on, and the one-off setup step.

Seconds come in two kinds. *Work* seconds (:attr:`Stopwatch.seconds`) are what each step's work
took, whichever point it was done for: a step's wall seconds less the one-off time within it
(importing a library, loading or compiling kernels: :func:`pipeline.jit.one_off_seconds`).
*Paid* seconds (:meth:`Stopwatch.paid`) are the same time by
:class:`~pipeline.run.records.Charge`: each step's work under the charge the stage registry
declares for it (:func:`pipeline.run.stages.step_charge`) and every one-off second under
``shared`` / :data:`SETUP_STEP`, so that they sum to the wall time of the steps
(:meth:`Stopwatch.paid_total`).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager

from pipeline import jit
from pipeline.run.records import Charge, Paid

__all__ = ["SETUP_STEP", "Stopwatch"]

#: A worker process's one-off work, charged ``shared`` to the point that paid it:
#: importing numba, torch and scikit-learn (and scipy's filters, for the synthetic recordings),
#: and loading (or, the first time, compiling) the numba kernels: the spikes level's warm-up
#: (:func:`pipeline.run.encoding.warm_kernels`), and every such second inside any other step
#: (:func:`pipeline.jit.one_off_seconds`).
SETUP_STEP = "setup"


class Stopwatch:
    """Accumulates wall seconds per step and reports each step the first time it starts.

    Attributes
    ----------
    seconds : dict[str, float]
        Each step's work (wall seconds less the one-off time within it), by step name.
    one_off_s : float
        The one-off seconds within every step timed (imports, kernel loads or compiles).
    on_stage : callable or None
        Called with a step's name when it first starts.
    """

    def __init__(self, on_stage: Callable[[str], None] | None):
        self.seconds: dict[str, float] = {}
        self.one_off_s = 0.0
        self.on_stage = on_stage

    @contextmanager
    def stage(self, name: str) -> Iterator[None]:
        """Time the ``with`` block as step ``name``, adding its wall seconds to ``seconds[name]``
        (a step timed twice is summed); ``on_stage(name)`` is called when the step first starts."""
        if self.on_stage is not None and name not in self.seconds:
            self.on_stage(name)
        one_off_before = jit.one_off_seconds()
        start = time.perf_counter()
        try:
            yield
        finally:
            wall = time.perf_counter() - start
            one_off = min(max(jit.one_off_seconds() - one_off_before, 0.0), wall)
            self.seconds[name] = self.seconds.get(name, 0.0) + wall - one_off
            self.one_off_s += one_off

    def paid(self, charge_of: Callable[[str], Charge]) -> Paid:
        """Paid seconds by charge and step: each step's work under ``charge_of(step)`` (the
        registry's :func:`~pipeline.run.stages.step_charge`), the one-off seconds (if any) under
        ``shared`` / :data:`SETUP_STEP`."""
        paid: Paid = {charge: {} for charge in Charge}
        for step, work in self.seconds.items():
            _add(paid[charge_of(step)], step, work)
        if self.one_off_s > 0.0:
            _add(paid[Charge.SHARED], SETUP_STEP, self.one_off_s)
        return paid

    def paid_total(self) -> dict[str, float]:
        """Paid seconds per step, both charges summed (the steps' wall time)."""
        total = dict(self.seconds)
        if self.one_off_s > 0.0:
            _add(total, SETUP_STEP, self.one_off_s)
        return total


def _add(seconds: dict[str, float], step: str, value: float) -> None:
    seconds[step] = seconds.get(step, 0.0) + value
