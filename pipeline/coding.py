"""The public name of the rate coder, where outside checks import it: ``pipeline.coding``.

The coder itself lives in :mod:`pipeline.chain.coding` (the equations are in its docstring);
this module only re-exports the name that the architecture lists as a contract, so that
``from pipeline.coding import rate_code`` keeps working wherever the code moves. ``rate_code`` is
the sweeps' own coder (:func:`pipeline.chain.coding.frames`) applied to one train, so a check of
the contract checks what every sweep runs.
"""

from pipeline.chain.coding import rate_code

__all__ = ["rate_code"]
