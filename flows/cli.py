"""The ``eskin`` command line.

``eskin run [--scene NAME|FILE] [--dataset NAME|PATH] [--json]`` simulates one scene and prints a
summary (or, with ``--json``, one JSON object on stdout). Errors in the user's input print one line
``eskin: error: ...`` on stderr and exit with status 2.

JSON numbers that are infinite (an SSNR of a REAL train equal to its TRUE train) are written as the
strings ``"inf"`` and ``"-inf"``: JSON has no infinity, and ``float("inf")`` reads them back.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from typing import Any

EXIT_USER_ERROR = 2


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="eskin",
        description="Neuromorphic e-skin design sweeps: spiking taxel readout to texture accuracy.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    run = commands.add_parser(
        "run",
        help="simulate one scene and print its accuracy, spike metrics and stage timings",
        description="Simulate one scene end to end and print a summary.",
    )
    run.add_argument(
        "--scene",
        default="paper",
        metavar="NAME|FILE",
        help="a built-in scene (paper, smoke) or a scene TOML file (default: paper)",
    )
    run.add_argument(
        "--dataset",
        metavar="NAME|PATH",
        help="override the scene's recordings: 'synthetic', a VibTac-12 folder (X/Y/Z.csv) "
        "or a folder dataset (dataset.toml)",
    )
    run.add_argument("--json", action="store_true", help="print one JSON object on stdout")
    run.set_defaults(handler=_run)
    return parser


def main(argv: list[str] | None = None) -> int:
    from pipeline.errors import EskinError

    args = build_parser().parse_args(argv)
    try:
        return args.handler(args)
    except EskinError as exc:
        print(f"eskin: error: {exc}", file=sys.stderr)
        return EXIT_USER_ERROR
    except KeyboardInterrupt:
        print("eskin: interrupted", file=sys.stderr)
        return 130


def _run(args: argparse.Namespace) -> int:
    from pipeline.recordings import resolve_dataset_argument
    from pipeline.scene import Scene
    from pipeline.simulate import run_scene, stage_names

    scene = Scene.load(args.scene)
    if args.dataset is not None:
        override = resolve_dataset_argument(args.dataset)
        scene = scene.replace(**{f"dataset.{k}": v for k, v in override.items()})
    progress = _StageProgress(stage_names(scene), enabled=not args.json)
    try:
        result = run_scene(scene, on_stage=progress.advance)
    finally:
        progress.close()
    summary = result_summary(result)
    if args.json:
        print(json.dumps(_json_safe(summary), indent=2))
    else:
        print(format_summary(summary))
    return 0


class _StageProgress:
    """A tqdm bar over a run's stages, on stderr, shown only on a terminal."""

    def __init__(self, stages: tuple[str, ...], enabled: bool):
        from tqdm import tqdm

        self.bar = tqdm(
            total=len(stages),
            unit="stage",
            file=sys.stderr,
            disable=None if enabled else True,
            leave=False,
        )
        self.started = 0

    def advance(self, stage: str) -> None:
        if self.started:
            self.bar.update(1)
        self.started += 1
        self.bar.set_description(stage)

    def close(self) -> None:
        self.bar.close()


def result_summary(result: Any) -> dict[str, Any]:
    """The JSON object of ``eskin run --json`` (ARCHITECTURE section 7)."""
    scene = result.scene
    m = result.metrics
    return {
        "scene": scene.name,
        "dataset": scene.dataset.kind.value,
        "n_recordings": result.n_recordings,
        "n_classes": result.n_classes,
        "chance": 1.0 / result.n_classes,
        "taxels": scene.array.n_taxels,
        "threshold_v": scene.readout.threshold_v,
        "window_s": scene.coding.window_s,
        "n_windows": result.n_windows,
        "dropped_spikes": result.dropped_spikes,
        "accuracy": {
            model.value: {
                "mean": cv.mean,
                "std": cv.std,
                "folds": [float(a) for a in cv.fold_accuracy],
            }
            for model, cv in result.accuracy.items()
        },
        "ssnr_db": m.ssnr_db,
        "ste_s2": m.ste_s2,
        "ste_sign_safe_s2": m.ste_sign_safe_s2,
        "event_rate_hz": m.event_rate_hz,
        "data_rate_bps": m.data_rate_bps,
        "equivalent_bits": m.equivalent_bits,
        "timings_s": dict(result.timings_s),
    }


def format_summary(s: dict[str, Any]) -> str:
    lines = [
        f"scene {s['scene']!r} on {s['dataset']} data: {s['n_recordings']} recordings, "
        f"{s['n_classes']} classes (chance {100 * s['chance']:.1f} %)",
        f"  {s['taxels']} taxels, threshold {s['threshold_v']:g} V "
        f"({s['equivalent_bits']:.2f} equivalent bits), "
        f"{s['n_windows']} windows of {s['window_s']:g} s",
    ]
    for model, acc in s["accuracy"].items():
        lines.append(
            f"  {model.upper():5s} accuracy {100 * acc['mean']:5.1f} % "
            f"+- {100 * acc['std']:.1f} % over {len(acc['folds'])} folds"
        )
    ssnr = "inf (REAL = TRUE)" if math.isinf(s["ssnr_db"]) else f"{s['ssnr_db']:.2f}"
    lines += [
        f"  SSNR {ssnr} dB, STE {s['ste_s2']:.3g} s^2 (sign-safe {s['ste_sign_safe_s2']:.3g})",
        f"  event rate {s['event_rate_hz']:.4g} spikes/s, "
        f"data rate {s['data_rate_bps']:.4g} bit/s (address-event)",
        "  seconds: "
        + ", ".join(f"{stage} {sec:.2f}" for stage, sec in s["timings_s"].items())
        + f" (total {sum(s['timings_s'].values()):.1f})",
    ]
    return "\n".join(lines)


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else "-inf" if value < 0 else "nan"
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_safe(v) for v in value]
    return value


if __name__ == "__main__":
    sys.exit(main())
