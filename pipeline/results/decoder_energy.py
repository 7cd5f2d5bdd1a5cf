r"""The decoder's energy per decision: the classifier, priced apart from the readout.

In the style of NeuroBench: a decision read at ``t`` seconds of touch has cost its decoder, on
average, ``AC(t)`` accumulates (effective synaptic operations whose input is a spike: nonzero inputs
times fan-out), ``MAC(t)`` multiply-accumulates (the same where the input is a real number, as the
rate-coded networks' counts and activations are) and ``NU(t)`` neuron updates, cumulative from the
touch's start (the cubes' ``decoder_acs``, ``decoder_macs``, ``decoder_neuron_updates``). Its energy
is a band, each operation priced at the low and at the high end of its declared range
(:class:`DecoderEnergyModel`, :func:`decoder_energy_j`):

.. math::

    E_\mathrm{low|high}(t) = \mathrm{AC}(t) \, e^\mathrm{AC}_\mathrm{low|high}
        + \mathrm{MAC}(t) \, e^\mathrm{MAC}_\mathrm{low|high}
        + \mathrm{NU}(t) \, e^\mathrm{NU}_\mathrm{low|high}

===================  ===============  =====================================================
operation            low - high       sources
===================  ===============  =====================================================
accumulate (AC)      12.7 - 23.6 pJ   ODIN (measured, 28 nm) - Loihi (pre-silicon, 14 nm)
multiply-acc. (MAC)  4.6 - 9.6 pJ     32-bit float arithmetic, alone - with a weight load
neuron update (NU)   52 - 81 pJ       Loihi, inactive - active neuron
===================  ===============  =====================================================

The per-synaptic-operation figures of the spiking chips include reading the synapse's weight;
the MAC's low end is the arithmetic alone (M. Horowitz, ISSCC 2014, 45 nm, 0.9 V: 3.7 pJ
multiply plus 0.9 pJ add, 32-bit float, the precision the rate-coded networks run in here), its
high end adds one 32-bit weight load, half a 64-bit read of an 8 kB SRAM (10 pJ) in the same
table. Neuron updates are priced at Loihi's for every model (a ReLU's update on a conventional
processor costs less: for the rate-coded networks the high end overstates). Not modelled: the
output's softmax, moving activations between layers, static power of the decoder's chip.

Each end of each band is a constant a designer's constants file can override
(``<operation>_low_j``, ``<operation>_high_j``, with its source:
:mod:`pipeline.results.hardware_constants`). Units: energies in J, counts per decision. The
readout's power and energy are in :mod:`pipeline.results.readout_power`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from pipeline.results.broadcast import plain

__all__ = [
    "DECODER_OPERATIONS",
    "HOROWITZ",
    "LOIHI",
    "ODIN",
    "DecoderEnergyModel",
    "EnergyBand",
    "OperationEnergy",
    "decoder_energy_j",
]

ODIN = "ODIN, C. Frenkel et al., IEEE TBioCAS 13(1), 2019, 28 nm, measured"
"""The low end of a synaptic operation's energy, 12.7 pJ (:class:`DecoderEnergyModel`)."""
LOIHI = "Loihi, M. Davies et al., IEEE Micro 38(1), 2018, 14 nm, pre-silicon figures"
"""The high end of a synaptic operation's energy, 23.6 pJ, and a neuron update's, 52 pJ for an
inactive and 81 pJ for an active neuron."""
HOROWITZ = "M. Horowitz, ISSCC 2014, 45 nm, 0.9 V"
"""The source of a multiply-accumulate's energy, with 3.7 pJ per 32-bit float multiply, 0.9 pJ
per add and 10 pJ per 64-bit read of an 8 kB SRAM."""


@dataclass(frozen=True)
class OperationEnergy:
    """The energy of one decoder operation as a band, ``low_j <= high_j`` (J), with what the
    operation is and where each end comes from.

    Raises
    ------
    ValueError
        An end is not a finite number >= 0, or ``low_j > high_j``.
    """

    low_j: float
    high_j: float
    what: str
    low_source: str
    high_source: str

    def __post_init__(self) -> None:
        ends = (self.low_j, self.high_j)
        if not all(
            isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) and v >= 0
            for v in ends
        ):
            raise ValueError(f"{self.what}: energies must be finite numbers >= 0, got {ends}")
        if self.low_j > self.high_j:
            raise ValueError(f"{self.what}: low {self.low_j!r} J above high {self.high_j!r} J")

    def sentence(self) -> str:
        """The band, what it prices and its sources, in one sentence."""
        return (
            f"{self.what}: {self.low_j * 1e12:.3g} pJ ({self.low_source}) to "
            f"{self.high_j * 1e12:.3g} pJ ({self.high_source})."
        )


@dataclass(frozen=True)
class DecoderEnergyModel:
    """Per-operation energies of a decoder (the classifier), each a band; defaults and sources
    in the module docstring.

    Attributes
    ----------
    ac : OperationEnergy
        An accumulate: a synaptic operation whose input is a spike. 12.7 pJ (:data:`ODIN`) to
        23.6 pJ (:data:`LOIHI`).
    mac : OperationEnergy
        A multiply-accumulate: a synaptic operation whose input is a real number, 32-bit float.
        4.6 pJ (arithmetic alone) to 9.6 pJ (with a 32-bit weight load), :data:`HOROWITZ`.
    neuron_update : OperationEnergy
        One neuron's state update. 52 pJ (inactive) to 81 pJ (active), :data:`LOIHI`.
    """

    ac: OperationEnergy = OperationEnergy(
        12.7e-12,
        23.6e-12,
        "accumulate (synaptic operation on a spike)",
        ODIN,
        LOIHI,
    )
    mac: OperationEnergy = OperationEnergy(
        4.6e-12,
        9.6e-12,
        "multiply-accumulate (synaptic operation on a real input, 32-bit float)",
        f"the arithmetic alone, a 3.7 pJ multiply and a 0.9 pJ add, {HOROWITZ}",
        f"with a 32-bit weight load, half a 10 pJ 64-bit read of an 8 kB SRAM, {HOROWITZ}",
    )
    neuron_update: OperationEnergy = OperationEnergy(
        52e-12,
        81e-12,
        "neuron update (priced alike for every model)",
        f"an inactive neuron, {LOIHI}",
        f"an active neuron, {LOIHI}",
    )

    def assumptions(self) -> tuple[str, ...]:
        """One sentence per operation (:data:`DECODER_OPERATIONS` order), with its band and
        sources."""
        return tuple(getattr(self, name).sentence() for name in DECODER_OPERATIONS)


#: The decoder's operations, as :class:`DecoderEnergyModel` names them, in the order
#: :func:`decoder_energy_j` takes their counts.
DECODER_OPERATIONS = ("ac", "mac", "neuron_update")


@dataclass(frozen=True)
class EnergyBand:
    """Energy of one decision at both ends of the per-operation bands, in J (floats, or arrays
    of one shape)."""

    low_j: Any
    high_j: Any


def decoder_energy_j(
    acs: Any, macs: Any, neuron_updates: Any, model: DecoderEnergyModel | None = None
) -> EnergyBand:
    """The decoder's energy per decision, low and high: operations times their energies.

    ``E = acs * e_ac + macs * e_mac + neuron_updates * e_nu`` at the low and at the high end of
    every band (see the module docstring).

    Parameters
    ----------
    acs, macs, neuron_updates : float or array-like
        Mean accumulates, multiply-accumulates and neuron updates per decision, >= 0; NaN where
        a count is unknown (a time the model decides nothing at) gives a NaN energy there. The
        three broadcast together.
    model : DecoderEnergyModel, optional
        The per-operation energies (default ``DecoderEnergyModel()``).

    Returns
    -------
    EnergyBand
        float64 J at each end, the inputs broadcast (Python floats for scalar inputs).

    Raises
    ------
    ValueError
        A count is not numeric, negative or infinite; the message names it.
    """
    model = DecoderEnergyModel() if model is None else model
    if not isinstance(model, DecoderEnergyModel):
        raise TypeError(f"model must be a DecoderEnergyModel, got {type(model).__name__}")
    counts = []
    for name, value in zip(DECODER_OPERATIONS, (acs, macs, neuron_updates), strict=True):
        values = np.asarray(value)
        if values.dtype.kind not in "iuf":
            raise ValueError(f"{name} counts must be numbers, got dtype {values.dtype}")
        values = values.astype(np.float64)
        bad = np.isinf(values) | (values < 0)
        if bad.any():
            raise ValueError(f"{name} counts must be finite and >= 0 (or NaN: unknown)")
        counts.append(values)
    ends = []
    for end in ("low_j", "high_j"):
        energy = sum(
            count * getattr(getattr(model, name), end)
            for name, count in zip(DECODER_OPERATIONS, counts, strict=True)
        )
        ends.append(plain(np.asarray(energy, dtype=np.float64)))
    return EnergyBand(*ends)
