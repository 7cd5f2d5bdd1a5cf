"""The public name of the readout, where outside checks import it: ``pipeline.readout``.

The encoder itself lives in :mod:`pipeline.chain.readout` (the equations are in its docstring);
this module only re-exports the names that the architecture lists as contracts, so that
``from pipeline.readout import level_crossings`` keeps working wherever the code moves.
A new public readout function is added to the list below, not copied here.
"""

from pipeline.chain.readout import decaying_crossings, level_crossings

__all__ = ["decaying_crossings", "level_crossings"]
