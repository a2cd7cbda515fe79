"""Sphinx configuration of the API reference (``make docs``): autodoc + autosummary over the pure packages.

The reference is generated from the docstrings (numpydoc reads their sections); nothing in it is written by hand
but index.rst. Built with warnings as errors by ``make docs`` and by test/test_api_docs.py.
"""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

project = "roe_sep"
extensions = ["sphinx.ext.autodoc", "sphinx.ext.autosummary", "sphinx.ext.mathjax", "numpydoc"]
autosummary_generate = True
autosummary_imported_members = False
autodoc_default_options = {"members": True, "undoc-members": False, "show-inheritance": True}
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_validation_checks = set()
numpydoc_xref_param_type = False
default_role = "py:obj"
nitpicky = False
exclude_patterns = ["_build", "generated/*.rst.tmp"]
html_theme = "alabaster"
html_title = "roe_sep API reference"


def _plain_bars(app, what, name, obj, options, lines):
    """The docstrings write absolute values and norms as ``|x|`` (plain text, as in the seeds): escape the bars so
    that reStructuredText does not read them as substitutions (no docstring uses a line block or a grid table)."""
    lines[:] = [line.replace("|", r"\|") for line in lines]


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars, priority=400)
