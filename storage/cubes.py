"""Stage names of stored result cubes.

Cubes are built by :func:`pipeline.cube.build_cube` and stored by
:meth:`storage.store.SweepStore.write_cube`. Their ``stage`` coordinate is :data:`SPIKE_STAGES`,
then ``coding`` and ``train_<model>`` per model: the names under which result entries record the
seconds of each stage.
"""

from __future__ import annotations

from pipeline.stages import steps_through

SPIKE_STAGES = steps_through("spikes")
