"""``roe-sep``: the command line of roe_sep. Human tables by default, ``--json`` for ground-segment scripts.

Subcommands: ``design`` (nominal double-impulse plan), ``mc`` (Monte Carlo p sweep), ``run`` (the scenario end to
end over ROS 2, the README's main command).
"""

import argparse
import dataclasses
import json
import math
import sys
from pathlib import Path

from .core.config import ConfigError, load_scenario
from .core.double_impulse import DoubleImpulseDesign, InfeasibleDesignError, design
from .core.montecarlo import SweepResult, sweep


def design_report(d: DoubleImpulseDesign) -> dict:
    """The machine-readable design: every key the README documents (SI units, angles in deg where named)."""
    b = d.bounds
    aimed = d.final_roe() * d.a
    return {
        "strategy": "double_impulse",
        "a": d.a,
        "n": d.n,
        "inclination_deg": math.degrees(d.inc),
        "u1_deg": math.degrees(d.u1),
        "u2_deg": math.degrees(d.u2),
        "k": d.k,
        "k_admissible": list(d.k_admissible),
        "eta_deg": math.degrees(d.eta),
        "dv1_rtn": d.dv1_rtn.tolist(),
        "dv2_rtn": d.dv2_rtn.tolist(),
        "dv2_carrier_rtn": (0.0 - d.dv2_rtn).tolist(),
        "a_dl_star": d.a_dl_star,
        "a_da1": d.a_da1,
        "a_dl_f": d.a_dl_f,
        "aimed_roe": aimed.tolist(),
        "p_sigma_level": d.config.p_sigma_level,
        "p_min_3sigma": d.p_min,
        "p_max": d.p_max,
        "bounds": dataclasses.asdict(b),
        "config": dataclasses.asdict(d.config),
    }


def _vec(v):
    return "[" + " ".join(f"{x:+.6f}" for x in v) + "]"


def print_design(rep: dict, out=None):
    b = rep["bounds"]
    w = (out or sys.stdout).write
    w("Double-impulse separation design (seeds 000/002, Eqs. 9-21)\n")
    w(f"  carrier orbit     a = {rep['a']:.1f} m   n = {rep['n']:.6e} rad/s   i = {rep['inclination_deg']:.3f} deg\n")
    w(f"  ejection (SPL)    u1 = {rep['u1_deg']:8.3f} deg   dv1 RTN = {_vec(rep['dv1_rtn'])} m/s "
      "(picosat rel. carrier)\n")
    w(f"  drift-stop        u2 = {rep['u2_deg']:8.3f} deg   dv2 RTN = {_vec(rep['dv2_rtn'])} m/s (relative effect)\n")
    w(f"                    k = {rep['k']} (admissible {rep['k_admissible']})   carrier burns "
      f"{_vec(rep['dv2_carrier_rtn'])} m/s\n")
    w(f"  e/i configuration eta = {rep['eta_deg']:.0f} deg   a*Delta dl* = {rep['a_dl_star']:.1f} m   "
      f"a da1 = {rep['a_da1']:.1f} m   a dl_F = {rep['a_dl_f']:.1f} m\n")
    w("  aimed ROE a*[da dl dex dey dix diy] = [" + " ".join(f"{x:.1f}" for x in rep["aimed_roe"]) + "] m\n")
    w("\nAdmissible sizes of the final relative orbit (Table 2, from Table 1)\n")
    w(f"  {'':10s}{'min [m]':>12s}{'max [m]':>12s}\n")
    for key, label in (("dl", "a dl"), ("de", "a de"), ("di", "a di")):
        w(f"  {label:10s}{b[f'a_{key}_min']:12.2f}{b[f'a_{key}_max']:12.2f}\n")
    w(f"  a di margin (safety #7) = {b['a_di_margin']:.2f} m\n")
    w(f"\nDrift-stop reduction (Eq. 21, {rep['p_sigma_level']:g} sigma): "
      f"{rep['p_min_3sigma']:.7f} <= |p| < {rep['p_max']:.7f} m/s\n")


def print_sweep(res: dict, out=None):
    w = (out or sys.stdout).write
    w(f"Monte Carlo p sweep: {res['samples']} samples, seed {res['seed']}, drag {'on' if res['drag'] else 'off'}, "
      f"J2 {'on' if res['j2'] else 'off'}, dB = {res['delta_b']:.5f} m^2/kg\n")
    cols = (("p", "p [m/s]", "{:9.4f}"), ("p_approach", "P(approach)", "{:11.3%}"),
            ("p_evaporation", "P(evap.)", "{:9.3%}"), ("p_below_radar_horizon", "P(<5km@24h)", "{:11.3%}"),
            ("p_min_rn_violation", "P(RN<min)", "{:9.3%}"), ("p_fov_violation", "P(FOV)", "{:8.3%}"),
            ("p_table2_violation", "P(>Tab.2)", "{:9.3%}"),
            ("a_dl_horizon_mean", "mean a dl@24h", "{:13.0f}"))
    w("  " + "  ".join(f"{h:>{len(fmt.format(0.0))}s}" for _, h, fmt in cols) + "\n")
    for row in res["rows"]:
        mark = "  <- p_best" if row["p"] == res["p_best"] else ""
        w("  " + "  ".join(fmt.format(row[k]) for k, _, fmt in cols) + mark + "\n")
    w(f"  p_best = {res['p_best']:g} m/s (minimum of P(approach) + P(evaporation))\n")
    w(f"  nearest R=0 transit before the drift-stop: min {res['crossing_min']:.0f} m over all samples, "
      f"{res['crossing_min_within_3sigma_f1']:.0f} m for f1 >= {res['f1_3sigma']:.2f}\n")


def _progress(enabled):
    if not enabled:
        return iter
    from tqdm import tqdm

    return lambda it: tqdm(it, desc="p sweep", unit="p", leave=False)


def run_sweep(scenario, args) -> SweepResult:
    mc = scenario.monte_carlo
    overrides = {}
    if args.samples is not None:
        overrides["samples"] = args.samples
    if args.seed is not None:
        overrides["seed"] = args.seed
    if args.no_drag:
        overrides["drag"] = False
    if args.j2:
        overrides["j2"] = True
    mc = dataclasses.replace(mc, **overrides)
    p_values = args.p if args.p is not None else scenario.p_values
    d = design(scenario.separation)
    return sweep(d, mc, p_values, progress=_progress(not args.json and sys.stderr.isatty()))


def sweep_report(res: SweepResult) -> dict:
    out = res.to_dict()
    out["f1_3sigma"] = 1.0 - 3.0 * res.design.config.spl_sigma
    return out


def _p_list(text):
    try:
        values = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"--p expects comma-separated numbers in m/s, got {text!r}") from None
    if not values or not all(math.isfinite(v) and v >= 0 for v in values):
        raise argparse.ArgumentTypeError(f"--p expects non-negative finite values in m/s, got {text!r}")
    return values


def _positive_int(text):
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def cmd_design(args):
    rep = design_report(design(load_scenario(args.config).separation))
    if args.json:
        json.dump(rep, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print_design(rep)


def cmd_mc(args):
    res = run_sweep(load_scenario(args.config), args)
    rep = sweep_report(res)
    if args.plots:
        from .plots import write_figures

        rep["figures"] = [str(p) for p in write_figures(res, Path(args.plots))]
    if args.json:
        json.dump(rep, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print_sweep(rep)
        for f in rep.get("figures", []):
            print(f"  figure: {f}")


def print_run(rep: dict, out=None):
    w = (out or sys.stdout).write
    w(f"Run {'SAFE' if rep['safe'] else 'UNSAFE'} ({rep['run']['reason']})\n")
    for m in rep["maneuvers"]:
        w(f"  t = {m['epoch']:10.1f} s  u = {m['u_deg'] % 360:7.2f} deg  {m['spacecraft']:13s} {m['purpose']:15s} "
          f"dv RTN = {_vec(m['dv_rtn'])} m/s  |dv| = {m['dv']:.4f} m/s\n")
    w(f"  carrier dv total = {rep['dv_total']:.4f} m/s "
      f"({', '.join(f'{k} {v:.4f}' for k, v in rep['dv_by_purpose'].items())})\n")
    if rep["time_to_ic"] is not None:
        w(f"  time to initial conditions = {rep['time_to_ic'] / 3600:.1f} h after the ejection\n")
    if rep["final_roe"]:
        w("  final truth a*ROE [da dl dex dey dix diy] = [" + " ".join(f"{x:.1f}" for x in rep["final_roe"]) + "] m\n")
    md = rep["min_distance"]
    w(f"  closest approach after departure = {'none' if md is None else f'{md:.1f} m'}\n")
    if rep["ic"]:
        ic = rep["ic"]
        w(f"  truth at the IC epoch t = {ic['epoch']:.0f} s: a*ROE = [" + " ".join(f"{x:.1f}" for x in ic["roe"])
          + f"] m, e/i angle {ic['ei_angle_deg']:.1f} deg, min R-N {ic['min_rn_distance']:.0f} m\n")
    if rep["od"]:
        od = rep["od"]
        w(f"  first OD: t = {od['epoch']:.0f} s, {od['passes']} passes, {od['measurements']} measurements, "
          f"NEES = {od.get('nees') if od.get('nees') is None else round(od['nees'], 2)}\n")
    for name, ok in rep["criteria"].items():
        w(f"  {'pass' if ok else 'FAIL'}  {name}\n")


def cmd_run(args):
    from .run import run

    rep = run(config=args.config, out=args.out, params=args.params, duration=args.duration, seed=args.seed,
              timeout=args.timeout, progress=not args.json and sys.stderr.isatty())
    if args.json:
        json.dump(rep, sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print_run(rep)
        print(f"\nbag: {Path(args.out) / 'bag'}   report: {Path(args.out) / 'report.json'}")
    return 0 if rep["safe"] else 1


def _delegated(argv):
    """``replay`` and ``bag recover`` own their argument parsing (and ``--help``): hand them the rest."""
    if argv[:1] == ["replay"]:
        from .bag import replay

        return replay.main(argv[1:])
    if argv[:2] == ["bag", "recover"]:
        from .bag import recover

        return recover.main(argv[2:])
    return None


def cmd_bag_info(args):
    from .bag import BagError, info
    from .bag.reader import format_info

    try:
        d = info(args.bag)
    except (BagError, OSError) as exc:
        raise ValueError(str(exc)) from exc
    print(json.dumps(d, indent=2) if args.json else format_info(d))
    return 0


def build_parser():
    parser = argparse.ArgumentParser(prog="roe-sep", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("design", help="nominal double-impulse separation plan")
    p.add_argument("--config", help="scenario YAML (default: the embedded BIROS/picosatellite case)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_design)

    p = sub.add_parser("mc", help="Monte Carlo sweep over the drift-stop reduction p")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--samples", type=_positive_int, help="number of samples (default 100000)")
    p.add_argument("--seed", type=int, help="random seed (default from the scenario: 0)")
    p.add_argument("--p", type=_p_list, help="comma-separated p values [m/s]")
    p.add_argument("--no-drag", action="store_true", help="switch differential drag off")
    p.add_argument("--j2", action="store_true", help="include secular J2 in the propagation")
    p.add_argument("--plots", metavar="DIR", help="write the figures (PNG) to DIR")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_mc)

    p = sub.add_parser("run", help="run the scenario end to end (all nodes, sim time), record a bag, write a report")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--params", help="ROS parameter YAML overriding node parameters ({node: {ros__parameters: ...}})")
    p.add_argument("--out", default="out/run", help="output directory: bag/, report.json, logs/ (default out/run)")
    p.add_argument("--duration", type=float, help="sim seconds to run (default 280800 = 3.25 days)")
    p.add_argument("--seed", type=int, help="seed of the simulated dispersions (default 0)")
    p.add_argument("--timeout", type=float, default=1800.0, help="wall-time limit [s] (default 1800)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.set_defaults(func=cmd_run)

    sub.add_parser("replay", add_help=False, help="play a bag back onto its topics (roe-sep replay --help)")

    bag = sub.add_parser("bag", help="inspect or recover a bag").add_subparsers(dest="bag_command", required=True)
    p = bag.add_parser("info", help="topics, types, counts, QoS and duration of a bag")
    p.add_argument("bag", help="bag directory or .mcap file")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_bag_info)
    bag.add_parser("recover", add_help=False, help="rebuild a complete bag from an unfinished recording "
                   "(roe-sep bag recover --help)")
    return parser


def main(argv=None):
    argv = sys.argv[1:] if argv is None else list(argv)
    delegated = _delegated(argv)
    if delegated is not None:
        return delegated
    args = build_parser().parse_args(argv)
    try:
        code = args.func(args)
    except (ConfigError, InfeasibleDesignError, ValueError, FileNotFoundError) as exc:
        print(f"roe-sep: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # e.g. `roe-sep mc --json | head`
        sys.stderr.close()
        return 0
    return code or 0


if __name__ == "__main__":
    sys.exit(main())
