"""The planner's response to the ejection the footage measured (issue 41 part 2;
roe_sep.core.decisions.planner.ejection_response, docs/run.md "The ejection camera"): nothing for a nominal
ejection; for a weak or mis-pointed one a carrier CAM, the ejection completed in pulses, the CAM undone and the
designed drift-stop after both, checked against the house's relative motion (seed 002 Eq. 2) from the true
ejection; a stuck picosatellite reported and its drift-stop withdrawn; the CAM alone without the completion; the
state's strict-JSON round trip and the restart."""

import dataclasses
import json
import math

import numpy as np
import pytest
from test_planner_footage import FOOTAGE, footage, planned
from test_planner_rules import EJECTION, PERIOD, D, kinds

from roe_sep.core.decisions import planner as rules
from roe_sep.core.decisions.cam import completion_burns, predicted_distance, reversal_burn
from roe_sep.core.decisions.common import PlannedBurn
from roe_sep.core.relmotion.maneuvers import delta_roe
from roe_sep.core.relmotion.orbit import mean_motion
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory

RESPONSE = dataclasses.replace(FOOTAGE, cam=True, completion=True)
CHIEF = Chief(D.a, D.inc, EJECTION.u1, 0.0)
END = 40 * 3600.0


def respond(f1, config=RESPONSE, dv=None):
    """The planner's state before and after, and its actions, at the footage's end for an ejection of ``f1`` of the
    commanded one (or ``dv``), the true dv and that epoch."""
    state, dv, times = footage(planned(config), f1, config, dv=dv)
    after, actions = rules.on_step(state, times[0] + 270.0, 101.0, True, config)
    return state, after, actions, dv, times[0] + 270.0


def relative(plan):
    return tuple(Burn(b.epoch, tuple(-np.array(b.dv_rtn))) for b in plan.burns)


def flown(dv, plan, times):
    """Distance [m] and the a-scaled ROE at END of the ejection ``dv`` released at t = 0 under ``plan``."""
    rho, _ = predicted_distance(dv, np.zeros((3, 3)), CHIEF, times, relative(plan))
    roe0 = delta_roe(np.asarray(dv, dtype=float), CHIEF.u0, D.a, mean_motion(D.a))
    return rho, trajectory(roe0, 0.0, relative(plan), np.array([END]), CHIEF)[0] * D.a


def test_a_nominal_ejection_changes_nothing():
    before, after, actions, _, _ = respond(1.0)
    assert kinds(actions) == ["PublishEstimate", "Log", "Log"] and "within its command" in actions[2].text
    assert after.in_force == before.in_force and after.last_plan == before.last_plan and after.responded


@pytest.mark.parametrize("f1", [0.1, 0.2, 0.3, 0.4, 0.6])
def test_a_weak_ejection_is_completed_and_reaches_the_designed_vectors(f1):
    _, state, actions, dv, t = respond(f1)
    assert kinds(actions) == ["PublishEstimate", "Log", "PublishPlan", "StopBearings", "Status"]
    plan, status = actions[2], actions[4]
    values = dict(status.values)
    assert values["contingency"] == "ejection_off" and float(values["f1"]) == pytest.approx(f1, abs=0.005)
    purposes = [b.purpose for b in plan.burns]
    epochs = [b.epoch for b in plan.burns]
    assert epochs == sorted(epochs) and purposes[-1] == "drift_stop" and epochs[0] >= t + RESPONSE.cam_latency
    pulses = [b for b in plan.burns if b.purpose == "ejection_completion"]
    assert len(pulses) == math.ceil((1 - f1) * np.linalg.norm(D.dv1_rtn) / RESPONSE.completion_max_pulse - 0.02)
    assert all(np.linalg.norm(b.dv_rtn) <= RESPONSE.completion_max_pulse + 1e-12 for b in pulses)
    # the carrier flies measured minus commanded, at the release's u, whole orbits after it
    assert np.sum([b.dv_rtn for b in pulses], axis=0) == pytest.approx(np.array(dv) - D.dv1_rtn, abs=0.002)
    assert all(b.u == pytest.approx(rules.wrap_angle(EJECTION.u1)) for b in pulses)
    assert all((b.epoch / PERIOD) == pytest.approx(round(b.epoch / PERIOD), abs=1e-9) for b in pulses)
    cams = [b for b in plan.burns if b.purpose in ("collision_avoidance", "collision_avoidance_reversal")]
    if cams:  # undone at its own u: together zero
        assert len(cams) == 2 and np.sum([b.dv_rtn for b in cams], axis=0) == pytest.approx(0.0, abs=1e-15)
        assert cams[0].u == cams[1].u and cams[1].epoch > pulses[-1].epoch
    assert state.in_force.t_stop == epochs[-1] and state.camera_done and state.last_plan == plan
    # the truth of the house (seed 002 Eq. 2 with J2) from the true ejection: the keep-out holds once left, and at
    # the end the designed drift and e/i vectors, only the along-track offset differs
    times = np.arange(0.0, END, 10.0)
    rho, roe = flown(dv, plan, times)
    out = np.nonzero(rho >= 1000.0)[0][0]
    assert rho[out:].min() >= 999.0 and rho[times > PERIOD].min() > 1000.0
    _, nominal = flown(np.array(D.dv1_rtn), rules.separation_plan(EJECTION, RESPONSE), times)
    assert np.abs(roe - nominal)[[0, 2, 3, 4, 5]].max() < 5.0


def test_a_mis_pointed_ejection_gets_the_cam_and_one_pulse():
    """The -7 deg turn about N (docs/contingencies.md: 14 m one orbit later): off in direction, back inside, so a
    CAM, the rest in one pulse, and the keep-out holds once left."""
    c, s = math.cos(math.radians(-7.0)), math.sin(math.radians(-7.0))
    turned = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]]) @ np.array(D.dv1_rtn)
    _, _, actions, dv, _ = respond(1.0, dv=turned)
    plan, values = actions[2], dict(actions[4].values)
    assert values["contingency"] == "ejection_off" and float(values["pointing_z"]) > 3.0
    assert [b.purpose for b in plan.burns] == ["collision_avoidance", "ejection_completion",
                                               "collision_avoidance_reversal", "drift_stop"]
    times = np.arange(0.0, END, 10.0)
    rho, _ = flown(dv, plan, times)
    assert rho[np.nonzero(rho >= 1000.0)[0][0]:].min() >= 999.0


def test_a_weak_ejection_without_the_response_comes_back():
    """What the CAM is for: f1 = 0.2 with the blind drift-stop comes back inside the keep-out in the first orbit."""
    _, _, _, dv, _ = respond(0.2)
    times = np.arange(0.0, PERIOD, 10.0)
    rho, _ = flown(dv, rules.separation_plan(EJECTION, RESPONSE), times)
    out = np.nonzero(rho >= 1000.0)[0][0]
    assert rho[out:].min() < 1000.0


def test_a_stuck_picosatellite_is_reported_and_its_drift_stop_withdrawn():
    _, state, actions, _, t = respond(0.02)
    assert kinds(actions) == ["PublishEstimate", "Log", "PublishPlan", "StopBearings", "Status"]
    plan, values = actions[2], dict(actions[4].values)
    assert values["contingency"] == "stuck_ejection" and [b.purpose for b in plan.burns] == ["collision_avoidance"]
    assert plan.burns[0].epoch == pytest.approx(t + RESPONSE.cam_latency, abs=1e-6)
    assert state.in_force is None and state.camera_done


def test_without_the_completion_the_cam_joins_the_plan_in_force():
    config = dataclasses.replace(RESPONSE, completion=False)
    before, state, actions, _, _ = respond(0.2, config)
    plan = actions[2]
    assert [b.purpose for b in plan.burns] == ["collision_avoidance", "drift_stop"]
    assert plan.burns[1] == before.last_plan.burns[0] and state.in_force == before.in_force
    off = dataclasses.replace(RESPONSE, cam=False, completion=False)
    assert kinds(respond(0.2, off)[2]) == ["PublishEstimate", "Log"]  # both off: the response is not run


def test_the_response_round_trips_and_a_restart_keeps_it():
    _, state, _, _, t = respond(0.2)
    restored = rules.PlannerState.from_dict(json.loads(json.dumps(state.to_dict(), allow_nan=False)))
    assert restored == state
    again, actions = rules.on_step(restored, t + 600.0, 102.0, True, RESPONSE)
    assert not any(isinstance(a, rules.PublishPlan) for a in actions)  # decided once
    _, actions = rules.on_restart(restored, RESPONSE)
    assert actions[1] == state.last_plan  # the plan in force, latched again


def test_completion_and_reversal_helpers():
    pulses = completion_burns((0.1, 0.0, 0.0), (1.0, 0.0, 0.0), t_release=100.0, u_release=0.5, period=5000.0,
                              t_earliest=5101.0, max_pulse=0.3)
    assert [b.epoch for b in pulses] == [10100.0, 15100.0, 20100.0]
    assert np.sum([b.dv_rtn for b in pulses], axis=0) == pytest.approx((-0.9, 0.0, 0.0))
    kw = dict(t_release=0.0, u_release=0.0, period=5000.0, t_earliest=0.0)
    assert completion_burns((1.0, 0.0, 0.0), (1.0, 0.0, 0.0), max_pulse=0.3, **kw) == ()
    with pytest.raises(ValueError, match="largest pulse"):
        completion_burns((0.1, 0.0, 0.0), (1.0, 0.0, 0.0), max_pulse=0.0, **kw)
    cam = PlannedBurn.at(600.0, 1.0, (0.0, 0.1, 0.0), "carrier", "collision_avoidance")
    undo = reversal_burn(cam, 5000.0, 20100.0)
    assert undo.epoch == 20600.0 and undo.dv_rtn == (-0.0, -0.1, -0.0) and undo.u == cam.u
    assert reversal_burn(cam, 5000.0, 0.0).epoch == 5600.0


def test_a_late_estimate_is_not_acted_on_and_costs_nothing():
    """An estimate after the drift-stop's epoch (or on another clock: a standalone planner on wall time, 1.8e9 s)
    gets no response, at once (the CAM rule's horizon is not stretched to it)."""
    import time

    state, dv, times = footage(planned(RESPONSE), 0.2, RESPONSE)
    done, actions = rules.on_step(state, times[0] + 270.0, 101.0, True, dataclasses.replace(RESPONSE, cam=False,
                                                                                            completion=False))
    tic = time.process_time()
    after, actions = rules.ejection_response(done, 1.8e9, RESPONSE)
    assert time.process_time() - tic < 1.0
    assert kinds(actions) == ["Log"] and "no response" in actions[0].text and after.responded
    from roe_sep.core.decisions.cam import cam_decision

    late = cam_decision(dv, np.eye(3) * 1e-8, D.dv1_rtn, CHIEF, 1.8e9)
    assert late.burn is None and "past the horizon" in late.reason
