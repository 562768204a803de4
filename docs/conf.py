"""Sphinx configuration of warpsim's manual (MyST Markdown pages, API reference from the docstrings).

Build: ``pip install -e '.[docs]'`` then ``sphinx-build -W -b html docs docs/_build/html`` (``.ci/run`` does).
"""

from __future__ import annotations

from pathlib import Path

import warpsim

HERE = Path(__file__).resolve().parent

project = "warpsim"
author = "warpsim developers"
copyright = "2026, warpsim developers"
release = version = warpsim.__version__

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
]

source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store"]

# MyST: `#heading` anchors for links between pages (`outputs.md#blow-ups`), `$...$` maths left as written
myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence", "deflist"]

# The API page documents only the public names of `warpsim` (its __init__ exports them lazily), so it survives
# modules moving behind them. Members in source order, as written.
autodoc_member_order = "bysource"
autodoc_typehints = "description"
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": False}
napoleon_google_docstring = True
napoleon_numpy_docstring = False
# a class docstring's "Attributes:" become fields of the class, not a second description of each dataclass field
napoleon_use_ivar = True

html_theme = "pydata_sphinx_theme"
html_title = "warpsim"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "secondary_sidebar_items": ["page-toc"],
}
html_static_path: list[str] = []
