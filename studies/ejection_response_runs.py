"""Study: closed-loop runs of the planner's response to an ejection off its command (issue 41 part 2; docs/run.md,
"The ejection camera"), gathered from their report.json into one result file the docs' figures read.

Each ``--reports NAME=DIR`` is a ``roe-sep run`` output directory, e.g. (a scenario file of the contingency block
alone, fixing the fraction; the rest is the default scenario: docs/contingencies.md)::

    printf 'contingency:\\n  name: spl_weak\\n  spl_fraction: 0.2\\n' > weak02.yaml
    roe-sep run --seed 5 --config weak02.yaml --in-process --out out/weak02
    python studies/ejection_response_runs.py --reports spl_weak_f020=out/weak02 \\
        --out bench/results/ejection_response_runs.json

Per run: the carrier's burns by purpose (epochs [s], |dv| [m/s]), the planner's finding, the truth's closest
approach after the departure [m], whether the keep-out held after it, and whether the ICs were reached.
"""

import argparse
import json
import sys
from pathlib import Path

RESPONSE = ("collision_avoidance", "ejection_completion", "collision_avoidance_reversal", "drift_stop")


def summary(report: dict) -> dict:
    """The response's numbers of one run's report."""
    burns = {}
    for m in report["maneuvers"]:
        if m["spacecraft"] == "carrier" and m["purpose"] in RESPONSE:
            b = burns.setdefault(m["purpose"], {"epochs_s": [], "dv_m_s": []})
            b["epochs_s"].append(round(m["epoch"], 1))
            b["dv_m_s"].append(round(m["dv"], 4))
    ejection = next(m for m in report["maneuvers"] if m["purpose"] == "ejection")
    approach = report["actual_approach"]
    found = [d for d in report.get("contingencies_detected", []) if d.get("name") in ("ejection_off",
                                                                                      "stuck_ejection")]
    return {"ejection_dv_m_s": round(ejection["dv"], 4), "burns": burns,
            "finding": found[0]["name"] if found else None,
            "finding_epoch_s": round(found[0]["epoch"], 1) if found else None,
            "closest_after_departure_m": round(approach["closest_approach"]["distance"], 1),
            "keep_out_violated": approach["keep_out_violated"],
            "dv_total_m_s": round(report["dv_total"], 4), "ic_reached": report["ic"]["reached"],
            "contingency": report["contingency"]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reports", action="append", default=[], metavar="NAME=DIR", help="a run's output directory")
    ap.add_argument("--out", required=True, help="the result JSON")
    args = ap.parse_args(argv)
    out = {}
    for item in args.reports:
        name, _, directory = item.partition("=")
        path = Path(directory) / "report.json"
        if not name or not path.is_file():
            ap.error(f"--reports {item!r}: expected NAME=DIR with DIR/report.json")
        out[name] = summary(json.loads(path.read_text(encoding="utf-8")))
    Path(args.out).write_text(json.dumps(out, indent=1, allow_nan=False) + "\n", encoding="utf-8")
    return 0


if __name__ == "__main__":
    sys.exit(main())
