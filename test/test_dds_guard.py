"""The ``dds`` marker guard (test/ddsguard) as a test: an inner pytest session with the guard's plugin, over tests
that initialise rclpy unmarked (in the test process, in a child process) and tests that do not. No DDS starts: the
guard refuses the initialisation itself."""

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

GUARD_DIR = Path(__file__).resolve().parent / "ddsguard"

INNER = '''
import subprocess
import sys

import pytest


def test_rclpy_init_in_the_test():
    import rclpy

    rclpy.init()


def test_rclpy_init_in_a_child_that_fails_quietly():
    subprocess.run([sys.executable, "-c", "import rclpy; rclpy.init()"], capture_output=True)


def test_rclpy_init_in_a_fixture(context):
    pass


@pytest.fixture
def context():
    import rclpy

    rclpy.Context().init()


def test_rclpy_imported_without_dds():
    subprocess.run([sys.executable, "-c", "import rclpy.context"], check=True)
    import rclpy  # noqa: F401


@pytest.mark.dds
def test_marked_without_dds():
    pass
'''


def test_unmarked_dds_fails_and_names_the_process(tmp_path):
    pytest.importorskip("rclpy", reason="the guard wraps rclpy's Context.init")
    (tmp_path / "test_inner.py").write_text(INNER)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(filter(None, [str(GUARD_DIR), os.environ.get("PYTHONPATH")])))
    proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "dds_plugin", "-p", "no:cacheprovider", "-q", "-rA",
                           str(tmp_path)], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=300)
    out = proc.stdout
    outcome = dict((name, word) for word, name in re.findall(r"^(PASSED|FAILED|ERROR) test_inner.py::(\w+)", out,
                                                              re.MULTILINE))
    assert outcome == {"test_rclpy_init_in_the_test": "FAILED",
                       "test_rclpy_init_in_a_child_that_fails_quietly": "FAILED",
                       "test_rclpy_init_in_a_fixture": "ERROR",
                       "test_rclpy_imported_without_dds": "PASSED",
                       "test_marked_without_dds": "PASSED"}, out[-3000:]
    assert proc.returncode == 1
    assert out.count("not marked dds: add @pytest.mark.dds") >= 3, out[-3000:]
    assert re.search(r"pid \d+: python\S* -c$", out, re.MULTILINE), out[-3000:]  # the child, by its command line


@pytest.mark.dds
def test_the_ros_context_fixture_is_initialised_in_the_sessions_domain_and_shut_down(ros_context):
    """The ``ros_context`` fixture (test/conftest.py): rclpy's default context, initialised in the domain the nodes a
    test starts get (``rosutil.ros_env``); ``rosutil.context`` shuts it down on leaving, also after a failure."""
    from rosutil import context, rclpy, ros_env

    assert ros_context is rclpy.get_default_context() and ros_context.ok()
    assert ros_context.get_domain_id() == int(ros_env()["ROS_DOMAIN_ID"])
    with pytest.raises(RuntimeError, match="inside"):
        with context("-p", "x:=1") as ctx:
            assert ctx.ok()
            raise RuntimeError("inside")
    assert not ctx.ok()
