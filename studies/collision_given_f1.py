"""Study: P(collision within R | f1) of a weak ejection (the SPL delivers a fraction f1 of its impulse), with the
blind drift-stop flown as designed and with it held (no drift-stop within the horizon: what the carrier does when
it knows the ejection was weak and waits for the first OD to re-plan).

The trajectory and the certified closest approach are those of ``roe-sep collision``
(:mod:`roe_sep.core.montecarlo.collision`: the Monte Carlo's secular model with drag, drift-stop at reduction p,
24 h of drift after it, closest approach after the departure beyond 1 km). f1 is fixed; the other eight
dispersions (drift-stop magnitude f2, both attitude-error triples, the differential ballistic coefficient) are
drawn as the Monte Carlo draws them (brute force, ``--samples`` per f1). Held: f2 = 0, the drift-stop burn is not
flown. Each estimate is k hits of n with its Wilson 95 % interval (0 hits: the interval's upper end is the bound).
Strict JSON on stdout, one object.

    python studies/collision_given_f1.py --samples 20000 > studies/results/collision_given_f1.json
"""

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep.core.montecarlo import collision as c  # noqa: E402
from roe_sep.core.montecarlo.allocator import keep_freed_memory  # noqa: E402
from roe_sep.core.montecarlo.stats import wilson_interval  # noqa: E402
from roe_sep.core.montecarlo.sweep import MonteCarloConfig  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402

RADII = (1.0, 10.0, 100.0, 250.0)
"""m, hard-body radii reported (1 m the picosatellite's, 250 m the keep-out of the Monte Carlo's approach check)."""


def conditional(d, mc, p, f1, samples, seed, held):
    """Closest approaches [m] of ``samples`` draws with the SPL factor fixed at ``f1`` (the other eight dispersions
    standard normal from ``seed``); ``held``: the drift-stop not flown (f2 = 0)."""
    rng = np.random.default_rng(np.random.SeedSequence([seed, int(round(f1 * 1e6))]))
    z = rng.standard_normal((samples, c.N_DIM))
    draws = c.draws_from_normal(d, mc, z)
    draws.f1[:] = f1
    if held:
        draws.f2[:] = 0.0
    cfg = c.CollisionConfig(hard_body_radius=RADII[0], p=p)
    return c.min_distance(d, mc, draws, cfg)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--f1", default="0.01,0.02,0.05,0.1,0.15,0.2,0.25,0.3,0.4,0.5")
    ap.add_argument("--p", type=float, default=0.06, help="drift-stop reduction [m/s] (default p_best of seed 0)")
    ap.add_argument("--samples", type=int, default=20000)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    keep_freed_memory()
    d, mc = design(), MonteCarloConfig(samples=args.samples, seed=args.seed)
    rows = []
    for f1 in (float(x) for x in args.f1.split(",")):
        row = {"f1": f1}
        for name, held in (("blind", False), ("held", True)):
            t0 = time.process_time()
            dist = conditional(d, mc, args.p, f1, args.samples, args.seed, held)
            finite = dist[np.isfinite(dist)]
            out = {"n": int(dist.size), "returned": int(finite.size),
                   "closest_m": float(finite.min()) if finite.size else None,
                   "p0_1_m": float(np.quantile(dist, 0.001)) if np.isfinite(np.quantile(dist, 0.001)) else None}
            for r in RADII:
                k = int(np.count_nonzero(dist <= r))
                lo, hi = wilson_interval(k, dist.size)
                out[f"R{r:g}"] = {"hits": k, "p": k / dist.size, "ci95": [float(lo), float(hi)]}
            out["cpu_s"] = round(time.process_time() - t0, 1)
            row[name] = out
        rows.append(row)
        print(json.dumps(row, allow_nan=False), file=sys.stderr)
    json.dump({"p": args.p, "samples": args.samples, "seed": args.seed, "radii_m": list(RADII), "rows": rows},
              sys.stdout, allow_nan=False, indent=1)
    print()


if __name__ == "__main__":
    main()
