"""The OD covariance against the nonlinear truth: a deterministic OD ensemble (roe_sep.core.od.ensemble, no DDS).

128 truth trajectories (J2-J4 and drag, the differential ballistic coefficient dispersed) x 2 radar noise sequences
= 256 chains of solutions as radar_od makes them, each after every counted pass, the drift prior carried across the
burns, compared with the truth's secular state. Many trajectories and few noise draws: the truth's dispersions
are half of the error, and chains that share a trajectory are not independent. Stated bounds: the mean drift-rate
z^2 of the first and of the last solution inside chi2(256, 0.025..0.975) / 256 = [0.83, 1.18], the mean 7-state
NEES inside chi2(7 * 256, 0.025..0.975) / 256 = [6.55, 7.47], and at least 90 % of the runs inside the single-run
95 % bounds (|z| <= 1.96, NEES <= chi2(7, 0.95)). An optimistic covariance (a prior
counted twice, a missing model term) pushes the means above the bands; the last solution's drift-rate sigma must be
less than half the first's (the prior's information)."""

import pytest

from roe_sep.core.montecarlo.stats import nees_bounds
from roe_sep.core.od.ensemble import consistency, run_ensemble

pytestmark = pytest.mark.slow

MEMBERS, DRAWS = 128, 2


@pytest.fixture(scope="module")
def solutions():
    return run_ensemble(MEMBERS, DRAWS, seed=0)


def test_bands_are_the_stated_ones():
    lo, hi = nees_bounds(1, MEMBERS * DRAWS)
    assert (round(lo, 2), round(hi, 2)) == (0.83, 1.18)
    lo, hi = nees_bounds(7, MEMBERS * DRAWS)
    assert (round(lo, 2), round(hi, 2)) == (6.55, 7.47)


@pytest.mark.parametrize("which", ["first", "last"])
def test_drift_rate_and_state_covariance_consistent(solutions, which):
    c = consistency(solutions, which)
    assert c["n"] == MEMBERS * DRAWS
    assert c["z2_band"][0] <= c["z2"] <= c["z2_band"][1], c
    assert c["nees7_band"][0] <= c["nees7"] <= c["nees7_band"][1], c
    assert c["inside95_z"] >= 0.90, c
    assert c["inside95_nees7"] >= 0.90, c
    assert c["with_prior"] == (0 if which == "first" else c["n"])


def test_prior_halves_the_drift_rate_sigma(solutions):
    first, last = consistency(solutions, "first"), consistency(solutions, "last")
    assert last["sigma_m_per_day"] < 0.5 * first["sigma_m_per_day"]
