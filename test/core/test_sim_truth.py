"""The simulator's truth timeline and burn execution without ROS (roe_sep.core.truth.simulated / .execution)."""

import math

import numpy as np
import pytest

from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.execution import EJECTION, BurnExecution, relative_impulse
from roe_sep.core.truth.secular import ExecutionErrors, TruthModel, chief_from_u
from roe_sep.core.truth.simulated import ClosestApproach, SimulatedTruth

D = design()
DRIFT_STOP = "/separation/drift_stop_plan"


def timeline(truth_period=60.0):
    out = {"samples": [], "hours": []}
    model = TruthModel(chief_from_u(D.a, D.inc, 0.3, D.u1), 0.0, 0.0)
    truth = SimulatedTruth(model, truth_period, 10.0, 1000.0, lambda e, s: out["samples"].extend(e),
                           lambda: out["hours"].append(truth.t))
    return truth, out


def execution(require_approval=True):
    truth, out = timeline()
    reports = []
    errors = ExecutionErrors(np.random.default_rng(1), 0.0, 0.0, 0.0)
    return BurnExecution(truth, errors, 5.0, require_approval, lambda lvl, text: reports.append((lvl, text))), \
        reports, out


def test_samples_and_hourly_reports_do_not_depend_on_the_step():
    coarse, out_coarse = timeline()
    fine, out_fine = timeline()
    coarse.advance(7300.0)
    for t in np.arange(600.0, 7300.0, 600.0).tolist() + [7300.0]:
        fine.advance(t)
    assert out_coarse == out_fine
    assert out_coarse["samples"] == [60.0 * k for k in range(int(7300 // 60) + 1)]
    assert out_coarse["hours"] == [3600.0, 7200.0]  # each at its own epoch


def test_closest_approach_across_steps_after_the_departure():
    t = np.arange(0.0, 101.0)
    # receding from 200 m, then an approach to 1950 m at t = 60
    dist = np.where(t > 50, 2000.0 - 10.0 * (t - 50) + 0.5 * (t - 50) ** 2, 2000.0 - 1800.0 * np.exp(-t / 5.0))
    ca = ClosestApproach(1000.0)
    for lo in range(0, 100, 10):  # consecutive steps share their ends; the minimum at t = 60 is a step's end
        ca.update(t[lo:lo + 11], dist[lo:lo + 11])
    assert ca.departed and ca.min_dist == (pytest.approx(1950.0), 60.0)
    near = ClosestApproach(1e6)
    near.update(t, dist)
    assert not near.departed and near.min_dist[0] == math.inf


def test_relative_impulse():
    assert relative_impulse([1.0, 2.0, 3.0], "carrier").tolist() == [-1.0, -2.0, -3.0]
    assert relative_impulse([1.0, 2.0, 3.0], "picosatellite").tolist() == [1.0, 2.0, 3.0]
    with pytest.raises(ValueError, match="unknown spacecraft 'tug'"):
        relative_impulse([1.0, 2.0, 3.0], "tug")


def test_ejection_once_with_its_delay_and_bad_events_reported():
    ex, reports, _ = execution()
    ex.eject(100.0, [0.0, 0.0, 0.0], "carrier", "ejection")
    ex.eject(math.nan, [0.0, 0.0, 0.0], "picosatellite", "ejection")
    assert [lvl for lvl, _ in reports] == ["ERROR", "ERROR"] and not ex.pending
    ex.eject(100.0, [1.0, 0.0, 0.0], "picosatellite", "ejection")
    ex.eject(100.0, [1.0, 0.0, 0.0], "picosatellite", "ejection")  # the latched event again: ignored
    assert [(b.epoch, b.source) for b in ex.pending] == [(105.0, EJECTION)]
    assert ex.verdict(ex.pending[0]) is True  # the ejection needs no check
    done = ex.execute(ex.take(ex.pending[0]))
    assert (done.epoch, done.purpose, ex.ejected_at, ex.burns) == (105.0, "ejection", 105.0, 1)
    assert ex.truth.t == 105.0 and ex.truth.model.separated
    ex.eject(200.0, [1.0, 0.0, 0.0], "picosatellite", "ejection")
    assert reports[-1] == ("WARN", "second ejection event ignored: the picosatellite is already released")


def test_plans_replace_pending_burns_never_fly_a_burn_twice_and_wait_for_their_check():
    ex, reports, _ = execution()
    plan = [(1000.0, [0.0, 0.1, 0.0], "carrier", "drift_stop"), (4000.0, [0.0, -0.1, 0.0], "carrier", "trim")]
    assert len(ex.plan(DRIFT_STOP, 10.0, plan, 0.0)) == 2
    assert ex.plan(DRIFT_STOP, 10.0, plan, 0.0) is None  # the plan in force again
    burn = ex.due(2000.0)[0]
    assert ex.verdict(burn) is None  # not checked yet
    ex.check(DRIFT_STOP, 10.0, False)
    assert ex.verdict(burn) is False and "flagged" in reports[-1][1]
    ex.check(DRIFT_STOP, 10.0, True)
    ex.execute(ex.take(burn))
    # a restarted planner re-publishes the plan with a new stamp: the flown burn stays flown
    burns = ex.plan(DRIFT_STOP, 20.0, plan, 0.0)
    assert [b.epoch for b in burns] == [4000.0] and [b.epoch for b in ex.pending] == [4000.0]
    with pytest.raises(ValueError, match="non-finite"):
        ex.plan(DRIFT_STOP, 30.0, [(math.inf, [0.0, 0.1, 0.0], "carrier", "trim")], 0.0)
    with pytest.raises(ValueError, match="unknown spacecraft"):
        ex.plan(DRIFT_STOP, 30.0, [(5000.0, [0.0, 0.1, 0.0], "tug", "trim")], 0.0)
    assert ex.plan_stamps[DRIFT_STOP] == 20.0  # a rejected plan leaves the one in force
    ex.truth.advance(4500.0)
    late = ex.execute(ex.take(ex.due(5000.0)[0]))
    assert late.epoch == 4500.0 and reports[-1] == ("WARN", "trim burn executed late at t = 4500 s (planned 4000 s)")
    assert execution(require_approval=False)[0].needs_check(burn) is False
