"""The first-orbit collision-avoidance rule on the measured ejection (roe_sep.core.decisions.cam, issue 41 part 2):
a nominal ejection is never acted on, a weak, stuck or mis-pointed one that comes back inside the keep-out gets a
carrier along-track CAM that keeps it out, one that stays out gets none, a late CAM is said not to clear, and the
predicted distance's sigma is the spread of the distances of sampled ejections."""

import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.decisions.cam import CamConfig, cam_decision, predicted_distance
from roe_sep.core.relmotion.dynamics import arg_latitude_rate, drag_da_dot
from roe_sep.core.relmotion.trajectory import Burn, Chief
from roe_sep.core.separation.double_impulse import design

SC = load_scenario(None)
D = design(SC.separation)
DA_DOT = float(drag_da_dot(SC.monte_carlo.delta_b, SC.monte_carlo.density, D.a))
CHIEF = Chief(D.a, D.inc, D.u1, 0.0)
CMD = np.asarray(D.dv1_rtn, dtype=float)
COV = np.diag([1.1e-3, 1.7e-4, 3.8e-4]) ** 2  # the footage's sigmas of seed 5's run (docs/run.md)
PERIOD = 2.0 * math.pi / float(arg_latitude_rate(D.a, D.inc, True))
CONFIG = CamConfig(spl_sigma=SC.separation.spl_sigma)
T_NOW = 300.0  # s: the footage processed (its window after the release)


def decide(dv, **changes):
    return cam_decision(dv, COV, CMD, CHIEF, T_NOW, da_dot=DA_DOT, config=CamConfig(**{**vars(CONFIG), **changes}))


def rotated_about_n(v, deg):
    c, s = math.cos(math.radians(deg)), math.sin(math.radians(deg))
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]])


@pytest.mark.parametrize("f1", [1.0, 0.8, 1.25])
def test_a_nominal_ejection_gets_no_cam(f1):
    d = decide(f1 * CMD)
    assert not d.off and d.burn is None and d.magnitude_z < CONFIG.off_sigmas and "within its command" in d.reason


def lower_after(dv, burns, t_from):
    times = np.arange(0.0, PERIOD + 5.0, CONFIG.step)
    rho, sig = predicted_distance(dv, COV, CHIEF, times, burns, da_dot=DA_DOT)
    low = rho - CONFIG.sigmas * sig
    out = np.nonzero(low >= CONFIG.keep_out)[0][0]
    return times, low, max(t_from, times[out])


@pytest.mark.parametrize("f1", [0.2, 0.3])
def test_a_weak_ejection_that_comes_back_gets_a_cam_that_keeps_it_out(f1):
    dv = f1 * CMD
    d = decide(dv)
    assert d.off and d.departs and d.returns and d.burn is not None
    times, low, t0 = lower_after(dv, (), T_NOW + CONFIG.latency)
    k = int(np.searchsorted(times, d.t_inside))
    assert low[k] < CONFIG.keep_out <= low[k - 1] and times[k - 1] >= t0  # the first re-entry after the departure
    assert d.closest < CONFIG.keep_out and d.t_inside < PERIOD
    burn = d.burn
    assert burn.spacecraft == "carrier" and burn.purpose == "collision_avoidance"
    assert burn.epoch == pytest.approx(T_NOW + CONFIG.latency) and abs(burn.dv_rtn[1]) == CONFIG.dv_cam
    assert burn.dv_rtn[0] == burn.dv_rtn[2] == 0.0
    assert d.cleared and d.closest_after >= CONFIG.keep_out
    times, low, t0 = lower_after(dv, (Burn(burn.epoch, tuple(-x for x in burn.dv_rtn)),), burn.epoch)
    assert np.all(low[times >= t0] >= CONFIG.keep_out)  # the CAM keeps the keep-out over the horizon
    other = Burn(burn.epoch, tuple(x for x in burn.dv_rtn))  # the other sign: no better
    times, low_o, t0_o = lower_after(dv, (other,), burn.epoch)
    assert closest(low_o[times >= t0_o]) <= closest(low[times >= t0]) == d.closest_after


def closest(low):
    """The smallest local minimum of a distance series, or its last sample while still decreasing (inf: none)."""
    k = np.nonzero((low[1:-1] <= low[:-2]) & (low[1:-1] < low[2:]))[0] + 1
    return min([*low[k], *([low[-1]] if low[-1] < low[-2] else [])], default=math.inf)


@pytest.mark.parametrize("f1", [0.0, 0.05])
def test_a_stuck_picosatellite_gets_a_cam(f1):
    d = decide(f1 * CMD + np.array([0.0, 0.0, 1e-4]))
    assert d.off and not d.departs and d.returns and d.t_inside is None and d.closest == -math.inf
    assert d.burn is not None and d.cleared and "never leaves the keep-out" in d.reason


def test_off_its_command_but_staying_out_gets_none():
    d = decide(0.45 * CMD)
    assert d.off and d.departs and not d.returns and d.burn is None and d.closest >= CONFIG.keep_out
    assert "stays outside" in d.reason


def test_a_mis_pointed_ejection_is_off_by_its_direction():
    d = decide(rotated_about_n(CMD, -7.0))
    assert d.off and d.pointing_z > CONFIG.off_sigmas and d.magnitude_z < 1e-9
    assert d.returns == (d.burn is not None)


def test_a_late_cam_does_not_clear():
    """The same weak ejection: the CAM's margin shrinks with its latency, and one too late does not clear."""
    after = [decide(0.2 * CMD, latency=lat).closest_after for lat in (300.0, 2400.0, 3600.0)]
    assert after[0] > after[1] > after[2] and after[1] >= CONFIG.keep_out > after[2]
    assert not decide(0.2 * CMD, latency=3600.0).cleared


def test_the_distance_sigma_is_the_spread_of_sampled_ejections():
    dv = 0.3 * CMD
    cov = COV * 100.0  # ten times the footage's sigmas: still linear
    times = np.array([1200.0, 3000.0, 5000.0])
    rho, sig = predicted_distance(dv, cov, CHIEF, times, da_dot=DA_DOT)
    draws = np.random.default_rng(4).multivariate_normal(dv, cov, size=2000)
    spread = np.std([predicted_distance(x, cov, CHIEF, times, da_dot=DA_DOT)[0] for x in draws], axis=0, ddof=1)
    assert sig == pytest.approx(spread, rel=0.08)  # 2,000 draws: 1.6 % of sigma, 5 of them
