"""Sphinx configuration of the trueaniso manual (Markdown pages through myst-parser)."""
import os
import sys

DOCS = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.dirname(DOCS)
sys.path[:0] = [os.path.join(DOCS, "_ext"), os.path.join(REPO, "pyscripts")]

project = "trueaniso"
author = "the trueaniso authors"
copyright = "the trueaniso authors"

extensions = ["myst_parser", "sphinx.ext.autodoc", "sphinx.ext.napoleon", "sphinx.ext.mathjax", "trueaniso_manual"]
source_suffix = {".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "data/**", "Thumbs.db", ".DS_Store"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

html_theme = "sphinx_rtd_theme"
html_title = "trueaniso manual"
html_static_path = ["_static"]
html_css_files = ["trueaniso.css"]  # table cells wrap (the theme clips a wide table's last column)

# Docstrings are Google style (Args:, Returns:, Raises:, Example:), read by napoleon; `name` in a
# docstring is code, linked when it names something documented.
napoleon_google_docstring = True
napoleon_numpy_docstring = False
napoleon_use_rtype = False
default_role = "py:obj"
autodoc_member_order = "bysource"
autodoc_mock_imports = ["yade"]
autodoc_preserve_defaults = True  # defaults as written (REPO_ROOT), not this checkout's path

# MathJax from Debian's libjs-mathjax (2.7, copied into the built manual's _static by
# trueaniso_manual), so that formulas render without a network; where it is not installed, Sphinx's
# default (MathJax 3 from a CDN).
if os.path.exists("/usr/share/javascript/mathjax/MathJax.js"):
    trueaniso_mathjax_dir = "/usr/share/javascript/mathjax"
    mathjax_path = "mathjax/MathJax.js?config=TeX-AMS_CHTML"
    # MathJax 2 reads only the formulas (myst marks the page's text to be ignored, so that a $ in
    # prose is a dollar); myst sets this for MathJax 3 only.
    mathjax2_config = {"tex2jax": {"processClass": "tex2jax_process|mathjax_process|math|output_area"}}
