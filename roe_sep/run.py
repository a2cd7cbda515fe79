"""``roe-sep run``: the default scenario end to end.

Starts the recorder, ground_bridge (CCSDS files in OUT/ccsds), safety_monitor, planner, radar, radar_od, ic_planner,
ejector (and foxglove_view with ``--foxglove``) and sim (last: it owns ``/clock``) with one generated parameter
file (:mod:`roe_sep.graph`): by default in two processes, the closed loop and the listeners, each on one executor
(:mod:`roe_sep.nodes.suite`); with ``process_per_node`` every node its own process as a deployment runs them; with
``in_process`` every node in this process (:func:`run_in_process`, a campaign's runs).
Waits until the simulator reports the scenario complete, stops the nodes with SIGINT (the recorder last, so the
bag closes cleanly) and writes ``report.json`` from the recorded bag.
"""

import collections
import os
import signal
import struct
import subprocess
import sys
import time
from pathlib import Path

import yaml

from .children import spawn
from .graph import (  # noqa: F401 (re-exported)
    NODES,
    OPTIONAL_NODES,
    PARTICIPANTS,
    RADAR_STREAM,
    SUBSCRIBERS,
    SUITES,
    dds_environment,
    graph_nodes,
    load_overrides,
    parameters,
    radar_seed,
    run_overrides,
    suites,
)
from .nodes.scenario_end import final_status_of
from .stamps import time_to_sec


def ros_environment(domain_id=None):
    """This process's environment with DDS kept on loopback and a domain id of its own."""
    env = dict(os.environ)
    env["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    env.pop("ROS_LOCALHOST_ONLY", None)
    env.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    if domain_id is not None:
        env["ROS_DOMAIN_ID"] = str(domain_id)
    else:
        env.setdefault("ROS_DOMAIN_ID", str(os.getpid() % 100 + 1))
    env["PYTHONUNBUFFERED"] = "1"
    return env




class Deployment:
    """The node processes of one run (one per node, or one ``suite``), their logs, and an orderly shutdown."""

    def __init__(self, out: Path, params_file: Path, env):
        self.out, self.params_file, self.env = out, params_file, env
        self.procs = {}
        self.interrupted = set()  # processes sent SIGINT (once: a second one cuts their shutdown drain short)
        (out / "logs").mkdir(parents=True, exist_ok=True)

    def start(self, node):
        """One node in a process of its own (log ``logs/<node>.log``)."""
        self._spawn(node, [f"roe_sep.nodes.{node}"])

    def start_suite(self, name, nodes, executor="events"):
        """``nodes`` in one process on one executor (:mod:`roe_sep.nodes.suite`; log ``logs/<name>.log``)."""
        self._spawn(name, ["roe_sep.nodes.suite", "--executor", executor, *nodes])

    def _spawn(self, name, module_args):
        log = open(self.out / "logs" / f"{name}.log", "w", encoding="utf-8")
        cmd = [sys.executable, "-m", *module_args, "--ros-args", "--params-file", str(self.params_file)]
        self.procs[name] = (spawn(cmd, env=self.env, stdout=log, stderr=subprocess.STDOUT), log)

    def dead(self):
        return [n for n, (p, _) in self.procs.items() if p.poll() is not None]

    def last_line(self, node):
        """The last non-empty line of a node's log (why it stopped, mostly)."""
        try:
            lines = (self.out / "logs" / f"{node}.log").read_text(encoding="utf-8", errors="replace").splitlines()
        except OSError:
            return ""
        return next((ln.strip() for ln in reversed(lines) if ln.strip()), "")

    def death(self, nodes):
        """One line naming each dead node, its exit status and its last log line."""
        parts = []
        for n in nodes:
            code = self.procs[n][0].poll()
            how = f"killed by signal {-code}" if code is not None and code < 0 else f"exit status {code}"
            parts.append(f"{n} exited early ({how}); last log line: {self.last_line(n) or '(none)'}")
        return "; ".join(parts)

    def interrupt(self, nodes):
        """SIGINT to each of ``nodes`` still running that has not had one."""
        for n in nodes:
            p, _ = self.procs[n]
            if p.poll() is None and n not in self.interrupted:
                p.send_signal(signal.SIGINT)
                self.interrupted.add(n)

    def wait_for_log(self, node, text, timeout=120.0):
        """Wait until ``text`` appears in ``node``'s log (True), or the process ends or ``timeout`` s pass."""
        path = self.out / "logs" / f"{node}.log"
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            try:
                if text in path.read_text(encoding="utf-8", errors="replace"):
                    return True
            except OSError:
                pass
            if self.procs[node][0].poll() is not None:
                return False
            time.sleep(0.05)
        return False

    def stop(self, nodes, timeout=120.0):
        """SIGINT to each of ``nodes``, then wait; SIGKILL to those still running ``timeout`` s after the SIGINT (one
        deadline for all: the ground_bridge writes the final CCSDS set of the whole run at shutdown, seconds, many
        more on a loaded machine; a process stuck in DDS, e.g. behind a shared-memory lock that a killed peer held,
        is ended then)."""
        self.interrupt(nodes)
        deadline = time.monotonic() + timeout
        codes = {}
        for n in nodes:
            p, log = self.procs[n]
            try:
                codes[n] = p.wait(timeout=max(0.0, deadline - time.monotonic()))
            except subprocess.TimeoutExpired:
                p.kill()
                codes[n] = p.wait()
            log.close()
        return codes


_Stamp = collections.namedtuple("_Stamp", "sec nanosec")


def stamp_of(data: bytes) -> float:
    """The time [s] in the first 8 bytes after the CDR encapsulation of a serialized message that starts with a
    ``builtin_interfaces/Time`` (a ``rosgraph_msgs/Clock``, the header stamp of a ``DiagnosticArray``): read from a
    raw subscription's bytes, without building the message."""
    return time_to_sec(_Stamp._make(struct.unpack_from("<iI" if data[1] & 1 else ">iI", data, 4)))


def wait_for_completion(duration, deployment, timeout, progress):
    """Spin a small observer node until the simulator reports the scenario complete (or aborted) on
    ``/diagnostics``; returns (reached, reason). The sim time of the timeout's reason is the latest status stamp
    (sim time); ``/clock`` (every step: thousands of wake-ups) is only subscribed to for the progress line. One
    executor for the whole wait (``rclpy.spin_once`` adds and removes the node at every call).

    The observer joins the nodes' DDS domain on loopback: rclpy reads both from this process's environment, which
    may carry neither (a plain shell), so the deployment's values are set here before ``rclpy.init``."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.executors import SingleThreadedExecutor
    from rosgraph_msgs.msg import Clock

    from . import interfaces

    for key in ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE"):
        os.environ[key] = deployment.env[key]
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    rclpy.init()
    node = rclpy.create_node("roe_sep_run")
    now = {"t": 0.0, "end": None}

    def on_status(data):
        now["t"] = max(now["t"], stamp_of(data))
        now["end"] = final_status_of(data) or now["end"]

    def on_clock(data):
        now["t"] = max(now["t"], stamp_of(data))

    if progress:
        node.create_subscription(Clock, interfaces.CLOCK_TOPIC, on_clock, 10, raw=True)
    node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, on_status, interfaces.DIAGNOSTICS,
                             raw=True)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    start = time.monotonic()
    shown = -1
    try:
        while True:
            executor.spin_once(timeout_sec=0.1)
            if now["end"] is not None:
                return now["end"] == "scenario complete", now["end"]
            dead = deployment.dead()
            if dead:
                return False, deployment.death(dead)
            if time.monotonic() - start > timeout:
                return False, f"wall-time limit of {timeout:g} s reached at sim time {now['t']:.0f} s"
            day = int(now["t"] // 21600)
            if progress and day != shown:
                shown = day
                print(f"\r  sim time {now['t'] / 86400:5.2f} d of {duration / 86400:.2f} d", end="", file=sys.stderr)
    finally:
        if progress:
            print(file=sys.stderr)
        executor.shutdown()
        node.destroy_node()
        rclpy.try_shutdown()


def run(config=None, out="out/run", params=None, duration=None, seed=None, *, timeout=1800.0, domain_id=None,
        progress=False, real_time_factor=None, foxglove=None, process_per_node=False, executor="events",
        in_process=False, ground_bridge=True, contingency=None):
    """Run the scenario; returns the report dict (``report['safe']``) and writes it to ``out/report.json``.
    ``foxglove``: a port on 127.0.0.1 for the live Foxglove view (the ``foxglove_view`` node), None = none.
    ``process_per_node``: every node its own process, as a deployment runs them (log per node); default: two
    processes (:data:`SUITES`: the closed loop, and the listeners), each its nodes on one executor
    (:mod:`roe_sep.nodes.suite`, ``executor`` ``events`` or ``single_threaded``); with ``in_process`` every node
    in this process, on one executor (:func:`run_in_process`: a campaign's runs). Under lockstep every layout and
    executor gives the same report. ``ground_bridge`` False: no CCSDS export (the loop and the report are the
    same). ``contingency``: a contingency's name (or 'none') for the simulator and the radar (their parameter
    ``contingency``, docs/contingencies.md); None: the scenario's ``contingency:`` block decides."""
    from .nodes.parameters import DEFAULT_DURATION, check_overrides

    out = Path(out)
    bag_dir = out / "bag"
    if bag_dir.exists():
        raise ValueError(f"output bag {bag_dir} exists already: choose another --out or remove it")
    # the same overrides and node order as the launch files (share/roe_sep/launch), from roe_sep.graph
    overrides = run_overrides(params, duration, seed, real_time_factor, foxglove, contingency=contingency)
    check_overrides(overrides, f"--params {params}" if params else "parameters")  # before any node starts
    out.mkdir(parents=True, exist_ok=True)
    sim = overrides["sim"]
    # foxglove_view before the sim: the clock starts with it up
    nodes = graph_nodes(foxglove=foxglove is not None, ground_bridge=ground_bridge)
    params_file = out / "params.yaml"
    params_file.write_text(yaml.safe_dump(parameters(config, bag_dir.resolve(), overrides, nodes), sort_keys=False))
    sim_duration = float(sim.setdefault("duration", DEFAULT_DURATION))

    if in_process:
        try:
            reached, reason, code = run_in_process(nodes, params_file, ros_environment(domain_id), out / "logs",
                                                   sim_duration, timeout=timeout, progress=progress, executor=executor)
        except Exception as exc:  # noqa: BLE001 -- as below: the runner says what went wrong
            reached, reason, code = False, f"runner error: {type(exc).__name__}: {exc}", 1
        # the recorder was destroyed in order whatever ended the spin: info() tells whether the bag is complete
        report = report_from_bag(bag_dir, out, sim_duration, 0)
        return _finish(out, report, reached, reason, {"in_process": code},
                       layout=f"one process ({executor} executor)", params_file=params_file)
    env = ros_environment(domain_id)
    env.update(dds_environment(out, env))  # the processes' DDS profile (out/fastdds.xml): prompt repairs
    deployment = Deployment(out, params_file, env)
    reached, reason = False, "not started"
    report = None
    try:
        if not process_per_node:
            for name, members in suites(nodes).items():  # the listeners first: the recorder is up early
                deployment.start_suite(name, members, executor)
        for node in nodes if process_per_node else ():
            deployment.start(node)
            if node == "recorder":
                time.sleep(1.0)  # let the recorder discover the graph before the clock starts
        reached, reason = wait_for_completion(sim_duration, deployment, timeout, progress)
    except KeyboardInterrupt as exc:  # Ctrl-C, or children.Interrupted: SIGTERM/SIGHUP under children.guarded()
        signum = getattr(exc, "signum", signal.SIGINT)
        reached, reason = False, interrupted(signum)
    except Exception as exc:  # noqa: BLE001 -- the runner outlives what goes wrong and says what it was
        reached, reason = False, f"runner error: {type(exc).__name__}: {exc}"
    finally:
        if process_per_node:
            codes = deployment.stop([n for n in nodes if n != "recorder"])
            codes.update(deployment.stop(["recorder"]))
        else:
            codes = deployment.stop(["loop"])
            # the listeners' recorder closes the bag first (roe_sep.nodes.suite): the report is built while the
            # ground_bridge writes the run's final CCSDS set
            deployment.interrupt(["listeners"])
            if deployment.wait_for_log("listeners", "bag closed: "):
                report = report_from_bag(bag_dir, out, sim_duration, 0)
            codes.update(deployment.stop(["listeners"]))
    if report is None:
        report = report_from_bag(bag_dir, out, sim_duration, codes.get("recorder", codes.get("listeners")))
    return _finish(out, report, reached, reason, codes,
                   layout="process_per_node" if process_per_node else f"suites ({executor} executor)",
                   params_file=params_file)


def interrupted(signum) -> str:
    """A run's ``reason`` when a stop signal ended it, in every layout: ``interrupted (Ctrl-C)`` for SIGINT, else
    the signal's name (``interrupted (SIGTERM)``)."""
    return "interrupted (Ctrl-C)" if signum == signal.SIGINT else f"interrupted ({signal.Signals(signum).name})"


def _finish(out, report, reached, reason, codes, *, layout, params_file):
    """The run's outcome into its report, written to ``out/report.json``; returns the report."""
    report["run"].update({"completed": reached, "reason": reason, "exit_codes": codes, "layout": layout,
                          "params_file": str(params_file)})
    if not reached:
        # a run that did not complete is unsafe only on a violation seen; else not known (its criteria hold what
        # could be evaluated, False also where there was no evidence yet)
        report["safe"] = False if report.get("violations_seen") else None
    write_report(out / "report.json", report)
    return report


def run_in_process(nodes, params_file, env, log_dir, duration, *, timeout, progress=False, executor="events"):
    """Every node of ``nodes`` in this process, on one executor (:func:`roe_sep.nodes.spin.serve`, as a suite), with
    an observer node that ends the spin once the simulator reports the scenario complete or aborted on
    ``/diagnostics`` (the drain then still hands the listeners what was delivered); the recorder is destroyed
    first, so the bag is complete on return. No process start-up and no inter-process transport: a campaign's
    runs use it (the same report as the other layouts, test_campaign). The nodes' output (rclpy logging and
    prints, at the file-descriptor level) goes to ``log_dir/run.log``. Returns (reached, reason, exit code).
    The nodes join ``env``'s DDS domain on loopback (this process's environment, restored on return)."""
    keys = ("ROS_DOMAIN_ID", "ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_LOCALHOST_ONLY")
    before = {key: os.environ.get(key) for key in keys}  # restored on return
    for key in keys[:2]:
        os.environ[key] = env[key]
    os.environ.pop("ROS_LOCALHOST_ONLY", None)
    try:
        return _run_in_process(nodes, params_file, log_dir, duration, timeout, progress=progress, executor=executor)
    finally:
        for key, value in before.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def _run_in_process(nodes, params_file, log_dir, duration, timeout, *, progress, executor):
    import rclpy.node
    from diagnostic_msgs.msg import DiagnosticArray
    from rosgraph_msgs.msg import Clock

    from . import interfaces
    from .nodes.spin import serve
    from .nodes.suite import make_executor, node_class

    state = {"t": 0.0, "end": None, "timeout": False}
    deadline = time.monotonic() + timeout
    shown = [-1]
    tty = os.fdopen(os.dup(2), "w") if progress else None

    def observer():
        node = rclpy.node.Node("roe_sep_run")

        def on_status(data):
            state["end"] = final_status_of(data) or state["end"]

        node.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, on_status, interfaces.DIAGNOSTICS,
                                 raw=True)
        if progress:
            node.create_subscription(Clock, interfaces.CLOCK_TOPIC,
                                     lambda m: state.update(t=time_to_sec(m.clock)), 10)
        return node

    def until():
        if progress and int(state["t"] // 21600) != shown[0]:
            shown[0] = int(state["t"] // 21600)
            print(f"\r  sim time {state['t'] / 86400:5.2f} d of {duration / 86400:.2f} d", end="", file=tty,
                  flush=True)
        if time.monotonic() > deadline:
            state["timeout"] = True
        return state["end"] is not None or state["timeout"]

    errors, stopped = [], []
    log_dir.mkdir(parents=True, exist_ok=True)
    saved = [os.dup(1), os.dup(2)]
    with open(log_dir / "run.log", "w", encoding="utf-8") as log:
        sys.stdout.flush()
        sys.stderr.flush()
        os.dup2(log.fileno(), 1)
        os.dup2(log.fileno(), 2)
        try:
            code = serve([(name, lambda name=name: node_class(name)()) for name in nodes] + [(None, observer)],
                         ["roe_sep_run", "--ros-args", "--params-file", str(params_file)],
                         make_executor=lambda: make_executor(executor), until=until, errors=errors,
                         stopped=stopped)
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for fd in saved:
                os.close(fd)
            if tty is not None:
                print(file=tty)
                tty.close()
    if state["end"] is not None:
        return state["end"] == "scenario complete", state["end"], code
    if state["timeout"]:
        return False, f"wall-time limit of {timeout:g} s reached at sim time {state['t']:.0f} s", code
    if code:
        why = errors[-1] if errors else "see logs/run.log"
        return False, f"in_process exited early (exit status {code}); last log line: {why}", code
    if stopped:
        return False, interrupted(stopped[0]), code
    return False, "interrupted (signal)", code


def report_from_bag(bag_dir, out, duration, recorder_code):
    """The run report from the bag; when the recorder died (or the bag is unfinished) the bag is recovered first
    (``roe-sep bag recover``) and the report says how much was lost. Never raises: a report that cannot be built
    says why, with ``safe: null``."""
    from .report import paused_gc

    with paused_gc():
        return _report_from_bag(bag_dir, out, duration, recorder_code)


def _report_from_bag(bag_dir, out, duration, recorder_code):
    from .bag import BagError, info
    from .bag.recover import recover, summary_line
    from .report import build_report

    run_info = {}
    source = bag_dir
    try:
        complete = info(bag_dir).get("complete", False)
    except (BagError, OSError) as exc:
        complete, run_info["bag_problem"] = False, str(exc)
    if recorder_code != 0 or not complete:
        try:
            rec = recover(bag_dir, out / "bag_recovered")
            source = out / "bag_recovered"
            last = rec.get("last_log_time_ns")
            run_info["bag_recovered"] = {
                "path": str(source), "messages": rec["messages"], "summary": summary_line(rec),
                "last_log_time": None if last is None else last * 1e-9,
                "seconds_lost": None if last is None else max(0.0, duration - last * 1e-9)}
        except Exception as exc:  # noqa: BLE001
            run_info["bag_problem"] = f"bag could not be recovered: {type(exc).__name__}: {exc}"
    try:
        report = build_report(source, duration)
    except Exception as exc:  # noqa: BLE001
        report = {"safe": None, "criteria": {}, "maneuvers": [], "duration": duration,
                  "report_error": f"report not built from {source}: {type(exc).__name__}: {exc}"}
    report["run"] = run_info
    return report


def write_report(path, report):
    """report.json, strict JSON (no NaN: null with the reason in ``null_reasons``), written atomically."""
    from . import jsonutil

    tmp = Path(path).with_suffix(".json.tmp")
    tmp.write_text(jsonutil.dumps(report) + "\n", encoding="utf-8")
    os.replace(tmp, path)
