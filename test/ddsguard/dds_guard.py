"""The ``dds`` marker made impossible to forget: a test that starts DDS without it fails.

Starting DDS always goes through ``rclpy.context.Context.init`` (``rclpy.init``, a node's ``main()``, ``roe-sep
run``, a campaign's runs, ``ros2`` and ``ros2 launch``). :func:`install` wraps it, in the test process (from
``test/conftest.py``) and in every Python process a test starts (``sitecustomize.py`` of this directory, which the
conftest puts first on ``PYTHONPATH``). While a test not marked ``dds`` runs, ``ROE_SEP_TEST_NO_DDS`` names a file:
an rclpy context initialised then is written to that file (pid and command line) and refused with an exception, and
the test fails naming the process and the marker (the hooks in ``test/conftest.py``). In a ``dds`` test the
variable is unset and nothing changes. Standard library only: every Python process of a session imports it.
"""

import functools
import importlib.abc
import importlib.machinery
import os
import sys
from pathlib import Path

ENV = "ROE_SEP_TEST_NO_DDS"


class DDSNotMarked(RuntimeError):
    """An rclpy context initialised by a test that is not marked ``dds``."""


def _guarded(init):
    @functools.wraps(init)
    def init_unless_forbidden(self, *args, **kwargs):
        path = os.environ.get(ENV)
        if path:
            who = f"pid {os.getpid()}: {' '.join([Path(sys.executable).name, *sys.argv])}"
            with open(path, "a", encoding="utf-8") as f:
                f.write(who + "\n")
            raise DDSNotMarked(f"rclpy context initialised in a test not marked dds ({who})")
        return init(self, *args, **kwargs)

    init_unless_forbidden.dds_guard = True
    return init_unless_forbidden


def _patch(module):
    context = module.Context
    if not getattr(context.init, "dds_guard", False):
        context.init = _guarded(context.init)


class _Finder(importlib.abc.MetaPathFinder):
    """Patches ``rclpy.context`` as soon as it is imported (nothing imports rclpy for a process that needs none)."""

    def find_spec(self, name, path, target=None):
        if name != "rclpy.context":
            return None
        spec = importlib.machinery.PathFinder.find_spec(name, path)
        if spec is None or spec.loader is None:
            return spec
        exec_module = spec.loader.exec_module

        def exec_and_patch(module):
            exec_module(module)
            _patch(module)

        spec.loader.exec_module = exec_and_patch
        return spec


def install():
    """Guard ``Context.init`` of this process: now if rclpy is imported, else when it is."""
    if "rclpy.context" in sys.modules:
        _patch(sys.modules["rclpy.context"])
    elif not any(isinstance(f, _Finder) for f in sys.meta_path):
        sys.meta_path.insert(0, _Finder())
