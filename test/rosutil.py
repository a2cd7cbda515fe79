"""Helpers for integration tests that start real node processes over DDS (localhost discovery only)."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

rclpy = pytest.importorskip("rclpy", reason="integration tests need the project venv (make test)")

ROOT = Path(__file__).resolve().parents[1]


def ros_env():
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
    env["PYTHONUNBUFFERED"] = "1"
    return env


def start_node(module, *ros_args):
    """Start ``python -m roe_sep.nodes.<module> --ros-args ...`` as its own process."""
    cmd = [sys.executable, "-m", f"roe_sep.nodes.{module}", "--ros-args", *ros_args]
    return subprocess.Popen(cmd, env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                            cwd=ROOT)


def stop_node(proc, timeout=10.0):
    """SIGINT, as a deployment's process manager would; returns (exit code, output)."""
    if proc.poll() is None:
        proc.send_signal(signal.SIGINT)
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
    return proc.returncode, out


def wait_exit(proc, timeout=30.0):
    """Wait for a process that should stop by itself; returns (exit code, output)."""
    try:
        out, _ = proc.communicate(timeout=timeout)
    except subprocess.TimeoutExpired:
        proc.kill()
        out, _ = proc.communicate()
        return None, out
    return proc.returncode, out


def spin_until(node, predicate, timeout=20.0):
    """Spin ``node`` until ``predicate()`` is true or ``timeout`` seconds pass; returns the predicate's value."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        rclpy.spin_once(node, timeout_sec=0.05)
        if predicate():
            return True
    return predicate()
