from pathlib import Path

import pytest
import yaml

from roe_sep.core.config import ConfigError, Scenario, load_scenario, scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]


def test_shipped_default_yaml_equals_the_embedded_defaults():
    assert load_scenario(ROOT / "config" / "default.yaml") == Scenario()
    assert load_scenario(None) == Scenario()


def test_partial_override():
    s = scenario_from_dict({"separation": {"k": 1}, "monte_carlo": {"samples": 10, "p_values": [0.05]}})
    assert s.separation.k == 1 and s.monte_carlo.samples == 10 and s.p_values == (0.05,)
    assert s.separation.spl_dv == Scenario().separation.spl_dv
    assert scenario_from_dict({"separation": {"spl_dv": 2}}).separation.spl_dv == 2.0  # ints accepted for floats


@pytest.mark.parametrize(
    "data,match",
    [
        ({"sepration": {}}, r"unknown section\(s\) \['sepration'\]"),
        ({"separation": {"spl_dvv": 1.0}}, r"separation: unknown key\(s\) \['spl_dvv'\]"),
        ({"separation": {"spl_dv": "1.41"}}, "separation.spl_dv: expected a number"),
        ({"separation": {"spl_dv": float("nan")}}, "separation.spl_dv: expected a finite number"),
        ({"separation": {"leading": 1}}, "separation.leading: expected true/false"),
        ({"separation": {"k": 3.0}}, "separation.k: expected an integer"),
        ({"separation": {"k": True}}, "separation.k: expected an integer"),
        ({"monte_carlo": {"carrier": {"mass": "heavy"}}}, "monte_carlo.carrier.mass: expected a number"),
        ({"monte_carlo": {"carrier": [1, 2]}}, "monte_carlo.carrier: expected a mapping"),
        ({"monte_carlo": {"p_values": []}}, "monte_carlo.p_values"),
        ({"monte_carlo": {"p_values": [0.1, -0.1]}}, "non-negative"),
        ({"monte_carlo": {"p_values": [0.1, "x"]}}, r"monte_carlo.p_values\[1\]"),
        ([1, 2], "top level"),
    ],
)
def test_bad_values_are_named(data, match):
    with pytest.raises(ConfigError, match=match):
        scenario_from_dict(data)


def test_unreadable_and_invalid_files(tmp_path):
    with pytest.raises(ConfigError, match="cannot read configuration"):
        load_scenario(tmp_path / "missing.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("separation: [unclosed\n")
    with pytest.raises(ConfigError, match="not valid YAML"):
        load_scenario(bad)
    empty = tmp_path / "empty.yaml"
    empty.write_text("")
    assert load_scenario(empty) == Scenario()
    assert yaml.safe_load("") is None
