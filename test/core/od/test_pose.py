"""The ejection camera's pose estimates and the ground filter of the executed ejection (seed 001 Sec. 2.3): the
measurement model's numbers, its geometry (camera frame, field of view, shadow), the filter's dynamics against a
numerical J2-J4 truth, and a 1,000-draw campaign of the seed's accuracy claim (0.2 % 1-sigma on |dv|)."""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.stats import chi2

from roe_sep.core.config import load_scenario
from roe_sep.core.constants import R_EARTH
from roe_sep.core.od import pose
from roe_sep.core.od.radar import julian_date, sun_direction, sun_right_ascension
from roe_sep.core.separation.double_impulse import design
from roe_sep.core.truth.nonlinear import apply_impulse, pair_rhs, pair_state, relative_rtn
from roe_sep.core.truth.simulated import PoseFootage, camera_rng, pose_rng

CAM = pose.PoseCamera()
T_RELEASE = 1000.37  # s: the release, between two frames (the grid is whole seconds)
DRAWS = 1000


@pytest.fixture(scope="module")
def ejection():
    """The default scenario's commanded ejection: (a, inc, u1, dv1_rtn)."""
    d = design(load_scenario(None).separation)
    return d.a, d.inc, d.u1, np.asarray(d.dv1_rtn, dtype=float)


def numerical_truth(a, inc, u1, dv, times):
    """The relative positions [m] (osculating carrier RTN) at ``times`` of a picosatellite given ``dv`` at
    T_RELEASE: both spacecraft integrated numerically with J2-J4, no drag (DOP853, rtol 1e-13)."""
    kep = np.array([a, 1.0e-3, inc, 0.3, 0.0, u1])
    s0 = apply_impulse(pair_state(kep, kep), dv, True)
    sol = solve_ivp(pair_rhs, (T_RELEASE, float(times[-1])), s0, method="DOP853", t_eval=times, rtol=1e-13,
                    atol=1e-7, args=([0.0, 0.0, 0.0, 0.0, 1.0], 4))
    assert sol.status == 0
    return relative_rtn(sol.y.T)[0]


def footage(a, inc, u1, dv, span=300.0):
    """The frames (whole seconds after T_RELEASE) in which a pose is taken, and the true positions there."""
    frames = np.arange(math.ceil(T_RELEASE), T_RELEASE + span, CAM.frame_period)
    pos = numerical_truth(a, inc, u1, dv, frames)
    keep = pose.in_view(pos, CAM, pose.camera_axes(dv))
    return frames[keep], pos[keep]


def test_sigma_is_the_seeds_sub_centimetre_near_and_grows_with_range():
    """sigma0 + c p rho laterally, sigma0 + c p rho^2 / size in depth: the numbers the docs quote."""
    s = pose.pose_sigma([0.0, 1.0, 5.0, 10.0, CAM.max_range], CAM)
    assert s[0] == pytest.approx([0.005] * 3)
    p = 2.0 * math.radians(9.15) / 1280
    assert CAM.pixel_angle == pytest.approx(p)
    assert CAM.max_range == pytest.approx(0.1 / (10 * p))  # 40.1 m
    assert s[1, 2] == pytest.approx(0.005 + 0.1 * p / 0.1)
    assert s[2, 2] < 0.0115 and s[3, 2] == pytest.approx(0.005 + 0.1 * p * 100 / 0.1)
    assert s[4, 0] < 0.0061 and s[4, 2] == pytest.approx(0.005 + 0.1 * p * CAM.max_range ** 2 / 0.1)
    assert np.all(np.diff(s[:, 2]) > 0) and np.all(np.diff(s[:, 0]) > 0)


def test_camera_frame_and_field_of_view(ejection):
    axes = pose.camera_axes(ejection[3])
    assert axes.T @ axes == pytest.approx(np.eye(3), abs=1e-15)
    assert np.linalg.det(axes) == pytest.approx(1.0)
    assert axes[:, 2] == pytest.approx(ejection[3] / np.linalg.norm(ejection[3]))
    z, x, y = axes[:, 2], axes[:, 0], axes[:, 1]
    tr, tn = math.tan(CAM.fov_half_r), math.tan(CAM.fov_half_n)
    pts = np.array([10 * z, 10 * (z + 0.99 * tr * x), 10 * (z + 1.01 * tr * x), 10 * (z - 0.99 * tn * y),
                    10 * (z - 1.01 * tn * y), -10 * z, 40.0 * z, 40.2 * z])
    assert pose.in_view(pts, CAM, axes).tolist() == [True, True, False, True, False, False, True, False]
    cov = pose.pose_covariance(10 * z, CAM, axes)  # depth along the boresight, lateral across
    s = pose.pose_sigma(10.0, CAM)
    assert z @ cov @ z == pytest.approx(s[2] ** 2) and x @ cov @ x == pytest.approx(s[0] ** 2)


def test_measured_poses_scatter_as_stated(ejection):
    axes = pose.camera_axes(ejection[3])
    true = np.broadcast_to(20.0 * axes[:, 2] + 1.0 * axes[:, 0], (20000, 3))
    err = (pose.measure_poses(true, CAM, axes, np.random.default_rng(7)) - true) @ axes
    s = pose.pose_sigma(np.linalg.norm(true[0]), CAM)
    assert np.std(err, axis=0) == pytest.approx(s, rel=0.02)  # 20,000 draws: 0.5 % of sigma per axis (4 of them)
    assert np.all(np.abs(np.mean(err, axis=0)) < 4 * s / math.sqrt(20000))


def test_shadow_and_sun():
    jd = julian_date("2016-07-01T00:00:00")
    sun = sun_direction(jd)
    assert np.linalg.norm(sun) == pytest.approx(1.0)
    assert math.atan2(sun[1], sun[0]) == pytest.approx(float(sun_right_ascension(jd)), abs=1e-12)
    assert math.degrees(math.asin(sun[2])) == pytest.approx(23.1, abs=0.1)  # 1 July: declination +23.1 deg
    r = R_EARTH + 515e3
    side = np.cross(sun, [0.0, 0.0, 1.0])
    side /= np.linalg.norm(side)
    assert pose.sunlit(np.array([r * sun, -r * sun, -r * sun + 1.01 * R_EARTH * side, -r * sun + 0.99 * R_EARTH
                                 * side]), sun).tolist() == [True, False, True, False]


def test_response_is_the_house_dynamics_and_matches_a_numerical_truth(ejection):
    a, inc, u1, dv = ejection
    h = 1e-3
    assert (pose.ejection_response(h, a, inc, u1) - pose.ejection_response(-h, a, inc, u1)) / (2 * h) == \
        pytest.approx(np.eye(3), abs=1e-12)
    tau = np.array([1.0, 10.0, 30.0, 120.0])
    model = pose.ejection_response(tau, a, inc, u1) @ dv
    true = numerical_truth(a, inc, u1, dv, T_RELEASE + tau)
    err = np.linalg.norm(model - true, axis=1) / np.linalg.norm(true, axis=1)
    # J2 times n tau (1.1e-3 rad/s): about 1e-6 of the range per second since the release (3.2e-5 at 30 s)
    assert np.all(err < 2e-6 * tau), err


@pytest.mark.parametrize("fraction", [1.0, 0.97])
def test_campaign_reaches_the_seeds_accuracy(ejection, fraction):
    """Seed 001 Sec. 2.3: |dv| to 0.2 % (1 sigma). 1,000 noise draws of the footage of a numerically integrated
    ejection; the filter estimates dv and the release epoch. The spread's 95 % interval (chi-square) lies below
    0.2 %, the covariance is consistent with the spread (NEES) and the estimate is unbiased."""
    a, inc, u1, dv_cmd = ejection
    dv = fraction * dv_cmd
    times, pos = footage(a, inc, u1, dv)
    assert len(times) >= 20 and times[0] > T_RELEASE
    axes = pose.camera_axes(dv_cmd)
    cov = pose.pose_covariance(pos, CAM, axes)
    rng = np.random.default_rng(41)
    z = pose.measure_poses(np.broadcast_to(pos, (DRAWS,) + pos.shape), CAM, axes, rng)
    est = pose.estimate_ejection(times, z, np.broadcast_to(cov, (DRAWS,) + cov.shape),
                                 np.full(DRAWS, times[0] - CAM.frame_period), (a, inc, u1, T_RELEASE))
    mag = np.linalg.norm(dv)
    rel = np.linalg.norm(est.dv, axis=1) / mag - 1.0
    std = rel.std(ddof=1)
    hi = std * math.sqrt((DRAWS - 1) / chi2.ppf(0.025, DRAWS - 1))  # the 95 % interval's upper end
    assert hi < 0.002, (std, hi)
    assert abs(rel.mean()) < 3.0 * std / math.sqrt(DRAWS)
    err = est.dv - dv
    nees = np.einsum("bi,bij,bj->b", err, np.linalg.inv(est.cov), err)
    lo_n, hi_n = chi2.ppf([0.001, 0.999], 3 * DRAWS) / DRAWS
    assert lo_n < nees.mean() < hi_n * 1.1, nees.mean()  # 10 %: the model's second-order residual (< 1 mm)
    u = est.dv / np.linalg.norm(est.dv, axis=1, keepdims=True)
    formal = np.sqrt(np.einsum("bi,bij,bj->b", u, est.cov, u)) / mag
    assert formal.mean() == pytest.approx(std, rel=0.1)
    assert np.abs(est.t0 - T_RELEASE).max() < 5 * est.sigma_t0.max() and est.sigma_t0.max() < 0.01
    assert est.chi2.mean() == pytest.approx(3 * len(times) - 4, rel=0.1)


def test_weak_ejection_is_measured_too(ejection):
    """A weak ejection (f1 = 0.2) stays longer within the pose range: more frames, |dv| within 0.2 % of its own
    magnitude (the interval's upper end), and far from the commanded one."""
    a, inc, u1, dv_cmd = ejection
    dv = 0.2 * dv_cmd
    times, pos = footage(a, inc, u1, dv)
    axes = pose.camera_axes(dv_cmd)
    cov = pose.pose_covariance(pos, CAM, axes)
    z = pose.measure_poses(np.broadcast_to(pos, (DRAWS,) + pos.shape), CAM, axes, np.random.default_rng(3))
    est = pose.estimate_ejection(times, z, np.broadcast_to(cov, (DRAWS,) + cov.shape),
                                 np.full(DRAWS, times[0] - 1.0), (a, inc, u1, T_RELEASE))
    rel = np.linalg.norm(est.dv, axis=1) / np.linalg.norm(dv) - 1.0
    assert rel.std(ddof=1) * math.sqrt((DRAWS - 1) / chi2.ppf(0.025, DRAWS - 1)) < 0.002
    assert np.linalg.norm(est.dv, axis=1).max() < 0.25 * np.linalg.norm(dv_cmd)


def test_one_estimate_unbatched(ejection):
    a, inc, u1, dv = ejection
    times, pos = footage(a, inc, u1, dv)
    cov = pose.pose_covariance(pos, CAM, pose.camera_axes(dv))
    est = pose.estimate_ejection(times, pos, cov, times[0] - 1.0, (a, inc, u1, T_RELEASE))
    assert est.dv.shape == (3,) and est.cov.shape == (3, 3) and est.samples == len(times)
    assert est.dv == pytest.approx(dv, abs=2e-5) and float(est.t0) == pytest.approx(T_RELEASE, abs=1e-4)


class Receding:
    """A truth whose relative position is 1.5 m/s (t - 100.4 s) along the radial axis."""

    @staticmethod
    def rtn_at(t):
        t = np.asarray(t, dtype=float)
        return np.stack([1.5 * (t - 100.4), np.zeros_like(t), np.zeros_like(t)], axis=-1), None


def test_the_simulators_footage_from_the_release_in_view_and_lit():
    """PoseFootage: frames on the whole-second grid after the release, until the picosatellite leaves the pose range
    (40.1 m: 26.7 s at 1.5 m/s), none in the dark, nothing after the window, a stream of its own."""
    got = []

    def keep(e, p, c):
        got.append((list(e), p, c))

    foot = PoseFootage(CAM, 270.0, pose_rng(5), lambda t: np.ones(len(t), dtype=bool), keep)
    foot.observe(Receding, 0.0, 600.0)
    assert got == []  # nothing before the release
    foot.release(100.4, [2.0, 0.0, 0.0])
    foot.release(200.0, [0.0, 1.0, 0.0])  # a second release is ignored
    foot.observe(Receding, 100.0, 110.0)
    foot.observe(Receding, 110.0, 600.0)
    epochs = [e for g in got for e in g[0]]
    assert epochs == [float(k) for k in range(101, 128)]  # 101 ... 127: 1.5 * 26.6 = 39.9 m < 40.1 m
    pos = np.concatenate([g[1] for g in got])
    true = Receding.rtn_at(np.array(epochs))[0]
    sig = pose.pose_sigma(np.linalg.norm(true, axis=1), CAM)[:, 2]
    assert np.all(np.abs(pos[:, 0] - true[:, 0]) < 5 * sig)
    assert np.concatenate([g[2] for g in got]).shape == (27, 3, 3)
    dark = []
    night = PoseFootage(CAM, 270.0, pose_rng(5), lambda t: t > 110.5, lambda e, p, c: dark.extend(e))
    night.release(100.4, [1.0, 0.0, 0.0])
    night.observe(Receding, 100.0, 600.0)
    assert dark == [float(k) for k in range(111, 128)]
    short = []
    none = PoseFootage(CAM, 5.0, pose_rng(5), lambda t: np.ones(len(t), dtype=bool), lambda e, p, c: short.extend(e))
    none.release(100.4, [1.0, 0.0, 0.0])
    none.observe(Receding, 100.0, 600.0)
    assert short == [101.0, 102.0, 103.0, 104.0, 105.0]  # the window: 5 s
    off = PoseFootage(CAM, 0.0, pose_rng(5), lambda t: np.ones(len(t), dtype=bool), lambda e, p, c: short.append(e))
    off.release(100.4, [1.0, 0.0, 0.0])
    off.observe(Receding, 100.0, 600.0)
    assert len(short) == 5  # window 0: a contact without footage
    a, b = pose_rng(5).normal(size=4), pose_rng(5).normal(size=4)
    assert np.array_equal(a, b) and not np.array_equal(a, camera_rng(5).normal(size=4))


def test_the_carrier_is_lit_as_the_sun_says():
    """Over one orbit of the default scenario (LTAN 09:30, 1 July 2016) a third to two-fifths in shadow, in one
    interval (the cylinder); at 90 deg of Sun-orbit-normal angle never in shadow."""
    a, inc = 6893137.0, math.radians(97.45)
    jd = julian_date("2016-07-01T00:00:00")
    t = np.arange(0.0, 5700.0, 10.0)
    lit = pose.carrier_lit([a, 0.0, inc, 1.0986, 0.0, 0.0], t, jd)
    assert 0.3 < 1.0 - lit.mean() < 0.4
    assert np.count_nonzero(np.diff(lit.astype(int))) == 2


def test_a_bad_pose_message_is_refused_and_a_good_one_passes():
    """roe_sep.validate.pose (the planner's lockstep reader drops a refused message with one ERROR line): a stamp, a
    finite position, a symmetric positive-definite position block; the simulator's covariances pass (symmetric to
    the bit, as pose_covariance makes them)."""
    pytest.importorskip("geometry_msgs")
    from geometry_msgs.msg import PoseWithCovarianceStamped

    from roe_sep.errors import BadMessage
    from roe_sep.validate import pose as check

    axes = pose.camera_axes([-1.33, -0.16, 0.44])
    good = pose.pose_covariance(np.array([[1.0, 2.0, 3.0], [-20.0, 3.0, 5.0]]), CAM, axes)

    def msg(cov, position=(1.0, 2.0, 3.0)):
        m = PoseWithCovarianceStamped()
        m.pose.pose.position.x, m.pose.pose.position.y, m.pose.pose.position.z = position
        full = [0.0] * 36
        for i in range(3):
            for j in range(3):
                full[6 * i + j] = float(cov[i][j])
        m.pose.covariance = full
        return m

    for c in good:
        check(msg(c))
    bad = good[0].copy()
    bad[0, 1] += 1e-3 * bad[0, 0]
    for m in (msg(bad), msg(-good[0]), msg(np.zeros((3, 3))), msg(good[0], (math.nan, 0.0, 0.0))):
        with pytest.raises(BadMessage):
            check(m)
