"""``roe-sep deploy-sweep`` and ``roe-sep cluster``: deployment direction/velocity (seed 003 Sec. 4.2) and the
adaptive cluster separation program (seed 004). Registered into ``roe-sep`` by :func:`register`.

Human tables by default, ``--json`` for scripts; bad input raises ``ValueError``/``ConfigError``, which ``roe-sep``
turns into exit status 2 with the message.
"""

import dataclasses
import sys
from pathlib import Path

import numpy as np

from ..plots.analysis import cluster_figures, deployment_figures
from .common import emit, finite_float, float_list, integer, seed


def deploy_config(args):
    from ..core.deployment.sweep import DeploymentConfig

    cfg = DeploymentConfig()
    changes = {}
    for name in ("altitude", "days", "density", "step"):
        if getattr(args, name) is not None:
            changes[name] = getattr(args, name)
    if args.inclinations is not None:
        changes["inclinations_deg"] = args.inclinations
    if args.dv is not None:
        changes["dv"] = args.dv
    if args.angles is not None:
        changes["angles_deg"] = args.angles
    elif args.angle_step is not None:
        changes["angles_deg"] = tuple(float(a) for a in np.arange(0.0, 360.0 - 1e-9, args.angle_step))
    if args.no_drag:
        changes["drag"] = False
    if args.no_j2:
        changes["j2"] = False
    if args.model is not None:
        changes["model"] = args.model
    return dataclasses.replace(cfg, **changes).validate()


def print_deploy(rep, out=None):
    w = (out or sys.stdout).write
    cfg = rep["config"]
    w(f"Deployment sweep (seed 003 Sec. 4.2): circular {cfg['altitude'] / 1e3:.0f} km, {rep['days']:g} days, "
      f"{rep['propagation']}\n  drag {'on' if cfg['drag'] else 'off'} (dB = {rep['delta_b']:.5f} m^2/kg, "
      f"rho = {cfg['density']:.3e} kg/m^3), J2 {'on' if cfg['j2'] else 'off'}\n")
    w("  angle from +V-bar, clockwise: 90 = +R-bar (nadir), 180 = -V-bar; first-orbit minimum over [T/2, 3T/2]\n")
    for s in rep["summary"]:
        w(f"\n  i = {s['inclination_deg']:.2f} deg, dv = {s['dv']:g} m/s\n")
        w(f"  {'angle':>7s}  {'dv_R':>7s}  {'dv_T':>7s}  {'min 1st orbit [m]':>17s}  {'t_min [s]':>9s}  "
          f"{'d(end) [km]':>11s}  {'max d [km]':>10s}\n")
        for c in rep["cases"]:
            if c["inclination_deg"] == s["inclination_deg"] and c["dv"] == s["dv"]:
                w(f"  {c['angle_deg']:7.1f}  {c['dv_rtn'][0]:+7.3f}  {c['dv_rtn'][1]:+7.3f}  "
                  f"{c['min_distance_first_orbit_m']:17.1f}  {c['t_min_first_orbit_s']:9.0f}  "
                  f"{c['distance_end_m'] / 1e3:11.1f}  {c['max_distance_m'] / 1e3:10.1f}\n")
        w(f"  largest distance after {rep['days']:g} d: {s['max_distance_end_m'] / 1e3:.1f} km at "
          f"{s['max_angle_deg']:g} deg; smallest: {s['min_distance_end_m'] / 1e3:.1f} km at "
          f"{s['min_angle_deg']:g} deg\n")


def cmd_deploy_sweep(args):
    from ..core.deployment.sweep import sweep

    res = sweep(deploy_config(args))
    rep = res.to_dict(curves=args.curves)
    if args.plots:
        rep["figures"] = [str(p) for p in deployment_figures(res, Path(args.plots))]
    emit(rep, args.json, print_deploy)
    return 0


# ------------------------------------------------------------------------------------------------ cluster


def cluster_report(prog, stat=None):
    """The machine-readable program (the documented keys)."""
    cfg = prog.config
    names = [s.name for s in cfg.sats]
    rep = {
        "feasible": prog.feasible,
        "names": names,
        "cluster": [s.cluster for s in cfg.sats],
        "delays_s": [None if not np.isfinite(d) else float(d) for d in prog.delays],
        "velocities_mps": [s.velocity for s in cfg.sats],
        "delta_q": [s.delta_q for s in cfg.sats],
        "max_pair_distance_m": None if not np.isfinite(prog.max_pair_distance) else prog.max_pair_distance,
        "platform_delay_max_s": [None if not np.isfinite(d) else float(d) for d in prog.platform_delay_max],
        "pair_regions": [{"pair": [names[i], names[j]], **r} for (i, j), r in prog.pair_regions.items()],
        "p_required": cfg.p_required,
        "p_safe": None,
        "config": dataclasses.asdict(cfg),
    }
    if stat is not None:
        rep["p_safe"] = stat["p_safe"]
        rep["statistical"] = {
            "samples": stat["samples"], "seed": stat["seed"],
            "p_platform": dict(zip(names, stat["p_platform"])),
            "p_pairs": [{"pair": [names[i], names[j]], **v} for (i, j), v in stat["p_pairs"].items()],
            "max_pair_distance_quantile_m": stat["max_pair_distance_quantile"],
        }
    return rep


def print_cluster(rep, out=None):
    w = (out or sys.stdout).write
    cfg = rep["config"]
    w(f"Cluster separation program (seed 004): {cfg['altitude'] / 1e3:.0f} km, rho = {cfg['density']:.3e} kg/m^3, "
      f"sigma = {cfg['sigma_deg_s']:g} deg/s, P* = {cfg['p_required']:g}, r* = {cfg['r_safe']:g} m, "
      f"r** = {cfg['r_max']:g} m over {cfg['turns']:g} turns, method {cfg['method']}\n")
    w(f"  {'NS':6s} {'cluster':>7s} {'V [m/s]':>8s} {'dQ [m^2/kg]':>12s} {'delay [s]':>10s} "
      f"{'OS-safe delays [s]':>20s}\n")
    for k, name in enumerate(rep["names"]):
        d = rep["delays_s"][k]
        dm = rep["platform_delay_max_s"][k]
        region = "none" if dm is None else f"[{cfg['min_delay']:g}, {dm:g}]"
        w(f"  {name:6s} {'yes' if rep['cluster'][k] else 'no':>7s} {rep['velocities_mps'][k]:8.2f} "
          f"{rep['delta_q'][k]:12.4f} {'-' if d is None else f'{d:.0f}':>10s} {region:>20s}\n")
    for r in rep["pair_regions"]:
        lo, hi = r["min_delay_difference_s"], r["max_delay_difference_s"]
        w(f"  pair {r['pair'][0]}-{r['pair'][1]}: safe for delay difference >= {lo if lo is not None else 'none'} s,"
          f" within r** for <= {hi if hi is not None else 'none'} s (after {r['first']} at {r['at_delay_s']:g} s)\n")
    if rep["feasible"]:
        w(f"  minimax: largest pair distance (P* bound) = {rep['max_pair_distance_m']:.0f} m\n")
    else:
        w("  NO FEASIBLE PROGRAM on the delay grid: the analytical conditions (3)-(4) cannot all hold\n")
    if rep.get("statistical", {}).get("samples"):
        s = rep["statistical"]
        w(f"  statistical check ({s['samples']} samples, seed {s['seed']}): P(all conditions) = {rep['p_safe']:.4f}, "
          f"P* quantile of the largest cluster distance = {s['max_pair_distance_quantile_m']:.0f} m\n")


def cmd_cluster(args):
    from ..core.deployment.cluster import draw, load_cluster_config, select_program, simulate_program

    cfg = load_cluster_config(args.config)
    changes = {k: v for k, v in (("sigma_deg_s", args.sigma), ("p_required", args.p), ("r_safe", args.r_safe),
                                 ("r_max", args.r_max), ("method", args.method)) if v is not None}
    cfg = dataclasses.replace(cfg, **changes).validate()
    prog = select_program(cfg)
    stat = None
    if prog.feasible and args.samples:
        stat = simulate_program(cfg, prog.delays, draw(cfg, args.samples, args.seed))
        stat.update(samples=args.samples, seed=args.seed)
    rep = cluster_report(prog, stat)
    if args.plots:
        rep["figures"] = [str(p) for p in cluster_figures(prog, Path(args.plots), samples=args.samples or 2000,
                                                          seed=args.seed)]
    emit(rep, args.json, print_cluster)
    return 0 if prog.feasible else 1


def register(subparsers):
    """Add ``deploy-sweep`` and ``cluster`` to the ``roe-sep`` sub-command parser."""
    p = subparsers.add_parser("deploy-sweep", help="CubeSat deployment direction/velocity sweep (seed 003 Sec. 4.2)")
    p.add_argument("--altitude", type=finite_float(100e3, 5000e3, unit="m"),
                   help="circular orbit altitude [m] in [100000, 5000000]; [200000, 1100000) for the nonlinear "
                   "model (default 400000)")
    p.add_argument("--inclinations", type=float_list(0.0, 180.0, lo_open=True, hi_open=True, unit="deg"),
                   help="deg, comma-separated, each in (0, 180) (default 97.03,37,5)")
    p.add_argument("--dv", type=float_list(0.0, 100.0, lo_open=True, unit="m/s"),
                   help="deployer dv [m/s], comma-separated, each in (0, 100] (default 1.0,0.2)")
    p.add_argument("--angles", type=float_list(-360.0, 360.0, unit="deg"),
                   help="deg from +V-bar clockwise, comma-separated, each in [-360, 360]")
    p.add_argument("--angle-step", type=finite_float(0.0, 180.0, lo_open=True, unit="deg"),
                   help="deg between angles from 0, in (0, 180] (default 15)")
    p.add_argument("--days", type=finite_float(0.0, 60.0, lo_open=True, unit="days"),
                   help="free drift [days] in (0, 60] (default 10)")
    p.add_argument("--step", type=finite_float(1.0, 86400.0, unit="s"),
                   help="s between samples of the distance curves, in [1, 86400] and at most days/4 (default 600)")
    p.add_argument("--density", type=finite_float(0.0, 1e-6, unit="kg/m^3"),
                   help="atmospheric density [kg/m^3] in [0, 1e-6] (default 2.803e-12, USSA76 400 km)")
    p.add_argument("--no-drag", action="store_true", help="switch differential drag off")
    p.add_argument("--no-j2", action="store_true", help="switch J2 off (needs --model linear)")
    p.add_argument("--model", choices=("nonlinear", "linear"), help="relative motion: numerical J2-J4 + drag "
                   "(default) or the secular ROE model")
    p.add_argument("--curves", action="store_true", help="include the full distance-vs-time curves in --json")
    p.add_argument("--plots", metavar="DIR", help="write the figures (PNG) to DIR")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_deploy_sweep)

    p = subparsers.add_parser("cluster", help="separation program of a nanosatellite cluster from a tumbling "
                              "platform (seed 004)")
    p.add_argument("--config", help="cluster YAML (default: the embedded Soyuz-stage example, config/cluster.yaml)")
    p.add_argument("--sigma", type=finite_float(0.0, 90.0, lo_open=True, unit="deg/s"),
                   help="1-sigma transverse angular velocity of the platform [deg/s] in (0, 90]")
    p.add_argument("--p", type=finite_float(0.5, 1.0, hi_open=True),
                   help="required probability P* in [0.5, 1) (default 0.997)")
    p.add_argument("--r-safe", type=finite_float(0.0, 1e6, lo_open=True, unit="m"),
                   help="keep-out radius r* [m] in (0, 1e6]")
    p.add_argument("--r-max", type=finite_float(0.0, 1e7, lo_open=True, unit="m"),
                   help="largest distance inside the cluster r** [m] in (0, 1e7], larger than r*")
    p.add_argument("--method", choices=("envelope", "gaussian"), help="'with probability P*': every state of the "
                   "P* tumbling set (default) or the seed's Gaussian k-sigma model")
    p.add_argument("--samples", type=integer(0, 1_000_000), default=5000,
                   help="statistical validation samples in [0, 1000000] (0: none; default 5000)")
    p.add_argument("--seed", type=seed(), default=0, help="seed of the statistical validation (default 0)")
    p.add_argument("--plots", metavar="DIR", help="write the figures (PNG) to DIR")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_cluster)
