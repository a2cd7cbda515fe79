"""The node graph of a run, in one place: which nodes, which of them take part in lockstep, which subscribers the
simulator waits for before its clock starts, and the run's ROS parameter file.

``roe-sep run`` (:mod:`roe_sep.run`), the composed suite process (:mod:`roe_sep.nodes.suite`) and the launch files
(``share/roe_sep/launch``) all start the graph described here, so they start the same nodes with the same
parameters.
"""

import os
from pathlib import Path

import yaml

NODES = ("recorder", "ground_bridge", "safety_monitor", "planner", "radar", "radar_od", "ic_planner", "ejector",
         "sim")
OPTIONAL_NODES = ("foxglove_view",)  # started on request: roe-sep run --foxglove [PORT]
MANAGED = ("safety_monitor", "planner", "radar", "radar_od", "ic_planner")
"""The managed (lifecycle) nodes, in start-up order: configured, then activated, by ``lifecycle_manager`` when the
graph is started managed (``ros2 launch roe_sep separation.launch.py managed:=true``), else each autostarts."""
PARTICIPANTS = ("ejector", "planner", "radar", "radar_od", "ic_planner", "safety_monitor")
"""The lockstep participants: every node that reacts to the simulation (recorder and ground_bridge listen)."""
# subscribers of each topic the simulator waits for before its clock starts (so that nobody misses a message)
SUBSCRIBERS = {
    "/sim/truth/roe": ("ejector", "radar", "radar_od", "safety_monitor", "recorder", "ground_bridge"),
    "/sim/truth/rtn": ("recorder",),
    "/sim/camera/bearing": ("planner", "recorder"),
    "/sim/camera/pose": ("planner", "recorder"),
    "/sim/executed_maneuvers": ("planner", "radar", "radar_od", "ic_planner", "safety_monitor", "recorder",
                                "ground_bridge"),
    "/separation/ejection": ("ejector", "planner", "ic_planner", "radar_od", "safety_monitor", "sim", "recorder",
                             "ground_bridge"),
    "/separation/drift_stop_plan": ("ic_planner", "safety_monitor", "sim", "recorder", "ground_bridge"),
    "/acquisition/plan": ("ic_planner", "safety_monitor", "sim", "recorder", "ground_bridge"),
    "/od/estimate": ("ic_planner", "safety_monitor", "sim", "recorder", "ground_bridge"),
    "/radar/measurements": ("radar_od", "recorder", "ground_bridge"),
    "/radar/passes": ("radar_od", "recorder"),
    "/radar/carrier_ranges": ("radar_od", "recorder"),
    "/safety/status": ("recorder",),
    "/safety/plan_check": ("sim", "recorder", "ground_bridge"),
}


# the default process layout (roe-sep run without --process-per-node): two processes, each its nodes on one executor
# (roe_sep.nodes.suite). The closed loop (the simulator and the lockstep participants) in one; the nodes that only
# listen (recorder, ground_bridge, the Foxglove view) in the other, off the loop's critical path.
LISTENERS = ("recorder", "ground_bridge", "foxglove_view")
SUITES = ("listeners", "loop")
EXECUTORS = ("events", "single_threaded")  # rclpy's EventsExecutor (default), SingleThreadedExecutor


DDS_HEARTBEAT_PERIOD = 0.1
"""s (wall): how often a reliable writer of a run's processes announces what it has sent when a reader has not yet
acknowledged all of it (Fast DDS's default: 3 s). A reader that missed messages (a listeners' process descheduled
on a loaded machine overflows its shared-memory port) asks for them again only when such an announcement comes; a
writer whose history is not full sends it no sooner, and a run of a few seconds of wall time then ends with the
gap unrepaired and the messages behind it never delivered (the bag lost every /clock after a 0.5 s stall)."""
DDS_PROFILE_ENV = ("FASTRTPS_DEFAULT_PROFILES_FILE", "FASTDDS_DEFAULT_PROFILES_FILE")  # a user's own profile wins


def dds_profile() -> str:
    """The Fast DDS XML profile of a run's node processes: the default writer profile with
    :data:`DDS_HEARTBEAT_PERIOD`; every QoS policy a ROS publisher sets stays the ROS one (rmw_fastrtps sets them
    over the default profile)."""
    sec = int(DDS_HEARTBEAT_PERIOD)
    nanosec = int(round((DDS_HEARTBEAT_PERIOD - sec) * 1e9))
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<!-- written by roe_sep (roe_sep.graph.dds_profile): the run\'s processes load it as their default -->\n'
            '<dds xmlns="http://www.eprosima.com/XMLSchemas/fastRTPS_Profiles">\n'
            '  <profiles>\n'
            '    <data_writer profile_name="roe_sep_writer" is_default_profile="true">\n'
            f'      <times><heartbeatPeriod><sec>{sec}</sec><nanosec>{nanosec}</nanosec></heartbeatPeriod></times>\n'
            '    </data_writer>\n'
            '  </profiles>\n'
            '</dds>\n')


def dds_environment(out, env=None) -> dict:
    """The environment entries that give a run's node processes :func:`dds_profile` (written to
    ``out/fastdds.xml``), or none when ``env`` (default: this process's) names a Fast DDS profile of its own or
    another RMW implementation."""
    env = os.environ if env is None else env
    if any(env.get(k) for k in DDS_PROFILE_ENV) or env.get("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp") not in (
            "rmw_fastrtps_cpp", "rmw_fastrtps_dynamic_cpp"):
        return {}
    path = Path(out) / "fastdds.xml"
    path.write_text(dds_profile(), encoding="utf-8")
    return {DDS_PROFILE_ENV[0]: str(path.resolve())}


def suites(nodes):
    """{suite process name: its nodes, in start order} of a run's ``nodes`` (:data:`SUITES`)."""
    return {"listeners": [n for n in nodes if n in LISTENERS], "loop": [n for n in nodes if n not in LISTENERS]}


RADAR_STREAM = 1  # the radar noise's stream of a run seed (the simulator uses the seed itself)


def radar_seed(seed: int) -> int:
    """The radar noise seed of a run seed: a 32-bit word of ``SeedSequence([seed, 1])``, a stream independent of
    the simulator's ``default_rng(seed)`` (the same integer in both would correlate the first draws). ``--seed``
    disperses the radar noise too, so a campaign's run k is reproduced by ``roe-sep run --seed S+k`` alone."""
    import numpy as np

    return int(np.random.SeedSequence([int(seed), RADAR_STREAM]).generate_state(1, np.uint32)[0])


def wait_for(nodes) -> list[str]:
    """The simulator's ``wait_for`` for a run of ``nodes``: 'topic=count' of the subscribers among them
    (:data:`SUBSCRIBERS`), so that its clock starts once each of them reads what it needs."""
    return [f"{topic}={sum(n in nodes for n in subs)}" for topic, subs in SUBSCRIBERS.items()]


def parameters(config, bag_dir, overrides, nodes=NODES):
    """The run's ROS parameter file content: shared values for every node, then per-node values. ``nodes``: the
    nodes the run starts (:func:`graph_nodes`); the simulator waits for the subscribers among them only."""
    shared = {"use_sim_time": True, "scenario_file": str(Path(config).resolve()) if config else ""}
    per_node = {
        # start the clock once every node is up (the planner after its start-up Monte Carlo) and subscribed to what
        # it reads, the recorder to every topic; then run in lockstep with every reacting node
        "sim": {"use_sim_time": False,
                "wait_for": wait_for(nodes),
                "lockstep_participants": list(PARTICIPANTS)},
        "recorder": {"output": str(bag_dir)},
        "ground_bridge": {"output_dir": str(Path(bag_dir).parent / "ccsds")},  # CCSDS files of the run (issue 18)
    }
    if "ground_bridge" not in nodes:  # no keeper of the decision records (a campaign's run): nothing to read back
        for node in ("planner", "ic_planner"):
            per_node[node] = {"recover_timeout": 0.0}
    for node, values in (overrides or {}).items():
        if node not in NODES + OPTIONAL_NODES + ("lifecycle_manager",) and node != "/**":
            raise ValueError(f"--params: unknown node {node!r}; nodes: {list(NODES)}")
        target = shared if node == "/**" else per_node.setdefault(node, {})
        target.update(values)
    out = {"/**": {"ros__parameters": shared}}
    out.update({node: {"ros__parameters": values} for node, values in per_node.items()})
    return out


CONTINGENCY_NODES = ("sim", "radar")  # the nodes that inject a contingency: the truth and the radar


def contingency_overrides(overrides, contingency):
    """``overrides`` with the node parameter ``contingency`` of :data:`CONTINGENCY_NODES` set to ``contingency`` (a
    name, 'none'); unchanged for None (the scenario's block decides)."""
    if contingency is not None:
        for node in CONTINGENCY_NODES:
            overrides.setdefault(node, {})["contingency"] = str(contingency)
    return overrides


def run_overrides(params=None, duration=None, seed=None, real_time_factor=None, foxglove=None, *, managed=False,
                  contingency=None):
    """The per-node parameter overrides of a run's options (``roe-sep run`` and the launch files' arguments):
    ``params`` (a params YAML, :func:`load_overrides`), the sim ``duration`` [s], the run ``seed`` (the simulator's,
    and the radar noise's :func:`radar_seed` unless the params file sets it), ``real_time_factor``, the
    ``foxglove`` port, ``managed`` (the :data:`MANAGED` nodes wait unconfigured for ``lifecycle_manager``,
    which then starts them in order) and ``contingency`` (:func:`contingency_overrides`)."""
    overrides = contingency_overrides(load_overrides(params), contingency)
    sim = overrides.setdefault("sim", {})
    if duration is not None:
        sim["duration"] = float(duration)
    if seed is not None:
        sim["seed"] = int(seed)
        overrides.setdefault("radar", {}).setdefault("seed", radar_seed(seed))
    if real_time_factor is not None:
        sim["real_time_factor"] = float(real_time_factor)
    if foxglove is not None:
        overrides.setdefault("foxglove_view", {})["port"] = int(foxglove)
    if managed:
        for node in MANAGED:
            overrides.setdefault(node, {})["autostart"] = False
        overrides.setdefault("lifecycle_manager", {})["node_names"] = list(MANAGED)
    return overrides


def graph_nodes(foxglove=False, managed=False, ground_bridge=True):
    """The nodes of a run, in start order (the recorder first, the simulator last: it owns ``/clock``); with
    ``foxglove`` the view before the simulator, ``managed`` the lifecycle manager after the managed nodes; without
    ``ground_bridge`` no CCSDS export (a campaign's runs unless asked: it only listens, the loop is the same)."""
    nodes = [n for n in NODES if ground_bridge or n != "ground_bridge"]
    if foxglove:
        nodes[-1:-1] = list(OPTIONAL_NODES)
    if managed:
        nodes.insert(max(nodes.index(n) for n in MANAGED) + 1, "lifecycle_manager")
    return tuple(nodes)


def load_overrides(path):
    """A params YAML in the ROS layout ``{node: {ros__parameters: {...}}}``."""
    if not path:
        return {}
    with open(path, encoding="utf-8") as fh:
        data = yaml.safe_load(fh) or {}
    try:
        return {node: dict(v["ros__parameters"]) for node, v in data.items()}
    except (TypeError, KeyError) as exc:
        raise ValueError(f"--params {path}: expected {{node: {{ros__parameters: {{...}}}}}}") from exc
