"""The Python API for notebooks and scripts: everything ``eskin`` does, as plain calls.

- Describe a scene and run it: :class:`Scene` (``Scene.load("smoke")``, ``scene.replace(...)``
  with dotted fields) and :func:`run_scene`; :func:`result_summary` and :func:`format_summary`
  give what ``eskin run --json`` and ``eskin run`` print.
- Sweep a grid: :func:`run_sweep` on a ``distributed.Client`` you give (or a local cluster it
  starts), without Prefect; the Prefect flow ``flows.sweep.sweep`` does the same with a UI.
  :func:`unique_points` gives a grid's distinct points (scenes by result cache key).
- Search a design space: :func:`run_optimize` (a space file or a
  :class:`pipeline.design.space.Space`, a budget in trials or stage seconds), without Prefect;
  the Prefect flow ``flows.optimize.optimize`` does the same with a UI.
- Open the results: :func:`open_results` (a dict of cubes by sweep name) or :func:`open_tree`
  (one ``xarray.DataTree``), and :func:`best_points` of a cube.
- Compare two designs recording by recording: :func:`compare` (a paired difference in accuracy
  with its 95 % interval and an exact McNemar test); :mod:`pipeline.results.stats` has the
  statistics themselves (accuracy intervals, paired comparisons, Holm's correction, trends).
- Read the answer, the report's first section: :func:`report_answers` (per model, the most
  accurate design and the cheapest ones not significantly below it).
- Write the report: :func:`write_run_report`, with hardware constants of your own
  (``constants=load_constants("mine.toml")``, :func:`load_constants`).

Nothing here imports Prefect.
"""

from flows.assembly import best_points
from flows.progress import SweepFailed
from flows.report import report_answers, write_run_report
from flows.run import run_sweep
from flows.search import run_optimize
from flows.summaries import format_summary, format_sweep_summary, json_safe, result_summary
from pipeline.design.grid import Grid, load_grid
from pipeline.design.scene import Scene
from pipeline.design.space import Space, load_space
from pipeline.errors import EskinError
from pipeline.report.evidence import compare_points as compare
from pipeline.results.hardware_constants import load_constants
from pipeline.run.grid_keys import unique_points
from pipeline.run.simulate import SceneResult, run_scene
from storage import open_results, open_tree

__all__ = [
    "EskinError",
    "Grid",
    "Scene",
    "SceneResult",
    "Space",
    "SweepFailed",
    "best_points",
    "compare",
    "format_summary",
    "format_sweep_summary",
    "json_safe",
    "load_constants",
    "load_grid",
    "load_space",
    "open_results",
    "open_tree",
    "report_answers",
    "result_summary",
    "run_optimize",
    "run_scene",
    "run_sweep",
    "unique_points",
    "write_run_report",
]
