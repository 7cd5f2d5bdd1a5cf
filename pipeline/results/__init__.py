"""What a sweep's points become: result cubes (:mod:`~pipeline.results.cube`), the statistics
on them (:mod:`~pipeline.results.stats`), the readout's power
(:mod:`~pipeline.results.readout_power`, its constants in
:mod:`~pipeline.results.readout_constants`), the comparators' matched area
(:mod:`~pipeline.results.matched_area`) and the decoder's energy
(:mod:`~pipeline.results.decoder_energy`); :mod:`pipeline.report` turns them into the report.
"""
