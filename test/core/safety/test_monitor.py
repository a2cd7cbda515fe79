import numpy as np
import pytest

from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.trajectory import Burn, Chief
from roe_sep.core.safety.monitor import MonitorLimits, assess, in_fov
from roe_sep.core.separation.double_impulse import design, plan_drift_stop

D = design()
CHIEF = Chief(a=D.a, inc=D.inc, u0=D.u1, t0=0.0)
LIM = MonitorLimits()


def test_nominal_after_drift_stop_is_safe_and_receding():
    stop = plan_drift_stop(D.dv1_rtn, D.u1, 0.0, D.a, D.inc, k=3, p=0.06)
    chief = Chief(D.a, D.inc, stop.u2, stop.epoch)
    res = assess(stop.aimed_roe, stop.epoch, chief, LIM)
    assert res.safe and not res.approaching
    assert set(res.failed) <= {"fov"}  # near 10 km the camera range may end within the orbit; not a safety issue
    # Eq. (25) of the end state; J2 turns de by about a quarter degree per orbit, so nearly min(de, di)
    ei_min = min(np.hypot(*stop.aimed_roe[2:4]), np.hypot(*stop.aimed_roe[4:6])) * D.a
    assert res.min_rn_distance == pytest.approx(ei_min, rel=1e-2)
    assert 8000 < res.along_track_separation < 10000
    assert res.min_distance > 8000


def test_right_after_ejection_passive_safety_comes_from_the_crossing_distance():
    roe = delta_roe(D.dv1_rtn, D.u1, D.a, D.n)
    res = assess(roe, 0.0, CHIEF, LIM, t_end=3 * np.pi / D.n)
    assert res.min_rn_distance < 150.0  # e and i nearly perpendicular after a single impulse
    assert res.nearest_crossing == pytest.approx(3 * np.pi * 295.0, rel=5e-3)  # Keplerian value, J2 shifts it
    assert "passive_safety" not in res.failed and res.safe


def test_drift_stop_plan_check_and_a_bad_plan():
    roe = delta_roe(D.dv1_rtn, D.u1, D.a, D.n)
    stop = plan_drift_stop(D.dv1_rtn, D.u1, 0.0, D.a, D.inc, k=3, p=0.06)
    good = assess(roe, 0.0, CHIEF, LIM, [Burn(stop.epoch, tuple(stop.dv_relative_rtn))], t_end=stop.epoch + 86400)
    assert good.safe and not good.approaching
    # a drift-stop with the wrong tangential sign doubles the drift towards evaporation
    bad_dv = stop.dv_relative_rtn * np.array([1, -1, 1])
    bad = assess(roe, 0.0, CHIEF, LIM, [Burn(stop.epoch, tuple(bad_dv))], t_end=stop.epoch + 86400)
    assert not bad.safe and "evaporation" in bad.failed


def test_collision_course_is_flagged():
    # pure along-track offset of 800 m and no e/i separation: inside the keep-out sphere
    res = assess(np.array([0, 800.0, 0, 0, 0, 0]) / D.a, 0.0, CHIEF, LIM)
    assert not res.safe and "keep_out" in res.failed and "passive_safety" in res.failed
    assert res.level == 2


def test_fov():
    assert in_fov(np.array([0, 7000.0, 0, -500.0, 0, 400.0]), LIM)
    assert not in_fov(np.array([0, 5000.0, 0, -700.0, 0, 400.0]), LIM)
    assert not in_fov(np.array([0, 12000.0, 0, -100.0, 0, 100.0]), LIM)
