"""The ic_planner's decisions without DDS (roe_sep.core.decisions.ic_planner, docs/run.md "Decisions"): each rule
as an event sequence with its actions and state -- re-plan, deferral by a committed burn, refusal of worse knowledge,
the final OD's trim (once), a departing burn's re-plan, a bad estimate, a restart from the latched plan -- and the
state's strict-JSON round trip."""

import dataclasses
import json
import math

import numpy as np
import pytest

from roe_sep.core.acquisition.planner import AcquisitionConfig
from roe_sep.core.decisions import ic_planner as rules
from roe_sep.core.decisions.common import ERROR, OK, WARN, PlannedBurn, Status, decision_record, read_record
from roe_sep.core.od.radar import DEFAULT_EPOCH_UTC, julian_date
from roe_sep.core.relmotion.dynamics import drag_da_dot
from roe_sep.core.separation.double_impulse import design

D = design()
A, INC = D.a, D.inc
DA_DOT = float(drag_da_dot(0.0151, 1e-12, A))  # 1/s: a da_dot about -68 m/day
MARGIN = 11400.0
CONFIG = rules.IcPlannerConfig(AcquisitionConfig(planning_margin=MARGIN), trim=False, burn_sigma=0.05,
                               final_od_arc=0.0, replan_on_burn=True, ei_margin_sigmas=0.0, ic_drift_tolerance=5.0,
                               jd0=julian_date(DEFAULT_EPOCH_UTC))
TRIM = dataclasses.replace(CONFIG, trim=True)
ROE = (-180.0, 25000.0, -30.0, -540.0, 10.0, 400.0)  # m, post-drift-stop: leading, drifting away


def od(epoch, delay=100.0, roe=ROE, sigma=1.0, a=A):
    """An OD solution of ``roe`` [m] at ``epoch`` [s], made ``delay`` later, a*ROE 1-sigma ``sigma`` [m]."""
    return rules.OdSolution(epoch + delay, epoch, (a, 0.0, INC, 1.0, 0.0, 1.0), 1.0, tuple(x / A for x in roe),
                            tuple(np.diag([sigma ** 2] * 6).ravel()), a_da_dot=DA_DOT * A, a_da_dot_sigma=1e-5)


def kinds(actions):
    return [type(a).__name__ for a in actions]


def statuses(actions, level=None):
    return [a for a in actions if isinstance(a, Status) and (level is None or a.level == level)]


@pytest.fixture(scope="module")
def first():
    """The first plan: the OD at t = 30000 s, decided at its solution time."""
    return rules.on_od(rules.IcPlannerState(), od(30000.0), 30100.0, CONFIG)


def test_the_first_od_plans_the_acquisition_and_fixes_the_ic_epoch(first):
    state, actions = first
    assert kinds(actions) == ["PublishPlan", "Log", "Status"]
    plan = actions[0]
    assert plan.stamp == 30100.0 and plan.burns and plan.t_final == state.t_final
    assert all(b.spacecraft == "carrier" and b.purpose == "ic_acquisition" for b in plan.burns)
    assert plan.burns[0].epoch >= 30100.0 + MARGIN  # first burn at or after now + planning_margin
    assert state.t_final <= 30000.0 + CONFIG.cfg.window  # the last grid epoch within OD epoch + window
    assert state.plan_in_force == plan.burns and state.burn_epochs == pytest.approx([b.epoch for b in plan.burns])
    assert state.plans == 1 and state.last_key == (30100.0, 30000.0) and state.last_od == od(30000.0)
    assert actions[2] == Status(OK, "acquisition plan published", tuple(rules.values(state).items()))
    assert dict(state.summary)["n_burns"] == len(plan.burns)


def test_an_od_not_newer_is_ignored(first):
    state, _ = first
    again, actions = rules.on_od(state, od(30000.0), 30100.0, CONFIG)
    assert again == state and kinds(actions) == ["Log"] and actions[0].level == "debug"
    older, actions = rules.on_od(state, od(29000.0, delay=1000.0), 30100.0, CONFIG)  # same stamp, older epoch
    assert older == state and kinds(actions) == ["Log"]


def test_an_od_during_the_separation_plan_is_not_used():
    state, _ = rules.on_separation_plan(rules.IcPlannerState(), [9000.0, 31000.0], CONFIG)
    assert state.separation_end == 31000.0
    after, actions = rules.on_od(state, od(30000.0), 30100.0, CONFIG)
    assert kinds(actions) == ["Status"] and "the separation plan flies until t = 31000.0 s" in actions[0].message
    assert after.last_od is None and after.plans == 0 and after.last_key == (30100.0, 30000.0)


def test_a_newer_od_replans_towards_the_same_ic_epoch(first):
    state, _ = first
    new, actions = rules.on_od(state, od(30050.0, delay=100.0), 30150.0, CONFIG)
    assert kinds(actions) == ["PublishPlan", "Log", "Status"]
    assert new.t_final == state.t_final and new.plans == 2  # the plan's own grid ends at or before it
    assert state.t_final - 2.0 * math.pi / D.n / CONFIG.cfg.grid_per_orbit < actions[0].t_final <= state.t_final
    assert new.plan_in_force == actions[0].burns and new.last_od.epoch == 30050.0


def test_a_committed_burn_defers_the_replan(first):
    state, _ = first
    now = state.burn_epochs[0] - 0.5 * MARGIN  # the plan's first burn is due within planning_margin
    new, actions = rules.on_od(state, od(now - 100.0), now, CONFIG)
    assert kinds(actions) == ["Status"] and actions[0].level == WARN and actions[0].log == "warning"
    assert f"the burn at t = {state.burn_epochs[0]:.1f} s of the plan in force is committed" in actions[0].message
    assert new.plan_in_force == state.plan_in_force and new.plans == 1 and new.last_od.epoch == now - 100.0


def test_an_od_that_knows_the_drift_worse_is_refused(first):
    state = dataclasses.replace(first[0], plan_sigma=1.0, plan_od_epoch=30000.0)
    new, actions = rules.on_od(state, od(30050.0, sigma=50.0), 30150.0, TRIM)
    assert kinds(actions) == ["Status"] and actions[0].level == OK
    assert "its a da at the IC epoch is known to 50.03 m (1-sigma), the plan in force's to 1.00 m" in actions[0].message
    assert new.plan_in_force == state.plan_in_force and new.plans == 1


def burn_as_flown(planned: PlannedBurn, extra_dv_t=0.0):
    return dataclasses.replace(planned, dv_rtn=(planned.dv_rtn[0], planned.dv_rtn[1] + extra_dv_t, planned.dv_rtn[2]))


def test_a_burn_flown_as_planned_changes_no_plan(first):
    state, _ = first
    new, actions = rules.on_executed(state, burn_as_flown(state.plan_in_force[0]), CONFIG)
    assert actions == () and len(new.executed) == 1 and new.executed[0].epoch == state.plan_in_force[0].epoch
    assert new.executed[0].dv_rel == pytest.approx([-c for c in state.plan_in_force[0].dv_rtn])  # the carrier's
    picosat, actions = rules.on_executed(state, dataclasses.replace(state.plan_in_force[0], spacecraft="picosatellite"),
                                         CONFIG)
    assert picosat == state and actions == ()


def test_a_departing_burn_replans_once_the_committed_burn_is_flown(first):
    """Burn 1 departs by 4 quanta (7 m of a da): its re-plan is deferred by burn 2, due within the margin; burn 2's
    record re-plans from the same OD with both burns."""
    state, _ = first
    b1, b2 = state.plan_in_force[:2]
    assert b2.epoch < b1.epoch + MARGIN
    deferred, actions = rules.on_executed(state, burn_as_flown(b1, 0.004), CONFIG)
    assert kinds(actions) == ["Status", "Status"] and [a.level for a in actions] == [OK, WARN]
    assert "departed from its plan by 7.25 m of a da: re-plan from the OD at t = 30000.0 s" in actions[0].message
    assert deferred.replan_pending and deferred.plans == 1
    replanned, actions = rules.on_executed(deferred, burn_as_flown(b2), CONFIG)
    assert kinds(actions) == ["Status", "PublishPlan", "Log", "Status"]
    assert "the committed burn that deferred an earlier departure's re-plan" in actions[0].message
    plan = actions[1]
    assert plan.stamp == pytest.approx(b2.epoch) and plan.burns[0].epoch >= b2.epoch + MARGIN
    assert replanned.t_final == state.t_final and not replanned.replan_pending and replanned.plans == 2
    off_plan, actions = rules.on_executed(state, burn_as_flown(b1, 0.004), dataclasses.replace(
        CONFIG, replan_on_burn=False))
    assert actions == () and len(off_plan.executed) == 1  # without replan_on_burn only the record grows
    # the same record again (a restarted ic_planner's latched history) is on record already: nothing is decided
    assert rules.on_executed(replanned, burn_as_flown(b1, 0.004), CONFIG) == (replanned, ())


def final_state(a_da_at_tf, t_final=250000.0):
    """An acquisition whose last burn is flown: the IC epoch ``t_final``, an OD 12000 s before it whose a da
    reaches ``a_da_at_tf`` [m] there."""
    t_od = t_final - 12000.0
    roe = (a_da_at_tf - DA_DOT * A * (t_final - t_od), 7400.0, 10.0, -260.0, 10.0, 360.0)
    state = rules.IcPlannerState(t_final=t_final, burn_epochs=(), plan_in_force=(), plans=1)
    return state, od(t_od, roe=roe, sigma=0.3)


def test_the_final_od_trims_the_drift_once():
    state, final = final_state(12.0)
    now = final.stamp
    trimmed, actions = rules.on_od(state, final, now, TRIM)
    assert kinds(actions) == ["PublishPlan", "Status"] and actions[1].level == OK
    plan = actions[0]
    (trim,) = plan.burns
    assert trim.dv_rtn[0] == trim.dv_rtn[2] == 0.0 and trim.dv_rtn[1] > 0.0  # tangential, raises a da (carrier)
    assert trim.epoch >= now + MARGIN and trimmed.t_final == plan.t_final
    assert trimmed.final_decided and trimmed.plans == 2 and dict(trimmed.summary)["final_trim"] is True
    assert actions[1].message.startswith("final OD at t = 238000.0 s: predicted a da at the IC epoch +12.00 m")
    later, actions = rules.on_od(trimmed, od(final.epoch + 600.0, roe=ROE), now + 600.0, TRIM)
    assert actions == () and later.plan_in_force == trimmed.plan_in_force  # later solutions are not used


def test_a_final_od_inside_the_tolerance_does_not_trim():
    state, final = final_state(0.5)
    decided, actions = rules.on_od(state, final, final.stamp, TRIM)
    assert kinds(actions) == ["Status"] and actions[0].message.endswith("no trim")
    assert decided.final_decided and decided.plans == 1 and dict(decided.summary)["final_trim"] is False


def test_a_final_od_waits_for_the_record_of_a_burn_flown_after_it():
    state, final = final_state(12.0)
    state = dataclasses.replace(state, burn_epochs=(final.epoch + 50.0,))  # flown, its record not yet here
    waiting, actions = rules.on_od(state, final, final.stamp, TRIM)
    assert actions == () and not waiting.final_decided


def test_a_bad_estimate_is_an_error_and_changes_no_plan(first):
    state, actions = rules.on_od(rules.IcPlannerState(), od(30000.0, a=1000.0), 30100.0, CONFIG)
    assert kinds(actions) == ["Status"] and actions[0].level == ERROR and actions[0].log == "error"
    assert actions[0].message.startswith("OD estimate rejected: chief semi-major axis 1000.0 m")
    assert state.plans == 0 and state.plan_in_force is None and state.t_final is None


def test_a_restarted_planner_continues_from_its_latched_plan(first):
    plan = first[1][0]
    state, actions = rules.on_own_plan(rules.IcPlannerState(), plan.burns, plan.t_final, CONFIG)
    assert actions == () and state.t_final == plan.t_final and state.plan_in_force == plan.burns
    again, _ = rules.on_own_plan(state, plan.burns[:1], plan.t_final + 1.0, CONFIG)
    assert again == state  # the IC epoch of the acquisition in progress stays
    assert rules.on_own_plan(rules.IcPlannerState(), (), 1.0, CONFIG)[0] == rules.IcPlannerState()


def test_the_state_round_trips_through_strict_json_and_decides_the_same(first):
    state, _ = first
    state, _ = rules.on_executed(state, burn_as_flown(state.plan_in_force[0], 0.004), CONFIG)
    text = json.dumps(state.to_dict(), allow_nan=False)
    restored = rules.IcPlannerState.from_dict(json.loads(text))
    assert restored == state and restored.replan_pending
    b2 = burn_as_flown(state.plan_in_force[1])
    assert rules.on_executed(restored, b2, CONFIG)[1][:2] == rules.on_executed(state, b2, CONFIG)[1][:2]
    trimmed, _ = rules.on_od(*final_state(12.0), 238100.0, TRIM)
    assert rules.IcPlannerState.from_dict(json.loads(json.dumps(trimmed.to_dict(), allow_nan=False))) == trimmed
    with pytest.raises(ValueError, match="not finite"):
        dataclasses.replace(state, t_final=math.inf).to_dict()



def test_an_ic_planner_restarted_mid_acquisition_keeps_its_plan(first):
    """Killed after the first burn of its plan: the decision record brings back the plan in force, the latched OD
    and executed record then come again and change nothing (a fresh ic_planner would re-plan from that OD)."""
    state, actions = first
    b1 = state.plan_in_force[0]
    state, _ = rules.on_executed(state, burn_as_flown(b1), CONFIG)
    back = rules.IcPlannerState.restored(read_record(decision_record("ic_planner", 2, b1.epoch, state),
                                                     "ic_planner")[2])
    assert back == state
    _, restart = rules.on_restart(back, CONFIG)
    assert kinds(restart) == ["PublishPlan", "Status"] and restart[0] == actions[0]
    now = b1.epoch + 60.0
    again, replies = rules.on_od(back, od(30000.0), now, CONFIG)
    assert again == back and kinds(replies) == ["Log"]  # not newer
    assert rules.on_executed(back, burn_as_flown(b1), CONFIG) == (back, ())  # on record already
    _, fresh = rules.on_od(rules.IcPlannerState(), od(30000.0), now, CONFIG)
    assert fresh[0].burns != actions[0].burns  # what a restart without the record would have published
    _, empty = rules.on_restart(rules.IcPlannerState(), CONFIG)
    assert kinds(empty) == ["Status"]
