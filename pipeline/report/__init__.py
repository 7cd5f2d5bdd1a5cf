"""The report: the numbers behind the paper's Figs. 7-10 and Table I, and what accuracy costs.

Stages, each a module with the frozen dataclasses it returns:

- :mod:`~pipeline.report.panels`: the figures (:class:`Panel`) and the swept fields that feed them;
- :mod:`~pipeline.report.cubes`: reading result cubes (the layout of :mod:`pipeline.cube`);
- :mod:`~pipeline.report.curves`: accuracy curves along a sweep and Fig. 9's lines;
- :mod:`~pipeline.report.claims`: the paper's claims beside this run's numbers;
- :mod:`~pipeline.report.tables`: Table I;
- :mod:`~pipeline.report.cost`: compute seconds, the Pareto front, observation time;
- :mod:`~pipeline.report.analysis`: :func:`build_report`, all of the above from the cubes;
- :mod:`~pipeline.report.figures`: matplotlib figures of a :class:`Report`;
- :mod:`~pipeline.report.blocks`, :mod:`~pipeline.report.render`: typed document blocks and
  their Markdown and HTML renderers;
- :mod:`~pipeline.report.document`: the report's blocks and the files of its folder.

All of it is pure: cubes in, numbers, text and file contents out. Everything is read from the
cubes themselves: scene fields from their coordinates, the class count from their attributes.
Which figure a cube feeds is decided by the scene fields its one dimension sweeps
(``readout.threshold_v`` for Fig. 7a, ``coding.window_s`` for 7b, ``array.rows``/``array.cols``
for 8, a ``correlate`` sweep for 9, ``readout.effects.threshold_mismatch.sigma_rel`` for 10,
``coding.n_windows`` alone for the observation time), not by its name; a figure with no such cube
is "not in this run". The equations are in each stage's docstring.
"""

from pipeline.report.analysis import Report, build_report
from pipeline.report.cost import SweepRun
from pipeline.report.cubes import sampling_rate_hz
from pipeline.report.panels import Panel
from pipeline.report.tables import FrameReadout

__all__ = ["FrameReadout", "Panel", "Report", "SweepRun", "build_report", "sampling_rate_hz"]
