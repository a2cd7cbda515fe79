"""Helpers for integration tests that start real node processes over DDS (localhost discovery only)."""

import contextlib
import math
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


def init(*ros_args):
    """(Re)initialise rclpy's default context in this process: the DDS domain the nodes a test starts get too
    (:func:`ros_env`'s ``ROS_DOMAIN_ID``), localhost discovery (test/conftest.py), and ``ros_args`` (what follows
    ``--ros-args``, e.g. ``"-p", "name:=value"``) for every node made in it. The context."""
    rclpy.try_shutdown()
    rclpy.init(args=["--ros-args", *ros_args] if ros_args else None, domain_id=int(ros_env()["ROS_DOMAIN_ID"]))
    return rclpy.get_default_context()


@contextlib.contextmanager
def context(*ros_args):
    """:func:`init` on entering, rclpy shut down on leaving (also when the test fails): the ``ros_context``
    fixture (test/conftest.py), and a module's fixtures or a helper process."""
    ctx = init(*ros_args)
    try:
        yield ctx
    finally:
        rclpy.try_shutdown()


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


def publish_until(node, send, predicate, timeout=30.0, period=0.5):
    """Call ``send()`` (it publishes) every ``period`` s while spinning ``node`` until ``predicate()`` holds.

    For an answer published once per message on a volatile topic (an ERROR status): whichever side of the
    discovery is slower, a later copy of the message meets a matched writer of the answer. Returns the predicate."""
    last = [-math.inf]

    def tick():
        if time.monotonic() - last[0] >= period:
            last[0] = time.monotonic()
            send()
        return predicate()

    return spin_until(node, tick, timeout=timeout)


def free_port():
    """A TCP port of 127.0.0.1 that nobody listens on (now)."""
    import socket

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _stat(pid):
    """(parent pid, state letter, start time in clock ticks) of a process from /proc, None if it is gone."""
    try:
        text = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return None
    fields = text[text.rindex(")") + 2:].split()  # after "pid (comm) "
    return int(fields[1]), fields[0], int(fields[19])


def _cmdline(pid):
    try:
        return Path(f"/proc/{pid}/cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace").strip()
    except OSError:
        return ""


def descendants(pid):
    """Every process below ``pid`` now (children, their children, ...): {pid: (start time, command line)}; a walk
    of /proc by parent pid. Kept with the start time, so that a reused pid is not taken for the process."""
    parents = {}
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            st = _stat(int(entry.name))
            if st is not None:
                parents.setdefault(st[0], []).append((int(entry.name), st[2]))
    found, todo = {}, [pid]
    while todo:
        for child, start in parents.get(todo.pop(), ()):
            if child not in found:
                found[child] = (start, _cmdline(child))
                todo.append(child)
    return found


def still_running(procs):
    """The processes of a :func:`descendants` capture that still run (not gone, not a zombie, not a reused pid)."""
    left = {}
    for pid, (start, cmd) in procs.items():
        st = _stat(pid)
        if st is not None and st[2] == start and st[1] != "Z":
            left[pid] = cmd
    return left


def wait_gone(procs, timeout=60.0):
    """Wait until no process of ``procs`` (a :func:`descendants` capture) runs; returns those still running."""
    deadline = time.monotonic() + timeout
    while still_running(procs) and time.monotonic() < deadline:
        time.sleep(0.2)
    return still_running(procs)


DDS_SHM = Path("/dev/shm")


def dds_segments():
    """Names of the Fast DDS shared-memory segments of participants in /dev/shm (``fastrtps_`` and 16 hex digits; not
    the ports')."""
    import re

    if not DDS_SHM.is_dir():
        return set()
    return {p.name for p in DDS_SHM.iterdir() if re.fullmatch(r"fastrtps_[0-9a-f]{16}", p.name)}


def stale_dds_segments():
    """:func:`dds_segments` whose owner has gone (the segment's ``_el`` file is not locked): the participant of a
    process that ended without deleting it (killed, or ``os._exit`` with its nodes still alive)."""
    import fcntl

    found = set()
    for name in dds_segments():
        try:
            fd = os.open(DDS_SHM / f"{name}_el", os.O_RDONLY)
        except OSError:
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:  # locked: its participant lives
            continue
        else:
            fcntl.flock(fd, fcntl.LOCK_UN)
            found.add(name)
        finally:
            os.close(fd)
    return found
