"""No process of ours outlives its parent: ``roe-sep replay --foxglove``, ``roe-sep run`` and ``roe-sep campaign``
stopped by SIGTERM, SIGINT or SIGHUP (as a process manager, a Ctrl-C or a closed terminal stops them), or killed
(SIGKILL), leave none of the processes below them running (the tree walked in /proc just before the signal). A
stopped command exits with 128 + the signal's number (``run`` with its INCOMPLETE report, status 1)."""

import json
import os
import signal
import socket
import subprocess
import sys
import time

import pytest
from rosutil import ROOT, descendants, free_port, ros_env, wait_gone

SIGNALS = [signal.SIGTERM, signal.SIGINT, signal.SIGHUP, signal.SIGKILL]
BAG = ROOT / "bags" / "default_run"


def _domains():
    own = int(os.environ.get("ROS_DOMAIN_ID", "0") or 0)
    return os.environ.get("ROE_SEP_TEST_CAMPAIGN_DOMAINS", f"{own}-{own}")


LONG = str(30 * 86400)  # s of sim time: a run still under way when the signal comes (seconds of wall time, not one)


def command(name, tmp_path):
    """(argv, what must be running below the parent before the signal: {command-line part: count}, the port)."""
    if name == "replay":
        port = free_port()
        return (["replay", str(BAG), "--rate", "2000", "--clock", "--foxglove", str(port)],
                {"roe_sep.nodes.foxglove_view": 1}, port)
    if name == "run":
        return (["run", "--out", str(tmp_path / "run"), "--timeout", "600", "--duration", LONG],
                {"roe_sep.nodes.suite": 2}, None)
    return (["campaign", "--runs", "1", "--workers", "1", "--duration", LONG, "--out", str(tmp_path / "c"),
             "--domains", _domains(), "--open-loop-samples", "100", "--no-figures", "--json"],
            {"roe_sep.campaign.forkserver": 2}, None)


def wait_for(proc, wanted, timeout=240.0):
    """The process tree below ``proc`` once it holds ``wanted`` ({command-line part: count})."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline and proc.poll() is None:
        tree = descendants(proc.pid)
        if all(sum(part in cmd for _, cmd in tree.values()) >= n for part, n in wanted.items()):
            return tree
        time.sleep(0.2)
    out, err = proc.communicate(timeout=30) if proc.poll() is not None else ("", "")
    raise AssertionError(f"{wanted} never ran below the parent (exit {proc.poll()}): {err[-2000:]}")


def port_free(port):
    with socket.socket() as s:
        try:
            s.bind(("127.0.0.1", port))
        except OSError:
            return False
    return True


@pytest.mark.dds
@pytest.mark.parametrize("sig", SIGNALS, ids=lambda s: s.name)
@pytest.mark.parametrize("name", ["replay", "run", "campaign"])
def test_no_process_outlives_its_parent(name, sig, tmp_path):
    argv, wanted, port = command(name, tmp_path)
    env = dict(ros_env(), PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "roe_sep.cli", *argv], cwd=ROOT, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True)
    tree = {}
    try:
        tree = wait_for(proc, wanted)
        time.sleep(1.0)  # the children under way (the view serving, the nodes spinning)
        tree.update(descendants(proc.pid))
        proc.send_signal(sig)  # to the parent alone: its children are in process groups of their own
        out, err = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
        left = wait_gone(tree, timeout=60.0)
        for pid in left:  # the test leaves nothing behind either
            os.kill(pid, signal.SIGKILL)
    assert left == {}, f"still running after the parent ended: {left}"
    if sig == signal.SIGKILL:
        assert proc.returncode == -signal.SIGKILL
    elif name == "run":
        rep = json.loads((tmp_path / "run" / "report.json").read_text())
        assert proc.returncode == 1 and rep["safe"] is None, err[-2000:]
        assert rep["run"]["reason"] == ("interrupted (Ctrl-C)" if sig == signal.SIGINT else f"interrupted ({sig.name})")
    else:
        assert proc.returncode == 128 + sig, err[-2000:]
        assert "Traceback" not in err, err[-2000:]
    if port is not None:
        assert port_free(port), f"port {port} still held"
