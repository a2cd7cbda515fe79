"""Study: where the drift at the IC epoch comes from, over the runs of a finished ``roe-sep campaign`` directory.

The initial condition that fails most is the drift, |a da| <= 5 m at the IC epoch (docs/campaigns.md). The truth's
a da there is the acquisition planner's prediction error (its last plan's aimed a*ROE minus the truth; the report's
``model_error.ic``). Two parts of it are measured here, run by run, from each run's bag:

* **execution**: the burns flown after the last acquisition plan against that plan (thruster magnitude and attitude
  errors of the simulator), mapped to a da with seed 002 Eq. (2) (:func:`roe_sep.core.relmotion.maneuvers.delta_roe`
  of the relative impulse ``-(executed - planned)``: a carrier burn moves the relative state the other way);
* **estimate**: the error of the last OD solution before that plan (the estimate it was made from) carried to the
  IC epoch: its a da error against the truth at the solution's epoch plus its drift-rate error (estimated
  differential drag ``a_da_dot`` against the truth's own drift rate) times the time to the IC epoch
  (:func:`roe_sep.report.od_solution`).

What neither explains (the planners' secular model against the nonlinear truth) is the remainder. Strict JSON on
stdout (``--json``) or a table.

    python studies/campaign_ic_drift.py DIR [--json]
"""

import argparse
import json
import math
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from roe_sep import interfaces, jsonutil  # noqa: E402
from roe_sep.campaign.table import Table  # noqa: E402
from roe_sep.core.montecarlo.stats import nees_bounds  # noqa: E402
from roe_sep.core.relmotion.maneuvers import delta_roe  # noqa: E402
from roe_sep.core.relmotion.orbit import mean_motion  # noqa: E402
from roe_sep.report import od_solution, read_topics  # noqa: E402
from roe_sep.stamps import time_to_sec  # noqa: E402

TOPICS = (interfaces.ACQUISITION_PLAN_TOPIC, interfaces.EXECUTED_TOPIC, interfaces.OD_TOPIC,
          interfaces.TRUTH_ROE_TOPIC)


def run_budget(run_dir: Path):
    """The parts of one run's a da error at the IC epoch [m]; None for a run without an acquisition plan."""
    rep = json.loads((run_dir / "report.json").read_text(encoding="utf-8"))
    if not rep.get("ic") or not (rep.get("model_error") or {}).get("ic"):
        return None
    data = read_topics(run_dir / "bag", TOPICS)
    plan = data[interfaces.ACQUISITION_PLAN_TOPIC][-1][1]
    t_plan = time_to_sec(plan.header.stamp)
    a = plan.aimed.chief.semi_major_axis
    n = mean_motion(a)
    planned = {round(time_to_sec(m.epoch)): np.array([m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z]) for m in plan.maneuvers}
    execution = 0.0
    flown = [m for _, m in data[interfaces.EXECUTED_TOPIC]
             if m.spacecraft == "carrier" and m.purpose == "ic_acquisition" and time_to_sec(m.epoch) >= t_plan]
    for m in flown:
        err = np.array([m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z]) - planned[round(time_to_sec(m.epoch))]
        execution += float(delta_roe(-err, m.mean_arg_latitude, a, n)[0]) * a
    ods = [od for _, od in data[interfaces.OD_TOPIC] if time_to_sec(od.estimate.header.stamp) <= t_plan]
    estimate = estimate_a_da = rate_z = lead_days = None
    if ods:  # the report's own comparison of a solution with the truth at its epoch
        sol = od_solution(ods[-1], data[interfaces.TRUTH_ROE_TOPIC], rep["truth_drag_a_da_dot_m_per_day"],
                          [time_to_sec(m.epoch) for _, m in data[interfaces.EXECUTED_TOPIC]])
        if "error" in sol:
            lead = rep["ic"]["epoch"] - sol["epoch"]
            estimate_a_da = sol["error"][0]
            estimate = estimate_a_da + sol["a_da_dot_error"] * lead
            rate_z, lead_days = sol["a_da_dot_z"], lead / 86400.0
    truth_da = rep["ic"]["roe"][0]
    prediction_error = -rep["model_error"]["ic"]["error"][0]  # truth - predicted
    return {"truth_a_da": truth_da, "truth_minus_predicted": prediction_error, "execution": execution,
            "estimate": estimate, "estimate_a_da_at_od": estimate_a_da, "estimate_rate_z": rate_z,
            "estimate_lead_days": lead_days, "burns_after_last_plan": len(flown), "reached": rep["ic"]["reached"]}


def summary(budgets):
    b = [x for x in budgets.values() if x is not None]
    col = {k: np.array([x[k] for x in b if x[k] is not None], dtype=float)
           for k in ("truth_a_da", "truth_minus_predicted", "execution", "estimate", "estimate_a_da_at_od")}
    # the estimate error makes the plan aim off by the same amount: truth - predicted = -estimate + execution + rest
    both = [x for x in b if x["estimate"] is not None]
    rest = np.array([x["truth_minus_predicted"] - x["execution"] + x["estimate"] for x in both])
    out = {"runs": len(b), "missed": sum(not x["reached"] for x in b)}
    for k, v in col.items():
        out[k] = {"n": int(v.size), "mean": float(v.mean()), "std": float(v.std(ddof=1))}
    out["rest"] = {"n": int(rest.size), "mean": float(rest.mean()), "std": float(rest.std(ddof=1))}
    out["corr_execution_vs_truth_minus_predicted"] = float(np.corrcoef(col["execution"],
                                                                       col["truth_minus_predicted"])[0, 1])
    tp = np.array([x["truth_minus_predicted"] for x in both])
    out["corr_minus_estimate_vs_truth_minus_predicted"] = float(np.corrcoef(-np.array([x["estimate"] for x in both]),
                                                                            tp)[0, 1])
    z = np.array([x["estimate_rate_z"] for x in b if x["estimate_rate_z"] is not None])
    out["estimate_rate_mean_z2"] = {"n": int(z.size), "mean": float(np.mean(z * z)),
                                    "band95": list(nees_bounds(1, int(z.size)))}
    lead = np.array([x["estimate_lead_days"] for x in b if x["estimate_lead_days"] is not None])
    out["estimate_lead_days"] = {"n": int(lead.size), "mean": float(lead.mean()), "min": float(lead.min()),
                                 "max": float(lead.max())}
    m, s = out["truth_a_da"]["mean"], out["truth_a_da"]["std"]
    out["gaussian_p_miss_5m"] = 1 - 0.5 * (math.erf((5 - m) / (s * math.sqrt(2))) - math.erf((-5 - m) /
                                                                                           (s * math.sqrt(2))))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dir", type=Path, help="a finished roe-sep campaign directory")
    ap.add_argument("--json", action="store_true")
    args = ap.parse_args(argv)
    if not (args.dir / "runs.csv").is_file():
        print(f"{args.dir}: no runs.csv (not a roe-sep campaign directory)", file=sys.stderr)
        return 2
    rows = Table(args.dir / "runs.csv").read()
    no_bag = [s for s, r in rows.items() if r["status"] == "ok" and not (args.dir / "runs" / str(s) / "bag").is_dir()]
    if no_bag:
        print(f"{args.dir}: {len(no_bag)} completed runs without a bag (a campaign with --no-bags?): this study reads "
              "the bags", file=sys.stderr)
        return 2
    budgets = {s: run_budget(args.dir / "runs" / str(s)) for s, r in sorted(rows.items()) if r["status"] == "ok"}
    if sum(b is not None for b in budgets.values()) < 2:
        print(f"{args.dir}: fewer than 2 completed runs with an acquisition plan (runs too short?)", file=sys.stderr)
        return 2
    out = summary(budgets)
    if args.json:
        print(jsonutil.dumps({"summary": out, "runs": {str(s): b for s, b in budgets.items()}}, indent=2))
        return 0
    print(f"{out['runs']} runs with an acquisition plan, {out['missed']} missed the ICs")
    print(f"  {'a da at the IC epoch [m]':44s}{'n':>5s}{'mean':>9s}{'std':>9s}")
    for k, label in (("truth_a_da", "truth"), ("truth_minus_predicted", "truth - last plan's prediction"),
                     ("execution", "execution of the burns after the last plan"),
                     ("estimate", "last OD's error before that plan"),
                     ("estimate_a_da_at_od", "  of which its a da error at its epoch"), ("rest", "remainder")):
        v = out[k]
        print(f"  {label:44s}{v['n']:5d}{v['mean']:9.2f}{v['std']:9.2f}")
    print(f"  correlation with truth - predicted: execution {out['corr_execution_vs_truth_minus_predicted']:.2f}, "
          f"-estimate {out['corr_minus_estimate_vs_truth_minus_predicted']:.2f}")
    print(f"  Gaussian P(|a da| > 5 m) with the truth's mean and std: {out['gaussian_p_miss_5m']:.3f}")
    lead = out["estimate_lead_days"]
    print(f"  that OD's epoch before the IC epoch: mean {lead['mean']:.2f} days ({lead['min']:.2f}-{lead['max']:.2f})")
    z2 = out["estimate_rate_mean_z2"]
    print(f"  that OD's drift rate against its sigma: mean z^2 {z2['mean']:.2f} over {z2['n']} runs (95 % band of an "
          f"honest sigma [{z2['band95'][0]:.2f}, {z2['band95'][1]:.2f}])")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
