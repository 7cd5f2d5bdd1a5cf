"""The paper's numbers, in one place: its operating point, its claims and its Table I.

Source: the paper, "End-to-End Optimization of High-Density e-Skin Design: From Spiking Taxel
Readout to Texture Classification": its text, its figures' claims and its Table I. Nothing here is
this project's own result; the report cites every number below as the paper's. Where the paper
gives only a plot, there is no number here.
"""

from __future__ import annotations

from dataclasses import dataclass

# Operating point and claims, by the paper's figure that makes each.
THRESHOLD_V = 0.09  # 7a: optimum near 0.09 V for both networks
THRESHOLD_BITS = 3.5  # 7a: "about 3.5 equivalent bits"
WINDOW_S = 0.1  # 7b: optimum at 0.1 s for both networks
TAXEL_GAIN = 0.63  # 8: accuracy rises by 63 % from 1 to 16 taxels (FFNN)
TAXELS = (1, 16)
SATURATION_ACCURACY = 0.90  # 8: saturates above 16 taxels at about 90 %
CNN_ACCURACY = 0.90  # abstract: CNN 90 % at 3.5 bits with rate coding
FRAME_RATIO_ORDERS = 3  # abstract: data rate up to three orders of magnitude below frames
DATA_RATE_HZ = 51.32  # Table I: the paper's own "estimated data rate"

CLAIMS = {
    "threshold": f"the optimum threshold near {THRESHOLD_V:g} V for both networks (about "
    f"{THRESHOLD_BITS:g} equivalent bits)",
    "threshold_lower": "that thresholds below the optimum lose accuracy again",
    "window": f"the optimum window at {WINDOW_S:g} s for both networks",
    "window_sides": "that shorter and longer windows lose accuracy",
    "taxel_gain": f"accuracy rising by {TAXEL_GAIN:.0%} from {TAXELS[0]} to {TAXELS[1]} taxels "
    "(FFNN)",
    "taxel_saturation": f"accuracy saturating above {TAXELS[1]} taxels (at about "
    f"{SATURATION_ACCURACY:.0%})",
    "metrics": "a strong positive correlation of accuracy with SSNR and a strong negative one "
    "with STE (one taxel, constant threshold)",
    "mismatch": "accuracy falling as the threshold mismatch between taxels grows",
    "frame_ratio": "a data rate up to three orders of magnitude below a frame-based readout",
}


@dataclass(frozen=True)
class ClaimRow:
    """One claim as the report's claims table names it: the paper's figure that makes it, the
    claim in a few words and the paper's own figure for it ("plot only" where the paper gives
    no number)."""

    figure: str
    claim: str
    value: str


CLAIM_ROWS = {
    "threshold": ClaimRow(
        "Fig. 7a",
        "optimum threshold",
        f"{THRESHOLD_V:g} V ({THRESHOLD_BITS:g} bits), both networks",
    ),
    "threshold_lower": ClaimRow(
        "Fig. 7a", "lower thresholds lose accuracy", "a loss below the optimum (plot only)"
    ),
    "window": ClaimRow("Fig. 7b", "optimum window", f"{WINDOW_S:g} s, both networks"),
    "window_sides": ClaimRow(
        "Fig. 7b", "shorter and longer windows lose accuracy", "a loss on both sides (plot only)"
    ),
    "taxel_gain": ClaimRow(
        "Fig. 8", f"gain from {TAXELS[0]} to {TAXELS[1]} taxels", f"{TAXEL_GAIN:+.0%} (FFNN)"
    ),
    "taxel_saturation": ClaimRow(
        "Fig. 8", f"saturation above {TAXELS[1]} taxels", f"flat, about {SATURATION_ACCURACY:.0%}"
    ),
    "metrics": ClaimRow(
        "Fig. 9", "accuracy rises with SSNR, falls with STE", "strong correlations (plot only)"
    ),
    "mismatch": ClaimRow("Fig. 10", "accuracy falls with threshold mismatch", "a fall (plot only)"),
}
"""The claims of ``CLAIMS`` that the report judges, in the report's order."""


@dataclass(frozen=True)
class TableRow:
    """One row of Table I (the paper's columns), as text."""

    reference: str
    readout: str
    hardware: str
    sensors: str
    data_rate: str
    preprocessing: str
    classifier: str
    classes: str
    accuracy: str


TABLE_COLUMNS = (
    "reference",
    "readout (resolution, rate)",
    "hardware",
    "sensors",
    "estimated data rate",
    "preprocessing",
    "classifier",
    "classes",
    "accuracy (chance)",
)

# The paper's Table I (state of the art in texture classification), row by row; references in
# brackets are the paper's own reference numbers.
TABLE_ROWS = (
    TableRow(
        "the paper",
        "on-chip spikes (3.5 b, variable)",
        "end-to-end model, hardware spike encoding",
        "9",
        f"{DATA_RATE_HZ:g} Hz",
        "rate code",
        "CNN",
        "12",
        "90 % (8.33 %)",
    ),
    TableRow(
        "the paper's ref. [16]",
        "frames (10 b, 9.6 kHz)",
        "off-the-shelf sensors + ADC, software classification",
        "4 (multi-modal)",
        "96 kHz",
        "cumulative multi-band power",
        "MLP",
        "12",
        "79 % (8.33 %)",
    ),
    TableRow(
        "the paper's ref. [17]",
        "software spikes (unreported, 300 Hz)",
        "in-house MEMS sensors + ADC",
        "6",
        "100 Hz",
        "none",
        "ELM chip",
        "10",
        "92 % (10 %)",
    ),
    TableRow(
        "the paper's ref. [11]",
        "software spikes (24 b, 380 Hz)",
        "in-house piezoresistive sensors + ADC",
        "4",
        "9.12 kHz (estimated)",
        "none",
        "SNN + KNN",
        "10",
        "94.2 % (10 %)",
    ),
    TableRow(
        "the paper's ref. [18]",
        "software spikes (10 b, 200 Hz)",
        "in-house sensors + ADC",
        "2 (multi-modal)",
        "115.2 kHz (link baud rate)",
        "wavelet transform",
        "SNN (Tempotron)",
        "2",
        "99.45 % (50 %)",
    ),
    TableRow(
        "the paper's ref. [19]",
        "software spikes (24 b, 300 Hz)",
        "in-house piezoresistive sensors + ADC",
        "4",
        "28.8 kHz (estimated)",
        "wavelet + cross-wavelet transform",
        "KNN",
        "3",
        "97.6 % (33.33 %)",
    ),
)
