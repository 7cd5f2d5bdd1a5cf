"""The description of a design: the scene schema (:mod:`~pipeline.design.fields`), the readout
effects a scene may name (:mod:`~pipeline.design.effects`), the scene
(:mod:`~pipeline.design.scene`) and its variants (:mod:`~pipeline.design.variants`), how many
windows a coding takes (:mod:`~pipeline.design.windows`), grids of scenes
(:mod:`~pipeline.design.grid`) and what they cost (:mod:`~pipeline.design.grid_cost`), design
spaces (:mod:`~pipeline.design.space`) and the built-in scenes and grids (the TOML files of
:mod:`pipeline.design.scenes` and :mod:`pipeline.design.grids`).
"""
