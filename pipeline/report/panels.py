"""The paper's figures (panels) and the observation time, and which swept fields feed each.

The report's other figures (a curve for any other one-dimensional sweep, a heat map of a 2-D
sweep, the hardware cost fronts) are named by :mod:`pipeline.report.sweeps` and
:class:`pipeline.report.designs.Cost`.
"""

from __future__ import annotations

import enum


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
    Panel.THRESHOLD: ({"readout.threshold_v"},),
    Panel.WINDOW: ({"coding.window_s"}, {"coding.window_s", "coding.n_windows"}),
    Panel.TAXELS: ({"array.rows"}, {"array.cols"}, {"array.rows", "array.cols"}),
    Panel.MISMATCH: ({"readout.effects.threshold_mismatch.sigma_rel"},),
    Panel.OBSERVATION: ({"coding.n_windows"},),
}


def absent(panel: Panel) -> str:
    """Why ``panel`` has no data: the sweep it needs."""
    needs = {
        Panel.THRESHOLD: "a sweep of readout.threshold_v",
        Panel.WINDOW: "a sweep of coding.window_s",
        Panel.TAXELS: "a sweep of array.rows / array.cols",
        Panel.SPIKE_METRICS: "a sweep with correlate = true",
        Panel.MISMATCH: "a sweep of readout.effects.threshold_mismatch.sigma_rel",
        Panel.OBSERVATION: "a sweep of coding.n_windows alone",
    }
    return f"not in this run: it needs {needs[panel]}"
