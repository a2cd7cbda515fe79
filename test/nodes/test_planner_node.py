"""The planner node as a real process over DDS: latched plan, bad input survived, restart loses nothing."""

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from roe_sep_msgs.msg import EjectionEvent, ImpulsiveManeuver, ManeuverPlan  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import publish_until, rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.relmotion.roe import wrap_angle  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402
from roe_sep.nodes.convert import array_to_vector, sec_to_time, time_to_sec  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

D = design()


def ejection_event(dv=None, stamp=1000.0):
    ev = EjectionEvent()
    ev.header.stamp = sec_to_time(stamp)
    ev.ejection.epoch = sec_to_time(stamp)
    ev.ejection.mean_arg_latitude = D.u1
    ev.ejection.dv_rtn = array_to_vector(D.dv1_rtn if dv is None else dv)
    ev.ejection.spacecraft = "picosatellite"
    ev.ejection.purpose = "ejection"
    ev.dv_magnitude = 1.41
    ev.chief.semi_major_axis = D.a
    ev.chief.inclination = D.inc
    ev.chief.mean_arg_latitude = D.u1
    return ev


@pytest.fixture()
def ground(ros_context):
    node = rclpy.create_node("ground_test")
    node.plans, node.diags = [], []
    node.create_subscription(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, node.plans.append, interfaces.LATCHED)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, interfaces.DIAGNOSTICS)
    node.ejection_pub = node.create_publisher(EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED)
    yield node
    node.destroy_node()


def test_plan_bad_event_and_restart(ground):
    planner = start_node("planner", "-p", "p_mode:=fixed", "-p", "p_reduction:=0.06")
    try:
        # the ERROR status is published once per event and /diagnostics is volatile: the bad event is sent again
        # until the ground has the status (a slow discovery of the status writer loses the first ones)
        # a NaN ejection is rejected with an ERROR diagnostic; the node keeps running
        bad = ejection_event(dv=[math.nan, 0.0, 0.0])
        assert publish_until(ground, lambda: ground.ejection_pub.publish(bad),
                             lambda: any(s.level == DiagnosticStatus.ERROR and "rejected" in s.message
                                         for d in ground.diags for s in d.status), timeout=60)
        assert planner.poll() is None
        ground.ejection_pub.publish(ejection_event())
        assert spin_until(ground, lambda: len(ground.plans) >= 1)
        plan = ground.plans[-1]
        assert plan.strategy == "double_impulse" and plan.p_reduction == pytest.approx(0.06)
        (burn,) = plan.maneuvers
        assert (burn.spacecraft, burn.purpose) == ("carrier", "drift_stop")
        # the carrier burns the opposite of the relative drift-stop (-1.329250, 0.162718 - 0.06, 0)
        assert [burn.dv_rtn.x, burn.dv_rtn.y, burn.dv_rtn.z] == pytest.approx([1.329250, -0.102718, 0.0], abs=1e-6)
        # every angle in our messages is wrapped to [-pi, pi) (docs/ros_interface.md)
        assert burn.mean_arg_latitude == pytest.approx(float(wrap_angle(D.u1 + 3 * math.pi)))
        assert time_to_sec(burn.epoch) - 1000.0 == pytest.approx(3 * math.pi / D.n, rel=2e-3)  # ~1.5 orbits
        assert time_to_sec(plan.ejection_epoch) == pytest.approx(1000.0)
        assert plan.aimed.a_da == pytest.approx(-2 * 0.06 / D.n, abs=0.5)  # the reduction leaves 2 p / n of da
        assert plan.aimed.chief.semi_major_axis == pytest.approx(D.a)
    finally:
        code, out = stop_node(planner)
    assert code == 0, out

    # a restarted planner receives the latched ejection again and re-publishes the plan
    ground.plans.clear()
    planner = start_node("planner", "-p", "p_mode:=three_sigma")
    try:
        assert spin_until(ground, lambda: len(ground.plans) >= 1)
        assert ground.plans[-1].p_reduction == pytest.approx(D.p_min, rel=1e-9)
    finally:
        code, out = stop_node(planner)
    assert code == 0, out


@pytest.mark.parametrize(
    "args,name",
    [(["-p", "k:=2"], "'k'"), (["-p", "p_mode:=guess"], "'p_mode'"), (["-p", "p_reduction:=-0.1"], "'p_reduction'"),
     (["-p", "scenario_file:=/nonexistent.yaml"], "'scenario_file'")],
)
def test_bad_parameter_refused_at_startup(args, name):
    code, out = wait_exit(start_node("planner", *args))
    assert code == 2, out
    assert name in out


def test_default_p_comes_from_the_monte_carlo(ground):
    planner = start_node("planner", "-p", "mc_samples:=20000")
    try:
        ground.ejection_pub.publish(ejection_event())
        assert spin_until(ground, lambda: len(ground.plans) >= 1, timeout=40)
        assert 0.03 <= ground.plans[-1].p_reduction <= 0.08
        assert np.isfinite(ground.plans[-1].aimed.a_dl)
    finally:
        code, out = stop_node(planner)
    assert code == 0, out


def test_plan_separation_service(ground):
    from roe_sep_msgs.srv import PlanSeparation

    planner = start_node("planner", "-p", "p_mode:=fixed", "-p", "p_reduction:=0.05")
    try:
        client = ground.create_client(PlanSeparation, interfaces.PLAN_SERVICE)
        assert client.wait_for_service(timeout_sec=20)

        def call(**fields):
            req = PlanSeparation.Request(u1=math.radians(88.0), **fields)
            future = client.call_async(req)
            assert spin_until(ground, future.done)
            return future.result()

        res = call(p_reduction=-1.0)  # negative: the planner's own p
        assert res.success, res.message
        ejection, stop = res.plan.maneuvers
        assert (ejection.spacecraft, stop.spacecraft) == ("picosatellite", "carrier")
        assert [ejection.dv_rtn.x, ejection.dv_rtn.y, ejection.dv_rtn.z] == pytest.approx(
            [-1.329250, -0.162718, 0.441269], abs=1e-6)
        assert stop.dv_rtn.y == pytest.approx(-(0.162718 - 0.05), abs=1e-6)
        assert res.plan.p_reduction == pytest.approx(0.05)
        assert call(p_reduction=0.0).plan.maneuvers[1].dv_rtn.y == pytest.approx(-0.162718, abs=1e-6)
        following = call(following=True, k=1, p_reduction=0.0)
        assert following.success and following.plan.maneuvers[0].dv_rtn.x > 0
        bad = call(spl_dv=0.3)
        assert not bad.success and "too small" in bad.message
        assert planner.poll() is None
    finally:
        code, out = stop_node(planner)
    assert code == 0, out


def executed_burn(purpose, t, spacecraft, dv):
    m = ImpulsiveManeuver(epoch=sec_to_time(t), dv_rtn=array_to_vector(dv), spacecraft=spacecraft, purpose=purpose)
    return m


@pytest.mark.parametrize("record", ["ejection and drift-stop", "ejection only"])
def test_a_restarted_planner_recovers_the_executed_record_before_it_replaces_a_drift_stop(ground, record):
    """A planner (re)started after the drift-stop's epoch receives the latched ejection at once; until the
    executed-maneuver record has arrived it must not call the drift-stop missing (it would fly twice). With the record:
    a drift-stop on it, nothing is replaced; only the ejection on it, the drift-stop is replaced (drift_stop_retry)."""
    clock_pub = ground.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)
    exec_pub = ground.create_publisher(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED)
    t_stop = 1000.0 + 3 * math.pi / D.n
    now = [t_stop + 600.0]  # past the drift-stop's epoch and its retry tolerance

    def tick():
        clock_pub.publish(Clock(clock=sec_to_time(now[0])))
        now[0] += 1.0

    ground.create_timer(0.02, tick)
    ground.ejection_pub.publish(ejection_event())
    planner = start_node("planner", "-p", "use_sim_time:=true", "-p", "p_mode:=fixed", "-p", "p_reduction:=0.06")
    try:
        assert spin_until(ground, lambda: len(ground.plans) >= 1)
        assert time_to_sec(ground.plans[0].maneuvers[0].epoch) == pytest.approx(t_stop, rel=2e-3)
        spin_until(ground, lambda: False, timeout=4.0)  # no record yet: nothing is replaced, however long
        assert len(ground.plans) == 1
        exec_pub.publish(executed_burn("ejection", 1003.0, "picosatellite", D.dv1_rtn))
        if record == "ejection and drift-stop":
            stop = ground.plans[0].maneuvers[0]
            exec_pub.publish(executed_burn("drift_stop", time_to_sec(stop.epoch), "carrier",
                                           [stop.dv_rtn.x, stop.dv_rtn.y, stop.dv_rtn.z]))
        replaced = spin_until(ground, lambda: len(ground.plans) >= 2, timeout=8.0)
        assert replaced is (record == "ejection only")
        if replaced:
            later = time_to_sec(ground.plans[-1].maneuvers[0].epoch) - time_to_sec(ground.plans[0].maneuvers[0].epoch)
            assert later > 0 and later / (2 * math.pi / D.n) == pytest.approx(round(later / (2 * math.pi / D.n)),
                                                                           abs=0.02)
            assert spin_until(ground, lambda: any(kv.value == "drift_stop_replaced" for d in ground.diags
                                                  for st in d.status for kv in st.values), timeout=5.0)
    finally:
        code, out = stop_node(planner)
    assert code == 0, out
