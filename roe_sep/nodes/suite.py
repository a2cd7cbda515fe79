"""suite: several roe_sep nodes in one process, on one executor (ROS 2 manual composition).

``ros2 run roe_sep suite recorder ground_bridge ... sim --ros-args --params-file F`` constructs the named nodes, in
the order given, in one process and spins them on one executor. They still talk over DDS (Fast DDS delivers
within the process), so the graph, the topics, ``ros2 node list`` and the bag are those of one process per node.
``roe-sep run`` starts the default scenario this way unless ``--process-per-node`` (docs/run.md); under
lockstep both give the same plans, maneuvers and report (test_lockstep checks it).

Why: a run wakes each node about 6,000 times (the truth every 60 s of sim time, the lockstep steps). With a process
per node every wake rebuilds that node's wait set and every process pays its own start-up (Python, NumPy, SciPy,
rclpy, about 1.2 CPU-s each); bench/bench_nodes.py measures both layouts side by side.

Executors (``--executor``, before ``--ros-args``):

* ``events`` (default): rclpy's ``EventsExecutor`` (``rclpy.experimental``, Jazzy 7.1.6): an event queue in C++,
  no wait set rebuilt per callback. It cannot hand message info to a callback, so no node of the suite asks for
  it (the recorder logs ``publish_time`` = ``log_time``).
* ``single_threaded``: rclpy's ``SingleThreadedExecutor``, the reference.

Signals, the drain of messages already delivered at shutdown and exit codes: :mod:`roe_sep.nodes.spin`, shared
with the nodes' own ``main()``. A node that cannot start (a bad parameter) stops the suite with exit code 2 and
names the node; an exception escaping a callback stops it with exit code 1 and the traceback in the log. Every
node catches what a bad message can raise, so neither happens on bad input (test_faults).
"""

import importlib
import sys

from rclpy.executors import SingleThreadedExecutor
from rclpy.utilities import remove_ros_args

from ..graph import EXECUTORS
from .params import help_requested
from .spin import leave, serve

NODE_CLASSES = {
    "recorder": "recorder:RecorderNode",
    "ground_bridge": "ground_bridge:GroundBridgeNode",
    "safety_monitor": "safety_monitor:SafetyMonitorNode",
    "planner": "planner:PlannerNode",
    "radar": "radar:RadarNode",
    "radar_od": "radar_od:RadarODNode",
    "ic_planner": "ic_planner:IcPlannerNode",
    "ejector": "ejector:EjectorNode",
    "foxglove_view": "foxglove_view:FoxgloveViewNode",
    "analysis_server": "analysis_server:AnalysisServer",
    "sim": "sim:SimNode",
}
USAGE = (f"usage: suite [--executor {{{','.join(EXECUTORS)}}}] NODE [NODE ...] [--ros-args ...]; "
         f"nodes: {', '.join(NODE_CLASSES)}")


def node_class(name: str):
    """The node class of a node name (:data:`NODE_CLASSES`)."""
    module, cls = NODE_CLASSES[name].split(":")
    return getattr(importlib.import_module(f"{__package__}.{module}"), cls)


def parse(argv):
    """(node names, executor name) from the non-ROS arguments; ValueError with the usage on a bad one."""
    args = list(argv)
    executor = "events"
    if "--executor" in args:
        k = args.index("--executor")
        if k + 1 >= len(args):
            raise ValueError(f"--executor needs a value; {USAGE}")
        executor = args[k + 1]
        del args[k:k + 2]
    if executor not in EXECUTORS:
        raise ValueError(f"unknown executor {executor!r}; {USAGE}")
    unknown = [n for n in args if n not in NODE_CLASSES]
    if unknown or not args:
        raise ValueError(f"unknown node(s) {unknown}; {USAGE}" if unknown else f"no node named; {USAGE}")
    if len(set(args)) != len(args):
        raise ValueError(f"a node named twice in {args}; {USAGE}")
    return args, executor


def make_executor(name: str):
    if name == "events":
        from rclpy.experimental import EventsExecutor

        return EventsExecutor()
    return SingleThreadedExecutor()


def main(args=None) -> int:
    argv = sys.argv if args is None else list(args)
    if help_requested(argv):
        print(f"{USAGE}\n\n{__doc__.splitlines()[0]}\n\nEach node takes its own parameters ({{NODE}} --help, "
              f"docs/parameters.md); a --params-file names them per node.")
        return 0
    try:
        names, executor_name = parse(remove_ros_args(argv)[1:])
    except ValueError as exc:
        print(f"[ERROR] {exc}", file=sys.stderr)
        return 2
    return leave(serve([(name, lambda name=name: node_class(name)()) for name in names], argv,
                       make_executor=lambda: make_executor(executor_name), leaving=True))


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
