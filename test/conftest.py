"""Session set-up of every test: DDS on this machine only, and the ``dds`` marker guard (test/ddsguard/dds_guard.py):
a test not marked ``dds`` that initialises an rclpy context, here or in any process it starts, fails."""

import os
import sys
from pathlib import Path

import pytest

# DDS traffic stays on this machine in every test session (see scripts/test.sh for the domain id).
os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")

HERE = Path(__file__).resolve().parent
# the guard's plugin (test/ddsguard) by module name; the helpers shared across the mirrored directories (rosutil,
# bagutil, oracle, ndm_schema) are in test/ itself, which pytest puts on sys.path with this file
sys.path.insert(0, str(HERE / "ddsguard"))
from dds_plugin import (  # noqa: E402,F401  (the guard's hooks, this session's)
    pytest_configure,
    pytest_runtest_makereport,
    pytest_runtest_setup,
    pytest_unconfigure,
)


@pytest.fixture
def ros_context():
    """rclpy's default context, initialised for the test (``rosutil.init``: the session's DDS domain, localhost
    discovery) and shut down after it; ``rosutil.init(*ros_args)`` re-initialises it with ROS arguments. The test
    must be marked ``dds``."""
    from rosutil import context

    with context() as ctx:
        yield ctx
