import time

import pytest

from pipeline import jit
from pipeline.run.records import Charge
from pipeline.run.stages import step_charge
from pipeline.run.stopwatch import Stopwatch


def test_the_stopwatch_books_kernel_compiles_as_shared_and_steps_by_their_charge(monkeypatch):
    clock = iter([10.0, 10.5, 10.5, 10.5])  # 0.5 s of compiling inside "readout", none in "load"
    monkeypatch.setattr(jit, "one_off_seconds", lambda: next(clock))
    watch = Stopwatch(None)
    with watch.stage("readout"):
        time.sleep(0.6)
    with watch.stage("load"):
        pass
    paid = watch.paid(step_charge)
    assert watch.seconds["readout"] == pytest.approx(paid[Charge.OWN]["readout"])
    assert paid[Charge.SHARED]["setup"] == 0.5
    assert paid[Charge.SHARED]["load"] == watch.seconds["load"]  # a shared step
    assert "load" not in paid[Charge.OWN]
    wall = watch.paid_total()
    assert wall["readout"] + wall["setup"] == pytest.approx(watch.seconds["readout"] + 0.5)


def test_a_stopwatch_without_one_off_time_pays_no_setup():
    watch = Stopwatch(None)
    with watch.stage("coding"):
        pass
    assert watch.one_off_s == 0.0
    assert "setup" not in watch.paid(step_charge)[Charge.SHARED]
    assert watch.paid_total() == watch.seconds
