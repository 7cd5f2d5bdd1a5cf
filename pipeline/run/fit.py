"""Does a scene fit its recordings? The checks made before any work starts.

A scene fits its recordings when its array fits them (no more taxels read than a real array
holds, no time-shift grid on one: :func:`pipeline.chain.real_taxels.array_misfits`), the taxel
delays of its array leave at least 2 samples of the
shortest recording, the remaining duration ``T = (n - cut - 1) / fs`` holds at least one whole
window of ``coding.window_s`` (and a fixed ``coding.n_windows`` of them:
:func:`pipeline.design.windows.whole_windows`), and every class has at least ``training.folds``
recordings: the conditions the simulation needs. :class:`DatasetLimits` is what the checks need
to know of a dataset (its shortest recording, its smallest class, its rate), known for the
built-in dataset without generating it. :func:`check_scene_fits` checks one scene (``eskin
run``), :func:`check_fits` every point of a grid, each distinct combination of recordings, array,
coding and folds once, and every problem is reported at once, naming the shortest recording.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from pipeline.chain.real_taxels import array_misfits
from pipeline.chain.taxels import cut_samples, taxel_delays_s
from pipeline.design.grid import Grid
from pipeline.design.scene import ArraySpec, CodingSpec, DatasetKind, DatasetSpec, Scene
from pipeline.design.windows import whole_windows
from pipeline.errors import SceneError
from pipeline.recordings.recording_set import Recordings
from pipeline.recordings.sources import load_recordings, synthetic_arguments
from pipeline.recordings.synthetic import synthetic_layout
from pipeline.run.stages import cache_key


@dataclass(frozen=True)
class DatasetLimits:
    """What :func:`check_scene_fits` needs to know of a dataset; build it with :meth:`of`.

    Attributes
    ----------
    fs_hz : float
        Sampling rate (Hz).
    min_samples : int
        Samples of the shortest recording.
    min_class_size : int
        Recordings of the smallest class.
    shortest : str
        Name of the shortest recording (the first of equally short ones) as
        :attr:`pipeline.recordings.recording_set.Recordings.names` gives it:
        ``"<class>/<file name>"`` for a folder dataset (its path relative to the dataset folder),
        ``"Texture3/segment07"``, ``"<class>/rec03"``; empty if unknown.
    dataset : str
        Name of the dataset (:attr:`pipeline.recordings.recording_set.Recordings.name`); empty if
        unknown.
    smallest_class : str
        Name of the smallest class (the first of equally small ones); empty if unknown.
    n_taxels : int
        Taxels each recording holds (1 for one channel).
    is_array : bool
        Whether the recordings hold the named columns of a real array.
    """

    fs_hz: float
    min_samples: int
    min_class_size: int
    shortest: str = ""
    dataset: str = ""
    smallest_class: str = ""
    n_taxels: int = 1
    is_array: bool = False

    @classmethod
    def of(cls, recordings: Recordings) -> DatasetLimits:
        """The limits of loaded recordings."""
        lengths = recordings.lengths
        shortest = int(np.argmin(lengths))
        sizes = np.bincount(recordings.labels, minlength=len(recordings.class_names))
        smallest = int(np.argmin(sizes))
        return cls(
            fs_hz=recordings.fs_hz,
            min_samples=int(lengths[shortest]),
            min_class_size=int(sizes[smallest]),
            shortest=recordings.names[shortest],
            dataset=recordings.name,
            smallest_class=recordings.class_names[smallest],
            n_taxels=recordings.n_taxels,
            is_array=recordings.is_array,
        )

    @classmethod
    def describe(cls, spec: DatasetSpec) -> DatasetLimits:
        """The limits of the recordings ``spec`` names; the built-in ones are not generated.

        Raises
        ------
        DatasetError
            As :func:`pipeline.recordings.sources.load_recordings`.
        """
        if DatasetKind(spec.kind) is not DatasetKind.SYNTHETIC:
            return cls.of(load_recordings(spec))

        layout = synthetic_layout(**synthetic_arguments(spec))
        return cls(
            fs_hz=layout.fs_hz,
            min_samples=layout.n_samples,
            min_class_size=spec.recordings_per_class,
            shortest=layout.names[0],
            dataset="synthetic",
            smallest_class=layout.class_names[0],
        )

    def shortest_recording(self) -> str:
        """``"the shortest recording, <name> of dataset '<dataset>' (<n> samples)"``."""
        named = f", {self.shortest}" if self.shortest else ""
        of = f" of dataset {self.dataset!r}" if self.dataset else ""
        return f"the shortest recording{named}{of} ({self.min_samples} samples)"


def scene_misfits(scene: Scene, limits: DatasetLimits) -> list[tuple[str, str]]:
    """Every way ``scene`` does not fit its recordings, as ``(scene field, problem)`` pairs.

    A scene fits when its taxel delays leave at least 2 samples of the shortest recording, the
    remaining duration holds at least one window (and a fixed ``coding.n_windows``), and every
    class has at least ``training.folds`` recordings: the same conditions the simulation needs.
    Each problem names the shortest recording where it is the culprit. Empty if the scene fits.
    """
    return _misfits(scene.array, scene.coding, scene.training.folds, limits)


def _misfits(
    array: ArraySpec, coding: CodingSpec, folds: int, limits: DatasetLimits
) -> list[tuple[str, str]]:
    """:func:`scene_misfits` of a scene with this ``array``, ``coding`` and ``training.folds``:
    all it depends on, so that a grid checks each distinct combination once."""
    problems = array_misfits(array, limits.n_taxels, limits.is_array, limits.dataset)
    cut = cut_samples(taxel_delays_s(array), limits.fs_hz)
    remaining = limits.min_samples - cut
    if remaining < 2:
        problems.append(
            (
                "array",
                f"the delays of a {array.rows}x{array.cols} array (pitch {array.pitch_mm:g} mm "
                f"at {array.speed_mm_s:g} mm/s: {cut / limits.fs_hz:.3g} s, {cut} samples at "
                f"{limits.fs_hz:g} Hz) use up {limits.shortest_recording()}; at least "
                f"{cut + 2} samples are needed",
            )
        )
    else:
        usable_s = (remaining - 1) / limits.fs_hz  # as SpikeTrains.duration_s
        fit = whole_windows(usable_s, coding.window_s)
        wanted = coding.n_windows
        if fit < 1 or (wanted != "auto" and wanted > fit):
            n = 1 if wanted == "auto" else wanted
            field = "coding.window_s" if fit < 1 else "coding.n_windows"
            problems.append(
                (
                    field,
                    f"{n} window(s) of {coding.window_s} s do not fit "
                    f"{limits.shortest_recording()}: {usable_s:.3g} s after taxel delays "
                    f"hold {fit}",
                )
            )
    if limits.min_class_size < folds:
        problems.append(
            (
                "training.folds",
                f"{folds} folds need at least that many recordings per class; "
                + (f"class {limits.smallest_class!r}" if limits.smallest_class else "a class")
                + f" has fewer ({limits.min_class_size})",
            )
        )
    return problems


def check_scene_fits(scene: Scene, limits: DatasetLimits) -> None:
    """Raise :class:`~pipeline.errors.SceneError` listing every misfit of ``scene``
    (:func:`scene_misfits`)."""
    problems = scene_misfits(scene, limits)
    if problems:
        raise SceneError([f"{field}: {text}" for field, text in problems], repr(scene.name))


def check_fits(grid: Grid, limits: Mapping[str, DatasetLimits]) -> None:
    """Check every point against its recordings; raise :class:`~pipeline.errors.SceneError`
    listing all misfits.

    Parameters
    ----------
    limits
        For each dataset of the grid, keyed by ``cache_key(scene, "recordings")``.
    """
    # Points sharing a problem (every threshold of a too-short dataset, say) are listed once.
    places: dict[str, list[str]] = {}
    recordings: dict[DatasetSpec, str] = {}
    misfits: dict[tuple[str, ArraySpec, CodingSpec, int], list[str]] = {}
    for point in grid.points():
        scene = point.scene
        key = recordings.get(scene.dataset)
        if key is None:  # the recordings key is a function of the dataset alone
            key = recordings[scene.dataset] = cache_key(scene, "recordings")
        combination = (key, scene.array, scene.coding, scene.training.folds)
        texts = misfits.get(combination)
        if texts is None:
            texts = misfits[combination] = [
                text for _, text in _misfits(*combination[1:], limits[key])
            ]
        if texts:
            where = f"sweeps.{point.sweep}[{', '.join(map(str, point.index))}]"
            for text in texts:
                places.setdefault(text, []).append(where)
    problems = [
        ", ".join(wheres[:3])
        + (f" and {len(wheres) - 3} more" if len(wheres) > 3 else "")
        + f": {text}"
        for text, wheres in places.items()
    ]
    if problems:
        raise SceneError(problems, repr(grid.name), "grid")
