"""ground_bridge and radar_od as real processes over DDS, fed with messages of the reference bag.

Out: an approved plan becomes its OPM pair in the output directory while the node runs, and the simulator's final
status the complete set. In: the TDM of the
reference run's first OD window, dropped into the input directory, reaches radar_od through
``/ground/radar_measurements`` and gives the run's OD solution again; a malformed file is moved aside with an ERROR
on ``/diagnostics`` and the node keeps running.
"""

from pathlib import Path

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from rclpy.serialization import deserialize_message
from roe_sep_msgs.msg import ManeuverPlan, OrbitDetermination, RelativeOrbitalElements, SafetyStatus
from rosgraph_msgs.msg import Clock
from rosutil import publish_until, rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces
from roe_sep.bag.reader import messages
from roe_sep.ndm import frames
from roe_sep.ndm import messages as ndm
from roe_sep.ndm.dataset import thin
from roe_sep.ndm.options import Options
from roe_sep.stamps import time_to_sec as stamp

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

BAG = Path(__file__).resolve().parents[2] / "bags" / "default_run"
EPOCH = "2016-07-01T00:00:00"
TYPES = {interfaces.TRUTH_ROE_TOPIC: RelativeOrbitalElements, interfaces.DRIFT_STOP_PLAN_TOPIC: ManeuverPlan,
         interfaces.PLAN_CHECK_TOPIC: SafetyStatus, interfaces.OD_TOPIC: OrbitDetermination}


@pytest.fixture(scope="module")
def bag():
    out = {t: [] for t in TYPES}
    for m in messages(BAG, topics=list(TYPES)):
        out[m.topic].append(deserialize_message(m.data, TYPES[m.topic]))
    return out


def od_window_tdm(path, bag):
    """TDM of the measurements of the run's first OD (after the drift-stop, up to its epoch), from export's TDM
    writer fed with the bag's radar messages."""
    from roe_sep.cli.export import read_run
    from roe_sep.ndm.dataset import radar_passes

    run = read_run(BAG)
    od = min(bag[interfaces.OD_TOPIC], key=lambda o: stamp(o.estimate.header.stamp))
    t_est = stamp(od.estimate.header.stamp)
    t_burn = max(stamp(m.epoch) for m in run[interfaces.EXECUTED_TOPIC] if stamp(m.epoch) <= t_est)
    passes = []
    for p in radar_passes(run):
        keep = (p.t >= t_burn) & (p.t <= t_est)
        if keep.any():
            p.t, p.z = p.t[keep], p.z[keep]
            passes.append(p)
    ndm.write_message(path, ndm.build_tdm(EPOCH, passes), "kvn")
    return od


def test_ground_bridge_writes_opms_and_feeds_tdm_files_to_radar_od(tmp_path, bag, ros_context):
    out, inp = tmp_path / "ccsds", tmp_path / "in"
    bridge = start_node("ground_bridge", "-p", f"output_dir:={out}", "-p", f"input_dir:={inp}",
                        "-p", "poll_period:=0.2")
    radar = start_node("radar_od")
    node = rclpy.create_node("ground_bridge_test")
    try:
        got = {"od": [], "diag": []}
        node.create_subscription(OrbitDetermination, interfaces.OD_TOPIC, got["od"].append, interfaces.LATCHED)
        node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, got["diag"].append,
                                 interfaces.DIAGNOSTICS)
        truth_pub = node.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.BULK)
        plan_pub = node.create_publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED)
        check_pub = node.create_publisher(SafetyStatus, interfaces.PLAN_CHECK_TOPIC, interfaces.EXECUTED)
        assert spin_until(node, lambda: truth_pub.get_subscription_count() >= 2, 30.0), "nodes did not come up"
        clock_pub = node.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)

        # out: the truth from the drift-stop to the first OD's epoch (radar_od takes the chief of an external
        # measurement from the first truth sample at or after it, as its own tracking did), then the drift-stop plan
        # and its approval -> the OPM pair
        truth = [m for m in bag[interfaces.TRUTH_ROE_TOPIC] if 9150.0 < stamp(m.header.stamp) < 75600.0 + 300.0]
        for m in truth:
            truth_pub.publish(m)
        spin_until(node, lambda: False, 0.5)
        clock_pub.publish(Clock(clock=Time(sec=76200)))  # the run's clock when its first OD came out
        plan_pub.publish(bag[interfaces.DRIFT_STOP_PLAN_TOPIC][0])
        check_pub.publish(bag[interfaces.PLAN_CHECK_TOPIC][0])
        names = ("plan01_double_impulse.opm.xml", "plan01_double_impulse_eme2000.opm.xml")
        assert spin_until(node, lambda: all((out / n).is_file() for n in names), 20.0), sorted(out.iterdir())
        opm = ndm.read_message(out / names[0]).body.segment.data.maneuver_parameters[0]
        dv = bag[interfaces.DRIFT_STOP_PLAN_TOPIC][0].maneuvers[0].dv_rtn
        assert opm.man_ref_frame == "RTN"
        assert abs(opm.man_dv_1.value * 1e3 - dv.x) < 1e-9 and abs(opm.man_dv_2.value * 1e3 - dv.y) < 1e-9
        # the files the live node writes are valid against the official NDM/XML 2.0.0 schemas and against the
        # schema of ccsds-ndm's models (test_ndm.py validates the whole set of a run, written by the same builders)
        from ccsds_ndm.models import ndmxml2 as nd
        from ndm_schema import errors, model_schema, official_schema

        schema = model_schema(nd.Opm)
        assert [errors(schema, out / n) for n in names] == [[], []]
        assert [errors(official_schema(), out / n) for n in names] == [[], []]

        # in: a malformed file is moved aside with an ERROR, the node keeps running
        (inp / "garbage.tdm").write_text("CCSDS_TDM_VERS = 2.0\nthis is not a TDM\n")

        def rejected():
            return any(s.level == DiagnosticStatus.ERROR and "garbage.tdm" in s.message
                       for a in got["diag"] for s in a.status)

        assert spin_until(node, rejected, 20.0)
        assert (inp / "rejected" / "garbage.tdm").is_file() and not (inp / "garbage.tdm").exists()
        assert bridge.poll() is None

        # in: the first OD window's TDM -> radar_od's solution equals the run's
        got["od"].clear()
        od = od_window_tdm(inp / "od_window.kvn", bag)
        assert spin_until(node, lambda: len(got["od"]) > 0, 60.0), "no OD solution from the TDM"
        assert (inp / "processed" / "od_window.kvn").is_file()
        new = got["od"][-1]
        keys = ("a_da", "a_dl", "a_dex", "a_dey", "a_dix", "a_diy")
        a = np.array([getattr(new.estimate, k) for k in keys])
        b = np.array([getattr(od.estimate, k) for k in keys])
        assert new.measurements == od.measurements == 117 and new.passes == od.passes == 3
        assert stamp(new.estimate.header.stamp) == stamp(od.estimate.header.stamp)
        assert np.max(np.abs(a - b)) < 1e-3  # m; the estimate's 1-sigma is meters
        assert new.a_da_dot == pytest.approx(od.a_da_dot, rel=1e-4, abs=1e-9)

        # the simulator's final status: the complete set is written at once, while the node still runs (the
        # status is volatile and sent once by a simulator that just started repeating it: sent until it is seen)
        assert not (out / "ephemeris.oem.xml").exists()  # the clock never reached write_period
        diag_pub = node.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        final = DiagnosticArray(status=[DiagnosticStatus(name="roe_sep/sim", message="scenario complete")])
        assert publish_until(node, lambda: diag_pub.publish(final), (out / "ephemeris.oem.xml").is_file, 60.0)
        assert bridge.poll() is None
    finally:
        node.destroy_node()
        code_b, log_b = stop_node(bridge, 30.0)
        code_r, log_r = stop_node(radar, 30.0)
    assert code_b == 0, log_b
    assert code_r == 0, log_r
    assert (out / "plan01_double_impulse.opm.xml").is_file()
    # the final set at shutdown: the carrier's ephemeris at every truth sample of the burst (thinned to the OEM
    # step as export's), none lost: 222 of the 223 samples published at once (a 100-deep reader keeps about half)
    segs = ndm.read_message(out / "ephemeris.oem.xml").body.segment
    states = segs[0].data.state_vector
    assert segs[0].metadata.object_id == "CARRIER"
    sent = np.array([stamp(m.header.stamp) for m in truth])
    expected = sent[thin(sent, Options().oem_step)]
    assert len(truth) == 223 and len(expected) == 222
    np.testing.assert_allclose([frames.sim_time(EPOCH, s.epoch) for s in states], expected, atol=1e-3)


def test_bad_parameters_exit_2(tmp_path):
    code, log = wait_exit(start_node("ground_bridge", "-p", f"output_dir:={tmp_path}", "-p", "format:=json"))
    assert code == 2 and "format" in log, log


def test_a_periodic_update_waits_for_both_the_sim_period_and_the_wall_interval():
    from roe_sep.nodes.ground_bridge import periodic_due

    assert periodic_due(86400.0, 86400.0, 10.0, 10.0)
    assert not periodic_due(86399.0, 86400.0, 60.0, 10.0)  # a day of sim time not yet passed
    assert not periodic_due(86400.0, 86400.0, 2.0, 10.0)  # a fast lockstep run: 2 s of wall time since the last
    assert periodic_due(86400.0, 86400.0, 0.0, 0.0)  # min_write_interval 0: every write_period
    assert not periodic_due(1e9, 0.0, 1e9, 0.0)  # write_period 0: only the final set
