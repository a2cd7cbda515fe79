"""The contingency table: one campaign per contingency (``roe-sep campaign --contingency NAME``), each beside the
nominal campaign of the same seeds, laid out as seed 001 Sec. 4 lays out its robust analysis: per case the outcome
(P(safe), closest approach, P(ICs reached), time to the ICs, carrier dv) and whether the ground saw it.

A row of the table is :func:`summarize` of one campaign's ``runs.csv`` rows (:class:`~roe_sep.campaign.table.Table`);
:func:`markdown` writes the rows as the Markdown table of docs/contingencies.md. Proportions carry their Wilson 95 %
interval (:func:`~roe_sep.core.montecarlo.stats.proportion`; with 0 of n the upper end is the bound). The closest
approach is the simulator's (after the departure, ``min_distance_m``); ``collisions`` counts those below
``HARD_BODY_RADIUS``.

Beside the passive-safety verdicts (``keep_out`` and ``passive_safety`` of the monitor on the truth: a prediction with
no further burns from each check), what happened, from the truth (the rows' ``truth_*`` columns,
:func:`roe_sep.report.actual_approach`): the closest approach after the departure and after the ejection,
P(collision) (the nearest approach after the ejection below
``collision_radius``, default :data:`~roe_sep.core.safety.approach.COLLISION_RADIUS`, derived from the two bodies'
sizes) and P(keep-out violated), each with its Clopper-Pearson 95 % interval. Rows recorded before those columns
have none: "n/a".
"""

import json
import math

import numpy as np

from ..core.montecarlo.stats import clopper_pearson, proportion
from ..core.safety.approach import COLLISION_RADIUS

HARD_BODY_RADIUS = 1.0
"""m, the radius of the simulator-based collision count ``collisions`` (README "R = 1 m"); the truth's count uses
the bodies' :data:`~roe_sep.core.safety.approach.COLLISION_RADIUS`."""

EXPECTED_DETECTIONS = {
    "spl_weak": ("ejection_off", "stuck_ejection", "weak_ejection", "od_inconsistent"),
    "drift_stop_delayed": ("burn_missing", "burn_late"),
    "drift_stop_missed": ("burn_missing",),
    "burn_underperformance": ("burn_magnitude", "burn_pointing"),
    "radar_pass_missed": ("radar_pass_missed",),
    "radar_bias": ("od_residuals", "range_bias_estimated"),
    "ejection_pointing": ("ejection_off", "weak_ejection", "od_inconsistent"),
    "carrier_safe_mode": ("burn_missing",),
    "drift_stop_overperformance": ("burn_magnitude",),
    "density_storm": ("od_inconsistent",),
}
"""Per contingency, the named findings (safety monitor, planner, radar station) that mean the ground saw it
(docs/contingencies.md, "Detection")."""


def _contingency(row):
    text = row.get("contingency") or ""
    return json.loads(text) if text else None


def _detected(row):
    text = row.get("contingencies_detected") or ""
    return json.loads(text) if text else {}


def _percentiles(values, qs):
    v = np.asarray([x for x in values if x is not None and math.isfinite(x)], dtype=float)
    return [float(np.percentile(v, q)) if v.size else None for q in qs]


def summarize(rows, label=None, collision_radius=COLLISION_RADIUS):
    """One row of the table from a campaign's rows (``{seed: row}`` or an iterable of rows); ``label`` names it
    (default: the contingency of its rows, 'nominal' without one); ``collision_radius`` [m] of the truth's collision
    count. Strict-JSON values (None for no value)."""
    rows = list(rows.values()) if isinstance(rows, dict) else list(rows)
    done = [r for r in rows if r["status"] == "ok"]
    names = {(_contingency(r) or {}).get("name") for r in done}
    name = names.pop() if len(names) == 1 else None
    n = len(done)
    dmin = [r["min_distance_m"] for r in done]
    finite = [d for d in dmin if d is not None]
    reached = [r for r in done if r["crit_ic_reached"]]
    expected = EXPECTED_DETECTIONS.get(name, ())
    seen = [r for r in done if expected and any(k in _detected(r) for k in expected)]
    first = [min(_detected(r)[k] for k in expected if k in _detected(r)) for r in seen]
    failed = {}
    for r in done:
        for key, value in r.items():
            if key.startswith("crit_") and value is False:
                failed[key[5:]] = failed.get(key[5:], 0) + 1
    p01, = _percentiles(finite, [0.1])
    t50, t95 = _percentiles([r["time_to_ic_s"] / 3600.0 for r in reached if r["time_to_ic_s"] is not None], [50, 95])
    dv50, dv95 = _percentiles([r["dv_total_m_s"] for r in done], [50, 95])
    known = [r for r in done if r.get("truth_keep_out_violated") is not None]  # rows with the truth's columns
    closest = [r.get("truth_closest_m") for r in known]
    nearest = [r.get("truth_nearest_m") for r in known]
    truth = {
        "collision_radius_m": collision_radius,
        "truth_missing": n - len(known),
        "truth_closest_min_m": min((d for d in closest if d is not None), default=None),
        "truth_nearest_min_m": min((d for d in nearest if d is not None), default=None),
        "truth_collisions": clopper_pearson(sum(1 for d in nearest if d is not None and d < collision_radius),
                                            len(known)) if known else None,
        "truth_keep_out_violated": clopper_pearson(sum(bool(r["truth_keep_out_violated"]) for r in known),
                                                   len(known)) if known else None,
        "truth_keep_out_s_p50_max": [_percentiles([r.get("truth_keep_out_s") for r in known], [50])[0],
                                     max((r["truth_keep_out_s"] for r in known
                                          if r.get("truth_keep_out_s") is not None), default=None)],
        "passive_safety_failed": {c: sum(1 for r in done if r.get(f"crit_{c}") is False)
                                  for c in ("keep_out", "passive_safety")},
    }
    return {
        "label": label or name or "nominal",
        "contingency": name,
        "runs": len(rows), "completed": n, "failed_runs": len(rows) - n,
        "seeds": [min(r["seed"] for r in rows), max(r["seed"] for r in rows)] if rows else None,
        "p_safe": proportion(sum(1 for r in done if r["safe"]), n) if n else None,
        "collisions": proportion(sum(1 for d in finite if d < HARD_BODY_RADIUS), n) if n else None,
        "min_distance_p0_1_m": p01,
        "min_distance_min_m": min(finite) if finite else None,
        "no_departure": sum(1 for d in dmin if d is None),
        "p_ic_reached": proportion(len(reached), n) if n else None,
        "time_to_ic_h_p50_p95": [t50, t95],
        "dv_total_m_s_p50_p95": [dv50, dv95],
        "criteria_failed": dict(sorted(failed.items())),
        "detections": list(expected),
        "p_detected": proportion(len(seen), n) if n and expected else None,
        "detected_epoch_s_p50": _percentiles(first, [50])[0] if first else None,
        **truth,
    }


def _p(prop):
    if prop is None:
        return "--"
    if prop.get("p") is None:
        return "n/a"
    lo, hi = prop["ci95"]
    return f"{_count(prop)} [{lo:.3f}, {hi:.3f}]"


def _num(v, fmt):
    return "--" if v is None else format(v, fmt)


def compact_markdown(summaries):
    """The README's short form of :func:`markdown`: per case the safe runs, the closest approach [m], the runs at the
    ICs, the carrier dv p50 / p95 [m/s] and the runs the ground saw ('–' for a case without a contingency)."""
    lines = ["| case | safe | closest approach [m] | ICs reached | carrier Δv p50 / p95 [m/s] | seen by the ground |",
             "|---|---|---|---|---|---|"]
    for s in summaries:
        dv50, dv95 = s["dv_total_m_s_p50_p95"]
        seen = "–" if s["p_detected"] is None else _count(s["p_detected"])
        lines.append(f"| {s['label']} | {_count(s['p_safe'])} | {_num(s['min_distance_min_m'], '.0f')} | "
                     f"{_count(s['p_ic_reached'])} | {_num(dv50, '.3f')} / {_num(dv95, '.3f')} | {seen} |")
    return "\n".join(lines) + "\n"


def _count(prop):
    return "--" if prop is None else f"{prop['k']}/{prop['n']}"


def _truth(s, key):
    """A truth proportion of a summary: "n/a" for rows recorded without the truth's columns (or a summary before
    them); the runs without them counted."""
    if s.get(key) is None:
        return "n/a"
    missing = s.get("truth_missing") or 0
    return _p(s[key]) + (f" ({missing} runs n/a)" if missing else "")


def _closest(s):
    if s.get("truth_collisions") is None:
        return "n/a"
    return f"{_num(s['truth_closest_min_m'], '.0f')} / {_num(s['truth_nearest_min_m'], '.0f')}"


def _radius(summaries):
    radii = {s.get("collision_radius_m", COLLISION_RADIUS) for s in summaries}
    return radii.pop() if len(radii) == 1 else COLLISION_RADIUS


def markdown(summaries):
    """The Markdown table of :func:`summarize` rows: the passive-safety verdicts (the runs in which a check's
    prediction with no further burns failed keep-out / passive safety) beside the truth's actual approach; "n/a"
    where the rows carry no truth columns. The collision radius in the header is the rows' (one for all)."""
    head = ("| case | runs | P(safe) | passive-safety verdicts failed: keep-out / passive safety (runs) | "
            "closest approach, sim p0.1 / min [m] | collisions, sim (d < 1 m) | "
            "closest approach, truth: min after the departure / after the ejection [m] | "
            f"P(collision), truth (d < {_radius(summaries):.3f} m), Clopper-Pearson 95 % | "
            "P(keep-out violated), truth, Clopper-Pearson 95 % | P(ICs reached) | "
            "time to ICs p50 / p95 [h] | dv p50 / p95 [m/s] | detected | criteria failed (runs) |")
    lines = [head, "|" + "---|" * (head.count("|") - 1)]
    for s in summaries:
        failed = s.get("passive_safety_failed") or {c: s["criteria_failed"].get(c, 0)
                                                    for c in ("keep_out", "passive_safety")}
        t50, t95 = s["time_to_ic_h_p50_p95"]
        dv50, dv95 = s["dv_total_m_s_p50_p95"]
        crit = ", ".join(f"{k} {v}" for k, v in s["criteria_failed"].items()) or "none"
        det = "--" if s["p_detected"] is None else f"{_p(s['p_detected'])} ({', '.join(s['detections'])})"
        lines.append(
            f"| {s['label']} | {s['completed']}/{s['runs']} | {_p(s['p_safe'])} | "
            f"{failed['keep_out']} / {failed['passive_safety']} | "
            f"{_num(s['min_distance_p0_1_m'], '.0f')} / {_num(s['min_distance_min_m'], '.0f')} | "
            f"{_p(s['collisions'])} | "
            f"{_closest(s)} | "
            f"{_truth(s, 'truth_collisions')} | {_truth(s, 'truth_keep_out_violated')} | "
            f"{_p(s['p_ic_reached'])} | {_num(t50, '.1f')} / {_num(t95, '.1f')} | "
            f"{_num(dv50, '.3f')} / {_num(dv95, '.3f')} | {det} | {crit} |")
    return "\n".join(lines) + "\n"
