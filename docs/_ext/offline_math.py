"""Math typeset with no network: MathJax served from the built site, not from a CDN.

Sphinx's ``sphinx.ext.mathjax`` loads MathJax from a CDN by default, so a reader offline sees the
TeX source. This extension points it at ``_static/mathjax/tex-chtml.js`` instead (a path relative
to each page) and copies MathJax there when the build ends, from the ``django-static-mathjax``
package of the docs extra: MathJax's own release files (3.2.2), installed by pip with the rest
of the pinned tools; its small Django app is not used. Only what the ``tex-chtml`` component
loads is copied (:data:`PARTS`), about 7 MB of the release's 24.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

from sphinx.application import Sphinx

#: Where MathJax goes in the built site, under ``_static``.
TARGET = "mathjax"
#: The component the pages load: TeX in, HTML with CSS and web fonts out.
COMPONENT = "tex-chtml.js"
#: What that component loads from beside itself: the TeX extensions it loads on first use
#: (``autoload``), its fonts, the context menu, and the accessibility parts and speech rules
#: the menu turns on.
PARTS = (COMPONENT, "input/tex", "output/chtml", "ui", "a11y", "sre")


def release_folder() -> Path:
    """The installed MathJax release's browser files (its ``es5`` folder)."""
    spec = importlib.util.find_spec("mathjax")
    if spec is None or not spec.submodule_search_locations:
        raise RuntimeError(
            "MathJax is missing: install the docs extra (pip install -r requirements.lock)"
        )
    folder = Path(next(iter(spec.submodule_search_locations))) / "static" / "mathjax"
    if not (folder / "es5" / COMPONENT).is_file():
        raise RuntimeError(f"{folder / 'es5' / COMPONENT}: not found")
    return folder


def copy_mathjax(app: Sphinx, exception: Exception | None) -> None:
    """Copy :data:`PARTS` and MathJax's licence into the built site's ``_static``."""
    if exception is not None or app.builder.format != "html":
        return
    source = release_folder()
    out = Path(app.outdir) / "_static" / TARGET
    for part in PARTS:
        if (source / "es5" / part).is_dir():
            shutil.copytree(source / "es5" / part, out / part, dirs_exist_ok=True)
        else:
            out.mkdir(parents=True, exist_ok=True)
            shutil.copy2(source / "es5" / part, out / part)
    shutil.copy2(source / "LICENSE", out / "LICENSE")


def use_local_mathjax(app: Sphinx, config) -> None:
    # A path without a scheme is taken relative to _static and written relative to each page.
    config.mathjax_path = f"{TARGET}/{COMPONENT}"


def setup(app: Sphinx) -> dict:
    app.setup_extension("sphinx.ext.mathjax")
    release_folder()  # a missing package fails the build at its start, not at its end
    app.connect("config-inited", use_local_mathjax)
    app.connect("build-finished", copy_mathjax)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
