"""``python -m benchmarks.data_statistics``: the built-in classes beside VibTac-12's, statistic by
statistic.

Prints, for the VibTac-12 copy (loaded through the project's loader: z axis, 10 segments per
texture, 200 Hz) and the built-in dataset (default arguments), the per-class statistics of
:func:`pipeline.synthetic.class_statistics`, then each statistic's range over the classes and the
dataset-level summaries, with the x and y axes of the same recordings beside z (one number per
dataset has no spread of its own; the three axes give one). A built-in value outside the real
z range (per class) or the three axes' range (per dataset) is marked ``*``. These are the
numbers quoted in the module docstring of :mod:`pipeline.synthetic`.

Options: ``--vibtac12 PATH`` (default ``../shared/datasets/vibtac12`` next to the repository),
``--seed N`` (of the built-in data, default 0).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from pipeline.recordings import load_recordings
from pipeline.scene import DatasetSpec
from pipeline.synthetic import ClassStatistics, class_statistics, synthetic_recordings

DEFAULT_VIBTAC12 = Path(__file__).resolve().parents[2] / "shared" / "datasets" / "vibtac12"

#: (attribute, heading, format) of the per-class statistics.
PER_CLASS = (
    ("rms_v", "rms V", "{:.4f}"),
    ("rms_cv", "cv", "{:.3f}"),
    ("mad_v", "mad V", "{:.4f}"),
    ("centroid_hz", "cen Hz", "{:.1f}"),
    ("centroid_nyquist", "cen/Nyq", "{:.3f}"),
    ("bandwidth_hz", "bw Hz", "{:.1f}"),
    ("bandwidth_nyquist", "bw/Nyq", "{:.3f}"),
    ("excess_kurtosis", "kurt", "{:.1f}"),
)
#: (attribute, heading, format) of the dataset-level summaries.
PER_DATASET = (
    ("across_class_cv", "across-class cv of rms V", "{:.3f}"),
    ("across_class_ratio", "loudest / quietest class", "{:.2f}"),
    ("median_rms_v", "median class rms V", "{:.4f}"),
    ("median_rms_cv", "median within-class cv", "{:.3f}"),
)


def vibtac12_statistics(path: Path, axis: str) -> ClassStatistics:
    """Statistics of one axis of the VibTac-12 copy at ``path`` (10 segments, 200 Hz)."""
    spec = DatasetSpec(
        kind="vibtac12", path=str(path), axis=axis, segments=10, sampling_rate_hz=200.0
    )
    return class_statistics(load_recordings(spec))


def per_class_table(stats: ClassStatistics) -> list[str]:
    """One line per class: name, RMS in recording units, then :data:`PER_CLASS`."""
    head = f"{'class':22s} {'rms ' + stats.units:>12s} " + " ".join(
        f"{h:>8s}" for _, h, _ in PER_CLASS
    )
    lines = [f"{stats.dataset}: fs {stats.fs_hz:g} Hz, gain {stats.gain_v_per_unit:.5g} V/unit"]
    lines.append(head)
    for c, name in enumerate(stats.class_names):
        cells = " ".join(f"{fmt.format(getattr(stats, a)[c]):>8s}" for a, _, fmt in PER_CLASS)
        lines.append(f"{name:22s} {stats.rms[c]:12.4g} {cells}")
    return lines


def ranges_table(real: ClassStatistics, built_in: ClassStatistics) -> list[str]:
    """Per statistic: the real classes' range and the built-in classes' range (``*``: outside)."""
    lines = [f"{'per class':22s} {real.dataset + ' range':>24s} {'built-in range':>24s}"]
    for attr, heading, fmt in PER_CLASS:
        lo, hi = np.min(getattr(real, attr)), np.max(getattr(real, attr))
        values = getattr(built_in, attr)
        outside = int(np.sum((values < lo) | (values > hi)))
        mark = f"  * {outside} classes outside" if outside else ""
        real_range = f"{fmt.format(lo)} .. {fmt.format(hi)}"
        ours = f"{fmt.format(np.min(values))} .. {fmt.format(np.max(values))}"
        lines.append(f"{heading:22s} {real_range:>24s} {ours:>24s}{mark}")
    return lines


def summary_table(axes: dict[str, ClassStatistics], built_in: ClassStatistics) -> list[str]:
    """Dataset-level summaries: each real axis, the built-in data (``*``: outside the axes)."""
    names = list(axes)
    lines = [f"{'per dataset':26s} " + " ".join(f"{a:>8s}" for a in names) + f" {'built-in':>9s}"]
    for attr, heading, fmt in PER_DATASET:
        real = [getattr(axes[a], attr) for a in names]
        ours = getattr(built_in, attr)
        mark = " *" if not min(real) <= ours <= max(real) else ""
        cells = " ".join(f"{fmt.format(v):>8s}" for v in real)
        lines.append(f"{heading:26s} {cells} {fmt.format(ours):>9s}{mark}")
    return lines


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.data_statistics")
    parser.add_argument("--vibtac12", type=Path, default=DEFAULT_VIBTAC12)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    axes = {axis: vibtac12_statistics(args.vibtac12, axis) for axis in ("z", "x", "y")}
    built_in = class_statistics(synthetic_recordings(seed=args.seed))
    lines = [*per_class_table(axes["z"]), "", *per_class_table(built_in), ""]
    lines += [*ranges_table(axes["z"], built_in), "", *summary_table(axes, built_in)]
    print("\n".join(lines))


if __name__ == "__main__":
    main()
