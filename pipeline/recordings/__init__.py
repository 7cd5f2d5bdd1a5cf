"""Where the signals come from: the value of a dataset (:mod:`~pipeline.recordings.recording_set`),
its sources, files or generated (:mod:`~pipeline.recordings.sources`,
:mod:`~pipeline.recordings.synthetic`, whose materials are :mod:`~pipeline.recordings.materials`
and whose touches :mod:`~pipeline.recordings.touch`), and whether a dataset is informative
(:mod:`~pipeline.recordings.touch_statistics`, :mod:`~pipeline.recordings.describe`).
"""
