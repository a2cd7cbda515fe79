"""Benchmarks of the node suite, side by side in one run:

* planner latency: wall time from publishing an EjectionEvent to receiving the drift-stop ManeuverPlan (DDS round
  trip included), against the bare in-process computation of the same plan (``make_plan``);
* the default scenario (nonlinear truth, node start-up and report included): ``roe-sep run`` wall and CPU time in
  lockstep (as fast as the machine allows) in the default layout (two processes on rclpy's EventsExecutor), the
  same on SingleThreadedExecutors, a process per node, beside the wall-paced free-running clock of before (a process
  per node, 40 s of sim time per 10 ms).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from roe_sep import jsonutil

ROOT = Path(__file__).resolve().parents[1]


def planner_latency(events):
    import rclpy
    from roe_sep_msgs.msg import ManeuverPlan

    from roe_sep import interfaces
    from roe_sep.core.separation.double_impulse import design
    from roe_sep.nodes.convert import time_to_sec
    from roe_sep.run import ros_environment

    sys.path.insert(0, str(ROOT / "test"))
    from test_planner_node import ejection_event  # the same event the tests use

    env = ros_environment()
    os.environ.update({k: env[k] for k in ("ROS_AUTOMATIC_DISCOVERY_RANGE", "ROS_DOMAIN_ID")})
    planner = subprocess.Popen([sys.executable, "-m", "roe_sep.nodes.planner", "--ros-args", "-p", "p_mode:=fixed",
                                "-p", "p_reduction:=0.06"], env=env, stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    rclpy.init()
    node = rclpy.create_node("bench_latency")
    received = {}
    node.create_subscription(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC,
                             lambda m: received.setdefault(time_to_sec(m.ejection_epoch), time.perf_counter()),
                             interfaces.LATCHED)
    pub = node.create_publisher(type(ejection_event()), interfaces.EJECTION_TOPIC, interfaces.LATCHED)
    try:
        deadline = time.monotonic() + 30
        while pub.get_subscription_count() == 0 or node.count_publishers(interfaces.DRIFT_STOP_PLAN_TOPIC) == 0:
            rclpy.spin_once(node, timeout_sec=0.05)
            if time.monotonic() > deadline:
                raise RuntimeError("planner did not come up")
        latencies = []
        for k in range(events + 3):
            stamp = 1000.0 + k
            sent = time.perf_counter()
            pub.publish(ejection_event(stamp=stamp))
            while stamp not in received:
                rclpy.spin_once(node, timeout_sec=0.01)
            if k >= 3:  # warm-up
                latencies.append(received[stamp] - sent)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
        planner.terminate()
        planner.wait()

    from roe_sep.core.separation.double_impulse import plan_drift_stop

    d = design()
    t0 = time.perf_counter()
    for _ in range(200):
        plan_drift_stop(d.dv1_rtn, d.u1, 0.0, d.a, d.inc, k=3, p=0.06)
    compute = (time.perf_counter() - t0) / 200
    return {"events": events, "median_ms": 1e3 * statistics.median(latencies),
            "p95_ms": 1e3 * sorted(latencies)[int(0.95 * (len(latencies) - 1))],
            "max_ms": 1e3 * max(latencies), "compute_only_ms": 1e3 * compute}


FREE_RUNNING = {"sim": {"ros__parameters": {"lockstep_participants": [""], "time_step": 40.0, "tick_period": 0.01}}}
"""The wall-paced mode of before the lockstep: 40 s of sim time every 10 ms of wall time, holds on wall timeouts."""


MODES = {
    "lockstep": [],  # the default: two processes (closed loop, listeners), each on an EventsExecutor
    "lockstep_single_threaded": ["--executor", "single_threaded"],
    "lockstep_process_per_node": ["--process-per-node"],
    "free": ["--process-per-node"],  # and FREE_RUNNING: the wall-paced mode of before
}


def scenario(mode):
    """One default run (nonlinear truth, node start-up included) in ``mode`` (:data:`MODES`)."""
    import resource

    import yaml

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "run"
        cmd = [sys.executable, "-m", "roe_sep.cli", "run", "--out", str(out), "--json", *MODES[mode]]
        if mode == "free":
            params = Path(tmp) / "free.yaml"
            params.write_text(yaml.safe_dump(FREE_RUNNING))
            cmd += ["--params", str(params)]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
        if proc.returncode not in (0, 1):
            raise RuntimeError(proc.stderr[-2000:])
        report = json.loads(proc.stdout)
        span = report["duration"]
    return {"mode": mode, "sim_seconds": span, "wall_seconds": wall, "cpu_seconds": cpu,
            "faster_than_real_time": span / wall, "safe": report["safe"], "dv_total": report["dv_total"],
            "maneuvers": report["maneuvers"]}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--events", type=int, default=50)
    ap.add_argument("--skip-scenario", action="store_true")
    ap.add_argument("--modes", default=",".join(MODES), help=f"comma-separated, of {list(MODES)}")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    result = {"planner_latency": planner_latency(args.events)}
    if not args.skip_scenario:
        result["scenario"] = [scenario(m) for m in args.modes.split(",")]
        lockstep = [sc for sc in result["scenario"] if sc["mode"] != "free"]
        result["same_maneuvers_in_every_lockstep_mode"] = all(sc["maneuvers"] == lockstep[0]["maneuvers"]
                                                              for sc in lockstep)
    if args.json:
        print(jsonutil.dumps(result))
        return 0
    lat = result["planner_latency"]
    print(f"planner: ejection event -> plan received over DDS, {lat['events']} events")
    print(f"  median {lat['median_ms']:.2f} ms   p95 {lat['p95_ms']:.2f} ms   max {lat['max_ms']:.2f} ms   "
          f"(plan computation alone {lat['compute_only_ms']:.3f} ms)")
    if "scenario" in result:
        base = result["scenario"][0]
        for sc in result["scenario"]:
            print(f"default scenario, {sc['mode']:26s}: {sc['sim_seconds'] / 86400:.2f} days in "
                  f"{sc['wall_seconds']:5.1f} s wall ({sc['wall_seconds'] / base['wall_seconds']:.2f}x "
                  f"{base['mode']}), {sc['cpu_seconds']:5.1f} CPU-s = {sc['faster_than_real_time']:.0f}x real time "
                  f"(safe: {sc['safe']}, carrier dv {sc['dv_total']:.4f} m/s)")
        print(f"  same maneuvers in every lockstep mode: {result['same_maneuvers_in_every_lockstep_mode']}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
