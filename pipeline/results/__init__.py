"""What a sweep's points become: result cubes (:mod:`~pipeline.results.cube`, the names they are
read by in :mod:`~pipeline.results.variables`, one module per group of variables: out-of-fold
predictions, accuracy summaries, correlations, scene coordinates, provenance, and per feature
:mod:`~pipeline.results.chip_cube` and :mod:`~pipeline.results.decision_cube`), the statistics on
them (:mod:`~pipeline.results.stats`) and the readout energy model
(:mod:`~pipeline.results.hardware`); :mod:`pipeline.report` turns them into the report.
"""
