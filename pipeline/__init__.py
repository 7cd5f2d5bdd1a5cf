"""The science of e-skin sweep: the simulated e-skin, from a recorded touch to a classifier's
accuracy, and the report on it.

Pure: functions on numpy and torch arrays and frozen value objects, with no I/O beyond reading
recordings, no Prefect, no Dask and no global state (:mod:`storage` keeps the results,
:mod:`flows` runs the sweeps). Its sub-packages, in the order the data flows:

- :mod:`pipeline.design`: what to simulate, the scene (dataset, taxel array, readout, coding,
  training) and grids and search spaces of scenes;
- :mod:`pipeline.recordings`: the recordings a scene reads, from files or generated;
- :mod:`pipeline.chain`: the model chain, front end -> taxel signals -> level-crossing readout
  (spike trains) -> rate coding -> cross-validated classifiers;
- :mod:`pipeline.run`: the chain bound to scenes, level by level (the stage registry and cache
  keys), and one scene end to end;
- :mod:`pipeline.results`: result cubes of a sweep's points, their statistics and the readout
  energy model;
- :mod:`pipeline.report`: the report on the cubes, which design to build, the paper's claims
  judged by tests and what accuracy costs.

Beside them, foundations every sub-package may import: :mod:`pipeline.errors` (bad user input),
:mod:`pipeline.numbers` (checks of the numbers a user gives) and :mod:`pipeline.jit` (numba
kernels compiled on first use, for the generated recordings and the chain alike); and the contract
names :mod:`pipeline.readout` and :mod:`pipeline.coding`.
"""
