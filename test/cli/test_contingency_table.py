"""The contingency table (roe_sep.campaign.contingency_table) from campaign rows as runs.csv stores them."""

import json

import pytest

from roe_sep.campaign.contingency_table import markdown, summarize
from roe_sep.campaign.table import CRITERIA, Table


def row(seed, safe=True, dmin=2000.0, reached=True, tic=68.8 * 3600, dv=1.53, name=None, detected=None, fail=()):
    r = {"seed": seed, "status": "ok", "safe": safe, "min_distance_m": dmin, "time_to_ic_s": tic if reached else None,
         "dv_total_m_s": dv, "ejection_epoch_s": 600.0,
         "contingency": json.dumps({"name": name, "parameters": {}}) if name else "",
         "contingencies_detected": json.dumps(detected or {}) if detected else ""}
    r.update({f"crit_{c}": c not in fail for c in CRITERIA})
    r["crit_ic_reached"] = reached
    return r


def written(tmp_path, rows):
    table = Table(tmp_path / "runs.csv")
    for r in rows:
        table.append(r)
    return table.read()


def test_a_contingency_row_counts_outcomes_detections_and_failed_criteria(tmp_path):
    rows = [row(1000 + k, name="drift_stop_missed", detected={"burn_missing": 9240.0 + k}) for k in range(8)]
    rows += [row(1008, safe=False, dmin=0.5, reached=False, name="drift_stop_missed", fail=("keep_out",)),
             row(1009, name="drift_stop_missed", dmin=None)]
    s = summarize(written(tmp_path, rows))
    assert s["label"] == "drift_stop_missed" and s["runs"] == 10 and s["completed"] == 10
    assert s["p_safe"]["k"] == 9 and s["collisions"]["k"] == 1 and s["no_departure"] == 1
    assert s["min_distance_min_m"] == 0.5 and s["p_ic_reached"]["k"] == 9
    assert s["p_detected"]["k"] == 8 and s["detected_epoch_s_p50"] == pytest.approx(9243.5)
    assert s["criteria_failed"] == {"ic_reached": 1, "keep_out": 1}
    assert s["time_to_ic_h_p50_p95"][0] == pytest.approx(68.8)
    json.dumps(s, allow_nan=False)  # strict JSON


def test_the_nominal_row_and_the_markdown(tmp_path):
    s = summarize(written(tmp_path, [row(1, dv=1.5), row(2, dv=1.6)]), "nominal, seeds 1-2")
    assert s["contingency"] is None and s["p_detected"] is None and s["criteria_failed"] == {}
    text = markdown([s])
    lines = text.splitlines()
    assert len(lines) == 3 and lines[0].count("|") == lines[1].count("|") == lines[2].count("|")
    assert "| nominal, seeds 1-2 | 2/2 | 2/2 [" in lines[2] and "| -- | none |" in lines[2]

