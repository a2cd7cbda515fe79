"""Decisions survive a restart (issue 41 part 5, docs/run.md "Decisions"): a planner or ic_planner killed (SIGKILL)
and restarted reads its decision record back from the ground_bridge, which keeps it latched, and never publishes a
withdrawn or superseded plan again -- after a hold, after a replacement, mid-acquisition. Without the record (the
control: ``recover_timeout:=0``) the restarted node plans its latched inputs afresh, which is what the record
prevents."""

import json
import math
import signal

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from geometry_msgs.msg import Vector3Stamped  # noqa: E402
from roe_sep_msgs.msg import EjectionEvent, ImpulsiveManeuver, ManeuverPlan, OrbitDetermination  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import rclpy, spin_until, start_node, stop_node  # noqa: I001  (skips without rclpy)
from std_msgs.msg import String  # noqa: E402
from test_ic_planner_node import MARGIN, ROE0, T_OD, od_message  # noqa: E402

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.config import load_scenario  # noqa: E402
from roe_sep.core.relmotion.dynamics import drag_da_dot  # noqa: E402
from roe_sep.core.safety.ejection_check import CAMERA_SIGMA_DEG, camera_bearing, predicted_los  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402
from roe_sep.core.truth.secular import chief_from_u  # noqa: E402
from roe_sep.nodes.convert import array_to_elements, array_to_vector, sec_to_time, time_to_sec  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

SC = load_scenario(None)
D = design(SC.separation)
T0 = 1000.0  # s, the commanded ejection and its release
CHIEF = chief_from_u(D.a, D.inc, 0.3, D.u1)  # mean elements at the release
PLANNER = ("-p", "use_sim_time:=true", "-p", "p_mode:=fixed", "-p", "p_reduction:=0.06")
IC_PLANNER = ("-p", "use_sim_time:=true", "-p", f"planning_margin:={MARGIN}", "-p", "final_od_arc:=0.0")


@pytest.fixture()
def ground(ros_context, tmp_path):
    """The test's ground: the plans, the statuses and the decision records it sees; the ejection, the executed
    record, the camera and the OD it publishes; a sim clock that advances 1 s per 0.05 s from ``sim_time``; the
    ground_bridge (the keeper of the decision records) as its own process."""
    node = rclpy.create_node("restart_ground")
    node.plans, node.ic_plans, node.diags, node.records = [], [], [], {}
    node.create_subscription(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, node.plans.append, interfaces.LATCHED)
    node.create_subscription(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, node.ic_plans.append,
                             interfaces.LATCHED)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, interfaces.DIAGNOSTICS)
    def on_record(topic, msg):
        if msg.data.startswith("{"):  # "": the keeper has nothing yet; anything else: the test's junk
            node.records[topic] = json.loads(msg.data)

    for topic in interfaces.DECISIONS_TOPICS:
        node.create_subscription(String, topic, lambda m, t=topic: on_record(t, m), interfaces.LATCHED)
    node.ejection_pub = node.create_publisher(EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED)
    node.exec_pub = node.create_publisher(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED)
    node.camera_pub = node.create_publisher(Vector3Stamped, interfaces.CAMERA_TOPIC, interfaces.STREAM)
    node.od_pub = node.create_publisher(OrbitDetermination, interfaces.OD_TOPIC, interfaces.LATCHED)
    clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)
    node.sim_time = None

    def tick():
        if node.sim_time is not None:
            clock_pub.publish(Clock(clock=sec_to_time(node.sim_time)))
            node.sim_time += 1.0

    node.create_timer(0.05, tick)
    node.procs = {"keeper": start_node("ground_bridge", "-p", f"output_dir:={tmp_path / 'ccsds'}")}
    yield node
    codes = {name: stop_node(p) for name, p in node.procs.items()}
    node.destroy_node()
    for name, (code, out) in codes.items():  # shown by pytest when the test fails
        print(f"--- {name} (exit status {code}):\n{out[-3000:]}")
    assert all(code in (0, -signal.SIGKILL) for code, _ in codes.values()), codes


def kill(node, name):
    """SIGKILL: no shutdown, no goodbye to DDS (its latched samples die with it)."""
    proc = node.procs.pop(name)
    proc.send_signal(signal.SIGKILL)
    out, _ = proc.communicate(timeout=10)
    print(f"--- {name} (killed):\n{out[-3000:]}")  # shown by pytest when the test fails


def record(node, who):
    return node.records.get(interfaces.PLANNER_DECISIONS_TOPIC if who == "planner" else
                            interfaces.IC_PLANNER_DECISIONS_TOPIC)


def ejection_event():
    ev = EjectionEvent(dv_magnitude=SC.separation.spl_dv)
    ev.header.stamp = sec_to_time(T0)
    ev.ejection.epoch = sec_to_time(T0)
    ev.ejection.mean_arg_latitude = D.u1
    ev.ejection.dv_rtn = array_to_vector(D.dv1_rtn)
    ev.ejection.spacecraft, ev.ejection.purpose = "picosatellite", "ejection"
    ev.chief = array_to_elements(CHIEF)
    return ev


def executed(purpose, t, spacecraft, dv):
    return ImpulsiveManeuver(epoch=sec_to_time(t), dv_rtn=array_to_vector(dv), spacecraft=spacecraft,
                             purpose=purpose)


def epochs(plan):
    return [round(time_to_sec(m.epoch), 3) for m in plan.maneuvers]


def test_a_planner_killed_after_a_hold_never_flies_the_blind_drift_stop(ground):
    """The camera sees f1 = 0.3: the drift-stop is withdrawn (an empty plan). Killed, restarted, and the drift-stop's
    epoch passes: the hold is latched again, the blind drift-stop never comes back, nothing is replaced."""
    ground.sim_time = T0 + 100.0
    ground.ejection_pub.publish(ejection_event())
    ground.exec_pub.publish(executed("ejection", T0, "picosatellite", D.dv1_rtn))
    ground.procs["planner"] = start_node("planner", *PLANNER)
    assert spin_until(ground, lambda: ground.plans and ground.camera_pub.get_subscription_count(), timeout=40)
    blind = ground.plans[0]
    t_stop = time_to_sec(blind.maneuvers[0].epoch)
    mc = SC.monte_carlo
    times = np.arange(T0 + 60.0, t_stop - 1800.0, 60.0)
    los = camera_bearing(predicted_los([0.3], D.dv1_rtn, T0, CHIEF, float(drag_da_dot(mc.delta_b, mc.density, D.a)),
                                       times=times)[0] * 1000.0, math.radians(CAMERA_SIGMA_DEG),
                         np.random.default_rng(7))
    for t, v in zip(times, los):
        msg = Vector3Stamped(vector=array_to_vector(v))
        msg.header.stamp = sec_to_time(float(t))
        ground.camera_pub.publish(msg)
    spin_until(ground, lambda: False, timeout=1.0)
    ground.sim_time = t_stop - 1800.0
    assert spin_until(ground, lambda: len(ground.plans) >= 2, timeout=20)
    hold = ground.plans[1]
    assert hold.maneuvers == [] and time_to_sec(hold.ejection_epoch) == T0
    assert spin_until(ground, lambda: (record(ground, "planner") or {}).get("state", {}).get("plans") == 2)
    assert record(ground, "planner")["state"]["in_force"] is None

    kill(ground, "planner")
    ground.plans.clear()
    ground.procs["planner"] = start_node("planner", *PLANNER)
    assert spin_until(ground, lambda: ground.plans, timeout=30)
    ground.sim_time = t_stop + 1800.0  # past the drift-stop and its retry tolerance: nothing to fly, nothing missing
    spin_until(ground, lambda: False, timeout=6.0)
    assert [p.maneuvers for p in ground.plans] == [[]]  # the hold, latched again; never the blind drift-stop
    assert ground.plans[0].header.stamp == hold.header.stamp
    assert ground.procs["planner"].poll() is None


def test_a_planner_killed_after_a_replacement_keeps_the_replacement(ground):
    """The drift-stop is missing from the record: replaced whole orbits later. Killed, restarted: the replacement is
    latched again; the withdrawn original is not published, and the original is not replaced a second time. The
    control: restarted without its record, the planner publishes the withdrawn original again."""
    args = (*PLANNER, "-p", "weak_ejection_hold:=false")
    t_stop = T0 + 3 * math.pi / D.n
    ground.sim_time = t_stop + 900.0
    ground.ejection_pub.publish(ejection_event())
    ground.exec_pub.publish(executed("ejection", T0, "picosatellite", D.dv1_rtn))
    ground.procs["planner"] = start_node("planner", *args)
    assert spin_until(ground, lambda: len(ground.plans) >= 2, timeout=40)
    original, replacement = ground.plans[:2]
    assert epochs(replacement)[0] > epochs(original)[0]
    assert spin_until(ground, lambda: (record(ground, "planner") or {}).get("state", {}).get("plans") == 2)
    version = record(ground, "planner")["version"]
    # junk on the topic (latched from the test's own writer too): the keeper keeps its record, the planner skips it
    junk = ground.create_publisher(String, interfaces.PLANNER_DECISIONS_TOPIC, interfaces.LATCHED)
    junk.publish(String(data="not a record"))
    assert spin_until(ground, lambda: any("decision record on /separation/decisions/planner rejected" in s.message
                                          for d in ground.diags for s in d.status), timeout=10)

    kill(ground, "planner")
    ground.plans.clear()
    ground.procs["planner"] = start_node("planner", *args)
    assert spin_until(ground, lambda: ground.plans, timeout=30)
    spin_until(ground, lambda: False, timeout=6.0)  # 3 times RECORD_SETTLE: a missing drift-stop would be found
    assert [epochs(p) for p in ground.plans] == [epochs(replacement)]
    assert ground.plans[0].header.stamp == replacement.header.stamp
    assert record(ground, "planner")["version"] >= version  # counted on, not from 1

    kill(ground, "planner")  # the control: no read-back
    ground.plans.clear()
    ground.procs["planner"] = start_node("planner", *args, "-p", "recover_timeout:=0.0")
    assert spin_until(ground, lambda: ground.plans, timeout=30)
    assert epochs(ground.plans[0]) == epochs(original)


def test_an_ic_planner_killed_mid_acquisition_keeps_its_plan(ground):
    """The first acquisition burn flown: killed, restarted. The plan in force is latched again unchanged; the latched
    OD is not planned again. The control: restarted without its record, it re-plans from that OD."""
    ground.sim_time = T_OD + 700.0
    ground.od_pub.publish(od_message(ROE0, T_OD))
    ground.procs["ic_planner"] = start_node("ic_planner", *IC_PLANNER)
    assert spin_until(ground, lambda: ground.ic_plans, timeout=40)
    plan = ground.ic_plans[0]
    first = plan.maneuvers[0]
    ground.sim_time = time_to_sec(first.epoch) + 60.0
    ground.exec_pub.publish(executed("ic_acquisition", time_to_sec(first.epoch), "carrier",
                                     [first.dv_rtn.x, first.dv_rtn.y, first.dv_rtn.z]))
    assert spin_until(ground, lambda: len((record(ground, "ic_planner") or {}).get("state", {}).get("executed", []))
                      == 1)

    kill(ground, "ic_planner")
    ground.ic_plans.clear()
    ground.procs["ic_planner"] = start_node("ic_planner", *IC_PLANNER)
    assert spin_until(ground, lambda: ground.ic_plans, timeout=30)
    spin_until(ground, lambda: False, timeout=5.0)
    assert len(ground.ic_plans) == 1 and ground.ic_plans[0] == plan  # the same message: stamp, burns, aim
    assert len(record(ground, "ic_planner")["state"]["executed"]) == 1  # the latched record taken once

    kill(ground, "ic_planner")  # the control: no read-back
    ground.ic_plans.clear()
    ground.procs["ic_planner"] = start_node("ic_planner", *IC_PLANNER, "-p", "recover_timeout:=0.0")
    assert spin_until(ground, lambda: ground.ic_plans, timeout=30)
    assert epochs(ground.ic_plans[0]) != epochs(plan)
