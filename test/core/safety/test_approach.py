"""The actual approach from sampled truth (roe_sep.core.safety.approach) against hand-made trajectories whose
closest approach and keep-out time are known in closed form."""

import math

import numpy as np
import pytest

from roe_sep.core.montecarlo.stats import clopper_pearson
from roe_sep.core.safety.approach import (
    CARRIER_BOX,
    COLLISION_RADIUS,
    PICOSAT_BOX,
    actual_approach,
    hard_body_radius,
    hcw_propagate,
)

N = 0.0011  # rad/s, a 500-km orbit's mean motion
T = 2.0 * math.pi / N


def sampled(pos0, vel0, times):
    """An HCW trajectory (exact for the scan's model) sampled at ``times`` from t = 0."""
    times = np.asarray(times, dtype=float)
    pos, vel = hcw_propagate(np.broadcast_to(pos0, (times.size, 3)), np.broadcast_to(vel0, (times.size, 3)), times, N)
    return times, pos, vel


def test_hcw_solves_the_equations_of_motion():
    """x'' = 3 n^2 x + 2 n y', y'' = -2 n x', z'' = -n^2 z, on a finite difference of the solution."""
    r0, v0 = np.array([120.0, -40.0, 30.0]), np.array([0.3, -0.2, 0.1])
    t, h = np.array([0.0, 500.0, 2500.0]), 1e-2
    (p, v), (pp, vp), (pm, vm) = (hcw_propagate(r0, v0, t + d, N) for d in (0.0, h, -h))
    acc = (vp - vm) / (2.0 * h)
    np.testing.assert_allclose((pp - pm) / (2.0 * h), v, atol=1e-7)
    expected = np.stack([3 * N**2 * p[:, 0] + 2 * N * v[:, 1], -2 * N * v[:, 0], -N**2 * p[:, 2]], axis=-1)
    np.testing.assert_allclose(acc, expected, atol=1e-9)


def test_a_normal_oscillation_past_a_fixed_along_track_offset():
    """y = 800 m, z = A sin(n t): |r| = sqrt(800^2 + A^2 sin^2): minima of exactly 800 m at n t = k pi, outside the
    1-km keep-out while |sin| >= 600 / A (A = 1500: 0.4), inside 2 asin(0.4) / n around each minimum. Sampled
    every 60 s."""
    a_z, keep_out = 1500.0, 1000.0
    times = np.arange(0.0, 2.9 * T, 60.0) + 7.0
    t, pos, vel = sampled([0.0, 800.0, 0.0], [0.0, 0.0, a_z * N], times - 7.0)
    t = t + 7.0
    ap = actual_approach(t, pos, vel, N, keep_out, start=7.0)
    alpha = math.asin(math.sqrt(keep_out**2 - 800.0**2) / a_z)
    assert ap.departure_epoch == pytest.approx(7.0 + alpha / N, abs=1e-6)
    minima = ap.minima[ap.minima[:, 0] > ap.departure_epoch]
    np.testing.assert_allclose(minima[:, 1], 800.0, atol=1e-9)
    np.testing.assert_allclose(minima[:, 0], 7.0 + np.arange(1, 6) * math.pi / N, atol=1e-6)
    assert ap.closest_distance == pytest.approx(800.0, abs=1e-9) and not ap.closest_at_end
    assert ap.keep_out_entries == 5 and ap.keep_out_violated
    assert ap.keep_out_s == pytest.approx(5 * 2.0 * alpha / N, abs=1e-5)
    assert ap.refine_error_m < 1e-6 and ap.truth_step_s == 60.0  # the truth is HCW itself: no model error
    # the first minimum lies 24 s from the nearest sample, which misses it by about 1 m: the refinement finds it
    near = np.abs(t - minima[0, 0]) < T / 4
    assert np.min(np.linalg.norm(pos[near], axis=1)) > 800.9


def test_a_burn_at_a_sample_turns_an_approach_into_a_departure():
    """Approaching along-track at 5 m/s, a burn at t = 300 s reverses the relative velocity: the minimum is the
    sample of the burn (a kink, no refinement there), the keep-out entered once and left again."""
    r0, v0 = np.array([0.0, 1800.0, 0.0]), np.array([0.0, -5.0, 0.0])
    t1 = np.arange(0.0, 301.0, 60.0)
    _, p1, w1 = sampled(r0, v0, t1)
    rb, vb = p1[-1], -w1[-1]  # the sample right after the burn: same position, reversed velocity
    t2 = 300.0 + np.arange(0.0, 301.0, 60.0)
    _, p2, w2 = sampled(rb, vb, t2 - 300.0)
    t = np.concatenate([t1, t2])  # 300 s twice: the pre-burn sample then the post-burn one (the last kept)
    pos, vel = np.concatenate([p1, p2]), np.concatenate([w1, w2])
    ap = actual_approach(t, pos, vel, N, 1000.0, start=0.0)
    d_burn = float(np.linalg.norm(rb))
    assert ap.departure_epoch == 0.0 and ap.closest_epoch == 300.0 and not ap.closest_at_end
    assert ap.closest_distance == pytest.approx(d_burn, abs=1e-9) and ap.closest_error_m == 0.0
    assert d_burn < 1000.0 < np.linalg.norm(pos[-1]) and ap.keep_out_entries == 1 and ap.keep_out_violated
    assert 0.0 < ap.keep_out_s < 600.0


def test_never_departed_and_still_approaching_at_the_end():
    """A pair that never leaves the keep-out: violated all along, the closest approach the first local minimum after
    the start; a pair approaching when the truth ends: its closest approach is the end, flagged."""
    t, pos, vel = sampled([0.0, 0.0, 0.0], [0.0, 0.0, 0.2], np.arange(0.0, 1.2 * T, 60.0))  # z = 0.2/n sin(nt)
    ap = actual_approach(t, pos, vel, N, 1000.0, start=0.0)
    assert ap.departure_epoch is None and ap.keep_out_violated and ap.keep_out_s == pytest.approx(t[-1])
    assert ap.closest_epoch == pytest.approx(math.pi / N, abs=1e-6) and ap.closest_distance == pytest.approx(0.0,
                                                                                                           abs=1e-9)
    assert ap.nearest == (ap.closest_distance, ap.closest_epoch, ap.closest_error_m)
    # 100 m below, 3 km behind: drifting towards the carrier at 1.5 n 100 m/s (x constant, y = -3000 + 0.165 t)
    t, pos, vel = sampled([-100.0, -3000.0, 0.0], [0.0, 150.0 * N, 0.0], np.arange(0.0, 1201.0, 60.0))
    ap = actual_approach(t, pos, vel, N, 1000.0, start=0.0)
    assert ap.closest_at_end and ap.closest_epoch == 1200.0 and not ap.keep_out_violated
    assert ap.closest_distance == pytest.approx(math.hypot(100.0, 3000.0 - 150.0 * N * 1200.0), abs=1e-6)
    assert actual_approach(t, pos, vel, N, 1000.0, start=1200.0) is None  # one sample: nothing to scan


def test_the_bound_reports_the_model_error():
    """Truth with an along-track acceleration HCW does not model: the reported bound covers the error of the
    refined closest approach (against the same trajectory sampled every 0.01 s)."""
    acc = 2e-5  # m/s^2 along-track
    fine = np.arange(0.0, 3000.0, 0.01)
    r, v = sampled([0.0, 1500.0, 0.0], [0.0, -1.0, 0.4], fine)[1:]
    r = r + np.stack([np.zeros_like(fine), 0.5 * acc * fine**2, np.zeros_like(fine)], axis=-1)
    v = v + np.stack([np.zeros_like(fine), acc * fine, np.zeros_like(fine)], axis=-1)
    true_min = float(np.min(np.linalg.norm(r, axis=1)))
    every = slice(0, None, 6000)  # 60 s
    ap = actual_approach(fine[every], r[every], v[every], N, 1000.0, start=0.0)
    assert ap.closest_error_m > 0.0 and abs(ap.closest_distance - true_min) <= ap.closest_error_m


def test_collision_radius_from_the_bodies_sizes_and_the_exact_interval():
    assert COLLISION_RADIUS == hard_body_radius(CARRIER_BOX, PICOSAT_BOX)
    assert COLLISION_RADIUS == pytest.approx(0.5 * math.sqrt(1.64) + 0.5 * math.sqrt(0.03))  # 0.727 m
    zero = clopper_pearson(0, 100)
    assert zero["ci95"] == [0.0, pytest.approx(1.0 - 0.025 ** (1 / 100))]  # the exact upper end of 0 of n
    three = clopper_pearson(3, 100)
    assert three["ci95"] == [pytest.approx(0.006229972, abs=1e-8), pytest.approx(0.085176053, abs=1e-8)]
    assert clopper_pearson(5, 5)["ci95"] == [pytest.approx(0.025 ** (1 / 5)), 1.0]
    assert clopper_pearson(0, 0)["p"] is None
    with pytest.raises(ValueError):
        clopper_pearson(3, 2)


def test_an_approach_before_the_departure_is_the_nearest():
    """Released inside the keep-out, the pair first closes in (a minimum at 400 m, before any departure), then a burn
    sends it out for good: the closest approach after the departure is none, the nearest is the 400-m one."""
    t1 = np.arange(0.0, 201.0, 20.0)
    _, p1, w1 = sampled([-300.0, 400.0, 0.0], [3.0, 0.0, 0.0], t1)
    t2 = 200.0 + np.arange(0.0, 1001.0, 20.0)
    _, p2, w2 = sampled(p1[-1], w1[-1] + np.array([3.0, 3.0, 0.0]), t2 - 200.0)
    t = np.concatenate([t1, t2])
    ap = actual_approach(t, np.concatenate([p1, p2]), np.concatenate([w1, w2]), N, 1000.0, start=0.0)
    dense = np.linspace(0.0, 200.0, 200001)
    d = np.linalg.norm(hcw_propagate([-300.0, 400.0, 0.0], [3.0, 0.0, 0.0], dense, N)[0], axis=1)
    assert ap.departure_epoch is not None and ap.departure_epoch > ap.nearest[1]
    assert ap.nearest[0] == pytest.approx(float(d.min()), abs=1e-6)  # the 1-ms grid: within 1e-8 m
    assert ap.nearest[1] == pytest.approx(float(dense[np.argmin(d)]), abs=2e-3)
    assert ap.closest_distance is None or ap.closest_distance > ap.nearest[0]


def test_the_passes_do_not_change_the_result():
    """Any number of grid points per vectorized pass gives the same minima, crossings and bounds."""
    t, pos, vel = sampled([0.0, 800.0, 0.0], [0.0, 0.0, 1500.0 * N], np.arange(0.0, 1.5 * T, 60.0))
    whole = actual_approach(t, pos, vel, N, 1000.0, start=0.0)
    small = actual_approach(t, pos, vel, N, 1000.0, start=0.0, chunk=20)
    assert np.array_equal(whole.minima, small.minima) and whole.keep_out_s == small.keep_out_s
    assert (whole.departure_epoch, whole.keep_out_entries, whole.refine_error_m) == (
        small.departure_epoch, small.keep_out_entries, small.refine_error_m)
