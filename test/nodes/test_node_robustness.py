"""Nodes never die on a bad message: they log, publish an ERROR diagnostic and keep running."""

import math

import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from roe_sep_msgs.msg import EjectionEvent, ManeuverPlan, RelativeOrbitalElements, SafetyStatus  # noqa: E402
from rosutil import publish_until, rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.nodes.convert import maneuver_msg, sec_to_time  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context


@pytest.fixture()
def tester(ros_context):
    node = rclpy.create_node("tester")
    node.diags, node.checks = [], []
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, 100)
    node.create_subscription(SafetyStatus, interfaces.PLAN_CHECK_TOPIC, node.checks.append, interfaces.EXECUTED)
    node.pubs = {
        "truth": node.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM),
        "ejection": node.create_publisher(EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED),
        "plan": node.create_publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED),
    }
    yield node
    node.destroy_node()


def errors(node, who, text):
    return any(s.level == DiagnosticStatus.ERROR and s.name.startswith(f"roe_sep/{who}") and text in s.message
               for d in node.diags for s in d.status)


def test_nan_inputs_are_survived(tester):
    procs = {name: start_node(name, "-p", "use_sim_time:=true") for name in ("safety_monitor", "ejector")}
    procs["sim"] = start_node("sim", "-p", "duration:=1e9", "-p", "time_step:=1.0", "-p", "tick_period:=0.05")
    try:
        spin_until(tester, lambda: False, timeout=2.0)
        bad_truth = RelativeOrbitalElements(a_da=math.nan)
        bad_truth.chief.semi_major_axis = math.nan
        bad_truth.header.stamp = sec_to_time(10.0)
        bad_event = EjectionEvent()
        bad_event.header.stamp = sec_to_time(100.0)
        bad_event.ejection = maneuver_msg(100.0, 0.0, [math.nan, 0.0, 0.0], "picosatellite", "ejection")
        bad_plan = ManeuverPlan(strategy="double_impulse")
        bad_plan.header.stamp = sec_to_time(5.0)
        bad_plan.maneuvers = [maneuver_msg(9000.0, 0.0, [math.inf, 0.0, 0.0], "carrier", "drift_stop")]
        # a volatile stream: published twice a second until both subscribers have had one
        assert publish_until(tester, lambda: tester.pubs["truth"].publish(bad_truth),
                             lambda: errors(tester, "ejector", "carrier state rejected")
                             and errors(tester, "safety_monitor", "truth state rejected"))
        # (after the truth: an ejection event on the topic, even a bad one, tells the ejector not to eject again)
        expected = [("sim", "ejection event rejected"), ("sim", f"plan on {interfaces.DRIFT_STOP_PLAN_TOPIC} rejected"),
                    ("safety_monitor", "ejection event rejected")]

        def send_bad_event_and_plan():
            tester.pubs["ejection"].publish(bad_event)
            tester.pubs["plan"].publish(bad_plan)

        publish_until(tester, send_bad_event_and_plan, lambda: all(errors(tester, *e) for e in expected))
        seen = [(s.name, s.message) for d in tester.diags for s in d.status if s.level == DiagnosticStatus.ERROR]
        assert all(errors(tester, *e) for e in expected), seen
        assert all(p.poll() is None for p in procs.values())
    finally:
        codes = {name: stop_node(p) for name, p in procs.items()}
    assert all(code == 0 for code, _ in codes.values()), codes


@pytest.mark.parametrize("node,args,name", [
    ("sim", ["-p", "time_step:=-1.0"], "'time_step'"),
    ("sim", ["-p", "scenario_file:=/nonexistent.yaml"], "'scenario_file'"),
    ("ejector", ["-p", "lead_time:=-5.0"], "'lead_time'"),
    ("safety_monitor", ["-p", "keep_out:=0.0"], "'keep_out'"),
])
def test_bad_parameters_are_refused(node, args, name):
    code, out = wait_exit(start_node(node, *args))
    assert code == 2, out
    assert name in out
