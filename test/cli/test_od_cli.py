"""``roe-sep od`` on a closed-loop run's own files: the reference run (bags/default_run) exported to CCSDS (its TDM,
its carrier OEM, its executed maneuvers), each burn-free arc of radar passes solved offline and compared with the
run's truth (NEES of the mean a*ROE in the chi-square band) and with the run's own OD of the same passes; the public
CCSDS example TDMs refused or read in one line; bad input exit 2 in one line (more cases: test_cli_bad_input.py)."""

import json
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from roe_sep import interfaces
from roe_sep.cli import main
from roe_sep.core.od.batch import nees
from roe_sep.ndm import frames
from roe_sep.report import read_topics, read_truth, truth_at, truth_secular_drift

ROOT = Path(__file__).resolve().parents[2]
BAG = ROOT / "bags" / "default_run"
EXAMPLES = ROOT / "test" / "data" / "ccsds_examples"
EPOCH = "2016-07-01T00:00:00"  # the reference run's sim time 0
NEES_P = 1e-3  # two-sided: a consistent estimator's NEES leaves the band once in 1000 arcs
# the burn-free arcs of the reference run's passes: (--until, passes); its carrier burns are at 02:32 on day 1,
# 00:20, 00:55, 04:05, 04:59 on day 2, 00:05 and 20:52, 20:58, 23:45 on day 3
ARCS = [("2016-07-01T21:05:00", 3), ("2016-07-01T23:30:00", 4), ("2016-07-02T23:30:00", 4),
        ("2016-07-03T20:45:00", 3)]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    out = tmp_path_factory.mktemp("od_cli")
    for fmt in ("xml", "kvn"):  # XML: read in a tenth of the time; KVN: the text the tests edit
        assert main(["export", str(BAG), "--out", str(out / fmt), "--format", fmt]) == 0
    return {"tdm": out / "xml" / "radar.tdm.xml", "oem": out / "xml" / "ephemeris.oem.xml",
            "opm": out / "xml" / "executed_carrier.opm.xml", "tdm_kvn": out / "kvn" / "radar.tdm.kvn",
            "oem_kvn": out / "kvn" / "ephemeris.oem.kvn", "out": out}


@pytest.fixture(scope="module")
def truth():
    data = read_topics(BAG, [interfaces.TRUTH_ROE_TOPIC, interfaces.EXECUTED_TOPIC],
                       raw=(interfaces.TRUTH_ROE_TOPIC,))
    burns = sorted({m.epoch.sec + m.epoch.nanosec * 1e-9 for _, m in data[interfaces.EXECUTED_TOPIC]})
    return read_truth(data[interfaces.TRUTH_ROE_TOPIC]), burns


def run_od(argv, capsys):
    try:
        code = main(["od", *argv])
    except SystemExit as exc:  # an option argparse refuses (one line, status 2)
        code = exc.code
    out = capsys.readouterr()
    return code, out.out, out.err


def solve(files, until, capsys, *extra):
    code, out, err = run_od(["--tdm", str(files["tdm"]), "--carrier-oem", str(files["oem"]), "--maneuvers",
                             str(files["opm"]), "--until", until, "--json", *extra], capsys)
    assert code == 0, err
    return json.loads(out, parse_constant=lambda c: pytest.fail(f"non-strict JSON {c}"))


def truth_mean_roe(truth, t):
    """The run's truth a*ROE [m] at sim time ``t`` with the secular a*da, as the run's report compares its OD."""
    tr, burns = truth
    at = truth_at(tr, t, -70.0)  # m/day: carries the last 10 s sample to t (0.01 m either way)
    secular = truth_secular_drift(tr, t, burns)
    at[0] = secular[0]
    return at, secular[1]


@pytest.mark.parametrize("until,passes", ARCS, ids=[a[0] for a in ARCS])
def test_closed_loop_arc_within_its_covariance(files, truth, capsys, until, passes):
    rep = solve(files, until, capsys)
    est = rep["estimate"]
    assert rep["measurements"]["passes"] == passes
    t = frames.sim_time(EPOCH, est["epoch"])
    at, _ = truth_mean_roe(truth, t)
    cov = np.asarray(est["covariance_a_roe_m2"])[:6, :6]
    value = nees(est["a_roe_m"], at, cov)
    lo, hi = stats.chi2.ppf([NEES_P / 2, 1 - NEES_P / 2], 6)
    assert lo <= value <= hi, f"NEES {value:.2f} outside [{lo:.2f}, {hi:.2f}] (6 dof)"
    c = rep["consistency"]
    assert c["dof"] == 3 * rep["measurements"]["used"] - 7
    lo, hi = stats.chi2.ppf([NEES_P / 2, 1 - NEES_P / 2], c["dof"]) / c["dof"]  # the printed band is 95 %
    assert c["band95"] == pytest.approx(stats.chi2.ppf([0.025, 0.975], c["dof"]) / c["dof"])
    assert lo <= c["chi2_per_dof"] <= hi, c
    assert all(p["n"] >= 5 and abs(p["range_m_mean"]) < 3 * 10.0 for p in rep["passes"])


def test_same_passes_as_the_run_give_the_runs_estimate(files, capsys):
    """The run's first OD (passes 1-3, at 21:00:00 = sim 75600 s): the offline OD of the same measurements agrees
    to a small fraction of its sigma. Not exactly: the carrier's plane comes from the OEM's neighbouring positions
    (offline_od.chief_elements), and the truth's mean elements scatter from one 300 s sample to the next (0.1 sigma
    of a*dix here)."""
    run = json.loads((ROOT / "bags" / "default_run.report.json").read_text())["od"]
    rep = solve(files, ARCS[0][0], capsys)
    assert rep["model"] == "circular"  # --model auto: our own run's OEM (ORIGINATOR ROE_SEP), its radar's model
    est = rep["estimate"]
    assert frames.sim_time(EPOCH, est["epoch"]) == pytest.approx(run["epoch"], abs=1e-3)
    assert rep["measurements"]["used"] == run["measurements"]
    z = (np.array(est["a_roe_m"]) - run["estimate"]) / np.array(run["sigma"])
    assert np.max(np.abs(z)) < 0.2, z
    assert np.allclose(est["a_roe_sigma_m"], run["sigma"], rtol=0.02)
    assert (est["a_da_dot_m_s"] - run["a_da_dot"]) / run["a_da_dot_sigma"] == pytest.approx(0.0, abs=0.2)


def test_writes_opm_with_covariance_and_oem_prediction(files, capsys, tmp_path):
    code, out, err = run_od(["--tdm", str(files["tdm"]), "--carrier-oem", str(files["oem"]), "--maneuvers",
                             str(files["opm"]), "--until", ARCS[2][0], "--out", str(tmp_path), "--predict", "2",
                             "--format", "kvn"], capsys)
    assert code == 0, err
    assert "consistency: chi-square" in out and "rejected:" in out and "before the latest maneuver" in out
    from roe_sep.ndm.messages import read_message

    opm = read_message(tmp_path / "od_estimate.opm.kvn")
    cov = opm.body.segment.data.covariance_matrix
    assert cov is not None and float(cov.cx_x.value) > 0.0
    oem = read_message(tmp_path / "od_prediction.oem.kvn")
    states = oem.body.segment[0].data.state_vector
    assert len(states) == 2 * 3600 // 300 + 1
    assert states[0].epoch.startswith(opm.body.segment.data.state_vector.epoch[:19])


def test_rejected_measurements_have_reasons(files, capsys):
    rep = solve(files, ARCS[2][0], capsys, "--since", "2016-07-01T12:00:00")
    reasons = {r["reason"].split(" (")[0] for r in rep["rejected"]}
    assert {"outside --since/--until", "before the latest maneuver"} <= reasons
    assert rep["measurements"]["used"] + rep["measurements"]["rejected"] == sum(
        1 for line in files["tdm_kvn"].read_text().splitlines() if line.startswith("RANGE "))


def test_a_tdm_tracking_two_objects_needs_the_target(files, capsys, tmp_path):
    """Pass 1 relabelled as tracking the carrier: refused without --target; with it, its measurements are rejected
    as another object's and the arc of passes 2-4 is solved."""
    text = files["tdm_kvn"].read_text()
    assert text.count("PARTICIPANT_2            = PICOSATELLITE") == 12
    two = tmp_path / "two.tdm"
    two.write_text(text.replace("PARTICIPANT_2            = PICOSATELLITE", "PARTICIPANT_2            = CARRIER", 1))
    argv = ["--tdm", str(two), "--carrier-oem", str(files["oem"]), "--maneuvers", str(files["opm"]), "--until",
            ARCS[1][0]]
    code, _, err = run_od(argv, capsys)
    assert code == 2 and "track 2 objects (CARRIER, PICOSATELLITE): give --target NAME" in err, err
    code, out, err = run_od([*argv, "--target", "PICOSATELLITE", "--json"], capsys)
    assert code == 0, err
    rep = json.loads(out)
    assert rep["measurements"]["passes"] == 3
    assert sum(r["reason"] == "tracks CARRIER, not PICOSATELLITE" for r in rep["rejected"]) == 42


def test_an_outlier_is_edited_out(files, capsys, tmp_path):
    """A range 300 m (30 sigma) off in pass 2: rejected by the editing with its chi-square (that one measurement
    only), the rest of the arc used and consistent."""
    lines = files["tdm_kvn"].read_text().splitlines()
    k = [i for i, ln in enumerate(lines) if ln.startswith("RANGE ")][60]  # pass 2 (pass 1 has 42)
    key, epoch, value = lines[k].split()[0], lines[k].split()[2], float(lines[k].split()[3])
    lines[k] = f"{key} = {epoch} {value + 0.3!r}"
    bad = tmp_path / "outlier.tdm"
    bad.write_text("\n".join(lines) + "\n")
    code, out, err = run_od(["--tdm", str(bad), "--carrier-oem", str(files["oem"]), "--maneuvers",
                             str(files["opm"]), "--until", ARCS[1][0], "--json"], capsys)
    assert code == 0, err
    rep = json.loads(out)
    edited = [r for r in rep["rejected"] if r["reason"].startswith("residual chi-square")]
    assert [r["epoch"][:19] for r in edited] == [epoch[:19]], edited
    clean = solve(files, ARCS[1][0], capsys)["measurements"]["used"]  # the same arc without the outlier
    assert rep["measurements"]["used"] == clean - 1 and rep["consistency"]["chi2_per_dof"] < 1.2


@pytest.mark.parametrize("name", sorted(p.name for p in EXAMPLES.glob("TDM*")))
def test_public_example_tdms_read_or_refused_in_one_line(name, files, capsys):
    code, out, err = run_od(["--tdm", str(EXAMPLES / name), "--carrier-oem", str(files["oem"])], capsys)
    assert code == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, (code, err)


@pytest.mark.parametrize("argv,needle", [
    (["--tdm", "{missing}", "--carrier-oem", "{oem}"], "{missing}"),
    (["--tdm", "{tdm}"], "--carrier-oem"),
    (["--tdm", "{oem}", "--carrier-oem", "{oem}"], "expected a TDM"),
    (["--tdm", "{tdm}", "--carrier-oem", "{tdm}"], "expected an OEM"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--maneuvers", "{opm}"], "1 pass counts"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--until", "2016-07-01T07:52:45", "--min-pass", "1",
      "--min-passes", "1"], "too few measurements"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--until", "2016-07-01T08:00:00"], "1 pass counts"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--until", "2016-06-01T00:00:00"], "no measurement"),
    (["--tdm", "{tdm}", "--carrier-oem", "{short_oem}"], "outside the carrier OEM"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--station", "OTHER,0,0,0"], "station TIRA is not known"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--station", "TIRA,95,0,0"], "--station"),
    (["--tdm", "{tdm}", "--carrier-oem", "{oem}", "--since", "July"], "--since"),
])
def test_bad_input_one_line_exit_2(argv, needle, files, capsys, tmp_path):
    short = tmp_path / "short.oem"
    text = files["oem_kvn"].read_text()
    head = "META_START".join(text.split("META_START")[:3])  # the header and the carrier's first two segments
    lines = head.splitlines()
    keep = [ln for ln in lines if not ln[:4].isdigit() or ln < "2016-07-01T03"]
    short.write_text("\n".join(keep).replace("STOP_TIME                = 2016-07-02T00:20:00.000000",
                                             "STOP_TIME                = 2016-07-01T02:59:00.000000") + "\n")
    names = {"missing": str(tmp_path / "none.tdm"), "tdm": str(files["tdm"]), "oem": str(files["oem"]),
             "opm": str(files["opm"]), "short_oem": str(short)}
    argv = [a.format(**names) for a in argv]
    code, out, err = run_od(argv, capsys)
    assert code == 2, (code, err)
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1 and needle.format(**names) in lines[0], err
