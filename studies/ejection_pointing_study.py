"""Study: the ejection turned about the orbit normal (``ejection_pointing``) on the default scenario, no DDS.

The design's ejection (seed 002: ``dv1_rtn`` at u1) is mostly radial with a small along-track part; a turn about N
by -atan(T / R) (-6.98 deg) cancels the along-track part, hence the drift: the picosatellite's relative orbit closes
on the carrier one orbit after the release. For each angle the world of an undispersed run (:func:`roe_sep.core.
truth.simulated.dispersed_truth`, ``disperse`` False) is released at u1 with the turned impulse
(:func:`~roe_sep.core.truth.contingency.rotate_about_normal`) and the relative distance sampled every second over
three orbits, in the nonlinear truth (J2-J4, drag) and the secular one: the distance one orbit (the carrier's mean
argument-of-latitude period) after the release and the closest approach between half an orbit and 1.5 orbits; over
the default draw U(-10, 10) deg (every 0.1 deg) the share that comes back inside the keep-out. With
``--reports NAME=DIR`` it also gathers closed-loop runs' report.json (``roe-sep run --seed 5 --contingency NAME
--out DIR``) into the result file.

    python studies/ejection_pointing_study.py --out bench/results/ejection_pointing.json \
        --reports ejection_pointing=out/p --reports ejection_pointing_m7=out/p7 ...
"""

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep.core.config import Scenario  # noqa: E402
from roe_sep.core.relmotion.dynamics import arg_latitude_rate  # noqa: E402
from roe_sep.core.separation.double_impulse import design  # noqa: E402
from roe_sep.core.truth.contingency import rotate_about_normal  # noqa: E402
from roe_sep.core.truth.simulated import dispersed_truth  # noqa: E402

D = design()
KEEP_OUT = 1000.0  # m, the safety monitor's keep-out sphere
PERIOD = 2.0 * math.pi / float(arg_latitude_rate(D.a, D.inc, True))


def approach(angle_deg, dynamics):
    """{distance at one orbit [m], closest in [0.5, 1.5] orbits [m], its epoch [orbits], T of the turned impulse}."""
    w = dispersed_truth(Scenario(), D, 0.0, D.u1, 0, disperse=False, dynamics=dynamics, j2=True,
                        ejection_delay_max=0.0)
    dv = rotate_about_normal(D.dv1_rtn, math.radians(angle_deg))
    w.model.apply(0.0, dv, "picosatellite")
    t = np.arange(0.0, 3.0 * PERIOD, 1.0)
    r = np.linalg.norm(w.model.rtn_at(t)[0], axis=-1)
    window = (t >= 0.5 * PERIOD) & (t <= 1.5 * PERIOD)
    k = int(np.argmin(np.where(window, r, np.inf)))
    at_one = float(np.interp(PERIOD, t, r))
    return {"at_one_orbit_m": at_one, "closest_m": float(r[k]), "closest_orbits": float(t[k] / PERIOD),
            "dv_t_m_s": float(dv[1])}


def report_row(path):
    """What a closed-loop run's report says about the contingency and its outcome."""
    rep = json.loads((Path(path) / "report.json").read_text(encoding="utf-8"))
    ap = rep.get("actual_approach") or {}
    return {"contingency": rep.get("contingency"), "safe": rep["safe"], "criteria": rep["criteria"],
            "closest_m": (ap.get("closest_approach") or {}).get("distance"),
            "closest_epoch_s": (ap.get("closest_approach") or {}).get("epoch"),
            "keep_out_violated": ap.get("keep_out_violated"), "dv_total_m_s": rep["dv_total"],
            "time_to_ic_h": None if rep.get("time_to_ic") is None else rep["time_to_ic"] / 3600.0,
            "detected": {d["name"]: d["epoch"] for d in rep["contingencies_detected"]},
            "od_epoch_s": (rep.get("od") or {}).get("epoch"),
            "ejection_estimate": {k: (rep.get("ejection_estimate") or {}).get(k) for k in ("dv_rtn", "sigma_rtn")}}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, help="the result file (JSON)")
    ap.add_argument("--reports", action="append", default=[], metavar="NAME=DIR")
    args = ap.parse_args(argv)
    cancel = -math.degrees(math.atan(D.dv1_rtn[1] / D.dv1_rtn[0]))
    out = {"period_s": PERIOD, "cancel_angle_deg": cancel, "dv1_rtn": D.dv1_rtn.tolist(), "angles": {}}
    for dynamics in ("nonlinear", "secular"):
        out["angles"][dynamics] = {f"{a:g}": approach(a, dynamics) for a in (-10.0, -7.0, -5.0, 0.0, 5.0, 10.0)}
        grid = {round(a, 2): approach(a, dynamics)["closest_m"] for a in np.arange(-7.10, -6.845, 0.01)}
        best = min(grid, key=grid.get)
        out[f"{dynamics}_min_over_angle"] = {"angle_deg": best, "closest_m": grid[best]}
    # the default draw U(-10, 10) deg: the share of turns whose first orbit comes back inside the keep-out
    turns = np.arange(-10.0, 10.0001, 0.1)
    closest = np.array([approach(a, "nonlinear")["closest_m"] for a in turns])
    inside = turns[closest < KEEP_OUT]
    out["default_draw"] = {"step_deg": 0.1, "keep_out_m": KEEP_OUT, "fraction_inside": float(inside.size / turns.size),
                           "inside_from_deg": float(inside.min()), "inside_to_deg": float(inside.max())}
    out["runs"] = {name: report_row(path) for name, path in (r.split("=", 1) for r in args.reports)}
    text = json.dumps(out, indent=1, sort_keys=True) + "\n"
    if args.out:
        args.out.write_text(text, encoding="utf-8")
    for dynamics in ("nonlinear", "secular"):
        for a, v in out["angles"][dynamics].items():
            print(f"{dynamics:9s} {a:>6s} deg: |r| at one orbit {v['at_one_orbit_m']:8.1f} m, closest "
                  f"{v['closest_m']:8.1f} m at {v['closest_orbits']:.3f} orbits (T {v['dv_t_m_s']:+.4f} m/s)")
        print(f"{dynamics}: closest over the angle {out[f'{dynamics}_min_over_angle']}")
    print(f"default draw: {out['default_draw']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
