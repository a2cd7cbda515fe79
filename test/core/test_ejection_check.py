"""The carrier camera's check of the ejection before the blind drift-stop (core.safety.ejection_check): the bearing
measurement model, the scale invariance of a pure impulse, the drag signature of a weak ejection and the test's
verdicts on the default design."""

import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.relmotion.roe import roe_to_rtn
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory
from roe_sep.core.safety.ejection_check import (
    bearing_cost,
    camera_bearing,
    check_ejection,
    normal_axes,
    predicted_los,
)
from roe_sep.core.separation.double_impulse import design

SC = load_scenario(None)
D = design(SC.separation)
CHIEF = Chief(D.a, D.inc, D.u1, 0.0)
DA_DOT = float(drag_da_dot(SC.monte_carlo.delta_b, SC.monte_carlo.density, D.a))
TIMES = np.arange(60.0, 8554.0 - 1800.0, 60.0)  # release to 30 min before the default drift-stop
SIGMA = math.radians(0.02)
MODEL = math.hypot(SIGMA, math.radians(0.05))


def positions(f1, da_dot=DA_DOT):
    roe = trajectory(np.zeros(6), 0.0, [Burn(0.0, tuple(f1 * np.asarray(D.dv1_rtn)))], TIMES, CHIEF, True, da_dot)
    return roe_to_rtn(roe * D.a, CHIEF.u_at(TIMES))[0]


def test_bearing_noise_has_its_sigma_per_axis_and_unit_length():
    pos = np.tile([100.0, -2000.0, 300.0], (20000, 1))
    los = camera_bearing(pos, SIGMA, np.random.default_rng(1))
    assert np.allclose(np.linalg.norm(los, axis=1), 1.0)
    u = pos[0] / np.linalg.norm(pos[0])
    e1, e2 = normal_axes(u[None, :])
    for e in (e1[0], e2[0]):
        assert np.std(los @ e) == pytest.approx(SIGMA, rel=0.03)
        assert abs(float(np.mean(los @ e))) < 5 * SIGMA / math.sqrt(len(pos))


def test_a_scaled_impulse_flies_the_same_lines_of_sight_without_drag():
    a = predicted_los(1.0, D.dv1_rtn, 0.0, CHIEF, 0.0, TIMES)
    b = predicted_los(0.3, D.dv1_rtn, 0.0, CHIEF, 0.0, TIMES)
    assert np.allclose(a, b, atol=1e-12)  # angles-only cannot observe the scale of a pure impulse


def test_with_drag_a_weak_ejection_turns_the_line_of_sight():
    nominal = predicted_los(1.0, D.dv1_rtn, 0.0, CHIEF, DA_DOT, TIMES)
    turn = {f1: float(np.degrees(np.max(np.arccos(np.clip(np.sum(
        nominal * predicted_los(f1, D.dv1_rtn, 0.0, CHIEF, DA_DOT, TIMES), axis=1), -1.0, 1.0)))))
        for f1 in (0.8, 0.5, 0.3, 0.1)}
    assert turn[0.8] < 0.05 < turn[0.5] < turn[0.3] < turn[0.1]  # docstring: 0.03, 0.13, 0.30, 1.1 deg
    assert turn[0.1] == pytest.approx(1.1, abs=0.1)


@pytest.mark.parametrize("f1, weak", [(1.0, False), (0.9, False), (0.3, True), (0.1, True), (0.0, True)])
def test_the_verdict_on_the_default_design(f1, weak):
    """The truth's drag 10 % off the planner's nominal one: the nominal SPL flies, f1 <= 0.3 is held."""
    los = camera_bearing(positions(f1, 1.1 * DA_DOT), SIGMA, np.random.default_rng(7))
    check = check_ejection(TIMES, los, D.dv1_rtn, 0.0, CHIEF, DA_DOT, MODEL, 0.1, 0.5, 1e-3)
    assert check.weak is weak and check.samples == len(TIMES)
    if weak:
        assert check.f1 == pytest.approx(f1, abs=0.1)


def test_no_bearing_no_verdict_and_the_cost_leaves_out_nan_rows():
    check = check_ejection([], np.zeros((0, 3)), D.dv1_rtn, 0.0, CHIEF, DA_DOT, MODEL, 0.1, 0.5, 1e-3)
    assert check.samples == 0 and not check.weak
    m = np.array([[1.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    assert bearing_cost(m, np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]), 1.0) == pytest.approx(2.0)
