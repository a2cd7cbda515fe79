"""``roe-sep campaign``: N closed-loop runs of ``roe-sep run`` (seeds S .. S+N-1) on Dask, resumable, aggregated."""

import argparse
import os
import sys

from ..children import guarded
from ..core.safety.approach import COLLISION_RADIUS
from .common import SEED_MAX, emit, finite_float, integer, seed
from .run import DAY, add_contingency, check_params_file

RUNS_MAX = 100_000
DOMAIN_MAX = 101  # ROS 2 on Linux: domain ids 0..101 keep the DDS ports below the ephemeral range


def domain_range(text):
    """``--domains LO-HI``: the DDS domain ids the runs may use, 0 <= LO <= HI <= 101."""
    lo, sep, hi = str(text).partition("-")
    try:
        lo_i, hi_i = int(lo, 10), int(hi, 10)
    except ValueError:
        lo_i = hi_i = None
    if not sep or lo_i is None or not 0 <= lo_i <= hi_i <= DOMAIN_MAX:
        raise argparse.ArgumentTypeError(f"expected LO-HI with 0 <= LO <= HI <= {DOMAIN_MAX}, got {text!r}")
    return lo_i, hi_i


def scheduler_address(text):
    if not str(text).startswith(("tcp://", "tls://", "inproc://", "ucx://")):
        raise argparse.ArgumentTypeError(f"expected a Dask scheduler address like tcp://127.0.0.1:8786, got {text!r}")
    return text


def _p(prop):
    if prop["p"] is None:
        return "    n/a   (0 runs)"
    lo, hi = prop["ci95"]
    return f"{prop['p']:7.3f}  [{lo:.3f}, {hi:.3f}]  ({prop['k']}/{prop['n']})"


def _num(v, fmt="{:.4g}"):
    return "-" if v is None else fmt.format(v)


def print_campaign(rep):
    print(f"Closed-loop campaign: seeds {rep['seeds'][0]}..{rep['seeds'][1]}, {rep['runs']} runs "
          f"({rep['completed']} completed, {rep['failed']} failed; {rep['executed_now']} run now, "
          f"{rep['skipped_done']} already done)")
    print(f"\n  {'':28s}{'P':>7s}  Wilson 95 %")
    print(f"  {'safe':28s}{_p(rep['p_safe'])}")
    for name, prop in rep["criteria"].items():
        print(f"  {name:28s}{_p(prop)}")
    print(f"  {'safe (failed = unsafe)':28s}{_p(rep['p_safe_failures_unsafe'])}")
    print("  (keep_out, passive_safety: passive-safety verdicts, a prediction with no further burns from each check)")
    if rep.get("ic_reached_lower_95") is not None:
        print(f"  {'ic_reached, one-sided 95 % lower bound (Clopper-Pearson)':60s}{rep['ic_reached_lower_95']:.4f}")
    if rep.get("ic_trims", {}).get("n"):
        print(f"  {'final OD flew a drift trim':28s}{_p(rep['ic_trims'])}")
    if any(prop["n"] for prop in rep["ic_checks"].values()):
        print("  initial conditions at the IC epoch:")
        for name, prop in rep["ic_checks"].items():
            print(f"    {name:26s}{_p(prop)}")
    if rep.get("truth_collision") is not None:
        print(f"\n  {'actual, from the truth':28s}{'P':>7s}  Clopper-Pearson 95 %")
        for key, label in (("truth_collision", f"collision (d < {rep['collision_radius']:.3f} m)"),
                           ("truth_keep_out_violated", "keep-out violated")):
            prop = rep[key]
            gone = f"  ({prop['missing']} runs without the truth's columns)" if prop["missing"] else ""
            print(f"  {label:28s}{_p(prop)}{gone}")
    print(f"\n  {'distribution':24s}{'unit':>6s}{'n':>5s}{'min':>11s}{'p5':>11s}{'p50':>11s}{'p95':>11s}{'max':>11s}")
    for name, d in rep["distributions"].items():
        scale, unit = (1 / 3600, "h") if d["unit"] == "s" else (1.0, d["unit"])
        cells = "".join(f"{_num(None if d[k] is None else d[k] * scale):>11s}" for k in ("min", "p5", "p50", "p95",
                                                                                           "max"))
        print(f"  {name:24s}{unit:>6s}{d['n']:5d}{cells}")
    print("\n  OD covariance against the truth (mean of the normalized squared errors in its chi-square 95 % band)")
    for key, label in (("od_nees", "first solution, ROE NEES"),
                       ("od_drift_rate", "first solution, drift rate z^2"),
                       ("od_last_nees", "last solution, ROE NEES"),
                       ("od_last_drift_rate", "last solution, drift rate z^2"),
                       ("od_nees7", "first solution, 7-state NEES"),
                       ("od_last_nees7", "last solution, 7-state NEES")):
        c = rep.get(key) or {"mean": None}
        if c["mean"] is None:
            print(f"    {label:32s}no OD solution in any completed run")
            continue
        lo, hi = c["mean_bounds"]
        slo, shi = c["single_run_bounds"]
        print(f"    {label:32s}mean {c['mean']:5.2f} in [{lo:.2f}, {hi:.2f}] "
              f"{'consistent  ' if c['consistent'] else 'INCONSISTENT'}  runs in chi2({c['dof']}) "
              f"[{slo:.2f}, {shi:.2f}]: {_p(c['within_single_run_bounds'])}")
    if rep.get("dispersions"):
        print("\n  dispersions as applied against the configured distributions (Kolmogorov-Smirnov, consistent at "
              "p >= 0.01)")
        for name, c in rep["dispersions"].items():
            verdict = {True: "consistent", False: "INCONSISTENT", None: "too few samples"}[c["consistent"]]
            p = "" if c["p_value"] is None else f"  KS D {c['statistic']:.3f}  p {c['p_value']:.3f}"
            print(f"    {name:18s}{c['reference']:>24s}  n {c['n']:5d}  mean {_num(c['mean'], '{:.4g}'):>10s}  "
                  f"std {_num(c['std'], '{:.4g}'):>10s}{p}  {verdict}")
    ol = rep["open_loop"]
    if ol.get("p") is not None:
        print(f"\n  open loop (roe-sep mc, {ol['samples']} samples, p = {ol['p']:g} m/s: {ol['p_source']}):")
        print(f"    P(approaching drift) {ol['p_approach']:.4f}   P(evaporation) {ol['p_evaporation']:.4f}   "
              f"P(min R-N violation) {ol['p_min_rn_violation']:.4f}   P(FOV violation) {ol['p_fov_violation']:.4f}")
        if rep["completed"]:
            print(f"    closed loop: P(passive_safety fails) {1 - rep['criteria']['passive_safety']['p']:.4f}   "
                  f"P(evaporation fails) {1 - rep['criteria']['evaporation']['p']:.4f}")
    else:
        print(f"\n  open loop: not comparable ({ol['p_source']})")
    if rep["failures"]["by_kind"]:
        print("\n  failures: " + ", ".join(f"{k} {v}" for k, v in rep["failures"]["by_kind"].items()))
        for reason, count in list(rep["failures"]["by_reason"].items())[:5]:
            print(f"    {count:4d} x {reason}")
    if rep["wall_s_per_run"] is not None:
        print(f"\n  wall time per run (in its worker): {rep['wall_s_per_run']:.1f} s")


def cmd_campaign(args):
    from ..campaign import run_campaign
    from ..core.config import load_scenario
    from ..graph import contingency_overrides
    from ..run import load_overrides

    if args.seed + args.runs - 1 > SEED_MAX:
        raise ValueError(f"--seed {args.seed} with --runs {args.runs}: the last seed must be <= {SEED_MAX}")
    load_scenario(args.config)  # a bad scenario is refused before any run starts
    overrides = {}
    if args.params:
        check_params_file(args.params)
        overrides = load_overrides(args.params)
    overrides = contingency_overrides(overrides, args.contingency)
    workers = args.workers or (None if args.scheduler else os.cpu_count() or 1)
    with guarded():  # SIGTERM/SIGHUP stop the campaign as Ctrl-C does (exit 128 + signal number)
        rep = run_campaign(args.runs, args.seed, args.out, workers=workers, scheduler=args.scheduler,
                           config=args.config, overrides=overrides, duration=args.duration, timeout=args.timeout,
                           domains=args.domains, retry_failed=args.retry_failed,
                           progress=not args.json and sys.stderr.isatty(), open_loop_samples=args.open_loop_samples,
                           figures=not args.no_figures, ccsds=args.ccsds, bags=not args.no_bags,
                           collision_radius=args.collision_radius)
    emit(rep, args.json, print_campaign)
    return 0 if rep["failed"] == 0 else 1


def register(subparsers):
    """Add ``campaign`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("campaign", help="closed-loop Monte Carlo: N end-to-end runs on Dask, resumable, "
                              "aggregated (P(safe), dv, time to IC, OD consistency)")
    p.add_argument("--runs", type=integer(1, RUNS_MAX), required=True, help=f"number of runs in [1, {RUNS_MAX}]")
    p.add_argument("--seed", type=seed(), default=0, help="first seed; run k has seed S+k (default 0)")
    p.add_argument("--out", default="out/campaign", help="campaign directory: runs.csv, runs/<seed>/, report.json, "
                   "figures/ (default out/campaign); rerunning into it skips the runs done")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=integer(1, 256),
                       help="embedded Dask cluster: worker processes, one run each at a time (default: CPU count)")
    where.add_argument("--scheduler", type=scheduler_address, help="use an existing Dask cluster (tcp://host:port)")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--params", help="ROS parameter YAML for every run ({node: {ros__parameters: ...}}); the "
                   "campaign sets radar.seed per run")
    add_contingency(p)
    p.add_argument("--duration", type=finite_float(0.0, 30 * DAY, lo_open=True, unit="s"),
                   help="sim seconds per run, in (0, 2592000] (default 280800 = 3.25 days)")
    p.add_argument("--timeout", type=finite_float(0.0, 7 * DAY, lo_open=True, unit="s"), default=1800.0,
                   help="wall-time limit of one run [s] in (0, 604800] (default 1800)")
    p.add_argument("--domains", type=domain_range, default=(1, 100), metavar="LO-HI",
                   help="DDS domain ids the runs may take, one per concurrent run (default 1-100)")
    p.add_argument("--retry-failed", action="store_true", help="rerun the seeds whose row says failed")
    p.add_argument("--open-loop-samples", type=integer(100, 10_000_000), default=20000,
                   help="samples of the open-loop Monte Carlo shown beside (default 20000)")
    p.add_argument("--ccsds", action="store_true",
                   help="run the ground_bridge in every run: its CCSDS set in runs/<seed>/ccsds/ (default: not, "
                        "the rows are the same; about 3 CPU-s per run)")
    p.add_argument("--no-bags", action="store_true",
                   help="remove each completed run's bag once its row is written (about 1.2 MB per run; the row and "
                        "report.json are the same; a failed run keeps its bag)")
    p.add_argument("--no-figures", action="store_true", help="do not write figures/")
    p.add_argument("--collision-radius", type=finite_float(0.0, 1000.0, lo_open=True, unit="m"), metavar="M",
                   default=COLLISION_RADIUS,
                   help="a collision: the truth's closest approach below this [m] (default %(default).3f: the sum of "
                        "the circumscribed spheres of the carrier's 60x80x80 cm and the picosatellite's 10x10x10 cm, "
                        "seed 001 Sec. 1)")
    p.add_argument("--json", action="store_true", help="print the aggregate report as JSON")
    p.set_defaults(func=cmd_campaign)
