"""Fill numba's disk cache with the kernels of the spikes level and the rate coder, once.

A process that finds a kernel in the cache loads it in milliseconds; one that does not compiles
it, several CPU-seconds for a module's kernels (:mod:`pipeline.jit`). Processes that start on an
empty cache at the same moment each compile the same kernels: on a fresh checkout, the first
``make test`` starts its test workers and dozens of sweep workers within a minute, and paid
about 50 s of its wall time for that (610 s against 560 s on a warm cache, 2 cores).
:func:`fill` compiles them once, ahead of such a start: the install runs ``python -m
pipeline.run.kernel_cache`` beside its bytecode compilation, and ``make test`` again before the
suite (a kernel whose source changed since is compiled there once); on a full cache it only
loads them (about 1 s, mostly imports).

What it calls: :func:`pipeline.run.encoding.warm_kernels`, the readout warm-up every point
runs, for each encoder (:class:`pipeline.design.scene.Encoder`) ideal, with each effect
(:class:`pipeline.design.effects.Effect`) alone and with all of them, so each kernel meets the
argument types a point's encoding gives it; then :func:`pipeline.chain.coding.frames` on a
tiny train. The spiking decoder's kernels are left to their first use: warming them needs
torch, whose import would cost every run more than the few processes that train that decoder
would save.
"""

from __future__ import annotations

import numpy as np

from pipeline.chain.coding import frames
from pipeline.chain.spikes import SpikeTrains
from pipeline.design.effects import Effect
from pipeline.design.scene import Encoder, Polarity, Scene
from pipeline.run.encoding import warm_kernels

__all__ = ["fill"]


def fill() -> int:
    """Run every readout kind's warm-up and the rate coder once; return the readout kinds run.

    Each warm-up loads its kernels from the cache or compiles them into it (numba's
    ``cache=True``: ``NUMBA_CACHE_DIR``, else beside the sources)."""
    base = Scene.builtin("smoke")
    effect_sets = [{}, *({effect.value: {}} for effect in Effect), {e.value: {} for e in Effect}]
    kinds = 0
    for encoder in Encoder:
        for effects in effect_sets:
            scene = base.replace(**{"readout.encoder": encoder, "readout.effects": effects})
            warm_kernels(scene.readout)
            kinds += 1
    trains = SpikeTrains(
        times_s=np.array([0.01, 0.25]),
        polarity=np.array([1, -1], dtype=np.int8),
        count=np.array([[1, 1]]),
        duration_s=np.array([0.3]),
    )
    frames(trains, 0.1, 2, Polarity.SPLIT)
    return kinds


if __name__ == "__main__":
    fill()
