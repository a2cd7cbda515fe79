"""``python -m roe_sep.cli``: the same as ``roe-sep``."""

from . import entry

entry()
