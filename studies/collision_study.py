"""Study: why importance sampling stalls for R = 1 m, where the collisions lie, and the bounds it leaves
(issue 17). For each p: the cross-entropy levels (as ``roe-sep collision --method is``), the closest approaches
among fresh samples of the stalled proposal (distance, radius |z| in the standard-normal dispersion space, the SPL
factor f1), a design-point search (SLSQP: min |z| s.t. d(z) <= R) from the closest sample, and the Gaussian mass
outside the ball of the radius reached (chi-square, 9 degrees of freedom). Strict JSON on stdout, one line per p.

    python studies/collision_study.py --p 0,0.06 > collision_study.json
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep.core.montecarlo import collision as c  # noqa: E402
from roe_sep.core.montecarlo.allocator import keep_freed_memory  # noqa: E402
from roe_sep.core.montecarlo.sweep import MonteCarloConfig  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402


def study(d, p, r, ce_samples, probe, seed, maxiter):
    t0 = time.process_time()
    mc = MonteCarloConfig(samples=probe, seed=seed)
    cfg = c.CollisionConfig(hard_body_radius=r, p=p)
    prop, levels, reached = c.cross_entropy(d, mc, cfg, samples_per_level=ce_samples, max_levels=14)
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(c.IS_STREAM, 2)))
    z = prop.sample(rng, probe)
    dist = c.min_distance(d, mc, c.draws_from_normal(d, mc, z), cfg)
    order = np.argsort(dist)[:10]
    closest = [{"distance_m": float(dist[i]), "radius": float(np.linalg.norm(z[i])), "f1": 1.0 + 0.1 * float(z[i, 0]),
                "z": [round(float(x), 3) for x in z[i]]} for i in order]
    fine = c.CollisionConfig(hard_body_radius=r, p=p, tol_abs=1e-7, tol_rel=1e-9)
    zs, rho, runs = c.design_point(d, mc, fine, z[order[:1]], maxiter=maxiter)
    best_run = min(runs, key=lambda x: x["distance"])
    out = {"p": p, "hard_body_radius": r, "ce_levels": levels, "ce_reached_r": reached,
           "proposal_mean": [round(float(x), 3) for x in prop.mean], "dimensions": list(c.DIMENSIONS),
           "probe_samples": probe, "closest": closest, "design_point_runs": runs,
           "design_point": None if zs is None else [round(float(x), 4) for x in zs], "design_point_radius": rho,
           "nearest_point_reached": {"radius": best_run["radius"], "distance_m": best_run["distance"],
                                     "ball_mass_outside": c.ball_bound(best_run["radius"])},
           "cpu_s": time.process_time() - t0}
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--p", default="0,0.06")
    ap.add_argument("--radius", type=float, default=1.0)
    ap.add_argument("--ce-samples", type=int, default=1000)
    ap.add_argument("--probe", type=int, default=4000)
    ap.add_argument("--maxiter", type=int, default=40)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    keep_freed_memory()
    d = design()
    res = []
    for p in args.p.split(","):  # one JSON line per p as soon as it is done (a long run keeps what it has)
        res.append(study(d, float(p), args.radius, args.ce_samples, args.probe, args.seed, args.maxiter))
        print(json.dumps(res[-1], allow_nan=False, default=lambda x: None if not math.isfinite(x) else x),
              flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
