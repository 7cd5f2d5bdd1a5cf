"""The built-in grids, one TOML file each, loaded by name with
:func:`pipeline.design.grid.load_grid` (names: :func:`pipeline.design.grid.builtin_grid_names`).

``paper.toml``
    The paper's one-dimensional sweeps (Figs. 7-10), each around its operating point.
``smoke.toml``
    A tiny grid for tests and CI: every kind of sweep, seconds per point.
"""
