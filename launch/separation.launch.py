"""The whole default scenario, as ``roe-sep run`` runs it: ``ros2 launch roe_sep separation.launch.py``.

The node graph and its parameter file come from :mod:`roe_sep.graph` (the one description shared with
``roe-sep run``): the same nodes in the same order (the recorder first, 1 s before the others, the simulator last),
one generated ``OUTPUT/params.yaml``. When the simulator reports the scenario complete (or aborted) on
``/diagnostics``, or a node exits early, or ``timeout`` passes, the launch shuts down; once the recorder has closed
the bag, ``OUTPUT/report.json`` is written from it (:func:`roe_sep.run.report_from_bag`), as ``roe-sep run`` does.

Arguments (``ros2 launch roe_sep separation.launch.py --show-args``): ``scenario`` (scenario YAML, '' = the
embedded default), ``params`` (a ROS params YAML of overrides), ``seed``, ``duration`` [s], ``real_time_factor``
(pacing; '' = lockstep as fast as possible), ``output`` (run directory, default ``out/launch``), ``managed``
(``true``: the planning nodes wait unconfigured and ``lifecycle_manager`` configures then activates them in
order), ``timeout`` [s of wall time].
"""

import os
import time
from pathlib import Path

import yaml
from launch.actions import (
    DeclareLaunchArgument,
    EmitEvent,
    LogInfo,
    OpaqueFunction,
    RegisterEventHandler,
    TimerAction,
)
from launch.event_handlers import OnProcessExit, OnShutdown
from launch.events import Shutdown
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription

ARGUMENTS = (
    ("scenario", "", "scenario YAML ('' = the embedded default scenario)"),
    ("params", "", "ROS params YAML of overrides, {node: {ros__parameters: {...}}} ('' = none)"),
    ("seed", "", "run seed: the simulator's, and the radar noise's stream of it ('' = the nodes' defaults)"),
    ("duration", "", "simulated duration [s] ('' = the simulator's default, 3.25 d)"),
    ("real_time_factor", "", "pace sim time at this multiple of wall time ('' = lockstep, as fast as possible)"),
    ("output", "out/launch", "run directory: bag/, ccsds/, params.yaml, report.json (its bag/ must not exist)"),
    ("managed", "false", "true: lifecycle_manager configures, then activates, the planning nodes in order"),
    ("timeout", "1800", "wall-time limit [s]"),
)


def _arg(context, name, cast=str):
    value = LaunchConfiguration(name).perform(context).strip()
    return cast(value) if value else None


def _graph(context):
    """The run's actions: the parameter file, the nodes in order, the end of run and the report."""
    from roe_sep import interfaces
    from roe_sep.graph import dds_environment, graph_nodes, parameters, run_overrides
    from roe_sep.nodes.sim import DEFAULT_DURATION

    out = Path(_arg(context, "output")).resolve()
    bag_dir = out / "bag"
    if bag_dir.exists():
        raise RuntimeError(f"output bag {bag_dir} exists already: choose another output:= or remove it")
    out.mkdir(parents=True, exist_ok=True)
    managed = _arg(context, "managed").lower() in ("true", "1", "yes")
    overrides = run_overrides(_arg(context, "params"), _arg(context, "duration", float), _arg(context, "seed", int),
                              _arg(context, "real_time_factor", float), managed=managed)
    params_file = out / "params.yaml"
    params_file.write_text(yaml.safe_dump(parameters(_arg(context, "scenario"), bag_dir, overrides),
                                          sort_keys=False))
    duration = float(overrides["sim"].get("duration", DEFAULT_DURATION))
    timeout = _arg(context, "timeout", float) or 1800.0

    state = {"end": None, "codes": {}, "start": time.monotonic()}
    # up to 20 s from SIGINT to SIGTERM, as roe-sep run waits (the recorder closes the bag, ground_bridge writes
    # its final CCSDS set; launch's default of 5 s is too short on a loaded machine)
    dds_env = dds_environment(out)  # the nodes' DDS profile (out/fastdds.xml), as roe-sep run gives it
    nodes = {name: Node(package="roe_sep", executable=name, name=name, output="screen", sigterm_timeout="20",
                        parameters=[str(params_file)], additional_env=dds_env)
             for name in graph_nodes(managed=managed)}

    def shutdown(reason):
        """End the launch, once: every Shutdown event shuts launch_ros's ROS adapter down (its OnShutdown handler),
        and a second one raises 'Cannot shutdown a ROS adapter that is not running' (launch then exits 1)."""
        if state["end"] is not None:
            return None
        state["end"] = reason
        return [EmitEvent(event=Shutdown(reason=reason))]

    def on_shutdown(event, ctx):  # any Shutdown, also launch's own on Ctrl-C: the nodes' exits that follow are no
        if state["end"] is None:  # early exits, and emit no second Shutdown
            state["end"] = f"launch shut down ({event.reason})"

    def on_status(array):  # in the launch's ROS node thread
        for s in array.status:
            if s.name == "roe_sep/sim" and (s.message == "scenario complete"
                                            or s.message.startswith("scenario aborted")):
                if state["end"] is None:
                    state["end"] = s.message
                    loop = context.asyncio_loop  # the last messages reach the recorder (0.5 s, as roe-sep run)
                    loop.call_soon_threadsafe(loop.call_later, 0.5, context.emit_event_sync,
                                              Shutdown(reason=f"roe_sep: {s.message}"))

    from diagnostic_msgs.msg import DiagnosticArray
    from launch_ros.ros_adapters import get_ros_node

    get_ros_node(context).create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, on_status,
                                              interfaces.DIAGNOSTICS)

    def on_exit(name):
        def handler(event, ctx):
            state["codes"][name] = event.returncode
            if name == "recorder":
                return write_report()
            how = f"killed by signal {-event.returncode}" if event.returncode < 0 else f"exit status {event.returncode}"
            return shutdown(f"{name} exited early ({how})")
        return handler

    def write_report():
        from roe_sep.run import report_from_bag, write_report

        time.sleep(0.5)
        report = report_from_bag(bag_dir, out, duration, state["codes"].get("recorder"))
        reached = state["end"] == "scenario complete"
        report["run"].update({"completed": reached, "reason": state["end"] or "launch shut down",
                              "exit_codes": state["codes"], "params_file": str(params_file),
                              "launch": "separation.launch.py", "wall_time": time.monotonic() - state["start"]})
        if not reached and report.get("safe") is not False:
            report["safe"] = None
        write_report(out / "report.json", report)
        criteria = report.get("criteria") or {}
        return [LogInfo(msg=f"report {out / 'report.json'}: safe = {report.get('safe')}, "
                            f"{sum(1 for c in criteria.values() if c is True)} of {len(criteria)} criteria met, "
                            f"carrier dv {report.get('dv_total')} m/s ({state['end']})")]

    actions = [RegisterEventHandler(OnShutdown(on_shutdown=on_shutdown))]
    actions += [RegisterEventHandler(OnProcessExit(target_action=node, on_exit=on_exit(name)))
                for name, node in nodes.items()]
    first, *rest = nodes.values()
    actions += [first, TimerAction(period=1.0, actions=rest),  # the recorder discovers the graph first
                TimerAction(period=timeout, actions=[OpaqueFunction(
                    function=lambda ctx: shutdown(f"wall-time limit of {timeout:g} s reached"))])]
    return actions


def generate_launch_description():
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")
    return LaunchDescription([DeclareLaunchArgument(name, default_value=default, description=text)
                              for name, default, text in ARGUMENTS] + [OpaqueFunction(function=_graph)])
