"""``roe-sep campaign``: rows written per run, resume, failures as rows, run k reproduced alone, and the statistics.

The closed-loop tests run short campaigns (20000 s of sim time: ejection, blind drift-stop and the first radar
passes) on an embedded Dask cluster. The runs take DDS domains from ``ROE_SEP_TEST_CAMPAIGN_DOMAINS`` (``LO-HI``;
default: the session's own domain only, so concurrent runs queue for it).
"""

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import psutil
import pytest
import yaml
from rosutil import stale_dds_segments

from roe_sep.campaign.runner import radar_seed, run_overrides
from roe_sep.campaign.table import FIELDS, RUN_FIELDS, Table, failed_row, format_row, row_from_report
from roe_sep.core.montecarlo.stats import distribution, nees_bounds, nees_consistency, wilson_interval

ROOT = Path(__file__).resolve().parents[2]
DURATION = 20000.0
SEED = 100
RUNS = 3


def _domains():
    own = int(os.environ.get("ROS_DOMAIN_ID", "0") or 0)
    return os.environ.get("ROE_SEP_TEST_CAMPAIGN_DOMAINS", f"{own}-{own}")


def _cli(*args, check=True):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.run([sys.executable, "-m", "roe_sep.cli", "campaign", *args, "--domains", _domains(),
                           "--open-loop-samples", "1000", "--json"], capture_output=True, text=True, env=env,
                          cwd=ROOT, timeout=900)
    if check and proc.returncode not in (0, 1):
        raise AssertionError(f"exit {proc.returncode}: {proc.stderr[-2000:]}")
    return proc


def _strict(text):
    def refuse(c):
        raise ValueError(f"non-strict JSON constant {c}")

    return json.loads(text, parse_constant=refuse)


def _comparable(row):
    """A row without how it ran (wall time, domain): what the run computed."""
    return format_row({k: v for k, v in row.items() if k not in RUN_FIELDS})


# ----------------------------------------------------------------------------------------------- statistics
def test_wilson_interval_known_values():
    lo, hi = wilson_interval(5, 10)
    assert lo == pytest.approx(0.2366, abs=1e-4) and hi == pytest.approx(0.7634, abs=1e-4)
    assert wilson_interval(0, 10) == (0.0, pytest.approx(1.959964 ** 2 / (10 + 1.959964 ** 2)))
    lo, hi = wilson_interval(10, 10)
    assert hi == 1.0 and lo == pytest.approx(10 / (10 + 1.959964 ** 2))
    assert wilson_interval(0, 0) == (0.0, 1.0)
    with pytest.raises(ValueError, match="k = 11"):
        wilson_interval(11, 10)


def test_nees_bounds_and_consistency():
    lo, hi = nees_bounds(6)
    assert lo == pytest.approx(1.2373, abs=1e-3) and hi == pytest.approx(14.4494, abs=1e-3)
    lo100, hi100 = nees_bounds(6, 100)
    assert lo < lo100 < 6 < hi100 < hi  # the mean of 100 runs is held tighter
    import numpy as np

    rng = np.random.default_rng(1)
    honest = (rng.standard_normal((400, 6)) ** 2).sum(axis=1)
    assert nees_consistency(honest)["consistent"]
    assert not nees_consistency(4.0 * honest)["consistent"]  # covariance 4x too small: errors 2x the sigmas
    assert nees_consistency([None, None])["mean"] is None


def test_distribution_skips_missing_values():
    d = distribution([1.0, None, 3.0, 2.0])
    assert d["n"] == 3 and d["missing"] == 1 and d["p50"] == 2.0 and d["max"] == 3.0
    assert distribution([None])["p50"] is None


def test_ic_checks_and_time_to_ic_of_the_runs_that_reached_them(tmp_path):
    """Each initial condition is a column and a proportion over the runs whose IC epoch was evaluated; the time to
    the ICs and |a da| at the IC epoch are distributions (the time over the runs that reached the ICs)."""
    from roe_sep.campaign.aggregate import aggregate
    from roe_sep.report import IC_CHECKS

    def rep(drift_m, reached):
        checks = dict.fromkeys(IC_CHECKS, True)
        checks["drift"] = reached
        return {"run": {"completed": True, "reason": "scenario complete"}, "safe": True,
                "criteria": {"ic_reached": reached}, "time_to_ic": 2.0e5 if reached else None,
                "ic": {"epoch": 2.5e5, "roe": [drift_m, 7500.0, 0.0, -400.0, 0.0, 400.0], "min_rn_distance": 400.0,
                       "checks": checks, "reached": reached}}

    table = Table(tmp_path / "runs.csv")
    for seed, r in ((1, rep(-1.5, True)), (2, rep(7.0, False)), (3, rep(2.0, True)),
                    (4, {"run": {"completed": True}})):  # 4: no IC plan flown (a short run)
        table.append(row_from_report(seed, r))
    rows = list(table.read().values())  # as the campaign aggregates them: read back from runs.csv
    assert rows[1]["ic_drift"] is False and rows[1]["ic_a_da_m"] == 7.0 and rows[1]["time_to_ic_s"] is None
    assert rows[3]["ic_drift"] is None and rows[3]["ic_a_da_m"] is None
    agg = aggregate(rows)
    assert agg["ic_checks"]["drift"] == {"k": 2, "n": 3, "p": pytest.approx(2 / 3), "ci95": pytest.approx(
        wilson_interval(2, 3))}
    assert agg["ic_checks"]["along_track"]["k"] == agg["ic_checks"]["along_track"]["n"] == 3
    assert agg["criteria"]["ic_reached"]["k"] == 2 and agg["criteria"]["ic_reached"]["n"] == 4
    assert agg["distributions"]["abs_a_da_ic"]["max"] == 7.0 and agg["distributions"]["abs_a_da_ic"]["min"] == 1.5
    assert agg["distributions"]["time_to_ic"]["n"] == 2 and agg["distributions"]["time_to_ic"]["missing"] == 2


def test_od_drift_rate_and_last_solution_columns_and_consistency(tmp_path):
    """The drift rate's error (m/day) and z of the first OD solution, and the last solution's NEES and z, are columns;
    the aggregate tests each against its chi-square band: honest sigmas pass, sigmas half the errors fail."""
    import numpy as np

    from roe_sep.campaign.aggregate import aggregate

    rng = np.random.default_rng(3)
    table = Table(tmp_path / "runs.csv")
    for seed in range(200):
        z_first, z_last = rng.standard_normal(2)
        sol = {"epoch": 75600.0, "passes": 3, "nees": float((rng.standard_normal(6) ** 2).sum()),
               "a_da_dot_error": 2.0 * z_first / 86400.0, "a_da_dot_z": float(z_first)}
        last = {"epoch": 250000.0, "nees": 4.0 * float((rng.standard_normal(6) ** 2).sum()),
                "a_da_dot_z": 2.0 * float(z_last)}  # optimistic: errors twice the sigmas
        table.append(row_from_report(seed, {"run": {"completed": True}, "od": {**sol, "solutions": 5, "last": last}}))
    rows = list(table.read().values())
    assert rows[0]["od_solutions"] == 5 and rows[0]["od_last_epoch_s"] == 250000.0
    assert rows[0]["od_err_a_da_dot_m_per_day"] == pytest.approx(2.0 * rows[0]["od_z_a_da_dot"])
    agg = aggregate(rows)
    assert agg["od_nees"]["consistent"] and agg["od_drift_rate"]["consistent"]
    assert agg["od_drift_rate"]["dof"] == 1 and agg["od_drift_rate"]["n"] == 200
    assert not agg["od_last_nees"]["consistent"] and not agg["od_last_drift_rate"]["consistent"]
    assert agg["od_last_drift_rate"]["mean"] > agg["od_last_drift_rate"]["mean_bounds"][1]


def _dispersed_report(rng, seed, spl_sigma=0.1, thruster_sigma=0.05, ballistic_sigma=0.2, noise_scale=1.0,
                      applied=None):
    """A run report whose ``dispersions`` are drawn as the simulator draws them (ExecutionErrors records each burn);
    ``applied`` overrides the sigmas actually used (a dispersion silently not applied: 0) while the configured ones
    stay in the report, as a framework with that bug would write them."""
    from roe_sep.core.truth.secular import ExecutionErrors

    used = {"spl_sigma": spl_sigma, "thruster_sigma": thruster_sigma, "ballistic_sigma": ballistic_sigma,
            **(applied or {})}
    att = 30.0 * math.pi / 180.0 / 3600.0
    errors = ExecutionErrors(rng, used["spl_sigma"], used["thruster_sigma"], att)
    errors.executed(np.array([0.0, 1.41, 0.0]), "picosatellite")
    for _ in range(rng.integers(3, 9)):
        errors.executed(np.array([0.0, 0.01, 0.0]), "carrier")
    m = 120  # radar measurements of the first OD: 3 m residuals, 7 parameters
    rms = noise_scale * math.sqrt(rng.chisquare(3 * m - 7) / (3 * m))
    return {"run": {"completed": True}, "safe": True,
            "od": {"epoch": 75600.0, "passes": 3, "measurements": m, "residual_rms": rms, "solutions": 3},
            "dispersions": {"drag_factor": float(rng.normal(1.0, used["ballistic_sigma"])),
                            "ejection_delay_s": float(rng.uniform(0.0, 10.0)), "burns": errors.applied,
                            "configured": {"disperse": True, "ballistic_sigma": ballistic_sigma,
                                           "ejection_delay_max_s": 10.0, "spl_sigma": spl_sigma,
                                           "thruster_sigma": thruster_sigma, "attitude_sigma": att}}}


@pytest.mark.parametrize("bug, failing", [
    (None, set()),
    ({"applied": {"spl_sigma": 0.0}}, {"spl_factor"}),
    ({"applied": {"thruster_sigma": 0.025}}, {"thruster_factor"}),
    ({"applied": {"ballistic_sigma": 0.0}}, {"drag_factor"}),
    ({"noise_scale": 1.2}, {"radar_noise"}),
])
def test_dispersions_as_applied_against_the_configured_distributions(tmp_path, bug, failing):
    """The dispersions each run drew go through runs.csv into a KS test per dispersion against the configured
    distribution: honest draws are consistent; a dispersion not applied (or applied at half its sigma, or radar
    noise 20 % above its sigma) is INCONSISTENT, and only that one."""
    from roe_sep.campaign.aggregate import aggregate

    rng = np.random.default_rng(11)
    table = Table(tmp_path / "runs.csv")
    for seed in range(300):
        table.append(row_from_report(seed, _dispersed_report(rng, seed, **(bug or {}))))
    rows = list(table.read().values())
    assert json.loads(rows[0]["dispersions"])["configured"]["spl_sigma"] == 0.1
    checks = aggregate(rows)["dispersions"]
    assert set(checks) == {"spl_factor", "spl_attitude", "thruster_factor", "thruster_attitude", "drag_factor",
                           "ejection_delay", "radar_noise"}
    assert checks["spl_factor"]["n"] == 300 and checks["spl_attitude"]["n"] == 900
    assert checks["spl_factor"]["reference"] == "N(1, 0.1)" and checks["ejection_delay"]["reference"] == "U(0, 10 s)"
    assert {k for k, c in checks.items() if not c["consistent"]} == failing
    for k in failing:
        assert checks[k]["p_value"] < 0.01


def test_ic_prediction_column_and_one_sided_bound(tmp_path):
    """The a da the last information predicted at the IC epoch is a column beside the truth (the final OD's
    prediction when it flew no trim, the trim plan's aim otherwise, :func:`roe_sep.report.predicted_ic_drift`); their
    difference is a distribution; ic_reached has its one-sided Clopper-Pearson lower bound (0 misses in 299: 0.990)."""
    from roe_sep.campaign.aggregate import aggregate, one_sided_lower
    from roe_sep.report import predicted_ic_drift

    def final(trim, predicted):
        return {"trim": trim, "trim_dv": 0.004 if trim else 0.0, "predicted_a_da": predicted, "sigma_a_da": 1.2,
                "threshold": 1.4, "t_final": 2.5e5}

    table = Table(tmp_path / "runs.csv")
    cases = ((final(False, 0.4), 1.0), (final(True, 6.0), -3.4), (None, 6.2))
    for seed, (fin, true) in enumerate(cases):
        aimed = {"predicted": [-0.9 if fin else 0.1, 7400.0, 0, 0, 0, 0]}
        table.append(row_from_report(seed, {
            "run": {"completed": True}, "criteria": {"ic_reached": abs(true) <= 5.0},
            "ic": {"epoch": 2.5e5, "roe": [true, 7500.0, 0.0, -400.0, 0.0, 400.0], "checks": {}},
            "final_od": fin, "ic_predicted_a_da": predicted_ic_drift(fin, aimed)}))
    rows = list(table.read().values())
    assert [r["ic_pred_a_da_m"] for r in rows] == [0.4, -0.9, 0.1]
    assert [r["ic_trim"] for r in rows] == [False, True, None] and rows[1]["ic_trim_dv_m_s"] == 0.004
    assert rows[0]["ic_final_od_sigma_m"] == 1.2
    agg = aggregate(rows)
    err = agg["distributions"]["a_da_ic_prediction_error"]
    assert err["n"] == 3 and err["max"] == pytest.approx(6.1) and err["min"] == pytest.approx(0.6)
    assert agg["distributions"]["abs_a_da_ic_predicted"]["max"] == 0.9
    assert agg["ic_trims"]["k"] == 1 and agg["ic_trims"]["n"] == 2
    assert agg["ic_reached_lower_95"] == pytest.approx(one_sided_lower(2, 3))
    assert one_sided_lower(299, 299) == pytest.approx(0.05 ** (1 / 299)) and 0.98999 < one_sided_lower(299, 299)
    assert one_sided_lower(472, 473) > 0.99 > one_sided_lower(471, 473)
    assert one_sided_lower(0, 5) == 0.0 and one_sided_lower(0, 0) is None
    assert predicted_ic_drift(None, None) is None


# ------------------------------------------------------------------------------------------------- the table
@pytest.mark.fault
def test_table_round_trip_and_torn_line(tmp_path):
    t = Table(tmp_path / "runs.csv")
    row = failed_row(7, "exception", 'bad, "quoted"\nreason')
    row.update(wall_s=1.5, domain_id=62, min_distance_m=float("nan"))
    t.append(row)
    with open(t.path, "a", encoding="utf-8") as fh:
        fh.write("8,ok,,scenario compl")  # a crash in the middle of a line
    rows = t.read()
    assert list(rows) == [7] and rows[7]["reason"] == row["reason"] and rows[7]["min_distance_m"] is None
    t.append(failed_row(9, "timeout", "x"))
    assert list(t.read()) == [7, 9]
    import numpy as np  # a report built in memory holds NumPy scalars: the same cells as Python's

    t.append({**failed_row(10, "timeout", "x"), "safe": np.bool_(True), "od_passes": np.int64(3),
              "dv_total_m_s": np.float64(1.25), "od_nees": np.float32(np.nan)})
    assert {k: t.read()[10][k] for k in ("safe", "od_passes", "dv_total_m_s", "od_nees")} == {
        "safe": True, "od_passes": 3, "dv_total_m_s": 1.25, "od_nees": None}
    assert t.path.read_text().splitlines()[0].split(",") == list(FIELDS)


def test_radar_seed_is_derived_and_independent():
    assert radar_seed(5) == radar_seed(5) != radar_seed(6)
    assert radar_seed(5) != 5 and 0 <= radar_seed(5) < 2**32
    over = run_overrides(5, {"radar": {"sigma_range": 1.0}, "sim": {"disperse": True}})
    assert over["radar"] == {"sigma_range": 1.0, "seed": radar_seed(5)} and over["sim"] == {"disperse": True}
    assert "ground_bridge" not in over  # no ground_bridge in a run without --ccsds
    assert run_overrides(5, {}, ccsds=True)["ground_bridge"] == {"write_period": 0.0}
    assert run_overrides(5, {"ground_bridge": {"write_period": 600.0}}, ccsds=True)["ground_bridge"] == {
        "write_period": 600.0}


# ------------------------------------------------------------------------------------------ closed-loop runs
@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    out = tmp_path_factory.mktemp("campaign") / "c"
    params = out.parent / "params.yaml"
    params.write_text(yaml.safe_dump({"planner": {"ros__parameters": {"mc_samples": 20000}}}))
    args = ("--runs", str(RUNS), "--seed", str(SEED), "--duration", str(DURATION), "--workers", "2",
            "--params", str(params), "--out", str(out))
    before = stale_dds_segments()
    proc = _cli(*args)
    LEFT_BEHIND.update(stale_dds_segments() - before)
    return out, args, params, _strict(proc.stdout)


LEFT_BEHIND = set()  # the stale DDS segments the campaign fixture's runs left in /dev/shm


@pytest.mark.dds
def test_the_runs_leave_no_dds_segment_behind(campaign):
    """A forked run ends with os._exit: its nodes (garbage in reference cycles) are collected first, so that rmw
    deletes its DDS participant; before, every run left its 549 KB shared-memory segment in /dev/shm."""
    assert not LEFT_BEHIND, sorted(LEFT_BEHIND)


@pytest.mark.dds
def test_campaign_writes_one_row_and_report_per_run(campaign):
    out, _, _, rep = campaign
    rows = Table(out / "runs.csv").read()
    assert sorted(rows) == list(range(SEED, SEED + RUNS))
    assert rep["executed_now"] == RUNS and rep["runs"] == RUNS and rep["completed"] + rep["failed"] == RUNS
    for s, row in rows.items():
        assert row["status"] == "ok", row["reason"]
        assert 0.5 < row["dv_total_m_s"] < 3.0 and row["min_distance_m"] > 0
        # what happened, from the truth: its closest approach is the simulator's (10-s grid) to within the bound
        assert row["truth_keep_out_violated"] is False and row["truth_departure_epoch_s"] > row["ejection_epoch_s"]
        assert 0.0 <= row["min_distance_m"] - row["truth_closest_m"] <= row["truth_closest_bound_m"] + 0.05
        run_rep = _strict((out / "runs" / str(s) / "report.json").read_text())
        assert _comparable(row) == _comparable(row_from_report(s, run_rep))
        over = yaml.safe_load((out / "runs" / str(s) / "overrides.yaml").read_text())
        assert over["radar"]["ros__parameters"]["seed"] == radar_seed(s)
        # every node in the run's process, no ground_bridge (no --ccsds); the nodes' output in logs/run.log
        assert run_rep["run"]["layout"] == "one process (events executor)"
        assert run_rep["run"]["exit_codes"] == {"in_process": 0}
        assert not (out / "runs" / str(s) / "ccsds").exists()
        assert "bag closed: " in (out / "runs" / str(s) / "logs" / "run.log").read_text()
    assert len({r["dv_total_m_s"] for r in rows.values()}) == RUNS  # each seed disperses differently
    assert rep["p_safe"]["n"] == rep["completed"] and 0 <= rep["p_safe"]["ci95"][0] <= rep["p_safe"]["ci95"][1] <= 1
    assert set(rep["criteria"]) >= {"keep_out", "passive_safety", "evaporation", "ic_reached"}
    assert rep["distributions"]["dv_total"]["n"] == rep["completed"]
    assert rep["truth_collision"]["n"] == rep["completed"] and rep["truth_collision"]["missing"] == 0
    assert rep["truth_keep_out_violated"]["k"] == 0 and rep["truth_keep_out_violated"]["method"] == "clopper-pearson"
    assert rep["open_loop"]["p"] is not None and 0 <= rep["open_loop"]["p_approach"] <= 1
    assert all(Path(f).stat().st_size > 0 for f in rep["figures"])
    assert _strict((out / "report.json").read_text())["runs"] == RUNS


@pytest.mark.dds
def test_rerun_skips_every_done_run(campaign):
    out, args, _, _ = campaign
    before = (out / "runs.csv").read_text()
    rep = _strict(_cli(*args).stdout)
    assert rep["executed_now"] == 0 and rep["skipped_done"] == RUNS
    assert (out / "runs.csv").read_text() == before


@pytest.mark.dds
def test_interrupted_campaign_completes_only_the_missing_run_with_the_same_row(campaign):
    """A campaign killed before its last row: the rerun (on one worker, with the CCSDS export) runs that seed
    only, into the leftover run directory, and writes the row the two-worker campaign wrote."""
    out, args, _, _ = campaign
    table = out / "runs.csv"
    lines = table.read_text().splitlines(keepends=True)
    last = Table(table).read()
    victim = int(lines[-1].split(",")[0])
    table.write_text("".join(lines[:-1]) + lines[-1][:25])  # the last row torn mid-line, as by a kill
    args = tuple(a if a != "2" else "1" for a in args) + ("--ccsds",)  # --workers 1
    rep = _strict(_cli(*args).stdout)
    assert rep["executed_now"] == 1 and rep["skipped_done"] == RUNS - 1
    again = Table(table).read()
    assert sorted(again) == sorted(last)
    assert _comparable(again[victim]) == _comparable(last[victim])
    # --ccsds: the run's ground_bridge wrote the CCSDS set once, at the end of the run
    over = yaml.safe_load((out / "runs" / str(victim) / "overrides.yaml").read_text())
    assert over["ground_bridge"]["ros__parameters"]["write_period"] == 0.0
    assert (out / "runs" / str(victim) / "ccsds" / "ephemeris.oem.xml").stat().st_size > 0


@pytest.mark.dds
@pytest.mark.fault
def test_ctrl_c_mid_campaign_then_rerun_completes_only_the_missing_runs(campaign, tmp_path):
    """A real interruption: SIGINT (Ctrl-C) to ``roe-sep campaign`` once its first row is written. It exits with
    130, leaves complete rows only and no process of its runs behind; the rerun runs only the seeds without a row,
    and every row (also those written before the interruption) is the row of the uninterrupted campaign."""
    done, _, params, _ = campaign
    out = tmp_path / "c"
    runs = RUNS + 1  # seeds SEED .. SEED + RUNS: the fixture's, and one more
    cmd = [sys.executable, "-m", "roe_sep.cli", "campaign", "--runs", str(runs), "--seed", str(SEED), "--duration",
           str(DURATION), "--workers", "2", "--params", str(params), "--out", str(out), "--domains", _domains(),
           "--open-loop-samples", "1000", "--no-figures", "--json"]
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    table = Table(out / "runs.csv")
    try:
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline and proc.poll() is None:
            if table.path.exists() and table.read():
                break
            time.sleep(0.2)
        assert proc.poll() is None, "the campaign ended before it could be interrupted"
        tree = psutil.Process(proc.pid).children(recursive=True)  # workers, fork servers, the runs under way
        assert any("roe_sep.campaign.forkserver" in " ".join(p.cmdline()) for p in tree), [p.cmdline() for p in tree]
        proc.send_signal(signal.SIGINT)
        _, stderr = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, stderr[-2000:]
    before = table.read()
    assert 1 <= len(before) < runs
    time.sleep(1.0)  # the kernel kills a run process when its fork server ends, and that when its worker ends
    left = [p for p in tree if p.is_running() and p.status() != psutil.STATUS_ZOMBIE]
    assert not left, f"processes outlived their campaign: {[p.cmdline() for p in left]}"
    rerun = subprocess.run(cmd, env=env, cwd=ROOT, capture_output=True, text=True, timeout=900)
    rep = _strict(rerun.stdout)
    assert rep["executed_now"] == runs - len(before) and rep["skipped_done"] == len(before)
    rows = table.read()
    assert sorted(rows) == list(range(SEED, SEED + runs)) and all(r["status"] == "ok" for r in rows.values())
    assert {s: _comparable(rows[s]) for s in before} == {s: _comparable(r) for s, r in before.items()}
    reference = Table(done / "runs.csv").read()
    assert {s: _comparable(rows[s]) for s in reference} == {s: _comparable(r) for s, r in reference.items()}


@pytest.mark.dds
def test_run_k_alone_gives_the_same_row(campaign):
    """``roe-sep run --seed S+k`` in its default layout (two processes, with the ground_bridge) gives the row the
    campaign's one-process run wrote."""
    from roe_sep.run import run

    out, _, params, _ = campaign
    k = 1
    seed = SEED + k
    overrides = out / "runs" / str(seed) / "overrides.yaml"
    # the run's overrides are the campaign's --params plus the radar seed
    assert yaml.safe_load(overrides.read_text())["planner"]["ros__parameters"]["mc_samples"] == 20000
    rep = run(out=out.parent / "alone", params=str(overrides), duration=DURATION, seed=seed,
              domain_id=int(_domains().split("-")[0]), timeout=600)
    assert rep["run"]["layout"] == "suites (events executor)"
    assert _comparable(row_from_report(seed, rep)) == _comparable(Table(out / "runs.csv").read()[seed])


@pytest.fixture
def dask_cluster(tmp_path):
    """An existing Dask cluster as an operator starts one: a ``dask scheduler`` process, every port on 127.0.0.1;
    yields its address and ``add_worker()``, which starts a ``dask worker`` process (one thread) joining it."""
    dask = Path(sys.executable).with_name("dask")
    sched_file = tmp_path / "scheduler.json"
    procs = [subprocess.Popen([str(dask), "scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                               "--dashboard-address", "127.0.0.1:0", "--scheduler-file", str(sched_file)],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path)]

    def add_worker():
        procs.append(subprocess.Popen([str(dask), "worker", address, "--nthreads", "1", "--nworkers", "1",
                                       "--host", "127.0.0.1", "--no-dashboard", "--local-directory",
                                       str(tmp_path / "worker")], stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, cwd=tmp_path))

    try:
        deadline = time.monotonic() + 60
        while not sched_file.exists() and time.monotonic() < deadline:
            time.sleep(0.2)
        address = json.loads(sched_file.read_text())["address"]
        assert address.startswith("tcp://127.0.0.1:")
        yield address, add_worker
    finally:
        for proc in reversed(procs):
            proc.terminate()
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()


@pytest.mark.dds
def test_campaign_on_an_existing_cluster_gives_the_rows_of_the_embedded_one(campaign, dask_cluster, tmp_path):
    """``--scheduler tcp://...``: joined while the cluster has no worker, the campaign says so and waits; once a
    worker joins, the runs go to it and write the rows the embedded two-worker cluster wrote for the same seeds
    (with ``--no-bags``: without keeping the runs' bags)."""
    import threading

    done, _, params, _ = campaign
    address, add_worker = dask_cluster
    out = tmp_path / "c"
    seeds = (SEED + 1, 2)  # the fixture's last two seeds
    cmd = [sys.executable, "-m", "roe_sep.cli", "campaign", "--runs", str(seeds[1]), "--seed", str(seeds[0]),
           "--duration", str(DURATION), "--scheduler", address, "--params", str(params), "--out", str(out),
           "--domains", _domains(), "--open-loop-samples", "1000", "--no-figures", "--no-bags", "--json"]
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    proc = subprocess.Popen(cmd, env=env, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    stderr, waiting = [], threading.Event()

    def read_stderr():
        for line in proc.stderr:
            stderr.append(line)
            if "has no worker yet" in line:
                waiting.set()

    reader = threading.Thread(target=read_stderr, daemon=True)
    reader.start()
    try:
        assert waiting.wait(120), "".join(stderr)[-2000:]
        assert not (out / "runs.csv").exists()  # nothing runs without a worker
        add_worker()
        proc.wait(timeout=600)  # the JSON report (a few kB) fits the pipe
        stdout = proc.stdout.read()
    finally:
        if proc.poll() is None:
            proc.kill()
    reader.join(10)
    rep = _strict(stdout)
    assert proc.returncode == 0 and rep["scheduler"] == address and rep["workers"] is None, "".join(stderr)[-2000:]
    assert rep["executed_now"] == seeds[1] and rep["completed"] == seeds[1]
    rows, reference = Table(out / "runs.csv").read(), Table(done / "runs.csv").read()
    assert sorted(rows) == [seeds[0], seeds[0] + 1]
    assert {s: _comparable(r) for s, r in rows.items()} == {s: _comparable(reference[s]) for s in rows}
    # --no-bags: the runs' bags removed once their rows were written, their reports kept
    assert all(not (out / "runs" / str(s) / "bag").exists() and (out / "runs" / str(s) / "report.json").exists()
               for s in rows)
    assert all((done / "runs" / str(s) / "bag").is_dir() for s in rows)  # kept by default


@pytest.mark.dds
@pytest.mark.fault
def test_failed_run_is_a_row_with_its_reason(tmp_path):
    params = tmp_path / "bad.yaml"
    # a parameter its table accepts (a path) that the node refuses at start-up (no such file)
    params.write_text(yaml.safe_dump({"sim": {"ros__parameters": {"scenario_file": str(tmp_path / "missing.yaml")}},
                                      "planner": {"ros__parameters": {"mc_samples": 20000}}}))
    proc = _cli("--runs", "1", "--seed", "3", "--duration", str(DURATION), "--workers", "1", "--timeout", "120",
                "--params", str(params), "--out", str(tmp_path / "c"), "--no-figures")
    assert proc.returncode == 1  # a failed run: the campaign completes, its status says so
    rep = _strict(proc.stdout)
    row = Table(tmp_path / "c" / "runs.csv").read()[3]
    assert row["status"] == "failed" and row["failure"] == "node_exit"
    # the run's one process names the node that refused its parameters
    assert "exited early" in row["reason"] and "sim" in row["reason"] and "parameter 'scenario_file'" in row["reason"]
    assert rep["failed"] == 1 and rep["failures"]["by_kind"] == {"node_exit": 1} and rep["p_safe"]["n"] == 0
    assert rep["p_safe_failures_unsafe"] == {"k": 0, "n": 1, "p": 0.0, "ci95": [0.0, pytest.approx(0.7935, abs=1e-4)]}
    assert not math.isnan(rep["p_safe_failures_unsafe"]["ci95"][1])


@pytest.mark.dds
def test_campaign_refuses_other_settings_in_the_same_directory(campaign):
    out, args, _, _ = campaign
    proc = _cli(*[a if a != str(DURATION) else "30000.0" for a in args], check=False)
    assert proc.returncode == 2 and "other duration" in proc.stderr and proc.stderr.count("\n") == 1


@pytest.mark.fault
@pytest.mark.parametrize("args, message", [
    (("--runs", "0"), "--runs"),
    (("--runs", "2", "--domains", "5-3"), "--domains"),
    (("--runs", "2", "--scheduler", "localhost:8786"), "--scheduler"),
    (("--runs", "2", "--seed", str(2**32 - 1)), "last seed"),
    (("--runs", "2", "--workers", "2", "--scheduler", "tcp://127.0.0.1:1"), "not allowed with"),
])
def test_bad_options_are_one_line_errors(tmp_path, args, message):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))  # the dds guard too
    proc = subprocess.run([sys.executable, "-m", "roe_sep.cli", "campaign", "--out", str(tmp_path / "c"), *args],
                          capture_output=True, text=True, env=env, cwd=ROOT, timeout=120)
    assert proc.returncode == 2 and message in proc.stderr and proc.stderr.strip().count("\n") == 0


def test_fork_server_forks_runs_and_ends_with_its_pipe(tmp_path):
    """The worker's fork server answers with the pid of a forked run, whose output goes to its log and whose exit
    status comes back (a run that fails: 1, with its reason), run after run; closing the pipe ends the server."""
    from roe_sep.campaign.forkserver import ForkServer

    srv = ForkServer()
    try:
        server = psutil.Process(srv.proc.pid)
        run = srv.spawn(["{not json"], tmp_path / "run.log")
        assert run.wait(timeout=60) == 1
        assert "JSONDecodeError" in (tmp_path / "run.log").read_text()
        run = srv.spawn([json.dumps({"out": str(tmp_path / "out"), "params": str(tmp_path / "missing.yaml"),
                                     "seed": 1, "timeout": 60, "domain_id": 0,
                                     "config": str(tmp_path / "missing_config.yaml")})], tmp_path / "run2.log")
        assert run.wait(timeout=120) == 1 and run.poll() == 1
        assert "missing.yaml" in (tmp_path / "run2.log").read_text()
    finally:
        srv.close()
    assert srv.proc.returncode == 0 and not server.is_running()
