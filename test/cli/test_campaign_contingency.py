"""Contingencies in a campaign's bookkeeping, without DDS: the ``--contingency`` flag as node parameters,
the campaign's settings, the ``contingency`` and ``contingencies_detected`` columns, and a table written before
them read and continued."""

import json

import pytest

from roe_sep.campaign import settings
from roe_sep.campaign.table import FIELDS, LEGACY_HEADERS, TRUTH_FIELDS, Table, format_row, row_from_report
from roe_sep.cli import build_parser
from roe_sep.graph import run_overrides
from roe_sep.nodes.parameters import check_overrides


def test_the_flag_sets_the_simulator_and_the_radar():
    nominal = run_overrides(seed=3)
    assert "contingency" not in nominal["sim"] and "contingency" not in nominal["radar"]
    over = run_overrides(seed=3, contingency="spl_weak")
    assert over["sim"]["contingency"] == "spl_weak" and over["radar"]["contingency"] == "spl_weak"
    check_overrides(over)
    with pytest.raises(ValueError, match=r"sim.contingency = 'meteor': must be one of '', 'none', 'spl_weak'"):
        check_overrides({"sim": {"contingency": "meteor"}})
    parser = build_parser()
    assert parser.parse_args(["run", "--contingency", "radar_bias"]).contingency == "radar_bias"
    assert parser.parse_args(["campaign", "--runs", "2", "--contingency", "none"]).contingency == "none"
    assert parser.parse_args(["run"]).contingency is None
    with pytest.raises(SystemExit):
        parser.parse_args(["run", "--contingency", "meteor"])


def test_settings_of_a_nominal_scenario_unchanged_and_a_block_counted(tmp_path):
    nominal = settings(None, {}, None)
    plain = tmp_path / "plain.yaml"
    plain.write_text("separation: {k: 3}\n", encoding="utf-8")
    block = tmp_path / "block.yaml"
    block.write_text("separation: {k: 3}\ncontingency: {name: spl_weak}\n", encoding="utf-8")
    assert settings(plain, {}, None)["scenario_sha256"] == nominal["scenario_sha256"]
    assert settings(block, {}, None)["scenario_sha256"] != nominal["scenario_sha256"]


def report(contingency=None, detected=()):
    return {"safe": True, "criteria": {}, "run": {"completed": True, "reason": "scenario complete"},
            "contingency": contingency, "contingencies_detected": list(detected)}


def test_the_columns():
    base = FIELDS[:-len(TRUTH_FIELDS)]
    assert FIELDS[len(base):] == TRUTH_FIELDS and TRUTH_FIELDS[0] == "truth_closest_m"
    assert base[-4:] == ("contingency", "contingencies_detected", "od_nees7", "od_last_nees7")
    assert LEGACY_HEADERS == (base[:-4], base[:-2], base)
    row = row_from_report(1, report())
    assert "contingency" not in row and "contingencies_detected" not in row  # empty cells: a nominal row as before
    applied = {"name": "spl_weak", "parameters": {"spl_fraction": 0.2, "residual_dv": 0.0}, "configured": {},
               "events": ["ejection ..."]}
    row = row_from_report(2, report(applied, [{"name": "od_inconsistent", "epoch": 75900.0, "text": "", "count": 1}]))
    assert json.loads(row["contingency"]) == applied
    assert json.loads(row["contingencies_detected"]) == {"od_inconsistent": 75900.0}


@pytest.mark.parametrize("legacy", LEGACY_HEADERS, ids=["before_contingencies", "before_nees7", "before_truth"])
def test_a_table_from_an_earlier_version_is_read_and_continued(tmp_path, legacy):
    import csv
    import io

    path = tmp_path / "runs.csv"
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(legacy)
    old = format_row(row_from_report(7, report())).rstrip("\n").split(",")[: len(legacy)]
    writer.writerow(old)
    path.write_text(buf.getvalue(), encoding="utf-8")
    table = Table(path)
    rows = table.read()
    assert rows[7]["status"] == "ok" and rows[7]["contingency"] == "" and rows[7]["od_nees7"] is None
    assert all(rows[7][f] is None for f in TRUTH_FIELDS)  # no value: "n/a" in the contingency table
    table.append(row_from_report(8, report({"name": "drift_stop_missed", "parameters": {}, "configured": {},
                                            "events": []})))
    assert path.read_text(encoding="utf-8").splitlines()[0].split(",") == list(FIELDS)
    rows = table.read()
    assert set(rows) == {7, 8} and json.loads(rows[8]["contingency"])["name"] == "drift_stop_missed"
    assert rows[7] == {**rows[7], "contingency": "", "contingencies_detected": "", "od_nees7": None}


@pytest.mark.parametrize("name", ["ejection_pointing", "carrier_safe_mode", "drift_stop_overperformance",
                                  "density_storm"])
def test_the_flight_contingencies_are_run_and_campaign_flags(name):
    """Issue 41 part 6: each is a ``--contingency`` of ``roe-sep run`` and ``campaign``, a parameter of both nodes
    (the radar ignores them: the simulator's side)."""
    parser = build_parser()
    assert parser.parse_args(["run", "--contingency", name]).contingency == name
    assert parser.parse_args(["campaign", "--runs", "2", "--contingency", name]).contingency == name
    over = run_overrides(seed=3, contingency=name)
    check_overrides(over)
    assert over["sim"]["contingency"] == name
