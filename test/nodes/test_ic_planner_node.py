"""The ic_planner node as a real process over DDS: latched OD in, latched acquisition plan out, a NaN estimate
survived with an ERROR diagnostic, the re-plan policy under sim time, bad parameters refused at start-up."""

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from roe_sep_msgs.msg import ManeuverPlan, OrbitalElements, OrbitDetermination  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import publish_until, rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.acquisition.planner import AcquisitionConfig, plan_acquisition  # noqa: E402
from roe_sep.core.relmotion.dynamics import drag_da_dot  # noqa: E402
from roe_sep.core.relmotion.roe import wrap_angle  # noqa: E402
from roe_sep.core.relmotion.trajectory import Chief, state_at  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402
from roe_sep.nodes.convert import msg_to_roe, plan_burns, roe_to_msg, sec_to_time, time_to_sec  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

D = design()
A = D.a
DA_DOT = float(drag_da_dot(0.0151, 1e-12, A))  # 1/s
ROE0 = np.array([-180.0, 25000.0, -30.0, -540.0, 10.0, 400.0]) / A
T_OD = 1000.0
U0 = 1.0
MARGIN = 5700.0


def od_message(roe, t_est, solved=None, u=U0, sigma=None):
    """An OD solution; ``sigma`` [m]: the 1-sigma of each a*ROE (default 1e-6 of the dimensionless ROE)."""
    msg = OrbitDetermination(a_da_dot=DA_DOT * A, a_da_dot_sigma=1e-4, passes=3, measurements=120,
                             residual_rms=1.0)
    msg.header.stamp = sec_to_time(t_est + 600.0 if solved is None else solved)
    chief = OrbitalElements(semi_major_axis=A, eccentricity=0.0, inclination=D.inc, raan=0.3, arg_perigee=0.0,
                            mean_arg_latitude=u)
    var = 1e-12 if sigma is None else (sigma / A) ** 2
    msg.estimate = roe_to_msg(roe, chief, sec_to_time(t_est), covariance=np.eye(6) * var)
    return msg


def errors(node, text, level=DiagnosticStatus.ERROR):
    return any(s.level == level and s.name == "roe_sep/ic_planner" and text in s.message
               for d in node.diags for s in d.status)


@pytest.fixture()
def ground(ros_context):
    node = rclpy.create_node("ic_ground_test")
    node.plans, node.diags = [], []
    node.create_subscription(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, node.plans.append, interfaces.LATCHED)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, interfaces.DIAGNOSTICS)
    node.od_pub = node.create_publisher(OrbitDetermination, interfaces.OD_TOPIC, interfaces.LATCHED)
    clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)
    node.sim_time = None  # published at 20 Hz once set

    def tick():
        if node.sim_time is not None:
            clock_pub.publish(Clock(clock=sec_to_time(node.sim_time)))

    node.create_timer(0.05, tick)
    yield node
    node.destroy_node()


def test_plan_bad_estimate_and_replan_policy(ground):
    # final_od_arc 0: the window's end is t_F, as plan_acquisition's (the final OD's arc: test_trim, test_run)
    proc = start_node("ic_planner", "-p", "use_sim_time:=true", "-p", f"planning_margin:={MARGIN}", "-p",
                      "final_od_arc:=0.0")
    try:
        # a NaN estimate: ERROR diagnostic, no plan, the node keeps running
        # (sent again until the ERROR arrives: it is published once per estimate on a volatile topic)
        bad = od_message(np.full(6, math.nan), T_OD - 500.0)
        assert publish_until(ground, lambda: ground.od_pub.publish(bad),
                             lambda: errors(ground, "OD estimate rejected"), timeout=60)
        assert proc.poll() is None and not ground.plans

        ground.od_pub.publish(od_message(ROE0, T_OD))
        assert spin_until(ground, lambda: len(ground.plans) >= 1, timeout=30)
        plan = ground.plans[-1]
        assert plan.strategy == "ic_acquisition" and plan.p_reduction == 0.0
        # the same plan as the core computes (no /clock yet: sim time 0, first burn >= OD epoch + margin)
        chief = Chief(a=A, inc=D.inc, u0=U0, t0=T_OD)
        cfg = AcquisitionConfig(planning_margin=MARGIN)
        ref = plan_acquisition(ROE0, chief, DA_DOT, cfg)
        assert len(plan.maneuvers) == ref.n_burns >= 1
        for m, t, dv in zip(plan.maneuvers, ref.epochs, ref.dv_carrier):
            assert (m.spacecraft, m.purpose) == ("carrier", "ic_acquisition")
            assert time_to_sec(m.epoch) == pytest.approx(t, abs=1e-6)
            got = np.array([m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z])
            np.testing.assert_allclose(got, dv, atol=1e-12)
            assert np.linalg.norm(got) <= 0.3 + 1e-12
            np.testing.assert_allclose(got / 1e-3, np.round(got / 1e-3), atol=1e-6)
            assert math.cos(m.mean_arg_latitude - chief.u_at(t)) == pytest.approx(1.0)
        assert time_to_sec(plan.maneuvers[0].epoch) >= T_OD + MARGIN
        aimed = plan.aimed
        assert time_to_sec(aimed.header.stamp) == pytest.approx(ref.t_final, abs=1e-6)
        assert aimed.chief.semi_major_axis == pytest.approx(A)
        assert math.cos(aimed.chief.mean_arg_latitude - chief.u_at(ref.t_final)) == pytest.approx(1.0)
        np.testing.assert_allclose(msg_to_roe(aimed) * A, ref.final_roe * A, atol=1e-6)
        assert abs(aimed.a_da) <= 1.0 and 7300.0 <= aimed.a_dl <= 7700.0
        assert spin_until(ground, lambda: errors(ground, "acquisition plan published", DiagnosticStatus.OK))

        # sim time passes the first burns: a newer OD whose epoch precedes an executed burn is not used
        t_exec = time_to_sec(plan.maneuvers[0].epoch)
        early = [time_to_sec(m.epoch) for m in plan.maneuvers if time_to_sec(m.epoch) < T_OD + 86400.0]
        ground.sim_time = max(early) + 2000.0
        spin_until(ground, lambda: False, timeout=1.5)  # the node's clock follows /clock
        ground.od_pub.publish(od_message(ROE0, t_exec - 100.0, solved=t_exec + 1000.0))
        assert spin_until(ground, lambda: errors(ground, "not used", DiagnosticStatus.WARN), timeout=30)
        assert len(ground.plans) == 1

        # an OD made after the executed burns re-plans the rest of the acquisition (correction), burns in the future
        t_new = max(early) + 1000.0
        roe_new = state_at(ROE0, T_OD, ref.burns(), t_new, chief, j2=True, da_dot=DA_DOT)
        ground.od_pub.publish(od_message(roe_new, t_new, solved=t_new + 500.0, u=float(chief.u_at(t_new))))
        assert spin_until(ground, lambda: len(ground.plans) >= 2, timeout=30)
        new = ground.plans[-1]
        assert all(time_to_sec(m.epoch) >= ground.sim_time + MARGIN - 1.0 for m in new.maneuvers)
        assert abs(new.aimed.a_da) <= 1.0
        assert proc.poll() is None
    finally:
        code, out = stop_node(proc)
    assert code == 0, out


def test_final_od_trims_the_drift_at_the_ic_epoch(ground):
    """An OD within two planning margins of the IC epoch whose a da at t_F is 8 m off: one tangential trim at or
    after now + planning_margin joins the burns still to fly, the IC epoch moves one grid step past it and the
    aimed a da is within half the lattice (0.9 m); a later solution is not used, nor, before, one that knows a da
    at t_F less well than the plan in force's OD. Without a predicted radar arc (final_od_arc 0) the final OD is
    the first solution within two planning margins of t_F."""
    proc = start_node("ic_planner", "-p", "use_sim_time:=true", "-p", f"planning_margin:={MARGIN}", "-p",
                      "final_od_arc:=0.0")
    try:
        ground.od_pub.publish(od_message(ROE0, T_OD))
        assert spin_until(ground, lambda: len(ground.plans) >= 1, timeout=30)
        plan = ground.plans[-1]
        # a newer solution that knows a da at t_F less well than the plan's (100 m against about 19 m): not used
        # (sent again until the status arrives: the plan's latched writer matched tells nothing of the status's)
        vague = od_message(ROE0, T_OD + 10.0, sigma=100.0)
        assert publish_until(ground, lambda: ground.od_pub.publish(vague),
                             lambda: errors(ground, "a da at the IC epoch is known to", DiagnosticStatus.OK))
        assert len(ground.plans) == 1
        t_f = time_to_sec(plan.aimed.header.stamp)
        epochs = [time_to_sec(m.epoch) for m in plan.maneuvers]
        now = t_f - 3000.0
        while any(now - 700.0 <= t < now for t in epochs):  # the node would wait for a burn's record
            now -= 400.0
        t_od = now - 600.0
        chief = Chief(a=A, inc=D.inc, u0=U0, t0=T_OD)
        burns = [b for b in plan_burns(plan.maneuvers) if b.epoch <= t_od]
        roe = state_at(ROE0, T_OD, burns, t_od, chief, j2=True, da_dot=DA_DOT) + np.array([8.0, 0, 0, 0, 0, 0]) / A
        ground.sim_time = now
        spin_until(ground, lambda: False, timeout=1.5)
        ground.od_pub.publish(od_message(roe, t_od, solved=now, u=float(wrap_angle(chief.u_at(t_od))), sigma=0.5))
        assert spin_until(ground, lambda: len(ground.plans) >= 2, timeout=30)
        new = ground.plans[-1]
        kept = [m for m in plan.maneuvers if time_to_sec(m.epoch) >= now]
        assert [time_to_sec(m.epoch) for m in new.maneuvers[:-1]] == [time_to_sec(m.epoch) for m in kept]
        trim = new.maneuvers[-1]
        assert time_to_sec(trim.epoch) >= now + MARGIN and trim.dv_rtn.x == trim.dv_rtn.z == 0.0
        assert 0.003 <= trim.dv_rtn.y <= 0.006  # about 8 m / (2 / n) pro-grade
        assert time_to_sec(new.aimed.header.stamp) > time_to_sec(trim.epoch) > t_f
        assert abs(new.aimed.a_da) <= 0.9 + 1e-9
        assert spin_until(ground, lambda: errors(ground, "trim of", DiagnosticStatus.OK))
        later = od_message(roe, t_od + 1.0, solved=now + 1.0, u=float(wrap_angle(chief.u_at(t_od + 1.0))), sigma=0.5)
        ground.od_pub.publish(later)
        spin_until(ground, lambda: False, timeout=2.0)
        assert len(ground.plans) == 2 and proc.poll() is None
    finally:
        code, out = stop_node(proc)
    assert code == 0, out


@pytest.mark.parametrize("args,name", [
    (["-p", "a_dl_max:=4000.0"], "'a_dl_max'"),
    (["-p", "axes:=TX"], "'axes'"),
    (["-p", "max_burn_dv:=1"], "'max_burn_dv'"),  # an integer for a double parameter
    (["-p", "window:=1000.0"], "'window'"),  # shorter than the planning margin
    (["-p", "ic_drift_tolerance:=-1.0"], "'ic_drift_tolerance'"),
    (["-p", "trim:=1"], "'trim'"),
    (["-p", "final_od_arc:=-1.0"], "'final_od_arc'"),
])
def test_bad_parameter_refused_at_startup(args, name):
    code, out = wait_exit(start_node("ic_planner", *args))
    assert code == 2, out
    assert name in out
