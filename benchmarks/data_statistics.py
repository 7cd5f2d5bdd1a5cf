"""``python -m benchmarks.data_statistics``: the built-in touches beside real ones, statistic by
statistic.

Prints :func:`pipeline.recordings.touch_statistics.touch_statistics` for the VibTac-12 copy (loaded
through the project's loader: z axis, 10 segments per texture, 200 Hz) and for the built-in dataset
(default arguments, ``--seed``), beside the real touches' reference (:data:`REAL_TOUCHES`: the value
on the real 12 x 10 set and the range it is judged by), then the built-in data's range over
``--seeds`` seeds. A value outside the reference range is marked ``*``. These are the numbers quoted
in the module docstring of :mod:`pipeline.recordings.synthetic`.

Options: ``--vibtac12 PATH`` (a VibTac-12 copy to set beside the built-in data; left out when not
given or absent), ``--seed N`` (of the built-in data, default 0), ``--seeds N`` (seeds ``0 ..
N-1`` for the range, default 8; 0 leaves the range out).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pipeline.design.scene import DatasetSpec
from pipeline.recordings.sources import load_recordings
from pipeline.recordings.synthetic import synthetic_recordings
from pipeline.recordings.touch_statistics import (
    REAL_TOUCHES,
    Reference,
    TouchStatistics,
    touch_statistics,
)

#: Statistics whose value is a range over the classes (the rest are one number per dataset).
PER_CLASS = {"centroid_hz": "class_centroid_hz", "bandwidth_hz": "class_bandwidth_hz"}


def extremes(stats: TouchStatistics, name: str) -> tuple[float, float]:
    """A :data:`REAL_TOUCHES` statistic of ``stats`` as ``(low, high)``: the class range of a
    spectrum statistic, the one value twice otherwise."""
    if name in PER_CLASS:
        values = getattr(stats, PER_CLASS[name])
        return float(np.nanmin(values)), float(np.nanmax(values))
    value = float(getattr(stats, name))
    return value, value


def cell(stats: TouchStatistics, name: str) -> str:
    """``stats``' value of ``name`` as printed (the contact transient with its 10-90 % band),
    ``*`` when outside the reference range."""
    low, high = extremes(stats, name)
    reference = REAL_TOUCHES[name]
    mark = "" if reference.holds(low) and reference.holds(high) else " *"
    if name == "contact_transient":
        band = f" ({stats.contact_transient_p10:.2f}-{stats.contact_transient_p90:.2f})"
        return f"{low:.2f}{band}{mark}"
    if name in PER_CLASS:
        return f"{low:.1f}-{high:.1f}{mark}"
    return f"{low:.3f}{mark}"


def reference_cell(reference: Reference) -> str:
    """The real value and the range it is judged by, e.g. ``0.59 [0.4, -]``."""
    typical = reference.typical
    value = f"{typical[0]:g}-{typical[1]:g}" if isinstance(typical, tuple) else f"{typical:g}"
    bounds = ", ".join("-" if b is None else f"{b:g}" for b in (reference.low, reference.high))
    return f"{value} [{bounds}]"


def seed_range(per_seed: list[TouchStatistics], name: str) -> str:
    """Lowest and highest value of ``name`` over several datasets (``*``: one outside)."""
    values = [extremes(stats, name) for stats in per_seed]
    low, high = min(v[0] for v in values), max(v[1] for v in values)
    reference = REAL_TOUCHES[name]
    mark = "" if reference.holds(low) and reference.holds(high) else " *"
    digits = 1 if name in PER_CLASS else 2 if name == "contact_transient" else 3
    return f"{low:.{digits}f} .. {high:.{digits}f}{mark}"


def table(columns: dict[str, TouchStatistics], per_seed: list[TouchStatistics]) -> list[str]:
    """One row per :data:`REAL_TOUCHES` statistic: the reference, each dataset, the seed range."""
    heads = ["real 12x10 [range]", *columns]
    if per_seed:
        heads.append(f"seeds 0-{len(per_seed) - 1}")
    lines = [f"{'statistic':24s}" + "".join(f" {h:>22s}" for h in heads)]
    for name, reference in REAL_TOUCHES.items():
        cells = [reference_cell(reference), *(cell(s, name) for s in columns.values())]
        if per_seed:
            cells.append(seed_range(per_seed, name))
        lines.append(f"{name:24s}" + "".join(f" {c:>22s}" for c in cells))
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.data_statistics")
    parser.add_argument("--vibtac12", type=Path)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--seeds", type=int, default=8)
    args = parser.parse_args(argv)
    columns = {}
    if args.vibtac12 is not None and args.vibtac12.is_dir():
        spec = DatasetSpec(
            kind="vibtac12", path=str(args.vibtac12), axis="z", segments=10, sampling_rate_hz=200.0
        )
        columns["VibTac-12 copy (z)"] = touch_statistics(load_recordings(spec))
    columns[f"built-in seed {args.seed}"] = touch_statistics(synthetic_recordings(seed=args.seed))
    per_seed = [touch_statistics(synthetic_recordings(seed=s)) for s in range(args.seeds)]
    print("\n".join(table(columns, per_seed)))


if __name__ == "__main__":
    main()
