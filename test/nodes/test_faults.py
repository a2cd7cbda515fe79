"""Fault injection: every node of a running `roe-sep run` killed in turn, and every subscribed topic
fuzzed while the closed loop runs. Marked ``fault`` (``pytest -m fault`` runs them apart, ``make chaos`` runs them
with more cases); they are part of ``make test``.

Killed node: the runner ends with one line naming the node, its exit status and its last log line, writes a strict
report.json (``safe`` null or false), recovers the bag itself when the recorder died, and exits non-zero; never a
Python traceback. Fuzzed topics: no node dies, each bad message is an ERROR on /diagnostics naming the topic and
field, and the run completes safe.
"""

import json
import math
import os
import signal
import subprocess
import sys
import time

import pytest
from roe_sep_msgs.msg import (  # noqa: E402
    EjectionEvent,
    ImpulsiveManeuver,
    ManeuverPlan,
    OrbitDetermination,
    RelativeOrbitalElements,
    SafetyStatus,
)
from rosutil import ROOT, context, descendants, rclpy, ros_env  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.bag import info  # noqa: E402
from roe_sep.jsonutil import loads_strict  # noqa: E402
from roe_sep.nodes.convert import maneuver_msg, sec_to_time  # noqa: E402
from roe_sep.run import NODES, SUITES, run  # noqa: E402

pytestmark = [pytest.mark.fault, pytest.mark.dds]
COUNTS = {"killed": 0, "reason_named": 0, "reports_strict": 0, "bags_readable": 0, "tracebacks": 0}


def start_run(out, *args):
    cmd = [sys.executable, "-m", "roe_sep.cli", "run", "--out", str(out), "--json", *args]
    return subprocess.Popen(cmd, env=ros_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)


def wait_for_text(path, text, timeout):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if path.exists() and text in path.read_text(errors="replace"):
            return True
        time.sleep(0.2)
    return False


def node_pid(node, out):
    """The pid of a node's process, or of a suite process (``loop``: the one with the sim; ``listeners``)."""
    params = str(out / "params.yaml")
    if node in SUITES:
        pattern = f"roe_sep.nodes.suite .*{'sim' if node == 'loop' else 'recorder'}.* --ros-args --params-file {params}"
    else:
        pattern = f"roe_sep.nodes.{node} --ros-args --params-file {params}"
    found = subprocess.run(["pgrep", "-f", pattern], capture_output=True, text=True).stdout.split()
    return int(found[0]) if found else None


def still_there(parent, out):
    """What a run that does not end is doing: its processes still running, and the last lines of every log."""
    lines = [f"  pid {pid}: {cmd[:160]}" for pid, (_, cmd) in descendants(parent).items()]
    for log in sorted((out / "logs").glob("*.log")):
        tail = log.read_text(errors="replace").splitlines()[-3:]
        lines += [f"  {log.name}: {line[:200]}" for line in tail]
    return "\n".join(lines)


@pytest.mark.parametrize("node", NODES + SUITES)
def test_killing_a_node_mid_run(tmp_path, node):
    """A node's process killed (``--process-per-node``), or one of the two processes of the default layout."""
    out = tmp_path / "run"
    layout = [] if node in SUITES else ["--process-per-node"]
    proc = start_run(out, "--duration", "40000", "--real-time-factor", "4000", *layout)  # 10 s of stepping
    try:
        log = "loop.log" if node in SUITES else "sim.log"
        # after the drift-stop (t = 9156 s of 40000): the recorder has flushed part of the bag before it is killed
        assert wait_for_text(out / "logs" / log, "executed drift_stop", 120), "the run did not start"
        pid = node_pid(node, out)
        assert pid is not None, node
        os.kill(pid, signal.SIGKILL)
        COUNTS["killed"] += 1
        # normally 2-4 s. The runner SIGKILLs what has not stopped 120 s after its SIGINT (run.Deployment.stop):
        # a process stuck in DDS after the kill (a shared-memory lock the killed process held) still ends, and so
        # does the run, with its report; the exit codes printed below show it (-9)
        try:
            stdout, stderr = proc.communicate(timeout=300)
        except subprocess.TimeoutExpired:
            pytest.fail(f"the run did not end within 300 s of the kill\n{still_there(proc.pid, out)}")
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode not in (0, None), (proc.returncode, stderr)
    COUNTS["tracebacks"] += "Traceback" in stderr
    assert "Traceback" not in stderr, stderr
    rep = loads_strict((out / "report.json").read_text())  # written, and strict JSON
    COUNTS["reports_strict"] += 1
    assert json.loads(stdout) == rep
    assert rep["safe"] in (None, False) and rep["run"]["completed"] is False
    reason = rep["run"]["reason"]
    assert node in reason and "last log line" in reason and "signal 9" in reason, reason
    COUNTS["reason_named"] += 1
    bag = out / ("bag_recovered" if node in ("recorder", "listeners") else "bag")
    if node in ("recorder", "listeners"):
        recovered = rep["run"]["bag_recovered"]
        assert recovered["messages"] > 0 and recovered["seconds_lost"] is not None
    assert info(bag)["message_count"] > 0
    COUNTS["bags_readable"] += 1
    print(f"\n[faults] kill {node}: {reason[:160]}; exit codes {rep['run']['exit_codes']}")
    print(f"[faults] {COUNTS}")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_stopping_an_in_process_run(tmp_path, sig):
    """``roe-sep run --in-process`` (every node in the runner's process, a campaign's layout) stopped by a signal
    mid-run: the nodes stop in order (the recorder first), the bag is complete, the report says why, no traceback."""
    out = tmp_path / "run"
    proc = start_run(out, "--duration", "40000", "--real-time-factor", "4000", "--in-process")
    try:
        assert wait_for_text(out / "logs" / "run.log", "executed drift_stop", 120), "the run did not start"
        proc.send_signal(sig)
        stdout, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 1 and "Traceback" not in stderr, (proc.returncode, stderr)
    rep = loads_strict((out / "report.json").read_text())
    assert json.loads(stdout) == rep
    why = "Ctrl-C" if sig == signal.SIGINT else "SIGTERM"  # the words of the other layouts
    assert rep["run"]["completed"] is False and rep["run"]["reason"] == f"interrupted ({why})"
    assert rep["safe"] is None and rep["run"]["layout"] == "one process (events executor)"
    assert "bag_recovered" not in rep["run"] and info(out / "bag")["complete"]
    assert [m["purpose"] for m in rep["maneuvers"]][:2] == ["ejection", "drift_stop"]
    assert "bag closed: " in (out / "logs" / "run.log").read_text()


def bad_messages():
    """One invalid message of each type a node reads (NaN, inf, impossible orbit, unknown spacecraft, bad size)."""
    truth = RelativeOrbitalElements(a_da=math.nan)
    truth.chief.semi_major_axis = 7.0e6
    truth.header.stamp = sec_to_time(100.0)
    event = EjectionEvent()
    event.header.stamp = sec_to_time(300.0)
    event.ejection = maneuver_msg(300.0, 0.0, [math.inf, 0.0, 0.0], "picosatellite", "ejection")
    plan = ManeuverPlan(strategy="double_impulse")
    plan.header.stamp = sec_to_time(5.0)
    plan.maneuvers = [maneuver_msg(9000.0, 0.0, [0.1, 0.0, 0.0], "the moon", "drift_stop")]
    od = OrbitDetermination()
    od.header.stamp = sec_to_time(50.0)
    od.estimate.chief.semi_major_axis = 1.0  # inside the Earth
    executed = maneuver_msg(10.0, 0.0, [1e6, 0.0, 0.0], "carrier", "drift_stop")
    check = SafetyStatus(source="")
    return {
        interfaces.TRUTH_ROE_TOPIC: (RelativeOrbitalElements, interfaces.STREAM, truth),
        interfaces.EJECTION_TOPIC: (EjectionEvent, interfaces.LATCHED, event),
        interfaces.DRIFT_STOP_PLAN_TOPIC: (ManeuverPlan, interfaces.LATCHED, plan),
        interfaces.ACQUISITION_PLAN_TOPIC: (ManeuverPlan, interfaces.LATCHED, plan),
        interfaces.OD_TOPIC: (OrbitDetermination, interfaces.LATCHED, od),
        interfaces.EXECUTED_TOPIC: (ImpulsiveManeuver, interfaces.EXECUTED, executed),
        interfaces.PLAN_CHECK_TOPIC: (SafetyStatus, interfaces.EXECUTED, check),
    }


def fuzz_main(seconds):
    """The fuzzer process: every bad message on every topic, 20 times a second, for ``seconds``; prints the count."""
    with context():
        node = rclpy.create_node("fuzzer")
        pubs = [(node.create_publisher(cls, topic, qos), msg) for topic, (cls, qos, msg) in bad_messages().items()]
        sent, end = 0, time.monotonic() + seconds
        while time.monotonic() < end:
            for pub, msg in pubs:
                pub.publish(msg)
                sent += 1
            time.sleep(0.05)
        node.destroy_node()
    print(sent)


@pytest.mark.parametrize("per_node", [True, False], ids=["process_per_node", "suites"])
def test_fuzzing_every_subscribed_topic(tmp_path, per_node):
    """A fuzzer publishes invalid messages on every topic a node reads while the run starts and steps; then it
    stops and leaves the graph, and the closed loop completes safe: with a process per node, and in the default
    layout, where an exception escaping one node's callback would stop every node of its process."""
    path = os.pathsep.join([str(ROOT / "test" / "nodes"), str(ROOT / "test"), os.environ.get("PYTHONPATH", "")])
    fuzzer = subprocess.Popen([sys.executable, "-c", "import test_faults; test_faults.fuzz_main(25.0)"],
                              env={**ros_env(), "PYTHONPATH": path},
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT / "test")
    try:
        result = run(out=tmp_path / "fuzzed", duration=100000.0, timeout=600, real_time_factor=100000.0 / 30.0,
                     process_per_node=per_node)
    finally:
        out, err = fuzzer.communicate(timeout=60)
    sent = int(out.strip().splitlines()[-1]) if out.strip() else 0
    assert sent > 100, err
    codes = result["run"]["exit_codes"]
    assert result["run"]["completed"], result["run"]
    assert all(code == 0 for code in codes.values()), codes  # no node died
    assert result["safe"], result["criteria"]
    if per_node:
        logs = {n: (tmp_path / "fuzzed" / "logs" / f"{n}.log").read_text() for n in NODES}
    else:  # the suites' logs, split by the node name rclpy writes on every line
        lines = "".join((tmp_path / "fuzzed" / "logs" / f"{s}.log").read_text() for s in SUITES).splitlines()
        logs = {n: "\n".join(ln for ln in lines if f"] [{n}]: " in ln) for n in NODES}
    rejected = {n: log.count("rejected [") for n, log in logs.items()}
    assert all(rejected[n] > 0 for n in ("sim", "safety_monitor", "radar_od", "ic_planner", "planner")), rejected
    print(f"\n[faults] fuzz: {sent} bad messages sent, rejections logged per node {rejected}, run safe")
