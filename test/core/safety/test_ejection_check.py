"""The carrier camera's check of the ejection before the blind drift-stop (core.safety.ejection_check) and the
simulator's camera (core.truth.simulated.Camera): the bearing measurement model, the scale invariance of a pure
impulse, the drag signature of a weak ejection, what the bearings observe (f1 over the drag's g) and the test's
verdicts on the default design."""

import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.safety.ejection_check import (
    bearing_cost,
    camera_bearing,
    check_ejection,
    nominal_fraction,
    normal_axes,
    predicted_los,
)
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.secular import chief_from_u
from roe_sep.core.truth.simulated import Camera, camera_rng

SC = load_scenario(None)
D = design(SC.separation)
CHIEF = chief_from_u(D.a, D.inc, 0.3, D.u1)  # mean elements at the release (t = 0)
DA_DOT = float(drag_da_dot(SC.monte_carlo.delta_b, SC.monte_carlo.density, D.a))
TIMES = np.arange(60.0, 8554.0 - 1800.0, 60.0)  # release to 30 min before the default drift-stop
SIGMA = math.radians(0.02)
BOUND = nominal_fraction(SC.separation.spl_sigma, SC.monte_carlo.ballistic_sigma, 3.0)


def angle_deg(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, axis=-1), -1.0, 1.0)))


def test_bearing_noise_has_its_sigma_per_axis_and_unit_length():
    pos = np.tile([100.0, -2000.0, 300.0], (20000, 1))
    los = camera_bearing(pos, SIGMA, np.random.default_rng(1))
    assert np.allclose(np.linalg.norm(los, axis=1), 1.0)
    u = pos[0] / np.linalg.norm(pos[0])
    e1, e2 = normal_axes(u[None, :])
    for e in (e1[0], e2[0]):
        assert np.std(los @ e) == pytest.approx(SIGMA, rel=0.03)
        assert abs(float(np.mean(los @ e))) < 5 * SIGMA / math.sqrt(len(pos))


def test_the_nominal_set_is_three_sigmas_of_spl_and_drag():
    assert BOUND == pytest.approx(0.7 / 1.6)
    assert nominal_fraction(0.1, 0.2, 0.0) == 1.0 and nominal_fraction(0.5, 0.2, 3.0) == 0.0


def test_a_scaled_impulse_flies_nearly_the_same_lines_of_sight_without_drag():
    """Linear: the same lines of sight; the Cartesian position of the curved relative orbit differs by the curvature
    only, y^2 / 2r radially (y / 2r = 0.02 deg at 6 km along-track), against 1.1 deg that the drag turns f1 = 0.1."""
    a, b = predicted_los([1.0, 0.3], D.dv1_rtn, 0.0, CHIEF, 0.0, times=TIMES)
    assert np.max(angle_deg(a, b)) < 0.025


def test_the_bearings_see_f1_over_the_drag():
    """f1 X + g Y: half the impulse with half the drag flies the nominal lines of sight (to the J2 terms)."""
    nominal = predicted_los([1.0], D.dv1_rtn, 0.0, CHIEF, DA_DOT, times=TIMES)[0]
    half = predicted_los([0.5], D.dv1_rtn, 0.0, CHIEF, 0.5 * DA_DOT, times=TIMES)[0]
    weak = predicted_los([0.5], D.dv1_rtn, 0.0, CHIEF, DA_DOT, times=TIMES)[0]
    assert np.max(angle_deg(nominal, half)) < 0.025 < 0.1 < np.max(angle_deg(nominal, weak))


def test_with_drag_a_weak_ejection_turns_the_line_of_sight():
    los = predicted_los([1.0, 0.8, 0.5, 0.3, 0.1], D.dv1_rtn, 0.0, CHIEF, DA_DOT, times=TIMES)
    turn = [float(np.max(angle_deg(los[0], x))) for x in los[1:]]
    assert turn[0] < 0.05 < turn[1] < turn[2] < turn[3]  # module docstring: 0.03, 0.13, 0.30, 1.1 deg
    assert turn[3] == pytest.approx(1.1, abs=0.15)


def truth_bearings(f1, g, seed):
    """Bearings of an ejection of f1 under g times the nominal drag (the model itself as truth, the camera's noise)."""
    pos_los = predicted_los([f1], D.dv1_rtn, 0.0, CHIEF, g * DA_DOT, times=TIMES)[0]
    return camera_bearing(pos_los * 1000.0, SIGMA, np.random.default_rng(seed))


@pytest.mark.parametrize("f1, g, weak", [(1.0, 1.0, False), (0.7, 1.6, False), (1.3, 0.4, False),
                                          (0.3, 1.0, True), (0.3, 0.8, True), (0.1, 0.6, True), (0.3, 0.6, False)])
def test_the_verdict_on_the_default_design(f1, g, weak):
    """The corners of the nominal set fly (f1 / g >= 0.4375); f1 = 0.3 is held unless the drag is low enough to make
    it look nominal (g = 0.6: f1 / g = 0.5)."""
    check = check_ejection(TIMES, truth_bearings(f1, g, 7), D.dv1_rtn, 0.0, CHIEF,
                           da_dot=DA_DOT, sigma=SIGMA, floor=1.0, bound=BOUND, alpha=1e-3)
    assert check.weak is weak and check.samples == len(TIMES) and check.bound == BOUND
    assert check.f1 == pytest.approx(min(f1 / g, 2.0), abs=0.05 + 0.1 * f1 / g)


def test_no_bearing_no_verdict_and_the_cost_leaves_out_nan_rows():
    check = check_ejection([], np.zeros((0, 3)), D.dv1_rtn, 0.0, CHIEF,
                           da_dot=DA_DOT, sigma=SIGMA, floor=1.0, bound=BOUND, alpha=1e-3)
    assert check.samples == 0 and not check.weak
    m = np.array([[1.0, 0.0, 0.0], [np.nan, 0.0, 0.0]])
    assert float(bearing_cost(m, np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]), 1.0)) == pytest.approx(2.0)
    per_sample = bearing_cost(m, np.array([[[0.0, 1.0, 0.0], [1.0, 0.0, 0.0]]] * 2), np.array([2.0, 1.0]))
    assert per_sample.shape == (2,) and per_sample == pytest.approx([0.5, 0.5])


class Line:
    """A truth whose relative position is (t, 1000, 0) m."""

    @staticmethod
    def rtn_at(t):
        t = np.asarray(t, dtype=float)
        return np.stack([t, np.full_like(t, 1000.0), np.zeros_like(t)], axis=-1), None


def test_the_simulators_camera_observes_from_the_release_every_period_for_its_duration():
    got = []
    cam = Camera(60.0, 0.0, 300.0, camera_rng(5), lambda e, los: got.extend(zip(e, los)))
    cam.observe(Line, 0.0, 1000.0)
    assert got == []  # nothing before the release
    cam.release(100.0)
    cam.release(200.0)  # a second release is ignored
    cam.observe(Line, 100.0, 250.0)
    cam.observe(Line, 250.0, 1000.0)
    assert [e for e, _ in got] == [160.0, 220.0, 280.0, 340.0, 400.0]
    t, los = got[2]
    assert np.allclose(los, np.array([t, 1000.0, 0.0]) / math.hypot(t, 1000.0))
    off = Camera(0.0, SIGMA, 300.0, camera_rng(5), lambda e, los: got.append(e))
    off.release(0.0)
    off.observe(Line, 0.0, 1000.0)
    assert len(got) == 5  # camera_period 0: no camera


def test_the_camera_noise_is_a_stream_of_its_own():
    a, b = camera_rng(5).normal(size=4), camera_rng(5).normal(size=4)
    assert np.array_equal(a, b) and not np.array_equal(a, np.random.default_rng(5).normal(size=4))
