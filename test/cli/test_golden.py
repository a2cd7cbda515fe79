"""The reference run ``bags/default_run`` is a frozen golden: the NDM, ground-bridge, Foxglove and run tests read it,
so it must be what the code records today.

It was recorded with ``roe-sep run --params config/bag_params.yaml`` (seed 0, the scenario's default; the truth
topics every 5 min), its report in ``bags/default_run.report.json``. A fresh run of that command must give that
report in every key but ``run`` (how it ran: layout, exit codes, paths), to the last digit: the lockstep clock makes
a run independent of timing and load. A change that moves the run fails here; if the change is meant, re-record the
golden with ``make golden`` and review the report's diff.
"""

import json
import math
from pathlib import Path

import pytest

from roe_sep.report import build_report

ROOT = Path(__file__).resolve().parents[2]
BAG = ROOT / "bags" / "default_run"
REPORT = ROOT / "bags" / "default_run.report.json"
PARAMS = ROOT / "config" / "bag_params.yaml"


def differences(fresh, golden, path=""):
    """Paths where two JSON values differ, with both values (exact: floats must be equal)."""
    if isinstance(fresh, dict) and isinstance(golden, dict):
        out = []
        for k in sorted(set(fresh) | set(golden)):
            if k not in golden or k not in fresh:
                out.append(f"{path}/{k}: only in the {'fresh run' if k in fresh else 'golden'}")
            else:
                out += differences(fresh[k], golden[k], f"{path}/{k}")
        return out
    if isinstance(fresh, list) and isinstance(golden, list):
        if len(fresh) != len(golden):
            return [f"{path}: {len(fresh)} items, the golden {len(golden)}"]
        return [d for i, (a, b) in enumerate(zip(fresh, golden)) for d in differences(a, b, f"{path}[{i}]")]
    if type(fresh) is not type(golden) or fresh != golden:
        return [f"{path}: {fresh!r}, the golden {golden!r}"]
    return []


def without_run(report):
    return {k: v for k, v in report.items() if k != "run"}


def test_differences_are_found():
    golden = {"a": [1.0, {"b": 2}], "c": None, "run": {"x": 1}}
    assert differences(without_run(golden), without_run({**golden, "run": {"x": 2}})) == []
    assert differences({"a": [1.0, {"b": 2.0000000000000004}]}, {"a": [1.0, {"b": 2}]}) == [
        "/a[1]/b: 2.0000000000000004, the golden 2"]
    assert differences({"a": [1.0]}, {"a": [1.0, 2.0], "c": 1}) == ["/a: 1 items, the golden 2",
                                                                  "/c: only in the golden"]
    assert differences({"x": 1}, {"x": 1.0}) == ["/x: 1, the golden 1.0"]


def test_golden_report_is_the_report_of_the_golden_bag():
    """The stored report is what today's report code makes of the stored bag (no DDS: the bag is read)."""
    golden = json.loads(REPORT.read_text(encoding="utf-8"))
    rebuilt = json.loads(json.dumps(build_report(BAG, golden["duration"]), allow_nan=False))
    assert differences(without_run(rebuilt), without_run(golden)) == [], "re-record the golden: make golden"


@pytest.mark.dds
def test_fresh_run_gives_the_golden_report(tmp_path):
    """``roe-sep run --params config/bag_params.yaml`` now, against the golden report (every key but ``run``)."""
    from roe_sep.run import run

    run(out=tmp_path, params=str(PARAMS), timeout=900)
    fresh = json.loads((tmp_path / "report.json").read_text(encoding="utf-8"))
    golden = json.loads(REPORT.read_text(encoding="utf-8"))
    assert fresh["run"]["completed"], fresh["run"]["reason"]
    assert fresh["safe"] is True and math.isclose(fresh["duration"], golden["duration"])
    diff = differences(without_run(fresh), without_run(golden))
    assert diff == [], f"{len(diff)} differences from the golden (make golden re-records it):\n" + "\n".join(diff[:40])
