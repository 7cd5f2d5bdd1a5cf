"""Many variants of one scene: the scenes of a grid's sweep, each part read once.

A sweep's points differ from one scene in a few fields. :class:`SceneVariants` reads each scene
part once per distinct combination of the swept values in it and shares the part between the
scenes that have it, so that expanding a sweep costs a few microseconds per point, and the
canonical forms of shared parts are written once (:meth:`pipeline.design.scene.Scene.canonical`
with a memo).
"""

from __future__ import annotations

import operator
from collections.abc import Mapping, Sequence
from typing import Any

from pipeline.design import fields
from pipeline.design.scene import Scene
from pipeline.errors import SceneError


class SceneVariants:
    """Copies of one scene with the same dotted fields replaced, each field from its own list.

    ``variants.scene(indices)`` is ``scene.replace(**fixed, **{field: values[i] ...})`` over
    ``axes`` and ``indices`` (``fixed`` set first, the axes' values after it): the same scene, or a
    :class:`~pipeline.errors.SceneError` with the same problems, but each scene part (``dataset``,
    ``array``, ...) is read and validated once per distinct combination of the value indices of the
    fields in it (a part no field is in, once), and the scenes share their parts. A grid whose
    fields take a few values each thus validates a few parts, not every point, and its scenes'
    canonical forms can be written once per part (:meth:`~pipeline.design.scene.Scene.canonical`
    with a memo).

    Parameters
    ----------
    scene : Scene
        The scene the variants start from.
    axes : sequence of (str, sequence)
        Dotted scene fields (``"readout.threshold_v"``), each with its values. A field must
        start with a top-level scene field (``dataset``, ..., ``name``, ``seed``).
    fixed : mapping of str to value, optional
        Dotted scene fields set at every variant before the axes' values (a sweep's ``set``).
        They are not checked on their own: a part is checked whole, with the axes' values in it,
        so that a fixed field that needs a swept one (a chip deployment that needs the swept
        mismatch effect) is valid wherever the variant is.

    Raises
    ------
    ValueError
        A field does not start with a top-level scene field.
    """

    def __init__(
        self,
        scene: Scene,
        axes: Sequence[tuple[str, Sequence[Any]]],
        fixed: Mapping[str, Any] | None = None,
    ):
        self._cls = type(scene)
        self._data = scene.to_dict()
        fixed = dict(fixed or {})
        for dotted, value in fixed.items():
            fields.put(self._data, dotted, _copy_plain(value))
        self._fields = [name for name, _ in axes]
        self._values = [values for _, values in axes]
        self.source = f"scene {scene.name!r} with {sorted({*fixed, *self._fields})}"
        tops = [name.split(".")[0] for name in self._fields]
        order = [slot.name for slot in fields.read_order(self._cls)]
        unknown = sorted({*tops, *(name.split(".")[0] for name in fixed)} - set(order))
        if unknown:
            raise ValueError(f"not top-level scene fields: {', '.join(unknown)}")
        self._positions = {top: tuple(i for i, t in enumerate(tops) if t == top) for top in order}
        # The memo key of a part: the indices of the values in it (none for an untouched part).
        self._part_indices = [
            (top, operator.itemgetter(*positions) if positions else lambda _: ())
            for top, positions in self._positions.items()
        ]
        self._parts: dict[tuple[str, Any], tuple[Any, list[str]]] = {}

    def problems(self, indices: Sequence[int]) -> list[str]:
        """What :meth:`scene` would raise at ``indices`` (one index per axis), or ``[]``."""
        problems: list[str] = []
        parts: dict[str, Any] = {}
        for top, part_indices in self._part_indices:
            parts[top], found = self._part(top, part_indices(indices), indices)
            problems += found
        if not problems:
            problems += _refused_together(self._cls(**parts))
        return problems

    def scene(self, indices: Sequence[int]) -> Scene:
        """The scene with each field set to ``values[indices[axis]]``.

        Raises
        ------
        SceneError
            The values the scene refuses, exactly as
            :meth:`~pipeline.design.scene.Scene.replace` says.
        """
        parts: dict[str, Any] = {}
        problems: list[str] = []
        for top, part_indices in self._part_indices:
            value, found = self._part(top, part_indices(indices), indices)
            parts[top] = value
            problems += found
        scene = None if problems else self._cls(**parts)
        if scene is not None:
            problems += _refused_together(scene)
        if problems:
            raise SceneError(problems, self.source)
        return scene

    def _part(self, top: str, part_indices: Any, indices: Sequence[int]) -> tuple[Any, list[str]]:
        found = self._parts.get((top, part_indices))
        if found is None:
            positions = self._positions[top]
            changes = [(self._fields[i], self._values[i][indices[i]]) for i in positions]
            found = self._parts[top, part_indices] = self._read(top, changes)
        return found

    def _read(self, top: str, changes: list[tuple[str, Any]]) -> tuple[Any, list[str]]:
        """Part ``top`` with ``changes`` made as :meth:`~pipeline.design.scene.Scene.replace`
        makes them, and what the reader found wrong with it."""
        data = {top: _copy_plain(self._data.get(top))}
        for dotted, value in changes:
            fields.put(data, dotted, value)
        problems: list[str] = []
        part = fields.read_slot(fields.slot_named(self._cls)[top], data[top], top, problems)
        return part, problems


def _refused_together(scene: Scene) -> list[str]:
    """What a scene's parts refuse together (:meth:`~pipeline.design.scene.Scene.refusals`), as
    reading says it."""
    refusals = getattr(scene, "refusals", None)
    return [] if refusals is None else [f"{name}: {text}" for name, text in refusals()]


def _copy_plain(value: Any) -> Any:
    """A copy of a plain nested dict/list, so that changing it leaves the original alone."""
    if isinstance(value, dict):
        return {k: _copy_plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy_plain(v) for v in value]
    return value
