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

from .cli_output import emit
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


STRATEGIES = ("double_impulse", "multi_impulse")


def _multi_design(scenario, args):
    from .core import multi_impulse

    overrides = {k: v for k, v in (("spl_dv", args.spl_dv), ("u1_deg", args.u1)) if v is not None}
    mcfg = dataclasses.replace(multi_impulse.MultiImpulseConfig(), **overrides)
    return multi_impulse.design(scenario.separation, mcfg, scenario.monte_carlo)


def print_multi_design(rep: dict, out=None):
    w = (out or sys.stdout).write
    a = rep["a"]
    w("Multi-impulse separation design (seed 001 Sec. 3)\n")
    w(f"  carrier orbit     a = {a:.1f} m   n = {rep['n']:.6e} rad/s   i = {rep['inclination_deg']:.3f} deg\n")
    w(f"  ejection (SPL)    u1 = {rep['u1_deg']:8.3f} deg   dv RTN = {_vec(rep['ejection_dv_rtn'])} m/s "
      f"(|dv| = {rep['spl_dv']:g} m/s, picosat rel. carrier)\n")
    w(f"    tangential: max(Eq. 10 e~ = {rep['dv_t_min_eq10']:.4f}, AC3 drift-free = {rep['dv_t_min_ac3']:.4f}) m/s;"
      f" normal: a di_F = {rep['a_di_f']:.1f} m; radial: the rest (Eq. 12)\n")
    w(f"  carrier burns (tangential, <= {rep['max_burn']:g} m/s, quantum {rep['dv_quantum'] * 1e3:g} mm/s)\n")
    w(f"    {'purpose':16s}{'u [deg]':>10s}{'u mod 360':>10s}{'t [h]':>9s}{'dvT carrier [m/s]':>19s}\n")
    for m in rep["maneuvers"]:
        w(f"    {m['purpose']:16s}{m['u_deg']:10.2f}{m['u_deg'] % 360:10.2f}{m['epoch'] / 3600:9.3f}"
          f"{m['dv_rtn'][1]:+19.3f}\n")
    w(f"  thrusted dv = {rep['thrusted_dv_total']:.3f} m/s = {rep['thrusted_to_ejection_ratio']:.1%} of the ejection dv"
      f"   (drift reduction |p| = {rep['p']:.4f} m/s)\n")
    for key, label in (("roe_after_ejection", "after ejection"), ("roe_after_reduction", "after drift reduction"),
                       ("roe_final", "after the pair (IC)")):
        w(f"  a*ROE {label:22s} [" + " ".join(f"{x:.1f}" for x in rep[key]) + "] m\n")
    w(f"  final e/i angle {rep['final_ei_angle_deg']:.2f} deg   "
      f"min R-N distance {rep['final_min_rn_distance']:.1f} m\n")
    j = rep["j2"]
    w("J2 (seed 001 Sec. 2.2 item 3)\n")
    w(f"  de rotation {j['e_vector_rotation_deg_per_day']:+.3f} deg/day (clockwise)\n")
    w(f"  a diy drift {j['a_diy_drift_per_m_dix_m_per_day']:.4f} m/day per m of a dix; a dix at u1 = "
      f"{j['a_dix_at_ejection']:.3f} m -> {j['a_diy_drift_m_per_day']:.3f} m/day "
      f"(u1 = 88 deg would give {j['a_diy_drift_m_per_day_if_u1_88deg']:.2f} m/day): eject at u = 90/270 deg\n")


def cmd_design(args):
    scenario = load_scenario(args.config)
    if args.strategy == "multi_impulse":
        from .core.multi_impulse import design_report as multi_report

        emit(multi_report(_multi_design(scenario, args)), args.json, print_multi_design)
        return
    emit(design_report(design(scenario.separation)), args.json, print_design)


def print_acceptance(rep: dict, out=None):
    w = (out or sys.stdout).write
    w(f"Multi-impulse Monte Carlo (seed 001 Sec. 4): {rep['samples']} samples, seed {rep['seed']}, "
      f"drag {'on' if rep['drag'] else 'off'}, J2 {'on' if rep['j2'] else 'off'}\n")
    w(f"  AC1  a da < 0 after the drift reduction          {rep['ac1']:9.3%}  ({rep['n_ac1_fail']} fail; "
      f"max a da = {rep['a_da_after_reduction_max']:.1f} m)\n")
    w(f"  AC2  nearest R=0 transit >= {rep['ac2_distance']:.0f} m              {rep['ac2']:9.3%}  "
      f"({rep['n_ac2_fail']} fail; min {rep['crossing_min']:.0f} m)\n")
    w(f"  AC3  min R-N > 150 m, |a da| < {rep['drift_free_a_da']:.1f} m         {rep['ac3']:9.3%}  "
      f"({rep['n_ac3_fail']} fail of {rep['n_drift_free']} drift-free)\n")


def cmd_mc(args):
    if args.strategy == "multi_impulse":
        from .core.acceptance import run as run_acceptance

        scenario = load_scenario(args.config)
        overrides = {k: v for k, v in (("samples", args.samples), ("seed", args.seed)) if v is not None}
        if args.no_drag:
            overrides["drag"] = False
        if args.j2:
            overrides["j2"] = True
        if args.p is not None:
            raise ValueError("--p applies to the double_impulse sweep only (multi_impulse sizes p by Eq. 21)")
        mc = dataclasses.replace(scenario.monte_carlo, **overrides)
        res = run_acceptance(_multi_design(scenario, args), mc)
        rep = res.to_dict()
        if args.plots:
            from .plots_ops import write_acceptance_figures

            rep["figures"] = [str(p) for p in write_acceptance_figures(res, Path(args.plots))]
        emit(rep, args.json, print_acceptance)
        return
    res = run_sweep(load_scenario(args.config), args)
    rep = sweep_report(res)
    if args.plots:
        from .plots import write_figures

        rep["figures"] = [str(p) for p in write_figures(res, Path(args.plots))]
    emit(rep, args.json, print_sweep)


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

    def human(r):
        print_run(r)
        print(f"\nbag: {Path(args.out) / 'bag'}   report: {Path(args.out) / 'report.json'}")

    emit(rep, args.json, human)
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


def _strategy_args(p):
    p.add_argument("--strategy", choices=STRATEGIES, default="double_impulse",
                   help="separation strategy (default double_impulse; multi_impulse: seed 001)")
    p.add_argument("--spl-dv", type=float, help="multi_impulse: SPL |dv| [m/s] (default 1.53)")
    p.add_argument("--u1", type=float, help="multi_impulse: ejection argument of latitude [deg] (default 90)")


def _date(text):
    import datetime

    try:
        return datetime.date.fromisoformat(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"--date expects YYYY-MM-DD, got {text!r}") from None


def cmd_ops(args):
    from .core import ops

    cfg = ops.load_ops_config(args.ops_config)
    if args.tle:
        cfg = ops.with_tle(cfg, args.tle)
    rep = ops.plan(cfg, args.date, days=args.days)
    if args.plot:
        from .plots_ops import fig_timeline

        fig_timeline(rep, Path(args.plot))
        rep["figure"] = args.plot
    emit(rep, args.json, lambda r: ops.print_plan(r, sys.stdout))


def build_parser():
    parser = argparse.ArgumentParser(prog="roe-sep", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("design", help="nominal double-impulse separation plan")
    p.add_argument("--config", help="scenario YAML (default: the embedded BIROS/picosatellite case)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    _strategy_args(p)
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
    _strategy_args(p)
    p.set_defaults(func=cmd_mc)

    p = sub.add_parser("ops", help="operational plan of the separation day (seed 001 Sec. 5)")
    p.add_argument("--date", required=True, type=_date, help="separation date YYYY-MM-DD (UTC)")
    p.add_argument("--tle", help="carrier TLE file (2 or 3 lines); default: mean elements of config/ops.yaml")
    p.add_argument("--ops-config", help="stations/radar/camera/orbit YAML (default: config/ops.yaml)")
    p.add_argument("--days", type=float, default=2.0, help="length of the plan [days] (default 2)")
    p.add_argument("--plot", metavar="PNG", help="write the timeline figure (like seed 001 Fig. 7)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_ops)

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

    from . import cli_analysis, cli_nonlinear

    cli_nonlinear.register(sub)
    cli_analysis.register(sub)

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
