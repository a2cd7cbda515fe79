"""Issue 42 (a): the statistics of two campaigns on the same seeds, before and after a change that may end the
acquisition LP at another optimal vertex: safe and ICs reached (Wilson 95 %), the per-run total delta-v's p50 and p95
(within 1 %) and a two-sample Kolmogorov-Smirnov test on it (p > 0.01), the rows that differ.

    python bench/equivalence.py out/c500_before out/c500_after --out bench/results/equivalence_500_seed1000.json
"""

import argparse
import csv
import json
import sys
from pathlib import Path

import numpy as np
from scipy.stats import ks_2samp

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
from roe_sep.core.montecarlo.stats import proportion  # noqa: E402

MACHINE = ("wall_s", "domain_id")  # how a run went on this machine, not what it computed


def side(directory):
    rows = list(csv.DictReader(open(Path(directory) / "runs.csv", encoding="utf-8")))
    dv = np.array([float(r["dv_total_m_s"]) for r in rows if r["dv_total_m_s"]])
    out = {"runs": len(rows), "dv_total_p50_m_s": float(np.percentile(dv, 50)),
           "dv_total_p95_m_s": float(np.percentile(dv, 95)), "dv_total_mean_m_s": float(dv.mean())}
    for crit in ("safe", "crit_ic_reached"):
        out[crit.replace("crit_", "")] = proportion(sum(r[crit] == "true" for r in rows), len(rows))
    return rows, dv, out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--out", type=Path)
    args = ap.parse_args(argv)
    rows_b, dv_b, before = side(args.before)
    rows_a, dv_a, after = side(args.after)
    by_seed = {r["seed"]: r for r in rows_b}
    differ = sum(1 for r in rows_a if {k: v for k, v in r.items() if k not in MACHINE}
                 != {k: v for k, v in by_seed.get(r["seed"], {}).items() if k not in MACHINE})
    ks = ks_2samp(dv_b, dv_a)
    result = {"before": before, "after": after, "rows_differing": differ,
              "dv_p50_rel_diff": abs(after["dv_total_p50_m_s"] / before["dv_total_p50_m_s"] - 1.0),
              "dv_p95_rel_diff": abs(after["dv_total_p95_m_s"] / before["dv_total_p95_m_s"] - 1.0),
              "ks_statistic": float(ks.statistic), "ks_p": float(ks.pvalue)}
    text = json.dumps(result, indent=1, allow_nan=False)
    if args.out:
        args.out.write_text(text + "\n", encoding="utf-8")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
