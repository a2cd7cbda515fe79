"""Nonlinear two-spacecraft truth: force model, integrator, burns, relative state."""

import numpy as np
import pytest

from roe_sep.core.constants import R_EARTH
from roe_sep.core.relmotion.dynamics import drag_da_dot, sun_synchronous_inclination
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion
from roe_sep.core.relmotion.roe import roe_to_kepler, roe_to_rtn
from roe_sep.core.truth import nonlinear as nl
from roe_sep.core.truth.mean_osc import mean_to_cartesian

A = R_EARTH + 515e3
INC = float(sun_synchronous_inclination(A))
ATM = nl.Atmosphere.scaled(1e-12, 515e3)
CHIEF = np.array([A, 0.0, INC, 0.0, 0.0, np.radians(88.0)])


@pytest.mark.parametrize("zonals", [2, 3, 4])
def test_symbolic_gradient_matches_closed_form(zonals):
    import heyoka as hy

    sys_ = nl.pair_equations(zonals)
    cf = hy.cfunc([rhs for _, rhs in sys_], vars=[v for v, _ in sys_])
    y = np.array([5e6, 3e6, 3.5e6, 1000, -6000, 4000.0, 5.1e6, 2.9e6, 3.4e6, 900, -6100, 4100])
    pars = np.array([0.01, 0.02, *ATM.pars()])
    assert np.allclose(cf(y, pars=pars), nl.pair_rhs(0.0, y, pars, zonals), rtol=1e-13, atol=1e-15)


def test_density_model():
    assert nl.vallado_density(515e3) == pytest.approx(6.967e-13 * np.exp(-15 / 63.822), rel=1e-12)
    assert ATM.scale_height == 63822.0 and ATM.density(515e3) == 1e-12
    assert ATM.density(515e3) / nl.vallado_density(515e3) == pytest.approx(1.816, abs=0.01)
    with pytest.raises(ValueError):
        nl.vallado_band(100e3)


def test_ejection_matches_gauss_equations():
    """Mean ROE right after an RTN impulse = seed 002 Eq. (2) up to O(J2 dv) and second-order terms (< 2 m here)."""
    dv = np.array([-1.33, -0.16, 0.44])
    s = nl.apply_impulse(nl.pair_state(CHIEF, CHIEF), dv, True)
    roe = nl.mean_roe(s) * A
    model = delta_roe(dv, CHIEF[5], A, mean_motion(A)) * A
    assert np.allclose(roe, model, atol=2.0)


def test_batch_equals_scalar_and_tolerances():
    dv = np.array([[-1.33, -0.16, 0.44], [-1.2, 0.1, 0.3], [0.5, 0.2, -0.1]])
    s0 = nl.apply_impulse(np.broadcast_to(nl.pair_state(CHIEF, CHIEF), (3, 12)), dv, np.ones(3, bool))
    b_d = np.array([0.023, 0.02, 0.0])
    batch = nl.propagate_pairs(s0, 0.0, 20000.0, 0.0079, b_d, atmosphere=ATM, zonals=2, tol=1e-12)
    for k in range(3):
        one = nl.propagate_pair(s0[k], 0.0, [20000.0], (), 0.0079, b_deputy=b_d[k], atmosphere=ATM, zonals=2)[0]
        rel_b = batch[k, 6:9] - batch[k, :3]
        rel_s = one[6:9] - one[:3]
        assert np.linalg.norm(rel_b - rel_s) < 1e-3  # 1 mm: tolerance 1e-12 vs 1e-15, batch vs scalar


def test_heyoka_agrees_with_solve_ivp():
    from scipy.integrate import solve_ivp

    s0 = nl.apply_impulse(nl.pair_state(CHIEF, CHIEF), [-1.33, -0.16, 0.44], True)
    pars = np.array([0.0079, 0.023, *ATM.pars()])
    t = 3 * 5700.0
    hy_ = nl.propagate_pair(s0, 0.0, [t], (), 0.0079, b_deputy=0.023, atmosphere=ATM, zonals=2)[0]
    sp = solve_ivp(nl.pair_rhs, (0, t), s0, method="DOP853", rtol=1e-12, atol=1e-6, args=(pars, 2)).y[:, -1]
    assert np.linalg.norm((hy_[6:9] - hy_[:3]) - (sp[6:9] - sp[:3])) < 0.01  # m


def test_relative_rtn_close_to_linear_map():
    roe = np.array([0.0, 5000.0, -20.0, -590.0, 14.0, 400.0]) / A
    s = nl.pair_state(CHIEF, roe_to_kepler(CHIEF, roe))
    pos, _ = nl.relative_rtn(s)
    lin = roe_to_rtn(roe, CHIEF[5])[0] * A
    # differences: along-track curvature y^2/(2a) and the differential J2 short-period terms (meters)
    assert np.linalg.norm(pos - lin) < 20.0


def test_differential_drag_rate_is_derived_factor_of_model():
    """Truth a*da rate = model rate times the orbit average of rho(h)/rho_ref * |v_r| v_r.T / v^2 (spherical
    altitude ~4 km above a - R_E lowers rho; the co-rotating atmosphere raises |v_r| for a retrograde orbit)."""
    from roe_sep.core.od.radar import rtn_matrix
    from roe_sep.core.relmotion.orbit import circular_speed

    t = np.arange(0.0, 43200.0 + 1, 20.0)
    s = nl.propagate_pair(nl.pair_state(CHIEF, CHIEF), 0.0, t, (), 0.0079, b_deputy=0.0230, atmosphere=ATM, zonals=2)
    da = nl.mean_roe(s)[:, 0] * A
    rate = np.polyfit(t, da, 1)[0]
    r, v = s[:, :3], s[:, 3:6]
    vr = v + nl.EARTH_ROTATION * np.stack([r[:, 1], -r[:, 0], 0 * r[:, 0]], 1)
    tan = rtn_matrix(r, v)[:, :, 1]
    factor = np.mean(ATM.density(np.linalg.norm(r, axis=1) - R_EARTH) / ATM.rho_ref
                     * np.linalg.norm(vr, axis=1) * np.sum(vr * tan, 1)) / circular_speed(A) ** 2
    model = drag_da_dot(0.0230 - 0.0079, 1e-12, A) * A
    assert 0.9 < factor < 1.0
    assert rate == pytest.approx(model * factor, rel=0.02)


def test_nonlinear_truth_drop_in_for_truth_model():
    """The simulator's usage: ticks of 40 s, distances then truth samples, the ejection and a carrier burn; the
    result matches the secular TruthModel within the model-error bounds of test_validation (one orbit here)."""
    from roe_sep.core.truth.secular import TruthModel

    chief0 = np.array([A, 0.0, INC, 0.5, 0.0, np.radians(50.0)])
    da_dot = float(drag_da_dot(0.0230 - 0.0079, 1e-12, A))
    nlt = nl.NonlinearTruth(chief0, 0.0, 0.0079, 0.0230, ATM, da_dot=da_dot)
    sec = TruthModel(chief0, 0.0, da_dot, True)
    assert np.all(nlt.roe_at(100.0) == 0.0) and not nlt.separated
    t = 0.0
    for k in range(200):
        t_to = t + 40.0
        if nlt.separated:  # SimulatedTruth.advance: distances over the step, then the truth samples inside it
            times, dist = nlt.distances(t, t_to, 10.0)
            assert times.size == 5 and np.all(np.isfinite(dist))
        nlt.roe_at(t + 20.0)
        if k == 15:  # BurnExecution.execute: advance to the epoch, then the burn
            nlt.roe_at(t_to)
            for truth in (nlt, sec):
                truth.apply(t_to, np.array([-1.33, -0.16, 0.44]))
        if k == 150:
            nlt.apply(t_to, -np.array([1.33, -0.16, 0.0]), "carrier")
            sec.apply(t_to, -np.array([1.33, -0.16, 0.0]))
        t = t_to
    assert np.allclose(nlt.roe_at(t) * A, sec.roe_at(t) * A, atol=10.0)  # as the MC bound after the stop
    assert abs(nlt.u_at(t) - np.mod(sec.u_at(t), 2 * np.pi)) < 1e-3  # J4 and O(J2^2) secular rates of u
    assert np.linalg.norm(nlt.rtn_at(t)[0] - sec.rtn_at(t)[0]) < 30.0
    with pytest.raises(ValueError):
        nlt.roe_at(0.0)


def test_propagate_pairs_grid_is_the_single_pair_propagation():
    """Batch lanes on a grid = one pair at a time (same integrator, same dense output), and it checks its times."""
    r, v = mean_to_cartesian(np.array([R_EARTH + 500e3, 0.0, 1.7, 0.3, 0.0, 0.2]))
    s = np.concatenate([r, v, r, v])
    s0 = nl.apply_impulse(np.stack([s] * 5), np.array([[0.1 * k, 1.0, -0.2] for k in range(5)]), np.ones(5, bool))
    times = np.array([50.0, 3000.0, 20000.0])
    grid = nl.propagate_pairs_grid(s0, 0.0, times, 0.0, 0.01, atmosphere=ATM, zonals=2, tol=1e-12)
    assert grid.shape == (5, 3, 12)
    for k in (0, 4):
        one = nl.propagate_pair(s0[k], 0.0, times, [], 0.0, b_deputy=0.01, atmosphere=ATM, zonals=2, tol=1e-12)
        assert np.max(np.abs(grid[k, :, :3] - one[:, :3])) < 1e-3  # m, after 20,000 s
    with pytest.raises(ValueError, match="sorted"):
        nl.propagate_pairs_grid(s0, 0.0, times[::-1], 0.0, 0.01, atmosphere=ATM)


def test_normalised_atmosphere_gives_the_model_drag_rate():
    """The default truth atmosphere (issue 20): its orbit-mean drag is the stated density by construction, and the
    integrated truth's differential a*da rate is then the model's (seed 002 Eq. 24) within 1.5 %, where the
    atmosphere referenced at a - R_E (``scaled``) is 5 % below it (the test above)."""
    norm = nl.Atmosphere.normalised(1e-12, CHIEF)
    assert nl.effective_density(norm, CHIEF) == pytest.approx(1e-12, rel=1e-12)
    assert norm.scale_height == ATM.scale_height and norm.h_ref == ATM.h_ref
    assert norm.rho_ref / ATM.rho_ref == pytest.approx(1e-12 / nl.effective_density(ATM, CHIEF), rel=1e-12)
    assert 0.93 < nl.effective_density(ATM, CHIEF) / 1e-12 < 0.97
    t = np.arange(0.0, 43200.0 + 1, 20.0)
    s = nl.propagate_pair(nl.pair_state(CHIEF, CHIEF), 0.0, t, (), 0.0079, b_deputy=0.0230, atmosphere=norm, zonals=2)
    rate = np.polyfit(t, nl.mean_roe(s)[:, 0] * A, 1)[0]
    assert rate == pytest.approx(drag_da_dot(0.0230 - 0.0079, 1e-12, A) * A, rel=0.015)


def test_ecef_to_geodetic_inverts_geodetic_to_ecef():
    from roe_sep.core.od.radar import geodetic_to_ecef

    lat = np.radians([0.0, 35.0, -60.0, 82.5])
    lon = np.radians([10.0, -120.0, 170.0, 45.0])
    h = np.array([515e3, 400e3, 520e3, 530e3])
    r = np.stack([geodetic_to_ecef(*x) for x in zip(lat, lon, h)])
    lat2, lon2, h2 = nl.ecef_to_geodetic(r)
    np.testing.assert_allclose(lat2, lat, atol=1e-11)
    np.testing.assert_allclose(lon2, lon, atol=1e-12)
    np.testing.assert_allclose(h2, h, atol=1e-4)


def test_nrlmsis_atmosphere_fit_and_integrator_expression():
    """NRLMSIS 2.0 through pymsis (no download: the indices are parameters), its fit along the sun-synchronous
    orbit at LTAN 09:30 on the default epoch, and the heyoka expression the truth integrates."""
    import heyoka as hy

    from roe_sep.core.truth.validation import sso_raan

    chief = np.array([A, 0.0, INC, sso_raan(), 0.0, np.radians(88.0)])
    m = nl.MsisAtmosphere.fit(chief, 43200.0)
    assert m.fit_rms < 0.10 and m.kind == "msis"

    class Raw:
        def density_at(self, pos, t):
            return nl.nrlmsis_density(pos, t, m.epoch_utc, m.f107, m.f107a, ap=m.ap)

    raw = nl.effective_density(Raw(), chief, span=43200.0, samples=720)
    assert nl.effective_density(m, chief, span=43200.0, samples=720) == pytest.approx(raw, rel=0.01)
    assert 1e-13 < raw < 1e-12  # moderate solar activity at 515 km: a few 1e-13 kg/m^3, below the seeds' 1e-12
    high = nl.MsisAtmosphere.fit(chief, 5700.0, f107=250.0, f107a=250.0)
    assert nl.effective_density(high, chief) > 2.0 * nl.effective_density(m, chief)
    x, y, z = hy.make_vars("x", "y", "z")
    cf = hy.cfunc([nl.density_expression("msis", x, y, z)], vars=[x, y, z])
    t = np.linspace(0.0, 43200.0, 4)
    pos = mean_to_cartesian(nl.propagate_chief(chief, t))[0]
    expr = [cf(p, pars=np.array([0.0, 0.0, *m.pars()]), time=tt)[0] for p, tt in zip(pos, t)]
    np.testing.assert_allclose(expr, m.density_at(pos, t), rtol=1e-9)  # sums of 46 terms: rounding
    with pytest.raises(ValueError, match="atmosphere"):
        nl.truth_atmosphere("jacchia", 1e-12, chief)
    with pytest.raises(ValueError, match="f107"):
        nl.MsisAtmosphere.fit(chief, 5700.0, f107=float("nan"))
