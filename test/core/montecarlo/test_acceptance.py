"""AC1-AC3 Monte Carlo of the multi-impulse separation (seed 001 Sec. 4)."""

import math

import numpy as np
import pytest

from roe_sep.core.montecarlo import acceptance
from roe_sep.core.montecarlo.sweep import MonteCarloConfig
from roe_sep.core.separation import multi_impulse

D = multi_impulse.design()
RES = acceptance.run(D, MonteCarloConfig(samples=20000, seed=3))


def test_drift_free_threshold_hand_value():
    # 5 km / (1.5 n 86400 s) with n = 1.10317e-3 rad/s
    assert acceptance.drift_free_threshold(5000.0, 1.1031727e-3, 86400.0) == pytest.approx(34.972, abs=1e-3)


def test_ac_fractions():
    rep = RES.to_dict()
    # Eq. (21) sizes |p| = e1 + e2 at 3 sigma of each error on the *unreduced* burns (Eq. 18), so the drift turns
    # inward only when the combined error (1 - f1) + (f2 - 1) [sigma 0.112] exceeds |p| / |dvT1| = 0.45 (4 sigma,
    # P = 3e-5: 0.6 expected samples of 20,000)
    assert rep["n_ac1_fail"] <= 4
    combined = (1.0 - RES.draws.f1) + (RES.draws.f2 - 1.0)
    assert np.all(combined[~RES.ac1] > 0.40)
    assert np.all(RES.ac1[combined < 0.40])
    assert rep["ac2"] >= 0.999
    # AC3 (seed 001 Sec. 4): min R-N > 150 m in each of the 15 nearly drift-free samples of these 20,000
    assert (rep["n_drift_free"], rep["n_ac3_fail"], rep["ac3"]) == (15, 0, 1.0)
    assert np.min(RES.min_rn[RES.drift_free]) > D.config.min_rn_distance == 150.0
    assert rep["drift_free_a_da"] == pytest.approx(34.97, abs=0.01)


def test_ac1_mean_residual_is_minus_2p_over_n():
    """Mean a da after the reduction = -2 |p| / n (Eq. 2) plus the drag drift until the reduction."""
    a, n = D.a, D.n
    t_red = D.plan.burns[0].epoch
    drag = -0.0151 * 1e-12 * (3.986004418e14 / a) / (n * a) * t_red * a
    mean = np.mean(RES.roe_after_reduction[:, 0]) * a
    assert mean == pytest.approx(-2 * D.plan.p / n * a / a + drag, abs=1.0)


def test_same_draws_as_the_foundation():
    from roe_sep.core.montecarlo.sweep import draw

    d = draw(D, MonteCarloConfig(samples=20000, seed=3))
    np.testing.assert_array_equal(d.f1, RES.draws.f1)
    assert np.std(d.f1) == pytest.approx(0.1, rel=0.03)


def test_no_reduction_breaks_ac1():
    """Sanity: with the full drift-stop (p = 0) about half the samples drift inward."""
    frac = np.mean(RES.draws.f1 * abs(D.dv1_rtn[1]) < RES.draws.f2 * abs(D.dv1_rtn[1]))
    assert 0.4 < frac < 0.6
    assert math.isfinite(RES.to_dict()["crossing_min"])


def test_ac3_against_seed_001():
    """AC3 of seed 001 Sec. 4: "the minimum distance in the RN plane must be larger than 150 m for a final orbit with
    almost no drift remaining"; the seed reports it satisfied by its Monte Carlo of at least 100,000 runs (Fig. 6,
    "Satisfaction of the AC3 criterion", 1000 of the samples plotted): no nearly drift-free sample below 150 m.

    Ours, over 100,000 samples (seed 0, the README's run): 54 of the 55 nearly drift-free samples (|a da| < 35 m
    after the drift reduction) meet it, 98.18 %. Where and why it differs: the one failure is a 4.5-sigma SPL
    under-performance (f1 = 0.55) whose minimum R-N distance is 146.6 m, 3.4 m short, at a da = -29.3 m. The seed
    quantifies neither "almost no drift" (our bound: the residual drift 1.5 n |a da| over one day below the 5 km
    radar separability) nor how many of its samples were drift-free; and a one-in-100,000 sample would be among
    the 1000 it plots with a probability of 1 %. The seed's own dispersions (f1 Gaussian, sigma 0.1) reach
    f1 = 0.55 with a probability of 3.5e-6 per sample, so a run of 100,000 holds such a sample about once in three.
    """
    res = acceptance.run(D, MonteCarloConfig(samples=100_000, seed=0))
    rep = res.to_dict()
    limit = D.config.min_rn_distance
    assert limit == 150.0 and rep["drift_free_a_da"] == pytest.approx(34.97, abs=0.01)
    assert (rep["n_drift_free"], rep["n_ac3_fail"]) == (55, 1)
    assert rep["ac3"] == pytest.approx(54 / 55, abs=1e-12)
    failed = np.flatnonzero(~res.ac3)
    assert res.drift_free[failed].all()
    assert res.min_rn[failed][0] == pytest.approx(146.57, abs=0.01)
    assert res.roe_after_reduction[failed[0], 0] * D.a == pytest.approx(-29.28, abs=0.01)
    assert res.draws.f1[failed][0] == pytest.approx(0.5506, abs=1e-4)  # (f1 - 1) / 0.1 = -4.5 sigma
    passing = res.drift_free & res.ac3
    assert np.count_nonzero(passing) == 54 and np.min(res.min_rn[passing]) > limit + 10.0
