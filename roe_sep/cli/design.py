"""``roe-sep design`` and ``roe-sep mc``: the separation design (double impulse, seeds 000/002; multi-impulse, seed
001) and its Monte Carlo (the p sweep of Table 3; the multi-impulse acceptance criteria AC1-AC3)."""

import dataclasses
import math
import sys
from pathlib import Path

from ..core.config import load_scenario
from ..core.montecarlo import streaming
from ..core.separation.double_impulse import DoubleImpulseDesign, design
from ..engine import auto_batch, cluster, ordered_map
from .common import SAMPLES_MAX, emit, finite_float, integer, p_list, positive_int, seed, vec


def design_report(d: DoubleImpulseDesign) -> dict:
    """The machine-readable design: every key docs/cli.md documents (SI units, angles in deg where named)."""
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

def print_design(rep: dict, out=None):
    b = rep["bounds"]
    w = (out or sys.stdout).write
    w("Double-impulse separation design (seeds 000/002, Eqs. 9-21)\n")
    w(f"  carrier orbit     a = {rep['a']:.1f} m   n = {rep['n']:.6e} rad/s   i = {rep['inclination_deg']:.3f} deg\n")
    w(f"  ejection (SPL)    u1 = {rep['u1_deg']:8.3f} deg   dv1 RTN = {vec(rep['dv1_rtn'])} m/s "
      "(picosat rel. carrier)\n")
    w(f"  drift-stop        u2 = {rep['u2_deg']:8.3f} deg   dv2 RTN = {vec(rep['dv2_rtn'])} m/s (relative effect)\n")
    w(f"                    k = {rep['k']} (admissible {rep['k_admissible']})   carrier burns "
      f"{vec(rep['dv2_carrier_rtn'])} m/s\n")
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

def progress_bar(total, desc):
    """A tqdm bar with ETA on stderr when stderr is a terminal, else None; call ``bar.update(n)``, ``bar.close()``."""
    if not sys.stderr.isatty():
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="sample", unit_scale=True, leave=False, file=sys.stderr)


def mc_config(scenario, args):
    """The scenario's Monte Carlo settings with the command line's overrides (seed resolved to an int)."""
    overrides = {}
    if args.samples is not None:
        overrides["samples"] = args.samples
    if args.seed is not None:
        overrides["seed"] = args.seed
    if args.no_drag:
        overrides["drag"] = False
    if args.j2:
        overrides["j2"] = True
    mc = dataclasses.replace(scenario.monte_carlo, **overrides)
    return dataclasses.replace(mc, seed=streaming.resolve_seed(mc.seed))


def streamed(fn, total, args, desc):
    """Run ``fn(mapper, on_chunk)`` on the engine chosen by ``--workers``/``--scheduler`` with a progress bar."""
    bar = progress_bar(total, desc)
    try:
        with cluster(workers=args.workers, scheduler=args.scheduler) as client:
            def mapper(f, items, *a):
                items = list(items)
                return ordered_map(client, f, items, *a, batch=auto_batch(client, len(items)))

            return fn(mapper, bar.update if bar is not None else None)
    finally:
        if bar is not None:
            bar.close()


PLOT_SAMPLES_MAX = 1_000_000  # --plots keeps every sample in memory (about 1.7 kB each)


def run_stream(scenario, args):
    """The streamed p sweep of ``roe-sep mc`` (double impulse): (report dict, design, mc, stats)."""
    mc = mc_config(scenario, args)
    p_values = args.p if args.p is not None else scenario.p_values
    if args.plots and mc.samples > PLOT_SAMPLES_MAX:
        raise ValueError(f"--plots keeps every sample in memory: at most {PLOT_SAMPLES_MAX} samples, "
                         f"got --samples {mc.samples}")
    d = design(separation_config(scenario, args))
    stats = streamed(lambda mapper, on_chunk: streaming.stream_sweep(
        d, mc, p_values, args.chunk_size, mapper=mapper, on_chunk=on_chunk), mc.samples, args, "mc")
    rep = streaming.report(stats, mc, args.chunk_size)
    rep["workers"] = args.workers
    rep["scheduler"] = args.scheduler
    return rep, d, mc, stats


def _cell(row, key):
    k, (lo, hi) = row[f"n_{key[2:]}"], row[f"{key}_ci95"]
    return f"{k} [{lo:.3%},{hi:.3%}]"


PROB_COLUMNS = (("p_approach", "P(approach)", "{:11.3%}"), ("p_evaporation", "P(evap.)", "{:9.3%}"),
                ("p_below_radar_horizon", "P(<5km@24h)", "{:11.3%}"), ("p_min_rn_violation", "P(RN<min)", "{:9.3%}"),
                ("p_fov_violation", "P(FOV)", "{:8.3%}"), ("p_table2_violation", "P(>Tab.2)", "{:9.3%}"))


def print_sweep(res: dict, out=None):
    w = (out or sys.stdout).write
    w(f"Monte Carlo p sweep: {res['samples']} samples, seed {res['seed']}, drag {'on' if res['drag'] else 'off'}, "
      f"J2 {'on' if res['j2'] else 'off'}, dB = {res['delta_b']:.5f} m^2/kg\n")
    cols = (("p", "p [m/s]", "{:9.4f}"),) + PROB_COLUMNS + (("a_dl_horizon_mean", "mean a dl@24h", "{:13.0f}"),)
    w("  " + "  ".join(f"{h:>{len(fmt.format(0.0))}s}" for _, h, fmt in cols) + "\n")
    for row in res["rows"]:
        mark = "  <- p_best" if row["p"] == res["p_best"] else ""
        w("  " + "  ".join(fmt.format(row[k]) for k, _, fmt in cols) + mark + "\n")
    w("  counts and Wilson 95 % intervals\n")
    width = {k: max(len(h), *(len(_cell(r, k)) for r in res["rows"])) for k, h, _ in PROB_COLUMNS}
    w("  " + f"{'p [m/s]':>9s}  " + "  ".join(f"{h:>{width[k]}s}" for k, h, _ in PROB_COLUMNS) + "\n")
    for row in res["rows"]:
        w("  " + f"{row['p']:9.4f}  " + "  ".join(f"{_cell(row, k):>{width[k]}s}" for k, _, _ in PROB_COLUMNS)
          + "\n")
    w(f"  p_best = {res['p_best']:g} m/s (minimum of P(approach) + P(evaporation))\n")
    within = res["crossing_min_within_3sigma_f1"]
    w(f"  nearest R=0 transit before the drift-stop: min {res['crossing_min']:.0f} m over all samples, "
      + (f"{within:.0f} m" if within is not None else "none") + f" for f1 >= {res['f1_3sigma']:.2f}\n")


STRATEGIES = ("double_impulse", "multi_impulse")

SWEEP_NULLS = {"crossing_min_within_3sigma_f1": "no sample with f1 >= 1 - 3 sigma (too few samples)"}
STREAM_SAMPLES_MAX = 10**10  # the streamed sweep keeps counts only: memory does not grow with the sample count
stream_samples = integer(1, STREAM_SAMPLES_MAX)


def _ejection_overrides(args) -> dict:
    """``--spl-dv`` and ``--u1`` as config fields (both strategies name them ``spl_dv`` and ``u1_deg``)."""
    return {k: v for k, v in (("spl_dv", args.spl_dv), ("u1_deg", args.u1)) if v is not None}


def separation_config(scenario, args):
    """The scenario's double-impulse inputs with ``--spl-dv`` and ``--u1`` applied (they override
    ``separation.spl_dv`` and ``separation.u1_deg``)."""
    return dataclasses.replace(scenario.separation, **_ejection_overrides(args))


def _multi_design(scenario, args):
    from ..core.separation import multi_impulse

    mcfg = dataclasses.replace(multi_impulse.MultiImpulseConfig(), **_ejection_overrides(args))
    return multi_impulse.design(scenario.separation, mcfg, scenario.monte_carlo)

def print_multi_design(rep: dict, out=None):
    w = (out or sys.stdout).write
    a = rep["a"]
    w("Multi-impulse separation design (seed 001 Sec. 3)\n")
    w(f"  carrier orbit     a = {a:.1f} m   n = {rep['n']:.6e} rad/s   i = {rep['inclination_deg']:.3f} deg\n")
    w(f"  ejection (SPL)    u1 = {rep['u1_deg']:8.3f} deg   dv RTN = {vec(rep['ejection_dv_rtn'])} m/s "
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
        from ..core.separation.multi_impulse import design_report as multi_report

        emit(multi_report(_multi_design(scenario, args)), args.json, print_multi_design)
        return
    emit(design_report(design(separation_config(scenario, args))), args.json, print_design)

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
        from ..core.montecarlo.acceptance import run as run_acceptance

        scenario = load_scenario(args.config)
        overrides = {k: v for k, v in (("samples", args.samples), ("seed", args.seed)) if v is not None}
        if args.no_drag:
            overrides["drag"] = False
        if args.j2:
            overrides["j2"] = True
        if args.p is not None:
            raise ValueError("--p applies to the double_impulse sweep only (multi_impulse sizes p by Eq. 21)")
        if args.samples is not None and args.samples > SAMPLES_MAX:
            raise ValueError(f"--samples {args.samples}: the multi_impulse acceptance Monte Carlo holds every sample "
                             f"in memory: at most {SAMPLES_MAX}")
        if args.workers is not None or args.scheduler is not None or args.chunk_size != streaming.DEFAULT_CHUNK_SIZE:
            raise ValueError("--workers, --scheduler and --chunk-size apply to the double_impulse sweep only")
        mc = dataclasses.replace(scenario.monte_carlo, **overrides)
        res = run_acceptance(_multi_design(scenario, args), mc)
        rep = res.to_dict()
        if args.plots:
            from ..plots.acceptance import write_acceptance_figures

            rep["figures"] = [str(p) for p in write_acceptance_figures(res, Path(args.plots))]
        emit(rep, args.json, print_acceptance)
        return
    rep, d, mc, stats = run_stream(load_scenario(args.config), args)
    if args.plots:
        from ..plots.montecarlo import write_figures

        res = streaming.in_memory_result(d, mc, stats)
        rep["figures"] = [str(p) for p in write_figures(res, Path(args.plots))]
    emit(rep, args.json, print_sweep, why=SWEEP_NULLS)

def _strategy_args(p):
    p.add_argument("--strategy", choices=STRATEGIES, default="double_impulse",
                   help="separation strategy (default double_impulse; multi_impulse: seed 001)")
    p.add_argument("--spl-dv", type=finite_float(0.0, 10.0, lo_open=True, unit="m/s"),
                   help="SPL ejection |dv| [m/s] in (0, 10] (default: double_impulse the scenario's "
                   "separation.spl_dv, 1.41; multi_impulse 1.53)")
    p.add_argument("--u1", type=finite_float(-360.0, 360.0, unit="deg"),
                   help="ejection mean argument of latitude [deg] in [-360, 360] (default: double_impulse the "
                   "scenario's separation.u1_deg, 88; multi_impulse 90)")

def register(subparsers):
    """Add ``design`` and ``mc`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("design", help="nominal double-impulse separation plan")
    p.add_argument("--config", help="scenario YAML (default: the embedded BIROS/picosatellite case)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    _strategy_args(p)
    p.set_defaults(func=cmd_design)

    p = subparsers.add_parser("mc", help="Monte Carlo sweep over the drift-stop reduction p")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--samples", type=stream_samples,
                   help=f"number of samples in [1, {STREAM_SAMPLES_MAX:.0e}] (default 100000; multi_impulse at most "
                        f"{SAMPLES_MAX})")
    p.add_argument("--seed", type=seed(), help="random seed in [0, 2**32 - 1] (default from the scenario: 0)")
    p.add_argument("--p", type=p_list, help="comma-separated p values [m/s], each in [0, 1] (double_impulse only)")
    p.add_argument("--no-drag", action="store_true", help="switch differential drag off")
    p.add_argument("--j2", action="store_true", help="include secular J2 in the propagation")
    p.add_argument("--plots", metavar="DIR", help="write the figures (PNG) to DIR (at most 1e6 samples)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    engine_args(p)
    _strategy_args(p)
    p.set_defaults(func=cmd_mc)


def engine_args(p):
    """--chunk-size, --workers, --scheduler: the streamed Monte Carlo's chunking and its Dask engine."""
    p.add_argument("--chunk-size", type=positive_int, default=streaming.DEFAULT_CHUNK_SIZE,
                   help=f"samples per vectorized chunk, a multiple of {streaming.BLOCK_SIZE} "
                        f"(default {streaming.DEFAULT_CHUNK_SIZE}); the result does not depend on it")
    p.add_argument("--workers", type=integer(1, 256),
                   help="distribute the chunks over W local Dask worker processes (127.0.0.1)")
    p.add_argument("--scheduler", metavar="ADDRESS", help="distribute over an existing Dask scheduler (tcp://host:port)")
