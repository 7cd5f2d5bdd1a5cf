"""The chain bound to scenes: the stage registry (:mod:`~pipeline.run.stages`: each level, the
scene parts in its cache key, its compute function and timed steps), what each stored level keeps
(:mod:`~pipeline.run.records`) and one scene end to end in memory (:mod:`~pipeline.run.simulate`).
"""
