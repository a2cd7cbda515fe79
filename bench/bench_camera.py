"""Accuracy of the ejection footage's ground filter (seed 001 Sec. 2.3: |dv| to 0.2 %, 1 sigma): for ejections of a
fraction f1 of the default scenario's commanded dv, the poses of a numerically integrated truth (both spacecraft,
J2-J4, DOP853 rtol 1e-13; :func:`roe_sep.core.truth.nonlinear.pair_rhs`) with the pose model's noise
(:mod:`roe_sep.core.od.pose`), ``--draws`` noise draws each, estimated in one vectorised pass. Writes
``bench/results/camera_pose.json`` (docs/run.md, "The ejection camera", renders its figures from it).

    python bench/bench_camera.py [--draws 1000] [--seed 41]
"""

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp
from scipy.stats import chi2

from roe_sep.core.config import load_scenario
from roe_sep.core.od import pose
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.nonlinear import apply_impulse, pair_rhs, pair_state, relative_rtn

OUT = Path(__file__).resolve().parent / "results" / "camera_pose.json"
RELEASE = 1000.37  # s: between two frames of the whole-second grid
FRACTIONS = (1.0, 0.8, 0.5, 0.2, 0.1)


def truth(d, dv, times):
    kep = np.array([d.a, 1.0e-3, d.inc, 0.3, 0.0, d.u1])
    sol = solve_ivp(pair_rhs, (RELEASE, float(times[-1])), apply_impulse(pair_state(kep, kep), dv, True),
                    method="DOP853", t_eval=times, rtol=1e-13, atol=1e-7, args=([0.0, 0.0, 0.0, 0.0, 1.0], 4))
    return relative_rtn(sol.y.T)[0]


def case(d, f1, draws, seed, cam):
    dv_cmd = np.asarray(d.dv1_rtn, dtype=float)
    dv = f1 * dv_cmd
    frames = np.arange(math.ceil(RELEASE), RELEASE + pose.FOOTAGE_WINDOW, cam.frame_period)
    pos = truth(d, dv, frames)
    axes = pose.camera_axes(dv_cmd)
    keep = pose.in_view(pos, cam, axes)
    times, pos = frames[keep], pos[keep]
    cov = pose.pose_covariance(pos, cam, axes)
    z = pose.measure_poses(np.broadcast_to(pos, (draws,) + pos.shape), cam, axes, np.random.default_rng(seed))
    t0 = time.perf_counter()
    est = pose.estimate_ejection(times, z, np.broadcast_to(cov, (draws,) + cov.shape),
                                 np.full(draws, times[0] - cam.frame_period), (d.a, d.inc, d.u1, RELEASE))
    wall = time.perf_counter() - t0
    mag = float(np.linalg.norm(dv))
    rel = np.linalg.norm(est.dv, axis=1) / mag - 1.0
    s = float(rel.std(ddof=1))
    err = est.dv - dv
    nees = np.einsum("bi,bij,bj->b", err, np.linalg.inv(est.cov), err)
    return {"f1": f1, "dv_m_s": mag, "poses": int(len(times)), "footage_s": float(times[-1] - RELEASE),
            "sigma_dv_pct": 100 * s, "sigma_dv_lo_pct": 100 * s * math.sqrt((draws - 1) / chi2.ppf(0.975, draws - 1)),
            "sigma_dv_hi_pct": 100 * s * math.sqrt((draws - 1) / chi2.ppf(0.025, draws - 1)),
            "bias_dv_pct": 100 * float(rel.mean()), "nees_mean": float(nees.mean()),
            "sigma_t0_ms": 1e3 * float(np.std(est.t0 - RELEASE, ddof=1)), "estimate_wall_s": wall}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=41)
    args = ap.parse_args(argv)
    d = design(load_scenario(None).separation)
    cam = pose.PoseCamera()
    sig = pose.pose_sigma(np.array([1.0, 5.0, 10.0, cam.max_range]), cam)
    out = {"about": "bench/bench_camera.py: the ground filter of the ejection footage against a numerical J2-J4 "
                    f"truth, {args.draws} noise draws per ejection fraction f1 of the default scenario's commanded "
                    "dv (interval: 95 %, chi-square); the pose model's sigmas at 1, 5, 10 m and the pose range",
           "draws": args.draws, "seed": args.seed, "max_range_m": cam.max_range, "pixel_urad": 1e6 * cam.pixel_angle,
           "sigma_depth_cm": [100 * float(x) for x in sig[:, 2]],
           "sigma_lateral_cm": [100 * float(x) for x in sig[:, 0]],
           "cases": [case(d, f1, args.draws, args.seed, cam) for f1 in FRACTIONS]}
    OUT.write_text(json.dumps(out, indent=2, allow_nan=False) + "\n", encoding="utf-8")
    for c in out["cases"]:
        print(f"f1 {c['f1']:g}: {c['poses']} poses over {c['footage_s']:.1f} s, sigma |dv| {c['sigma_dv_pct']:.4f} % "
              f"[{c['sigma_dv_lo_pct']:.4f}, {c['sigma_dv_hi_pct']:.4f}], bias {c['bias_dv_pct']:+.5f} %, "
              f"NEES {c['nees_mean']:.2f}, sigma t0 {c['sigma_t0_ms']:.2f} ms")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
