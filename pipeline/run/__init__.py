"""The chain bound to scenes: the stage registry (:mod:`~pipeline.run.stages`: each level, the
scene parts in its cache key, its compute function and timed steps), the stopwatch the levels time
their steps on (:mod:`~pipeline.run.stopwatch`), the spikes level's encoding
(:mod:`~pipeline.run.encoding`), what each stored level keeps (:mod:`~pipeline.run.records`: the
declarations and shared codecs; :mod:`~pipeline.run.entries`: the spike and result entries), the
chips and decisions a point keeps (:mod:`~pipeline.run.chips`, :mod:`~pipeline.run.decisions`)
and one scene end to end in memory (:mod:`~pipeline.run.simulate`).
"""
