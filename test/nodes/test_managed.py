"""Managed (lifecycle) nodes: autostart (active once constructed), or configure -> activate driven from outside
(lifecycle_manager, ``ros2 lifecycle set``); parameter errors surface at ``configure``."""

import time

import pytest
from diagnostic_msgs.msg import DiagnosticArray  # noqa: E402
from lifecycle_msgs.msg import State, Transition  # noqa: E402
from lifecycle_msgs.srv import ChangeState, GetState  # noqa: E402
from rcl_interfaces.srv import ListParameters  # noqa: E402
from rclpy.lifecycle import TransitionCallbackReturn  # noqa: E402
from rosutil import init, rclpy, spin_until, start_node, stop_node, wait_exit  # noqa: I001  (skips without rclpy)

from roe_sep import interfaces  # noqa: E402
from roe_sep.nodes.params import ParameterError  # noqa: E402
from roe_sep.nodes.planner import PlannerNode  # noqa: E402
from roe_sep.nodes.safety_monitor import SafetyMonitorNode  # noqa: E402

pytestmark = pytest.mark.dds  # every test here starts a node or an rclpy context

FAST_PLANNER = ("-p", "p_mode:=fixed", "-p", "p_reduction:=0.06")


@pytest.fixture
def context(ros_context):
    """``context(*params)``: rclpy's default context, initialised again with these ``-p`` parameters for every
    node."""
    yield lambda *params: init(*[a for p in params for a in ("-p", p)])


def label(node):
    return node._state_machine.current_state[1]


def subscribers(node, topic):
    return [s for s in node.subscriptions if s.topic_name == topic]


def test_autostart_node_is_active_after_construction(context):
    context("use_sim_time:=false")
    node = SafetyMonitorNode()
    try:
        assert isinstance(node, rclpy.lifecycle.Node)
        assert label(node) == "active" and node.autostart is True
        assert len(subscribers(node, interfaces.TRUTH_ROE_TOPIC)) == 1
        assert node.has_parameter("keep_out") and node.status_pub is not None
    finally:
        node.destroy_node()


def test_unconfigured_node_is_driven_through_its_states(context):
    context("autostart:=false", "use_sim_time:=false")
    node = SafetyMonitorNode()
    try:
        assert label(node) == "unconfigured"
        assert not node.has_parameter("keep_out") and not subscribers(node, interfaces.TRUTH_ROE_TOPIC)
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS and label(node) == "inactive"
        assert node.has_parameter("keep_out") and not subscribers(node, interfaces.TRUTH_ROE_TOPIC)
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS and label(node) == "active"
        assert len(subscribers(node, interfaces.TRUTH_ROE_TOPIC)) == 1
        assert node.count_publishers(interfaces.SAFETY_TOPIC) == 1
        # deactivate removes exactly what activate created; activate again recreates it
        assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS and label(node) == "inactive"
        assert not subscribers(node, interfaces.TRUTH_ROE_TOPIC)
        assert not [p for p in node.publishers if p.topic_name == interfaces.SAFETY_TOPIC]
        assert node.trigger_activate() == TransitionCallbackReturn.SUCCESS
        assert len(subscribers(node, interfaces.TRUTH_ROE_TOPIC)) == 1
        # cleanup -> configure again (parameters already declared)
        assert node.trigger_deactivate() == TransitionCallbackReturn.SUCCESS
        assert node.trigger_cleanup() == TransitionCallbackReturn.SUCCESS and label(node) == "unconfigured"
        assert node.trigger_configure() == TransitionCallbackReturn.SUCCESS and label(node) == "inactive"
    finally:
        node.destroy_node()


def test_parameter_error_fails_configure_or_construction(context):
    context("autostart:=false", "k:=2", "p_mode:=fixed")
    node = PlannerNode()
    try:
        assert node.trigger_configure() == TransitionCallbackReturn.FAILURE
        assert label(node) == "unconfigured"
        assert isinstance(node.transition_error, ParameterError)
        assert "parameter 'k' must be an odd integer in [1, 99], got 2" in str(node.transition_error)
    finally:
        node.destroy_node()
    context("k:=2", "p_mode:=fixed")  # autostart: the constructor raises (main exits 2)
    with pytest.raises(ParameterError, match="parameter 'k'"):
        PlannerNode()


def _state(node, name):
    """The node's lifecycle state id, None when it did not answer (yet)."""
    client = node.create_client(GetState, f"/{name}/get_state")
    try:
        if not client.wait_for_service(timeout_sec=2.0):
            return None
        future = client.call_async(GetState.Request())
        rclpy.spin_until_future_complete(node, future, timeout_sec=3.0)
        return future.result().current_state.id if future.done() else None
    finally:
        node.destroy_client(client)


@pytest.mark.dds
def test_lifecycle_manager_answers_while_it_waits_and_exits_0_on_sigint(ros_context):
    """Waiting for a node that never comes, the manager still serves its parameter services (what ``ros2 param list
    /lifecycle_manager`` asks); SIGINT then ends it with status 0."""
    manager = start_node("lifecycle_manager", "-p", "node_names:=['nobody_here']", "-p", "timeout:=120.0")
    probe = rclpy.create_node("manager_probe")
    names = None
    try:
        client = probe.create_client(ListParameters, "/lifecycle_manager/list_parameters")
        deadline = time.monotonic() + 60.0
        while names is None and time.monotonic() < deadline and manager.poll() is None:
            if not client.wait_for_service(timeout_sec=2.0):
                continue
            future = client.call_async(ListParameters.Request())
            rclpy.spin_until_future_complete(probe, future, timeout_sec=5.0)
            if future.done():
                names = set(future.result().result.names)
    finally:
        probe.destroy_node()
        code, out = stop_node(manager)
    assert names is not None and {"node_names", "timeout", "use_sim_time"} <= names, (names, out)
    assert code == 0, out
    assert "Traceback" not in out and "managed nodes active" not in out, out


@pytest.mark.dds
def test_lifecycle_manager_starts_the_nodes_in_order(ros_context):
    monitor = start_node("safety_monitor", "-p", "autostart:=false", "-p", "use_sim_time:=false")
    planner = start_node("planner", "-p", "autostart:=false", "-p", "use_sim_time:=false", *FAST_PLANNER)
    manager = start_node("lifecycle_manager", "-p", "node_names:=['safety_monitor', 'planner']")
    probe = rclpy.create_node("managed_probe")
    try:
        active = State.PRIMARY_STATE_ACTIVE
        deadline = time.monotonic() + 90.0
        while True:  # a query may go unanswered under load (None): ask again until both say active, or time is up
            states = [_state(probe, "planner"), _state(probe, "safety_monitor")]
            if states == [active] * 2 or time.monotonic() > deadline:
                break
            time.sleep(0.5)
    finally:
        probe.destroy_node()
        code_m, out_m = stop_node(manager)
        outs = [stop_node(p) for p in (monitor, planner)]
    assert states == [State.PRIMARY_STATE_ACTIVE] * 2, (states, out_m, outs)
    assert code_m == 0, out_m
    order = [line for line in out_m.splitlines() if ": configure ok" in line or ": activate ok" in line]
    assert [line.split("]: ")[-1] for line in order] == [
        "/safety_monitor: configure ok", "/planner: configure ok", "/safety_monitor: activate ok",
        "/planner: activate ok"]
    assert "managed nodes active: safety_monitor, planner" in out_m
    assert all(code == 0 for code, _ in outs), outs


@pytest.mark.dds
def test_lifecycle_manager_stops_at_a_failed_configure():
    planner = start_node("planner", "-p", "autostart:=false", "-p", "use_sim_time:=false", "-p", "k:=4",
                         *FAST_PLANNER)
    manager = start_node("lifecycle_manager", "-p", "node_names:=['planner']")
    code, out = wait_exit(manager, timeout=60.0)
    _, out_p = stop_node(planner)
    assert code == 1, out
    assert "configure of /planner failed (state now 'unconfigured'" in out
    assert "configure failed: parameter 'k' must be an odd integer in [1, 99], got 4" in out_p


def _change_state(spin, client, transition_id, transition_label=""):
    """The ChangeState response's success, None when there was no answer; ``spin(future)`` spins until it is done."""
    request = ChangeState.Request()
    request.transition.id, request.transition.label = transition_id, transition_label
    future = client.call_async(request)
    spin(future)
    return future.result().success if future.done() else None


def test_an_invalid_transition_is_refused_and_the_node_goes_on(context, capfd):
    """rclpy alone raises RCLError ('Transition is not registered') inside the service callback: the executor, and
    with it the node's process, ends. The managed node refuses the request (success false, a WARN) instead."""
    context("use_sim_time:=false")
    node = SafetyMonitorNode()  # autostart: active
    probe = rclpy.create_node("change_state_probe")
    executor = rclpy.executors.SingleThreadedExecutor()
    executor.add_node(node)
    executor.add_node(probe)

    def spin(future):
        executor.spin_until_future_complete(future, timeout_sec=10.0)
    try:
        client = probe.create_client(ChangeState, "/safety_monitor/change_state")
        assert client.wait_for_service(timeout_sec=10.0)
        for request in [(Transition.TRANSITION_CONFIGURE, ""), (0, "configure"), (0, "activate"),
                        (Transition.TRANSITION_UNCONFIGURED_SHUTDOWN, ""), (99, ""), (0, "")]:
            assert _change_state(spin, client, *request) is False, request
            assert label(node) == "active" and len(subscribers(node, interfaces.TRUTH_ROE_TOPIC)) == 1
        # the node goes on: valid transitions still work, and an invalid one from 'inactive' is refused too
        assert _change_state(spin, client, Transition.TRANSITION_DEACTIVATE) is True
        assert label(node) == "inactive"
        assert _change_state(spin, client, 0, "deactivate") is False and label(node) == "inactive"
        assert _change_state(spin, client, 0, "activate") is True and label(node) == "active"
    finally:
        executor.shutdown()
        probe.destroy_node()
        node.destroy_node()
    err = capfd.readouterr().err
    assert "transition 'configure' [1] refused: not valid from state 'active' (valid: deactivate [4], shutdown [7])" \
        in err, err
    assert "transition 'deactivate' refused: not valid from state 'inactive'" in err, err


MANAGED_ARGS = {"safety_monitor": (), "planner": FAST_PLANNER, "radar_od": (), "ic_planner": ()}


def test_lifecycle_manager_adopts_active_nodes_that_refuse_invalid_transitions():
    """Every managed node started with autostart (active), the manager beside them: it reads each node's state and
    adopts it (no configure of an active node, which killed it); then invalid transitions sent from outside are
    refused; every node still runs and answers, and the manager exits 0 on SIGINT."""
    nodes = {name: start_node(name, "-p", "use_sim_time:=false", *args) for name, args in MANAGED_ARGS.items()}
    rclpy.init()
    probe = rclpy.create_node("adopt_probe")
    reports = []
    probe.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC,
                              lambda m: reports.extend(s.message for s in m.status
                                                       if s.name == "roe_sep/lifecycle_manager"),
                              interfaces.DIAGNOSTICS)
    manager = None
    active = State.PRIMARY_STATE_ACTIVE
    try:
        deadline = time.monotonic() + 120.0
        while (states := {n: _state(probe, n) for n in nodes}) != dict.fromkeys(nodes, active):
            assert time.monotonic() < deadline, states
            time.sleep(0.5)
        manager = start_node("lifecycle_manager", "-p", f"node_names:={list(nodes)!r}")
        assert spin_until(probe, lambda: reports, timeout=120.0), "no status of the lifecycle_manager"
        refused = {}

        def spin(future):
            rclpy.spin_until_future_complete(probe, future, timeout_sec=10.0)
        for name in nodes:
            client = probe.create_client(ChangeState, f"/{name}/change_state")
            assert client.wait_for_service(timeout_sec=10.0)
            refused[name] = [_change_state(spin, client, *request)
                             for request in [(Transition.TRANSITION_CONFIGURE, ""), (0, "cleanup")]]
            probe.destroy_client(client)
        states = {n: _state(probe, n) for n in nodes}
    finally:
        probe.destroy_node()
        rclpy.try_shutdown()
        code_m, out_m = stop_node(manager) if manager is not None else (None, "")
        outs = {name: stop_node(proc) for name, proc in nodes.items()}
    assert reports[0] == f"managed nodes active: {', '.join(nodes)}", (reports, out_m)
    assert code_m == 0, out_m
    for name in nodes:
        assert f"/{name}: configure already done (state 'active'), adopted" in out_m, out_m
        assert f"/{name}: activate already done (state 'active'), adopted" in out_m, out_m
    assert ": configure ok" not in out_m and ": activate ok" not in out_m, out_m
    assert refused == dict.fromkeys(nodes, [False, False]), (refused, outs)
    assert states == dict.fromkeys(nodes, active), (states, outs)
    for name, (code, out) in outs.items():
        assert code == 0 and "Traceback" not in out and "RCLError" not in out, (name, out)
        assert "transition 'configure' [1] refused: not valid from state 'active'" in out, (name, out)
