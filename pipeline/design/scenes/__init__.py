"""The built-in scenes, one TOML file each, loaded by name with
:meth:`pipeline.design.scene.Scene.load` (names: :func:`pipeline.design.scene.builtin_scene_names`).

``paper.toml``
    The paper's operating point (Figs. 7-10 sweep around it).
``smoke.toml``
    A tiny scene for tests and quick checks: seconds, not minutes.
"""
