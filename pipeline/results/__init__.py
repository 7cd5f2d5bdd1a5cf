"""What a sweep's points become: result cubes (:mod:`~pipeline.results.cube`, the names they are
read by in :mod:`~pipeline.results.variables`, one module per group of variables: out-of-fold
predictions, accuracy summaries, correlations, scene coordinates, provenance, and per feature
:mod:`~pipeline.results.chip_cube` and :mod:`~pipeline.results.decision_cube`), the statistics on
them (:mod:`~pipeline.results.stats`; the recordings a paired test needs,
:mod:`~pipeline.results.sample_size`), the readout's power (:mod:`~pipeline.results.readout_power`,
its constants in :mod:`~pipeline.results.readout_constants`), the comparators' matched area
(:mod:`~pipeline.results.matched_area`) and the decoder's energy
(:mod:`~pipeline.results.decoder_energy`); :mod:`pipeline.report` turns them into the report.
"""
