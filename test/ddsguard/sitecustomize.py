"""Imported by every Python process of a test session (``test/conftest.py`` puts this directory on PYTHONPATH):
the ``dds`` marker guard of :mod:`dds_guard` in that process."""

import dds_guard

dds_guard.install()
