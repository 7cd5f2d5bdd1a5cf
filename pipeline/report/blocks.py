"""The typed blocks a report document is made of; :mod:`pipeline.report.render` renders them.

Text in a block is plain text: the renderers escape it for their format, so a ``|`` in a table
cell or a ``<`` in a sentence is shown as such, never read as markup.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal


@dataclass(frozen=True)
class Heading:
    """A section title; ``level`` 1 is the document's title."""

    level: Literal[1, 2, 3, 4, 5, 6]
    text: str


@dataclass(frozen=True)
class Paragraph:
    """A paragraph of plain text."""

    text: str


@dataclass(frozen=True)
class Table:
    """A table with one header row; every row has one cell per header cell."""

    header: tuple[str, ...]
    rows: tuple[tuple[str, ...], ...]


@dataclass(frozen=True)
class Figure:
    """A figure by name (its file stem); the renderers find its image from the name."""

    name: str
    caption: str


@dataclass(frozen=True)
class Items:
    """A bulleted list of short texts."""

    items: tuple[str, ...]


@dataclass(frozen=True)
class Details:
    """Blocks a reader opens on demand: collapsed under ``summary`` in HTML, a section in
    Markdown."""

    summary: str
    blocks: tuple[Block, ...]


Block = Heading | Paragraph | Table | Figure | Items | Details
