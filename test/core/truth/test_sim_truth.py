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
                           on_hour=lambda: out["hours"].append(truth.t))
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


class PerStep:
    """A model without its ``integrated_to``: SimulatedTruth evaluates its samples step by step."""

    def __init__(self, model):
        self.model = model

    def __getattr__(self, name):
        if name == "integrated_to":
            raise AttributeError(name)
        return getattr(self.model, name)


STEPS = {600.0: np.arange(600.0, 11000.0, 600.0).tolist(), 250.0: np.arange(250.0, 11000.0, 250.0).tolist()}


@pytest.mark.parametrize("step", [600.0, 250.0])
def test_nonlinear_samples_evaluated_ahead_are_each_steps_to_the_bit(step):
    """With a NonlinearTruth the samples up to the end of the integrated span are evaluated in one pass and the
    steps take theirs from it; a burn drops those after it. Every sample (epochs, elements, ROE, RTN) is the
    per-step evaluation's to the bit: across hour ends, a burn between truth epochs, one on a truth epoch and on the
    hour (whose sample before the burn is published, then the one after it, as the simulator does)."""
    from roe_sep.core.truth.nonlinear import Atmosphere, NonlinearTruth

    chief0 = chief_from_u(D.a, D.inc, 0.3, D.u1)
    burns = [(1234.5678, [-1.33, -0.16, 0.44], "picosatellite"), (5000.25, [0.01, -0.02, 0.0], "carrier"),
             (7200.0, [0.0, 0.03, 0.01], "carrier"), (9060.0, [0.0, -0.01, 0.0], "picosatellite")]

    def run(ahead):
        model = NonlinearTruth(chief0, 0.0, 0.0079, 0.0230, Atmosphere.normalised(1e-12, chief0))
        out = []
        truth = SimulatedTruth(model if ahead else PerStep(model), 60.0, 10.0, 1000.0,
                               lambda e, s: out.append((list(e), [np.asarray(a).tobytes() for a in
                                                                   (s[0], s[1], *s[2])])), on_hour=lambda: None)
        pending = list(burns)
        for t_to in STEPS[step]:
            while pending and pending[0][0] <= t_to:  # as BurnExecution.execute and the sim node
                epoch, dv, spacecraft = pending.pop(0)
                truth.advance(epoch)
                model.apply(epoch, relative_impulse(dv, spacecraft), spacecraft)
                truth.publish([epoch])
            truth.advance(t_to)
        return out, truth.closest.min_dist

    ahead, per_step = run(True), run(False)
    assert ahead == per_step
    samples = ahead[0]
    assert sum(len(e) for e, _ in samples) == int(STEPS[step][-1] // 60.0) + 1 + len(burns)
    epochs = [t for e, _ in samples for t in e]
    assert epochs.count(7200.0) == epochs.count(9060.0) == 2  # before and after the burn on it


def test_nonlinear_distances_from_the_pass_ahead_are_each_windows():
    """NonlinearTruth.distances evaluates |r| on its grid up to the end of the integrated span and the next windows
    on that grid take theirs from it: every window's times and distances are its own evaluation's to the bit, also
    for windows off the grid (after a burn, ending on one) and after a burn (which drops the pass)."""
    from roe_sep.core.truth.nonlinear import Atmosphere, NonlinearTruth, relative_rtn

    chief0 = chief_from_u(D.a, D.inc, 0.3, D.u1)
    model = NonlinearTruth(chief0, 0.0, 0.0079, 0.0230, Atmosphere.normalised(1e-12, chief0))
    model.apply(100.3, relative_impulse([-1.33, -0.16, 0.44], "picosatellite"))
    ends = [700.0, 1300.0, 1900.0, 3600.0, 4200.0, 4800.0, 5400.0, 5650.25, 6200.0, 6800.0, 7300.0]
    t, hits = 100.3, 0
    for t_to in ends:
        passes = model._distances
        times, dist = model.distances(t, t_to, 10.0)
        hits += model._distances is passes
        assert times.tolist() == np.append(np.arange(t, t_to, 10.0), t_to).tolist()
        assert dist.tobytes() == np.linalg.norm(relative_rtn(model.states(times))[0], axis=-1).tobytes()
        if t_to in (4800.0, 5650.25):  # a burn on the pass's grid, one off it
            model.apply(t_to, relative_impulse([0.0, 0.05, 0.0], "carrier"), "carrier")
        t = t_to
    assert hits == 3  # to 1900 and 3600 (the pass from 700) and 4800 (from 3600); not 5400 after the burn
