"""Benchmark: nonlinear Monte Carlo throughput, heyoka batch mode vs a per-sample scipy solve_ivp loop, side by side.

Both integrate the same force model (J2 + drag of both spacecraft, :func:`roe_sep.core.truth.nonlinear.pair_rhs` for
scipy, the compiled Taylor integrator for heyoka) over the same span: ejection -> drift-stop (k pi) -> 24 h, for
one p. heyoka runs every sample (batch lanes over a thread pool); the scipy loop runs ``--loop-samples`` samples
(DOP853, rtol 1e-12, atol 1e-6 m) and is extrapolated linearly. Throughput per core = sample pairs / CPU second.
"""

import argparse
import math
import os
import sys
import time

import numpy as np

from roe_sep import jsonutil
from roe_sep.core.constants import R_EARTH, SECONDS_PER_DAY
from roe_sep.core.montecarlo.sweep import MonteCarloConfig, draw
from roe_sep.core.relmotion.dynamics import arg_latitude_rate
from roe_sep.core.relmotion.maneuvers import dispersed_dv
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth import nonlinear as nl
from roe_sep.core.truth.validation import MC_TOL, MC_ZONALS


def setup(d, mc, p):
    dr = draw(d, mc)
    n = mc.samples
    chief = np.array([d.a, 0.0, d.inc, 0.0, 0.0, d.u1])
    s0 = np.broadcast_to(nl.pair_state(chief, chief), (n, 12))
    s1 = nl.apply_impulse(s0, dispersed_dv(d.dv1_rtn, dr.f1, dr.eps1), np.ones(n, bool))
    dv2 = dispersed_dv(0.0 - d.drift_stop_dv(p), dr.f2, dr.eps2, 0.0 - d.drift_stop_dv(0.0))
    b_d = mc.carrier.ballistic + mc.delta_b * dr.db_factor
    return s1, dv2, b_d


def run_heyoka(s1, dv2, b_c, b_d, atm, t_stop, t_end, workers):
    s = nl.propagate_pairs(s1, 0.0, t_stop, b_c, b_d, atmosphere=atm, zonals=MC_ZONALS, tol=MC_TOL, workers=workers)
    s = nl.apply_impulse(s, dv2, np.zeros(len(s), bool))
    return nl.propagate_pairs(s, t_stop, t_end, b_c, b_d, atmosphere=atm, zonals=MC_ZONALS, tol=MC_TOL, workers=workers)


def run_scipy(s1, dv2, b_c, b_d, atm, t_stop, t_end):
    from scipy.integrate import solve_ivp

    out = np.empty_like(s1)
    for k in range(len(s1)):  # the per-sample loop this benchmark measures
        pars = np.array([b_c, b_d[k], *atm.pars()])
        kw = dict(method="DOP853", rtol=1e-12, atol=1e-6, args=(pars, MC_ZONALS))
        y = solve_ivp(nl.pair_rhs, (0.0, t_stop), s1[k], **kw).y[:, -1]
        y = nl.apply_impulse(y, dv2[k], False)
        out[k] = solve_ivp(nl.pair_rhs, (t_stop, t_end), y, **kw).y[:, -1]
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=100_000)
    ap.add_argument("--loop-samples", type=int, default=10)
    ap.add_argument("--p", type=float, default=0.06)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)

    d = design()
    mc = MonteCarloConfig(samples=args.samples)
    atm = nl.Atmosphere.scaled(mc.density, d.a - R_EARTH)
    t_stop = d.k * math.pi / float(arg_latitude_rate(d.a, d.inc, True))
    t_end = t_stop + SECONDS_PER_DAY
    b_c = mc.carrier.ballistic
    s1, dv2, b_d = setup(d, mc, args.p)

    t0 = time.perf_counter()
    nl.pair_integrator(MC_ZONALS, nl.simd_size(), MC_TOL)
    t_compile = time.perf_counter() - t0
    w0, c0 = time.perf_counter(), time.process_time()
    s_hy = run_heyoka(s1, dv2, b_c, b_d, atm, t_stop, t_end, args.workers)
    w_hy, c_hy = time.perf_counter() - w0, time.process_time() - c0

    m = args.loop_samples
    w0, c0 = time.perf_counter(), time.process_time()
    s_sp = run_scipy(s1[:m], dv2[:m], b_c, b_d[:m], atm, t_stop, t_end)
    w_sp, c_sp = time.perf_counter() - w0, time.process_time() - c0
    rel = lambda s: s[:, 6:9] - s[:, :3]  # noqa: E731
    agree = float(np.max(np.linalg.norm(rel(s_hy[:m]) - rel(s_sp), axis=1)))

    n = args.samples
    res = {
        "samples": n, "span_s": t_end, "cores": len(os.sched_getaffinity(0)), "simd_lanes": nl.simd_size(),
        "heyoka_compile_or_cache_s": t_compile,
        "heyoka_wall_s": w_hy, "heyoka_cpu_s": c_hy,
        "heyoka_pairs_per_s": n / w_hy, "heyoka_pairs_per_cpu_s": n / c_hy,
        "scipy_loop_samples": m, "scipy_pairs_per_cpu_s": m / c_sp, "scipy_wall_s_extrapolated": w_sp * n / m,
        "ratio_per_core": (n / c_hy) / (m / c_sp),
        "max_relative_position_difference_m": agree,
    }
    if args.json:
        jsonutil.dump(res, sys.stdout)
        print()
        return 0
    print(f"nonlinear Monte Carlo, {n} sample pairs, ejection -> drift-stop -> +24 h ({t_end / 3600:.1f} h), "
          f"{res['cores']} cores, {res['simd_lanes']} SIMD lanes")
    print(f"  heyoka compile (or cache hit): {t_compile:.1f} s")
    print(f"  heyoka batch : {w_hy:8.1f} s wall, {c_hy:8.1f} s CPU  -> {n / w_hy:8.0f} pairs/s, "
          f"{n / c_hy:8.0f} pairs/s per core")
    print(f"  scipy loop   : {m} samples in {c_sp:.1f} s CPU -> {m / c_sp:8.1f} pairs/s per core "
          f"(extrapolated {w_sp * n / m / 3600:.1f} h wall for {n})")
    print(f"  ratio (per core) heyoka / scipy = {res['ratio_per_core']:.0f}x; relative positions agree to "
          f"{agree * 1e3:.2f} mm")
    return 0


if __name__ == "__main__":
    sys.exit(main())
