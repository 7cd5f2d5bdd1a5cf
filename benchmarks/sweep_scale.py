"""The sweep machinery at scale: plan, compute and assemble 1,000, 10,000 and 100,000 points.

Each size runs the real machinery of ``eskin sweep`` on a fresh root, phase by phase, as
:func:`flows.run.run_sweep` calls it: the store opened (or created) and its lock held,
:func:`~flows.planning.checked_grid` and :func:`~flows.planning.plan_sweep` (planning),
:func:`~flows.scheduling.submit_missing` and :func:`~flows.progress.completed_points` on a fresh
local cluster of 2 single-thread worker processes (:func:`flows.cluster.dask_client`; compute),
then :func:`~flows.assembly.assemble_cubes` (assembly). Only the science is left out: the ``spikes``
and ``results`` levels' compute functions are replaced, in this process and in every worker
process (a ``distributed.WorkerPlugin``), by stand-ins that take microseconds and return outputs
of the real shapes. The spike stand-in returns the real spike trains of one point, computed once
here (``paper`` with a threshold mismatch of 0.1, so REAL and TRUE trains are both stored); the
classifier stand-in returns, for every model, cross-validation results of the real shapes
derived from the labels and the training seed. The recordings, front-end and rate-coding levels
run for real (each worker loads the recordings once). The stand-ins exist only in this harness:
nothing in the package can reach them.

Every size is one grid with the same mix of entries per point, so that per-point figures
compare across sizes: 1,000 points are 10 thresholds x 10 windows x 10 training seeds (10 spike
trains, 100 rate matrices, 1,000 results); 10,000 add 10 scene seeds and 100,000 ten threshold
mismatches, each multiplying every level by 10 (the mismatch draws random numbers, so the scene
seed is in every key). Every spike train has the shape of the one point's (3 x 3 taxels, 120
recordings); its number of events is that of its threshold, 0.09 V, at every threshold.

Per size: seconds per point of planning; wall seconds per point of the compute phase (submit
and wait); its overhead per point, ``(wall - busy / workers) / points`` where ``busy`` is the
seconds every worker spent inside level compute functions (idle workers count as overhead);
milliseconds per point of assembly; files per point and MB (apparent size) under the root. The
growth ratios divide each per-point figure by the one of the next smaller size: near 1 is
linear. Targets: overhead <= 5 ms per point on 2 workers, assembly <= 1 ms per point, <= 5 files
per point at 10,000 points.

``python -m benchmarks.sweep_scale [--sizes 1000 10000 100000] [--workers 2]`` runs this suite
alone and prints the markdown table; ``ESKIN_BENCH_SCALE_SIZES=1000,10000`` picks the sizes
within ``python -m benchmarks`` too. Each size is removed before the next starts; a size whose
files would not fit the free space or inodes (judged from the size before) is refused before it
starts. ``run(tiny=True)`` measures :data:`TINY_SIZES` the same way, on one worker (a second
would add only its start-up at that size).
"""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import functools
import gc
import itertools
import json
import math
import os
import resource
import shutil
import tempfile
import threading
import time
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import Any

import numpy as np
import xarray as xr
from distributed import WorkerPlugin

from flows.assembly import assemble_cubes
from flows.cluster import dask_client
from flows.environment import hermetic_environment, restored_environment
from flows.planning import checked_grid, plan_sweep
from flows.progress import completed_points, failure_message
from flows.scheduling import submit_missing
from pipeline.design.scene import Scene
from pipeline.results.variables import ACCURACY, FOLD_DIM, MODEL_DIM, REPEAT_DIM
from pipeline.run.decoding import Rates
from pipeline.run.encoding import Spikes
from pipeline.run.stages import LEVELS, RESULTS, SPIKES
from pipeline.run.stopwatch import Stopwatch
from storage import SweepStore

SIZES = (1_000, 10_000, 100_000)
TINY_SIZES = (10, 20)
SIZES_ENV = "ESKIN_BENCH_SCALE_SIZES"
WORKERS = 2
OVERHEAD_TARGET_MS = 5.0
ASSEMBLE_TARGET_MS = 1.0
FILES_TARGET = 5.0
FILES_AT = 10_000
LINEAR_TARGET = 1.5
MISMATCH_FIELD = "readout.effects.threshold_mismatch.sigma_rel"
BASE_MISMATCH_REL = 0.1
#: The axes a grid of n points takes, in order, as many values of each as n needs (10 at most).
AXES: dict[str, list[Any]] = {
    "readout.threshold_v": [0.01, 0.02, 0.03, 0.05, 0.07, 0.09, 0.12, 0.15, 0.2, 0.25],
    "coding.window_s": [0.025, 0.05, 0.075, 0.1, 0.125, 0.15, 0.2, 0.25, 0.3, 0.4],
    "training.seed": list(range(10)),
    "seed": list(range(10)),
    MISMATCH_FIELD: [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5],
}
#: Room left on the file system beyond what a size is expected to write.
ROOM_MARGIN = 1.25
MODEL_AXES = (MODEL_DIM, REPEAT_DIM, FOLD_DIM)

# Which level compute functions are real, captured before any stand-in can be installed; the
# stand-ins are put back to these, whatever ran in between.
_REAL_COMPUTE = {level.name: level.compute for level in LEVELS}
_busy_s = 0.0
_busy_lock = threading.Lock()


# ---------------------------------------------------------------------------------------------
# Grids


def axis_lengths(n_points: int) -> list[int]:
    """How many values of each of :data:`AXES` a grid of ``n_points`` takes, in order.

    Each axis takes the largest divisor of what is left that is at most 10.

    Raises
    ------
    ValueError
        ``n_points`` is not a product of at most 5 factors of at most 10.
    """
    if n_points < 1:
        raise ValueError(f"a grid needs at least 1 point, got {n_points}")
    lengths, left = [], n_points
    for _ in AXES:
        if left == 1:
            break
        take = max(d for d in range(1, 11) if left % d == 0)
        if take == 1:
            break
        lengths.append(take)
        left //= take
    if left != 1:
        raise ValueError(
            f"{n_points} points: not a product of at most {len(AXES)} factors of at most 10"
        )
    return lengths


def grid_text(n_points: int) -> str:
    """A grid TOML of ``n_points`` distinct points on ``paper``, one named sweep ``scale``."""
    axes = dict(zip(AXES, axis_lengths(n_points), strict=False))
    lines = [f'name = "scale{n_points}"', 'base = "paper"', "[sweeps.scale]"]
    if MISMATCH_FIELD not in axes:
        lines.append(f'set = {{ "{MISMATCH_FIELD}" = {BASE_MISMATCH_REL} }}')
    lines.append("[sweeps.scale.axes]")
    lines += [f'"{field}" = {json.dumps(AXES[field][:n])}' for field, n in axes.items()]
    return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Stand-ins for the science, installed only by this harness


def one_point_spikes() -> Spikes:
    """The real spike trains of one point (``paper``, threshold mismatch 0.1), computed here."""
    scene = Scene.paper().replace(**{MISMATCH_FIELD: BASE_MISMATCH_REL})
    watch = Stopwatch(None)
    outputs: dict[str, Any] = {}
    for level in LEVELS[: LEVELS.index(SPIKES) + 1]:
        outputs[level.name] = level.run(scene, outputs, watch)
    return outputs[SPIKES.name]


def stand_in_spikes(*, spikes: Spikes, watch: Stopwatch, **_: Any) -> Spikes:
    """The ``spikes`` level's stand-in: the same trains for every scene, its steps timed."""
    for step in SPIKES.steps:
        with watch.stage(step):
            pass
    return spikes


def stand_in_cross_validation(labels: np.ndarray, model: Any, training: Any) -> Any:
    """Cross-validation results of the real shapes, from the labels and the training seed.

    Each repeat tests recording ``i`` in fold ``(i + repeat) % folds`` and predicts the labels
    shifted by 1 to 5 places (set by the training seed, the repeat and the model), so every
    fold holds recordings and the accuracy differs between training seeds and models.
    """
    from pipeline.chain.training import CrossValidation

    n, repeats, folds = len(labels), training.repeats, training.folds
    order = np.arange(n)
    test_fold = (order[None, :] + np.arange(repeats)[:, None]) % folds
    offset = sum(map(ord, model.value))
    shifts = 1 + (training.seed + np.arange(repeats) + offset) % 5
    predicted = np.stack([np.roll(labels, int(s)) for s in shifts])
    correct = (predicted == labels[None, :]).astype(np.float64)
    fold_accuracy = np.stack(
        [
            np.bincount(test_fold[r], weights=correct[r], minlength=folds)
            / np.bincount(test_fold[r], minlength=folds)
            for r in range(repeats)
        ]
    )
    train_loss = np.full((repeats, folds), math.log(max(len(np.unique(labels)), 2)))
    return CrossValidation(model, fold_accuracy, 0.0, train_loss, predicted, test_fold)


def stand_in_classify(*, rates: Rates, training: Any, watch: Stopwatch) -> dict[Any, Any]:
    """The ``results`` level's stand-in: one result per model, its ``train_<model>`` timed."""
    labels = np.asarray(rates.labels, dtype=np.int64)
    accuracy = {}
    for model in training.models:
        with watch.stage(f"train_{model.value}"):
            accuracy[model] = stand_in_cross_validation(labels, model, training)
    return accuracy


def _timed(compute: Any) -> Any:
    """``compute``, adding its seconds to this process's busy total."""

    @functools.wraps(compute)
    def timed(**arguments: Any) -> Any:
        global _busy_s
        start = time.perf_counter()
        try:
            return compute(**arguments)
        finally:
            elapsed = time.perf_counter() - start
            with _busy_lock:
                _busy_s += elapsed

    return timed


def install_stand_ins(spikes: Spikes) -> None:
    """Put the stand-ins in place of the ``spikes`` and ``results`` compute functions of this
    process, and time every level's compute function (:func:`busy_seconds`)."""
    stand_ins = {
        SPIKES.name: functools.partial(stand_in_spikes, spikes=spikes),
        RESULTS.name: stand_in_classify,
    }
    for level in LEVELS:
        # Level is a frozen dataclass: the registry is patched in place, as the workers use it.
        compute = stand_ins.get(level.name, _REAL_COMPUTE[level.name])
        object.__setattr__(level, "compute", _timed(compute))


def remove_stand_ins() -> None:
    """Put every level's real compute function back (safe to call more than once)."""
    for level in LEVELS:
        object.__setattr__(level, "compute", _REAL_COMPUTE[level.name])


@contextlib.contextmanager
def stand_ins(spikes: Spikes) -> Iterator[None]:
    """The stand-ins installed in this process for the ``with`` block."""
    install_stand_ins(spikes)
    try:
        yield
    finally:
        remove_stand_ins()


def busy_seconds() -> tuple[int, float]:
    """This process's ID and the seconds it spent in level compute functions since the reset."""
    return os.getpid(), _busy_s


def reset_busy_seconds() -> None:
    global _busy_s
    with _busy_lock:
        _busy_s = 0.0


class StandInCompute(WorkerPlugin):
    """Installs the stand-ins in a worker's process; its teardown puts the real ones back.

    The worker imports the modules its tasks need at set-up, as a long-lived cluster would
    have, so that no import is timed as sweep overhead.
    """

    name = "eskin-sweep-scale-stand-ins"

    def __init__(self, spikes: Spikes):
        self.spikes = spikes

    def setup(self, worker: Any) -> None:
        import flows.work  # noqa: F401
        import pipeline.chain.training  # noqa: F401

        install_stand_ins(self.spikes)
        reset_busy_seconds()

    def teardown(self, worker: Any) -> None:
        remove_stand_ins()


# ---------------------------------------------------------------------------------------------
# One size


@dataclasses.dataclass(frozen=True)
class SizeRun:
    """The measured phases of one grid size.

    Attributes
    ----------
    points : int
        Distinct points planned (and computed: the root starts empty).
    plan_s, submit_s, compute_s, assemble_s : float
        Wall seconds of planning, of submitting, of the compute phase (submitting included,
        until the last point finished) and of assembling and writing the cube.
    busy_s : float
        Seconds the workers spent inside level compute functions, summed over workers.
    workers : int
        Worker threads of the cluster.
    failures : int
        Points that failed.
    cube_points : int
        Points of the written cube with every accuracy value finite.
    files, bytes, disk_bytes : int
        Files under the root after assembly, their apparent size and the disk blocks they use.
    peak_rss_mib : float
        Peak resident memory of this process so far (MiB).
    """

    points: int
    plan_s: float
    submit_s: float
    compute_s: float
    busy_s: float
    workers: int
    assemble_s: float
    failures: int
    cube_points: int
    files: int
    bytes: int
    disk_bytes: int
    peak_rss_mib: float

    @property
    def overhead_ms(self) -> float:
        """Compute-phase overhead per point (ms): wall minus busy seconds per worker."""
        return (self.compute_s - self.busy_s / self.workers) / self.points * 1e3

    def per_point(self) -> dict[str, float]:
        """The table's per-point figures, by column."""
        return {
            "plan s/pt": self.plan_s / self.points,
            "compute wall s/pt": self.compute_s / self.points,
            "overhead ms/pt": self.overhead_ms,
            "assemble ms/pt": self.assemble_s / self.points * 1e3,
            "files/pt": self.files / self.points,
            "MB": self.bytes / 1e6,
        }


@contextlib.contextmanager
def hermetic_state(state: Path) -> Iterator[None]:
    """Dask's scratch and the tools' state under ``state`` for the ``with`` block, whatever
    this process's environment says; the environment is restored afterwards."""
    import dask

    names = ("DASK_TEMPORARY_DIRECTORY", "MPLCONFIGDIR", "DO_NOT_TRACK")
    with restored_environment(names):
        for name in names:
            os.environ.pop(name, None)
        hermetic_environment(state, prefect=False)
        # Dask read its environment at import: the nannies made here take the folder from config.
        with dask.config.set({"temporary-directory": os.environ["DASK_TEMPORARY_DIRECTORY"]}):
            yield


@contextlib.contextmanager
def registered_stand_ins(client: Any, spikes: Spikes) -> Iterator[None]:
    """The stand-ins installed on every worker of ``client`` for the ``with`` block."""
    client.register_plugin(StandInCompute(spikes))
    try:
        yield
    finally:
        client.unregister_worker_plugin(StandInCompute.name)


@contextlib.contextmanager
def fresh_cluster(workers: int, state: Path, spikes: Spikes) -> Iterator[Any]:
    """A client of a fresh local cluster of ``workers``, its state under ``state``, the
    stand-ins installed on its workers."""
    with hermetic_state(state), dask_client(workers) as client:
        with registered_stand_ins(client, spikes):
            yield client


def tree_size(root: Path) -> tuple[int, int, int]:
    """Files under ``root``, their apparent size and their disk blocks (bytes)."""
    files = size = disk = 0
    for folder, _, names in os.walk(root):
        for name in names:
            stat = os.lstat(os.path.join(folder, name))
            files += 1
            size += stat.st_size
            disk += stat.st_blocks * 512
    return files, size, disk


def complete_cube_points(location: str) -> int:
    """Points of the cube at ``location`` whose accuracy is finite for every model and fold."""
    with xr.open_zarr(location, consolidated=False, chunks=None) as cube:
        accuracy = cube[ACCURACY]
        dims = [d for d in accuracy.dims if d not in MODEL_AXES]
        values = accuracy.transpose(*dims, ...).values
    n_points = math.prod(values.shape[: len(dims)])
    return int(np.isfinite(values.reshape(n_points, -1)).all(axis=1).sum())


def check_room(folder: Path, n_points: int, before: SizeRun | None) -> None:
    """Refuse a size whose files would not fit where ``folder`` is, judged per point from the
    size ``before`` (nothing is judged for the first size).

    Raises
    ------
    RuntimeError
        Too few free inodes or bytes, with :data:`ROOM_MARGIN` to spare.
    """
    if before is None:
        return
    room = os.statvfs(folder)
    files = before.files / before.points * n_points * ROOM_MARGIN
    disk = before.disk_bytes / before.points * n_points * ROOM_MARGIN
    if room.f_favail < files or room.f_bavail * room.f_frsize < disk:
        raise RuntimeError(
            f"{n_points:,} points would need about {files:,.0f} files and {disk / 1e9:.1f} GB "
            f"under {folder} (as {before.points:,} points did, per point, with "
            f"{ROOM_MARGIN - 1:.0%} to spare); {room.f_favail:,} inodes and "
            f"{room.f_bavail * room.f_frsize / 1e9:.1f} GB are free"
        )


def measure_size(
    n_points: int, folder: Path, spikes: Spikes, *, workers: int = WORKERS, client: Any = None
) -> SizeRun:
    """Run one grid of ``n_points`` on a fresh root under ``folder``, phase by phase.

    ``client``, when given, is used as it is, and must have the stand-ins on its workers
    (:func:`registered_stand_ins`); otherwise a fresh local cluster of ``workers``, with the
    stand-ins returning ``spikes``, runs the points. The stand-ins must be installed in this
    process too (:func:`stand_ins`).

    Raises
    ------
    RuntimeError
        The grid did not plan ``n_points`` missing points, or a point failed.
    """
    grid = folder / f"scale{n_points}.toml"
    grid.write_text(grid_text(n_points))
    store = SweepStore.open_or_create(folder / f"root{n_points}")
    with store.lock():
        start = time.perf_counter()
        plan = plan_sweep(checked_grid(grid), store.root)
        plan_s = time.perf_counter() - start
        if len(plan.scenes) != n_points or plan.cached:
            raise RuntimeError(
                f"{grid} planned {len(plan.scenes)} points, {len(plan.cached)} cached; "
                f"expected {n_points} missing"
            )
        failures = []
        with contextlib.ExitStack() as stack:
            dask = (
                client
                if client is not None
                else stack.enter_context(
                    fresh_cluster(workers, folder / f"state{n_points}", spikes)
                )
            )
            dask.run(reset_busy_seconds)
            start = time.perf_counter()
            futures = submit_missing(plan, dask)
            submit_s = time.perf_counter() - start
            for _, failure in completed_points(dask, futures):
                if failure:
                    failures.append(failure)
            compute_s = time.perf_counter() - start
            del futures
            # In-process workers share one process, and so one busy total: count each once.
            busy = dict(dask.run(busy_seconds).values())
            threads = sum(dask.nthreads().values())
        if failures:
            raise RuntimeError(failure_message(failures, n_points, plan.root))
        start = time.perf_counter()
        cubes = assemble_cubes(plan)
        assemble_s = time.perf_counter() - start
    files, size, disk = tree_size(store.root)
    cube_points = sum(complete_cube_points(location) for location in cubes.values())
    return SizeRun(
        points=n_points,
        plan_s=plan_s,
        submit_s=submit_s,
        compute_s=compute_s,
        busy_s=sum(busy.values()),
        workers=threads,
        assemble_s=assemble_s,
        failures=len(failures),
        cube_points=cube_points,
        files=files,
        bytes=size,
        disk_bytes=disk,
        peak_rss_mib=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    )


def measure(
    sizes: Sequence[int] = SIZES,
    *,
    workers: int = WORKERS,
    client: Any = None,
    folder: Path | None = None,
    progress: Any = None,
) -> list[SizeRun]:
    """Measure every size in turn, each root removed before the next size starts.

    ``folder`` (default: a temporary folder, removed at the end) holds the roots; ``client``,
    when given, runs every size (the stand-ins are registered on its workers meanwhile), else
    each size gets a fresh local cluster of ``workers``; ``progress`` is called with a line of
    text after each size.
    """
    spikes = one_point_spikes()
    runs: list[SizeRun] = []
    with contextlib.ExitStack() as stack:
        if folder is None:
            folder = Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="eskin-scale-")))
        stack.enter_context(stand_ins(spikes))
        if client is not None:
            stack.enter_context(registered_stand_ins(client, spikes))
        for n in sizes:
            check_room(folder, n, runs[-1] if runs else None)
            try:
                runs.append(measure_size(n, folder, spikes, workers=workers, client=client))
            finally:
                for name in (f"root{n}", f"state{n}"):
                    shutil.rmtree(folder / name, ignore_errors=True)
                gc.collect()
            if progress is not None:
                progress(describe(runs[-1]))
    return runs


# ---------------------------------------------------------------------------------------------
# Reporting


def describe(run: SizeRun) -> str:
    """One line of a size's raw figures."""
    return (
        f"{run.points:,} points: plan {run.plan_s:.2f} s, compute {run.compute_s:.1f} s "
        f"(submit {run.submit_s:.1f} s, busy {run.busy_s:.1f} s on {run.workers} workers), "
        f"assemble {run.assemble_s:.1f} s, {run.files:,} files, {run.bytes / 1e6:.0f} MB "
        f"({run.disk_bytes / 1e6:.0f} MB on disk), peak {run.peak_rss_mib:.0f} MiB here"
    )


def _figure(value: float) -> str:
    return f"{value:.3g}" if abs(value) < 1000 else f"{value:,.0f}"


def markdown_table(runs: Sequence[SizeRun]) -> str:
    """Per-point figures of each size, then each per-point figure over the size before's."""
    columns = list(runs[0].per_point()) if runs else []
    lines = [
        "| points | " + " | ".join(columns) + " |",
        "|---:|" + "---:|" * len(columns),
    ]
    for run in runs:
        cells = [_figure(v) for v in run.per_point().values()]
        lines.append(f"| {run.points:,} | " + " | ".join(cells) + " |")
    for small, large in itertools.pairwise(runs):
        a, b = small.per_point(), large.per_point()
        cells = []
        for column in columns:
            # MB is a total: its ratio is of MB per point, like the other columns.
            x = a[column] / (small.points if column == "MB" else 1)
            y = b[column] / (large.points if column == "MB" else 1)
            cells.append(f"{y / x:.2f}" if x > 0 else "n/a")
        lines.append(f"| ratio {large.points:,} / {small.points:,} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def rows(runs: Sequence[SizeRun]) -> list[dict]:
    """Rows of ``python -m benchmarks``: the targets at the largest (or 10,000-point) size,
    and the growth of the compute wall per point; the markdown table rides on the first."""
    small, large = runs[0], runs[-1]
    at_files = next((r for r in runs if r.points == FILES_AT), large)
    growth = large.compute_s / large.points / (small.compute_s / small.points)
    steps = ", ".join(
        f"{b.points:,}/{a.points:,}: {(b.compute_s / b.points) / (a.compute_s / a.points):.2f}"
        for a, b in itertools.pairwise(runs)
    )
    found = [
        {
            "benchmark": f"sweep overhead per point, {large.points:,} points, {large.workers} "
            f"workers / {OVERHEAD_TARGET_MS:g} ms",
            "ratio": large.overhead_ms / OVERHEAD_TARGET_MS,
            "target": "<= 1",
            "detail": f"{large.overhead_ms:.1f} ms/point: {large.compute_s:.0f} s wall "
            f"(submit {large.submit_s:.0f} s) - {large.busy_s:.0f} busy s / {large.workers}; "
            f"peak {large.peak_rss_mib:.0f} MiB here",
        },
        {
            "benchmark": f"cube assembly per point, {large.points:,} points / "
            f"{ASSEMBLE_TARGET_MS:g} ms",
            "ratio": large.assemble_s / large.points * 1e3 / ASSEMBLE_TARGET_MS,
            "target": "<= 1",
            "detail": f"{large.assemble_s:.1f} s; "
            + ", ".join(f"{r.points:,}: {r.assemble_s / r.points * 1e3:.2f} ms/pt" for r in runs),
        },
        {
            "benchmark": f"store files per point, {at_files.points:,} points / {FILES_TARGET:g}",
            "ratio": at_files.files / at_files.points / FILES_TARGET,
            "target": "<= 1",
            "detail": f"{at_files.files:,} files, {at_files.bytes / 1e6:.0f} MB "
            f"({at_files.disk_bytes / 1e6:.0f} MB on disk)",
        },
        {
            "benchmark": f"compute wall per point: {large.points:,} / {small.points:,} points",
            "ratio": growth,
            "target": f"<= {LINEAR_TARGET} (linear)",
            "detail": steps or "one size only",
        },
    ]
    found[0]["table"] = markdown_table(runs)
    return found


def sizes_from_env() -> tuple[int, ...]:
    text = os.environ.get(SIZES_ENV, "").strip()
    return tuple(int(n) for n in text.split(",")) if text else SIZES


def run(
    sizes: Sequence[int] | None = None, workers: int = WORKERS, tiny: bool = False
) -> list[dict]:
    """The rows; ``tiny``: :data:`TINY_SIZES` on one worker (module docstring)."""
    if tiny:
        return rows(measure(TINY_SIZES, workers=1))
    return rows(measure(sizes or sizes_from_env(), workers=workers))


def main(argv: Sequence[str] | None = None) -> None:
    parser = argparse.ArgumentParser(
        prog="python -m benchmarks.sweep_scale",
        description="Time planning, compute overhead and cube assembly per point at scale, "
        "with stand-ins for the science.",
    )
    parser.add_argument(
        "--sizes",
        type=int,
        nargs="+",
        help=f"grid sizes in points (default: ${SIZES_ENV} or {' '.join(str(n) for n in SIZES)})",
    )
    parser.add_argument("--workers", type=int, default=WORKERS, help="local worker processes")
    args = parser.parse_args(argv)
    for n in args.sizes or ():
        axis_lengths(n)  # refuse a bad size before the first one runs
    runs = measure(
        args.sizes or sizes_from_env(),
        workers=args.workers,
        progress=lambda line: print(line, flush=True),
    )
    print(markdown_table(runs))
    print(
        f"targets: overhead <= {OVERHEAD_TARGET_MS:g} ms/pt on {WORKERS} workers, assembly <= "
        f"{ASSEMBLE_TARGET_MS:g} ms/pt, <= {FILES_TARGET:g} files/pt at {FILES_AT:,} points; "
        "ratios near 1 are linear"
    )


if __name__ == "__main__":
    # Run as benchmarks.sweep_scale, not __main__: the workers import the plugin's class by that
    # name, where cloudpickle would otherwise copy this module's globals (a lock) by value.
    from benchmarks import sweep_scale

    sweep_scale.main()
