"""The radar sensor's pure parts (roe_sep.core.od.sensor): which epochs a station measures, the noise and the range
bias of a measurement, when a pass is lost, and which records the OD counts."""

import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.od.radar import add_noise
from roe_sep.core.od.sensor import RadarRecord, counted_passes, noisy_measurement, pass_lost, trackable
from roe_sep.core.truth.contingency import RadarContingency, resolve

MASK = math.radians(10.0)
SIGMA = np.array([10.0, math.radians(0.01), math.radians(0.01)])


def test_trackable_needs_the_mask_and_the_separation():
    el = np.radians([5.0, 10.0, 10.001, 40.0, 40.0, 80.0])
    sep = np.array([9e3, 9e3, 9e3, 4999.9, 5000.0, 2e4])
    assert trackable(el, sep, MASK, 5000.0).tolist() == [False, False, True, False, True, True]
    assert trackable(el, sep, MASK, 0.0).tolist() == [False, False, True, True, True, True]


def test_noise_is_the_seeded_gaussian_and_the_bias_goes_on_the_range_only():
    z_true = np.array([1.2e6, 2 * math.pi - 1e-7, 0.5])
    plain = noisy_measurement(z_true, SIGMA, np.random.default_rng(7))
    np.testing.assert_array_equal(plain, add_noise(z_true, SIGMA, np.random.default_rng(7)))
    biased = noisy_measurement(z_true, SIGMA, np.random.default_rng(7), range_bias=-75.0)
    assert biased[0] == plain[0] - 75.0 and biased[1:].tolist() == plain[1:].tolist()
    assert 0.0 <= plain[1] < 2 * math.pi  # azimuth wrapped
    rng = np.random.default_rng(1)
    draws = np.array([noisy_measurement(z_true, SIGMA, rng, 30.0) for _ in range(4000)])
    dev = draws - z_true
    dev[:, 1] = np.mod(dev[:, 1] + math.pi, 2 * math.pi) - math.pi
    np.testing.assert_allclose(dev.std(axis=0) / SIGMA, 1.0, atol=0.05)
    np.testing.assert_allclose(dev.mean(axis=0) / SIGMA, [3.0, 0.0, 0.0], atol=0.06)


@pytest.mark.parametrize("count,seen,lost", [(0, 5, True), (0, 40, True), (0, 4, False), (1, 40, False),
                                             (5, 5, False)])
def test_a_pass_in_view_without_a_measurement_is_lost(count, seen, lost):
    assert pass_lost(count, seen, 5) is lost


def test_missed_passes_of_the_contingency_are_lost():
    """radar_pass_missed drops whole passes: each has measurements 0 and, in view long enough, is lost."""
    cont = RadarContingency(resolve(load_scenario(None).contingency, "radar_pass_missed"), 3, ["TIRA"])
    lost = []
    for pass_id in range(1, 6):
        t0 = 1e4 * pass_id
        cont.pass_opened(0, pass_id, t0)
        epochs = t0 + 10.0 * np.arange(30)
        delivered = sum(not cont.dropped(0, pass_id, float(t)) for t in epochs)
        lost.append(pass_lost(delivered, len(epochs), 5))
    assert any(lost) and not all(lost)
    assert lost == [True] * lost.count(True) + [False] * lost.count(False)  # the first passes


def _rec(t, station, pass_id, truth_t=None):
    return RadarRecord(t=t, station=station, pass_id=pass_id, z=np.zeros(3), chief=np.zeros(6), earth=np.eye(3),
                       truth_t=t if truth_t is None else truth_t)


def test_counted_passes_are_closed_complete_and_after_the_burn():
    records = ([_rec(100.0 + 10 * k, 0, 1) for k in range(5)]  # closed, 5: counts before the burn only
               + [_rec(5000.0 + 10 * k, 0, 2) for k in range(5)]  # closed, 5
               + [_rec(6000.0 + 10 * k, 1, 1) for k in range(4)]  # closed, 4: too few
               + [_rec(9000.0 + 10 * k, 0, 3) for k in range(6)]  # open
               + [_rec(7000.0 + 10 * k, 1, -3) for k in range(5)])  # external: never open
    closed = {(0, 1), (0, 2), (1, 1)}
    recs, passes = counted_passes(records, -math.inf, closed, 5)
    assert passes == {(0, 1), (0, 2), (1, -3)} and len(recs) == 15
    assert [r.t for r in recs] == sorted(r.t for r in recs)  # in their order
    recs, passes = counted_passes(records, 1000.0, closed, 5)
    assert passes == {(0, 2), (1, -3)}
    # a measurement simulated from a truth sample older than the burn is not used
    stale = records + [_rec(1200.0, 1, 9, truth_t=900.0)] * 5
    assert (1, 9) not in counted_passes(stale, 1000.0, closed | {(1, 9)}, 5)[1]
