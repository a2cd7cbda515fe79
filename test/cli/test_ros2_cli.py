"""The real ``ros2`` command line against the colcon-built package (scripts/ros2_cli.sh): ``ros2 pkg executables``,
``ros2 run`` of every executable, ``ros2 node/topic/param/lifecycle/interface``, and ``ros2 launch`` of the whole
scenario to the same report as ``roe-sep run``. Selected with ``pytest -m ros2cli``; it needs the ros2cli/launch
source archives of ../shared/ros2_sources (README.md there) and skips without them."""

import json
import os
import re
import subprocess
from pathlib import Path

import pytest

from roe_sep.graph import dds_profile

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "scripts" / "ros2_cli.sh"
CHECKS = ROOT / "build" / "ros2cli" / "checks"
DURATION = 20000.0  # s of sim time: the ejection, the drift-stop, the first radar passes
NODES = ("planner", "radar", "radar_od", "ic_planner", "safety_monitor", "ejector", "ground_bridge", "recorder",
         "analysis_server", "foxglove_view", "sim")
MANAGED = ("planner", "radar", "radar_od", "ic_planner", "safety_monitor")

pytestmark = [pytest.mark.ros2cli, pytest.mark.dds]


def sources():
    """The archives where scripts/ros2_cli.sh looks for them (None: absent)."""
    if os.environ.get("ROS2_SOURCES"):
        return Path(os.environ["ROS2_SOURCES"])
    candidates = [ROOT.parent / "shared" / "ros2_sources"]
    common = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--path-format=absolute", "--git-common-dir"],
                            capture_output=True, text=True)
    if common.returncode == 0 and common.stdout.strip():
        candidates.append(Path(common.stdout.strip()).parent.parent / "shared" / "ros2_sources")
    return next((c for c in candidates if (c / "ros2cli-jazzy.tar.gz").is_file()), None)


@pytest.fixture(scope="module")
def checks():
    if sources() is None:
        pytest.skip("no ../shared/ros2_sources (the ros2cli/launch/launch_ros archives): the ros2 CLI is not built")
    env = dict(os.environ, ROS2_CLI_DURATION=str(DURATION), ROS_AUTOMATIC_DISCOVERY_RANGE="LOCALHOST")
    proc = subprocess.run(["bash", str(SCRIPT)], cwd=ROOT, env=env, capture_output=True, text=True, timeout=1500)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    return {p.stem: p.read_text(encoding="utf-8") for p in CHECKS.glob("*.txt")}


def section(text, title):
    """The lines of one ``==== title`` section of a check output."""
    part = text.split(f"==== {title}", 1)[1]
    return part.split("\n==== ", 1)[0]


def test_package_executables_and_interfaces(checks):
    listed = set(re.findall(r"^roe_sep (\S+)$", checks["static"], re.M))
    assert listed == {*NODES, "lifecycle_manager", "suite", "roe-sep"}, listed
    show = section(checks["static"], "interface show")
    assert "string strategy" in show and "ImpulsiveManeuver[] maneuvers" in show.replace("roe_sep_msgs/", "")


def test_every_executable_runs_and_is_seen(checks):
    nodes = set(re.findall(r"^/(\w+)$", section(checks["standalone"], "node list"), re.M))
    assert nodes == set(NODES), nodes
    topics = section(checks["standalone"], "topic list")
    for line in ("/separation/drift_stop_plan [roe_sep_msgs/msg/ManeuverPlan]", "/clock [rosgraph_msgs/msg/Clock]",
                 "/planner/transition_event [lifecycle_msgs/msg/TransitionEvent]"):
        assert line in topics
    # every managed node autostarts: configure -> activate in its constructor
    states = re.findall(r"^\$ ros2 lifecycle get /(\w+).*\n(.*)$", section(checks["standalone"], "lifecycle"), re.M)
    assert dict(states) == {n: "active [3]" for n in MANAGED}
    params = section(checks["standalone"], "param")
    assert "Integer value is: 3" in params and "Boolean value is: True" in params
    assert {"autostart", "k", "p_mode", "mc_samples", "use_sim_time"} <= set(re.findall(r"^  (\w+)$", params, re.M))
    echo = section(checks["standalone"], "topic echo/hz")
    assert "strategy: double_impulse" in echo and "purpose: drift_stop" in echo
    rate = float(re.search(r"average rate: ([0-9.]+)", echo).group(1))
    assert 0.5 < rate < 20.0  # every node's status, about 1 Hz (recorder, ground_bridge, ...)


def test_lifecycle_transitions_with_ros2_lifecycle_set(checks):
    managed = checks["managed"]
    states = re.findall(r"^(unconfigured \[1\]|inactive \[2\]|active \[3\])$",
                        section(managed, "lifecycle set"), re.M)
    assert states == ["unconfigured [1]", "inactive [2]", "active [3]"]
    assert section(managed, "lifecycle set").count("Transitioning successful") == 2
    bad = section(managed, "a parameter error at configure")
    assert "Transitioning failed" in bad and "unconfigured [1]" in bad
    assert "configure failed: parameter 'k' must be an odd integer in [1, 99], got 2" in bad


def test_invalid_transitions_leave_every_managed_node_running(checks):
    """Every managed node by ``ros2 run`` (autostart: active), ``ros2 run roe_sep lifecycle_manager`` beside them,
    then transitions invalid from 'active' sent with ``ros2 service call`` (ChangeState by id and by label) and ``ros2
    lifecycle set``: the manager adopted every node, each request was refused with a WARN, every node still runs and
    answers, and the manager exits 0 on SIGINT."""
    text = checks["lifecycle"]
    adopted = section(text, "manager beside active nodes")
    for name in MANAGED:
        assert f"/{name}: configure already done (state 'active'), adopted" in adopted, adopted
    assert "managed nodes active" in adopted and "ERROR" not in adopted
    sent = section(text, "invalid transitions")
    assert sent.count("ChangeState_Response(success=False)") == 2 * len(MANAGED), sent
    assert "success=True" not in sent
    assert sent.count("Unknown transition requested") == len(MANAGED), sent  # ros2 lifecycle set checks itself
    after = section(text, "after the invalid transitions")
    states = dict(re.findall(r"^\$ ros2 lifecycle get /(\w+).*\n(.*)$", after, re.M))
    assert states == dict.fromkeys(MANAGED, "active [3]"), after
    assert after.count("Boolean value is: True") == len(MANAGED), after  # each answers its parameter services
    running = section(text, "node processes")
    assert sorted(re.findall(r"^running: roe_sep (\w+)$", running, re.M)) == sorted([*MANAGED, "lifecycle_manager"])
    logs = section(text, "node logs")
    for name in MANAGED:
        assert f"[{name}]: transition 'configure' [1] refused: not valid from state 'active'" in logs, logs
        assert f"[{name}]: transition 'cleanup' refused: not valid from state 'active'" in logs, logs
    assert "Traceback" not in logs and "RCLError" not in logs and "ERROR" not in logs, logs
    assert "lifecycle_manager exit status 0" in section(text, "manager SIGINT")


def test_launch_runs_the_scenario_to_the_report_of_roe_sep_run(checks):
    reports = {name: json.loads((CHECKS / name / "report.json").read_text(encoding="utf-8"))
               for name in ("run", "launch", "launch_xml")}
    run = reports["run"]
    assert run["run"]["completed"] is True and run["duration"] == DURATION
    assert run["criteria"]["keep_out"] and run["criteria"]["plans_approved"]
    assert [m["purpose"] for m in run["maneuvers"]] == ["ejection", "drift_stop"]
    for name in ("launch", "launch_xml"):
        report = reports[name]
        assert report["run"]["completed"] is True, report["run"]
        # the nodes' DDS profile, as roe-sep run writes it (graph.dds_environment)
        assert (CHECKS / name / "fastdds.xml").read_text(encoding="utf-8") == dds_profile()
        assert report["run"]["reason"] == "scenario complete"
        for key in ("dv_total", "maneuvers", "criteria", "safe", "min_distance", "final_roe"):
            assert report[key] == run[key], (name, key)
    assert "lifecycle_manager]: managed nodes active" in checks["launch_xml"]
