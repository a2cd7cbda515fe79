"""The pytest side of the ``dds`` marker guard (:mod:`dds_guard`): ``test/conftest.py`` takes these hooks; another
session takes them with ``-p dds_plugin`` (this directory on PYTHONPATH), as ``test/test_dds_guard.py`` does.

Before each test's fixtures the guard is armed (not ``dds``) or disarmed (``dds``); after each phase a test not
marked ``dds`` fails if an rclpy context was initialised meanwhile, here or in any process it started, naming the
processes."""

import os
import tempfile
from pathlib import Path

import dds_guard
import pytest

GUARD_DIR = Path(dds_guard.__file__).resolve().parent
_PATH = pytest.StashKey[str]()
_SEEN = pytest.StashKey[int]()


def pytest_configure(config):
    dds_guard.install()
    config.addinivalue_line("markers", "dds: starts DDS (an rclpy context, here or in a process the test starts)")
    # every Python process a test starts imports ddsguard/sitecustomize.py, which guards it the same way
    os.environ["PYTHONPATH"] = os.pathsep.join(filter(None, [str(GUARD_DIR), os.environ.get("PYTHONPATH")]))
    fd, path = tempfile.mkstemp(prefix="roe_sep_dds_guard_", suffix=".txt")
    os.close(fd)
    config.stash[_PATH] = path


def pytest_unconfigure(config):
    os.environ.pop(dds_guard.ENV, None)
    if _PATH in config.stash:
        Path(config.stash[_PATH]).unlink(missing_ok=True)


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """Before the test's fixtures: a ``dds`` test may start DDS, any other test is watched."""
    item.stash[_SEEN] = 0
    if item.get_closest_marker("dds"):
        os.environ.pop(dds_guard.ENV, None)
    else:
        Path(item.config.stash[_PATH]).write_text("", encoding="utf-8")
        os.environ[dds_guard.ENV] = item.config.stash[_PATH]


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """A phase (setup, call, teardown) of a test not marked ``dds`` during which an rclpy context was initialised
    fails, naming the processes."""
    report = yield
    if item.get_closest_marker("dds") or _PATH not in item.config.stash:
        return report
    try:
        started = Path(item.config.stash[_PATH]).read_text(encoding="utf-8").splitlines()
    except FileNotFoundError:
        return report
    new = started[item.stash.get(_SEEN, 0):]
    if new:
        item.stash[_SEEN] = len(started)
        text = "\n".join(["this test starts DDS (an rclpy context) but is not marked dds: add @pytest.mark.dds",
                          *(f"  {line}" for line in new)])
        if report.outcome == "failed":
            report.sections.append(("dds guard", text))
        else:
            report.outcome, report.longrepr = "failed", text
    return report
