"""``roe-sep collision``: the probability that the picosatellite, once beyond the departure distance, comes back
within a hard-body radius of the carrier before the horizon (:mod:`roe_sep.core.montecarlo.collision`), brute force
(``mc``, the draws of ``roe-sep mc``) or by cross-entropy importance sampling (``is``)."""

import dataclasses
import math
import sys

from ..core.config import load_scenario
from ..core.montecarlo import streaming
from ..core.separation.double_impulse import design
from .common import SAMPLES_MAX, emit, finite_float, integer, samples, seed
from .design import engine_args, mc_config, streamed

IS_SAMPLES = 20_000  # default final importance-sampling samples


# The options' ranges. --p: as ``roe-sep mc --p``, beyond 1 m/s a reduction exceeds any drift-stop burn of the
# design. --departure-distance: two spacecraft of one low orbit are never farther apart than its diameter (< 2e7 m);
# --hard-body-radius: below half the departure distance (checked with it). --ce-samples: the elite set (the rho = 0.1
# quantile) must hold at least 10 points, one more than the 9 dimensions of the Gaussian proposal fitted to it.
P_MAX = 1.0  # m/s
DEPARTURE_MAX = 1e7  # m
CE_SAMPLES_MIN = 100


def run(args) -> dict:
    from ..core.montecarlo import collision  # SciPy's statistics load with the command, not with every roe-sep call

    scenario = load_scenario(args.config)
    samples = args.samples
    if samples is None:
        samples = scenario.monte_carlo.samples if args.method == "mc" else IS_SAMPLES
    args.samples = samples
    mc = mc_config(scenario, args)
    d = design(scenario.separation)
    p_source = "--p"
    p = args.p
    if p is None:  # p_best of the scenario's own sweep, as the planner picks it
        sweep_mc = dataclasses.replace(mc, samples=scenario.monte_carlo.samples)
        stats = streamed(lambda mapper, on_chunk: streaming.stream_sweep(
            d, sweep_mc, scenario.p_values, args.chunk_size, mapper=mapper, on_chunk=on_chunk),
            sweep_mc.samples, args, "p sweep")
        p = stats.p_best()
        p_source = f"p_best of the {sweep_mc.samples}-sample sweep"
    cfg = collision.CollisionConfig(hard_body_radius=args.hard_body_radius, p=p,
                                    departure_distance=args.departure_distance)
    cfg.validate()
    extra = {}
    proposal, reached, est_cfg = None, True, cfg
    if args.method == "is":
        proposal, levels, reached = collision.cross_entropy(d, mc, cfg, samples_per_level=args.ce_samples)
        if not reached:  # estimate at the smallest level reached: an upper bound of P(d <= R)
            est_cfg = dataclasses.replace(cfg, hard_body_radius=min(lv["gamma"] for lv in levels))
        extra = {"ce_levels": levels, "ce_samples_per_level": args.ce_samples, "ce_reached_r": reached,
                 "proposal_mean": proposal.mean.tolist(),
                 "proposal_std": [math.sqrt(x) for x in proposal.cov.diagonal()],
                 "dimensions": list(collision.DIMENSIONS)}
    plan = streaming.chunk_plan(mc.samples, args.chunk_size)

    def job(mapper, on_chunk):
        total = collision.CollisionStats()
        for part in mapper(collision.evaluate_chunk, plan, d, mc, est_cfg, proposal):
            total.merge(part)
            if on_chunk is not None:
                on_chunk(part.n)
        return total

    stats = streamed(job, mc.samples, args, f"collision {args.method}")
    rep = collision.estimate(stats, est_cfg, args.method)
    if not reached:
        rep["upper_bound"] = {k: rep[k] for k in ("hard_body_radius", "p", "ci95", "relative_half_width", "ess",
                                                  "hits")}
        rep.update(p=None, ci95=None, relative_half_width=None, ess=None, hits=None,
                   hard_body_radius=cfg.hard_body_radius,
                   reason=f"the cross-entropy levels stalled at gamma = {est_cfg.hard_body_radius:.3g} m > R: "
                          "P(d <= R) <= upper_bound.p (the failure set is too thin for one Gaussian proposal)")
    rep.update(seed=mc.seed, drag=mc.drag, j2=mc.j2, horizon=mc.horizon, p_source=p_source, **extra)
    return rep


def _g(x):
    return f"{x:.3g}"


def print_collision(rep: dict, out=None):
    w = (out or sys.stdout).write
    w(f"Collision probability: back within R = {rep['hard_body_radius']:g} m of the carrier after leaving "
      f"{rep['departure_distance']:g} m, until {rep['horizon'] / 3600:g} h after the drift-stop\n")
    w(f"  p = {rep['p_reduction']:g} m/s ({rep['p_source']}), seed {rep['seed']}, drag "
      f"{'on' if rep['drag'] else 'off'}, J2 {'on' if rep['j2'] else 'off'}\n")
    est = rep if rep["p"] is not None else rep["upper_bound"]
    lo, hi = est["ci95"]
    rel = est["relative_half_width"]
    label = "P" if rep["p"] is not None else f"P <= P(d <= {est['hard_body_radius']:.3g} m) ="
    w(f"  method {rep['method']}: {label} {_g(est['p'])}   95 % interval [{_g(lo)}, {_g(hi)}]"
      + (f"   relative half-width {rel:.0%}" if rel is not None else "") + "\n")
    if rep["p"] is None:
        w(f"  ({rep['reason']})\n")
    w(f"  {rep['samples']} samples, {est['hits']} within {est['hard_body_radius']:.3g} m, effective sample size "
      f"{est['ess']:.0f}\n")
    if rep["method"] == "is":
        gam = ", ".join(f"{lv['gamma']:.3g}" for lv in rep["ce_levels"])
        w(f"  cross-entropy: {len(rep['ce_levels'])} levels of {rep['ce_samples_per_level']} samples, "
          f"gamma [m] = {gam}\n")
        w("  proposal mean [sigma]: " + "  ".join(f"{n} {m:+.2f}" for n, m in
                                                  zip(rep["dimensions"], rep["proposal_mean"])) + "\n")
    ca = rep["closest_approach_min"]
    w(f"  closest approach over the samples: {'none' if ca is None else f'{ca:.3f} m'}\n")


def cmd_collision(args):
    emit(run(args), args.json, print_collision)


def register(subparsers):
    """Add ``collision`` to the ``roe-sep`` subparsers."""
    p = subparsers.add_parser("collision", help="probability of coming back within a hard-body radius")
    p.add_argument("--hard-body-radius", type=finite_float(0.0, DEPARTURE_MAX / 2, lo_open=True, unit="m"),
                   required=True, metavar="R",
                   help="hard-body radius [m] (below half the departure distance)")
    p.add_argument("--method", choices=("mc", "is"), default="is",
                   help="mc: brute force on the draws of roe-sep mc; is: cross-entropy importance sampling "
                        "(default)")
    p.add_argument("--samples", type=samples,
                   help=f"samples of the estimator (default: mc the scenario's 100000, is {IS_SAMPLES})")
    p.add_argument("--p", type=finite_float(0.0, P_MAX, unit="m/s"),
                   help=f"drift-stop reduction in [0, {P_MAX:g}] m/s (default: p_best of the sweep)")
    p.add_argument("--seed", type=seed(), help="random seed in [0, 2**32 - 1] (default from the scenario: 0)")
    p.add_argument("--departure-distance", type=finite_float(0.0, DEPARTURE_MAX, lo_open=True, unit="m"),
                   default=1000.0,
                   help="m, approaches count once the picosatellite was this far (default 1000, as the sim)")
    p.add_argument("--ce-samples", type=integer(CE_SAMPLES_MIN, SAMPLES_MAX), default=2000,
                   help=f"is: samples per cross-entropy level, at least {CE_SAMPLES_MIN} (default 2000)")
    p.add_argument("--config", help="scenario YAML")
    p.add_argument("--no-drag", action="store_true", help="switch differential drag off")
    p.add_argument("--j2", action="store_true", help="include secular J2 in the propagation")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    engine_args(p)
    p.set_defaults(func=cmd_collision)
