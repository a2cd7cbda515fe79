"""The cheaper forms of the safety monitor's and the radar's computations give the values of the forms they
replaced, to the bit: each test holds the replaced form (its expressions, as they were) and compares bytes.

Why they must agree: an IEEE sum, product, quotient or square root is correctly rounded, so the same operation on
the same operands gives the same bits whether the operands are array elements or floats; a NumPy ufunc gives an
element the same value whatever the array's length, stride or the element's position in it (checked below for the
transcendental functions used); only reductions (sums, norms, einsum) depend on order and length, and those are
kept (the norm's three-term sum is formed in its own order). Two traps, tested: ``x ** 2`` of a NumPy or Python
float is ``pow(x, 2)``, of an array (0-d included) ``x * x``; and ``math``'s acos, atan2, tan and hypot are not
NumPy's.
"""

import numpy as np
import pytest

from roe_sep.core.od import radar
from roe_sep.core.relmotion.dynamics import (
    arg_latitude_rate,
    eccentricity_vector_rotation_rate,
    j2_kappa,
    propagate,
    propagate_chief,
    propagate_elements,
    raan_rate,
    secular_rates,
)
from roe_sep.core.relmotion.orbit import mean_motion, orbital_period
from roe_sep.core.relmotion.roe import components, roe_to_rtn, rtn_position, stack_last
from roe_sep.core.relmotion.trajectory import Burn, Chief, trajectory
from roe_sep.core.safety.metrics import approaching, fov_limit, min_rn_distance, min_rn_distance_one, nearest_crossing
from roe_sep.core.safety.monitor import Assessment, MonitorLimits, assess, in_fov, linspace


def same(x, y):
    """Equal to the bit (NaN and signed zeros included), shapes too."""
    x, y = np.asarray(x), np.asarray(y)
    return x.shape == y.shape and x.dtype == y.dtype and x.tobytes() == y.tobytes()


def old_rtn_position(roe, u):
    r = np.asarray(roe, dtype=float)
    da, dl, dex, dey, dix, diy = np.moveaxis(r, -1, 0)
    s, c = np.sin(u), np.cos(u)
    return np.stack([da - dex * c - dey * s, dl + 2.0 * dex * s - 2.0 * dey * c, dix * s - diy * c], axis=-1)


def old_propagate(roe, dt, a, inc, j2=True, da_dot=0.0):
    r = np.asarray(roe, dtype=float)
    return np.stack(propagate_elements(np.moveaxis(r, -1, 0), dt, a, inc, j2, da_dot=da_dot), axis=-1)


def old_assess(roe0, t0, chief, limits, burns=(), t_end=None, j2=True, da_dot=0.0):
    """monitor.assess as it was: the whole trajectory stacked, roe_to_rtn's position, numpy.linalg.norm, the
    batched nearest_crossing, the array criteria."""
    a = chief.a
    t_end = t0 + limits.window if t_end is None else t_end
    n_samples = max(2, int(limits.samples_per_orbit * (t_end - t0) / orbital_period(a)) + 1)
    times = np.linspace(t0, t_end, n_samples)
    roes = trajectory(roe0, t0, burns, times, chief, j2=j2, da_dot=da_dot)
    pos = old_rtn_position(roes, chief.u_at(times, j2))
    dist = np.linalg.norm(pos, axis=-1) * a
    outside = np.nonzero(dist >= limits.keep_out)[0]
    returning = dist[outside[0]:] if outside.size else dist
    burn_epochs = [b.epoch for b in burns if b.epoch >= t0]
    last_burn = max(burn_epochs, default=t0)
    start = trajectory(roe0, t0, burns, np.array([last_burn]), chief, j2=j2,
                       da_dot=da_dot)[0] if burn_epochs else roes[0]
    crossing, _ = nearest_crossing(start[None], chief.u_at(last_burn, j2), t_end - last_burn, a, chief.inc, j2=j2,
                                   da_dot=da_dot)  # (1, 6): the batched form
    end = roes[-1] * a
    res = Assessment(approaching=bool(approaching(end)), along_track_separation=float(roes[0][1] * a),
                     distance=float(dist[0]), min_distance=float(returning.min()),
                     min_rn_distance=float(min_rn_distance(end)), nearest_crossing=float(crossing[0] * a),
                     evaporated=bool(abs(end[1]) > limits.evaporation), in_fov=bool(in_fov(end, limits)))
    checks = {"keep_out": res.min_distance >= limits.keep_out,
              "passive_safety": res.min_rn_distance >= limits.min_rn_distance
              or res.nearest_crossing >= limits.crossing_min,
              "evaporation": not res.evaporated, "drift_direction": not res.approaching,
              "radar_separability": abs(end[1]) >= limits.a_dl_min, "fov": res.in_fov}
    res.failed = [name for name, ok in checks.items() if not ok]
    return res


def random_case(rng, k):
    a = 6878e3 + rng.uniform(-2e5, 2e5)
    inc = rng.uniform(0.3, 2.0)
    roe = rng.standard_normal(6) * 10 ** rng.uniform(-6, -2.5)
    if k % 23 == 0:
        roe[[0, 2, 3]] = 0.0  # no radial motion
    if k % 31 == 0:
        roe[2:4] = 0.0  # circular: NaN candidates, masked
    t0 = rng.uniform(0.0, 3e5)
    chief = Chief(a, inc, rng.uniform(-4.0, 4.0), t0 - rng.uniform(0.0, 1e4) * (k % 2))
    return roe, t0, chief, bool(k % 3), float(rng.standard_normal() * 1e-10) * (k % 4 != 0)


def test_numpy_elementwise_functions_do_not_depend_on_the_batch_and_math_is_not_numpy():
    rng = np.random.default_rng(11)
    x, y = rng.uniform(-50.0, 50.0, 4099), rng.uniform(-3.0, 3.0, 4099)
    z = rng.uniform(-1.0, 1.0, 4099)
    for f, args in ((np.sin, (x,)), (np.cos, (x,)), (np.tan, (z,)), (np.arccos, (z,)), (np.arctan2, (y, x)),
                    (np.hypot, (y, x)), (np.sqrt, (np.abs(x),))):
        whole = f(*args)
        assert all(same(f(*(a[k] for a in args)), whole[k]) for k in range(0, 4099, 17))  # one at a time
        assert all(same(f(*(a[k:k + n] for a in args)), whole[k:k + n]) for k, n in ((0, 1), (5, 3), (40, 13)))
        assert same(f(*(a[::3] for a in args)), whole[::3])  # strided
    # an array's square (0-d included) is the product (a float's is pow(x, 2), not correctly rounded everywhere:
    # here it differs from x * x for about one value in a thousand over ten decades)
    w = rng.uniform(-1e4, 1e4, 4099) * 10.0 ** rng.uniform(-5, 5, 4099)
    assert same(w ** 2, w * w) and all(same(np.asarray(v) ** 2, v * v) for v in w[:500])


def test_the_norm_of_three_components_is_their_sum_of_squares_in_order():
    rng = np.random.default_rng(12)
    for n in (1, 2, 3, 362, 5000):
        p = rng.standard_normal((n, 3)) * np.array([1e3, 1.0, 1e-3]) * rng.uniform(0.1, 10.0, (n, 1))
        r, t, nn = p[:, 0].copy(), p[:, 1].copy(), p[:, 2].copy()
        assert same(np.linalg.norm(p, axis=-1), np.sqrt(r * r + t * t + nn * nn))
    # the other order differs: the test would see a change of it
    p = rng.standard_normal((5000, 3))
    assert not same(np.linalg.norm(p, axis=-1), np.sqrt(p[:, 0] ** 2 + (p[:, 1] ** 2 + p[:, 2] ** 2)))


def test_components_and_stack_last_are_moveaxis_and_stack():
    rng = np.random.default_rng(13)
    for shape in ((6,), (5, 6), (2, 3, 6), (0, 6)):
        x = rng.standard_normal(shape)
        old = list(np.moveaxis(x, -1, 0))
        new = components(x)
        assert len(new) == len(old) and all(type(p) is type(q) and same(p, q) for p, q in zip(new, old))
        assert same(stack_last(list(new)), np.stack(old, axis=-1)) and stack_last(list(new)).flags.c_contiguous
    assert same(stack_last([np.float64(1.0), np.float64(-0.0)]), np.stack([np.float64(1.0), np.float64(-0.0)], -1))
    assert same(stack_last([1.0, 2.0]), np.array([1.0, 2.0]))  # not arrays: numpy.stack
    with pytest.raises(ValueError):
        stack_last([np.zeros(3), np.zeros(2)])  # numpy.stack's refusal


def test_linspace_is_numpys():
    rng = np.random.default_rng(14)
    for k in range(3000):
        t0 = rng.uniform(-1e6, 1e6) * 10.0 ** rng.integers(-3, 3)
        t1 = t0 + rng.uniform(0.0, 1e5) * (k % 7 != 0)  # some with a zero step
        num = int(rng.integers(2, 6000)) if k % 3 else 2
        assert same(linspace(t0, t1, num), np.linspace(t0, t1, num))
    assert same(linspace(3, 10, 8), np.linspace(3, 10, 8)) and same(linspace(1e-320, 3e-320, 5),
                                                                    np.linspace(1e-320, 3e-320, 5))


def test_the_rates_formed_once_are_those_of_their_functions():
    for a in (6878e3, np.array([6878e3, 7000e3, 6600e3])):
        for inc in (1.7, np.radians(97.459), 0.3) if np.ndim(a) == 0 else (np.array([1.7, 0.3, 1.1]),):
            r = secular_rates(a, inc, True)
            assert same(r.e_rotation, eccentricity_vector_rotation_rate(a, inc))
            kap, n = j2_kappa(a), mean_motion(a)
            p_fac = 3.0 * np.cos(inc) ** 2 - 1.0
            assert same(r.dl_da, -(1.5 * n + 7.0 * kap * p_fac)) and same(r.diy_dix, 2.0 * kap * np.sin(inc) ** 2)
            c2 = np.cos(inc) ** 2
            assert same(arg_latitude_rate(a, inc, True), n + kap * ((3.0 * c2 - 1.0) + (5.0 * c2 - 1.0)))
    rng = np.random.default_rng(15)
    kep = np.column_stack([rng.uniform(6.6e6, 7.2e6, 40), rng.uniform(0, 0.01, 40), rng.uniform(0.1, 3.0, 40),
                           rng.uniform(-4, 4, (40, 3))])
    dt = rng.uniform(-1e4, 1e5, 40)
    for k, d in ((kep, dt), (kep[0], dt[0]), (kep[0], dt), (kep[:, None, :], dt[None, :5])):
        a, inc = k[..., 0], k[..., 2]
        old = np.broadcast_to(k, np.broadcast_shapes(k.shape, np.shape(d) + (6,))).copy()
        old[..., 3] = k[..., 3] + raan_rate(a, inc) * d
        old[..., 4] = k[..., 4] + j2_kappa(a) * (5.0 * np.cos(inc) ** 2 - 1.0) * d
        old[..., 5] = k[..., 5] + (mean_motion(a) + j2_kappa(a) * (3.0 * np.cos(inc) ** 2 - 1.0)) * d
        assert same(propagate_chief(k, d), old)


def test_propagate_and_the_rtn_position_are_the_stacked_forms():
    rng = np.random.default_rng(16)
    roe = rng.standard_normal((50, 6)) * 1e-4
    dt = rng.uniform(0, 1e5, 50)
    a, inc = rng.uniform(6.6e6, 7.2e6, 50), rng.uniform(0.1, 3.0, 50)
    for j2 in (True, False):
        assert same(propagate(roe, dt, a, inc, j2, da_dot=1e-11), old_propagate(roe, dt, a, inc, j2, 1e-11))
        assert same(propagate(roe[0], dt, 6.9e6, 1.7, j2, da_dot=0.0), old_propagate(roe[0], dt, 6.9e6, 1.7, j2, 0.0))
        assert same(propagate(roe[0], 100.0, 6.9e6, 1.7, j2), old_propagate(roe[0], 100.0, 6.9e6, 1.7, j2))
    u = rng.uniform(-5, 5, 50)
    assert same(rtn_position(roe, u), old_rtn_position(roe, u))
    assert same(rtn_position(roe[3], 0.3), old_rtn_position(roe[3], 0.3))
    pos, vel = roe_to_rtn(roe, u)
    r = np.moveaxis(roe, -1, 0)
    s, c = np.sin(u), np.cos(u)
    assert same(vel, np.stack([r[2] * s - r[3] * c, -1.5 * r[0] + 2.0 * r[2] * c + 2.0 * r[3] * s,
                               r[4] * c + r[5] * s], axis=-1))


def test_min_rn_distance_of_one_state_is_the_arrays():
    rng = np.random.default_rng(17)
    ei = rng.standard_normal((5000, 4)) * 10 ** rng.uniform(-3, 3, (5000, 1))
    ei[::50] = 0.0
    ei[1::50, :2] = ei[1::50, 2:]  # parallel
    for row in ei:
        roe = np.concatenate([[0.0, 0.0], row])
        assert same(min_rn_distance_one(*row.tolist()), min_rn_distance(roe))


def test_nearest_crossing_of_one_state_is_the_batched_one():
    rng = np.random.default_rng(18)
    for k in range(1500):
        roe, _, chief, j2, dad = random_case(rng, k)
        u0, dur = rng.uniform(-10.0, 10.0), rng.uniform(0.0, 3e4)
        t_min = None if k % 2 else rng.uniform(0.0, 100.0)
        one = nearest_crossing(roe, u0, dur, chief.a, chief.inc, j2=j2, da_dot=dad, t_min=t_min, iterations=k % 4)
        batch = nearest_crossing(roe[None], u0, dur, chief.a, chief.inc, j2=j2, da_dot=dad, t_min=t_min,
                                 iterations=k % 4)
        assert same(one[0], batch[0][0]) and same(one[1], batch[1][0])


def test_assess_is_the_stacked_trajectory_assessment():
    rng = np.random.default_rng(19)
    limits = MonitorLimits()
    for k in range(600):
        roe, t0, chief, j2, dad = random_case(rng, k)
        burns = [] if k % 5 else [Burn(t0 + rng.uniform(-100.0, 3000.0), tuple(rng.standard_normal(3) * 0.05))
                                  for _ in range(1 + k % 3)]
        t_end = None if k % 7 else t0 + rng.uniform(0.0, 5e4)
        new, old = assess(roe, t0, chief, limits, burns, t_end=t_end, j2=j2,
                          da_dot=dad), old_assess(roe, t0, chief, limits, burns,
                                                                                       t_end, j2, dad)
        assert new.failed == old.failed
        for name in Assessment.__dataclass_fields__:
            assert same(getattr(new, name), getattr(old, name)), name
    with pytest.raises(ValueError, match="must not precede"):
        assess(np.full(6, 1e-4), 100.0, Chief(6.9e6, 1.7, 0.0, 0.0), limits, t_end=50.0)


def test_in_fov_of_one_state_is_the_arrays():
    from roe_sep.core.safety.monitor import _in_fov_one

    rng = np.random.default_rng(20)
    limits = MonitorLimits()
    for _ in range(3000):
        end = rng.standard_normal(6) * np.array([1e2, 1e4, 1e3, 1e3, 1e3, 1e3]) * rng.uniform(0.01, 2.0)
        assert _in_fov_one(end.tolist(), limits) == bool(in_fov(end, limits))
        dl = abs(end[1])
        assert same(fov_limit(dl, limits.fov_half_r), np.tan(limits.fov_half_r) * np.abs(np.asarray(dl)))


def test_the_observation_from_the_shared_relative_position_is_observe():
    rng = np.random.default_rng(21)
    n = 37
    roe = rng.standard_normal((n, 6)) * 1e-3
    kep = np.column_stack([rng.uniform(6.6e6, 7.2e6, n), np.zeros(n), rng.uniform(0.1, 3.0, n),
                           rng.uniform(-4, 4, (n, 3))])
    theta = rng.uniform(0, 2 * np.pi, n)
    u = kep[:, 4] + kep[:, 5]
    site = radar.TIRA

    def old_rtn_matrix(r, v):
        er = r / np.linalg.norm(r, axis=-1, keepdims=True)
        h = np.cross(r, v)
        en = h / np.linalg.norm(h, axis=-1, keepdims=True)
        return np.stack([er, np.cross(en, er), en], axis=-1)

    co, so, ci, si, cu, su = (np.cos(kep[:, 3]), np.sin(kep[:, 3]), np.cos(kep[:, 2]), np.sin(kep[:, 2]), np.cos(u),
                              np.sin(u))
    rc = kep[:, :1] * np.stack([co * cu - so * su * ci, so * cu + co * su * ci, su * si], axis=-1)
    vc = np.sqrt(radar.MU_EARTH / kep[:, 0])[:, None] * np.stack([-co * su - so * cu * ci, -so * su + co * cu * ci,
                                                                   cu * si], axis=-1)
    assert all(same(x, y) for x, y in zip(radar.chief_position_velocity(kep[:, 0], kep[:, 2], kep[:, 3], u),
                                          (rc, vc)))
    assert same(radar.rtn_matrix(rc, vc), old_rtn_matrix(rc, vc))
    c, s = np.cos(theta), np.sin(theta)
    z, one = np.zeros_like(theta), np.ones_like(theta)
    rot = np.stack([np.stack([c, s, z], -1), np.stack([-s, c, z], -1), np.stack([z, z, one], -1)], axis=-2)
    dep = rc + np.einsum("...ij,...j->...i", old_rtn_matrix(rc, vc), old_rtn_position(roe, u) * kep[:, :1])
    r_ef = np.einsum("...ij,...j->...i", rot, dep)
    d = r_ef - site.ecef
    e, nn, up = np.moveaxis(np.einsum("...ij,...j->...i", site.enu, d), -1, 0)
    old = np.stack([np.sqrt(e * e + nn * nn + up * up), np.mod(np.arctan2(e, nn), 2.0 * np.pi),
                    np.arctan2(up, np.hypot(e, nn))], axis=-1)
    rel = rtn_position(roe, u)
    state = radar.deputy_earth_fixed_state(roe, kep, rot, rel)
    assert same(radar.look_angles(state[..., 0, :], site.ecef, site.enu), old)
    assert same(radar.observe(roe, kep, rot, site.ecef, site.enu), radar.two_way_look(state, site.ecef, site.enu))
    assert same(radar.relative_distance(roe, kep[:, 0], None, rel),
                np.linalg.norm(old_rtn_position(roe, u), axis=-1) * kep[:, 0])
