"""The radar_od node as a real process over DDS, fed with a truth stream of a drifting relative orbit.

A test node plays the simulator: 34 h of sim time in 60 s steps (a truth message each step, one NaN truth, one
executed burn at 15 h), as the lockstep coordinator (a ``LockstepStep`` per step, the next one once radar_od has
acknowledged: what the node computes is independent of timing and load) or as a free-running ``/clock`` (the node
run alone) that runs LEAD ahead of the truth, as a loaded node sees it when the clock's messages overtake the
truth's (3 h: 0.18 wall s of the free-running simulator's default 60000x). The node must measure only during TIRA
passes and only once the spacecraft are 5 km apart, ignore the pre-burn passes, and publish OD solutions consistent
with the truth, in both modes: alone, it measures an epoch only once a truth sample at or after it has arrived,
from that sample.
"""

import math
import time

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus  # noqa: E402
from roe_sep_msgs.msg import (  # noqa: E402
    ImpulsiveManeuver,
    LockstepAck,
    LockstepStep,
    OrbitDetermination,
    RadarMeasurement,
    RelativeOrbitalElements,  # noqa: E402
)
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.od.radar import TIRA, gmst, julian_date, observe, raan_from_ltan, relative_distance  # noqa: E402
from roe_sep.core.relmotion.dynamics import propagate_chief, sun_synchronous_inclination  # noqa: E402
from roe_sep.core.relmotion.orbit import semi_major_axis  # noqa: E402
from roe_sep.core.relmotion.roe import wrap_angle  # noqa: E402
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory  # noqa: E402
from roe_sep.nodes.convert import array_to_elements, maneuver_msg, roe_to_msg, sec_to_time, time_to_sec  # noqa
from roe_sep.nodes.lockstep import ACK_QOS, STEP_QOS  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

EPOCH = "2016-07-01T00:00:00"
JD0 = julian_date(EPOCH)
A = float(semi_major_axis(515e3))
INC = float(sun_synchronous_inclination(A))
KEP0 = np.array([A, 0.0, INC, float(raan_from_ltan(9.5, JD0)), 0.0, 0.3])
CHIEF = Chief(a=A, inc=INC, u0=0.3, t0=0.0)
# 300 m ahead at t = 0, drifting ahead (a da = -60 m) and accelerated by differential drag: the first TIRA pass
# (8.0 h) is below 5 km, the second (9.6 h) above
ROE0 = np.array([-60.0, 300.0, -20.6, -589.6, 14.0, 399.8]) / A
DA_DOT = -8e-4 / A
BURN_T, BURN_DV = 54000.0, (0.0, 0.02, 0.0)  # relative impulse at 15 h (the carrier burns the opposite)
NAN_T = 3 * 3600.0
TICK, SIM_END, SAMPLE = 60.0, 34 * 3600.0, 10.0
LEAD = 3 * 3600.0  # s: run alone, the clock is this far ahead of the truth
MASK = math.radians(10.0)


def truth(t):
    """Truth ROE and chief elements at times ``t`` (the test's own model of the simulator)."""
    t = np.atleast_1d(np.asarray(t, dtype=float))
    return trajectory(ROE0, 0.0, [Burn(BURN_T, BURN_DV)], t, CHIEF, j2=True, da_dot=DA_DOT), propagate_chief(KEP0, t)


def truth_msg(t, roe, kep):
    kep = np.array(kep, dtype=float)
    kep[3:] = wrap_angle(kep[3:])
    return roe_to_msg(roe, array_to_elements(kep), sec_to_time(t))


@pytest.fixture()
def sim():
    rclpy.init()
    node = rclpy.create_node("sim_test")
    node.meas, node.ods, node.diags = [], [], []
    node.create_subscription(RadarMeasurement, interfaces.RADAR_TOPIC, node.meas.append, interfaces.STREAM)
    node.create_subscription(OrbitDetermination, interfaces.OD_TOPIC, node.ods.append, interfaces.LATCHED)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, interfaces.DIAGNOSTICS)
    node.truth_pub = node.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
    node.clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, interfaces.STREAM)
    node.burn_pub = node.create_publisher(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED)
    node.step_pub = node.create_publisher(LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, STEP_QOS)
    node.acks = set()
    node.create_subscription(LockstepAck, interfaces.LOCKSTEP_ACK_TOPIC,
                             lambda a: node.acks.add((a.node, a.step, a.round)), ACK_QOS)
    yield node
    node.destroy_node()
    rclpy.try_shutdown()


def statuses(node, level):
    return [s.message for d in node.diags for s in d.status if s.level == level and s.name == "roe_sep/radar_od"]


def run_sim(node, proc, lockstep):
    """Publish the truth from 0 to SIM_END, each tick closed by a lockstep step message acknowledged by radar_od
    (``lockstep``) or by /clock LEAD ahead of the tick (spinning 2 ms between ticks so that nothing queues up)."""
    assert spin_until(node, lambda: node.truth_pub.get_subscription_count() >= 1
                      and node.clock_pub.get_subscription_count() >= 1
                      and node.count_publishers(interfaces.OD_TOPIC) >= 1,
                      timeout=30), "radar_od did not come up"
    time.sleep(0.5)  # let the reliable endpoints finish matching
    ticks = np.arange(0.0, SIM_END + TICK / 2, TICK)
    roe, kep = truth(ticks)
    counts = {interfaces.EXECUTED_TOPIC: 0, interfaces.TRUTH_ROE_TOPIC: 0}
    for k, t in enumerate(ticks):
        if t == BURN_T:
            node.burn_pub.publish(maneuver_msg(t, CHIEF.u_at(t), [-v for v in BURN_DV], "carrier", "drift_reduction"))
            counts[interfaces.EXECUTED_TOPIC] += 1
        msg = truth_msg(t, roe[k], kep[k])
        if t == NAN_T:
            msg.a_dl = math.nan  # rejected before it is counted: the step does not count it either
        else:
            counts[interfaces.TRUTH_ROE_TOPIC] += 1
        node.truth_pub.publish(msg)
        if lockstep:
            topics = sorted(counts)
            step = LockstepStep(step=k, round=0, period_start=float(ticks[k - 1] if k else 0.0), topics=topics,
                                counts=[counts[tp] for tp in topics], final=False)
            step.header.stamp = sec_to_time(t)
            node.step_pub.publish(step)
            assert spin_until(node, lambda: ("radar_od", k, 0) in node.acks, timeout=30), f"no ack of step {k}"
            assert proc.poll() is None, "radar_od died"
            continue
        node.clock_pub.publish(Clock(clock=sec_to_time(min(t + LEAD, SIM_END))))
        deadline = time.monotonic() + 0.002
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.001)
        assert proc.poll() is None, "radar_od died"


@pytest.mark.parametrize("lockstep", [True, False], ids=["lockstep", "alone"])
def test_tracks_passes_after_separation_and_estimates_consistently(sim, lockstep):
    proc = start_node("radar_od", "-p", "use_sim_time:=true", "-p", f"epoch_utc:={EPOCH}", "-p", "seed:=3")
    try:
        if lockstep:  # the step topic must be matched before the first step, or radar_od starts alone
            assert spin_until(sim, lambda: sim.step_pub.get_subscription_count() >= 1, timeout=30)
        run_sim(sim, proc, lockstep)
        assert spin_until(sim, lambda: len(sim.ods) >= 2, timeout=20), "no second OD solution"
        spin_until(sim, lambda: False, timeout=0.5)
        assert proc.poll() is None  # survived the NaN truth message
    finally:
        code, out = stop_node(proc)
    assert code == 0, out

    # --- measurements: exactly the visible epochs >= 5 km apart, nothing else ---------------------------------
    grid = np.arange(SAMPLE, SIM_END + SAMPLE / 2, SAMPLE)
    roe, kep = truth(grid)
    z = observe(roe, kep, gmst(JD0 + grid / 86400.0), TIRA.ecef, TIRA.enu)
    sep = relative_distance(roe, A, kep[:, 4] + kep[:, 5])
    seen = z[:, 2] > MASK
    expected = grid[seen & (sep >= 5000.0)]
    stamps = np.array([time_to_sec(m.header.stamp) for m in sim.meas])
    np.testing.assert_allclose(np.sort(stamps), expected, atol=1e-6)
    assert np.any(seen & (sep < 5000.0)), "the scenario must contain a pass below the 5 km separability"
    assert not set(np.round(grid[seen & (sep < 5000.0)])) & set(np.round(stamps))
    m0 = sim.meas[0]
    assert (m0.station, m0.header.frame_id, m0.sigma_range) == ("TIRA", "TIRA", pytest.approx(10.0))
    assert m0.sigma_angle == pytest.approx(math.radians(0.01))
    zm = np.array([[m.range, m.azimuth, m.elevation] for m in sim.meas])
    zt = z[np.searchsorted(grid, stamps)]
    dev = zm - zt
    dev[:, 1] = wrap_angle(dev[:, 1])
    assert np.all(np.abs(dev / [10.0, math.radians(0.01), math.radians(0.01)]) < 5.0)
    pass_ids = [m.pass_id for m in sim.meas]
    assert pass_ids == sorted(pass_ids) and pass_ids[0] == 1 and pass_ids[-1] == 5  # 8.0 h pass never started

    # --- diagnostics ---------------------------------------------------------------------------------------
    assert any("waiting for separation" in s for s in statuses(sim, DiagnosticStatus.WARN))
    assert any("rejected" in s for s in statuses(sim, DiagnosticStatus.ERROR))

    # --- OD: only post-burn passes, consistent with the truth ----------------------------------------------
    first, second = sim.ods[0], sim.ods[1]
    t1 = time_to_sec(first.estimate.header.stamp)
    # without the burn the 9.6 h and 21.0 h passes would have given an estimate; after it, 21.0 h to 31.8 h
    assert t1 > 31 * 3600.0 and first.passes == 3 and second.passes == 4
    assert first.measurements == np.count_nonzero((stamps >= BURN_T) & (stamps <= t1))
    for od in (first, second):
        t_est = time_to_sec(od.estimate.header.stamp)
        roe_t, kep_t = truth(t_est)
        est = np.array([od.estimate.a_da, od.estimate.a_dl, od.estimate.a_dex, od.estimate.a_dey,
                        od.estimate.a_dix, od.estimate.a_diy])
        cov = np.array(od.estimate.covariance).reshape(6, 6)
        sigma = np.sqrt(np.diag(cov))
        assert np.all(np.abs(est - roe_t[0] * A) < 3.0 * sigma), (est - roe_t[0] * A, sigma)
        assert abs(od.a_da_dot - DA_DOT * A) < 3.0 * od.a_da_dot_sigma
        assert np.all(sigma < 50.0) and od.a_da_dot_sigma < 1e-4
        assert 0.8 < od.residual_rms < 1.2
        assert od.estimate.chief.semi_major_axis == pytest.approx(A)
        assert od.estimate.chief.mean_arg_latitude == pytest.approx(wrap_angle(kep_t[0, 4] + kep_t[0, 5]), abs=1e-9)
        assert od.estimate.chief.raan == pytest.approx(wrap_angle(kep_t[0, 3]), abs=1e-9)


@pytest.mark.parametrize(
    "args,name",
    [(["-p", "sigma_range_m:=-1.0"], "'sigma_range_m'"),
     (["-p", "station_latitudes_deg:=[50.6, 48.1]"], "'station_latitudes_deg'"),
     (["-p", "epoch_utc:=yesterday"], "'epoch_utc'"),
     (["-p", "min_separation:=5000"], "'min_separation'"),
     (["-p", "density_walk:=-0.1"], "'density_walk'"),
     (["-p", "drag_ballistic_ratio:=0.5"], "'drag_ballistic_ratio'")],
)
def test_bad_parameter_refused_at_startup(args, name):
    code, out = wait_exit(start_node("radar_od", *args))
    assert code == 2, out
    assert name in out
