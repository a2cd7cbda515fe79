"""The radar sensor and radar_od as real processes over DDS, fed with a truth stream of a drifting relative orbit.

A test node plays the simulator: 34 h of sim time in 60 s steps (a truth message each step, one NaN truth, one
executed burn at 15 h), as the lockstep coordinator (a ``LockstepStep`` per step; a second round carries what the
radar published to radar_od; the next step once both have acknowledged: what the nodes compute is independent of
timing and load) or as a free-running ``/clock`` (the nodes run alone) that runs LEAD ahead of the truth, as a
loaded node sees it when the clock's messages overtake the truth's (3 h: 0.18 wall s of the free-running
simulator's default 60000x). The radar must measure only during TIRA passes and only once the spacecraft are 5 km
apart; radar_od must ignore the pre-burn passes and publish OD solutions consistent with the truth, in both modes:
alone, the radar measures an epoch only once a truth sample at or after it has arrived, from that sample. Without
the radar, radar_od estimates from measurements and pass ends that the test publishes itself (as a ground segment
would).
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
    RadarPass,
    RelativeOrbitalElements,  # noqa: E402
)
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.core.frames import gcrs_to_itrs  # noqa: E402
from roe_sep.core.od.radar import TIRA, julian_date, observe, raan_from_ltan, relative_distance  # noqa: E402
from roe_sep.core.od.sensor import noisy_measurement, trackable  # noqa: E402
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
def sim(ros_context):
    node = rclpy.create_node("sim_test")
    node.meas, node.ends, node.ods, node.diags = [], [], [], []
    node.create_subscription(RadarMeasurement, interfaces.RADAR_TOPIC, node.meas.append, interfaces.STREAM)
    node.create_subscription(RadarPass, interfaces.RADAR_PASS_TOPIC, node.ends.append, interfaces.STREAM)
    node.create_subscription(OrbitDetermination, interfaces.OD_TOPIC, node.ods.append, interfaces.LATCHED)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append, interfaces.DIAGNOSTICS)
    node.truth_pub = node.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
    node.clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, interfaces.STREAM)
    node.burn_pub = node.create_publisher(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED)
    node.step_pub = node.create_publisher(LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, STEP_QOS)
    node.acks = {}
    node.create_subscription(LockstepAck, interfaces.LOCKSTEP_ACK_TOPIC,
                             lambda a: node.acks.__setitem__((a.node, a.step, a.round), a), ACK_QOS)
    yield node
    node.destroy_node()


def statuses(node, level, name="radar_od"):
    return [s.message for d in node.diags for s in d.status if s.level == level and s.name == f"roe_sep/{name}"]


def step_round(node, procs, counts, k, rnd, period_start, t):
    """Publish round ``rnd`` of step ``k`` with ``counts`` and wait for every participant's acknowledgement."""
    topics = sorted(counts)
    step = LockstepStep(step=k, round=rnd, period_start=period_start, topics=topics,
                        counts=[counts[tp] for tp in topics], final=False)
    step.header.stamp = sec_to_time(t)
    node.step_pub.publish(step)
    for name, proc in procs.items():
        assert spin_until(node, lambda n=name: (n, k, rnd) in node.acks, timeout=30), f"no ack of {name} {k}/{rnd}"
        assert proc.poll() is None, f"{name} died"


def run_sim(node, procs, lockstep):
    """Publish the truth from 0 to SIM_END, each tick closed by the lockstep step messages acknowledged by the
    participants ``procs`` (``lockstep``: round 0 the truth and the burn, round 1 what the radar published) or by
    /clock LEAD ahead of the tick (spinning 2 ms between ticks so that nothing queues up)."""
    assert spin_until(node, lambda: node.truth_pub.get_subscription_count() >= len(procs)
                      and node.clock_pub.get_subscription_count() >= len(procs)
                      and node.count_publishers(interfaces.OD_TOPIC) >= 1,
                      timeout=30), "the nodes did not come up"
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
            period_start = float(ticks[k - 1] if k else 0.0)
            step_round(node, procs, counts, k, 0, period_start, t)
            if "radar" in procs:  # the radar's measurements and pass ends for radar_od
                ack = node.acks[("radar", k, 0)]
                new = dict(zip(ack.topics, ack.published))
                if any(counts.get(tp, 0) != n for tp, n in new.items()):
                    counts.update(new)
                    step_round(node, procs, counts, k, 1, period_start, t)
            continue
        node.clock_pub.publish(Clock(clock=sec_to_time(min(t + LEAD, SIM_END))))
        deadline = time.monotonic() + 0.002
        while time.monotonic() < deadline:
            rclpy.spin_once(node, timeout_sec=0.001)
        for name, proc in procs.items():
            assert proc.poll() is None, f"{name} died"


def start_pair():
    return {"radar": start_node("radar", "-p", "use_sim_time:=true", "-p", f"epoch_utc:={EPOCH}", "-p", "seed:=3"),
            "radar_od": start_node("radar_od", "-p", "use_sim_time:=true", "-p", f"epoch_utc:={EPOCH}")}


def stop_all(procs):
    for name, proc in procs.items():
        code, out = stop_node(proc)
        assert code == 0, f"{name}: {out}"


@pytest.mark.parametrize("lockstep", [True, False], ids=["lockstep", "alone"])
def test_tracks_passes_after_separation_and_estimates_consistently(sim, lockstep):
    procs = start_pair()
    try:
        if lockstep:  # the step topic must be matched before the first step, or the nodes start alone
            assert spin_until(sim, lambda: sim.step_pub.get_subscription_count() >= 2, timeout=30)
        run_sim(sim, procs, lockstep)
        assert spin_until(sim, lambda: len(sim.ods) >= 2, timeout=20), "no second OD solution"
        spin_until(sim, lambda: False, timeout=0.5)
        assert all(p.poll() is None for p in procs.values())  # survived the NaN truth message
    finally:
        stop_all(procs)

    # --- measurements: exactly the visible epochs >= 5 km apart, nothing else ---------------------------------
    grid = np.arange(SAMPLE, SIM_END + SAMPLE / 2, SAMPLE)
    roe, kep = truth(grid)
    z = observe(roe, kep, gcrs_to_itrs(JD0, grid), TIRA.ecef, TIRA.enu)
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
    # every pass ends after its last measurement, with their count
    ends = {e.pass_id: e for e in sim.ends}
    assert sorted(ends) == [1, 2, 3, 4, 5] or sorted(ends) == [1, 2, 3, 4]  # the last one may be open at the end
    for pid, e in ends.items():
        own = stamps[np.array(pass_ids) == pid]
        assert e.measurements == own.size == e.epochs_in_view and time_to_sec(e.header.stamp) > own.max()

    # --- diagnostics ---------------------------------------------------------------------------------------
    assert any("waiting for separation" in s for s in statuses(sim, DiagnosticStatus.WARN, "radar"))
    assert any("rejected" in s for s in statuses(sim, DiagnosticStatus.ERROR, "radar"))
    assert any("rejected" in s for s in statuses(sim, DiagnosticStatus.ERROR))
    check_solutions(sim, stamps)


def check_solutions(sim, stamps):
    """OD: only post-burn passes, consistent with the truth."""
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


def test_estimates_from_measurements_without_the_sensor(sim):
    """No radar node: the test publishes the measurements and pass ends itself (a ground segment's, simulated
    here from the truth with the core's model and noise), then the truth as radar_od's chief. radar_od estimates
    from them alone, consistent with the truth, over DDS."""
    proc = start_node("radar_od", "-p", f"epoch_utc:={EPOCH}")
    procs = {"radar_od": proc}
    meas_pub = sim.create_publisher(RadarMeasurement, interfaces.RADAR_TOPIC, interfaces.STREAM)
    end_pub = sim.create_publisher(RadarPass, interfaces.RADAR_PASS_TOPIC, interfaces.STREAM)
    grid = np.arange(SAMPLE, SIM_END + SAMPLE / 2, SAMPLE)
    roe, kep = truth(grid)
    z = observe(roe, kep, gcrs_to_itrs(JD0, grid), TIRA.ecef, TIRA.enu)
    good = trackable(z[:, 2], relative_distance(roe, A, kep[:, 4] + kep[:, 5]), MASK, 5000.0)
    rng = np.random.default_rng(11)
    sigma = np.array([10.0, math.radians(0.01), math.radians(0.01)])
    try:
        assert spin_until(sim, lambda: meas_pub.get_subscription_count() >= 1 and end_pub.get_subscription_count() >= 1
                          and sim.truth_pub.get_subscription_count() >= 1, timeout=30), "radar_od did not come up"
        time.sleep(0.5)
        ticks = np.arange(0.0, SIM_END + TICK / 2, TICK)
        roe_t, kep_t = truth(ticks)
        for k, t in enumerate(ticks):  # the carrier's orbit first: every measurement finds its chief
            sim.truth_pub.publish(truth_msg(t, roe_t[k], kep_t[k]))
        sim.burn_pub.publish(maneuver_msg(BURN_T, CHIEF.u_at(BURN_T), [-v for v in BURN_DV], "carrier",
                                          "drift_reduction"))
        spin_until(sim, lambda: False, timeout=1.0)
        pass_id, stamps, count = 0, [], 0
        for j, t in enumerate(grid):
            if good[j]:
                if count == 0:
                    pass_id += 1
                zj = noisy_measurement(z[j], sigma, rng)
                m = RadarMeasurement(station="TIRA", pass_id=pass_id, range=float(zj[0]), azimuth=float(zj[1]),
                                     elevation=float(zj[2]), sigma_range=float(sigma[0]),
                                     sigma_angle=float(sigma[1]))
                m.header.stamp = sec_to_time(t)
                meas_pub.publish(m)
                stamps.append(t)
                count += 1
            elif count:
                end = RadarPass(station="TIRA", pass_id=pass_id, measurements=count, epochs_in_view=count)
                end.header.stamp = sec_to_time(t)
                end_pub.publish(end)
                count = 0
                rclpy.spin_once(sim, timeout_sec=0.01)
        assert spin_until(sim, lambda: len(sim.ods) >= 2, timeout=30), "no second OD solution"
        assert proc.poll() is None
    finally:
        stop_all(procs)
    check_solutions(sim, np.array(stamps))
    cov = np.array(sim.ods[-1].estimate.covariance).reshape(6, 6)
    assert np.all(np.linalg.eigvalsh(cov) > 0.0)  # an estimate with its covariance


@pytest.mark.parametrize(
    "node,args,name",
    [("radar_od", ["-p", "sigma_range_m:=-1.0"], "'sigma_range_m'"),
     ("radar", ["-p", "station_latitudes_deg:=[50.6, 48.1]"], "'station_latitudes_deg'"),
     ("radar_od", ["-p", "station_latitudes_deg:=[50.6, 48.1]"], "'station_latitudes_deg'"),
     ("radar", ["-p", "epoch_utc:=yesterday"], "'epoch_utc'"),
     ("radar", ["-p", "min_separation:=5000"], "'min_separation'"),
     ("radar_od", ["-p", "density_walk:=-0.1"], "'density_walk'"),
     ("radar_od", ["-p", "drag_ballistic_ratio:=0.5"], "'drag_ballistic_ratio'")],
)
def test_bad_parameter_refused_at_startup(node, args, name):
    code, out = wait_exit(start_node(node, *args))
    assert code == 2, out
    assert name in out
