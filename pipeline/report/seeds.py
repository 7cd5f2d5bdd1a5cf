"""The report's bootstrap generators: one fixed seed, and per comparison a generator derived from
it and the comparison's parts.

Every bootstrap draws from ``numpy.random.default_rng([REPORT_SEED, crc32(part), ...])`` with
the parts the compared result keys and the model (:func:`rng_for`), so a comparison gives the
same interval wherever the report shows it and in whatever order the report computes it.
"""

from __future__ import annotations

import zlib

import numpy as np

REPORT_SEED = 20_240_531
"""The report's fixed seed, the root of every bootstrap generator (:func:`rng_for`)."""


def rng_for(*parts: str) -> np.random.Generator:
    """The bootstrap generator of one comparison: ``default_rng([REPORT_SEED, crc32(part)...])``."""
    return np.random.default_rng([REPORT_SEED, *(zlib.crc32(p.encode("utf-8")) for p in parts)])
