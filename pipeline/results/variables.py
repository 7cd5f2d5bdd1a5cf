"""The names a result cube is read by: its dimensions and shared variables, each declared once, with
its units and long name (:data:`~pipeline.results.variables.SHARED_VARIABLES`), and imported by
every module that builds or reads a cube.

A feature's own names are declared beside its cube module: the ``chip`` dimension and the yield
statistics' units in :mod:`pipeline.results.chip_cube` (their names where they are computed,
:mod:`pipeline.results.yields`), the ``decision_s`` dimension and the decision variables in
:mod:`pipeline.results.decision_cube`; :data:`pipeline.results.cube.CUBE_VARIABLES`
gathers them all. The spike metrics are the fields of
:class:`~pipeline.chain.metrics.SpikeMetrics` (:data:`METRICS`), and the values a point's result
states beside them are declared on the results record (:data:`RESULT_VALUES`).
"""

from __future__ import annotations

import dataclasses

from pipeline.chain.metrics import SpikeMetrics

# Dimensions
#: The classifier.
MODEL_DIM = "model"
#: The cross-validation repeat.
REPEAT_DIM = "repeat"
#: The cross-validation fold.
FOLD_DIM = "fold"
#: The recording; its coordinate holds the names, the union of the points' recordings.
RECORDING_DIM = "recording"
#: The pipeline stage of ``seconds`` and ``work_seconds``: every step of the stage registry.
STAGE_DIM = "stage"
#: The dimension of ``seconds`` that says whom they were paid for
#: (:class:`~pipeline.run.records.Charge`).
CHARGE_DIM = "charge"
#: The spike metric a correlation is of.
METRIC_DIM = "metric"
#: The correlation coefficient (Pearson, Spearman).
COEFFICIENT_DIM = "coefficient"

# Variables and coordinates
ACCURACY = "accuracy"
ACCURACY_MEAN = "accuracy_mean"
ACCURACY_LOW = "accuracy_low"
ACCURACY_HIGH = "accuracy_high"
PREDICTED = "predicted"
CORRECT = "correct"
TEST_FOLD = "test_fold"
LABEL = "label"
SECONDS = "seconds"
WORK_SECONDS = "work_seconds"
CORRELATION_R = "correlation_r"
CORRELATION_P = "correlation_p"
CORRELATION_N = "correlation_n"
RESULT_KEY = "result_key"

#: The spike metrics, one cube variable each (axes...), in
#: :class:`~pipeline.chain.metrics.SpikeMetrics` field order.
METRICS = tuple(f.name for f in dataclasses.fields(SpikeMetrics))
#: ``units`` and ``long_name`` of the cube's own variables and coordinates that every cube may
#: have (a feature's own are declared beside its cube module).
SHARED_VARIABLES: dict[str, dict[str, str]] = {
    ACCURACY: {"units": "1", "long_name": "fraction of test recordings classified correctly"},
    ACCURACY_MEAN: {"units": "1", "long_name": "fraction of recordings classified correctly"},
    ACCURACY_LOW: {"units": "1", "long_name": "lower end of the 95 % interval of accuracy"},
    ACCURACY_HIGH: {"units": "1", "long_name": "upper end of the 95 % interval of accuracy"},
    PREDICTED: {"units": "1", "long_name": "out-of-fold predicted class (-1: none)"},
    CORRECT: {"units": "1", "long_name": "out-of-fold prediction correct (1, 0; -1: none)"},
    TEST_FOLD: {"units": "1", "long_name": "fold that tested the recording (-1: none)"},
    REPEAT_DIM: {"units": "1", "long_name": "cross-validation repeat"},
    RECORDING_DIM: {"units": "1", "long_name": "recording"},
    LABEL: {"units": "1", "long_name": "class index of the recording"},
    SECONDS: {
        "units": "s",
        "long_name": "wall time a worker paid computing the point, by stage and charge",
    },
    WORK_SECONDS: {
        "units": "s",
        "long_name": "wall time of the stage's work for the point, as measured when it ran",
    },
    CHARGE_DIM: {
        "units": "1",
        "long_name": "whom paid seconds were for: the point (own) or its worker's later points",
    },
    CORRELATION_R: {"units": "1", "long_name": "correlation of the metric with mean accuracy"},
    CORRELATION_P: {"units": "1", "long_name": "two-sided p-value of the correlation"},
    CORRELATION_N: {"units": "1", "long_name": "sweep points in the correlation"},
    MODEL_DIM: {"units": "1", "long_name": "classifier"},
    FOLD_DIM: {"units": "1", "long_name": "cross-validation fold"},
    STAGE_DIM: {"units": "1", "long_name": "pipeline stage"},
    METRIC_DIM: {"units": "1", "long_name": "spike metric correlated with accuracy"},
    COEFFICIENT_DIM: {"units": "1", "long_name": "correlation coefficient"},
    RESULT_KEY: {"units": "1", "long_name": "result cache key of the point"},
}
#: Per-point values the results store beside accuracy and metrics, as cube variables (axes...):
#: name -> the value where a point's result does not state it. Units and long names are those
#: of the results record's declaration (:data:`pipeline.run.stages.RESULTS`).
RESULT_VALUES: dict[str, int] = {"n_windows_used": -1}
#: The cube's measured variables, wall times; every other one is a deterministic function of
#: the grid and its seeds.
MEASURED = (SECONDS, WORK_SECONDS)
