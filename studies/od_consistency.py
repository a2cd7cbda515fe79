"""Study: is the radar OD's covariance honest against the nonlinear truth? (a deterministic OD ensemble, no DDS)

:func:`roe_sep.core.od.ensemble.run_ensemble`: MEMBERS truth pairs (J2-J4 and drag, the differential ballistic
coefficient dispersed) from just after the drift-stop, with acquisition-sized burns, each observed with DRAWS radar
noise sequences; the OD after every counted pass as radar_od runs it, with and without the drift prior carried
across the burns. The table: for the first and the last solution of every chain, the mean 7-state NEES, 6-state
(ROE) NEES against the instantaneous mean ROE and drift-rate z^2 with their chi-square 95 % bands, the fraction
inside the single-run 95 % bounds, and the mean drift-rate sigma.

    python studies/od_consistency.py [--members 128] [--draws 2] [--seed 0] [--json]
"""

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep import jsonutil  # noqa: E402
from roe_sep.core.od.ensemble import consistency, run_ensemble  # noqa: E402


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--members", type=int, default=128)
    p.add_argument("--draws", type=int, default=2)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--json", action="store_true")
    args = p.parse_args(argv)
    out = {}
    for prior in (False, True):
        t0 = time.monotonic()
        sols = run_ensemble(args.members, args.draws, seed=args.seed, prior=prior)
        out["prior" if prior else "no_prior"] = {
            "seconds": time.monotonic() - t0, "solutions": len(sols),
            **{w: consistency(sols, w) for w in ("first", "last", "all")}}
    if args.json:
        print(jsonutil.dumps(out))
        return 0
    print(f"OD ensemble: {args.members} truth pairs x {args.draws} noise draws, seed {args.seed}")
    print(f"{'':24s}{'n':>5s} {'NEES7':>6s} {'band':>14s} {'NEES6':>6s} {'band':>14s} {'z^2':>6s} {'band':>14s}"
          f" {'in95 NEES7':>10s} {'in95 z':>7s} {'sigma m/day':>11s}")
    for key, res in out.items():
        for w in ("first", "last", "all"):
            c = res[w]
            bands = [f"[{c[b][0]:.2f}, {c[b][1]:.2f}]" for b in ("nees7_band", "nees6_band", "z2_band")]
            print(f"{key + ' ' + w:24s}{c['n']:5d} {c['nees7']:6.2f} {bands[0]:>14s} {c['nees6']:6.2f} "
                  f"{bands[1]:>14s} {c['z2']:6.2f} {bands[2]:>14s} {c['inside95_nees7']:10.3f} "
                  f"{c['inside95_z']:7.3f} {c['sigma_m_per_day']:11.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
