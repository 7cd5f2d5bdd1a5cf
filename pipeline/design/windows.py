"""How many rate-coding windows a duration holds: the arithmetic a scene's ``coding`` is checked
with before any recording is read, and that the coder uses on the recordings.

Windows are half-open, ``[k * w, (k + 1) * w)`` with edges ``e_k = k * w``
(:func:`pipeline.chain.coding.window_edges_s`); ``K`` windows fit a duration ``T`` when
``K * w <= T``. ``n_windows = "auto"`` takes as many whole windows as every recording's taxel
signal holds, at most :data:`MAX_AUTO_WINDOWS` (the paper's 40 x 0.1 s = 4 s).
"""

from __future__ import annotations

import math

#: Most windows ``n_windows = "auto"`` takes (the paper's 40 x 0.1 s = 4 s).
MAX_AUTO_WINDOWS = 40


def whole_windows(duration_s: float, window_s: float) -> int:
    """How many whole windows of ``window_s`` (s) fit in ``duration_s`` (s): the largest ``K``
    with ``K * window_s <= duration_s``, 0 if none."""
    k = math.floor(duration_s / window_s) + 1
    while k > 0 and k * window_s > duration_s:  # floor division can round up across an edge
        k -= 1
    return k
