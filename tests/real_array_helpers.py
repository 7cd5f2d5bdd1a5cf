"""A synthetic real array whose class information sits in one taxel only.

Three classes, 12 recordings each, of 4 taxels at 500 Hz, 1 s long: taxel 2 (the one a design
reading one taxel of four reads, :func:`pipeline.recordings.taxel_choice.chosen_taxels`) vibrates
at a frequency of its class (4, 12 or 30 Hz); the other three vibrate at a frequency drawn alike for
every class from the same range; every taxel carries a little white noise.
"""

import dataclasses

import numpy as np

from pipeline.recordings.recording_set import Recordings

FS_HZ = 500.0
N_TAXELS = 4
INFORMATIVE = 2
PER_CLASS = 12
CLASS_HZ = (4.0, 12.0, 30.0)
CHANCE = 1 / len(CLASS_HZ)


def one_informative_taxel(seed: int = 0) -> Recordings:
    """The dataset of the module docstring: 1 s recordings, float64 (500, 4)."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(FS_HZ)) / FS_HZ
    signals, labels = [], []
    for label, hz in enumerate(CLASS_HZ):
        for _ in range(PER_CLASS):
            columns = []
            for taxel in range(N_TAXELS):
                if taxel == INFORMATIVE:
                    phase = rng.uniform(0, 2 * np.pi)
                    column = np.sin(2 * np.pi * hz * t + phase)
                else:  # every class alike: a random frequency from one range
                    f = rng.uniform(CLASS_HZ[0], CLASS_HZ[-1])
                    column = np.sin(2 * np.pi * f * t + rng.uniform(0, 2 * np.pi))
                columns.append(column + 0.05 * rng.standard_normal(t.size))
            signals.append(np.stack(columns, axis=1))
            labels.append(label)
    return Recordings(
        signals=tuple(signals),
        labels=np.array(labels),
        class_names=tuple(f"c{hz:g}Hz" for hz in CLASS_HZ),
        fs_hz=FS_HZ,
        names=tuple(f"c{label}/r{i:02d}.npy" for i, label in enumerate(labels)),
        units="a.u.",
        name="one informative taxel",
        taxel_names=tuple(f"t{k}" for k in range(N_TAXELS)),
    )


def write_npy_folder(recordings: Recordings, folder) -> None:
    """``recordings`` as a folder dataset: a 2-D ``.npy`` (samples, taxels) per recording under
    its class folder, and a ``dataset.toml`` with the rate (every column a taxel)."""
    folder.mkdir()
    (folder / "dataset.toml").write_text(
        f"sampling_rate_hz = {recordings.fs_hz!r}\nname = 'one informative taxel'\n"
    )
    for i, (signal, label) in enumerate(zip(recordings.signals, recordings.labels, strict=True)):
        class_folder = folder / recordings.class_names[label]
        class_folder.mkdir(exist_ok=True)
        np.save(class_folder / f"r{i:02d}.npy", np.asarray(signal))


def only_taxel(recordings: Recordings, taxel: int) -> Recordings:
    """The dataset of one taxel's column of ``recordings`` alone (a one-taxel array)."""
    return dataclasses.replace(
        recordings,
        signals=tuple(np.asarray(s)[:, [taxel]] for s in recordings.signals),
        name=f"taxel {taxel}",
        taxel_names=(recordings.taxel_names[taxel],),
        taxel_positions_mm=None,
    )
