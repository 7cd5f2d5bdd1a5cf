"""Decisions along the touch, by hand, on the cubes of :mod:`tests.report_helpers` (no training).

:func:`with_decisions` adds the decision variables a cube keeps for models read at several
times of the touch: ``decision_s`` (:data:`TIMES`), ``decision_correct``,
``decision_confidence`` (axes..., model, decision_s, repeat, recording) and the operation counts
``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates`` (axes..., model, decision_s).

At the full touch (the last time) every model's decisions are the cube's out-of-fold ones
(``correct``). At time ``k`` a model is right on the first ``round(FRACTIONS[k] * k_full)`` of
the recordings it gets right at the full touch (nested, as the cubes' points are), wrong on the
rest. The rate-coded model (``ffnn``) decides only at its window boundaries,
:data:`BOUNDARIES`, -1 at the other times; the other decides at every time. A right decision's
confidence is :data:`RIGHT_CONFIDENCE` at each time, a wrong one's :data:`WRONG_CONFIDENCE`.
Operations per decision: the ``ffnn`` :data:`FFNN_MACS` multiply-accumulates per second of
touch and :data:`FFNN_UPDATES` neuron updates, the other :data:`SPIKING_ACS` accumulates and
:data:`SPIKING_UPDATES` neuron updates per second (NaN where a model does not decide).
"""

import numpy as np
import xarray as xr

from pipeline.report.cubes import sweep_dims

TIMES = np.array([0.25, 0.5, 0.75, 1.0])
FRACTIONS = (0.5, 0.8, 0.97, 1.0)
BOUNDARIES = (1, 3)  # ffnn decides at 0.5 s and 1.0 s
RIGHT_CONFIDENCE = np.array([0.6, 0.8, 0.92, 0.99])
WRONG_CONFIDENCE = 0.4
FFNN_MACS, FFNN_UPDATES = 4000.0, 100.0
SPIKING_ACS, SPIKING_UPDATES = 800.0, 400.0


def with_decisions(cube: xr.Dataset, operations: bool = True) -> xr.Dataset:
    """``cube`` with decision variables (see the module docstring); ``operations=False`` leaves
    out the operation counts."""
    dims = sweep_dims(cube)
    full = cube["correct"].transpose(*dims, "model", "repeat", "recording").values
    right = full == 1
    rank = np.cumsum(right, axis=-1)
    k_full = right.sum(axis=-1, keepdims=True)
    steps = [
        np.where(full < 0, -1, (right & (rank <= np.round(f * k_full))).astype(np.int8))
        for f in FRACTIONS
    ]
    correct = np.stack(steps, axis=-3).astype(np.int8)  # (..., model, time, repeat, recording)
    models = [str(m) for m in cube["model"].values]
    ffnn = models.index("ffnn") if "ffnn" in models else None
    if ffnn is not None:
        others = [k for k in range(TIMES.size) if k not in BOUNDARIES]
        correct[..., ffnn, others, :, :] = -1
    confidence = np.where(
        correct == 1,
        RIGHT_CONFIDENCE[:, np.newaxis, np.newaxis],
        np.where(correct == 0, WRONG_CONFIDENCE, np.nan),
    ).astype(np.float32)
    order = (*dims, "model", "decision_s", "repeat", "recording")
    out = cube.assign_coords(decision_s=("decision_s", TIMES, {"units": "s"})).assign(
        decision_correct=(order, correct),
        decision_confidence=(order, confidence),
    )
    if not operations:
        return out
    shape = (*correct.shape[:-2],)  # (..., model, time)
    acs, macs, updates = (np.zeros(shape) for _ in range(3))
    for m, model in enumerate(models):
        if model == "ffnn":
            macs[..., m, :] = FFNN_MACS * TIMES
            updates[..., m, :] = FFNN_UPDATES
            acs[..., m, :] = 0.0
        else:
            acs[..., m, :] = SPIKING_ACS * TIMES
            updates[..., m, :] = SPIKING_UPDATES * TIMES
    decided = (correct >= 0).any(axis=(-2, -1))
    counts = {
        name: np.where(decided, values, np.nan)
        for name, values in (
            ("decoder_acs", acs),
            ("decoder_macs", macs),
            ("decoder_neuron_updates", updates),
        )
    }
    return out.assign({name: ((*dims, "model", "decision_s"), v) for name, v in counts.items()})
