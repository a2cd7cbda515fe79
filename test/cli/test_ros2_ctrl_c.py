"""Ctrl-C with the real ``ros2`` command line of scripts/ros2_cli.sh (``pytest -m ros2cli``; skips without its
sources), as a user meets it:

* ``ros2 launch roe_sep separation.launch.py`` (and its XML front end) mid-run: every node finishes cleanly, launch
  exits 0 without an ``[ERROR]`` (no second Shutdown event that would shut launch_ros's ROS adapter down twice; no
  node killed by launch's late SIGINT while it exits), the report says why the run ended, and no process is left;
* ``ros2 run roe_sep lifecycle_manager`` alone, waiting for its nodes: ``ros2 param list /lifecycle_manager``
  answers, and Ctrl-C ends it with status 0."""

import json
import os
import signal
import subprocess
import threading
import time

import pytest
from rosutil import ROOT, descendants, ros_env, wait_gone
from test_ros2_cli import SCRIPT, sources

from roe_sep.graph import graph_nodes

pytestmark = [pytest.mark.ros2cli, pytest.mark.dds]


@pytest.fixture(scope="module")
def ros2_env():
    """The environment of the colcon-built package (``scripts/ros2_cli.sh setup``, cached)."""
    if sources() is None:
        pytest.skip("no ../shared/ros2_sources (the ros2cli/launch/launch_ros archives): the ros2 CLI is not built")
    env = dict(ros_env(), ROS2_SOURCES=str(sources()))
    setup = subprocess.run(["bash", str(SCRIPT), "setup"], cwd=ROOT, env=env, capture_output=True, text=True,
                           timeout=1500)
    assert setup.returncode == 0, setup.stdout[-3000:] + setup.stderr[-3000:]
    dump = subprocess.run(["bash", "-c", "source build/ros2cli/env.sh && source build/ros2cli/ws/install/local_setup"
                           ".bash && env -0"], cwd=ROOT, env=env, capture_output=True, check=True)
    return dict(item.split("=", 1) for item in dump.stdout.decode().split("\0") if "=" in item)


@pytest.mark.parametrize("front_end", ["separation.launch.py", "separation.launch.xml"])
def test_ctrl_c_mid_run_exits_0_without_error_and_leaves_no_process(ros2_env, front_end, tmp_path):
    out = tmp_path / "launch"
    proc = subprocess.Popen(["ros2", "launch", "roe_sep", front_end, f"output:={out}", "seed:=1"], cwd=ROOT,
                            env=ros2_env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            start_new_session=True)  # its own group: the terminal's, which Ctrl-C signals
    lines = []
    reader = threading.Thread(target=lambda: lines.extend(proc.stdout), daemon=True)
    reader.start()
    tree = {}
    try:
        deadline = time.monotonic() + 300.0
        while proc.poll() is None and time.monotonic() < deadline and not any(
                "executed drift_stop" in line for line in list(lines)):  # mid-run: the loop is closed and turning
            time.sleep(0.2)
        assert proc.poll() is None, "".join(lines)[-3000:]
        tree = descendants(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C: launch and every node at once
        proc.wait(timeout=180)
        reader.join(timeout=10)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
        left = wait_gone(tree, timeout=60.0)
        for pid in left:
            os.kill(pid, signal.SIGKILL)
    text = "".join(lines)
    assert proc.returncode == 0, text[-3000:]
    died = [line.split("]")[1].strip(" [") for line in lines if "process has died" in line]  # e.g. 'ejector-8'
    assert "[ERROR]" not in text, ([line for line in lines if "[ERROR]" in line]
                                   + [line for line in lines if any(f"[{name}]" in line for name in died)][-40:])
    expected = len(graph_nodes())  # every node of the graph (the radar sensor since the split: 9)
    assert text.count("process has finished cleanly") == expected, text[-3000:]
    assert left == {}, left
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["reason"] == "launch shut down (ctrl-c (SIGINT))" and report["run"]["completed"] is False


def test_lifecycle_manager_alone_answers_ros2_param_list_and_exits_0_on_ctrl_c(ros2_env):
    proc = subprocess.Popen(["ros2", "run", "roe_sep", "lifecycle_manager", "--ros-args", "-p",
                             "node_names:=[nobody_here]"], cwd=ROOT, env=ros2_env, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True, start_new_session=True)
    listed = None
    try:
        deadline = time.monotonic() + 120.0
        while proc.poll() is None and time.monotonic() < deadline:
            try:  # never the ros2 daemon: it would outlive the test
                ask = subprocess.run(["ros2", "param", "list", "/lifecycle_manager", "--no-daemon", "--spin-time", "3"],
                                     env=ros2_env, capture_output=True, text=True, timeout=60)
            except subprocess.TimeoutExpired:  # no answer
                continue
            if ask.returncode == 0 and "node_names" in ask.stdout:
                listed = ask.stdout
                break
            time.sleep(1.0)
        tree = descendants(proc.pid)
        os.killpg(proc.pid, signal.SIGINT)  # Ctrl-C: ros2 run and the manager
        out, _ = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.communicate()
    assert listed is not None and "timeout" in listed, out
    assert proc.returncode == 0, out
    assert "Traceback" not in out, out
    assert wait_gone(tree, timeout=30.0) == {}
