"""The model chain, in the order the data flows: front-end scaling
(:mod:`~pipeline.chain.frontend`), taxel signals (:mod:`~pipeline.chain.taxels`), the
level-crossing readout (:mod:`~pipeline.chain.readout`, with the readout's effects in
:mod:`~pipeline.chain.readout_effects`) and its spike trains
(:mod:`~pipeline.chain.spikes`), spike-train metrics (:mod:`~pipeline.chain.metrics`), rate coding
(:mod:`~pipeline.chain.coding`), the classifiers (:mod:`~pipeline.chain.models`) and their
cross-validated training (:mod:`~pipeline.chain.training`).
"""
