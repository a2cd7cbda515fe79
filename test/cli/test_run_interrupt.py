"""A Ctrl-C in the middle of a run's lockstep stepping stops it there, in both layouts.

The closed loop keeps an EventsExecutor's queue busy without a pause while it steps (each callback publishes what the
next one takes), and that executor's slice does not end at its timeout while its queue never empties: a Ctrl-C
used to wait for the end of the scenario (a 30-day run: the whole run), and a run in one process finished with
"scenario complete" as if no signal had come (roe_sep.nodes.spin now ends the slice with a timer)."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from rosutil import ROOT, ros_env

from roe_sep.bag import info

DURATION = 30 * 86400.0  # s of sim time: minutes of stepping, far more than the test waits


@pytest.mark.dds
@pytest.mark.parametrize("layout", ["suites", "in_process"])
def test_ctrl_c_mid_run_stops_the_stepping(layout, tmp_path):
    out = tmp_path / "run"
    log = out / "logs" / ("run.log" if layout == "in_process" else "loop.log")
    argv = ["run", "--seed", "3", "--duration", str(DURATION), "--out", str(out), "--timeout", "600"]
    argv += ["--in-process"] if layout == "in_process" else []
    env = dict(ros_env(), PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen([sys.executable, "-m", "roe_sep.cli", *argv], cwd=ROOT, env=env, text=True,
                            stdout=subprocess.PIPE, stderr=subprocess.STDOUT, start_new_session=True)
    try:
        deadline = time.monotonic() + 240
        while not (log.is_file() and "first truth" in log.read_text(errors="replace")):
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate(timeout=30)[0][-3000:]
            time.sleep(0.1)
        time.sleep(1.0)  # stepping
        os.killpg(proc.pid, signal.SIGINT)  # a terminal's Ctrl-C: the whole foreground group
        text = proc.communicate(timeout=120)[0]
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    report = json.loads((out / "report.json").read_text())
    assert report["run"]["completed"] is False, text[-3000:]
    assert report["run"]["reason"] == "interrupted (Ctrl-C)", report["run"]["reason"]
    assert proc.returncode != 0
    reached = info(out / "bag")["end_ns"] * 1e-9
    assert reached < DURATION / 2, f"the loop stepped on to t = {reached:.0f} s after the Ctrl-C"
