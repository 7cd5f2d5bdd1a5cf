"""The description of a design: the scene schema (:mod:`~pipeline.design.fields`), the scene
(:mod:`~pipeline.design.scene`), grids of scenes (:mod:`~pipeline.design.grid`) and the built-in
scenes and grids (the TOML files of :mod:`pipeline.design.scenes` and :mod:`pipeline.design.grids`).
"""
