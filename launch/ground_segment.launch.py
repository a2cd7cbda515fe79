"""Planner and safety monitor alone, for a ground segment that provides its own ejection events:
``ros2 launch roe_sep ground_segment.launch.py``.

The two nodes are started managed: unconfigured, then ``lifecycle_manager`` configures and activates them in order
(safety_monitor, planner), the way nav2 starts its servers; a parameter error fails ``configure`` with the
parameter's name in the node's log and the manager exits with status 1. Their parameters come from the same
:func:`roe_sep.graph.parameters` as the full run (``OUTPUT/params.yaml``). Publish a
``roe_sep_msgs/EjectionEvent`` on ``/separation/ejection`` (RELIABLE, TRANSIENT_LOCAL) and read the drift-stop
plan on ``/separation/drift_stop_plan`` and its check on ``/safety/plan_check``; the ``/separation/plan`` service
designs a separation on request.

Arguments: ``scenario``, ``params`` (as separation.launch.py), ``use_sim_time`` (default false: wall-clock time),
``managed`` (default true; false: each node autostarts), ``output`` (where params.yaml is written).
"""

from pathlib import Path

import yaml
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription

NODES = ("safety_monitor", "planner")  # in start-up order
ARGUMENTS = (
    ("scenario", "", "scenario YAML ('' = the embedded default scenario)"),
    ("params", "", "ROS params YAML of overrides, {node: {ros__parameters: {...}}} ('' = none)"),
    ("use_sim_time", "false", "true: follow /clock"),
    ("managed", "true", "true: lifecycle_manager configures, then activates, the nodes in order"),
    ("output", "out/ground_segment", "directory of the generated params.yaml"),
)


def _nodes(context):
    from roe_sep.graph import parameters, run_overrides

    def arg(name):
        return LaunchConfiguration(name).perform(context).strip()

    managed = arg("managed").lower() in ("true", "1", "yes")
    overrides = run_overrides(arg("params") or None, managed=managed)
    overrides.setdefault("/**", {})["use_sim_time"] = arg("use_sim_time").lower() in ("true", "1", "yes")
    if managed:
        overrides["lifecycle_manager"]["node_names"] = list(NODES)
    out = Path(arg("output")).resolve()
    out.mkdir(parents=True, exist_ok=True)
    params = parameters(arg("scenario") or None, out / "bag", overrides)
    params = {k: v for k, v in params.items() if k in ("/**", *NODES, "lifecycle_manager")}
    params_file = out / "params.yaml"
    params_file.write_text(yaml.safe_dump(params, sort_keys=False))
    names = NODES + (("lifecycle_manager",) if managed else ())
    return [Node(package="roe_sep", executable=n, name=n, output="screen", sigterm_timeout="20",
                 parameters=[str(params_file)])
            for n in names]


def generate_launch_description():
    return LaunchDescription([DeclareLaunchArgument(name, default_value=default, description=text)
                              for name, default, text in ARGUMENTS] + [OpaqueFunction(function=_nodes)])
