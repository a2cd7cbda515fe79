"""The planner's ground filter of the ejection footage (roe_sep.core.decisions.planner, docs/run.md "The ejection
camera"): the poses kept, the estimate published once the footage is complete, the weak-ejection test on it, the
bearings as the fallback of a contact without footage, and the state's strict-JSON round trip."""

import dataclasses
import json

import numpy as np
import pytest
from test_planner_rules import CONFIG, EJECTION, D, bearings, executed, kinds

from roe_sep.core.decisions import planner as rules
from roe_sep.core.od import pose

FOOTAGE = dataclasses.replace(CONFIG, footage=True, footage_window=270.0)
CAM = pose.PoseCamera()
RELEASE = 0.4  # s after the commanded ejection (t = 0): between two frames


def planned(config):
    state, _ = rules.on_ejection(rules.PlannerState(), EJECTION, config)
    state, _ = rules.on_executed(state, executed(RELEASE, D.dv1_rtn, "picosatellite", "ejection"), 100.0, config)
    return state


def footage(state, f1, config, seed=5, dv=None):
    """The poses of an ejection of ``f1`` (or ``dv`` [m/s] RTN) released at RELEASE (the house's response as the
    truth; the filter's accuracy against a numerical truth: test/core/od/test_pose.py), one per second while in
    view."""
    dv = f1 * np.array(D.dv1_rtn) if dv is None else np.asarray(dv, dtype=float)
    times = np.arange(1.0, 270.0, CAM.frame_period)
    pos = pose.ejection_response(times - RELEASE, D.a, D.inc, EJECTION.u1) @ dv
    axes = pose.camera_axes(D.dv1_rtn)
    keep = pose.in_view(pos, CAM, axes)
    times, pos = times[keep], pos[keep]
    cov = pose.pose_covariance(pos, CAM, axes)
    z = pose.measure_poses(pos, CAM, axes, np.random.default_rng(seed))
    for t, p, c in zip(times, z, cov):
        state, actions = rules.on_pose(state, float(t), p, c.reshape(-1), config)
        assert actions == ()
    return state, dv, times


@pytest.mark.parametrize("f1", [1.0, 0.2])
def test_the_footage_gives_the_executed_ejection(f1):
    state, dv, times = footage(planned(FOOTAGE), f1, FOOTAGE)
    assert len(state.poses) == len(times) > 20
    early, actions = rules.on_step(state, times[0] + 269.0, 101.0, True, FOOTAGE)
    assert early == state and actions == ()  # the footage is not complete yet
    done, actions = rules.on_step(state, times[0] + 270.0, 101.0, True, FOOTAGE)
    assert kinds(actions) == ["PublishEstimate", "Log"]
    est = actions[0]
    cov = np.array(est.cov).reshape(3, 3)
    err = np.array(est.dv) - dv
    assert float(err @ np.linalg.solve(cov, err)) < 16.3  # chi-square(3) at 0.999
    assert np.sqrt(np.diag(cov)).max() < 0.002 * np.linalg.norm(dv)
    assert rules.sec_nanosec(RELEASE - 0.05) < est.stamp < rules.sec_nanosec(RELEASE + 0.05)
    assert done.footage_done and done.poses == () and done.estimate[0] == est.dv and done.estimate[2] == len(times)
    again, actions = rules.on_step(done, times[0] + 900.0, 101.0, True, FOOTAGE)
    assert again == done and actions == ()  # once
    late, _ = rules.on_pose(done, times[-1] + 1.0, (1.0, 2.0, 3.0), np.eye(3).reshape(-1), FOOTAGE)
    assert late == done


def test_the_footage_decides_the_hold_without_a_bearing():
    state, _, times = footage(planned(FOOTAGE), 0.2, FOOTAGE)
    state, _ = rules.on_step(state, times[0] + 270.0, 101.0, True, FOOTAGE)
    t = state.in_force.t_stop - FOOTAGE.hold_lead
    held, actions = rules.on_step(state, t, 101.0, True, FOOTAGE)
    assert kinds(actions) == ["StopBearings", "Log", "PublishPlan", "Status"]
    values = dict(actions[3].values)
    assert values["contingency"] == "weak_ejection" and values["source"] == "footage"
    assert float(values["f1"]) == pytest.approx(0.2, abs=0.002) and held.in_force is None


def test_a_nominal_footage_flies_the_drift_stop():
    state, _, times = footage(planned(FOOTAGE), 0.8, FOOTAGE)
    state, _ = rules.on_step(state, times[0] + 270.0, 101.0, True, FOOTAGE)
    flies, actions = rules.on_step(state, state.in_force.t_stop - FOOTAGE.hold_lead, 101.0, True, FOOTAGE)
    assert kinds(actions) == ["StopBearings", "Log"] and actions[1].text.endswith("drift-stop flies")
    assert "footage check" in actions[1].text and flies.in_force == state.in_force


def test_without_footage_the_bearings_decide():
    """A contact without footage (no pose) or the filter switched off: the bearings-only test, as before."""
    for config, with_poses in ((FOOTAGE, False), (CONFIG, True)):
        state = planned(config)
        if with_poses:
            state, _, _ = footage(state, 0.3, config)
            assert state.poses == ()  # footage off: ignored
        state = bearings(state, 0.3)
        t = state.in_force.t_stop - config.hold_lead
        held, actions = rules.on_step(state, t, 101.0, True, config)
        assert kinds(actions) == ["StopBearings", "Log", "PublishPlan", "Status"]
        assert "source" not in dict(actions[3].values) and held.estimate is None


def test_the_footage_state_round_trips_through_strict_json():
    state, _, times = footage(planned(FOOTAGE), 0.2, FOOTAGE)
    for s in (state, rules.on_step(state, times[0] + 270.0, 101.0, True, FOOTAGE)[0]):
        restored = rules.PlannerState.from_dict(json.loads(json.dumps(s.to_dict(), allow_nan=False)))
        assert restored == s
        t = s.in_force.t_stop - FOOTAGE.hold_lead
        assert rules.on_step(restored, t, 101.0, True, FOOTAGE) == rules.on_step(s, t, 101.0, True, FOOTAGE)


def test_a_degenerate_footage_gives_no_estimate_and_the_bearings_decide():
    """Poses that cannot fix the ejection (all at one place: a singular least squares) or a single pose: a log line,
    no estimate, the footage done; the bearings' test decides later."""
    state = planned(FOOTAGE)
    for t in (1.0, 2.0, 3.0):
        state, _ = rules.on_pose(state, t, (0.0, 0.0, 0.0), (1e-4, 0, 0, 0, 1e-4, 0, 0, 0, 1e-4), FOOTAGE)
    done, actions = rules.on_step(state, 300.0, 101.0, True, FOOTAGE)
    assert kinds(actions) == ["Log"] and done.footage_done and done.estimate is None and done.poses == ()
    one, _ = rules.on_pose(planned(FOOTAGE), 1.0, (1.0, 0.0, 0.0), np.eye(3).reshape(-1) * 1e-4, FOOTAGE)
    done, actions = rules.on_step(one, 300.0, 101.0, True, FOOTAGE)
    assert kinds(actions) == ["Log"] and "1 pose(s)" in actions[0].text and done.estimate is None


def test_footage_complete_at_the_decision_step_keeps_both_actions():
    """A footage window that ends at the hold decision's step: the estimate and the decision on it, in that order."""
    state = planned(FOOTAGE)
    t = state.in_force.t_stop - FOOTAGE.hold_lead
    late = dataclasses.replace(FOOTAGE, footage_window=t - 1.0)
    state, _, times = footage(state, 0.2, late)
    assert times[0] == 1.0
    held, actions = rules.on_step(state, t, 101.0, True, late)
    assert kinds(actions) == ["PublishEstimate", "Log", "StopBearings", "Log", "PublishPlan", "Status"]
    assert dict(actions[5].values)["source"] == "footage" and held.in_force is None
