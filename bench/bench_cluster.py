"""Benchmark: one pair table of the cluster program (seed 004 default, ns1-ns2, 56 x 56 delays over two orbits), the
envelope decided in cache-sized chunks (``cluster_envelope.CHUNK_CASES``) vs all cases at once, and the seed's
Gaussian model, side by side.

All three go through :func:`roe_sep.core.deployment.cluster.pair_tables`; the two envelope runs must agree exactly
(checked).
"""

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from timing import best_of  # noqa: E402

from roe_sep import jsonutil
from roe_sep.core.deployment import cluster_envelope
from roe_sep.core.deployment.cluster import ClusterConfig, _time_grid, pair_tables  # noqa: E402


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    cfg = ClusterConfig()
    si, sj = cfg.sats[0], cfg.sats[1]
    cases, times = len(cfg.delays) ** 2, _time_grid(cfg, 0.0, cfg.horizon).size
    chunk = cluster_envelope.CHUNK_CASES
    t_chunk, chunked = best_of(lambda: pair_tables(cfg, si, sj), args.repeat)
    cluster_envelope.CHUNK_CASES = cases  # every case at once
    try:
        t_all, whole = best_of(lambda: pair_tables(cfg, si, sj), args.repeat)
    finally:
        cluster_envelope.CHUNK_CASES = chunk
    for a, b in zip(chunked, whole):
        assert np.array_equal(a, b), "chunked and whole envelope tables differ"
    t_gauss, _ = best_of(lambda: pair_tables(ClusterConfig(method="gaussian"), si, sj), args.repeat)
    rep = {"cases": cases, "times": times, "chunk_cases": chunk,
           "envelope_chunked_s": t_chunk, "envelope_all_at_once_s": t_all, "gaussian_s": t_gauss,
           "chunked_speedup": t_all / t_chunk, "envelope_over_gaussian": t_chunk / t_gauss}
    if args.json:
        print(jsonutil.dumps(rep))
    else:
        print(f"pair table ns1-ns2: {cases} delay pairs x {times} times (best of {args.repeat})")
        print(f"  envelope, chunks of {chunk} cases   {t_chunk:7.2f} s")
        print(f"  envelope, all cases at once   {t_all:7.2f} s   ({rep['chunked_speedup']:.1f}x slower than chunked)")
        print(f"  gaussian (seed's model)       {t_gauss:7.2f} s   (envelope {rep['envelope_over_gaussian']:.1f}x)")


if __name__ == "__main__":
    main()
