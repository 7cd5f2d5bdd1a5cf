"""Planning a sweep: load, check and plan grids of 1,000, 10,000 and 100,000 points.

What ``eskin sweep`` does before any point is computed, timed as the user meets it: the
command line loads the grid once and checks it against its recordings
(:func:`flows.planning.check_grid`), then the flow opens the root and plans the checked grid
(:func:`flows.planning.plan_sweep`: distinct points by key, cached entries) on an empty store.
Each grid is a product of five axes over the ``paper`` scene (threshold, window, taxel rows,
threshold mismatch, training seed), the same sweep at every size.

Rows: the 100,000-point plan against its absolute target (10 s on 2 cores); the cost per point
at 100,000 over that at 1,000 (linear growth keeps it near 1); and, side by side in this
process on 1,000 points, the straightforward way (``Scene.replace``, the whole canonical form
and the fit check at every point) over the shared-parts path, after checking that both give the
same points and keys. Medians of 3 runs.

Scale rows: 100,000 and 1,000,000 points (:data:`SCALE_SIZES`), each planned in a fresh process
(``python -m benchmarks.planning --one N``) so that its peak memory is its own: the time per
point (CPU seconds of the process, which a busy machine does not inflate as it does wall time;
wall time in the detail) and the peak resident memory per point above the process's before it
plans (on Linux the peak is reset then, after the imports: :func:`reset_peak_memory`), at
1,000,000 over 100,000 (linear: at most 1.5). Medians of 3 processes.

``run(tiny=True)`` plans 1,000 and 10,000 points (:data:`TINY_SIZES`; the absolute target scaled
to 10,000 points) and scales 10,000 to 100,000 (:data:`TINY_SCALE_SIZES`: fewer points can fit
in the memory the imports freed, and need none more), one run of each.

``python -m benchmarks.planning`` runs this suite alone and prints its rows and the seconds of
each phase at 100,000 points; ``--scale`` runs the scale rows alone.
"""

from __future__ import annotations

import contextlib
import dataclasses
import hashlib
import json
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

from benchmarks.timing import median_seconds
from flows.planning import check_grid, load_sweep_grid, open_root, plan_sweep
from pipeline.design import fields
from pipeline.design.grid import Grid, load_grid
from pipeline.design.scene import MODEL_REVISION, Scene
from pipeline.run.fit import DatasetLimits, check_scene_fits
from pipeline.run.grid_keys import unique_points
from pipeline.run.stages import RECORDINGS, RESULTS, Level

SIZES = (1_000, 10_000, 100_000)
#: The sizes of ``run(tiny=True)``.
TINY_SIZES = (1_000, 10_000)
REPEAT = 3
#: Seconds to plan and check :data:`TARGET_POINTS` points (a smaller size: its share, linearly).
TARGET_S = 10.0
TARGET_POINTS = 100_000
LINEAR_TARGET = 1.5
BASELINE_POINTS = 1_000
THRESHOLDS_V = [0.01, 0.02, 0.03, 0.05, 0.07, 0.09, 0.12, 0.15, 0.2, 0.25]
WINDOWS_S = [0.025, 0.05, 0.075, 0.1, 0.125, 0.15, 0.2, 0.25, 0.3, 0.4]
ROWS = list(range(1, 11))  # 10 rows at 1 mm, 20 mm/s: 0.45 s of delays, 4.5 s left of 5 s
MISMATCH_REL = [0.0, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.5]


def grid_text(n_points: int) -> str:
    """A grid TOML of ``n_points`` (1,000 times a power of ten up to 1,000,000) on ``paper``."""
    mismatch = MISMATCH_REL if n_points >= 10_000 else MISMATCH_REL[1:2]
    seeds = list(range(n_points // 10_000)) if n_points >= 100_000 else [0]
    axes = {
        "readout.threshold_v": THRESHOLDS_V,
        "coding.window_s": WINDOWS_S,
        "array.rows": ROWS,
        "readout.effects.threshold_mismatch.sigma_rel": mismatch,
        "training.seed": seeds,
    }
    lines = [f'name = "plan{n_points}"', 'base = "paper"', "[sweeps.big.axes]"]
    lines += [f'"{field}" = {json.dumps(values)}' for field, values in axes.items()]
    return "\n".join(lines) + "\n"


def sweep_before_work(grid_path: str, root: str) -> int:
    """What ``eskin sweep`` does before computing: load and check, open the root, plan.

    Returns the number of distinct points planned.
    """
    grid = load_sweep_grid(grid_path)
    check_grid(grid)
    store = open_root(grid, root)
    return len(plan_sweep(grid, store.root).scenes)


def reference_key(scene: Scene, level: Level) -> str:
    """A level's key from the canonical form of the whole scene written at once.

    The whole form leaves out what the field declarations leave out of every key (labels, a
    field at a neutral default, a part kept only with a sibling's value); the level's
    :meth:`~pipeline.run.stages.Level.key_parts` then select what it reads.
    """
    data = fields.plain(scene, canonical=True)
    canonical = json.dumps(
        fields.select(data, level.key_parts(scene)),
        sort_keys=True,
        separators=(",", ":"),
        allow_nan=False,
    )
    text = f"r{MODEL_REVISION}:{level.name}:{canonical}"
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def reference_plan(grid: Grid) -> dict[str, Scene]:
    """The baseline: every point built with ``Scene.replace``, its keys from the whole
    canonical form, its fit checked on its own; the distinct scenes by result key."""
    limits: dict[str, DatasetLimits] = {}
    unique: dict[str, Scene] = {}
    for sweep in grid.sweeps:
        for _, values in sweep.index_values():
            scene = grid.base.replace(**{**sweep.fixed, **values})
            recordings = reference_key(scene, RECORDINGS)
            if recordings not in limits:
                limits[recordings] = DatasetLimits.describe(scene.dataset)
            check_scene_fits(scene, limits[recordings])
            unique.setdefault(reference_key(scene, RESULTS), scene)
    return unique


def shared_parts_plan(grid: Grid) -> dict[str, Scene]:
    """The same from a fresh copy of ``grid`` (nothing cached): check, then distinct points."""
    fresh = dataclasses.replace(grid)
    check_grid(fresh)
    return unique_points(fresh)


def timed(function: Callable[[], object]) -> float:
    start = time.perf_counter()
    function()
    return time.perf_counter() - start


def phases(grid_path: str, root: str) -> dict[str, float]:
    """Seconds of each planning phase of one grid, in the order a sweep meets them."""
    seconds = {}
    start = time.perf_counter()
    grid = load_grid(grid_path)
    seconds["load_grid"] = time.perf_counter() - start
    seconds["points()"] = timed(grid.points)
    seconds["check_grid"] = timed(lambda: check_grid(grid))
    seconds["unique_points()"] = timed(lambda: unique_points(grid))
    store = open_root(grid, root)
    seconds["plan_sweep"] = timed(lambda: plan_sweep(grid, store.root))
    return seconds


def measure(folder: Path, repeat: int = REPEAT, sizes: tuple[int, ...] = SIZES) -> dict:
    """Medians of the sweep-before-work time per size, the baseline pair, phases at the most."""
    paths = {}
    for n in sizes:
        paths[n] = folder / f"plan{n}.toml"
        paths[n].write_text(grid_text(n))
    seconds = {}
    for n in sizes:
        runs = []
        for i in range(repeat):
            root = str(folder / f"root{n}-{i}")
            start = time.perf_counter()
            planned = sweep_before_work(str(paths[n]), root)
            runs.append(time.perf_counter() - start)
            if planned != n:
                raise RuntimeError(f"{paths[n]} planned {planned} distinct points, not {n}")
        seconds[n] = statistics.median(runs)
    grid = load_grid(str(paths[BASELINE_POINTS]))
    if list(shared_parts_plan(grid).items()) != list(reference_plan(grid).items()):
        raise RuntimeError("the shared-parts plan and the Scene.replace baseline differ")
    ours_s, baseline_s = median_seconds(
        lambda: shared_parts_plan(grid), lambda: reference_plan(grid), repeat=repeat
    )
    return {
        "seconds": seconds,
        "ours_s": ours_s,
        "baseline_s": baseline_s,
        "phases": phases(str(paths[sizes[-1]]), str(folder / "phases")),
        "peak_rss_mib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
    }


SCALE_SIZES = (100_000, 1_000_000)
TINY_SCALE_SIZES = (10_000, 100_000)


def reset_peak_memory() -> None:
    """Start this process's peak resident memory (:func:`peak_memory_mib`) afresh from what it
    holds now, so that a later peak is that of the work since, not of the imports before
    (Linux: ``/proc/self/clear_refs``; elsewhere the peak stays the process's)."""
    with contextlib.suppress(OSError):
        Path("/proc/self/clear_refs").write_text("5")


def peak_memory_mib() -> float:
    """This process's peak resident memory (MiB) since it started or since
    :func:`reset_peak_memory`: Linux's ``VmHWM``, where ``ru_maxrss`` would also count the
    memory of the parent that started this process (it carries over the fork); ``ru_maxrss``
    elsewhere."""
    with contextlib.suppress(OSError):
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def plan_in_process(n_points: int, folder: Path) -> dict[str, float]:
    """Plan an ``n_points`` grid as :func:`sweep_before_work` does, in this process: wall and
    CPU seconds, peak resident memory and the memory before planning (MiB)."""
    path = folder / f"plan{n_points}.toml"
    path.write_text(grid_text(n_points))
    reset_peak_memory()
    before_mib = peak_memory_mib()
    wall, cpu = time.perf_counter(), time.process_time()
    planned = sweep_before_work(str(path), str(folder / f"root{n_points}"))
    wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    if planned != n_points:
        raise RuntimeError(f"{path} planned {planned} distinct points, not {n_points}")
    peak_mib = peak_memory_mib()
    return {"wall_s": wall, "cpu_s": cpu, "peak_mib": peak_mib, "before_mib": before_mib}


def plan_in_fresh_process(n_points: int) -> dict[str, float]:
    """:func:`plan_in_process` in a new Python process (its peak memory its own)."""
    with tempfile.TemporaryDirectory(prefix="eskin-plan-") as folder:
        done = subprocess.run(
            [sys.executable, "-m", "benchmarks.planning", "--one", str(n_points), folder],
            check=True,
            capture_output=True,
            text=True,
        )
    return json.loads(done.stdout.splitlines()[-1])


def scale_rows(repeat: int = REPEAT, points: tuple[int, int] = SCALE_SIZES) -> list[dict]:
    """Time and peak memory per point at 1,000,000 points over 100,000 (module docstring), or at
    the larger of ``points`` over the smaller."""
    runs = {n: [plan_in_fresh_process(n) for _ in range(repeat)] for n in points}
    figures = {}
    for n, found in runs.items():
        figures[n] = {
            "cpu_us": statistics.median(r["cpu_s"] for r in found) / n * 1e6,
            "wall_us": statistics.median(r["wall_s"] for r in found) / n * 1e6,
            # At least the resolution of the figure (1 KiB): a plan may fit in memory already
            # held.
            "peak_b": statistics.median(
                max(r["peak_mib"] - r["before_mib"], 2**-10) * 2**20 for r in found
            )
            / n,
            "peak_mib": statistics.median(r["peak_mib"] for r in found),
        }
    small, large = (figures[n] for n in points)
    sizes = "; ".join(
        f"{n:,}: {f['cpu_us']:.1f} us CPU ({f['wall_us']:.1f} wall), "
        f"{f['peak_b']:.0f} B per point (peak {f['peak_mib']:.0f} MiB)"
        for n, f in figures.items()
    )
    return [
        {
            "benchmark": f"plan+check time per point: {points[1]:,} / {points[0]:,}",
            "ratio": large["cpu_us"] / small["cpu_us"],
            "target": f"<= {LINEAR_TARGET} (linear)",
            "detail": sizes,
        },
        {
            "benchmark": f"plan+check peak memory per point: {points[1]:,} / {points[0]:,}",
            "ratio": large["peak_b"] / small["peak_b"],
            "target": f"<= {LINEAR_TARGET} (linear)",
            "detail": "peak resident memory above the process's before it plans",
        },
    ]


def rows(found: dict) -> list[dict]:
    seconds = found["seconds"]
    per_point_us = {n: s / n * 1e6 for n, s in seconds.items()}
    measured = list(seconds)
    small, middle, large = measured[0], measured[-2], measured[-1]
    target_s = TARGET_S * large / TARGET_POINTS
    sizes = ", ".join(
        f"{n:,}: {seconds[n]:.2f} s ({per_point_us[n]:.0f} us/point)" for n in measured
    )
    return [
        {
            "benchmark": f"plan+check {large:,} points / {target_s:g} s",
            "ratio": seconds[large] / target_s,
            "target": "<= 1",
            "detail": f"{sizes}; peak {found['peak_rss_mib']:.0f} MiB",
        },
        {
            "benchmark": f"plan+check per point: {large:,} / {small:,} points",
            "ratio": per_point_us[large] / per_point_us[small],
            "target": f"<= {LINEAR_TARGET} (linear)",
            "detail": f"{per_point_us[small]:.0f} us/point at {small:,} (fixed costs "
            f"included), {per_point_us[large]:.0f} us/point at {large:,}; "
            f"{large:,} / {middle:,}: {per_point_us[large] / per_point_us[middle]:.2f}",
        },
        {
            "benchmark": "check+distinct points: Scene.replace per point / shared parts",
            "ratio": found["baseline_s"] / found["ours_s"],
            "target": ">= 10",
            "detail": f"{BASELINE_POINTS:,} points: {found['ours_s'] * 1e3:.0f} ms vs "
            f"{found['baseline_s'] * 1e3:.0f} ms",
        },
    ]


def run(repeat: int = REPEAT, tiny: bool = False) -> list[dict]:
    """The rows; ``tiny``: the tiny sizes, one run of each (module docstring)."""
    if tiny:
        return run_sizes(1, TINY_SIZES, TINY_SCALE_SIZES)
    return run_sizes(repeat, SIZES, SCALE_SIZES)


def run_sizes(repeat: int, sizes: tuple[int, ...], scale_sizes: tuple[int, int]) -> list[dict]:
    """The plan rows at ``sizes`` and the scale rows at ``scale_sizes``, ``repeat`` runs each."""
    with tempfile.TemporaryDirectory(prefix="eskin-plan-") as folder:
        plan = rows(measure(Path(folder), repeat, sizes))
    return plan + scale_rows(repeat, scale_sizes)


def main() -> None:
    if sys.argv[1:2] == ["--one"]:
        print(json.dumps(plan_in_process(int(sys.argv[2]), Path(sys.argv[3]))))
        return
    if sys.argv[1:2] == ["--scale"]:
        for r in scale_rows():
            print(f"{r['benchmark']}  {r['ratio']:.2f}  {r['target']}; {r['detail']}")
        return
    with tempfile.TemporaryDirectory(prefix="eskin-plan-") as folder:
        found = measure(Path(folder))
    table = rows(found)
    width = max(len(r["benchmark"]) for r in table)
    print(f"{'benchmark':{width}s}  {'ratio':>8s}  target / detail")
    for r in table:
        print(f"{r['benchmark']:{width}s}  {r['ratio']:8.2f}  {r['target']}; {r['detail']}")
    print(f"phases at {SIZES[-1]:,} points (s):")
    for name, seconds in found["phases"].items():
        print(f"  {name:16s} {seconds:6.2f}")


if __name__ == "__main__":
    main()
