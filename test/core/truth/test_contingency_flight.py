"""The contingencies of issue 41 part 6, each injected by the simulator where it happens in flight: the ejection
turned about the orbit normal (``ejection_pointing``), the carrier's safe mode losing its time-tagged burns
(``carrier_safe_mode``), a drift-stop that overperforms (``drift_stop_overperformance``) and a density storm in the
truth's drag (``density_storm``): the block's errors, the draws, what each turns, drops or scales and nothing else,
and the storm's window in both truth models. The closed loop: test/cli/test_contingency_run.py."""

import math

import numpy as np
import pytest

from roe_sep.core.config import Scenario, scenario_from_dict
from roe_sep.core.relmotion.dynamics import arg_latitude_rate
from roe_sep.core.relmotion.orbit import angle_between
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.contingency import (
    SIM_SIDE,
    DensityStorm,
    TruthContingency,
    contingency_from_dict,
    default_config,
    draw,
    rotate_about_normal,
)
from roe_sep.core.truth.execution import BurnExecution
from roe_sep.core.truth.simulated import SimulatedTruth, dispersed_truth
from roe_sep.errors import ConfigError

D = design()
DRIFT_STOP = "/separation/drift_stop_plan"
ACQ = "/acquisition/plan"
PERIOD = 2 * math.pi / float(arg_latitude_rate(D.a, D.inc, True))
NEW = ("ejection_pointing", "carrier_safe_mode", "drift_stop_overperformance", "density_storm")
H = 3600.0


def world(contingency=None, seed=3, dynamics="secular"):
    return dispersed_truth(Scenario(), D, 0.3, D.u1 - 0.2, seed, disperse=True, dynamics=dynamics, j2=True,
                           ejection_delay_max=10.0, contingency=contingency)


def fly(contingency=None, seed=3, plans=None):
    """The ejection commanded at t = 100 s and the plans (source, burns), every burn due flown in epoch order
    (approved): the executed burns [(epoch, dv, spacecraft, purpose)] and the world."""
    w = world(contingency, seed)
    truth = SimulatedTruth(w.model, 60.0, 10.0, 1000.0, lambda e, s: None, on_hour=lambda: None)
    ex = BurnExecution(truth, w.errors, w.ejection_delay, False, lambda lvl, text: None, contingency=w.contingency)
    ex.eject(100.0, D.dv1_rtn, "picosatellite", "ejection")
    if plans is None:
        plans = [(DRIFT_STOP, [(9000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")]),
                 (ACQ, [(30000.0, [0.0, 0.01, 0.0], "carrier", "ic_acquisition"),
                        (100000.0, [0.0, -0.005, 0.01], "carrier", "ic_acquisition")])]
    for k, (source, burns) in enumerate(plans):
        ex.plan(source, 50.0 + k, burns, 0.0)
    done = []
    while True:
        due = ex.due(1e9)  # the safe mode's losses come off here
        if not due:
            break
        b = ex.execute(ex.take(due[0]))
        done.append((b.epoch, b.dv_rtn, b.spacecraft, b.purpose))
    return done, w


# ---------------------------------------------------------------------------------------------------- configuration
def test_the_four_are_the_simulators_with_their_defaults():
    assert set(NEW) <= set(SIM_SIDE)
    assert default_config("ejection_pointing").get("angle_deg") == (-10.0, 10.0)
    assert default_config("carrier_safe_mode").get("hours") == (6.0, 24.0)
    assert default_config("carrier_safe_mode").get("start_h") == (0.0, 12.0)
    assert default_config("drift_stop_overperformance").get("magnitude") == (1.1, 1.5)
    c = default_config("density_storm")
    assert (c.get("factor"), c.get("start_h"), c.get("hours")) == ((2.0, 5.0), (6.0, 30.0), (6.0, 24.0))


@pytest.mark.parametrize("block, message", [
    ({"name": "ejection_pointing", "angle_deg": 190.0}, r"^contingency.angle_deg: expected a finite number in "
                                                        r"\[-180, 180\] deg, got 190"),
    ({"name": "ejection_pointing", "angle_deg": [5.0, -5.0]}, r"^contingency.angle_deg: expected \[lo, hi\] with "
                                                              r"lo <= hi"),
    ({"name": "ejection_pointing", "pointing_deg": 5.0}, r"^contingency: unknown key\(s\) \['pointing_deg'\] for "
                                                         r"ejection_pointing; its parameters: \['angle_deg'\]"),
    ({"name": "carrier_safe_mode", "hours": -1.0}, r"^contingency.hours: expected a finite number in \[0, 720\] h"),
    ({"name": "carrier_safe_mode", "start_h": [0.0, "x"]}, r"^contingency.start_h\[1\]: expected a number"),
    ({"name": "drift_stop_overperformance", "magnitude": 0.9}, r"^contingency.magnitude: expected a finite number "
                                                               r"in \[1, 3\]"),
    ({"name": "drift_stop_overperformance", "magnitude": [1.2, 3.5]}, r"^contingency.magnitude\[1\]: expected a "
                                                                      r"finite number in \[1, 3\]"),
    ({"name": "density_storm", "factor": -2.0}, r"^contingency.factor: expected a finite number in \[0, 100\]"),
    ({"name": "density_storm", "factor": True}, r"^contingency.factor: expected a number or \[lo, hi\]"),
    ({"name": "density_storm", "start_h": [30.0, 6.0]}, r"^contingency.start_h: expected \[lo, hi\] with lo <= hi"),
    ({"name": "density_storm", "hours": float("nan")}, r"^contingency.hours: expected a finite number"),
])
def test_bad_blocks_are_named(block, message):
    with pytest.raises(ConfigError, match=message):
        scenario_from_dict({"contingency": block})


def test_draws_in_range_from_the_contingency_stream():
    for seed in range(30):
        assert -10.0 <= draw(default_config("ejection_pointing"), seed)["angle_deg"] <= 10.0
        v = draw(default_config("carrier_safe_mode"), seed)
        assert 0.0 <= v["start_h"] <= 12.0 and 6.0 <= v["hours"] <= 24.0
        assert 1.1 <= draw(default_config("drift_stop_overperformance"), seed)["magnitude"] <= 1.5
        v = draw(default_config("density_storm"), seed)
        assert 2.0 <= v["factor"] <= 5.0 and 6.0 <= v["start_h"] <= 30.0 and 6.0 <= v["hours"] <= 24.0
    assert draw(default_config("density_storm"), 4) == draw(default_config("density_storm"), 4)
    fixed = contingency_from_dict({"name": "density_storm", "factor": 3.0})
    assert draw(fixed, 4)["factor"] == 3.0
    assert draw(fixed, 4)["start_h"] == draw(default_config("density_storm"), 4)["start_h"]  # the others kept


def test_every_other_dispersion_of_the_seed_is_kept():
    base, w0 = fly(None)
    for name in NEW:
        _, w = fly(default_config(name))
        assert (w.ejection_delay, w.da_dot, w.drag_factor) == (w0.ejection_delay, w0.da_dot, w0.drag_factor)
        assert w.errors.applied[:2] == w0.errors.applied[:2]  # the ejection's and the drift-stop's errors
        assert w.applied() == w0.applied() or name == "carrier_safe_mode"  # a lost burn draws no error


# ---------------------------------------------------------------------------------------------------- what each does
def test_rotate_about_normal():
    r = rotate_about_normal([1.0, 0.0, 0.3], math.radians(90.0))
    assert np.allclose(r, [0.0, 1.0, 0.3], atol=1e-15)  # R towards T, N kept
    v = D.dv1_rtn
    for deg in (-7.0, 3.0, 180.0):
        t = rotate_about_normal(v, math.radians(deg))
        assert np.linalg.norm(t) == pytest.approx(np.linalg.norm(v)) and t[2] == v[2]
        assert math.degrees(angle_between(t[:2], v[:2])) == pytest.approx(abs(deg))
    # -6.98 deg cancels the design's along-track ejection component (docs/contingencies.md)
    cancel = -math.atan(v[1] / v[0])
    assert math.degrees(cancel) == pytest.approx(-6.979, abs=1e-3)
    assert abs(rotate_about_normal(v, cancel)[1]) < 1e-15


def test_ejection_pointing_turns_the_ejection_only():
    base, _ = fly(None)
    turned, w = fly(contingency_from_dict({"name": "ejection_pointing", "angle_deg": -7.0}))
    assert turned[0][3] == "ejection"
    assert np.allclose(turned[0][1], rotate_about_normal(base[0][1], math.radians(-7.0)), rtol=0, atol=1e-15)
    for b, c in zip(base[1:], turned[1:]):
        assert b[0] == c[0] and np.array_equal(b[1], c[1])
    assert "turned by -7.00 deg about N" in w.contingency.events[0]


def test_drift_stop_overperformance_scales_the_first_drift_stop_only():
    plans = [(DRIFT_STOP, [(9000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop"),
                           (20000.0, [0.1, 0.0, 0.0], "carrier", "drift_stop")])]
    base, _ = fly(None, plans=plans)
    over, w = fly(default_config("drift_stop_overperformance"), plans=plans)
    f = w.contingency.values["magnitude"]
    assert 1.1 <= f <= 1.5
    assert np.array_equal(over[0][1], base[0][1])
    assert np.allclose(over[1][1], f * base[1][1], rtol=0, atol=1e-15)
    assert np.array_equal(over[2][1], base[2][1])  # the second drift-stop as it was
    assert len(w.contingency.events) == 1 and f"{f:.3f} of its magnitude" in w.contingency.events[0]


def test_carrier_safe_mode_loses_the_carrier_burns_of_its_window_only():
    block = contingency_from_dict({"name": "carrier_safe_mode", "start_h": 2.0, "hours": 8.0})
    base, _ = fly(None)
    t_ej = base[0][0]
    lost, w = fly(block)
    window = w.contingency.safe_mode_window()
    assert window == pytest.approx((t_ej + 2 * H, t_ej + 10 * H))
    # the drift-stop (9000 s) and the first acquisition burn (30000 s) are inside, the last one (100000 s) is not
    assert [(b[0], b[3]) for b in lost] == [(t_ej, "ejection"), (100000.0, "ic_acquisition")]
    events = w.contingency.events
    assert "carrier safe mode from" in events[0] and len(events) == 3
    assert "drift_stop commanded at t = 9000.0 s: not executed (carrier safe mode" in events[1]
    # a plan re-published for the same epoch inside the window is lost again, once recorded; one after it flies
    again = [(DRIFT_STOP, [(9000.0, [0.3, 0.05, 0.0], "carrier", "drift_stop")])] * 2 + \
        [(ACQ, [(t_ej + 10 * H, [0.0, 0.01, 0.0], "carrier", "ic_acquisition")])]
    flown, w = fly(block, plans=again)
    assert [b[3] for b in flown] == ["ejection", "ic_acquisition"] and len(w.contingency.events) == 2
    # before the ejection nothing is lost (the window starts at the executed ejection)
    tc = TruthContingency(block, 1, PERIOD)
    assert tc.safe_mode_window() is None and not tc.dropped(50.0, "drift_stop", "carrier")
    tc.executed(np.array(D.dv1_rtn), "ejection", "picosatellite", 100.0)
    assert tc.dropped(100.0 + 2 * H, "x", "carrier") and not tc.dropped(100.0 + 10 * H, "x", "carrier")
    assert not tc.dropped(100.0 + 3 * H, "x", "picosatellite")


# ---------------------------------------------------------------------------------------------------- the storm
def test_density_storm_window_and_factor():
    storm = DensityStorm(3.0, 6 * H, 12 * H)
    assert storm.window(100.0) == (100.0 + 6 * H, 100.0 + 18 * H)
    t = 100.0 + np.array([0.0, 6 * H - 1, 6 * H, 17 * H, 18 * H, 30 * H])
    assert storm.factor_at(t, 100.0).tolist() == [1.0, 1.0, 3.0, 3.0, 1.0, 1.0]
    assert storm.factor_at(t, None).tolist() == [1.0] * 6
    tc = TruthContingency(contingency_from_dict({"name": "density_storm", "factor": 3.0, "start_h": 6.0,
                                                 "hours": 12.0}), 1, PERIOD)
    assert tc.storm == storm
    assert TruthContingency(default_config("carrier_safe_mode"), 1, PERIOD).storm is None
    tc.executed(np.array(D.dv1_rtn), "ejection", "picosatellite", 100.0)
    assert tc.events == [f"density storm x3.000 from t = {100 + 6 * H:.1f} s to t = {100 + 18 * H:.1f} s"]


def storm_run(dynamics, storm, times):
    """The ejection at t = 0 (undispersed), the truth's ROE at ``times`` with ``storm`` (None: none)."""
    w = dispersed_truth(Scenario(), D, 0.3, D.u1, 0, disperse=False, dynamics=dynamics, j2=True,
                        ejection_delay_max=0.0)
    w.model.storm = storm
    w.model.apply(0.0, D.dv1_rtn, "picosatellite")
    return w.model.roe_at(np.asarray(times, dtype=float)), w


@pytest.mark.parametrize("dynamics", ["secular", "nonlinear"])
def test_density_storm_multiplies_the_drag_in_its_window(dynamics):
    """Before the storm the truth is the nominal one to the bit; in it the differential drag drifts da ``factor``
    times as fast; after it at the nominal rate again (both spacecraft see the density: their difference follows
    from their ballistic coefficients)."""
    storm = DensityStorm(4.0, 2 * H, 4 * H)
    times = np.array([1.0, 1.5, 2.0, 3.0, 6.0, 7.0, 8.0]) * H
    nominal, w = storm_run(dynamics, None, times)
    stormy, _ = storm_run(dynamics, storm, times)
    assert np.array_equal(stormy[:3], nominal[:3])  # to the storm's start, bit for bit
    da, da0 = stormy[:, 0], nominal[:, 0]
    rate0 = (da0[6] - da0[4]) / (2 * H)  # the nominal drift of da, per s
    assert rate0 < 0  # the picosatellite's larger ballistic coefficient
    assert (da[4] - da[2]) / (4 * H) == pytest.approx(4.0 * (da0[4] - da0[2]) / (4 * H), rel=0.15)
    assert (da[6] - da[4]) / (2 * H) == pytest.approx(rate0, rel=0.15)
    assert (da - da0)[6] == pytest.approx(3.0 * (da0[4] - da0[2]), rel=0.15)  # three storm-hours' more


def test_density_storm_is_applied_to_the_truth_of_a_run():
    w = world(default_config("density_storm"), dynamics="secular")
    assert w.model.storm == w.contingency.storm and w.model.storm is not None
    assert world(None).model.storm is None and world(default_config("ejection_pointing")).model.storm is None
