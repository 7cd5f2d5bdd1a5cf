"""Renderers on hand-made blocks: Markdown and HTML escape text, HTML is one self-contained page."""

import re
from html.parser import HTMLParser

import pytest

from pipeline.report.blocks import Details, Figure, Heading, Items, Paragraph, Table
from pipeline.report.render import render_html, render_markdown

TRICKY = "a|b <script>alert(1)</script> & &amp; p < 0.05"
SVG = '<?xml version="1.0"?>\n<!DOCTYPE svg>\n<svg xmlns="http://www.w3.org/2000/svg"></svg>\n'
BLOCKS = (
    Heading(1, "Title <1> & co"),
    Paragraph(TRICKY),
    Table(("col|umn", "b"), ((TRICKY, "x & y"),)),
    Figure("fig", "caption <i> & more"),
    Items(("one & two", "<b>three</b>")),
)


def test_markdown_escapes_pipes_in_cells_and_markup_everywhere():
    md = render_markdown(BLOCKS)
    lines = md.splitlines()
    assert lines[0] == "# Title <1> & co"  # not a tag: shown as typed
    assert lines[2] == "a|b \\<script>alert(1)\\</script> & \\&amp; p < 0.05"
    assert lines[4] == "| col\\|umn | b |"
    assert lines[5] == "| --- | --- |"
    # One cell per column: every unescaped pipe is a cell border.
    assert lines[6].count("|") - lines[6].count("\\|") == 3
    assert lines[6].startswith("| a\\|b \\<script>")
    assert "![caption \\<i> & more](figures/fig.png)" in lines
    assert "- \\<b>three\\</b>" in lines and "- one & two" in lines


def test_markdown_leaves_plain_text_alone():
    text = "threshold_v = 0.09 V; 50 % +- 2 % (3 x 3), p < 0.05 & done"
    assert render_markdown([Paragraph(text)]) == text + "\n"


def test_markdown_figure_folder():
    assert render_markdown([Figure("f", "c")], figure_folder="img") == "![c](img/f.png)\n"


class _Tags(HTMLParser):
    def __init__(self):
        super().__init__()
        self.tags, self.text = [], []

    def handle_starttag(self, tag, attrs):
        self.tags.append((tag, dict(attrs)))

    def handle_data(self, data):
        self.text.append(data)


def test_html_escapes_text_and_is_self_contained():
    page = render_html(BLOCKS, {"fig": SVG})
    parser = _Tags()
    parser.feed(page)
    tags = [t for t, _ in parser.tags]
    assert "script" not in tags and "i" not in tags and "b" not in tags
    assert TRICKY in "".join(parser.text)  # shown as typed, '|' included
    assert "&lt;script&gt;" in page and "&amp;amp;" in page and "x &amp; y" in page
    assert not [a for _, attrs in parser.tags for a in ("src", "href") if a in attrs]
    assert not re.search(r"<link|@import|url\(", page)
    assert tags.count("svg") == 1 and "<?xml" not in page and "<!DOCTYPE svg" not in page
    assert page.startswith("<!DOCTYPE html>") and page.endswith("</html>\n")
    assert tags.count("th") == 2 and tags.count("td") == 2 and tags.count("li") == 2


def test_html_figure_without_its_svg_is_an_error():
    with pytest.raises(KeyError):
        render_html([Figure("missing", "c")], {})


def test_details_are_collapsed_in_html_and_a_details_element_in_markdown():
    inner = (Paragraph("p < 0.05 & more"), Table(("a",), (("x|y",),)))
    blocks = [Paragraph("first"), Details("How <it> was found", inner), Paragraph("last")]
    page = render_html(blocks, {})
    opened = page.index("<details><summary>How &lt;it&gt; was found</summary>")
    closed = page.index("</details>")
    assert page.index("<p>first</p>") < opened < page.index("<p>p &lt; 0.05 &amp; more</p>")
    assert page.index("<td>x|y</td>") < closed < page.index("<p>last</p>")
    assert "<details open" not in page
    markdown = render_markdown(blocks)
    assert "<details><summary>How &lt;it&gt; was found</summary>\n\np < 0.05 & more\n" in markdown
    assert "| x\\|y |\n\n</details>\n\nlast" in markdown
