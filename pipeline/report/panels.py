"""The paper's figures (panels) and the observation time, and which swept fields feed each.

The report's other figures (a curve for any other one-dimensional sweep, a heat map of a 2-D
sweep, the hardware cost fronts) are named by :mod:`pipeline.report.sweeps` and
:class:`pipeline.report.designs.Cost`.
"""

from __future__ import annotations

import enum

from pipeline.design.scene import Deployment, Model, scene_field

# The scene fields the report reads, by their dotted names (checked against the declarations).
THRESHOLD_V = scene_field("readout.threshold_v")
FULL_SCALE_V = scene_field("readout.full_scale_v")
MISMATCH_SIGMA_REL = scene_field("readout.effects.threshold_mismatch.sigma_rel")
WINDOW_S = scene_field("coding.window_s")
N_WINDOWS = scene_field("coding.n_windows")
ROWS = scene_field("array.rows")
COLS = scene_field("array.cols")
TAXELS = scene_field("array.taxels")
DATASET_KIND = scene_field("dataset.kind")
DATASET_PATH = scene_field("dataset.path")
REPEATS = scene_field("training.repeats")
#: How one classifier meets many chips (the scene's ``chips`` part; see
#: :mod:`pipeline.report.chip_population`).
DEPLOYMENT = scene_field("chips.deployment")


class Panel(enum.StrEnum):
    """One figure of the report; the value is its file stem."""

    THRESHOLD = "fig7a_threshold"
    WINDOW = "fig7b_window"
    TAXELS = "fig8_taxels"
    SPIKE_METRICS = "fig9_ssnr_ste"
    MISMATCH = "fig10_mismatch"
    OBSERVATION = "observation_time"


PANEL_TITLES = {
    Panel.THRESHOLD: "Fig. 7a: accuracy against the readout threshold",
    Panel.WINDOW: "Fig. 7b: accuracy against the window length",
    Panel.TAXELS: "Fig. 8: accuracy against the taxel count",
    Panel.SPIKE_METRICS: "Fig. 9: accuracy against SSNR and STE",
    Panel.MISMATCH: "Fig. 10: accuracy against threshold mismatch",
    Panel.OBSERVATION: "Accuracy against observation time",
}

# The swept fields (as sets) that make a one-dimensional cube feed a panel.
PANEL_FIELDS = {
    Panel.THRESHOLD: ({THRESHOLD_V},),
    Panel.WINDOW: ({WINDOW_S}, {WINDOW_S, N_WINDOWS}),
    Panel.TAXELS: ({ROWS}, {COLS}, {ROWS, COLS}),
    Panel.MISMATCH: ({MISMATCH_SIGMA_REL},),
    Panel.OBSERVATION: ({N_WINDOWS},),
}


def absent(panel: Panel) -> str:
    """Why ``panel`` has no data: the sweep it needs."""
    needs = {
        Panel.THRESHOLD: f"a sweep of {THRESHOLD_V}",
        Panel.WINDOW: f"a sweep of {WINDOW_S}",
        Panel.TAXELS: f"a sweep of {ROWS} / {COLS}",
        Panel.SPIKE_METRICS: "a sweep with correlate = true",
        Panel.MISMATCH: f"a sweep of {MISMATCH_SIGMA_REL}",
        Panel.OBSERVATION: f"a sweep of {N_WINDOWS} alone",
    }
    return f"not in this run: it needs {needs[panel]}"


DECLARED = {
    "model": tuple(m.value for m in Model),
    "deployment": tuple(d.value for d in Deployment),
}
"""The categories a figure draws as panels or series, each in its declared order (the models as
:class:`~pipeline.design.scene.Model` declares them, the chips' deployments as
:class:`~pipeline.design.scene.Deployment` does)."""


def declared_rank(kind: str, value: str) -> int:
    """Where ``value`` comes among the categories of ``kind`` (``"model"``, ``"deployment"``) in
    a figure: its place in the declaration (:data:`DECLARED`), never alphabetical; a value the
    declaration does not name comes after every one it names (sort stably to keep such values
    in the order met)."""
    declared = DECLARED[kind]
    return declared.index(value) if value in declared else len(declared)
