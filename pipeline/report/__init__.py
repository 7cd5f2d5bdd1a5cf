"""The report: which design to build, the paper's claims judged by tests, and what accuracy costs.

Stages, each a module with the frozen dataclasses it returns:

- :mod:`~pipeline.report.paper`: the paper's numbers (claims, Table I), in one place;
- :mod:`~pipeline.report.panels`: the paper's figures (:class:`~pipeline.report.panels.Panel`)
  and the fields that feed them;
- :mod:`~pipeline.report.cubes`: reading result cubes (the layout of :mod:`pipeline.results.cube`);
- :mod:`~pipeline.report.evidence`: the run's per-recording results and the paired and trend
  tests on them (fixed seeds);
- :mod:`~pipeline.report.designs`: the run's distinct designs, their accuracy and costs, the
  frame-based readout (:class:`~pipeline.report.designs.FrameReadout`);
- :mod:`~pipeline.report.answer`: per model, the cheapest design not significantly below the
  best (Holm-corrected paired tests);
- :mod:`~pipeline.report.recordings_needed`: how many recordings per class would tell the
  answer's designs from the best;
- :mod:`~pipeline.report.curves`: accuracy curves along a sweep and Fig. 9's lines;
- :mod:`~pipeline.report.sweeps`: a curve for any other 1-D sweep, a heat map for a 2-D sweep;
- :mod:`~pipeline.report.claims`: the paper's claims, each judged by a paired or trend test,
  as a table of verdicts;
- :mod:`~pipeline.report.tables`: Table I, the paper's rows beside this run's answer designs;
- :mod:`~pipeline.report.fronts`: accuracy against data rate, event rate, bits, compute time
  and readout power, with designs indistinguishable from the front marked;
- :mod:`~pipeline.report.cost`: the front rule, observation time, the sweep's own cost;
- :mod:`~pipeline.report.decision_time`: accuracy against decision time, the earliest decision not
  significantly below the full touch, early exit and the energy per decision (decoder and
  readout), where the cubes keep decisions along the touch;
- :mod:`~pipeline.report.taxel_count`: accuracy against the number of a real array's taxels
  read, each count compared with the most read, where a sweep varies ``array.taxels``;
- :mod:`~pipeline.report.analysis`: :func:`~pipeline.report.analysis.build_report`, all of the
  above from the cubes;
- :mod:`~pipeline.report.figures`: matplotlib figures of a
  :class:`~pipeline.report.analysis.Report`;
- :mod:`~pipeline.report.blocks`, :mod:`~pipeline.report.render`: typed document blocks and
  their Markdown and HTML renderers;
- :mod:`~pipeline.report.document`: the report's blocks and the files of its folder.

All of it is pure: cubes in, numbers, text and file contents out. Everything is read from the
cubes themselves: scene fields from their coordinates, the class count from their attributes,
per-recording results from ``correct``. Which paper figure a cube feeds is decided by the scene
fields its one dimension sweeps (``readout.threshold_v`` for Fig. 7a, ``coding.window_s`` for 7b,
``array.rows``/``array.cols`` for 8, a ``correlate`` sweep for 9,
``readout.effects.threshold_mismatch.sigma_rel`` for 10, ``coding.n_windows`` alone for the
observation time), not by its name; a figure with no such cube is "not in this run". Any other
sweep gets its own curve or heat map. The equations are in each stage's docstring.
"""

from pipeline.report.analysis import Report, build_report
from pipeline.report.cost import SweepRun
from pipeline.report.cubes import sampling_rate_hz
from pipeline.report.designs import FrameReadout
from pipeline.report.panels import Panel

__all__ = ["FrameReadout", "Panel", "Report", "SweepRun", "build_report", "sampling_rate_hz"]
