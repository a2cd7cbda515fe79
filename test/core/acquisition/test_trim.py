"""The final drift trim of the IC acquisition (roe_sep.core.acquisition.trim): the decision threshold from the
tolerance and the OD sigma, no trim inside it, a trim that nulls the predicted a da at the IC epoch to within half
the quantization lattice (checked with the secular propagation and seed 002 Eq. 2 directly), the IC epoch moved
past a trim that falls after it, and the other initial conditions kept."""

import dataclasses
import math

import numpy as np
import pytest

from roe_sep.core.acquisition.planner import AcquisitionConfig, AcquisitionInfeasible
from roe_sep.core.acquisition.trim import (
    CLUSTER_GAP,
    a_da_change,
    burns_drift_sigma,
    drift_lattice,
    ei_margin,
    final_od_arc,
    plan_trim,
    predicted_drift_sigma,
    radar_passes,
    trim_threshold,
)
from roe_sep.core.relmotion.dynamics import arg_latitude_rate, drag_da_dot, propagate
from roe_sep.core.relmotion.trajectory import Burn, Chief
from roe_sep.core.separation.double_impulse import design

D = design()
A, INC, N = D.a, D.inc, D.n
DA_DOT = float(drag_da_dot(0.0151, 1e-12, A))  # 1/s: a da_dot about -68 m/day
T0 = 246660.0  # s, the final OD's decision time
CHIEF = Chief(a=A, inc=INC, u0=0.3, t0=T0)
T_F = T0 + 1700.0  # s, the IC epoch in force: the final OD came just before it
MARGIN = 11400.0
CFG = AcquisitionConfig()
STEP = 2.0 * math.pi / CFG.grid_per_orbit / float(arg_latitude_rate(A, INC, True))


def state(a_da_at_tf, t_f=T_F, a_dl=7400.0):
    """An acquired state at T0 whose a da reaches ``a_da_at_tf`` [m] at ``t_f`` under the drag drift."""
    a_da0 = a_da_at_tf - DA_DOT * A * (t_f - T0)
    return np.array([a_da0, a_dl, 10.0, -260.0, 10.0, 360.0]) / A


def a_da_at(roe0, t, burns):
    """a da [m] at ``t`` with the secular propagation and Eq. 2 (a Delta da = 2 dvT / n) applied by hand."""
    x = propagate(np.asarray(roe0, dtype=float), t - T0, A, INC, True, da_dot=DA_DOT)
    return float(x[0] * A) + sum(2.0 * b.dv_rel[1] / N for b in burns if b.epoch <= t)


def decide(roe0, burns=(), **kw):
    """:func:`plan_trim` at T0 for the IC epoch T_F, a trim no earlier than T0 + MARGIN, a 5 m tolerance and the
    default config unless ``kw`` says otherwise (``sigma_a_da`` and ``sigma_rate`` always)."""
    kw = {"t_final": T_F, "t_earliest": T0 + MARGIN, "tolerance": 5.0, "cfg": CFG} | kw
    return plan_trim(roe0, CHIEF, DA_DOT, list(burns), kw.pop("t_final"), **kw)


def test_threshold_from_tolerance_and_sigma():
    lattice = drift_lattice(A, 0.001)
    assert lattice == pytest.approx(2 * 0.001 / N) and 1.7 < lattice < 1.9  # 0.9 m per quantum at 515 km
    assert trim_threshold(5.0, 0.5, lattice) == pytest.approx(3.5)  # 3 sigma inside the tolerance
    assert trim_threshold(5.0, 2.0, lattice) == pytest.approx(0.5 * lattice)  # a poor OD: trim whenever it helps
    assert trim_threshold(5.0, 0.0, lattice) == 5.0
    assert predicted_drift_sigma(0.8, 2.0 / 86400.0, 43200.0) == pytest.approx(math.hypot(0.8, 1.0))


def test_no_trim_inside_the_threshold_keeps_the_ic_epoch():
    d = decide(state(1.5), sigma_a_da=0.5, sigma_rate=1.0 / 86400.0)
    assert not d.trim and d.dv_t == 0.0 and d.epoch is None and d.t_final == T_F
    assert d.predicted_a_da == pytest.approx(1.5, abs=1e-6)
    assert d.threshold == pytest.approx(5.0 - 3.0 * d.sigma_a_da)
    assert d.final_roe[0] * A == pytest.approx(1.5, abs=1e-6)
    # the drift-rate error grows from the OD's epoch, not from the decision time
    rate = 1.0 / 86400.0
    late = decide(state(1.5), sigma_a_da=0.5, sigma_rate=rate, t_od=T0 - 43200.0)
    assert late.sigma_a_da == pytest.approx(predicted_drift_sigma(0.5, rate, T_F - T0 + 43200.0))
    assert late.sigma_a_da > d.sigma_a_da


@pytest.mark.parametrize("a_da_tf", [4.2, -4.7, 9.0, -12.0])
def test_trim_nulls_the_drift_at_the_moved_ic_epoch(a_da_tf):
    """The trim falls after t_F (the OD came 1700 s before it): t_F moves one grid step past the trim, and the
    a da there, propagated independently, is within half the lattice of zero."""
    roe0 = state(a_da_tf)
    d = decide(roe0, sigma_a_da=1.0, sigma_rate=1.5 / 86400.0)
    assert d.trim and d.predicted_a_da == pytest.approx(a_da_tf, abs=1e-6)
    assert T0 + MARGIN <= d.epoch < T0 + MARGIN + STEP + 1e-6
    assert d.t_final == pytest.approx(d.epoch + STEP)
    assert d.dv_t == pytest.approx(round(d.dv_t / CFG.dv_quantum) * CFG.dv_quantum, abs=1e-12)
    trim = Burn(d.epoch, (0.0, -d.dv_t, 0.0))  # carrier +dvT: relative -dvT
    after = a_da_at(roe0, d.t_final, [trim])
    assert abs(after) <= 0.5 * drift_lattice(A, CFG.dv_quantum) + 1e-9
    assert d.final_roe[0] * A == pytest.approx(after, abs=1e-6)
    assert np.sign(d.dv_t) == np.sign(a_da_at(roe0, d.t_final, []))  # a carrier pro-grade burn lowers a da


def test_trim_before_the_ic_epoch_keeps_it_and_counts_the_burns_still_to_fly():
    """An OD early enough: the trim flies before t_F, which stays; a committed burn of the plan in force is part of
    the prediction (here it alone would leave 8 m, the trim takes that out)."""
    t_f = T0 + 2 * MARGIN
    committed = Burn(T0 + 3000.0, (0.0, -0.004, 0.0))  # relative -4 mm/s: a da -7.3 m
    roe0 = state(1.0 + 7.3, t_f)
    before = a_da_at(roe0, t_f, [committed])
    d = decide(roe0, [committed], t_final=t_f, sigma_a_da=0.5, sigma_rate=1.0 / 86400.0)
    assert d.predicted_a_da == pytest.approx(before, abs=1e-6)
    assert not d.trim  # |1.0 m| inside the threshold
    roe0 = state(4.5 + 7.3, t_f)
    d = decide(roe0, [committed], t_final=t_f, sigma_a_da=0.5, sigma_rate=1.0 / 86400.0)
    assert d.trim and d.t_final == t_f and d.epoch < t_f
    after = a_da_at(roe0, t_f, [committed, Burn(d.epoch, (0.0, -d.dv_t, 0.0))])
    assert abs(after) <= 0.5 * drift_lattice(A, CFG.dv_quantum) + 1e-9


def test_trim_refused_when_it_alone_would_break_another_initial_condition():
    """A -12 m trim lowers the minimum R-N distance at t_F from 259.3 to 249.6 m: with min_ei between the two, the
    trim alone would break it and is refused; bad inputs are refused too."""
    from roe_sep.core.relmotion.trajectory import trajectory
    from roe_sep.core.safety.metrics import min_rn_distance

    roe0 = state(-12.0)
    d = decide(roe0, sigma_a_da=1.0, sigma_rate=1.0 / 86400.0)
    free = trajectory(roe0, T0, [], [d.t_final], CHIEF, j2=CFG.j2, da_dot=DA_DOT)[0]
    kept, trimmed = float(min_rn_distance(free)) * A, float(min_rn_distance(d.final_roe)) * A
    assert d.trim and not d.problems and trimmed < kept - 5.0
    cfg = dataclasses.replace(CFG, min_ei=0.5 * (kept + trimmed))
    with pytest.raises(AcquisitionInfeasible, match="would break the initial conditions: minimum R-N distance"):
        decide(roe0, sigma_a_da=1.0, sigma_rate=1.0 / 86400.0, cfg=cfg)
    with pytest.raises(AcquisitionInfeasible, match="not finite"):
        decide(state(8.0), sigma_a_da=math.nan, sigma_rate=1.0 / 86400.0)


def test_trim_still_nulls_the_drift_when_an_initial_condition_is_missed_anyway():
    """dl already out of its band (4000 m < a_dl_min): the ICs are missed with or without the trim, which still
    flies and nulls the drift (holding the formation); the decision names what is missed."""
    roe0 = state(8.0, a_dl=4000.0)
    d = decide(roe0, sigma_a_da=1.0, sigma_rate=1.0 / 86400.0)
    assert d.trim and len(d.problems) == 1 and "a dl_F| = 3909" in d.problems[0]
    assert d.summary()["missed"] == d.problems[0]
    after = a_da_at(roe0, d.t_final, [Burn(d.epoch, (0.0, -d.dv_t, 0.0))])
    assert abs(after) <= 0.5 * drift_lattice(A, CFG.dv_quantum) + 1e-9


def test_no_trim_from_an_od_too_uncertain_to_place_a_da_inside_the_tolerance():
    """sigma > tolerance / 3: the trim could not put a da inside the tolerance with 3-sigma confidence."""
    d = decide(state(12.0), sigma_a_da=1.7, sigma_rate=0.0)
    assert d.sigma_a_da == pytest.approx(1.7) and not d.trim and d.t_final == T_F
    assert decide(state(12.0), sigma_a_da=1.6, sigma_rate=0.0).trim


def test_final_od_arc_from_the_passes_before_the_ic_epoch():
    """The arc ends with the last pass before t_F (or with that pass's cluster, passes about an orbit apart, also
    after t_F) and starts at the latest pass that spans min_arc with that end and leaves three (four) passes in the
    arc (the default scenario's TIRA passes around its IC epoch)."""
    passes = [(160770, 161124), (166389, 166813), (199489, 199841), (205084, 205514), (246349, 246627),
              (251930, 252376), (293000, 293400)]
    assert final_od_arc(passes, 248334.0, 36000.0) == (199489.0, 246349.0, 246627.0)
    assert final_od_arc(passes, 248334.0, 36000.0, min_passes=2) == (205084.0, 246349.0, 246627.0)
    assert final_od_arc(passes, 248334.0, 46000.0) == (199489.0, 246349.0, 246627.0)
    assert final_od_arc(passes, 248334.0, 80000.0) == (166389.0, 246349.0, 246627.0)
    cluster = (199489.0, 251930.0, 252376.0)
    assert final_od_arc(passes, 248334.0, 36000.0, min_passes=4, cluster_gap=CLUSTER_GAP) == cluster
    assert final_od_arc(passes, 265000.0, 36000.0, min_passes=4, cluster_gap=CLUSTER_GAP) == cluster
    assert final_od_arc(passes, 253000.0, 36000.0) == (205084.0, 251930.0, 252376.0)
    assert final_od_arc(passes[:2], 200000.0, 36000.0) is None  # two passes only
    assert final_od_arc(passes, 248334.0, 200000.0) is None
    assert final_od_arc(passes, 100000.0, 36000.0) is None


def test_radar_passes_see_the_carrier_above_the_mask():
    """Predicted passes: the carrier is above the 10 deg mask inside each and below it just outside; passes come
    in clusters about half a day apart (a 515 km sun-synchronous orbit over 50.6 deg N)."""
    from roe_sep.core.frames import gcrs_to_itrs
    from roe_sep.core.od.radar import DEFAULT_EPOCH_UTC, TIRA, chief_elevation, julian_date
    from roe_sep.core.relmotion.dynamics import propagate_chief

    jd0 = julian_date(DEFAULT_EPOCH_UTC)
    kep = np.array([A, 0.0, INC, 1.1, 0.0, 0.3])
    passes = radar_passes(kep, 0.0, 0.0, 2 * 86400.0, jd0)
    assert 4 <= len(passes) <= 12 and np.all(passes[:, 1] - passes[:, 0] >= 60.0)

    def elevation(t):
        return np.degrees(chief_elevation(propagate_chief(kep, t), gcrs_to_itrs(jd0, t), TIRA.ecef, TIRA.enu))

    for rise, set_ in passes:
        assert elevation(0.5 * (rise + set_)) > 10.0
        assert elevation(rise - 5.0) < 10.0 < elevation(rise + 5.0)
        assert elevation(set_ + 5.0) < 10.0 < elevation(set_ - 5.0)
    gaps = np.diff(passes[:, 0])
    assert np.any(gaps > 30000.0) and np.any(gaps < 7000.0)  # within a cluster one orbit, between clusters ~12 h


def test_burns_drift_sigma_is_each_burns_share_of_eq_2():
    """burn_sigma of each tangential burn's a da change 2 |dvT| / n, root-sum-square."""
    assert burns_drift_sigma([], A, 0.05) == 0.0
    one = burns_drift_sigma([0.01], A, 0.05)
    assert one == pytest.approx(0.05 * 2.0 * 0.01 / N)
    assert burns_drift_sigma([0.01, -0.01], A, 0.05) == pytest.approx(math.sqrt(2.0) * one)


def test_the_burns_still_to_fly_widen_the_decision_sigma():
    """An OD that knows a da to 0.2 m predicts 3.9 m: inside 5 - 3 x 0.2 = 4.4 m, no trim; with a 7.5 mm/s burn
    still to fly (its 5 % error: 0.68 m) the sigma is 0.71 m, the threshold 2.86 m, and the trim flies. The "too
    uncertain" rule stays the OD's own: a large burn to fly does not stop the trim."""
    roe0 = state(3.9)
    d = decide(roe0, sigma_a_da=0.2, sigma_rate=0.0)
    assert not d.trim and d.threshold == pytest.approx(4.4)
    s = burns_drift_sigma([0.0075], A, 0.05)
    d = decide(roe0, sigma_a_da=0.2, sigma_rate=0.0, sigma_burns=s)
    assert d.trim and d.sigma_a_da == pytest.approx(math.hypot(0.2, s))
    assert d.threshold == pytest.approx(5.0 - 3.0 * math.hypot(0.2, s))
    assert decide(roe0, sigma_a_da=0.2, sigma_rate=0.0, sigma_burns=10.0).trim


def test_ei_margin_is_the_larger_sigma_along_the_e_and_i_vectors():
    """z times the 1-sigma of |a de| along a de and of |a di| along a di; a sigma across a vector (its direction)
    does not change the magnitude and does not count."""
    roe = np.array([0.0, 7500.0, 0.0, -300.0, 0.0, 400.0])
    cov = np.diag([1.0, 100.0, 400.0, 25.0, 9.0, 16.0])  # de: along (dey) 5 m, across (dex) 20 m; di: along 4 m
    assert ei_margin(roe, cov, 2.0) == pytest.approx(10.0)
    cov[5, 5] = 144.0  # di along: 12 m
    assert ei_margin(roe, cov, 2.0) == pytest.approx(24.0)
    assert ei_margin(roe, cov, 0.0) == 0.0
    assert ei_margin(np.zeros(6), cov, 2.0) == 0.0  # no vector, no direction


def test_a_da_change_is_eq_2():
    """2 dvT / n, signed and broadcasting; the lattice is one quantum of it."""
    assert float(a_da_change(0.01, A)) == pytest.approx(2.0 * 0.01 / N)
    assert np.allclose(a_da_change([0.01, -0.02], A), [2.0 * 0.01 / N, -2.0 * 0.02 / N])
    assert drift_lattice(A, CFG.dv_quantum) == pytest.approx(float(a_da_change(CFG.dv_quantum, A)))
