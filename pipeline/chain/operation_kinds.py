"""The kinds of operation a decoder's decision is counted in (:mod:`pipeline.chain.operations`).

Declared apart from the counting, which needs torch: result cubes name a variable after each
kind, and a sweep's coordinating process builds cubes without ever training, so it need not pay
torch's import (about a second).
"""

__all__ = ["OPERATIONS"]

#: The kinds of operation counted, in the order of
#: :meth:`pipeline.chain.operations.Operations.stacked`: accumulates, multiply-accumulates and
#: neuron updates.
OPERATIONS = ("acs", "macs", "neuron_updates")
