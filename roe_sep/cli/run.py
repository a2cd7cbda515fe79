"""``roe-sep run``, ``roe-sep replay`` and ``roe-sep bag``: the scenario end to end over ROS 2
(docs/run.md), and the tools for its bags."""

import json
import math
import sys
from pathlib import Path

from .. import jsonutil
from ..children import guarded
from ..graph import EXECUTORS
from .common import emit, finite_float, seed, vec
from .foxglove import DEFAULT_PORT, port_number

DAY = 86400.0


def print_run(rep: dict, out=None):
    """The run report as a table; copes with a partial report (a run that did not complete)."""
    w = (out or sys.stdout).write
    verdict = {True: "SAFE", False: "UNSAFE", None: "INCOMPLETE"}[rep.get("safe")]
    w(f"Run {verdict} ({rep.get('run', {}).get('reason', '')})\n")
    if rep.get("report_error"):
        w(f"  {rep['report_error']}\n")
    recovered = rep.get("run", {}).get("bag_recovered")
    if recovered:
        lost = recovered.get("seconds_lost")
        w(f"  bag recovered to {recovered['path']}" + ("" if lost is None else f" ({lost:.0f} s of sim time lost)")
          + "\n")
    for m in rep.get("maneuvers", []):
        w(f"  t = {m['epoch']:10.1f} s  u = {m['u_deg'] % 360:7.2f} deg  {m['spacecraft']:13s} {m['purpose']:15s} "
          f"dv RTN = {vec(m['dv_rtn'])} m/s  |dv| = {m['dv']:.4f} m/s\n")
    if "dv_total" in rep:
        w(f"  carrier dv total = {rep['dv_total']:.4f} m/s "
          f"({', '.join(f'{k} {v:.4f}' for k, v in rep['dv_by_purpose'].items())})\n")
    if rep.get("time_to_ic") is not None:
        w(f"  time to initial conditions = {rep['time_to_ic'] / 3600:.1f} h after the ejection\n")
    elif rep.get("ic"):
        failed = ", ".join(k for k, ok in rep["ic"]["checks"].items() if not ok)
        w(f"  initial conditions NOT reached at the IC epoch t = {rep['ic']['epoch']:.0f} s ({failed})\n")
    if rep.get("final_roe"):
        w("  final truth a*ROE [da dl dex dey dix diy] = [" + " ".join(f"{x:.1f}" for x in rep["final_roe"]) + "] m\n")
    if "min_distance" in rep:
        md = rep["min_distance"]
        w(f"  closest approach after departure = {'none' if md is None else f'{md:.1f} m'}\n")
    ap = rep.get("actual_approach")
    if ap:
        c = ap.get("closest_approach")
        end = ", still approaching at the end" if c and c["at_end"] else ""
        where = "none" if c is None else (f"{c['distance']:.1f} m at t = {c['epoch']:.0f} s (refined within "
                                          f"{c['bound']:.2f} m{end})")
        w(f"  actual approach (truth): closest {where}; keep-out "
          + (f"VIOLATED ({ap['keep_out_time']:.0f} s inside after the departure, {ap['keep_out_entries']} entries)"
             if ap["keep_out_violated"] else "held after the departure") + "\n")
    if rep.get("ic"):
        ic = rep["ic"]
        w(f"  truth at the IC epoch t = {ic['epoch']:.0f} s: a*ROE = [" + " ".join(f"{x:.1f}" for x in ic["roe"])
          + f"] m, e/i angle {ic['ei_angle_deg']:.1f} deg, min R-N {ic['min_rn_distance']:.0f} m\n")
    if rep.get("od"):
        od = rep["od"]
        w(f"  first OD: t = {od['epoch']:.0f} s, {od['passes']} passes, {od['measurements']} measurements, "
          f"NEES = {od.get('nees') if od.get('nees') is None else round(od['nees'], 2)}\n")
    if rep.get("contingency"):
        c = rep["contingency"]
        w(f"  contingency {c.get('name')}: {json.dumps(c.get('parameters'))}\n")
        for event in c.get("events") or ():
            w(f"    {event}\n")
    for d in rep.get("contingencies_detected") or ():
        w(f"  detected {d['name']} at t = {d['epoch']:.0f} s: {d['text']}\n")
    for name, ok in rep.get("criteria", {}).items():
        verdict = name in ("keep_out", "passive_safety")
        kind = "  (passive-safety verdict: predicted, no further burns)" if verdict else ""
        w(f"  {'pass' if ok else 'FAIL'}  {name}{kind}\n")


def add_contingency(p):
    """``--contingency NAME`` (docs/contingencies.md)."""
    from ..core.truth.contingency import NAMES, NONE

    p.add_argument("--contingency", choices=(*NAMES, NONE), metavar="NAME",
                   help="inject a contingency (simulator and radar; the scenario's contingency block gives its "
                        f"parameters when it names it, else its defaults): {', '.join(NAMES)}; or {NONE} (none, "
                        "whatever the scenario says). Default: the scenario's block, if any (docs/contingencies.md)")


def check_params_file(path):
    """``--params``: readable YAML in the ROS layout ``{node: {ros__parameters: {...}}}`` with finite numbers only,
    every value within its node's parameter table (:func:`roe_sep.nodes.parameters.check_overrides`: a bad value is
    refused before any node starts); ValueError/ConfigError naming the file, the node, the key and the rule."""
    from ..core.config import read_yaml
    from ..nodes.parameters import check_overrides

    data = read_yaml(path)
    if data is None:
        return
    if not isinstance(data, dict) or not all(isinstance(v, dict) and isinstance(v.get("ros__parameters"), dict)
                                             for v in data.values()):
        raise ValueError(f"--params {path}: expected {{node: {{ros__parameters: {{name: value}}}}}}")

    def walk(x, where):
        if isinstance(x, dict):
            for k, v in x.items():
                walk(v, f"{where}.{k}")
        elif isinstance(x, list):
            for i, v in enumerate(x):
                walk(v, f"{where}[{i}]")
        elif isinstance(x, float) and not math.isfinite(x):
            raise ValueError(f"--params {path}: {where} = {x}: parameters must be finite numbers")

    for node, v in data.items():
        walk(v["ros__parameters"], str(node))
    check_overrides({node: v["ros__parameters"] for node, v in data.items()}, f"--params {path}")


def cmd_run(args):
    from ..core.config import load_scenario
    from ..run import run

    load_scenario(args.config)  # a bad scenario is refused before any node starts
    if args.params:
        check_params_file(args.params)

    with guarded():  # SIGTERM/SIGHUP stop the run as Ctrl-C does; no node process outlives it
        rep = run(config=args.config, out=args.out, params=args.params, duration=args.duration, seed=args.seed,
                  timeout=args.timeout, progress=not args.json and sys.stderr.isatty(),
                  real_time_factor=args.real_time_factor, foxglove=args.foxglove,
                  process_per_node=args.process_per_node, executor=args.executor, in_process=args.in_process,
                  contingency=args.contingency)

    def human(r):
        print_run(r)
        print(f"\nbag: {Path(args.out) / 'bag'}   report: {Path(args.out) / 'report.json'}")

    emit(rep, args.json, human)
    return 0 if rep["safe"] else 1

def delegated(argv):
    """``replay`` and ``bag recover`` own their argument parsing (and ``--help``): hand them the rest."""
    if argv[:1] == ["replay"]:
        from ..bag import replay
        from .foxglove import split_foxglove, with_foxglove

        rest, port = split_foxglove(argv[1:])
        if port is None:
            return replay.main(rest)
        with guarded():  # SIGTERM/SIGHUP stop the replay as Ctrl-C does, and the view with it
            return with_foxglove(port, lambda: replay.main(rest), sim_time="--clock" in rest)
    if argv[:2] == ["bag", "recover"]:
        from ..bag import recover

        return recover.main(argv[2:])
    return None

def cmd_bag_info(args):
    """Exit 0 for a complete, consistent bag; 1 for a damaged one (the report says what and where); 2 when nothing
    can be read (no such path, not an MCAP file)."""
    from ..bag import BagError, info
    from ..bag.reader import format_info

    try:
        d = info(args.bag)
    except (BagError, OSError) as exc:
        raise ValueError(str(exc)) from exc
    if args.json:
        jsonutil.dump(d, sys.stdout)
    else:
        print(format_info(d))
    return 0 if d["complete"] and not d.get("problems") else 1

def register_run(subparsers):
    """Add ``run`` and ``replay`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("run", help="run the scenario end to end (all nodes, sim time), record a bag, "
                              "write a report")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--params", help="ROS parameter YAML overriding node parameters ({node: {ros__parameters: ...}})")
    p.add_argument("--out", default="out/run", help="output directory: bag/, report.json, logs/ (default out/run)")
    p.add_argument("--duration", type=finite_float(0.0, 30 * DAY, lo_open=True, unit="s"),
                   help="sim seconds to run, in (0, 2592000] (default 280800 = 3.25 days)")
    p.add_argument("--seed", type=seed(), help="seed of the simulated dispersions in [0, 2**32 - 1] (default 0)")
    p.add_argument("--timeout", type=finite_float(0.0, 7 * DAY, lo_open=True, unit="s"), default=1800.0,
                   help="wall-time limit [s] in (0, 604800] (default 1800)")
    p.add_argument("--real-time-factor", type=finite_float(0.0, 1e9, unit="sim s per wall s"), metavar="X",
                   help="pace the lockstep clock at X sim seconds per wall second at most (default 0: as fast as "
                        "the machine allows; the results are the same either way)")
    add_contingency(p)
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    layout = p.add_mutually_exclusive_group()
    layout.add_argument("--process-per-node", action="store_true",
                        help="every node its own process, as a deployment runs them (default: two processes, the "
                             "closed loop and the listeners, each on one executor; same report)")
    layout.add_argument("--in-process", action="store_true",
                        help="every node in this process on one executor, node output in OUT/logs/run.log (a "
                             "campaign's runs; the least CPU per run; same report)")
    p.add_argument("--executor", choices=EXECUTORS, default="events",
                   help="rclpy executor of the suite process(es) (default events: rclpy's EventsExecutor); "
                        "--process-per-node always uses single_threaded")
    p.add_argument("--foxglove", type=port_number, nargs="?", const=DEFAULT_PORT, metavar="PORT",
                   help=f"serve a live Foxglove view on ws://127.0.0.1:PORT (default {DEFAULT_PORT})")
    p.set_defaults(func=cmd_run)

    subparsers.add_parser("replay", add_help=False, help="play a bag back onto its topics (roe-sep replay --help)")


def register_bag(subparsers):
    """Add ``bag info`` and ``bag recover`` to the ``roe-sep`` subparsers."""
    bag = subparsers.add_parser("bag", help="inspect or recover a bag").add_subparsers(dest="bag_command",
                                                                                      required=True)
    p = bag.add_parser("info", help="topics, types, counts, QoS and duration of a bag")
    p.add_argument("bag", help="bag directory or .mcap file")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_bag_info)
    bag.add_parser("recover", add_help=False, help="rebuild a complete bag from an unfinished recording "
                   "(roe-sep bag recover --help)")
