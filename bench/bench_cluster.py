"""Benchmark: one pair table of the cluster program (seed 004 default, ns1-ns2, 56 x 56 delays over two orbits), the
envelope decided in cache-sized chunks vs all cases at once, and the seed's Gaussian model, side by side.

All three evaluate the same cases and times; the two envelope runs must agree exactly (checked).
"""

import argparse
import json
import time

import numpy as np

from roe_sep.core.cluster import ClusterConfig, _time_grid, drag_acceleration, pair_tables
from roe_sep.core.cluster_envelope import CHUNK_CASES, conditions


def envelope_table(cfg, si, sj, chunk):
    d = cfg.delays
    di, dj = np.meshgrid(d, d, indexing="ij")
    t = np.maximum(di, dj)[..., None] + _time_grid(cfg, 0.0, cfg.horizon)
    pi = drag_acceleration(-si.delta_q, cfg.density, cfg.a)
    pj = drag_acceleration(-sj.delta_q, cfg.density, cfg.a)
    return conditions(si.velocity, di.ravel(), pi, sj.velocity, dj.ravel(), pj, t.reshape(di.size, -1), cfg.n,
                      cfg.omega_star, cfg.r_safe, cfg.r_max, chunk=chunk)


def timed(fn, repeat):
    best, out = float("inf"), None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    cfg = ClusterConfig()
    si, sj = cfg.sats[0], cfg.sats[1]
    cases = len(cfg.delays) ** 2
    t_chunk, chunked = timed(lambda: envelope_table(cfg, si, sj, CHUNK_CASES), args.repeat)
    t_all, whole = timed(lambda: envelope_table(cfg, si, sj, cases), args.repeat)
    for a, b in zip(chunked, whole):
        assert np.array_equal(a, b), "chunked and whole envelope tables differ"
    gauss = ClusterConfig(method="gaussian")
    t_gauss, _ = timed(lambda: pair_tables(gauss, si, sj), args.repeat)
    rep = {"cases": cases, "times": int(_time_grid(cfg, 0.0, cfg.horizon).size),
           "envelope_chunked_s": t_chunk, "envelope_all_at_once_s": t_all, "gaussian_s": t_gauss,
           "chunked_speedup": t_all / t_chunk, "envelope_over_gaussian": t_chunk / t_gauss}
    if args.json:
        print(json.dumps(rep, indent=2))
    else:
        print(f"pair table ns1-ns2: {cases} delay pairs x {rep['times']} times (best of {args.repeat})")
        print(f"  envelope, chunks of {CHUNK_CASES} cases   {t_chunk:7.2f} s")
        print(f"  envelope, all cases at once   {t_all:7.2f} s   ({rep['chunked_speedup']:.1f}x slower than chunked)")
        print(f"  gaussian (seed's model)       {t_gauss:7.2f} s   (envelope {rep['envelope_over_gaussian']:.1f}x)")


if __name__ == "__main__":
    main()
