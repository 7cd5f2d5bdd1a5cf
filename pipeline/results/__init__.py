"""What a sweep's points become: result cubes (:mod:`~pipeline.results.cube`), the statistics
on them (:mod:`~pipeline.results.stats`) and the readout energy model
(:mod:`~pipeline.results.hardware`); :mod:`pipeline.report` turns them into the report.
"""
