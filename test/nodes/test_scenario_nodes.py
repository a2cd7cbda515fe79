"""The separation loop as real processes: ejector -> planner -> safety_monitor -> sim executes the drift-stop."""

import math

import pytest
from roe_sep_msgs.msg import ImpulsiveManeuver, RelativeOrbitalElements, SafetyStatus  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import rclpy, spin_until, start_node, stop_node  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402
from roe_sep.graph import wait_for  # noqa: E402
from roe_sep.nodes.convert import time_to_sec  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

D = design()
SIM_ARGS = ["-p", "duration:=30000.0", "-p", "time_step:=30.0", "-p", "seed:=3", "-p", "truth_period:=300.0"]


@pytest.fixture()
def observer(ros_context):
    node = rclpy.create_node("observer")
    node.got = {"executed": [], "checks": [], "truth": [], "status": [], "clock": []}
    node.create_subscription(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, node.got["executed"].append,
                             interfaces.EXECUTED)
    node.create_subscription(SafetyStatus, interfaces.PLAN_CHECK_TOPIC, node.got["checks"].append, interfaces.EXECUTED)
    node.create_subscription(SafetyStatus, interfaces.SAFETY_TOPIC, node.got["status"].append, interfaces.STREAM)
    node.create_subscription(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, node.got["truth"].append,
                             interfaces.STREAM)
    node.create_subscription(Clock, interfaces.CLOCK_TOPIC, node.got["clock"].append, 10)
    yield node
    node.destroy_node()


@pytest.mark.parametrize("dynamics", ["secular", "nonlinear"])
def test_ejection_drift_stop_loop(observer, dynamics):
    sim_time = ["-p", "use_sim_time:=true"]
    procs = [start_node("safety_monitor", *sim_time), start_node("planner", *sim_time, "-p", "p_mode:=fixed",
                                                                  "-p", "p_reduction:=0.06"),
             start_node("ejector", *sim_time)]
    spin_until(observer, lambda: False, timeout=2.0)  # let discovery settle before the clock starts
    procs.append(start_node("sim", *SIM_ARGS, "-p", f"dynamics:={dynamics}"))
    try:
        g = observer.got
        assert spin_until(observer, lambda: g["clock"] and g["clock"][-1].clock.sec >= 30000, timeout=180)
        purposes = [m.purpose for m in g["executed"]]
        assert purposes == ["ejection", "drift_stop"], purposes
        ejection, stop = g["executed"]
        # the ejection at u1 = 88 deg, the drift-stop 3 half revolutions later
        assert math.degrees(ejection.mean_arg_latitude) % 360 == pytest.approx(88.0, abs=0.05)
        assert time_to_sec(stop.epoch) - time_to_sec(ejection.epoch) == pytest.approx(3 * math.pi / D.n, rel=2e-3)
        # executed with dispersion: close to, not equal to, the commanded burns
        assert math.hypot(ejection.dv_rtn.x, ejection.dv_rtn.y, ejection.dv_rtn.z) == pytest.approx(1.41, rel=0.35)
        assert [c.safe for c in g["checks"]] == [True]
        assert g["checks"][0].source == f"plan:{interfaces.DRIFT_STOP_PLAN_TOPIC}"
        after = [t for t in g["truth"] if time_to_sec(t.header.stamp) > time_to_sec(stop.epoch)]
        assert after and all(t.a_da * t.a_dl < 0 for t in after)  # receding after the drift-stop
        assert all(s.safe for s in g["status"] if s.source == "truth")
        assert {s.source for s in g["status"]} == {"truth"}
    finally:
        codes = [stop_node(p) for p in procs]
    assert all(code == 0 for code, _ in codes), codes


def test_restarting_planner_and_monitor_loses_nothing(observer):
    sim_time = ["-p", "use_sim_time:=true"]
    planner_args = [*sim_time, "-p", "p_mode:=fixed", "-p", "p_reduction:=0.06"]
    # the clock starts once the nodes have subscribed (in the ROS graph), as roe-sep run sets it: at 2,000 s of sim
    # time per wall second a node still starting would miss the first ejection opportunity
    waiting = f"wait_for:={wait_for(('planner', 'ejector', 'sim'))!r}"
    procs = {"planner": start_node("planner", *planner_args), "ejector": start_node("ejector", *sim_time),
             "sim": start_node("sim", "-p", "duration:=40000.0", "-p", "time_step:=20.0", "-p",
                               "approval_timeout:=60.0", "-p", waiting)}
    try:
        g = observer.got
        # no monitor yet: the drift-stop (3 half revolutions after the ejection, whichever revolution the ejector
        # took) waits for its approval with the clock held
        assert spin_until(observer, lambda: g["executed"], timeout=60)
        t_stop = time_to_sec(g["executed"][0].epoch) + 3 * math.pi / D.n
        assert spin_until(observer, lambda: g["clock"] and g["clock"][-1].clock.sec > t_stop - 1000, timeout=60)
        spin_until(observer, lambda: False, timeout=2.0)
        held = g["clock"][-1].clock.sec
        assert held < t_stop + 700 and [m.purpose for m in g["executed"]] == ["ejection"], (held, t_stop)
        # the monitor (as if restarted) gets the latched ejection and plan again, checks it: the burn is flown
        procs["monitor"] = start_node("safety_monitor", *sim_time)
        assert spin_until(observer, lambda: [m.purpose for m in g["executed"]] == ["ejection", "drift_stop"],
                          timeout=60)
        # kill and restart the planner and the monitor: plan and check come again, nothing is flown twice
        for name in ("planner", "monitor"):
            stop_node(procs.pop(name))
        checks_before = len(g["checks"])
        procs["planner"] = start_node("planner", *planner_args)
        procs["monitor"] = start_node("safety_monitor", *sim_time)
        assert spin_until(observer, lambda: len(g["checks"]) > checks_before, timeout=60)
        assert spin_until(observer, lambda: g["clock"][-1].clock.sec >= 40000, timeout=90)
        assert [m.purpose for m in g["executed"]] == ["ejection", "drift_stop"]
    finally:
        codes = [stop_node(p) for p in procs.values()]
        for name, (code, out) in zip(procs, codes):  # shown by pytest when the test fails
            print(f"--- {name} (exit status {code}):\n{out[-4000:]}")
    assert all(code == 0 for code, _ in codes), codes
