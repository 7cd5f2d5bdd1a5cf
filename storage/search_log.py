"""The journal of a search (``eskin optimize``) in its run root: every trial asked and told.

``<root>/search-<space>.jsonl`` holds one JSON object per line, appended as the search goes:
``{"space", "trial", "params", "sampler"}`` when a trial is asked (before its point is
submitted; ``sampler`` names the sampler that asked it, absent in journals written before) and
``{"space", "trial", "values"}`` (its objective values) or ``{"space", "trial", "failed"}``
when it is told. ``space`` is the fingerprint of the space searched, so a journal is never
replayed into another space. Each line is written with one ``write`` on a file opened with
``O_APPEND`` and flushed to disk (``fsync``); a line that does not parse (a write torn by a kill)
is skipped when reading. The search replays it to resume: told trials go back into the sampler
as they were, asked ones that were never told are asked again with the same values.

A search keeps its cubes under its own name, ``<space>.trials`` and ``<space>.front``
(:func:`search_cube_name`), so a root keeps every search made in it. A root written before
searches were named holds one search's as ``trials`` and ``front``, the space named in their
attribute ``space``: :func:`named_search_cubes` gives them their search's names on reading.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from storage import cube_files
from storage.errors import StoreError

#: What a search's cubes hold, every trial told and the front of them.
SEARCH_CUBES = ("trials", "front")
#: The attribute of a search's cubes naming the space searched (as
#: :func:`pipeline.report.trials.trial_cube` writes it; storage reads it only to name the cubes
#: of a root written before searches were named).
SPACE_ATTR = "space"


def search_cube_name(space: str, kind: str) -> str:
    """The name of the cube ``kind`` (one of :data:`SEARCH_CUBES`) of the search of ``space``:
    ``<space>.<kind>``, which no sweep's cube can be named (a sweep's name holds no dot)."""
    if kind not in SEARCH_CUBES:
        raise ValueError(f"unknown cube of a search {kind!r}: expected one of {SEARCH_CUBES}")
    return f"{space}.{kind}"


def named_search_cubes(cubes: Mapping[str, Any]) -> dict[str, Any]:
    """``cubes`` (name -> cube, as stored) with a search's cubes of a root written before
    searches were named (``trials`` and ``front``, attribute :data:`SPACE_ATTR` naming the
    space) under their search's names (:func:`search_cube_name`), sorted by name; where that
    search's cubes were written under those names since, the old ones are left out."""
    named: dict[str, Any] = {}
    old: dict[str, Any] = {}
    for name, cube in cubes.items():
        space = cube.attrs.get(SPACE_ATTR) if name in SEARCH_CUBES else None
        if isinstance(space, str) and cube_files.valid_name(f"{space}.{name}") and "." not in space:
            old[search_cube_name(space, name)] = cube
        else:
            named[name] = cube
    return dict(sorted({**old, **named}.items()))


def journal_path(root: str | Path, name: str) -> Path:
    """``<root>/search-<name>.jsonl``: the journal of the search of space ``name`` in ``root``."""
    return Path(root) / f"search-{name}.jsonl"


def journal_fingerprint(root: str | Path, name: str) -> str | None:
    """The fingerprint of the space whose trials the journal of space ``name`` under ``root``
    holds (its first readable line's), or None when there is no such line."""
    path = journal_path(root, name)
    if not path.is_file():
        return None
    for line in path.read_text(encoding="utf-8", errors="replace").splitlines():
        try:
            record = json.loads(line)
            int(record["trial"])
            return str(record["space"])
        except (ValueError, KeyError, TypeError):
            continue
    return None


@dataclass
class SearchJournal:
    """The trials of one search read from its journal, in trial order.

    ``params`` maps each asked trial's number to its values by field; ``values`` each told
    trial's objective values; ``failed`` each failed trial's reason; ``sampler`` names the
    sampler that asked the journal's first trial (None if it was not recorded).
    """

    path: Path
    fingerprint: str
    params: dict[int, dict[str, Any]] = field(default_factory=dict)
    values: dict[int, list[float]] = field(default_factory=dict)
    failed: dict[int, str] = field(default_factory=dict)
    sampler: str | None = None

    @classmethod
    def open(cls, root: str | Path, name: str, fingerprint: str) -> SearchJournal:
        """The journal of space ``name`` under ``root`` (empty if there is none yet).

        Raises
        ------
        StoreError
            The journal holds trials of another space of that name (other ranges or
            objectives): continuing it would mix them.
        """
        journal = cls(journal_path(root, name), fingerprint)
        if not journal.path.is_file():
            return journal
        for line in journal.path.read_text(encoding="utf-8", errors="replace").splitlines():
            try:
                record = json.loads(line)
                number = int(record["trial"])
                space = record["space"]
            except (ValueError, KeyError, TypeError):
                continue
            if space != fingerprint:
                raise StoreError(
                    f"{journal.path} holds a search of another space named {name!r} (its "
                    "base, ranges, objectives, seed or sampler differ): give another --root or name"
                )
            try:
                if "params" in record:
                    journal.params[number] = dict(record["params"])
                    if journal.sampler is None and isinstance(record.get("sampler"), str):
                        journal.sampler = record["sampler"]
                elif "values" in record:
                    journal.values[number] = [float(v) for v in record["values"]]
                else:
                    journal.failed[number] = str(record["failed"])
            except (ValueError, KeyError, TypeError):
                continue
        return journal

    @property
    def pending(self) -> list[int]:
        """Trials asked but never told (a killed search's), in order."""
        return [n for n in sorted(self.params) if n not in self.values and n not in self.failed]

    def asked(self, number: int, params: Mapping[str, Any], sampler: str | None = None) -> None:
        """Record that trial ``number`` was asked with ``params`` (values by field) by
        ``sampler`` (None: not recorded), before its point is submitted."""
        self.params[number] = dict(params)
        record: dict[str, Any] = {"trial": number, "params": dict(params)}
        if sampler is not None:
            self.sampler = self.sampler or sampler
            record["sampler"] = sampler
        self._append(record)

    def told(self, number: int, values: Sequence[float]) -> None:
        """Record trial ``number``'s objective values, in the order of the space's
        objectives."""
        self.values[number] = [float(v) for v in values]
        self._append({"trial": number, "values": self.values[number]})

    def told_failed(self, number: int, why: str) -> None:
        """Record that trial ``number`` failed, and ``why``."""
        self.failed[number] = why
        self._append({"trial": number, "failed": why})

    def _append(self, record: dict[str, Any]) -> None:
        line = json.dumps({"space": self.fingerprint, **record}, sort_keys=True) + "\n"
        fd = os.open(self.path, os.O_WRONLY | os.O_CREAT | os.O_APPEND, 0o644)
        try:
            os.write(fd, line.encode())
            os.fsync(fd)
        finally:
            os.close(fd)
