"""Strict JSON (roe_sep.jsonutil) and the input checks (roe_sep.checks) shared by every command line."""

import argparse
import io
import json
import math

import numpy as np
import pytest

from roe_sep import checks, jsonutil


def test_non_finite_become_null_with_a_reason():
    rep = {"a": 1.0, "rows": [{"p": 0.05, "mean": float("nan")}, {"p": 0.1, "mean": np.float64(np.inf)}],
           "arr": np.array([1.0, -np.inf]), "n": np.int64(3), "ok": np.bool_(True), "t": (1, 2)}
    text = jsonutil.dumps(rep, why={"mean": "no sample in the class"})
    out = jsonutil.loads_strict(text)
    assert out["rows"][0]["mean"] is None and out["rows"][1]["mean"] is None and out["arr"] == [1.0, None]
    assert out["null_reasons"] == {"rows[0].mean": "NaN (no sample in the class)",
                                   "rows[1].mean": "+Infinity (no sample in the class)",
                                   "arr[1]": "-Infinity: not a finite number"}
    assert out["n"] == 3 and out["ok"] is True and out["t"] == [1, 2] and out["a"] == 1.0
    assert "null_reasons" not in jsonutil.loads_strict(jsonutil.dumps({"x": 1.5}))  # nothing nulled, no key


def test_strict_parser_and_writer_refuse_nan():
    with pytest.raises(ValueError, match="NaN"):
        jsonutil.loads_strict('{"x": NaN}')
    with pytest.raises(ValueError):
        jsonutil.loads_strict(json.dumps({"x": math.inf}))
    with pytest.raises(TypeError, match="x"):
        jsonutil.strict_json({"x": object()})
    with pytest.raises(ValueError, match="top-level"):
        jsonutil.with_null_reasons([float("nan")])  # nowhere to explain it
    fh = io.StringIO()
    jsonutil.dump({"x": [float("nan")], "null_reasons": {"y": "kept"}}, fh)
    assert jsonutil.loads_strict(fh.getvalue())["null_reasons"] == {"y": "kept", "x[0]": "NaN: not a finite number"}


def test_option_types_name_the_range_and_the_value():
    parse = checks.finite_float(0.0, 10.0, lo_open=True, unit="m/s")
    assert parse("1.5") == 1.5 and parse("10") == 10.0
    for bad in ("nan", "inf", "-inf", "0", "-1", "10.01", "abc", "", "1e308"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"expected a finite number in \(0, 10\] m/s, got"):
            parse(bad)
    seed = checks.seed()
    assert seed("0") == 0 and seed(str(checks.SEED_MAX)) == checks.SEED_MAX
    for bad in ("-1", str(checks.SEED_MAX + 1), "1.0", "1e3", "nan"):
        with pytest.raises(argparse.ArgumentTypeError, match=r"an integer in \[0, 4294967295\]"):
            seed(bad)
    roe = checks.number_list(-1e6, 1e6, length=6)
    assert roe("0,100,0,0,0,0") == (0.0, 100.0, 0.0, 0.0, 0.0, 0.0)
    for bad in ("1,2,3", "0,nan,0,0,0,0", "", ",", "a,b,c,d,e,f"):
        with pytest.raises(argparse.ArgumentTypeError, match="6 comma-separated values"):
            roe(bad)
    assert checks.check_number("k", 3, 1, 99, integer=True) == 3
    with pytest.raises(ValueError, match=r"^k: expected an integer in \[1, 99\], got True$"):
        checks.check_number("k", True, 1, 99, integer=True)
    with pytest.raises(ValueError, match=r"^rules.time_step_s: expected a finite number in \(0, 600\] s, got 0$"):
        checks.check_number("rules.time_step_s", 0, 0.0, 600.0, lo_open=True, unit="s")


def test_one_line_parser(capsys):
    p = checks.OneLineParser(prog="x")
    p.add_argument("--n", type=checks.integer(1, 5))
    with pytest.raises(SystemExit) as exc:
        p.parse_args(["--n", "9"])
    assert exc.value.code == 2
    err = capsys.readouterr().err
    assert err == "x: error: argument --n: expected an integer in [1, 5], got '9' (see x --help)\n"
    assert checks.one_line("a\n  b\n\nc") == "a; b; c"
