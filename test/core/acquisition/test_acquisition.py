"""Initial-condition acquisition (seed 001): the quantized minimum-delta-v carrier plan meets every IC, checked
independently on a dense :func:`trajectory`; the LP matrices equal single-burn trajectories; delta-v optimality
against a lower bound and a hand-derived two-tangential-burn plan; clear reasons for infeasible inputs."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from roe_sep.core.acquisition.lp_transfer import (
    carrier_burn_effects,
    grid_epochs,
    grid_response,
    parse_axes,
    response_at,
    sagitta,
    transition_matrices,
)
from roe_sep.core.acquisition.planner import (
    AcquisitionConfig,
    AcquisitionInfeasible,
    InvalidAcquisitionConfig,
    drift_nulling_dv_bound,
    ei_magnitude_floor,
    plan_acquisition,
    signed_rows,
    verify,
)
from roe_sep.core.relmotion.dynamics import arg_latitude_rate, drag_da_dot, propagate
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory
from roe_sep.core.safety.metrics import min_rn_distance
from roe_sep.core.separation.double_impulse import design

D = design()
A, INC = D.a, D.inc
N = D.n
DA_DOT = float(drag_da_dot(0.0151, 1e-12, A))  # 1/s, seed 002 differential drag: a da_dot = -0.79 mm/s (-68 m/day)
CHIEF = Chief(a=A, inc=INC, u0=1.0, t0=1000.0)
TYPICAL = np.array([-180.0, 25000.0, -30.0, -540.0, 10.0, 400.0]) / A  # post-drift-stop: leading, drifting away
CFG = AcquisitionConfig()


def roe_from(a_da, a_dl, de, phi, di, theta):
    return np.array([a_da, a_dl, de * math.cos(phi), de * math.sin(phi), di * math.cos(theta),
                     di * math.sin(theta)]) / A


def check_plan(plan, roe0, chief, da_dot, cfg, target_band=True):
    """Every requirement, recomputed here from a dense trajectory (independent of the planner's own checks)."""
    q = cfg.dv_quantum
    assert plan.n_burns >= 1
    mags = np.linalg.norm(plan.dv_carrier, axis=1)
    assert np.all(mags <= cfg.max_burn_dv + 1e-12)
    np.testing.assert_allclose(plan.dv_carrier / q, np.round(plan.dv_carrier / q), atol=1e-9)
    assert np.all(np.diff(plan.epochs) > 0)
    assert plan.epochs[0] >= chief.t0 + (cfg.planning_margin or 0.0) - 1e-6
    assert plan.epochs[-1] <= plan.t_final + 1e-9 <= chief.t0 + cfg.window + 1e-6
    for k in set("RTN") - set(cfg.axes):  # only the allowed axes
        assert np.all(plan.dv_carrier[:, "RTN".index(k)] == 0.0)
    burns = [Burn(float(t), tuple(-dv)) for t, dv in zip(plan.epochs, plan.dv_carrier)]  # carrier -> relative
    period = 2 * math.pi / arg_latitude_rate(chief.a, chief.inc, cfg.j2)
    times = np.append(np.arange(chief.t0, plan.t_final, period / 200.0), plan.t_final)
    traj = trajectory(roe0, chief.t0, burns, times, chief, j2=cfg.j2, da_dot=da_dot) * chief.a
    f = traj[-1]
    np.testing.assert_allclose(f, plan.final_roe * chief.a, atol=1e-6)
    s = math.copysign(1.0, roe0[1])
    # mean along-track separation never below the minimum, configuration kept
    assert np.min(s * traj[:, 1]) >= cfg.a_dl_min - 1e-6
    assert cfg.a_dl_min - 1e-6 <= s * f[1] <= cfg.a_dl_max + 1e-6
    if cfg.a_dl_target and target_band:
        assert abs(s * f[1] - cfg.a_dl_target) <= cfg.a_dl_target_tol + 1e-6
    assert abs(f[0]) <= cfg.drift_tolerance + 1e-6  # nearly no drift
    de, di = np.hypot(f[2], f[3]), np.hypot(f[4], f[5])
    assert de >= cfg.min_ei - 1e-6 and di >= cfg.min_ei - 1e-6
    cos_ei = (f[2] * f[4] + f[3] * f[5]) / (de * di)  # -1 anti-parallel (leading), +1 parallel (following)
    assert -s * cos_ei >= math.cos(math.radians(cfg.ei_angle_tol_deg)) - 1e-12
    assert min_rn_distance(f) >= cfg.min_ei - 1e-6  # seed 002 Eq. (25)
    assert de <= math.tan(math.radians(cfg.fov_half_r_deg)) * abs(f[1]) + 1e-6  # Eq. (11)
    assert di <= math.tan(math.radians(cfg.fov_half_n_deg)) * abs(f[1]) + 1e-6
    # minimality: never below the drift-nulling bound; the quantized plan stays within a few quanta of the LP
    bound = 0.5 * N * max(0.0, abs(roe0[0] * A + da_dot * A * (plan.t_final - chief.t0)) - cfg.drift_tolerance)
    assert plan.lp_dv >= bound - 1e-9
    assert plan.total_dv_l1 >= bound - 1e-9
    assert plan.total_dv_l1 <= plan.lp_dv + 6 * q
    assert verify(plan, cfg) == []
    return f


@pytest.fixture(scope="module")
def typical():
    return plan_acquisition(TYPICAL, CHIEF, DA_DOT, CFG)


def test_typical_post_drift_stop_state(typical):
    p = typical
    f = check_plan(p, TYPICAL, CHIEF, DA_DOT, CFG)
    assert 0.1 < p.total_dv < 0.3 and p.n_burns <= 6
    assert p.time_to_ic == pytest.approx(CFG.window, abs=400.0)  # the ICs at the end of the window
    assert p.fov_ok and p.min_rn >= 150.0 and f[1] > 0 and p.leading
    assert np.max(np.abs(p.residual[[0, 2, 3, 4, 5]])) < 20.0  # quantization moves da, de, di by meters only
    summary = p.summary()
    assert summary["n_burns"] == p.n_burns and summary["fov_ok"] is True


def test_prediction_is_the_shared_trajectory(typical):
    t = np.linspace(CHIEF.t0, typical.t_final, 7)
    direct = trajectory(TYPICAL, CHIEF.t0, typical.burns(), t, CHIEF, j2=True, da_dot=DA_DOT)
    np.testing.assert_allclose(direct[-1], typical.final_roe, atol=1e-15)
    assert typical.burns()[0].dv_rel == tuple(-typical.dv_carrier[0])


# post-drift-stop states of the brief: pico leading by 20-35 km, drifting away (a da -100..-250 m), e/i roughly
# anti-parallel, a de 450-600 m, a di ~ 400 m at the ejection's pole phase; differential drag 0..-1 mm/s
@pytest.mark.slow
@given(a_da=st.floats(-250, -100), a_dl=st.floats(20e3, 35e3), de=st.floats(450, 600), dphi=st.floats(-0.6, 0.6),
       di=st.floats(350, 450), theta=st.floats(math.radians(75), math.radians(105)), a_dad=st.floats(-1e-3, 0.0),
       u0=st.floats(0, 2 * math.pi))
@settings(max_examples=8, deadline=None)
def test_generated_states_meet_every_constraint(a_da, a_dl, de, dphi, di, theta, a_dad, u0):
    roe0 = roe_from(a_da, a_dl, de, theta + math.pi + dphi, di, theta)
    chief = Chief(a=A, inc=INC, u0=u0, t0=5e4)
    plan = plan_acquisition(roe0, chief, a_dad / A, CFG)
    check_plan(plan, roe0, chief, a_dad / A, CFG)


def test_following_picosatellite_gets_parallel_vectors():
    roe0 = roe_from(+150.0, -24000.0, 520.0, math.radians(95.0), 400.0, math.radians(88.0))
    plan = plan_acquisition(roe0, CHIEF, DA_DOT, CFG)
    f = check_plan(plan, roe0, CHIEF, DA_DOT, CFG)
    assert f[1] < 0 and not plan.leading


@pytest.mark.parametrize("changes", [
    {"axes": "T"}, {"axes": "RTN"}, {"max_burn_dv": 0.05}, {"dv_quantum": 0.002, "drift_tolerance": 1.9},
    {"a_dl_target": 0.0}, {"window": 86400.0, "planning_margin": 3000.0}, {"j2": False}, {"grid_per_orbit": 8},
])
def test_parameters_are_respected(changes):
    cfg = dataclasses.replace(CFG, **changes)
    plan = plan_acquisition(TYPICAL, CHIEF, DA_DOT, cfg)
    check_plan(plan, TYPICAL, CHIEF, DA_DOT, cfg)


def test_free_along_track_target_is_a_cheaper_relaxation(typical):
    free = plan_acquisition(TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, a_dl_target=0.0))
    assert free.lp_dv <= typical.lp_dv + 1e-9


def test_lower_bound_from_the_required_da_change():
    # seed 002 Eq. (2): a Delta da = 2 dvT / n, so any plan needs n/2 |required change| of tangential delta-v
    assert drift_nulling_dv_bound(-200.0, 0.0, 1e5, N, 1.0) == pytest.approx(0.5 * N * 199.0)
    assert drift_nulling_dv_bound(-100.0, -1e-3, 1e5, N, 1.0) == pytest.approx(0.5 * N * 199.0)
    assert drift_nulling_dv_bound(0.5, 0.0, 1e5, N, 1.0) == 0.0


def test_ei_floor_keeps_eq25_above_the_minimum():
    g = math.radians(1.0)
    m = ei_magnitude_floor(150.0, g)
    for ratio in (1.0, 1.2, 3.0):
        roe = np.array([0, 0, m, 0, -ratio * m * math.cos(g), -ratio * m * math.sin(g)])
        assert min_rn_distance(roe) >= 150.0 - 1e-9
    assert min_rn_distance(np.array([0, 0, m, 0, -m * math.cos(g), -m * math.sin(g)])) == pytest.approx(150.0)


# --- a hand-derived two-tangential-burn plan (Keplerian, no drag) built backwards from the targets -----------

def hand_two_burn_case(r1, r2, k1, m, mu):
    """Relative tangential impulses r1, r2 [m/s] at grid epochs k1 and k1 + (2m+1) half orbits reach
    a da = 0, a dl = 7500 m, de = -mu i^ exactly (Eq. 2: a Delta da = 2 R / n, a Delta de = 2 R (cos u, sin u) / n;
    Keplerian dl drift -3/2 n a da): returns the initial state, chief, config and the burns."""
    chief = Chief(a=A, inc=INC, u0=0.0, t0=0.0)
    period = 2 * math.pi / N
    step = period / 16
    t1 = period + k1 * step
    t2 = t1 + (2 * m + 1) * 8 * step
    u1 = N * t1
    x0 = -2.0 * (r1 + r2) / N
    x1 = x0 + 2.0 * r1 / N
    e_f = np.array([0.0, -mu])
    e0 = e_f - 2.0 * (r1 - r2) / N * np.array([math.cos(u1), math.sin(u1)])
    dl0 = 7500.0 + 1.5 * N * (x0 * t1 + x1 * (t2 - t1))
    roe0 = np.array([x0, dl0, e0[0], e0[1], 0.0, 400.0]) / A
    cfg = dataclasses.replace(CFG, j2=False, planning_margin=period, window=t2 + 2.2 * period)
    return roe0, chief, cfg, [Burn(t1, (0.0, r1, 0.0)), Burn(t2, (0.0, r2, 0.0))]


@given(r1=st.integers(120, 300), r2=st.integers(-150, 0), k1=st.integers(0, 15), m=st.integers(2, 8),
       mu=st.floats(250, 600))
@settings(max_examples=6, deadline=None)
def test_not_more_than_a_hand_derived_two_burn_plan(r1, r2, k1, m, mu):
    r1, r2 = r1 * 1e-3, r2 * 1e-3  # multiples of the 1 mm/s quantum
    roe0, chief, cfg, hand = hand_two_burn_case(r1, r2, k1, m, mu)
    a_roe0 = roe0 * A
    assume(a_roe0[1] > 6000.0 and np.hypot(a_roe0[2], a_roe0[3]) > 100.0)
    # the oracle itself: the hand plan reaches the targets
    f = trajectory(roe0, 0.0, hand, [cfg.window], chief, j2=False)[0] * A
    np.testing.assert_allclose(f, [0.0, 7500.0, 0.0, -mu, 0.0, 400.0], atol=1e-6)
    hand_dv = abs(r1) + abs(r2)
    plan = plan_acquisition(roe0, chief, 0.0, cfg)
    check_plan(plan, roe0, chief, 0.0, cfg)
    assert plan.lp_dv <= hand_dv + 1e-9  # the hand plan is feasible for the LP, so the optimum cannot be worse
    assert plan.total_dv <= hand_dv + 3 * cfg.dv_quantum
    assert plan.lp_dv >= drift_nulling_dv_bound(a_roe0[0], 0.0, plan.time_to_ic, N, cfg.drift_tolerance) - 1e-9


# --- the LP matrices are exactly the shared trajectory of single burns ------------------------------------

def test_lp_maps_equal_single_burn_trajectories():
    epochs = grid_epochs(CHIEF.t0 + 5000.0, CHIEF.t0 + 40000.0, CHIEF, 16)
    step = epochs[1] - epochs[0]
    np.testing.assert_allclose(np.diff(epochs), step)
    u = CHIEF.u_at(epochs)
    np.testing.assert_allclose((u / (2 * math.pi / 16) + 0.5) % 1.0, 0.5, atol=1e-9)  # round values of u
    axes = parse_axes("RTN")
    eff = carrier_burn_effects(epochs, axes, CHIEF)
    path = grid_response(eff, step, A, INC, True, component=1)
    final = response_at(eff, epochs, epochs[-1], A, INC, j2=True)
    for k, j in ((0, 1), (5, 0), (17, 2), (len(epochs) - 1, 1)):
        dv = np.zeros(3)
        dv[axes[j]] = 1.0
        traj = trajectory(np.zeros(6), CHIEF.t0, [Burn(float(epochs[k]), tuple(-dv))], epochs, CHIEF)
        np.testing.assert_allclose(path[:, k, j], traj[:, 1], atol=1e-15)
        np.testing.assert_allclose(final[k, j], traj[-1], atol=1e-15)
    phi = transition_matrices(3000.0, A, INC)
    x = np.array([1e-5, 2e-4, -3e-5, 4e-5, 1e-5, 6e-5])
    np.testing.assert_allclose(phi @ x, propagate(x, 3000.0, A, INC), atol=1e-17)
    # between two grid epochs drag bends dl by the sagitta of its quadratic: 3/16 n |da_dot| h^2 (Keplerian)
    assert sagitta(step, A, INC, False, DA_DOT) * A == pytest.approx(0.1875 * N * abs(DA_DOT * A) * step**2)


# --- infeasible inputs and bad configurations ------------------------------------------------------------

@pytest.mark.parametrize("roe0,chief,dad,cfg,reason", [
    (np.full(6, math.nan), CHIEF, 0.0, CFG, "not six finite numbers"),
    (TYPICAL, Chief(a=math.nan, inc=INC, u0=0.0, t0=0.0), 0.0, CFG, "a of the estimate is not finite"),
    (TYPICAL, CHIEF, math.inf, CFG, "da_dot of the estimate is not finite"),
    (roe_from(-100, 0.0, 500, 0, 400, 1.5), CHIEF, 0.0, CFG, "along-track separation is zero"),
    (roe_from(100, 5500.0, 500, -1.6, 400, 1.5), CHIEF, 0.0, CFG, "before the first burn opportunity"),
    (TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, window=6000.0, planning_margin=5900.0),
     "window too short"),
    (TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, window=12 * 3600.0, max_burn_dv=0.001), "window too short"),
    (TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, axes="N"), "without tangential burns"),
    (TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, window=30 * 86400.0), "shorten the window"),
    (TYPICAL, CHIEF, DA_DOT, dataclasses.replace(CFG, drift_tolerance=0.05), "drift_tolerance"),
    (roe_from(-180, 25000.0, 500, -1.6, 0.2, 1.5), CHIEF, 0.0, dataclasses.replace(CFG, j2=False), "too small"),
    (roe_from(-180, 25000.0, 500, -1.6, 100.0, 1.5), CHIEF, DA_DOT, dataclasses.replace(CFG, axes="T"),
     "e/i vectors cannot be made"),
])
def test_infeasible_inputs_raise_with_the_reason(roe0, chief, dad, cfg, reason):
    with pytest.raises(AcquisitionInfeasible, match=reason):
        plan_acquisition(roe0, chief, dad, cfg)


def test_separation_that_would_drop_below_the_minimum_is_refused():
    # approaching at 400 m of da from 9 km: tiny burns cannot stop the approach before 5 km
    roe0 = roe_from(400.0, 9500.0, 500.0, -1.6, 400.0, 1.5)
    cfg = dataclasses.replace(CFG, max_burn_dv=0.004, planning_margin=0.0)
    with pytest.raises(AcquisitionInfeasible, match="below a_dl_min"):
        plan_acquisition(roe0, CHIEF, 0.0, cfg)


@pytest.mark.parametrize("changes,name", [
    ({"a_dl_max": 4000.0}, "a_dl_max"), ({"a_dl_target": 12000.0}, "a_dl_target"), ({"min_ei": -1.0}, "min_ei"),
    ({"max_burn_dv": math.nan}, "max_burn_dv"), ({"dv_quantum": 0.5}, "dv_quantum"), ({"axes": "TX"}, "axes"),
    ({"window": 100.0, "planning_margin": 600.0}, "window"), ({"grid_per_orbit": 0}, "grid_per_orbit"),
    ({"fov_half_r_deg": 95.0}, "fov_half_r_deg"), ({"j2": "yes"}, "j2"),
])
def test_bad_configuration_names_the_field(changes, name):
    with pytest.raises(InvalidAcquisitionConfig) as info:
        plan_acquisition(TYPICAL, CHIEF, 0.0, dataclasses.replace(CFG, **changes))
    assert info.value.name == name and name in str(info.value)


def test_no_burns_keeps_an_interval_free_of_burns():
    """``no_burns`` (the final OD's radar arc): no burn in the interval, every IC still met; without it the same
    problem burns there."""
    free = plan_acquisition(TYPICAL, CHIEF, DA_DOT, CFG)
    arc = (free.t_final - 46800.0, free.t_final - 1800.0)
    assert np.any((free.epochs >= arc[0]) & (free.epochs <= arc[1]))
    quiet = plan_acquisition(TYPICAL, CHIEF, DA_DOT, CFG, no_burns=[arc])
    assert quiet.t_final == free.t_final and quiet.n_burns >= 1
    assert not np.any((quiet.epochs >= arc[0]) & (quiet.epochs <= arc[1]))
    check_plan(quiet, TYPICAL, CHIEF, DA_DOT, CFG)


# --- the LP handed to HiGHS directly is linprog's to the bit ---------------------------------------------

@pytest.mark.parametrize("roe0,dad,cfg,raises", [
    (TYPICAL, DA_DOT, CFG, False),
    (roe_from(120.0, -18000.0, 350.0, 2.0, 250.0, -0.4), 0.0, CFG, False),  # following, approaching
    (roe_from(-60.0, 40000.0, 700.0, 0.3, 500.0, 2.5), DA_DOT, dataclasses.replace(CFG, axes="TN"), False),
    (roe_from(-180, 25000.0, 500, -1.6, 100.0, 1.5), DA_DOT, dataclasses.replace(CFG, axes="T"), True),  # infeasible
])
def test_direct_highs_solve_equals_linprog(monkeypatch, roe0, dad, cfg, raises):
    """Every LP of a plan (the e/i iterations and, for an infeasible one, the diagnosis), solved by
    :func:`roe_sep.core.acquisition.highs.solve_lp` and by ``linprog(method="highs")``: the same status, solution,
    objective and iteration count, bit for bit."""
    import roe_sep.core.acquisition.planner as planner

    solve, seen = planner._linprog, []

    def both(pb, cols, ihat, **flags):
        direct = solve(pb, cols, ihat, **flags)
        ref = solve(pb, cols, ihat, use_linprog=True, **flags)
        seen.append((direct.status, ref.status))
        assert direct.status == ref.status
        if ref.status == 0:
            assert np.array_equal(direct.x, ref.x) and direct.fun == ref.fun and direct.nit == ref.nit
        return direct

    monkeypatch.setattr(planner, "_linprog", both)
    if raises:
        with pytest.raises(AcquisitionInfeasible):
            plan_acquisition(roe0, CHIEF, dad, cfg)
        assert any(s == 2 for s, _ in seen)
    else:
        plan_acquisition(roe0, CHIEF, dad, cfg)
        assert seen and all(s == 0 for s, _ in seen)


def test_signed_rows_equal_the_two_block_construction_to_the_bit():
    """[sub, -sub, 0] from one dense-to-CSR conversion of sub: the same CSR arrays (shape, indptr, indices, data
    bytes, dtypes) as converting [sub, -sub] and appending an empty (R, 3) block, zeros (also -0.0) left out in both;
    empty rows and an all-zero block included."""
    from scipy import sparse

    rng = np.random.default_rng(7)
    for rows, cols in ((1, 1), (5, 3), (4, 6), (60, 40), (300, 120)):
        sub = np.tril(rng.normal(size=(rows, cols)) * 10.0 ** rng.integers(-12, 6, size=(rows, cols)))
        sub[rng.random((rows, cols)) < 0.1] = -0.0
        if cols == 6:
            sub[:] = 0.0  # no nonzero at all
        sub[rows // 2] = 0.0  # an empty row
        ref = sparse.hstack([sparse.csr_matrix(np.hstack([sub, -sub])), sparse.csr_matrix((len(sub), 3))])
        got = signed_rows(sub)
        assert got.format == ref.format == "csr" and got.shape == ref.shape == (rows, 2 * cols + 3)
        for name in ("indptr", "indices", "data"):
            a, b = getattr(got, name), getattr(ref, name)
            assert a.dtype == b.dtype and a.tobytes() == b.tobytes()
