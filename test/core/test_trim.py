"""The final drift trim of the IC acquisition (roe_sep.core.acquisition.trim): the decision threshold from the
tolerance and the OD sigma, no trim inside it, a trim that nulls the predicted a da at the IC epoch to within half
the quantization lattice (checked with the secular propagation and seed 002 Eq. 2 directly), the IC epoch moved
past a trim that falls after it, and the other initial conditions kept."""

import math

import numpy as np
import pytest

from roe_sep.core.acquisition.planner import AcquisitionConfig, AcquisitionInfeasible
from roe_sep.core.acquisition.trim import (
    drift_lattice,
    plan_trim,
    predicted_drift_sigma,
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
    x = propagate(np.asarray(roe0, dtype=float), t - T0, A, INC, True, DA_DOT)
    return float(x[0] * A) + sum(2.0 * b.dv_rel[1] / N for b in burns if b.epoch <= t)


def test_threshold_from_tolerance_and_sigma():
    lattice = drift_lattice(A, 0.001)
    assert lattice == pytest.approx(2 * 0.001 / N) and 1.7 < lattice < 1.9  # 0.9 m per quantum at 515 km
    assert trim_threshold(5.0, 0.5, lattice) == pytest.approx(3.5)  # 3 sigma inside the tolerance
    assert trim_threshold(5.0, 2.0, lattice) == pytest.approx(0.5 * lattice)  # a poor OD: trim whenever it helps
    assert trim_threshold(5.0, 0.0, lattice) == 5.0
    assert predicted_drift_sigma(0.8, 2.0 / 86400.0, 43200.0) == pytest.approx(math.hypot(0.8, 1.0))


def test_no_trim_inside_the_threshold_keeps_the_ic_epoch():
    d = plan_trim(state(1.5), CHIEF, DA_DOT, [], T_F, T0 + MARGIN, 0.5, 1.0 / 86400.0, 5.0, CFG)
    assert not d.trim and d.dv_t == 0.0 and d.epoch is None and d.t_final == T_F
    assert d.predicted_a_da == pytest.approx(1.5, abs=1e-6)
    assert d.threshold == pytest.approx(5.0 - 3.0 * d.sigma_a_da)
    assert d.final_roe[0] * A == pytest.approx(1.5, abs=1e-6)


@pytest.mark.parametrize("a_da_tf", [4.2, -4.7, 9.0, -12.0])
def test_trim_nulls_the_drift_at_the_moved_ic_epoch(a_da_tf):
    """The trim falls after t_F (the OD came 1700 s before it): t_F moves one grid step past the trim, and the
    a da there, propagated independently, is within half the lattice of zero."""
    roe0 = state(a_da_tf)
    d = plan_trim(roe0, CHIEF, DA_DOT, [], T_F, T0 + MARGIN, 1.0, 1.5 / 86400.0, 5.0, CFG)
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
    d = plan_trim(roe0, CHIEF, DA_DOT, [committed], t_f, T0 + MARGIN, 0.5, 1.0 / 86400.0, 5.0, CFG)
    assert d.predicted_a_da == pytest.approx(before, abs=1e-6)
    assert not d.trim  # |1.0 m| inside the threshold
    roe0 = state(4.5 + 7.3, t_f)
    d = plan_trim(roe0, CHIEF, DA_DOT, [committed], t_f, T0 + MARGIN, 0.5, 1.0 / 86400.0, 5.0, CFG)
    assert d.trim and d.t_final == t_f and d.epoch < t_f
    after = a_da_at(roe0, t_f, [committed, Burn(d.epoch, (0.0, -d.dv_t, 0.0))])
    assert abs(after) <= 0.5 * drift_lattice(A, CFG.dv_quantum) + 1e-9


def test_trim_refused_when_another_initial_condition_would_break():
    with pytest.raises(AcquisitionInfeasible, match=r"a dl_F\| = 3909.* outside \[5000, 10000\] m"):
        plan_trim(state(8.0, a_dl=4000.0), CHIEF, DA_DOT, [], T_F, T0 + MARGIN, 1.0, 1.0 / 86400.0, 5.0, CFG)
    with pytest.raises(AcquisitionInfeasible, match="not finite"):
        plan_trim(state(8.0), CHIEF, DA_DOT, [], T_F, T0 + MARGIN, math.nan, 1.0 / 86400.0, 5.0, CFG)
