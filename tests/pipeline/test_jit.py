"""Numba kernels compiled on first use: numba is not imported until a kernel runs, and kernels
that call kernels of their module run compiled."""

import subprocess
import sys

import numpy as np
import pytest

from pipeline.design.effects import Effect
from pipeline.design.scene import Encoder


def test_planning_a_sweep_imports_no_numba_and_a_kernel_call_does():
    code = (
        "import sys\n"
        "import flows.cli, flows.sweep, flows.assembly, flows.dry_run, pipeline.run.stages\n"
        "assert 'numba' not in sys.modules, 'numba imported without a kernel call'\n"
        "from pipeline.chain import coding\n"
        "counts, dropped = coding.rate_code([0.05, 0.15, 0.16, 0.5], 0.1, 3)\n"
        "assert counts.tolist() == [1, 2, 0] and dropped == 1, (counts, dropped)\n"
        "import numba\n"
        "assert isinstance(coding._count_sorted, numba.core.registry.CPUDispatcher)\n"
        "assert isinstance(coding._count_trains, numba.core.registry.CPUDispatcher)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr


def test_a_kernel_calling_a_kernel_runs_compiled_from_any_reference():
    from pipeline.chain import coding, spikes

    held = coding._count_trains  # a reference taken before or after compiling works alike
    trains = spikes.SpikeTrains(
        times_s=np.array([0.01, 0.02, 0.25, 0.05]),
        polarity=np.array([1, -1, 1, 1], dtype=np.int8),
        count=np.array([[3, 1]]),
        duration_s=np.array([0.3]),
    )
    counts, dropped = coding.frames(trains, 0.1, 2, coding.Polarity.SPLIT)
    assert counts[0, :, 0].tolist() == [[1, 0], [1, 0]]
    assert counts[0, :, 1].tolist() == [[1, 0], [0, 0]]
    assert dropped.tolist() == [[1, 0]]
    out = np.zeros((2, 2), dtype=np.int64)
    held(
        trains.times_s[:1],
        trains.polarity[:1],
        np.array([1, 0]),
        False,
        np.array([0.0, 0.1, 0.2]),
        out,
        np.zeros(2, dtype=np.int64),
    )
    assert out.tolist() == [[1, 0], [0, 0]]


# A second process finds the kernels in the disk cache: numba's own dispatcher statistics say
# whether each signature was loaded (a cache hit) or compiled (a miss); no timing. The process
# fills the cache as ``make test`` does before the suite (every readout kind and the rate coder).
_WARM_AND_COUNT = (
    "import json\n"
    "import numba\n"
    "from pipeline.chain import coding, metrics, readout, readout_effects\n"
    "from pipeline.run.kernel_cache import fill\n"
    "kinds = fill()\n"
    "hits = misses = 0\n"
    "for module in (readout, readout_effects, metrics, coding):\n"
    "    for kernel in vars(module).values():\n"
    "        if isinstance(kernel, numba.core.registry.CPUDispatcher):\n"
    "            hits += sum(kernel.stats.cache_hits.values())\n"
    "            misses += sum(kernel.stats.cache_misses.values())\n"
    "print(json.dumps({'kinds': kinds, 'hits': hits, 'misses': misses}))\n"
)


def _warm_in_a_new_process(cache_dir):
    import json
    import os

    env = os.environ | {"NUMBA_CACHE_DIR": str(cache_dir)}
    done = subprocess.run(
        [sys.executable, "-c", _WARM_AND_COUNT], capture_output=True, text=True, env=env
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.splitlines()[-1])


def test_a_second_process_finds_the_kernels_cached(tmp_path):
    cache = tmp_path / "numba"
    first = _warm_in_a_new_process(cache)
    # Every encoder: ideal, with each effect alone, with all of them.
    assert first["kinds"] == len(Encoder) * (1 + len(Effect) + 1)
    assert first["misses"] > 0 and first["hits"] == 0  # an empty cache: compiled
    assert list(cache.rglob("*.nbi")) and list(cache.rglob("*.nbc"))  # index and code files
    second = _warm_in_a_new_process(cache)
    # Every kernel called from Python loaded, none compiled (kernels that only other kernels
    # call are compiled into them, and cached with them).
    assert second["misses"] == 0 and 0 < second["hits"] <= first["misses"]


def test_the_kernels_are_warmed_once_per_process_and_kind():
    from pipeline import jit

    calls = []
    jit.once(("test", 1), lambda: calls.append(1))
    jit.once(("test", 1), lambda: calls.append(2))
    jit.once(("test", 2), lambda: calls.append(3))
    assert calls == [1, 3]


def test_a_failed_warm_up_is_tried_again():
    from pipeline import jit

    def fail():
        raise RuntimeError("no")

    with pytest.raises(RuntimeError):
        jit.once(("test", "fails"), fail)
    calls = []
    jit.once(("test", "fails"), lambda: calls.append(1))
    assert calls == [1]
