"""Bags over real DDS: the recorder process writes a rosbag2-compatible MCAP bag that two independent readers
(mcap + mcap_ros2, rosbags) decode to exactly what was published; a SIGKILLed recording is recovered; the replay
re-publishes the same messages in order and re-latches the latched plan for late joiners."""

import os
import signal
import subprocess
import sys
import time
from types import SimpleNamespace

import pytest
import yaml
from bagutil import bag_replay_process, mcap_file, norm, read_mcap_ros2, read_rosbags  # noqa: E402
from builtin_interfaces.msg import Time  # noqa: E402
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue  # noqa: E402
from mcap.reader import make_reader  # noqa: E402
from roe_sep_msgs.msg import ImpulsiveManeuver, ManeuverPlan, RelativeOrbitalElements  # noqa: E402
from rosgraph_msgs.msg import Clock  # noqa: E402
from rosutil import ROOT, context, rclpy, ros_env, spin_until, start_node, stop_node, wait_exit  # noqa: I001,E402

from roe_sep import interfaces  # noqa: E402
from roe_sep.bag import BagError, definitions, info, metadata  # noqa: E402
from roe_sep.bag import reader as bag_reader  # noqa: E402
from roe_sep.bag import recover as bag_recover  # noqa: E402
from roe_sep.bag import replay as bag_replay  # noqa: E402
from roe_sep.nodes.convert import array_to_vector, sec_to_time  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

CLOCK_QOS = rclpy.qos.QoSProfile(depth=10)
SOURCE_STATUS = "bag_test/source"
N_ROE, N_DIAG, N_CLOCK = 20, 5, 5


# -- helpers ---------------------------------------------------------------------------------------------------------
def plan_msg():
    plan = ManeuverPlan(strategy="double_impulse", ejection_epoch=sec_to_time(1000.0), p_reduction=0.06)
    plan.header.stamp = sec_to_time(1000.5)
    plan.header.frame_id = "carrier_rtn"
    plan.maneuvers = [ImpulsiveManeuver(epoch=sec_to_time(9000.25), mean_arg_latitude=11.0,
                                        dv_rtn=array_to_vector([1.32925, -0.102718, 0.0]), spacecraft="carrier",
                                        purpose="drift_stop")]
    plan.aimed.a_dl = 8990.2
    plan.aimed.chief.semi_major_axis = 6893137.0
    return plan


def roe_msg(i):
    m = RelativeOrbitalElements(a_da=-1.5 * i, a_dl=8990.2 + i, a_dex=-20.6, a_dey=-589.6, a_dix=14.0, a_diy=399.8)
    m.header.stamp = sec_to_time(2000.0 + 0.1 * i)
    m.header.frame_id = "carrier_rtn"
    m.covariance = [float(i * 36 + k) for k in range(36)]
    m.chief.semi_major_axis = 6893137.0 + i
    m.chief.inclination = 1.7
    return m


def diag_msg(i):
    status = DiagnosticStatus(level=DiagnosticStatus.WARN if i % 2 else DiagnosticStatus.OK, name=SOURCE_STATUS,
                              message=f"tick {i}", hardware_id="test",
                              values=[KeyValue(key="i", value=str(i)), KeyValue(key="x", value="ü")])
    array = DiagnosticArray(status=[status])
    array.header.stamp = Time(sec=3000 + i, nanosec=7)
    return array


def recorder_values(diags):
    """The latest key/values of the recorder's own diagnostics status."""
    values = {}
    for d in diags:
        for s in d.status:
            if s.name == "roe_sep/recorder":
                values = {kv.key: kv.value for kv in s.values}
    return values


def published_diags(msgs):
    """Only the test source's DiagnosticArrays (the recorder publishes its own on the same topic)."""
    return [m for m in msgs if any(s.name == SOURCE_STATUS for s in m.status)]


# -- fixtures --------------------------------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def ros():
    with context():  # module-wide: the recording is shared by the module's tests
        node = rclpy.create_node("bag_test")
        node.diags = []
        node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, node.diags.append,
                                 interfaces.DIAGNOSTICS)
        yield node
        node.destroy_node()


@pytest.fixture(scope="module")
def recorded(ros, tmp_path_factory):
    """A bag recorded by the real recorder process: the latched plan published before it started, then streams."""
    bag = str(tmp_path_factory.mktemp("rec") / "run1")
    plan_pub = ros.create_publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED)
    roe_pub = ros.create_publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
    diag_pub = ros.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
    clock_pub = ros.create_publisher(Clock, interfaces.CLOCK_TOPIC, CLOCK_QOS)
    plan = plan_msg()
    plan_pub.publish(plan)  # before the recorder exists: it must come from the transient-local history
    t0 = time.monotonic()
    rec = start_node("recorder", "-p", f"output:={bag}", "-p", "flush_period:=0.5", "-p", "exclude:=[/rosout]")
    try:
        assert spin_until(ros, lambda: all(p.get_subscription_count() >= 1 for p in (roe_pub, clock_pub))
                          and plan_pub.get_subscription_count() >= 1, timeout=20), "recorder did not subscribe"
        roes, diags, clocks = [], [], []
        for i in range(N_ROE):
            roes.append(roe_msg(i))
            roe_pub.publish(roes[-1])
            if i % 4 == 0:
                diags.append(diag_msg(i))
                diag_pub.publish(diags[-1])
                clocks.append(Clock(clock=Time(sec=100 + i, nanosec=250_000_000)))
                clock_pub.publish(clocks[-1])
            rclpy.spin_once(ros, timeout_sec=0.025)
        expect = {interfaces.TRUTH_ROE_TOPIC: N_ROE, interfaces.CLOCK_TOPIC: N_CLOCK,
                  interfaces.DRIFT_STOP_PLAN_TOPIC: 1}
        assert spin_until(ros, lambda: all(recorder_values(ros.diags).get(t) == str(n) for t, n in expect.items()),
                          timeout=10), recorder_values(ros.diags)
    finally:
        code, out = stop_node(rec)
    assert code == 0, out
    for p in (plan_pub, roe_pub, diag_pub, clock_pub):
        ros.destroy_publisher(p)
    return SimpleNamespace(bag=bag, plan=plan, roes=roes, diags=diags, clocks=clocks, log=out,
                           seconds=time.monotonic() - t0)


# -- recording -------------------------------------------------------------------------------------------------------
def test_metadata_yaml_is_rosbag2_jazzy(recorded):
    with open(os.path.join(recorded.bag, "metadata.yaml")) as fh:
        meta = yaml.safe_load(fh)["rosbag2_bagfile_information"]
    assert meta["version"] == 9 and meta["storage_identifier"] == "mcap" and meta["ros_distro"]
    assert meta["compression_format"] == "" and meta["compression_mode"] == "" and "custom_data" in meta
    (fname,) = meta["relative_file_paths"]
    assert fname == "run1_0.mcap" and os.path.isfile(os.path.join(recorded.bag, fname))
    topics = {t["topic_metadata"]["name"]: t for t in meta["topics_with_message_count"]}
    assert "/rosout" not in topics  # excluded
    assert topics[interfaces.TRUTH_ROE_TOPIC]["message_count"] == N_ROE
    assert topics[interfaces.CLOCK_TOPIC]["message_count"] == N_CLOCK
    assert topics[interfaces.DRIFT_STOP_PLAN_TOPIC]["message_count"] == 1
    assert topics[interfaces.DIAGNOSTICS_TOPIC]["message_count"] >= N_DIAG
    assert meta["message_count"] == sum(t["message_count"] for t in topics.values())
    (f,) = meta["files"]
    assert f["path"] == fname and f["message_count"] == meta["message_count"]
    assert f["duration"] == meta["duration"] and f["starting_time"] == meta["starting_time"]
    plan_meta = topics[interfaces.DRIFT_STOP_PLAN_TOPIC]["topic_metadata"]
    assert plan_meta["type"] == "roe_sep_msgs/msg/ManeuverPlan" and plan_meta["serialization_format"] == "cdr"
    (offer,) = plan_meta["offered_qos_profiles"]
    assert offer["durability"] == "transient_local" and offer["reliability"] == "reliable"
    assert set(offer) == {"history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
                          "liveliness_lease_duration", "avoid_ros_namespace_conventions"}
    assert offer["deadline"] == {"sec": 9223372036, "nsec": 854775807}
    roe_offer = topics[interfaces.TRUTH_ROE_TOPIC]["topic_metadata"]["offered_qos_profiles"][0]
    assert roe_offer["durability"] == "volatile"
    for t in topics.values():
        tm = t["topic_metadata"]
        assert tm["type_description_hash"] == definitions.type_hash(tm["type"])
        assert tm["type_description_hash"].startswith("RIHS01_") and len(tm["type_description_hash"]) == 71


def test_mcap_layout_is_rosbag2_storage_mcap(recorded):
    with open(mcap_file(recorded.bag), "rb") as fh:
        reader = make_reader(fh)
        header, summary = reader.get_header(), reader.get_summary()
        seqs, times = {}, {}
        for _s, ch, m in reader.iter_messages(log_time_order=False):
            seqs.setdefault(ch.topic, []).append(m.sequence)
            times.setdefault(ch.topic, []).append(m.log_time)
        (meta_rec,) = [m for m in reader.iter_metadata() if m.name == "rosbag2"][-1:]
    assert header.profile == "ros2"
    assert summary.statistics.message_count == sum(len(v) for v in seqs.values())
    for schema in summary.schemas.values():
        assert schema.encoding == "ros2msg"
        assert schema.data.decode() == definitions.full_text(schema.name)
    plan_schema = next(s for s in summary.schemas.values() if s.name == "roe_sep_msgs/msg/ManeuverPlan")
    text = plan_schema.data.decode()
    plan_msg_file = definitions.share_dir("roe_sep_msgs") / "msg" / "ManeuverPlan.msg"
    assert text.startswith(plan_msg_file.read_text())
    sections = text.split("\n" + "=" * 80 + "\n")
    assert sorted(s.splitlines()[0] for s in sections[1:]) == sorted(
        ["MSG: builtin_interfaces/Time", "MSG: geometry_msgs/Vector3", "MSG: roe_sep_msgs/ImpulsiveManeuver",
         "MSG: roe_sep_msgs/OrbitalElements", "MSG: roe_sep_msgs/RelativeOrbitalElements", "MSG: std_msgs/Header"])
    for ch in summary.channels.values():
        assert ch.message_encoding == "cdr"
        assert set(ch.metadata) == {"offered_qos_profiles", "topic_type_hash"}
        assert metadata.parse_qos(ch.metadata["offered_qos_profiles"])[0]["reliability"] in ("reliable", "best_effort")
    for topic, s in seqs.items():
        assert s == list(range(1, len(s) + 1)), topic  # per-channel sequence numbers
        assert times[topic] == sorted(times[topic]) and times[topic][0] > 0
    assert yaml.safe_load(meta_rec.metadata["serialized_metadata"])["message_count"] == sum(map(len, seqs.values()))


def test_round_trip_with_mcap_ros2(recorded):
    got = read_mcap_ros2(mcap_file(recorded.bag))
    assert [norm(m) for m, _, _ in got[interfaces.DRIFT_STOP_PLAN_TOPIC]] == [norm(recorded.plan)]
    assert [norm(m) for m, _, _ in got[interfaces.TRUTH_ROE_TOPIC]] == [norm(m) for m in recorded.roes]
    assert [norm(m) for m, _, _ in got[interfaces.CLOCK_TOPIC]] == [norm(m) for m in recorded.clocks]
    mine = [m for m, _, _ in got[interfaces.DIAGNOSTICS_TOPIC] if any(s.name == SOURCE_STATUS for s in m.status)]
    assert [norm(m) for m in mine] == [norm(m) for m in recorded.diags]


def test_round_trip_with_rosbags(recorded):
    got, conns = read_rosbags(recorded.bag)
    assert [norm(m) for m in got[interfaces.DRIFT_STOP_PLAN_TOPIC]] == [norm(recorded.plan)]
    assert [norm(m) for m in got[interfaces.TRUTH_ROE_TOPIC]] == [norm(m) for m in recorded.roes]
    assert [norm(m) for m in got[interfaces.CLOCK_TOPIC]] == [norm(m) for m in recorded.clocks]
    assert [norm(m) for m in published_diags(got[interfaces.DIAGNOSTICS_TOPIC])] == [norm(m) for m in recorded.diags]
    plan_conn = conns[interfaces.DRIFT_STOP_PLAN_TOPIC]
    assert plan_conn.msgcount == 1 and plan_conn.digest == definitions.type_hash("roe_sep_msgs/msg/ManeuverPlan")
    assert plan_conn.ext.offered_qos_profiles[0].durability.name == "TRANSIENT_LOCAL"


def test_info(recorded):
    d = info(recorded.bag)
    assert d["complete"] and d["profile"] == "ros2" and d["ros_distro"]
    counts = {t["name"]: t["message_count"] for t in d["topics"]}
    assert counts[interfaces.TRUTH_ROE_TOPIC] == N_ROE and counts[interfaces.CLOCK_TOPIC] == N_CLOCK
    assert d["message_count"] == sum(counts.values()) and 0 < d["duration_s"] < recorded.seconds
    types = {t["name"]: t["type"] for t in d["topics"]}
    assert types[interfaces.TRUTH_ROE_TOPIC] == "roe_sep_msgs/msg/RelativeOrbitalElements"


# -- replay ----------------------------------------------------------------------------------------------------------
def test_replay_same_messages_in_order_and_relatched(ros, recorded):
    roes, clocks, arrivals = [], [], []
    roe_sub = ros.create_subscription(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC,
                                      lambda m: (roes.append(m), arrivals.append(time.monotonic())), interfaces.STREAM)
    clock_sub = ros.create_subscription(Clock, interfaces.CLOCK_TOPIC, clocks.append, CLOCK_QOS)
    proc = bag_replay_process(recorded.bag, "--rate", "1", "--delay", "10", "--linger", "3",
                              "--topics", interfaces.TRUTH_ROE_TOPIC, interfaces.CLOCK_TOPIC,
                              interfaces.DRIFT_STOP_PLAN_TOPIC)
    try:
        assert spin_until(ros, lambda: len(roes) >= N_ROE and len(clocks) >= N_CLOCK, timeout=20), (
            [m.a_dl for m in roes], len(clocks))
        assert [norm(m) for m in roes] == [norm(m) for m in recorded.roes]
        assert [norm(m) for m in clocks] == [norm(m) for m in recorded.clocks]
        # original timing: the 20 messages were recorded ~25 ms apart; replayed at rate 1 they are spread out too
        recorded_span = (read_mcap_ros2(mcap_file(recorded.bag))[interfaces.TRUTH_ROE_TOPIC][-1][1]
                         - read_mcap_ros2(mcap_file(recorded.bag))[interfaces.TRUTH_ROE_TOPIC][0][1]) * 1e-9
        assert arrivals[-1] - arrivals[0] > 0.5 * recorded_span
        # a subscriber created after the replay published the latched plan still receives it
        plans = []
        plan_sub = ros.create_subscription(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, plans.append,
                                           interfaces.LATCHED)
        assert spin_until(ros, lambda: len(plans) >= 1, timeout=5)
        assert [norm(p) for p in plans] == [norm(recorded.plan)]
        ros.destroy_subscription(plan_sub)
    finally:
        code, out = wait_exit(proc, timeout=30)
        ros.destroy_subscription(roe_sub)
        ros.destroy_subscription(clock_sub)
    assert code == 0, out
    assert f"replayed {N_ROE + N_CLOCK + 1} messages on 3 topics" in out


def test_replay_publishes_clock_from_log_times(ros, tmp_path):
    from rclpy.serialization import serialize_message

    from roe_sep.bag.qos import profile_dict
    from roe_sep.bag.writer import BagWriter

    topic, t0 = "/bag_test/clocked", 7000 * 10**9
    with BagWriter(tmp_path / "noclock") as w:
        w.add_topic(topic, "roe_sep_msgs/msg/RelativeOrbitalElements", [profile_dict()])
        for i in range(4):
            w.write(topic, serialize_message(roe_msg(i)), t0 + i * 100_000_000)
    clocks, roes = [], []
    subs = [ros.create_subscription(Clock, interfaces.CLOCK_TOPIC, clocks.append, CLOCK_QOS),
            ros.create_subscription(RelativeOrbitalElements, topic, roes.append, interfaces.STREAM)]
    proc = bag_replay_process(str(tmp_path / "noclock"), "--clock", "50", "--delay", "10", "--linger", "0.2")
    try:
        spin_until(ros, lambda: proc.poll() is not None, timeout=30)  # take every /clock as it comes
        code, out = wait_exit(proc, timeout=5)
        spin_until(ros, lambda: len(roes) >= 4, timeout=2)
    finally:
        for sub in subs:
            ros.destroy_subscription(sub)
    assert code == 0, out
    assert [norm(m) for m in roes] == [norm(roe_msg(i)) for i in range(4)]
    stamps = [c.clock.sec * 10**9 + c.clock.nanosec for c in clocks]
    assert stamps and stamps == sorted(stamps) and t0 <= stamps[0] and stamps[-1] == t0 + 300_000_000
    assert {t0 + i * 100_000_000 for i in range(4)} <= set(stamps)


def test_sim_time_log_times(ros, tmp_path):
    """Under use_sim_time the log time is the simulator's /clock; messages received before the first /clock
    (here the latched plan and one ROE message) take the first clock time instead of 0."""
    roe_topic, plan_topic = "/bag_test/sim/roe", "/bag_test/sim/plan"
    bag = tmp_path / "sim"
    clock_pub = ros.create_publisher(Clock, interfaces.CLOCK_TOPIC, CLOCK_QOS)
    roe_pub = ros.create_publisher(RelativeOrbitalElements, roe_topic, interfaces.STREAM)
    plan_pub = ros.create_publisher(ManeuverPlan, plan_topic, interfaces.LATCHED)
    plan_pub.publish(plan_msg())
    rec = start_node("recorder", "-p", f"output:={bag}", "-p", "use_sim_time:=true", "-p", "flush_period:=0.2",
                     "-p", f"topics:=[{roe_topic}, {plan_topic}]")
    try:
        assert spin_until(ros, lambda: roe_pub.get_subscription_count() >= 1
                          and clock_pub.get_subscription_count() >= 1, timeout=20)
        for k in range(3):
            roe_pub.publish(roe_msg(k))
            spin_until(ros, lambda: False, timeout=0.3)
            clock_pub.publish(Clock(clock=Time(sec=5000 + k)))
            spin_until(ros, lambda: False, timeout=0.3)
        assert spin_until(ros, lambda: recorder_values(ros.diags).get(roe_topic) == "3", timeout=10)
    finally:
        code, out = stop_node(rec)
        for p in (clock_pub, roe_pub, plan_pub):
            ros.destroy_publisher(p)
    assert code == 0, out
    got = read_mcap_ros2(mcap_file(bag))
    roe_times = [t for _, t, _ in got[roe_topic]]
    assert [t for _, t, _ in got[plan_topic]] == [5000 * 10**9]
    assert roe_times == [5000 * 10**9, 5000 * 10**9, 5001 * 10**9]
    assert metadata.read(bag)["starting_time"]["nanoseconds_since_epoch"] == 5000 * 10**9


# -- crash safety ----------------------------------------------------------------------------------------------------
def test_sigkill_then_recover(ros, tmp_path):
    topic = "/bag_test/kill_roe"
    bag, out = tmp_path / "killed", tmp_path / "recovered"
    pub = ros.create_publisher(RelativeOrbitalElements, topic, interfaces.STREAM)
    rec = start_node("recorder", "-p", f"output:={bag}", "-p", f"topics:=[{topic}]", "-p", "flush_period:=0.3")
    try:
        assert spin_until(ros, lambda: pub.get_subscription_count() >= 1, timeout=20)
        sent = [roe_msg(i) for i in range(12)]
        for m in sent:
            pub.publish(m)
        assert spin_until(ros, lambda: recorder_values(ros.diags).get(topic) == str(len(sent)), timeout=10)
        spin_until(ros, lambda: False, timeout=1.0)  # > 3 flush periods after the last message
    finally:
        rec.send_signal(signal.SIGKILL)
        rec.communicate(timeout=10)
        ros.destroy_publisher(pub)
    assert not (bag / "metadata.yaml").exists()
    d = info(bag)
    assert d["complete"] is False and d["message_count"] == len(sent)
    with pytest.raises(BagError, match="recover"):
        list(bag_reader.messages(bag))

    assert bag_recover.main([str(bag), str(out)]) == 0
    got = read_mcap_ros2(mcap_file(out))
    assert [norm(m) for m, _, _ in got[topic]] == [norm(m) for m in sent]
    rb, conns = read_rosbags(str(out))
    assert [norm(m) for m in rb[topic]] == [norm(m) for m in sent]
    assert conns[topic].msgtype == "roe_sep_msgs/msg/RelativeOrbitalElements"
    meta = metadata.read(out)
    assert meta["message_count"] == len(sent) and info(out)["complete"]


def test_bad_message_survived_and_sigterm_closes_the_bag(ros, tmp_path):
    """Garbage bytes on a typed topic are recorded as they are (never deserialized); SIGTERM closes the bag."""
    topic = "/bag_test/garbage"
    bag = tmp_path / "term"
    pub = ros.create_publisher(RelativeOrbitalElements, topic, interfaces.STREAM)
    rec = start_node("recorder", "-p", f"output:={bag}", "-p", f"topics:=[{topic}]")
    try:
        assert spin_until(ros, lambda: pub.get_subscription_count() >= 1, timeout=20)
        pub.publish(b"\x00\x01\x00\x00garbage")  # not a valid RelativeOrbitalElements
        pub.publish(roe_msg(1))
        assert spin_until(ros, lambda: recorder_values(ros.diags).get(topic) == "2", timeout=10)
        assert rec.poll() is None
    finally:
        ros.destroy_publisher(pub)
        rec.send_signal(signal.SIGTERM)
        code, out = wait_exit(rec, timeout=10)
    assert code == 0, out
    assert (bag / "metadata.yaml").is_file() and info(bag)["complete"]
    data = [m.data for m in bag_reader.messages(bag)]
    assert data[0].startswith(b"\x00\x01\x00\x00garbage") and len(data) == 2  # (DDS pads to 4 bytes)


@pytest.mark.parametrize("layout", ["node", "suite"])
def test_stop_right_after_a_burst_records_all_of_it(ros, tmp_path, layout):
    """SIGINT right after a burst: the recorder drains what DDS already delivered before it closes the bag (as the
    runner stops it right after the simulator's final status), alone or in a suite on the EventsExecutor."""
    topic, n = "/bag_test/burst", 400
    bag = tmp_path / "burst"
    pub = ros.create_publisher(RelativeOrbitalElements, topic, interfaces.BULK)
    ros_args = ["--ros-args", "-p", f"output:={bag}", "-p", f"topics:=[{topic}]"]
    if layout == "node":
        rec = start_node("recorder", *ros_args[1:])
    else:
        rec = subprocess.Popen([sys.executable, "-m", "roe_sep.nodes.suite", "recorder", *ros_args], env=ros_env(),
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, cwd=ROOT)
    try:
        assert spin_until(ros, lambda: pub.get_subscription_count() >= 1, timeout=20)
        for i in range(n):
            pub.publish(roe_msg(i))
        code, out = stop_node(rec, timeout=30)
    finally:
        ros.destroy_publisher(pub)
    assert code == 0, out
    assert info(bag)["complete"] and info(bag)["message_count"] == n, out


# -- errors ----------------------------------------------------------------------------------------------------------
def test_existing_output_and_bad_parameters_are_refused(tmp_path):
    busy = tmp_path / "busy"
    busy.mkdir()
    (busy / "keep.txt").write_text("precious")
    code, out = wait_exit(start_node("recorder", "-p", f"output:={busy}"))
    assert code == 2, out
    assert "'output'" in out and "not an empty directory" in out
    assert (busy / "keep.txt").read_text() == "precious" and len(os.listdir(busy)) == 1
    code, out = wait_exit(start_node("recorder", "-p", f"output:={tmp_path / 'x'}", "-p", "flush_period:=-1"))
    assert code == 2 and "'flush_period'" in out, out


def test_bad_bag_paths_give_clear_errors(tmp_path, capsys, recorded):
    assert bag_replay.main([str(tmp_path / "nope")]) == 2
    assert "no such bag" in capsys.readouterr().err
    assert bag_replay.main([recorded.bag, "--topics", "/not/recorded"]) == 2
    assert "/not/recorded" in capsys.readouterr().err
    assert bag_recover.main([str(tmp_path / "nope"), str(tmp_path / "out")]) == 2
    assert "no such bag" in capsys.readouterr().err
    assert bag_recover.main([recorded.bag, recorded.bag]) == 2  # would overwrite
    assert "not an empty directory" in capsys.readouterr().err
    (tmp_path / "junk.mcap").write_bytes(b"not an mcap file")
    assert bag_recover.main([str(tmp_path / "junk.mcap"), str(tmp_path / "out2")]) == 2
    assert "not an MCAP file" in capsys.readouterr().err
    with pytest.raises(BagError, match="no such bag"):
        info(tmp_path / "nope")
