"""Chips as a population: a ``shared`` deployment onto 100 chips against one chip, side by side.

At the paper's operating point on the built-in data, with threshold mismatch (``sigma_rel`` 0.5),
one scene simulates one chip (``per_chip``, the default) and the other 100 chips with one
classifier trained on the nominal chip (``shared``). Both run end to end in this process
(:func:`pipeline.run.simulate.run_scene`), interleaved, at one torch thread as the Dask workers
train; the figure is the median of each one's paid seconds (every step's wall time, the
process's one-off set-up left out: it is paid once, whichever runs first). Target: 100 chips
cost at most 3x one chip (training runs once per fold whatever the number of chips; encoding,
coding and testing the chips is what grows).

``run(tiny=True)``: the ``smoke`` scene, 4 chips, one timing of each.
"""

from __future__ import annotations

import statistics

import torch

from pipeline.design.scene import Scene
from pipeline.run.simulate import run_scene
from pipeline.run.stages import SETUP_STEP

SIGMA_REL = 0.5


def scenes(name: str, chips: int) -> tuple[Scene, Scene]:
    """The one-chip scene and the shared deployment onto ``chips`` chips, built-in ``name``."""
    one = Scene.builtin(name).replace(
        **{"readout.effects": {"threshold_mismatch": {"sigma_rel": SIGMA_REL}}}
    )
    return one, one.replace(**{"chips.count": chips, "chips.deployment": "shared"})


def paid_seconds(scene: Scene) -> float:
    """Seconds of every step of one run of ``scene`` (the one-off set-up left out)."""
    result = run_scene(scene)
    return sum(s for step, s in result.timings_s.items() if step != SETUP_STEP)


def run(repeat: int = 3, tiny: bool = False) -> list[dict]:
    """The row; ``tiny``: the ``smoke`` scene with 4 chips, one timing of each."""
    name, chips, repeat = ("smoke", 4, 1) if tiny else ("paper", 100, repeat)
    one, many = scenes(name, chips)
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        run_scene(scenes("smoke", 2)[1])  # the one-off set-up (imports, kernels), uncounted
        samples: dict[str, list[float]] = {"one": [], "many": []}
        for _ in range(repeat):
            samples["one"].append(paid_seconds(one))
            samples["many"].append(paid_seconds(many))
    finally:
        torch.set_num_threads(threads)
    one_s, many_s = (statistics.median(samples[k]) for k in ("one", "many"))
    return [
        {
            "benchmark": f"{name}, sigma_rel {SIGMA_REL}: shared onto {chips} chips / one chip, "
            "paid seconds",
            "ratio": many_s / one_s,
            "target": "<= 3",
            "detail": f"1 torch thread; medians of {repeat}: {chips} chips {many_s:.1f} s, "
            f"one chip {one_s:.1f} s",
        }
    ]
