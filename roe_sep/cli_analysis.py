"""``roe-sep deploy-sweep`` and ``roe-sep cluster``: deployment direction/velocity (seed 003 Sec. 4.2) and the
adaptive cluster separation program (seed 004). Registered into ``roe-sep`` by :func:`register`.

Human tables by default, ``--json`` for scripts; bad input raises ``ValueError``/``ConfigError``, which ``roe-sep``
turns into exit status 2 with the message.
"""

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from .cli_output import emit
from .plots import _pyplot, _save


def _float_list(what):
    def parse(text):
        try:
            values = [float(x) for x in text.split(",") if x.strip()]
        except ValueError:
            raise argparse.ArgumentTypeError(f"{what}: expected comma-separated numbers, got {text!r}") from None
        if not values or not all(math.isfinite(v) for v in values):
            raise argparse.ArgumentTypeError(f"{what}: expected finite numbers, got {text!r}")
        return tuple(values)

    return parse


# ------------------------------------------------------------------------------------------------ figures


def deployment_figures(res, out_dir):
    """deploy_distance_<i>.png (seed 003 Fig. 5: distance vs time per angle, both dv) for each inclination and
    deploy_first_orbits.png (Figs. 4, 6b: the first three orbits after a radial and a V-bar deployment)."""
    from .core.deployment import distance_curves
    from .core.orbit import mean_motion

    plt = _pyplot()
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg, paths = res.config, []
    days = res.times / 86400.0
    for ii, inc in enumerate(cfg.inclinations_deg):
        angles = list(cfg.angles_deg)
        shown = [k for k, a in enumerate(angles) if abs(a / 45.0 - round(a / 45.0)) < 1e-9] or list(range(len(angles)))
        cols = 4
        rows = int(np.ceil(len(shown) / cols))
        fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 2.5 * rows), sharex=True, squeeze=False)
        for ax, k in zip(axes.flat, shown):
            for jd, dv in enumerate(cfg.dv):
                ax.plot(days, res.distance[ii, jd, k] / 1e3, label=f"{dv:g} m/s")
            ax.set_title(f"deploy {angles[k]:g} deg", fontsize=9)
            ax.grid(alpha=0.3)
        for ax in axes.flat[len(shown):]:
            ax.axis("off")
        axes.flat[0].legend(fontsize=8)
        for ax in axes[-1]:
            ax.set_xlabel("time [day]")
        for ax in axes[:, 0]:
            ax.set_ylabel("distance [km]")
        fig.suptitle(f"CubeSat-mother craft distance, i = {inc:g} deg, {cfg.altitude / 1e3:.0f} km")
        path = out_dir / ("deploy_distance_i" + f"{inc:g}".replace(".", "p") + ".png")
        _save(fig, path, dpi=100)
        paths.append(path)
    # first three orbits (baseline inclination): radial vs V-bar deployments, both dv
    n = mean_motion(cfg.a)
    t = np.linspace(0.0, 3 * 2 * np.pi / n, 1501)[1:]  # the departure (distance 0) is off the log scale
    fig, ax = plt.subplots(figsize=(7, 4))
    shown = [(k, jd) for k, ang in enumerate(cfg.angles_deg) if ang % 90 == 0 for jd in range(len(cfg.dv))]
    if shown:
        dv_rtn = np.stack([res.dv_rtn[0, jd, k] for k, jd in shown])
        curves = distance_curves(cfg, dv_rtn, np.radians(cfg.inclinations_deg[0]), t)
        for (k, jd), d in zip(shown, curves):
            ax.plot(t * n / (2 * np.pi), d / 1e3,
                    label=f"{cfg.angles_deg[k]:g} deg, {cfg.dv[jd]:g} m/s")
    ax.set_xlabel("orbits after deployment")
    ax.set_ylabel("distance [km]")
    ax.set_yscale("log")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("first three orbits: radial deployments return to the mother craft")
    path = out_dir / "deploy_first_orbits.png"
    _save(fig, path, dpi=100)
    paths.append(path)
    return paths


def cluster_figures(prog, out_dir, samples=2000, seed=0):
    """cluster_regions.png (seed 004 Figs. 3-4: P(safe from the OS) vs delay, analytical condition vs statistical
    estimate) and cluster_program.png (Fig. 5: pair distances of the selected program, simulated, with the P* bound)."""
    from .core.cluster import (
        METHODS,
        draw,
        pair_distance_bound,
        platform_safe,
        simulated_platform_safety,
        simulated_positions,
    )

    plt = _pyplot()
    out_dir.mkdir(parents=True, exist_ok=True)
    cfg, paths = prog.config, []
    dr = draw(cfg, samples, seed)
    # the regions over a delay range wide enough to show where the analytical one ends
    wide = dataclasses.replace(cfg, max_delay=max(cfg.max_delay, 150.0), delay_step=5.0)
    d = wide.delays
    fig, ax = plt.subplots(figsize=(7, 4))
    for k, s in enumerate(cfg.sats):
        p = simulated_platform_safety(wide, dr, s, d)
        line, = ax.plot(d, p, label=f"{s.name} statistical (V = {s.velocity:g} m/s)")
        for m, (method, marker) in enumerate(zip(METHODS, "s^")):
            ok = platform_safe(dataclasses.replace(wide, method=method), s, d)
            ax.plot(d[ok], np.full(ok.sum(), 1.0 + 0.002 * (2 * k + m + 1)), marker, ms=3, color=line.get_color(),
                    label=f"{s.name} {method}: safe with P*")
    ax.axhline(cfg.p_required, color="k", ls="--", lw=0.8)
    ax.set_xlabel("separation delay [s]")
    ax.set_ylabel("P(safe from the OS)")
    ax.set_title("safe from the OS: analytical regions (envelope squares, gaussian triangles) and the "
                 "statistical P", fontsize=9)
    ax.legend(fontsize=7)
    ax.grid(alpha=0.3)
    path = out_dir / "cluster_regions.png"
    _save(fig, path, dpi=100)
    paths.append(path)
    if prog.feasible:
        members = [i for i, s in enumerate(cfg.sats) if s.cluster]
        t = np.arange(np.nanmin(prog.delays), np.nanmax(prog.delays) + cfg.horizon, cfg.time_step)
        pos = {i: simulated_positions(cfg, dr, cfg.sats[i], prog.delays[i], t) for i in members}
        fig, ax = plt.subplots(figsize=(7, 4))
        for a_, i in enumerate(members):
            for j in members[a_ + 1:]:
                dist = np.linalg.norm(pos[i] - pos[j], axis=-1)
                q = np.quantile(dist, [1.0 - cfg.p_required, 0.5, cfg.p_required], axis=0)
                line, = ax.plot(t, q[1] / 1e3, label=f"{cfg.sats[i].name}-{cfg.sats[j].name} median")
                ax.fill_between(t, q[0] / 1e3, q[2] / 1e3, color=line.get_color(), alpha=0.2)
                bound = pair_distance_bound(cfg, cfg.sats[i], prog.delays[i], cfg.sats[j], prog.delays[j], t)
                ax.plot(t, bound / 1e3, ls="--", color=line.get_color(), lw=0.8)
        ax.axhline(cfg.r_max / 1e3, color="k", ls=":", lw=0.8)
        ax.set_xlabel("time from the start of the program [s]")
        ax.set_ylabel("pair distance [km]")
        ax.set_title(f"selected program: simulated median and (1-P*, P*) quantiles, {cfg.method} P* bound (dashed)",
                     fontsize=9)
        ax.legend(fontsize=7)
        ax.grid(alpha=0.3)
        path = out_dir / "cluster_program.png"
        _save(fig, path, dpi=100)
        paths.append(path)
    return paths


# ------------------------------------------------------------------------------------------------ deploy-sweep


def deploy_config(args):
    from .core.deployment import DeploymentConfig

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
        if not (math.isfinite(args.angle_step) and 0 < args.angle_step <= 180):
            raise ValueError(f"--angle-step must be in (0, 180] deg, got {args.angle_step}")
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
    from .core.deployment import sweep

    res = sweep(deploy_config(args))
    rep = res.to_dict(curves=args.curves)
    if args.plots:
        rep["figures"] = [str(p) for p in deployment_figures(res, Path(args.plots))]
    emit(rep, args.json, print_deploy)
    return 0


# ------------------------------------------------------------------------------------------------ cluster


def cluster_report(prog, stat=None):
    """The machine-readable program (README keys)."""
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
    from .core.cluster import draw, load_cluster_config, select_program, simulate_program

    cfg = load_cluster_config(args.config)
    changes = {k: v for k, v in (("sigma_deg_s", args.sigma), ("p_required", args.p), ("r_safe", args.r_safe),
                                 ("r_max", args.r_max), ("method", args.method)) if v is not None}
    cfg = dataclasses.replace(cfg, **changes).validate()
    if args.samples is not None and args.samples < 0:
        raise ValueError(f"--samples must be >= 0, got {args.samples}")
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
    p.add_argument("--altitude", type=float, help="circular orbit altitude [m] (default 400000)")
    p.add_argument("--inclinations", type=_float_list("--inclinations"), help="deg, comma-separated "
                   "(default 97.03,37,5)")
    p.add_argument("--dv", type=_float_list("--dv"), help="deployer dv [m/s], comma-separated (default 1.0,0.2)")
    p.add_argument("--angles", type=_float_list("--angles"), help="deg from +V-bar clockwise, comma-separated")
    p.add_argument("--angle-step", type=float, help="deg between angles from 0 (default 15)")
    p.add_argument("--days", type=float, help="free drift [days] (default 10)")
    p.add_argument("--step", type=float, help="s between samples of the distance curves (default 600)")
    p.add_argument("--density", type=float, help="atmospheric density [kg/m^3] (default 2.803e-12, USSA76 400 km)")
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
    p.add_argument("--sigma", type=float, help="1-sigma transverse angular velocity of the platform [deg/s]")
    p.add_argument("--p", type=float, help="required probability P* (default 0.997)")
    p.add_argument("--r-safe", type=float, help="keep-out radius r* [m]")
    p.add_argument("--r-max", type=float, help="largest distance inside the cluster r** [m]")
    p.add_argument("--method", choices=("envelope", "gaussian"), help="'with probability P*': every state of the "
                   "P* tumbling set (default) or the seed's Gaussian k-sigma model")
    p.add_argument("--samples", type=int, default=5000, help="statistical validation samples (0: none; default 5000)")
    p.add_argument("--seed", type=int, default=0, help="seed of the statistical validation (default 0)")
    p.add_argument("--plots", metavar="DIR", help="write the figures (PNG) to DIR")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_cluster)
