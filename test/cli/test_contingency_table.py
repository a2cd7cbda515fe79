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



def test_the_truth_columns_beside_the_passive_safety_verdicts(tmp_path):
    """Rows with the truth's columns: P(collision) from the truth's nearest approach below the bodies' radius and
    P(keep-out violated), with their Clopper-Pearson intervals, beside the runs that failed a passive-safety
    verdict; rows recorded before the columns show n/a."""
    from roe_sep.campaign.aggregate import truth_outcomes
    from roe_sep.core.safety.approach import COLLISION_RADIUS

    def truth(r, closest, violated, inside=0.0):
        r.update(truth_closest_m=closest, truth_nearest_m=closest, truth_keep_out_violated=violated,
                 truth_keep_out_s=inside,
                 truth_keep_out_entries=int(violated))
        return r

    rows = [truth(row(1, safe=False, fail=("passive_safety",)), 1500.0, False),  # a verdict failed, truth clear
            truth(row(2, safe=False, fail=("keep_out", "passive_safety")), 0.5, True, 240.0),  # a collision
            truth(row(3), 0.9, True, 60.0),  # inside, closer than 1 m, yet beyond the bodies' 0.727 m
            truth(row(4), None, False),  # never came back: no closest approach
            row(5)]  # recorded before the truth's columns
    s = summarize(written(tmp_path, rows), "spl_weak, smoke")
    assert s["collision_radius_m"] == COLLISION_RADIUS and s["truth_missing"] == 1
    assert s["truth_collisions"]["k"] == 1 and s["truth_collisions"]["n"] == 4
    assert s["truth_collisions"]["method"] == "clopper-pearson"
    assert s["truth_keep_out_violated"]["k"] == 2 and s["truth_closest_min_m"] == s["truth_nearest_min_m"] == 0.5
    assert s["passive_safety_failed"] == {"keep_out": 1, "passive_safety": 2}
    assert s["truth_keep_out_s_p50_max"] == [30.0, 240.0]  # median of 0, 240, 60, 0
    out = truth_outcomes(list(written(tmp_path / "again", rows).values()))
    assert out["truth_collision"]["k"] == 1 and out["truth_collision"]["missing"] == 1
    assert out["truth_keep_out_violated"]["ci95"] == s["truth_keep_out_violated"]["ci95"]
    assert summarize(written(tmp_path / "one", rows[2:3]), collision_radius=1.0)["truth_collisions"]["k"] == 1
    line = markdown([s]).splitlines()[2]
    assert "| 1 / 2 |" in line and "| 1/4 [" in line and "(1 runs n/a)" in line
    old = summarize(written(tmp_path / "old", [row(6), row(7)]), "nominal, recorded before")
    assert old["truth_collisions"] is None
    assert "| n/a | n/a | n/a |" in markdown([old]).splitlines()[2]
    json.dumps(s, allow_nan=False)


def test_the_recorded_table_renders_with_the_new_columns_as_na():
    """The recorded rows (bench/results/contingency_table.json, written before the truth's columns) still render:
    every truth cell n/a, the passive-safety verdicts from the failed criteria."""
    from pathlib import Path

    rows = json.loads((Path(__file__).resolve().parents[2] / "bench/results/contingency_table.json").read_text())
    lines = markdown(rows).splitlines()
    assert len(lines) == len(rows) + 2 and all(line.count("| n/a | n/a | n/a |") == 1 for line in lines[2:])
    weak = next(line for line in lines if line.startswith("| spl_weak, hold on |"))
    assert "| 82 / 99 |" in weak


@pytest.mark.parametrize("name, finding", [("carrier_safe_mode", "burn_missing"),
                                           ("drift_stop_overperformance", "burn_magnitude"),
                                           ("ejection_pointing", "od_inconsistent"),
                                           ("ejection_pointing", "weak_ejection"),
                                           ("density_storm", "od_inconsistent")])
def test_the_findings_that_mean_the_ground_saw_the_flight_contingencies(tmp_path, name, finding):
    """Issue 41 part 6's contingencies in a row: the runs with a finding the ground can raise for them."""
    rows = [row(1, name=name, detected={finding: 75600.0}), row(2, name=name), row(3, name=name,
                                                                                  detected={"od_residuals": 1.0})]
    s = summarize(written(tmp_path, rows))
    assert s["label"] == name and finding in s["detections"] and s["p_detected"]["k"] == 1
