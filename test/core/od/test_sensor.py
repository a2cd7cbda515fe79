"""The radar sensor's pure parts (roe_sep.core.od.sensor): which epochs a station measures, the noise and the range
bias of a measurement, when a pass is lost, and which records the OD counts."""

import math

import numpy as np
import pytest

from roe_sep.core.config import load_scenario
from roe_sep.core.od.radar import add_noise, chief_from_kepler, chief_position_velocity, deputy_position
from roe_sep.core.od.sensor import (
    RadarRecord,
    TruthSamples,
    chief_between,
    chief_from_samples,
    counted_passes,
    noisy_measurement,
    pass_lost,
    sample_pair,
    trackable,
    truth_between,
)
from roe_sep.core.relmotion.dynamics import propagate, propagate_chief
from roe_sep.core.relmotion.roe import wrap_angle
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


# --- the truth between two samples (truth_between, chief_between, sample_pair) ------------------------------------
KEP0 = np.array([6.878e6, 1e-3, math.radians(97.4), 1.0, 0.3, 2.0 * math.pi - 0.01])  # u wraps past 2 pi below
ROE0 = np.array([1e-6, 8e-4, 5e-5, -3e-5, 2e-5, 6e-5])
RATE = -2e-11  # the truth's drift of da [1/s]


def two_samples(jump_m=40.0):
    """A sample at 0 s and one at 300 s that is off the first's secular arc: the chief 40 m ahead along its orbit
    (and a past 2 pi in u), the ROE off by 1 m of a*dl."""
    kep1 = propagate_chief(KEP0, np.array([300.0]))[0]
    kep1[5] = np.mod(kep1[5] + jump_m / KEP0[0], 2.0 * math.pi)  # u of the two samples 2 pi apart
    roe1 = propagate(ROE0, 300.0, KEP0[0], KEP0[2], True, da_dot=RATE)
    roe1[1] += 1.0 / KEP0[0]
    return (TruthSamples(np.array([0.0]), ROE0[None], KEP0[None]),
            TruthSamples(np.array([300.0]), roe1[None], kep1[None]))


def at(samples, n):
    return TruthSamples(*(np.repeat(x, n, axis=0) for x in samples))


def deputy(roe, kep):
    return deputy_position(roe, kep)


def test_the_truth_between_two_samples_is_exact_at_both_and_continuous():
    before, after = two_samples()
    t = np.array([0.0, 1e-6, 150.0, 300.0 - 1e-6, 300.0])
    roe, kep = truth_between(t, at(after, 5), at(before, 5), np.full(5, RATE))
    np.testing.assert_allclose(roe[0], ROE0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(roe[-1], after.roe[0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(kep[0, :3], KEP0[:3], rtol=1e-15)
    assert abs(wrap_angle((kep[0, 4] + kep[0, 5]) - (KEP0[4] + KEP0[5]))) < 1e-12
    pos = np.array([deputy(r, k) for r, k in zip(roe, kep)])
    # continuous at both ends: a micro-second moves the deputy by its speed times 1e-6 s, not by the 40 m jump
    assert np.linalg.norm(pos[1] - pos[0]) < 0.05 and np.linalg.norm(pos[-1] - pos[-2]) < 0.05
    # half-way, the mean of the two carried states: 20 m from each arc (u wraps past 2 pi in between)
    kep_a = propagate_chief(after.kep[0], np.array([-150.0]))[0]
    c_mid = chief_position_velocity(*chief_from_kepler(kep[2]))[0]
    c_a = chief_position_velocity(*chief_from_kepler(kep_a))[0]
    assert np.linalg.norm(c_mid - c_a) == pytest.approx(20.0, rel=1e-3)


def test_without_an_earlier_sample_the_truth_is_the_later_one_carried_back():
    before, after = two_samples()
    t = np.array([10.0, 150.0, 299.0])
    roe, kep = truth_between(t, at(after, 3), at(after, 3), np.full(3, RATE))
    np.testing.assert_array_equal(roe, propagate(after.roe[0], t - 300.0, KEP0[0], KEP0[2], True, da_dot=RATE))
    np.testing.assert_array_equal(kep, propagate_chief(after.kep[0], t - 300.0))
    np.testing.assert_array_equal(chief_between(t, at(after, 3), at(after, 3)), kep)


def test_the_sample_pair_is_the_later_sample_and_the_one_before_unless_a_burn_parts_them():
    history = [0.0, 300.0, 450.0, 600.0]
    assert sample_pair(history, [], -5.0) == (0, 0)  # no earlier sample
    assert sample_pair(history, [], 0.0) == (0, 0)
    assert sample_pair(history, [], 10.0) == (1, 0)
    assert sample_pair(history, [], 300.0) == (1, 0)
    assert sample_pair(history, [], 301.0) == (2, 1)
    assert sample_pair(history, [], 900.0) == (3, 2)  # after the last: the last, carried
    assert sample_pair(history, [450.0], 400.0) == (2, 2)  # the burn at 450 s: its post-burn sample alone
    assert sample_pair(history, [450.0], 500.0) == (3, 2)  # after it: blended from the post-burn sample on
    assert sample_pair(history, [100.0, 450.0], 200.0) == (1, 1)


def test_the_chief_from_a_history_is_the_pair_blended():
    before, after = two_samples()
    hist_t, hist_kep = [0.0, 300.0], np.vstack([before.kep, after.kep])
    kep, t_after = chief_from_samples(hist_t, hist_kep, [], 120.0)
    np.testing.assert_array_equal(kep, chief_between(np.array([120.0]), after, before)[0])
    assert t_after == 300.0
    kep, _ = chief_from_samples(hist_t, hist_kep, [200.0], 120.0)  # a burn between them: the later sample alone
    np.testing.assert_array_equal(kep, propagate_chief(after.kep[0], np.array([-180.0]))[0])
