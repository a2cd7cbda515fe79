"""Contingencies as scenario inputs: the ``contingency:`` block and its errors, the draws from their own
stream of the seed, what each contingency changes in the simulator's burn execution and the radar (and nothing
else), and the safety monitor's detection of what it can see (core.safety.anomaly)."""

import math

import numpy as np
import pytest

from roe_sep.core.config import Scenario, load_scenario, scenario_from_dict
from roe_sep.core.relmotion.dynamics import arg_latitude_rate
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import angle_between, mean_motion
from roe_sep.core.relmotion.trajectory import Chief
from roe_sep.core.safety.anomaly import AnomalyLimits, AnomalyWatch
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.contingency import (
    NAMES,
    SPECS,
    ContingencyConfig,
    RadarContingency,
    TruthContingency,
    contingency_from_dict,
    default_config,
    draw,
    resolve,
    rotate_normal,
)
from roe_sep.core.truth.execution import BurnExecution
from roe_sep.core.truth.simulated import SimulatedTruth, dispersed_truth
from roe_sep.errors import ConfigError

D = design()
DRIFT_STOP = "/separation/drift_stop_plan"
ACQ = "/acquisition/plan"
PERIOD = 2 * math.pi / float(arg_latitude_rate(D.a, D.inc, True))


# ---------------------------------------------------------------------------------------------------- configuration
def test_the_ten_contingencies_of_the_issue():
    assert set(NAMES) == {"spl_weak", "drift_stop_delayed", "drift_stop_missed", "radar_pass_missed",
                          "burn_underperformance", "radar_bias", "ejection_pointing", "carrier_safe_mode",
                          "drift_stop_overperformance", "density_storm"}
    c = default_config("spl_weak")
    assert c.get("spl_fraction") == (0.0, 0.5) and c.get("residual_dv") == 0.0
    assert default_config("drift_stop_delayed").get("delay_orbits") == (1, 3)
    assert default_config("burn_underperformance").get("magnitude") == (0.5, 0.8)
    assert default_config("burn_underperformance").get("pointing_deg") == (5.0, 15.0)
    assert default_config("radar_pass_missed").get("passes") == (1, 2)
    assert default_config("radar_bias").get("bias_m") == (10.0, 50.0)


def test_scenario_block_and_no_block():
    assert load_scenario(None).contingency is None and scenario_from_dict({}).contingency is None
    assert scenario_from_dict({"contingency": None}).contingency is None
    assert scenario_from_dict({"contingency": {"name": "none"}}).contingency is None
    s = scenario_from_dict({"contingency": {"name": "spl_weak", "spl_fraction": 0.2}})
    assert s.contingency == ContingencyConfig("spl_weak", (("residual_dv", 0.0), ("spl_fraction", 0.2)))
    # a scenario without a block is what it was (its repr: the campaign's settings hash), with one it differs there
    assert "contingency" not in repr(Scenario()) and repr(s) == repr(Scenario())
    r = scenario_from_dict({"contingency": {"name": "drift_stop_delayed", "delay_orbits": [2, 2]}}).contingency
    assert r.get("delay_orbits") == (2, 2)


@pytest.mark.parametrize("block, message", [
    ("spl_weak", r"^contingency: expected a mapping"),
    ({"name": "spl_strong"}, r"^contingency.name: expected one of \['spl_weak', .*'none'\], got 'spl_strong'"),
    ({}, r"^contingency.name: expected one of"),
    ({"name": "spl_weak", "magnitude": 0.5}, r"^contingency: unknown key\(s\) \['magnitude'\] for spl_weak; its "
                                             r"parameters: \['residual_dv', 'spl_fraction'\]"),
    ({"name": "spl_weak", "spl_fraction": 1.5}, r"^contingency.spl_fraction: expected a finite number in \[0, 1\]"),
    ({"name": "spl_weak", "spl_fraction": [0.4, 0.1]}, r"^contingency.spl_fraction: expected \[lo, hi\] with lo <= "
                                                       r"hi, got \[0.4, 0.1\]"),
    ({"name": "spl_weak", "spl_fraction": [0.1, 0.2, 0.3]}, r"^contingency.spl_fraction: expected a number or \[lo"),
    ({"name": "spl_weak", "spl_fraction": [0.1, "x"]}, r"^contingency.spl_fraction\[1\]: expected a number"),
    ({"name": "spl_weak", "spl_fraction": True}, r"^contingency.spl_fraction: expected a number or \[lo, hi\]"),
    ({"name": "spl_weak", "residual_dv": [0.0, 0.1]}, r"^contingency.residual_dv: expected a number, got"),
    ({"name": "drift_stop_delayed", "delay_orbits": 1.5}, r"^contingency.delay_orbits: expected an integer"),
    ({"name": "drift_stop_delayed", "delay_orbits": [0, 3]}, r"^contingency.delay_orbits\[0\]: expected an integer "
                                                             r"in \[1, 10\] orbits, got 0"),
    ({"name": "burn_underperformance", "mode": "both"}, r"^contingency.mode: expected one of \['magnitude', "
                                                       r"'pointing'\], got 'both'"),
    ({"name": "radar_bias", "station": 3}, r"^contingency.station: expected a string, got 3"),
    ({"name": "radar_pass_missed", "outage": -1.0}, r"^contingency.outage: expected a finite number in"),
    ({"name": "none", "passes": 1}, r"^contingency: 'name: none' takes no parameters"),
])
def test_bad_blocks_are_named(block, message):
    with pytest.raises(ConfigError, match=message):
        scenario_from_dict({"contingency": block})


def test_a_bad_block_in_a_file_names_the_file_and_the_key(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text("contingency:\n  name: radar_bias\n  bias_m: [10.0, 100000.0]\n", encoding="utf-8")
    with pytest.raises(ConfigError, match=rf"^configuration {path}: contingency.bias_m\[1\]: expected a finite"):
        load_scenario(path)
    with pytest.raises(ConfigError, match=r"unknown section\(s\) \['contingencies'\]; known: \['separation', "
                                          r"'monte_carlo', 'contingency', 'earth'\]"):
        scenario_from_dict({"contingencies": {}})


def test_resolve_the_parameter_against_the_block():
    block = contingency_from_dict({"name": "spl_weak", "spl_fraction": 0.3})
    assert resolve(block, "") is block and resolve(None, "") is None
    assert resolve(block, "none") is None
    assert resolve(block, "spl_weak") is block
    assert resolve(block, "radar_bias") == default_config("radar_bias")
    with pytest.raises(ConfigError, match="contingency: expected one of"):
        resolve(block, "meteor")


def test_draws_are_seeded_in_range_and_fixed_values_kept():
    for name in NAMES:
        c = default_config(name)
        assert draw(c, 7) == draw(c, 7)
        for seed in range(40):
            v = draw(c, seed)
            for key, spec in SPECS[name].items():
                conf = c.get(key)
                if isinstance(conf, tuple):
                    assert conf[0] <= v[key] <= conf[1]
                    assert isinstance(v[key], int if spec.kind == "irange" else float)
                else:
                    assert v[key] == conf
    orbits = {draw(default_config("drift_stop_delayed"), s)["delay_orbits"] for s in range(60)}
    assert orbits == {1, 2, 3}
    fixed = contingency_from_dict({"name": "spl_weak", "spl_fraction": 0.25})
    assert all(draw(fixed, s)["spl_fraction"] == 0.25 for s in range(5))


# ---------------------------------------------------------------------------------------------------- the simulator
def world(contingency=None, seed=3):
    return dispersed_truth(Scenario(), D, 0.3, D.u1 - 0.2, seed, disperse=True, dynamics="secular", j2=True,
                           ejection_delay_max=10.0, contingency=contingency)


def fly(contingency=None, seed=3, plans=None):
    """The ejection at t = 100 s and the plans (source, burns), every burn flown at its epoch (approved):
    the executed burns [(epoch, u, dv, spacecraft, purpose)], the contingency drawn."""
    w = world(contingency, seed)
    truth = SimulatedTruth(w.model, 60.0, 10.0, 1000.0, lambda e, s: None, on_hour=lambda: None)
    ex = BurnExecution(truth, w.errors, w.ejection_delay, False, lambda lvl, text: None, contingency=w.contingency)
    ex.eject(100.0, [0.0, 0.0, 1.41], "picosatellite", "ejection")
    if plans is None:
        plans = [(DRIFT_STOP, [(3000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")]),
                 (ACQ, [(30000.0, [0.0, 0.01, 0.0], "carrier", "ic_acquisition"),
                        (33000.0, [0.0, -0.005, 0.01], "carrier", "ic_acquisition")])]
    for k, (source, burns) in enumerate(plans):
        ex.plan(source, 50.0 + k, burns, 0.0)
    done = []
    while ex.pending:
        burn = ex.take(ex.due(1e9)[0])
        b = ex.execute(burn)
        done.append((b.epoch, b.u, b.dv_rtn, b.spacecraft, b.purpose))
    return done, w


def test_no_contingency_draws_what_it_drew_and_a_contingency_keeps_the_other_draws():
    base, w0 = fly(None)
    again, _ = fly(None)
    assert [(e, d.tolist()) for e, _, d, _, _ in base] == [(e, d.tolist()) for e, _, d, _, _ in again]
    assert w0.contingency is None and "contingency" not in w0.applied()
    for name in ("spl_weak", "drift_stop_delayed", "burn_underperformance", "radar_bias"):
        _, w = fly(default_config(name))
        assert (w.ejection_delay, w.da_dot, w.drag_factor) == (w0.ejection_delay, w0.da_dot, w0.drag_factor)
        assert w.errors.applied == w0.errors.applied  # the same execution errors, burn by burn
        assert w.applied() == w0.applied()  # the dispersions as before: the contingency is recorded apart
    assert world(default_config("radar_bias")).contingency is None  # the radar's: nothing in the simulator


def test_spl_weak_scales_the_ejection_only():
    base, _ = fly(None)
    weak, w = fly(contingency_from_dict({"name": "spl_weak", "spl_fraction": [0.0, 0.5]}))
    f1 = w.contingency.values["spl_fraction"]
    assert 0.0 <= f1 <= 0.5
    assert weak[0][4] == "ejection" and np.allclose(weak[0][2], f1 * base[0][2], rtol=0, atol=1e-15)
    for b, c in zip(base[1:], weak[1:]):
        assert b[0] == c[0] and np.array_equal(b[2], c[2])  # the carrier's burns as commanded and dispersed
    applied = w.contingency.applied()
    assert applied["name"] == "spl_weak" and applied["configured"]["spl_fraction"] == [0.0, 0.5]
    assert "f1 = " in applied["events"][0]
    # f1 = 0 with the deployer's residual speed: the picosatellite drifts off at that speed along the ejection
    zero, _ = fly(contingency_from_dict({"name": "spl_weak", "spl_fraction": 0.0, "residual_dv": 0.02}))
    assert np.linalg.norm(zero[0][2]) == pytest.approx(0.02)
    assert angle_between(zero[0][2], base[0][2]) < 1e-12
    attached, _ = fly(contingency_from_dict({"name": "spl_weak", "spl_fraction": 0.0}))
    assert not np.any(attached[0][2])


def test_drift_stop_delayed_whole_orbits_late_at_its_argument_of_latitude():
    base, _ = fly(None)
    late, w = fly(contingency_from_dict({"name": "drift_stop_delayed", "delay_orbits": 2}))
    assert [b[4] for b in late] == [b[4] for b in base]
    ds0, ds = base[1], late[1]
    assert ds[4] == "drift_stop" and ds[0] == pytest.approx(ds0[0] + 2 * PERIOD)
    assert math.remainder(ds[1] - ds0[1], 2 * math.pi) == pytest.approx(0.0, abs=1e-9)
    assert np.array_equal(ds[2], ds0[2])  # the same burn, later
    assert [b[0] for b in late[2:]] == [b[0] for b in base[2:]]  # the acquisition on time
    assert "2 orbit(s) late" in w.contingency.applied()["events"][0]


def test_drift_stop_missed_never_executes_and_a_republished_plan_does_not_bring_it_back():
    base, _ = fly(None)
    plans = [(DRIFT_STOP, [(3000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")])] * 2  # restarted planner
    missed, w = fly(contingency_from_dict({"name": "drift_stop_missed"}), plans=plans)
    assert [b[4] for b in missed] == ["ejection"]
    assert len(w.contingency.events) == 1 and "not executed" in w.contingency.events[0]
    assert np.array_equal(missed[0][2], base[0][2])


def test_a_replacement_drift_stop_for_another_epoch_flies_and_cancels_a_late_one():
    """The contingency acts on the first drift-stop commanded; the planner's replacement (the same burn whole orbits
    later, a new plan on the same topic) flies, and replaces a delayed one still pending."""
    first = (DRIFT_STOP, [(3000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")])
    late = 3000.0 + 3 * PERIOD
    replacement = (DRIFT_STOP, [(late, [0.3, 0.05, 0.0], "carrier", "drift_stop")])
    missed, w = fly(contingency_from_dict({"name": "drift_stop_missed"}), plans=[first, replacement])
    assert [(b[4], b[0]) for b in missed] == [("ejection", missed[0][0]), ("drift_stop", late)]
    assert len(w.contingency.events) == 1
    delayed, w = fly(contingency_from_dict({"name": "drift_stop_delayed", "delay_orbits": 1}),
                     plans=[first, replacement])
    assert [(b[4], b[0]) for b in delayed][1:] == [("drift_stop", late)]  # the late one is not flown as well


def test_burn_underperformance_magnitude_and_pointing_on_the_nth_carrier_burn():
    base, _ = fly(None)
    low, w = fly(contingency_from_dict({"name": "burn_underperformance", "burn": 2}))
    f = w.contingency.values["magnitude"]
    assert 0.5 <= f <= 0.8
    assert np.array_equal(low[1][2], base[1][2]) and np.array_equal(low[3][2], base[3][2])
    assert np.allclose(low[2][2], f * base[2][2], rtol=0, atol=1e-15)
    turned, w = fly(contingency_from_dict({"name": "burn_underperformance", "mode": "pointing"}))
    angle = w.contingency.values["pointing_deg"]
    assert 5.0 <= angle <= 15.0
    assert math.degrees(angle_between(turned[1][2], base[1][2])) == pytest.approx(angle)
    assert np.linalg.norm(turned[1][2]) == pytest.approx(np.linalg.norm(base[1][2]))
    assert np.array_equal(turned[2][2], base[2][2])


def test_rotate_normal_turns_by_the_angle_about_a_normal_axis():
    for v in ([0.0, 0.1, 0.0], [0.3, 0.0, 0.0], [0.1, -0.2, 0.05]):
        for az in (0.0, 1.0, 4.0):
            r = rotate_normal(v, math.radians(7.0), az)
            assert math.degrees(angle_between(r, v)) == pytest.approx(7.0)
            assert np.linalg.norm(r) == pytest.approx(np.linalg.norm(v))
    assert not np.any(rotate_normal([0.0, 0.0, 0.0], 0.1, 0.0))


# ---------------------------------------------------------------------------------------------------- the radar
def test_radar_pass_missed_drops_the_first_passes_only():
    radar = RadarContingency(contingency_from_dict({"name": "radar_pass_missed", "passes": 2}), 1, ["TIRA", "X"])
    radar.pass_opened(0, 1, 100.0)
    radar.pass_opened(1, 1, 150.0)
    radar.pass_opened(0, 2, 6000.0)
    assert radar.dropped(0, 1, 110.0) and radar.dropped(1, 1, 160.0) and not radar.dropped(0, 2, 6010.0)
    assert radar.range_bias(0) == 0.0 and len(radar.applied()["events"]) == 2


def test_radar_outage_from_the_first_pass():
    radar = RadarContingency(contingency_from_dict({"name": "radar_pass_missed", "outage": 86400.0}), 1, ["TIRA"])
    assert not radar.dropped(0, 1, 50.0)  # nothing before the first pass
    radar.pass_opened(0, 1, 100.0)
    radar.pass_opened(0, 2, 50000.0)
    assert radar.dropped(0, 1, 100.0) and radar.dropped(0, 2, 50010.0) and not radar.dropped(0, 3, 86500.0)
    assert "radar outage from t = 100.0 s to t = 86500.0 s" in radar.events[0]


def test_radar_bias_at_one_station():
    block = contingency_from_dict({"name": "radar_bias", "station": "X"})
    radar = RadarContingency(block, 4, ["TIRA", "X"])
    assert radar.range_bias(0) == 0.0 and 10.0 <= radar.range_bias(1) <= 50.0
    assert not radar.dropped(1, 1, 0.0)
    assert RadarContingency(default_config("radar_bias"), 4, ["TIRA", "X"]).bias_station == 0
    with pytest.raises(ConfigError, match=r"contingency.station: 'Y' is not a radar station"):
        RadarContingency(contingency_from_dict({"name": "radar_bias", "station": "Y"}), 4, ["TIRA"])


def test_truth_contingency_of_the_radar_side_changes_nothing():
    tc = TruthContingency(default_config("radar_bias"), 1, PERIOD)
    assert tc.reschedule(10.0, "drift_stop", "carrier") == 10.0
    assert np.array_equal(tc.executed(np.array([0.1, 0.2, 0.3]), "ejection", "picosatellite", 1.0), [0.1, 0.2, 0.3])


# ---------------------------------------------------------------------------------------------------- detection
SIGMAS = (0.10, 0.05, 30.0 * math.pi / 648000.0)


def watch():
    w = AnomalyWatch(AnomalyLimits(), *SIGMAS)
    w.plan(DRIFT_STOP, [(3000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")], 0.0)
    return w


def test_a_burn_as_planned_raises_nothing():
    w = watch()
    assert w.at(3000.0) == [] and w.at(3050.0) == []
    rng = np.random.default_rng(0)
    for _ in range(200):  # within the thruster's 5 % and 30 arcsec: no false alarm at 3.5 sigma
        w2 = watch()
        dv = np.array([0.3, 0.05, 0.0]) * rng.normal(1.0, 0.05 / 3)
        assert w2.executed(3001.0, dv, "carrier", "drift_stop", 1.0) == []
    assert w.executed(3000.0, [0.1, 0.0, 0.0], "picosatellite", "ejection", 0.0) == []  # not the carrier's


def test_a_missed_then_late_drift_stop():
    w = watch()
    missing = w.at(3061.0)
    assert [d.name for d in missing] == ["burn_missing"] and missing[0].values["planned_epoch_s"] == 3000.0
    assert w.at(4000.0) == []  # raised once
    late = w.executed(3000.0 + PERIOD, [0.3, 0.05, 0.0], "carrier", "drift_stop", 1.0)
    assert [d.name for d in late] == ["burn_late"] and late[0].values["delay_s"] == pytest.approx(PERIOD)


def test_magnitude_and_pointing_off():
    w = watch()
    found = w.executed(3000.0, [0.21, 0.035, 0.0], "carrier", "drift_stop", 1.0)
    assert [d.name for d in found] == ["burn_magnitude"] and found[0].values["ratio"] == pytest.approx(0.7)
    w = watch()
    turned = rotate_normal([0.3, 0.05, 0.0], math.radians(5.0), 1.0)
    found = w.executed(3000.0, turned, "carrier", "drift_stop", 1.0)
    assert [d.name for d in found] == ["burn_pointing"] and found[0].values["angle_deg"] == pytest.approx(5.0)
    # a replaced plan's burns are expected no more
    w = watch()
    w.plan(DRIFT_STOP, [(9000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")], 0.0)
    assert w.at(5000.0) == [] and [d.name for d in w.at(9100.0)] == ["burn_missing"]


def od_of(roe, t, chief, sigma=5.0):
    return dict(t_now=t, t_od=t, roe=roe, cov6=np.eye(6) * sigma ** 2, chief=chief, da_dot=0.0,
                residual_rms=1.0, measurements=100)


def test_a_weak_ejection_makes_the_first_od_inconsistent():
    chief = Chief(D.a, D.inc, D.u1, 100.0)
    dv = np.array([0.0, 0.0, 1.41])  # along N: a di only, no drift
    nominal = delta_roe(dv, D.u1, D.a, mean_motion(D.a))
    t = 100.0 + 0.5 * 86400
    for f1, expect in ((1.05, []), (0.95, []), (0.5, ["od_inconsistent"]), (0.1, ["od_inconsistent"])):
        w = AnomalyWatch(AnomalyLimits(), *SIGMAS)
        w.ejection(100.0, dv, chief, 0.0)
        from roe_sep.core.relmotion.dynamics import propagate

        truth = propagate(f1 * nominal, t - 100.0, D.a, D.inc, True, da_dot=0.0)
        assert [d.name for d in w.od(**od_of(truth, t, chief))] == expect, f1
    # a second OD is predicted from the first
    assert w.od(**od_of(propagate(truth, 3600.0, D.a, D.inc, True, da_dot=0.0), t + 3600.0, chief)) == []


def test_the_measured_ejection_is_the_knowledge_until_an_od():
    """The footage's executed ejection (issue 41 part 2) replaces the commanded one: a weak ejection's first OD is
    consistent with it; after an OD a late estimate changes nothing."""
    from roe_sep.core.relmotion.dynamics import propagate

    chief = Chief(D.a, D.inc, D.u1, 100.0)
    dv = np.array([0.0, 0.0, 1.41])
    t = 100.0 + 0.5 * 86400
    truth = propagate(0.2 * delta_roe(dv, D.u1, D.a, mean_motion(D.a)), t - 100.0, D.a, D.inc, True, da_dot=0.0)
    w = AnomalyWatch(AnomalyLimits(), *SIGMAS)
    w.ejection(100.0, dv, chief, 0.0)
    w.measured_ejection(0.2 * dv, np.eye(3) * (0.001 * 0.28) ** 2)
    assert w.measured_from == "footage" and w.od(**od_of(truth, t, chief)) == []
    w.measured_ejection(dv, np.eye(3) * 1e-8)  # after an OD: ignored
    assert w.measured_from == "od" and w.knowledge[0] == t
    fresh = AnomalyWatch(AnomalyLimits(), *SIGMAS)
    fresh.measured_ejection(dv, np.eye(3))  # before the commanded ejection: nothing to replace
    assert fresh.knowledge is None


def test_od_residuals_beyond_their_chi_square():
    w = AnomalyWatch(AnomalyLimits(), *SIGMAS)
    roe = np.zeros(6)
    chief = Chief(D.a, D.inc, 0.0, 0.0)
    assert w.od(**od_of(roe, 0.0, chief)) == []
    bad = {**od_of(roe, 10.0, chief), "residual_rms": 1.6}
    assert [d.name for d in w.od(**bad)] == ["od_residuals"]
