"""Where the signals come from: the value of a dataset (:mod:`~pipeline.recordings.recording_set`),
its sources, files or generated (:mod:`~pipeline.recordings.sources`,
:mod:`~pipeline.recordings.synthetic`), and whether a dataset is informative
(:mod:`~pipeline.recordings.touch_statistics`, :mod:`~pipeline.recordings.describe`).
"""
