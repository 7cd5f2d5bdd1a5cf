"""Summaries of a scene's run and of a sweep: plain functions the command line prints.

A notebook calls them too: :func:`result_summary` turns a :class:`pipeline.run.simulate.SceneResult`
into the JSON-able dict of ``eskin run --json``, :func:`format_summary` prints it as
``eskin run`` does, and :func:`format_sweep_summary` prints a sweep's summary (what
:func:`flows.run.run_sweep` and the ``sweep`` flow return) with the best point per model
of each cube; :func:`format_power` prints ``eskin power``. :func:`json_safe` writes infinite
numbers as the strings ``"inf"`` and ``"-inf"`` (JSON has none; ``float("inf")`` reads them back).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:  # the command line imports this module; xarray loads only when a sweep prints
    import xarray as xr

    from pipeline.results.readout_power import PowerBudget


def result_summary(result: Any) -> dict[str, Any]:
    """The JSON object of ``eskin run --json`` (its keys are documented in docs/scenes.md).

    Parameters
    ----------
    result
        What :func:`pipeline.run.simulate.run_scene` returned.

    Returns
    -------
    dict
        Plain numbers, strings, lists and dicts; ``ssnr_db`` may be infinite (see
        :func:`json_safe`). Accuracies are fractions in [0, 1], ``timings_s`` seconds per stage.
    """
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
                "folds": [float(a) for a in np.ravel(cv.fold_accuracy)],
                "repeats": int(np.atleast_2d(cv.fold_accuracy).shape[0]),
                **_interval(cv, result.labels, scene, model.value),
                **_chips(cv, result.labels, scene),
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


def _interval(cv: Any, labels: np.ndarray | None, scene: Any, model: str) -> dict[str, Any]:
    """The 95 % interval of a model's accuracy over recordings, where its predictions are known:
    the interval a sweep's cube gives the same design (a bootstrap seeded from the scene's result
    key and the model)."""
    predicted = getattr(cv, "predicted", None)
    if predicted is None or labels is None:
        return {}
    from pipeline.results.stats import accuracy_interval
    from pipeline.run.stages import RESULTS, interval_generator

    rng = interval_generator(RESULTS.key(scene), model)
    interval = accuracy_interval(predicted == labels, labels, rng=rng)
    return {"low": interval.low, "high": interval.high, "interval": interval.method}


def _chips(cv: Any, labels: np.ndarray | None, scene: Any) -> dict[str, Any]:
    """A model's accuracy over the chips of a scene that simulates chips (``mean``, ``folds``
    and the interval are chip 0's): ``chips`` with the count, the deployment, each chip's
    accuracy and the yield statistics of :func:`pipeline.results.yields.yield_statistics`."""
    predicted = getattr(cv, "chip_predicted", None)
    if predicted is None or labels is None:
        return {}
    from pipeline.results.yields import yield_statistics

    per_chip = (predicted == labels).mean(axis=(1, 2))
    stats = yield_statistics(per_chip, scene.chips.yield_target)
    return {
        "chips": {
            "count": int(per_chip.size),
            "deployment": scene.chips.deployment.value,
            "yield_target": scene.chips.yield_target,
            "accuracy": [float(a) for a in per_chip],
            **{name: float(value) for name, value in stats.items()},
        }
    }


def format_summary(s: Mapping[str, Any]) -> str:
    """The text ``eskin run`` prints for a :func:`result_summary` (no trailing newline)."""
    lines = [
        f"scene {s['scene']!r} on {s['dataset']} data: {s['n_recordings']} recordings, "
        f"{s['n_classes']} classes (chance {100 * s['chance']:.1f} %)",
        f"  {s['taxels']} taxels, threshold {s['threshold_v']:g} V "
        f"({s['equivalent_bits']:.2f} equivalent bits), "
        f"{s['n_windows']} windows of {s['window_s']:g} s",
    ]
    for model, acc in s["accuracy"].items():
        lines.append(
            f"  {model.upper():5s} accuracy {100 * acc['mean']:5.1f} %"
            + (" on chip 0" if "chips" in acc else "")
            + (
                f" (95 % interval {100 * acc['low']:.1f}-{100 * acc['high']:.1f} %)"
                if "low" in acc
                else ""
            )
            + f", fold spread +- {100 * acc['std']:.1f} % over "
            + f"{len(acc['folds']) // acc['repeats']} folds"
            + (f" x {acc['repeats']} repeats" if acc["repeats"] > 1 else "")
        )
        if "chips" in acc:
            c = acc["chips"]
            lines.append(
                f"        {c['count']} chips ({c['deployment']}): mean "
                f"{100 * c['accuracy_chip_mean']:.1f} %, 5th percentile "
                f"{100 * c['accuracy_p05']:.1f} %, {100 * c['yield_share']:.0f} % of chips at "
                f"or above {100 * c['yield_target']:.0f} %"
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


def format_sweep_summary(
    summary: Mapping[str, Any], cubes: Mapping[str, xr.Dataset] | None = None
) -> str:
    """The text ``eskin sweep`` prints: counts, each cube's best point per model, where it is.

    Parameters
    ----------
    summary
        A sweep's summary: ``root``, ``cubes`` (names in order), ``points``, ``cache_hits``,
        ``computed`` and ``seconds``, optionally ``sweeps`` (each cube's summary,
        :func:`flows.assembly.summarize`), ``report`` and ``flow_run_url``.
    cubes
        The sweep's cubes by name, summarized when ``summary`` has no ``sweeps``; default:
        read from ``summary["root"]`` (:func:`storage.store.open_results`).
    """
    from flows.assembly import summarize
    from storage import open_results

    sweeps = summary.get("sweeps")
    if sweeps is None:
        cubes = open_results(summary["root"]) if cubes is None else cubes
        sweeps = {name: summarize(cubes[name]) for name in summary["cubes"]}
    dims = {
        name: ", ".join(f"{d}={size}" for d, size in sweeps[name]["dims"].items())
        for name in summary["cubes"]
    }
    # Columns as wide as their longest entry, so long sweep names keep the table aligned.
    name_w = max([len("sweep"), *map(len, dims)])
    dims_w = max([len("dims"), *map(len, dims.values())])
    lines = [
        f"{summary['points']} points ({summary['cache_hits']} cached, {summary['computed']} "
        f"computed) in {summary['seconds']:.1f} s",
        f"{'sweep':{name_w}s} {'dims':{dims_w}s} {'model':6s} best accuracy (mean over folds)",
    ]
    for name in summary["cubes"]:
        for row in sweeps[name]["best"]:
            at = ", ".join(f"{d}={_coordinate(v)}" for d, v in row["at"].items())
            lines.append(
                f"{name:{name_w}s} {dims[name]:{dims_w}s} {row['model']:6s} "
                f"{100 * row['accuracy']:5.1f} % at {at}"
            )
    # A root may be a URL (s3://...), which Path would mangle.
    lines.append(f"cubes: {str(summary['root']).rstrip('/')}/store.zarr/cubes")
    lines.append(f"open with: storage.open_results({str(summary['root'])!r})")
    if summary.get("report"):
        lines.append(f"report: {summary['report']}")
    if summary.get("flow_run_url"):
        lines.append(f"Prefect flow run: {summary['flow_run_url']}")
    return "\n".join(lines)


def _coordinate(value: Any) -> str:
    """A coordinate's value: a number in short form, an option (``"decaying"``) as is."""
    return f"{value:g}" if isinstance(value, int | float) else str(value)


def json_safe(value: Any) -> Any:
    """``value`` with every non-finite float as ``"inf"``, ``"-inf"`` or ``"nan"`` (nested)."""
    if isinstance(value, float) and not math.isfinite(value):
        return "inf" if value > 0 else "-inf" if value < 0 else "nan"
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, list):
        return [json_safe(v) for v in value]
    return value


def format_search_summary(summary: Mapping[str, Any]) -> str:
    """The text ``eskin optimize`` prints: counts, the front (trial, objectives, searched
    values; ``~`` marks a trial a paired test cannot tell from the front), where the cubes are.

    ``summary`` is :func:`flows.search.search_summary`'s, optionally with ``report`` and
    ``flow_run_url``.
    """
    lines = [
        f"{summary['trials']} trials ({summary['new_trials']} new: {summary['computed']} points "
        f"computed, {summary['cache_hits']} found in the store) in {summary['seconds']:.1f} s; "
        f"{summary['search_seconds']:.1f} stage seconds in all; sampler {summary['sampler']}",
        "front (~: off it, but not significantly worse):",
    ]
    for row in summary["front"]:
        values = ", ".join(f"{k} {v:.4g}" for k, v in row["objectives"].items())
        at = ", ".join(
            f"{k}={v:.4g}" if isinstance(v, float) else f"{k}={v}" for k, v in row["params"].items()
        )
        lines.append(f"  {'' if row['on_front'] else '~'}trial {row['trial']}: {values} at {at}")
    lines += [f"cube {name}: {where}" for name, where in summary["cubes"].items()]
    for key, label in (("report", "report"), ("flow_run_url", "Prefect flow run")):
        if summary.get(key):
            lines.append(f"{label}: {summary[key]}")
    return "\n".join(lines)


def format_power(budget: PowerBudget) -> str:
    """``eskin power``'s lines: each readout's power (static and dynamic), per taxel, data rate."""
    from pipeline.report.text import rate, si

    n = budget.n_taxels
    lines = [f"{n} taxel{'' if n == 1 else 's'}, {budget.event_rate_hz:g} events/s in all"]
    readouts = [("event readout", budget.event, budget.event_data_rate_bps, "address events")]
    if budget.frame is not None and budget.frame_data_rate_bps is not None:
        readouts.append(
            (
                "frame readout",
                budget.frame,
                budget.frame_data_rate_bps,
                f"{budget.bits:g}-bit ADC at {budget.sampling_rate_hz:g} Hz per taxel, "
                f"{budget.model.taxels_per_adc} taxels per ADC",
            )
        )
    for name, power, data_rate, how in readouts:
        lines.append(
            f"{name:<14} {si(power.total_w, 'W'):>9} ({si(power.total_w / n, 'W')} per taxel; "
            f"static {si(power.static_w, 'W')}, dynamic {si(power.dynamic_w, 'W')}), "
            f"{rate(data_rate, 'bit/s')} ({how})"
        )
    if budget.frame is None:
        lines.append("frame readout  unknown: give --sampling-rate-hz")
    elif budget.event_data_rate_bps > 0:
        out = budget.to_json()
        lines.append(
            f"frame / event: {out['frame_over_event_power']:.3g}x the power, "
            f"{out['frame_data_rate_bps'] / out['event_data_rate_bps']:.3g}x the data rate"
        )
    return "\n".join(lines)
