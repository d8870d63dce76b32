"""Sphinx configuration of the trueaniso manual (Markdown pages through myst-parser)."""
import os
import sys

DOCS = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(DOCS)
sys.path[:0] = [os.path.join(DOCS, "_ext"), os.path.join(REPO, "pyscripts")]

project = "trueaniso"
author = "the trueaniso authors"
copyright = "the trueaniso authors"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.mathjax", "trueaniso_manual"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "data/**", "Thumbs.db", ".DS_Store"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

html_theme = "sphinx_rtd_theme"
html_title = "trueaniso manual"

autodoc_member_order = "bysource"
autodoc_mock_imports = ["yade"]
autodoc_preserve_defaults = True  # defaults as written (REPO_ROOT), not this checkout's path
