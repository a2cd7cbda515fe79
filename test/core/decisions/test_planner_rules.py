"""The planner's decisions without DDS (roe_sep.core.decisions.planner, docs/run.md "Decisions"): the drift-stop of
a commanded ejection, the hold of a weak one (camera bearings), the replacement of a missing drift-stop, the
completion of a short one, a malformed event, the record a restarted planner waits for, the state's strict-JSON
round trip, and a planner restarted from its decision record after a hold, a replacement and a completion."""

import dataclasses
import json
import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.decisions import planner as rules
from roe_sep.core.decisions.common import ERROR, WARN, PlannedBurn, decision_record, read_record
from roe_sep.core.relmotion.dynamics import arg_latitude_rate, drag_da_dot
from roe_sep.core.safety.ejection_check import camera_bearing, predicted_los
from roe_sep.core.separation.double_impulse import design, plan_drift_stop
from roe_sep.core.truth.secular import chief_from_u

SC = load_scenario(None)
D = design(SC.separation)
CHIEF = chief_from_u(D.a, D.inc, 0.3, D.u1)  # mean elements at the release (t = 0)
EJECTION = rules.Ejection(0, 0, tuple(float(x) for x in CHIEF), float(CHIEF[4] + CHIEF[5]),
                          tuple(float(x) for x in D.dv1_rtn), float(D.u1))
PERIOD = 2.0 * math.pi / float(arg_latitude_rate(D.a, D.inc, True))
CONFIG = rules.PlannerConfig("double_impulse", 3, "fixed", 0.06, True, SC, retry=True, retry_tolerance=600.0,
                             retry_margin=11400.0, makeup=True, makeup_z=3.0, makeup_pointing=math.radians(5.0),
                             hold=True, camera_sigma=math.radians(0.02), camera_floor=1.0, hold_sigmas=3.0,
                             hold_alpha=1e-3, hold_lead=1800.0)


def kinds(actions):
    return [type(a).__name__ for a in actions]


def executed(epoch, dv, spacecraft="carrier", purpose="drift_stop"):
    return PlannedBurn.at(epoch, 0.0, dv, spacecraft, purpose)


@pytest.fixture(scope="module")
def planned():
    """The drift-stop of the default design's ejection, released at its commanded epoch (t = 0)."""
    state, actions = rules.on_ejection(rules.PlannerState(), EJECTION, CONFIG)
    state, _ = rules.on_executed(state, executed(0.0, D.dv1_rtn, "picosatellite", "ejection"), 100.0, CONFIG)
    return state, actions


def test_an_ejection_gets_its_drift_stop(planned):
    state, actions = planned
    assert kinds(actions) == ["PublishPlan", "Log", "Status"]
    plan = actions[0]
    stop = plan_drift_stop(np.array(D.dv1_rtn), D.u1, 0.0, D.a, D.inc, k=3, p=0.06, j2=True)
    (burn,) = plan.burns
    assert burn.dv_rtn == pytest.approx(stop.dv_carrier_rtn, abs=1e-15) and burn.epoch == pytest.approx(stop.epoch)
    assert plan.strategy == "double_impulse" and plan.p_reduction == 0.06 and plan.stamp == (0, 0)
    assert plan.aimed.roe == pytest.approx(stop.aimed_roe) and plan.aimed.t == stop.epoch
    assert state.in_force == rules.InForce(EJECTION, None, 0.06, burn.epoch) and state.plans == 1
    assert state.released == 0.0 and state.record_since == 100.0


def test_a_malformed_ejection_is_an_error():
    bad = dataclasses.replace(EJECTION, kep=(math.nan, *EJECTION.kep[1:]))
    state, actions = rules.on_ejection(rules.PlannerState(), bad, CONFIG)
    assert kinds(actions) == ["Status"] and actions[0].level == ERROR and actions[0].log == "error"
    assert actions[0].message.startswith("ejection event rejected: chief elements are not a valid low Earth orbit")
    assert state == rules.PlannerState()


def bearings(state, f1, seed=7):
    """The camera's bearings of an ejection of ``f1`` at the nominal drag, every minute until the decision."""
    mc = SC.monte_carlo
    da_dot = float(drag_da_dot(mc.delta_b, mc.density, D.a))
    times = np.arange(60.0, state.in_force.t_stop - CONFIG.hold_lead, 60.0)
    los = camera_bearing(predicted_los([f1], D.dv1_rtn, 0.0, CHIEF, da_dot, times=times)[0] * 1000.0,
                         CONFIG.camera_sigma, np.random.default_rng(seed))
    for t, v in zip(times, los):
        state, _ = rules.on_bearing(state, float(t), v, CONFIG)
    return state


def test_a_weak_ejection_holds_the_drift_stop(planned):
    state = bearings(planned[0], 0.3)
    t = state.in_force.t_stop - CONFIG.hold_lead
    early, actions = rules.on_step(state, t - 60.0, 101.0, True, CONFIG)
    assert early == state and actions == ()  # not yet: hold_lead before the drift-stop
    held, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    assert kinds(actions) == ["StopBearings", "Log", "PublishPlan", "Status"]
    assert actions[2] == rules.PublishPlan("double_impulse", (0, 0), rules.sec_nanosec(t), 0.0)  # no burn, no aim
    finding = actions[3]
    assert finding.level == WARN and finding.part == "contingency" and finding.stamp == t
    assert dict(finding.values)["contingency"] == "weak_ejection" and finding.message.startswith("weak_ejection: ")
    assert held.in_force is None and held.camera_done and held.bearings == () and held.plans == 2


def test_a_nominal_ejection_flies_its_drift_stop(planned):
    state = bearings(planned[0], 1.0)
    t = state.in_force.t_stop - CONFIG.hold_lead
    flies, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    assert kinds(actions) == ["StopBearings", "Log"] and actions[1].text.endswith("drift-stop flies")
    assert flies.in_force == state.in_force and flies.camera_done and flies.plans == 1
    late, _ = rules.on_bearing(flies, t + 60.0, (1.0, 0.0, 0.0), CONFIG)
    assert late == flies  # the decision is made: no more bearings


def checked(state):
    """The camera's decision made (no bearing: nothing to hold)."""
    return dataclasses.replace(state, camera_done=True)


def test_a_missing_drift_stop_is_replaced_whole_orbits_later(planned):
    state = checked(planned[0])
    t_stop = state.in_force.t_stop
    t = t_stop + CONFIG.retry_tolerance + 60.0
    waiting, actions = rules.on_step(state, t - 120.0, 101.0, True, CONFIG)
    assert actions == () and waiting == state  # within retry_tolerance: not missing yet
    replaced, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    assert kinds(actions) == ["PublishPlan", "Status"]
    plan, finding = actions
    orbits = math.ceil((t + CONFIG.retry_margin - t_stop) / PERIOD)
    assert plan.stamp == rules.sec_nanosec(t) and plan.burns[0].epoch == pytest.approx(t_stop + orbits * PERIOD,
                                                                                        abs=1.0)
    assert plan.burns[0].dv_rtn == pytest.approx(planned[1][0].burns[0].dv_rtn, rel=1e-3)  # the same drift-stop
    assert replaced.in_force.t_stop == plan.burns[0].epoch and replaced.in_force.k == 3 + 2 * orbits
    assert replaced.retried == (round(t_stop, 3),) and replaced.plans == 2
    assert dict(finding.values)["contingency"] == "drift_stop_replaced" and finding.level == WARN
    again, actions = rules.on_step(replaced, t + 60.0, 101.0, True, CONFIG)
    assert actions == ()  # the replacement is not due yet


def test_no_replacement_before_the_record_is_recovered(planned):
    state = checked(planned[0])
    t = state.in_force.t_stop + CONFIG.retry_tolerance + 60.0
    assert rules.on_step(state, t, 101.0, False, CONFIG)[1] == ()  # free running: 1 s after the release arrived
    assert kinds(rules.on_step(state, t, 102.0, False, CONFIG)[1]) == ["PublishPlan", "Status"]  # RECORD_SETTLE later
    unreleased = dataclasses.replace(state, released=None, record_since=None)
    assert rules.on_step(unreleased, t, 1e9, True, CONFIG)[1] == ()
    off = dataclasses.replace(CONFIG, retry=False, makeup=False)
    assert rules.on_step(state, t, 101.0, True, off)[1] == ()


def test_a_short_drift_stop_is_completed(planned):
    state = checked(planned[0])
    commanded = np.array(planned[1][0].burns[0].dv_rtn)
    t_exec = state.in_force.t_stop
    state, _ = rules.on_executed(state, executed(t_exec, 0.8 * commanded), 101.0, CONFIG)
    t = t_exec + 600.0
    completed, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    assert kinds(actions) == ["PublishPlan", "Status"]
    plan, finding = actions
    (rest,) = plan.burns
    orbits = math.ceil((t + CONFIG.retry_margin - t_exec) / PERIOD)
    assert rest.dv_rtn == pytest.approx(0.2 * commanded, abs=1e-12) and rest.purpose == "drift_stop"
    assert rest.epoch == pytest.approx(t_exec + orbits * PERIOD, abs=1e-3) and rest.u == planned[1][0].burns[0].u
    assert plan.aimed == planned[1][0].aimed and plan.p_reduction == 0.0 and plan.stamp == rules.sec_nanosec(t)
    assert dict(finding.values)["contingency"] == "drift_stop_completed" and completed.in_force is None
    assert completed.plans == 2


def test_a_nominal_drift_stop_is_checked_once(planned):
    state = checked(planned[0])
    commanded = np.array(planned[1][0].burns[0].dv_rtn)
    state, _ = rules.on_executed(state, executed(state.in_force.t_stop, commanded), 101.0, CONFIG)
    done, actions = rules.on_step(state, state.in_force.t_stop + 600.0, 101.0, True, CONFIG)
    assert actions == () and done.in_force is None and done.plans == 1


def test_a_failed_check_is_an_error(planned):
    state = checked(planned[0])
    bad = dataclasses.replace(state, in_force=dataclasses.replace(
        state.in_force, ejection=dataclasses.replace(EJECTION, dv_rtn=(math.nan, 0.0, 0.0))))
    t = state.in_force.t_stop + CONFIG.retry_tolerance + 60.0
    after, actions = rules.on_step(bad, t, 101.0, True, CONFIG)
    assert kinds(actions) == ["Status"] and actions[0].level == ERROR
    assert actions[0].message.startswith("drift-stop check failed: ejection dv is not finite")
    assert after.retried == (round(state.in_force.t_stop, 3),)  # found missing, not replaced twice


def test_the_state_round_trips_through_strict_json(planned):
    state = bearings(planned[0], 1.0)
    state, _ = rules.on_executed(state, executed(9000.0, (0.1, 0.2, 0.3)), 101.0, CONFIG)
    state = dataclasses.replace(state, retried=(1.5,))
    restored = rules.PlannerState.from_dict(json.loads(json.dumps(state.to_dict(), allow_nan=False)))
    assert restored == state
    t = state.in_force.t_stop - CONFIG.hold_lead
    assert rules.on_step(restored, t, 101.0, True, CONFIG) == rules.on_step(state, t, 101.0, True, CONFIG)


def restart(state):
    """What a restarted planner recovers: its decision record (strict JSON, as the decisions topic carries it) read
    back."""
    version, stamp, persisted = read_record(decision_record("planner", 3, 1234.5, state), "planner")
    assert (version, stamp) == (3, 1234.5) and "bearings" not in persisted and "record_since" not in persisted
    return rules.PlannerState.restored(persisted)


def test_a_planner_restarted_after_a_hold_keeps_the_drift_stop_withdrawn(planned):
    state = bearings(planned[0], 0.3)
    t_stop = state.in_force.t_stop
    t = t_stop - CONFIG.hold_lead
    held, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    hold = actions[2]
    assert hold.burns == () and held.last_plan == hold
    back = restart(held)
    assert back == dataclasses.replace(held, released=None, record_since=None)
    _, actions = rules.on_restart(back, CONFIG)  # the hold latched again as it was, the camera left alone
    assert kinds(actions) == ["StopBearings", "PublishPlan", "Status"] and actions[1] == hold
    again, actions = rules.on_ejection(back, EJECTION, CONFIG)  # the latched ejection again: decided already
    assert again == back and kinds(actions) == ["Log"] and "already decided" in actions[0].text
    back, _ = rules.on_executed(back, executed(0.0, D.dv1_rtn, "picosatellite", "ejection"), 500.0, CONFIG)
    for now in (t + 60.0, t_stop, t_stop + 2 * CONFIG.retry_tolerance):  # nothing flies, nothing is replaced
        back, actions = rules.on_step(back, now, 510.0, False, CONFIG)
        assert not [a for a in actions if isinstance(a, rules.PublishPlan)]
    # what a planner without its record does with the latched ejection: the blind drift-stop once more
    _, actions = rules.on_ejection(rules.PlannerState(), EJECTION, CONFIG)
    assert actions[0].burns == planned[1][0].burns


def test_a_planner_restarted_after_a_replacement_keeps_the_replacement(planned):
    state = checked(planned[0])
    t_stop = state.in_force.t_stop
    t = t_stop + CONFIG.retry_tolerance + 60.0
    replaced, actions = rules.on_step(state, t, 101.0, True, CONFIG)
    replacement = actions[0]
    back = restart(replaced)
    _, actions = rules.on_restart(back, CONFIG)
    assert kinds(actions) == ["StopBearings", "PublishPlan", "Status"] and actions[1] == replacement
    assert kinds(rules.on_ejection(back, EJECTION, CONFIG)[1]) == ["Log"]  # not the withdrawn original again
    # the latched record again (the ejection, no drift-stop), settled: the original is not replaced a second time
    back, _ = rules.on_executed(back, executed(0.0, D.dv1_rtn, "picosatellite", "ejection"), 500.0, CONFIG)
    later, actions = rules.on_step(back, t + 3600.0, 510.0, False, CONFIG)
    assert actions == () and later.in_force == replaced.in_force
    # the rule goes on: the replacement missing in turn is replaced, later
    t_new = replaced.in_force.t_stop
    _, actions = rules.on_step(back, t_new + CONFIG.retry_tolerance + 60.0, 510.0, False, CONFIG)
    assert kinds(actions) == ["PublishPlan", "Status"] and actions[0].burns[0].epoch > t_new


def test_a_restarted_planner_after_a_completion_keeps_it(planned):
    state = checked(planned[0])
    commanded = np.array(planned[1][0].burns[0].dv_rtn)
    t_exec = state.in_force.t_stop
    state, _ = rules.on_executed(state, executed(t_exec, 0.8 * commanded), 101.0, CONFIG)
    completed, actions = rules.on_step(state, t_exec + 600.0, 101.0, True, CONFIG)
    back = restart(completed)
    assert rules.on_restart(back, CONFIG)[1][1] == actions[0]
    back, _ = rules.on_executed(back, executed(t_exec, 0.8 * commanded), 500.0, CONFIG)  # on record already
    assert back.executed_stops == completed.executed_stops
    back, _ = rules.on_executed(back, executed(0.0, D.dv1_rtn, "picosatellite", "ejection"), 500.0, CONFIG)
    assert rules.on_step(back, t_exec + 1200.0, 510.0, False, CONFIG)[1] == ()  # not completed twice


def test_a_bad_decision_record_is_refused():
    good = decision_record("planner", 1, 10.0, rules.PlannerState())
    with pytest.raises(ValueError, match="of 'planner', not of 'ic_planner'"):
        read_record(good, "ic_planner")
    for bad in ("{", "[]", good.replace('"version":1', '"version":"1"'), good.replace("10.0", "NaN")):
        with pytest.raises(ValueError):
            read_record(bad, "planner")
    persisted = read_record(good, "planner")[2]
    with pytest.raises(ValueError, match="needs the fields"):
        rules.PlannerState.restored({**persisted, "surprise": 1})
    with pytest.raises(ValueError, match="malformed"):
        rules.PlannerState.restored({**persisted, "in_force": {"k": 3}})


def test_a_run_without_the_keeper_reads_no_decision_record_back():
    """A run without ground_bridge (a campaign's) has no keeper of the decision records: the planners are told not
    to wait for one (recover_timeout 0); with it, they keep their default."""
    from roe_sep import graph

    alone = graph.parameters(None, "bag", {}, graph.graph_nodes(ground_bridge=False))
    assert alone["planner"]["ros__parameters"] == alone["ic_planner"]["ros__parameters"] == {"recover_timeout": 0.0}
    kept = graph.parameters(None, "bag", {}, graph.graph_nodes())
    assert "planner" not in kept and "ic_planner" not in kept
