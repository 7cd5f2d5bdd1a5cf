"""The two renderers of a report document: Markdown and one self-contained HTML page.

Each takes the same :mod:`pipeline.report.blocks` and escapes their plain text for its format:
HTML escapes ``<``, ``>``, ``&`` and quotes everywhere; Markdown escapes ``|`` in table cells and
the ``<`` and ``&`` that would otherwise start an HTML tag or entity. Neither writes anything.
"""

from __future__ import annotations

import html
import re
from collections.abc import Mapping, Sequence

from pipeline.report.blocks import Block, Details, Figure, Heading, Items, Paragraph, Table

TITLE = "e-skin sweep report"
FIGURES = "figures"

# A '<' before a letter, '/', '!' or '?' opens a tag, comment or autolink in Markdown, and '&'
# before 'name;' or '#123;' is an entity; other '<' and '&' (as in "p < 0.05") show as typed.
_MD_MARKUP = re.compile(r"<(?=[A-Za-z/!?])|&(?=#?\w+;)")

_STYLE = (
    "body{font-family:sans-serif;max-width:72em;margin:1em auto;padding:0 1em}"
    "table{border-collapse:collapse;margin:.6em 0;font-size:.9em}"
    "th,td{border:1px solid #ccc;padding:.2em .4em;text-align:left;vertical-align:top}"
    "figure{margin:.6em 0}figure svg{max-width:100%;max-height:24em;width:auto;height:auto}"
    "summary{cursor:pointer;font-weight:bold;margin:1em 0}"
)


def render_markdown(blocks: Sequence[Block], *, figure_folder: str = FIGURES) -> str:
    """Markdown of ``blocks``; a figure links ``<figure_folder>/<name>.png``;
    :class:`~pipeline.report.blocks.Details` become a ``<details>`` element (collapsed where the
    Markdown viewer renders HTML)."""
    return "\n".join(_markdown_lines(blocks, figure_folder))


def _markdown_lines(blocks: Sequence[Block], figure_folder: str) -> list[str]:
    lines: list[str] = []
    for block in blocks:
        match block:
            case Heading(level, text):
                lines += ["#" * level + " " + _md_text(text), ""]
            case Paragraph(text):
                lines += [_md_text(text), ""]
            case Figure(name, caption):
                lines += [f"![{_md_text(caption)}]({figure_folder}/{name}.png)", ""]
            case Table(header, rows):
                lines.append("| " + " | ".join(map(_md_cell, header)) + " |")
                lines.append("|" + " --- |" * len(header))
                lines += ["| " + " | ".join(map(_md_cell, row)) + " |" for row in rows]
                lines.append("")
            case Items(items):
                lines += [f"- {_md_text(item)}" for item in items] + [""]
            case Details(summary, inner):
                lines += [f"<details><summary>{html.escape(summary)}</summary>", ""]
                lines += [*_markdown_lines(inner, figure_folder), "</details>", ""]
    return lines


def render_html(blocks: Sequence[Block], svgs: Mapping[str, str]) -> str:
    """One self-contained page: figures inlined from ``svgs`` (name -> SVG document), a little
    CSS, no scripts and no links to other files.

    Raises
    ------
    KeyError
        A figure block names a figure ``svgs`` does not hold.
    """
    return (
        f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8"><title>{TITLE}</title>'
        f"<style>{_STYLE}</style></head><body>\n"
        + "\n".join(_html_parts(blocks, svgs))
        + "\n</body></html>\n"
    )


def _html_parts(blocks: Sequence[Block], svgs: Mapping[str, str]) -> list[str]:
    body: list[str] = []
    for block in blocks:
        match block:
            case Heading(level, text):
                body.append(f"<h{level}>{html.escape(text)}</h{level}>")
            case Paragraph(text):
                body.append(f"<p>{html.escape(text)}</p>")
            case Figure(name, caption):
                svg = svgs[name]
                # Drop the XML declaration and doctype: inline SVG starts at its element.
                body.append(
                    f"<figure>{svg[svg.index('<svg') :]}<figcaption>"
                    f"{html.escape(caption)}</figcaption></figure>"
                )
            case Table(header, rows):
                head = "".join(f"<th>{html.escape(c)}</th>" for c in header)
                cells = "".join(
                    "<tr>" + "".join(f"<td>{html.escape(c)}</td>" for c in row) + "</tr>"
                    for row in rows
                )
                body.append(f"<table><thead><tr>{head}</tr></thead><tbody>{cells}</tbody></table>")
            case Items(items):
                body.append("<ul>" + "".join(f"<li>{html.escape(i)}</li>" for i in items) + "</ul>")
            case Details(summary, inner):
                body.append(f"<details><summary>{html.escape(summary)}</summary>")
                body += _html_parts(inner, svgs)
                body.append("</details>")
    return body


def _md_text(text: str) -> str:
    return _MD_MARKUP.sub(lambda m: "\\" + m.group(0), text)


def _md_cell(text: str) -> str:
    return _md_text(text).replace("|", "\\|")
