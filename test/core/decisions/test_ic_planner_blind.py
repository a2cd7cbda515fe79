"""The ic_planner's blind acquisition through a radar outage (issue 41 part 3; roe_sep.core.decisions.ic_planner
.on_step, docs/run.md "Decisions"): no OD ``blind_after`` after the release, so the acquisition is planned from
the ejection on record and the burns executed since; it stops the drift that would carry the pair past 50 km
before the first OD after a 24-h outage (the house's relative motion, seed 002 Eq. 2, with the nominal drag); the
first OD after it plans anew; the measured ejection replaces the commanded one; never with an OD on record; the
state's strict-JSON round trip."""

import dataclasses
import json

import numpy as np
import pytest

from roe_sep.core.acquisition.planner import AcquisitionConfig
from roe_sep.core.decisions import ic_planner as rules
from roe_sep.core.decisions.common import WARN, PlannedBurn
from roe_sep.core.od.radar import DEFAULT_EPOCH_UTC, julian_date
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory
from roe_sep.core.separation.double_impulse import design, plan_drift_stop
from roe_sep.core.truth.secular import chief_from_u

D = design()
KEP = tuple(float(x) for x in chief_from_u(D.a, D.inc, 0.3, D.u1))  # the chief at the release (t = 0)
A_DA_DOT = float(drag_da_dot(0.0151, 1e-12, D.a)) * D.a  # m/s: about -68 m/day
DV = np.array(D.dv1_rtn)
COV = 0.1 ** 2 * np.outer(DV, DV)
CONFIG = rules.IcPlannerConfig(AcquisitionConfig(planning_margin=11400.0), trim=False, burn_sigma=0.05,
                               final_od_arc=0.0, replan_on_burn=True, ei_margin_sigmas=0.0, ic_drift_tolerance=5.0,
                               jd0=julian_date(DEFAULT_EPOCH_UTC), blind_after=86400.0)
PRIOR = rules.EjectionPrior(0.0, KEP, float(D.u1), tuple(DV), tuple(COV.reshape(-1)), A_DA_DOT, 0.2 * abs(A_DA_DOT))
STOP = plan_drift_stop(DV, D.u1, 0.0, D.a, D.inc, k=3, p=0.06, j2=True)
CHIEF = Chief(D.a, D.inc, float(D.u1), 0.0)


def after_drift_stop(prior=PRIOR):
    state, _ = rules.on_separation_plan(rules.IcPlannerState(), [STOP.epoch], CONFIG)
    state, _ = rules.on_ejection(state, prior, CONFIG)
    burn = PlannedBurn.at(STOP.epoch, STOP.u2, STOP.dv_carrier_rtn, "carrier", "drift_stop")
    state, _ = rules.on_executed(state, burn, CONFIG)
    return state


def along_track(burns, times):
    """a dl [m] of the design's ejection under the drift-stop and ``burns`` (relative), the nominal drag."""
    flown = (Burn(STOP.epoch, tuple(-np.array(STOP.dv_carrier_rtn))), *burns)
    roe0 = delta_roe(DV, CHIEF.u0, D.a, mean_motion(D.a))
    return trajectory(roe0, 0.0, flown, times, CHIEF, da_dot=A_DA_DOT / D.a)[:, 1] * D.a


def test_no_od_a_day_after_the_release_plans_the_acquisition_blind():
    state = after_drift_stop()
    early, actions = rules.on_step(state, 86399.0, CONFIG)
    assert early == state and actions == ()
    blind, actions = rules.on_step(state, 86400.0, CONFIG)
    assert kinds(actions) == ["Status", "PublishPlan"]
    finding = dict(actions[0].values)
    assert actions[0].level == WARN and finding["contingency"] == "blind_acquisition"
    assert finding["source"] == "commanded" and "holds a dl" in actions[0].message
    plan = actions[1]
    (burn,) = plan.burns
    assert burn.epoch >= 86400.0 + CONFIG.cfg.planning_margin and burn.dv_rtn[0] == burn.dv_rtn[2] == 0.0
    assert burn.purpose == "ic_acquisition" and abs(burn.dv_rtn[1]) <= CONFIG.cfg.max_burn_dv
    assert round(burn.dv_rtn[1] / CONFIG.cfg.dv_quantum, 9) % 1 == 0.0  # quantized
    assert blind.blind and blind.plans == 1 and blind.t_final is None and blind.plan_in_force == plan.burns
    # the drift it stops: without it the pair passes 50 km before the first OD after a 24-h outage (about 45 h);
    # with it the separation is back to its value a day after the burn, and stays far from both bounds
    times = np.arange(86400.0, 3 * 86400.0, 600.0)
    free = along_track((), times)
    assert free[times <= 45 * 3600.0].max() > 50e3
    flown = along_track((burn.relative(),), times)
    at_burn = along_track((), np.array([burn.epoch]))[0]
    # within the quantization: half a quantum is a da of q / n, which moves dl by 1.5 n (q / n) H = 1.5 q H
    assert along_track((burn.relative(),), np.array([burn.epoch + CONFIG.blind_after]))[0] == pytest.approx(
        at_burn, abs=1.5 * CONFIG.cfg.dv_quantum * CONFIG.blind_after)
    assert np.abs(flown).max() < 0.8 * 50e3 and np.abs(flown).min() > 10e3
    assert plan.t_final == pytest.approx(burn.epoch + CONFIG.blind_after)
    again, actions = rules.on_step(blind, 90000.0, CONFIG)
    assert again == blind and actions == ()  # once
    # its own latched plan read back fixes no IC epoch: the first OD after the outage opens the acquisition's window
    latched, _ = rules.on_own_plan(blind, plan.burns, plan.t_final, CONFIG)
    assert latched == blind and latched.t_final is None


def test_the_first_od_after_the_outage_plans_in_a_window_of_its_own():
    blind, actions = rules.on_step(after_drift_stop(), 86400.0, CONFIG)
    plan = actions[1]
    blind, _ = rules.on_executed(blind, plan.burns[0], CONFIG)
    t_od = 45 * 3600.0
    roe = trajectory(delta_roe(DV, CHIEF.u0, D.a, mean_motion(D.a)), 0.0,
                     (Burn(STOP.epoch, tuple(-np.array(STOP.dv_carrier_rtn))), plan.burns[0].relative()),
                     np.array([t_od]), CHIEF, da_dot=A_DA_DOT / D.a)[0]
    od = rules.OdSolution(t_od + 100.0, t_od, KEP, float(CHIEF.u_at(t_od)), tuple(roe),
                          tuple(np.diag([1.0] * 6).ravel()), A_DA_DOT, 1e-5)
    state, actions = rules.on_od(blind, od, t_od + 100.0, CONFIG)
    assert "PublishPlan" in kinds(actions)
    assert state.t_final is not None and state.t_final > t_od + 100.0 + CONFIG.cfg.planning_margin
    assert state.plans == 2


def test_never_with_an_od_on_record_or_switched_off():
    state = after_drift_stop()
    seen = dataclasses.replace(state, last_key=(80000.0, 79900.0))
    assert rules.on_step(seen, 90000.0, CONFIG) == (seen, ())
    off = dataclasses.replace(CONFIG, blind_after=0.0)
    assert rules.on_step(state, 90000.0, off) == (state, ())
    flying = dataclasses.replace(state, separation_end=100000.0)
    assert rules.on_step(flying, 90000.0, CONFIG) == (flying, ())
    assert rules.on_step(rules.IcPlannerState(), 90000.0, CONFIG) == (rules.IcPlannerState(), ())


def test_the_measured_ejection_replaces_the_commanded_one():
    state = after_drift_stop()
    measured, _ = rules.on_measured(state, 0.5 * DV, (1e-8 * np.eye(3)).reshape(-1), CONFIG)
    assert measured.ejection.source == "footage" and measured.ejection.dv == pytest.approx(tuple(0.5 * DV))
    again, _ = rules.on_ejection(measured, PRIOR, CONFIG)  # the latched event again: the measurement stays
    assert again == measured
    blind, actions = rules.on_step(measured, 86400.0, CONFIG)
    assert dict(actions[0].values)["source"] == "footage"
    none, _ = rules.on_measured(rules.IcPlannerState(), DV, np.eye(3).reshape(-1), CONFIG)
    assert none == rules.IcPlannerState()  # no chief to put it on


def test_the_prior_as_a_solution():
    od = PRIOR.solution(86400.0)
    assert od.stamp == 86400.0 and od.epoch == 0.0 and od.a == D.a
    assert np.array(od.roe) == pytest.approx(delta_roe(DV, D.u1, D.a, mean_motion(D.a)))
    cov = np.array(od.covariance).reshape(6, 6)
    x = np.array(od.roe) * D.a
    assert cov == pytest.approx(0.01 * np.outer(x, x), rel=1e-9, abs=1e-9)  # 10 % of the ejection, linear


def test_the_blind_state_round_trips_through_strict_json():
    blind, _ = rules.on_step(after_drift_stop(), 86400.0, CONFIG)
    restored = rules.IcPlannerState.from_dict(json.loads(json.dumps(blind.to_dict(), allow_nan=False)))
    assert restored == blind


def kinds(actions):
    return [type(a).__name__ for a in actions]


def test_the_commanded_prior_carries_the_spl_errors_and_the_nominal_drag():
    """The covariance: spl_sigma of the magnitude along dv, the attitude sigma across it (seed 002 Eq. 22); the
    drag: the scenario's nominal, its ballistic_sigma as 1-sigma."""
    from roe_sep.core.config import load_scenario
    from roe_sep.core.constants import ARCSEC

    sc = load_scenario(None)
    prior = rules.EjectionPrior.commanded(10.0, KEP, float(D.u1), DV, sc)
    cov = np.array(prior.cov).reshape(3, 3)
    unit = DV / np.linalg.norm(DV)
    across = np.cross(unit, [0.0, 0.0, 1.0])
    across /= np.linalg.norm(across)
    assert unit @ cov @ unit == pytest.approx((sc.separation.spl_sigma * np.linalg.norm(DV)) ** 2)
    assert across @ cov @ across == pytest.approx((sc.monte_carlo.attitude_sigma_arcsec * ARCSEC
                                                   * np.linalg.norm(DV)) ** 2)
    a = KEP[0]
    assert prior.a_da_dot == pytest.approx(float(drag_da_dot(sc.monte_carlo.delta_b, sc.monte_carlo.density, a)) * a)
    assert prior.a_da_dot_sigma == pytest.approx(abs(prior.a_da_dot) * sc.monte_carlo.ballistic_sigma)
    assert prior.source == "commanded" and prior.t == 10.0 and prior.dv == pytest.approx(tuple(DV))
