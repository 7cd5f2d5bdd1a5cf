"""What a grid costs: the relative training cost of a point, the kind of point whose measured
seconds predict another's, and what planning a grid takes of a machine.

A point's cost is the product of the fields declared to scale it
(:attr:`pipeline.design.fields.Cost.SIZE`: taxel rows and columns, windows, models trained):
training dominates a point, and it grows with the frame size (taxels x windows) per model. A
grid's planning takes :data:`PLAN_BYTES_PER_POINT` and :data:`PLAN_SECONDS_PER_POINT` per point;
a grid too large to plan is refused from its axis sizes alone
(:func:`pipeline.design.grid.too_large`), before any point is built.
"""

from __future__ import annotations

import json
import math
from typing import Any

from pipeline.design import fields
from pipeline.design.scene import Scene
from pipeline.design.windows import MAX_AUTO_WINDOWS


def training_cost(scene: Scene) -> int:
    """A point's relative cost: the product of the fields declared to scale it
    (:attr:`pipeline.design.fields.Cost.SIZE`: taxel rows and columns, windows, models trained).

    Training dominates a point, and its cost grows with the frame size (taxels x windows) per
    model; ``auto`` windows count as the most they can be, a list as its length. Only the order
    in which points run depends on it, never a result.
    """
    _, sizes = fields.cost_parts(scene)
    return math.prod(_size(value) for value in sizes)


def _size(value: Any) -> int:
    if value == "auto":
        return MAX_AUTO_WINDOWS
    return len(value) if isinstance(value, tuple | list) else int(value)


def cost_kind(scene: Scene) -> str:
    """What a point's cost depends on: its plain form without the fields declared free of cost
    (:attr:`pipeline.design.fields.Cost.FREE`: the threshold, the effects' parameter values, every
    seed) and without its name, as canonical JSON. The names of the effects that run stay; what
    is left (dataset, taxels, windows, models, epochs, folds, ...) decides how long encoding and
    training take, so points of one kind cost about the same."""
    form, _ = fields.cost_parts(scene)
    return json.dumps(form, sort_keys=True, separators=(",", ":"))


#: Memory planning takes per point (load, check, distinct points, cache keys, cached entries),
#: in bytes, measured at 1,000,000 points by ``benchmarks/planning.py`` (peak resident memory
#: above the interpreter's), rounded up.
PLAN_BYTES_PER_POINT = 1_000
#: Time planning takes per point, in CPU seconds, measured and rounded up likewise.
PLAN_SECONDS_PER_POINT = 20e-6
#: The share of the machine's memory a plan may take (the sweep needs the rest).
PLAN_MEMORY_SHARE = 0.5
#: The longest a command may plan before it says anything (s).
PLAN_MAX_S = 120.0
#: Stage seconds of a typical point, for the cost of a grid too large to plan. The ``paper``
#: grid's mean (483 stage seconds over 48 points, 2 cores).
TYPICAL_POINT_S = 10.0


def plannable_points(memory_bytes: int) -> int:
    """The most points a machine of ``memory_bytes`` plans: in :data:`PLAN_MEMORY_SHARE` of its
    memory at :data:`PLAN_BYTES_PER_POINT`, and in :data:`PLAN_MAX_S` at
    :data:`PLAN_SECONDS_PER_POINT` (6,000,000 points on a machine of 12 GB or more)."""
    by_memory = memory_bytes * PLAN_MEMORY_SHARE / PLAN_BYTES_PER_POINT
    return int(min(by_memory, round(PLAN_MAX_S / PLAN_SECONDS_PER_POINT)))
