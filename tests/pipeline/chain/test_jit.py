"""Numba kernels compiled on first use: numba is not imported until a kernel runs, and kernels
that call kernels of their module run compiled."""

import subprocess
import sys

import numpy as np


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
