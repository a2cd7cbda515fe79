import json
import subprocess
import sys

import pytest

from roe_sep.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_design_json_keys_and_values(capsys):
    code, out, _ = run_cli(capsys, "design", "--json")
    assert code == 0
    rep = json.loads(out)
    assert rep["dv1_rtn"] == pytest.approx([-1.329250, -0.162718, 0.441269], abs=5e-7)
    assert rep["dv2_rtn"] == pytest.approx([-1.329250, 0.162718, 0.0], abs=5e-7)
    assert rep["dv2_carrier_rtn"] == pytest.approx([1.329250, -0.162718, 0.0], abs=5e-7)
    assert rep["k"] == 3
    assert rep["p_min_3sigma"] == pytest.approx(0.0732231, abs=5e-8)
    for key in ("a_de_min", "a_de_max", "a_di_min", "a_di_max", "a_dl_min", "a_dl_max"):
        assert key in rep["bounds"]


def test_design_table(capsys):
    code, out, _ = run_cli(capsys, "design")
    assert code == 0
    assert "-1.329250 -0.162718 +0.441269" in out
    assert "0.0732231 <= |p|" in out


def test_mc_json(capsys):
    code, out, _ = run_cli(capsys, "mc", "--samples", "3000", "--seed", "2", "--p", "0,0.05,0.08", "--json")
    assert code == 0
    rep = json.loads(out)
    assert [r["p"] for r in rep["rows"]] == [0.0, 0.05, 0.08]
    assert all(0.0 <= r["p_approach"] <= 1.0 and 0.0 <= r["p_evaporation"] <= 1.0 for r in rep["rows"])
    assert rep["p_best"] in (0.0, 0.05, 0.08)
    assert rep["samples"] == 3000


@pytest.mark.slow
def test_mc_plots(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    code, out, _ = run_cli(capsys, "mc", "--samples", "2000", "--p", "0,0.05", "--plots", str(tmp_path), "--json")
    assert code == 0
    figures = json.loads(out)["figures"]
    assert len(figures) >= 5
    for f in figures:
        with open(f, "rb") as fh:
            assert fh.read(8) == b"\x89PNG\r\n\x1a\n"


def test_bad_config_exits_2_with_a_message(capsys, tmp_path):
    cfg = tmp_path / "c.yaml"
    cfg.write_text("separation: {a_de_f: 300.0}\n")
    code, out, err = run_cli(capsys, "design", "--config", str(cfg))
    assert code == 2 and out == ""
    assert "safety #6" in err


def test_bad_arguments_are_refused():
    for argv in (["mc", "--p", "x"], ["mc", "--samples", "0"], ["frobnicate"]):
        proc = subprocess.run([sys.executable, "-m", "roe_sep.cli", *argv], capture_output=True, text=True)
        assert proc.returncode == 2
        assert "error" in proc.stderr
