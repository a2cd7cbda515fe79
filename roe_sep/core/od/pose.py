"""The ejection footage on the ground, without ROS: the carrier camera's 3D pose estimates of the picosatellite and
the filter that estimates the executed ejection delta-v from them (seed 001 Sec. 2.1 req. 3: the ejection is filmed
during a ground contact and the footage downlinked; Sec. 2.3: 3D pose "at the (sub-)centimeter level", the
deployment's velocity increment "accurate to 0.2%"). Derivation, defaults and measured accuracy: docs/run.md,
"The ejection camera".

The measurement (:func:`pose_sigma`, :func:`measure_poses`): a model-fitting pose estimator locates the silhouette
of the object (size ``size``) to ``c`` pixels of angle ``p``, per axis of the camera frame (z the boresight, the
ejection direction by seed 001 Sec. 5):

    lateral:  sigma_xy(rho) = sigma0 + c p rho             (the centroid, c p rad seen at the range rho)
    depth:    sigma_z(rho)  = sigma0 + c p rho^2 / size    (the range from the apparent size size / rho)

With the defaults the depth sigma is 0.52 cm at 1 m, 1.1 cm at 5 m, 3.0 cm at 10 m and 40 cm at the pose range limit
size / (min_pixels p) = 40 m. A pose is taken every ``frame_period`` on the sim-time grid while the picosatellite is
in the field of view, within that range and lit (:func:`in_view`, :func:`sunlit`).

The filter (:func:`estimate_ejection`): r(t) = Phi(t - t0) dv with Phi the house's linear relative motion
(:func:`ejection_response`: seed 002 Eq. 2, the secular J2 propagation, the ROE-to-RTN map), normalised so that
the velocity right after the impulse is dv exactly. Weighted batch least squares (Gauss-Newton in dv and the
unknown release epoch t0, every draw of a campaign in one vectorised pass) gives dv and its covariance. Over the
footage (< 3 min) the differential drag moves the picosatellite by < 1 um: left out.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..constants import R_EARTH, SECONDS_PER_DAY
from ..relmotion.dynamics import arg_latitude_rate, propagate, propagate_chief
from ..relmotion.maneuvers import control_matrix
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import rtn_position
from .radar import chief_position_velocity, sun_direction

POSE_SIGMA0 = 0.005
"""m, the pose error's floor at zero range (calibration, mounting): seed 001 Sec. 2.3's "sub-centimeter"."""
POSE_PIXELS = 1280.0
"""pixels of the ejection camera across its normal field of view (an assumption: a 1.3-Mpixel 1280 x 1024 sensor,
the class of RGB camera a microsatellite flies; no seed gives it)."""
POSE_CENTROID_PX = 0.1
"""pixels, 1-sigma of the model fit's silhouette edge (sub-pixel model fitting; an assumption)."""
POSE_SIZE = 0.1
"""m, the picosatellite's size (BEESAT-4: a 1U CubeSat, seed 001 Sec. 1)."""
POSE_MIN_PIXELS = 10.0
"""pixels the picosatellite must span for a pose (an assumption): the pose range limit."""
FRAME_PERIOD = 1.0
"""s between frames of the footage that are processed (an assumption: 1 Hz of the video)."""
FOOTAGE_WINDOW = 270.0
"""s of footage after the release: half the 9-min ejection contact of seed 001 Sec. 5 (the ejection mid-contact);
the nominal ejection leaves the pose range after 28 s, f1 = 0.1 after 270 s."""
FOV_HALF_R_DEG = 6.8
"""deg, the camera's half field of view about the radial-like axis (seed 001 Sec. 2.2, config/default.yaml)."""
FOV_HALF_N_DEG = 9.15
"""deg, the camera's half field of view about the other axis (seed 001 Sec. 2.2, config/default.yaml)."""
UNKNOWN = -1.0
"""Variance marking a block of a covariance as not estimated (the sensor_msgs/Imu convention)."""


@dataclass(frozen=True)
class PoseCamera:
    """The ejection camera and its pose estimation (module docstring): ``sigma0`` [m], ``pixels`` across the normal
    field of view, ``centroid_px`` [pixel], the object ``size`` [m], ``min_pixels``, ``frame_period`` [s] and the
    half fields of view ``fov_half_r``, ``fov_half_n`` [rad]."""

    sigma0: float = POSE_SIGMA0
    pixels: float = POSE_PIXELS
    centroid_px: float = POSE_CENTROID_PX
    size: float = POSE_SIZE
    min_pixels: float = POSE_MIN_PIXELS
    frame_period: float = FRAME_PERIOD
    fov_half_r: float = math.radians(FOV_HALF_R_DEG)
    fov_half_n: float = math.radians(FOV_HALF_N_DEG)

    @property
    def pixel_angle(self) -> float:
        """rad, one pixel: 2 ``fov_half_n`` / ``pixels``."""
        return 2.0 * self.fov_half_n / self.pixels

    @property
    def max_range(self) -> float:
        """m, the pose range limit: ``size`` / (``min_pixels`` ``pixel_angle``)."""
        return self.size / (self.min_pixels * self.pixel_angle)


@dataclass(frozen=True)
class EjectionEstimate:
    """The filter's result (per draw when batched): ``dv`` (..., 3) [m/s] RTN, its covariance ``cov`` (..., 3, 3)
    [m^2/s^2] (t0 estimated alongside), the release epoch ``t0`` [s] and its ``sigma_t0`` [s], the weighted
    residual ``chi2`` and the ``samples`` used."""

    dv: np.ndarray
    cov: np.ndarray
    t0: np.ndarray
    sigma_t0: np.ndarray
    chi2: np.ndarray
    samples: int


def camera_axes(boresight_rtn: ArrayLike) -> np.ndarray:
    """The camera frame in the carrier's RTN frame: the columns x, y, z (z the unit ``boresight_rtn``; x the radial
    axis made normal to z, the normal axis where z is radial; y = z x x).

    Parameters
    ----------
    boresight_rtn : array_like, shape (3,)
        The boresight (any length, not zero), RTN.

    Returns
    -------
    numpy.ndarray, shape (3, 3)
        The rotation camera -> RTN (columns: the camera's axes).
    """
    z = np.asarray(boresight_rtn, dtype=float)
    z = z / np.linalg.norm(z)
    ref = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 0.0, 1.0])
    x = ref - (ref @ z) * z
    x /= np.linalg.norm(x)
    return np.stack([x, np.cross(z, x), z], axis=1)


def pose_sigma(rho: ArrayLike, cam: PoseCamera) -> np.ndarray:
    """The 1-sigma pose error ``(..., 3)`` [m] along the camera's x, y (lateral) and z (depth) at the ranges ``rho``
    [m] (module docstring: sigma0 + c p rho laterally, sigma0 + c p rho^2 / size in depth).

    Parameters
    ----------
    rho : array_like, shape (...)
        The ranges [m].
    cam : PoseCamera
        The camera.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The sigmas [m] along x, y, z of the camera frame.
    """
    rho = np.asarray(rho, dtype=float)
    k = cam.centroid_px * cam.pixel_angle
    lateral = cam.sigma0 + k * rho
    return np.stack([lateral, lateral, cam.sigma0 + k * rho * rho / cam.size], axis=-1)


def pose_covariance(pos_rtn: ArrayLike, cam: PoseCamera, axes: np.ndarray) -> np.ndarray:
    """The covariances ``(..., 3, 3)`` [m^2] in RTN of poses at the relative positions ``pos_rtn`` (:func:`pose_sigma`
    in the camera frame ``axes``, :func:`camera_axes`, turned to RTN: A diag(sigma^2) A^T).

    Parameters
    ----------
    pos_rtn : array_like, shape (..., 3)
        The relative positions [m], RTN.
    cam : PoseCamera
        The camera.
    axes : numpy.ndarray, shape (3, 3)
        The camera frame (:func:`camera_axes`).

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        The covariances [m^2], RTN.
    """
    s = pose_sigma(np.linalg.norm(np.asarray(pos_rtn, dtype=float), axis=-1), cam)
    cov = np.einsum("ik,...k,jk->...ij", axes, s * s, axes)
    return 0.5 * (cov + np.swapaxes(cov, -1, -2))  # symmetric to the bit


def in_view(pos_rtn: ArrayLike, cam: PoseCamera, axes: np.ndarray) -> np.ndarray:
    """Whether a pose can be taken at each relative position ``(..., 3)`` [m]: in front of the camera, inside both
    half fields of view and within the pose range limit (:attr:`PoseCamera.max_range`).

    Parameters
    ----------
    pos_rtn : array_like, shape (..., 3)
        The relative positions [m], RTN.
    cam : PoseCamera
        The camera.
    axes : numpy.ndarray, shape (3, 3)
        The camera frame (:func:`camera_axes`).

    Returns
    -------
    numpy.ndarray of bool, shape (...)
        True where a pose is taken (lighting aside: :func:`sunlit`).
    """
    p = np.asarray(pos_rtn, dtype=float) @ axes  # camera frame
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    with np.errstate(invalid="ignore", divide="ignore"):
        inside = (z > 0.0) & (np.abs(x) <= z * math.tan(cam.fov_half_r)) & (np.abs(y) <= z * math.tan(cam.fov_half_n))
    return inside & (np.linalg.norm(p, axis=-1) <= cam.max_range)


def sunlit(r_inertial: ArrayLike, sun: ArrayLike) -> np.ndarray:
    """Whether the inertial positions ``(..., 3)`` [m] are outside the Earth's cylindrical shadow of the unit Sun
    direction ``sun`` (3,) (on the Sun's side, or farther than the Earth's radius from the shadow's axis).

    Parameters
    ----------
    r_inertial : array_like, shape (..., 3)
        The positions [m], inertial.
    sun : array_like, shape (3,)
        The unit vector to the Sun (:func:`~roe_sep.core.od.radar.sun_direction`).

    Returns
    -------
    numpy.ndarray of bool, shape (...)
        True where lit.
    """
    r = np.asarray(r_inertial, dtype=float)
    s = np.asarray(sun, dtype=float)
    along = r @ s
    off = np.linalg.norm(r - along[..., None] * s, axis=-1)
    return (along > 0.0) | (off > R_EARTH)


def carrier_lit(chief_kep: ArrayLike, times: ArrayLike, jd0: float, j2: bool = True) -> np.ndarray:
    """Whether the carrier is lit at ``times`` [s]: its mean elements ``chief_kep`` at sim time 0 propagated
    secularly (:func:`~roe_sep.core.relmotion.dynamics.propagate_chief`), its circular-orbit position
    (:func:`~roe_sep.core.od.radar.chief_position_velocity`) tested against the cylindrical shadow (:func:`sunlit`)
    of the Sun of :func:`~roe_sep.core.od.radar.sun_direction` at the Julian date ``jd0`` + t / 86400. Within the
    pose range the picosatellite shares the carrier's light.

    Parameters
    ----------
    chief_kep : array_like, shape (6,)
        The carrier's mean elements [a m, e, i rad, raan rad, argp rad, M rad] at sim time 0.
    times : array_like, shape (m,)
        Sim times [s].
    jd0 : float
        The Julian date (UTC) of sim time 0.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray of bool, shape (m,)
        True where lit.
    """
    t = np.asarray(times, dtype=float)
    kep = propagate_chief(np.asarray(chief_kep, dtype=float), t, j2)
    r, _ = chief_position_velocity(kep[..., 0], kep[..., 2], kep[..., 3], kep[..., 4] + kep[..., 5])
    sun = sun_direction(jd0 + t / SECONDS_PER_DAY)
    along = np.sum(r * sun, axis=-1)
    off = np.linalg.norm(r - along[..., None] * sun, axis=-1)
    return (along > 0.0) | (off > R_EARTH)


def measure_poses(pos_rtn: ArrayLike, cam: PoseCamera, axes: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The pose estimates ``(..., 3)`` [m] (RTN) of the true relative positions ``pos_rtn``: normal errors of
    :func:`pose_sigma` along the camera axes ``axes``, three draws of ``rng`` per pose (x, y, z).

    Parameters
    ----------
    pos_rtn : array_like, shape (..., 3)
        The true relative positions [m], RTN.
    cam : PoseCamera
        The camera.
    axes : numpy.ndarray, shape (3, 3)
        The camera frame (:func:`camera_axes`).
    rng : numpy.random.Generator
        The noise's generator.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The measured relative positions [m], RTN.
    """
    p = np.asarray(pos_rtn, dtype=float)
    s = pose_sigma(np.linalg.norm(p, axis=-1), cam)
    return p + (rng.normal(size=p.shape) * s) @ axes.T


def ejection_response(tau: ArrayLike, a: float, inc: float, u0: ArrayLike, j2: bool = True) -> np.ndarray:
    """Phi ``(..., 3, 3)``: the relative position [m] ``tau`` [s] after a unit impulse [m/s] (columns R, T, N) given
    to the picosatellite at the carrier's mean argument of latitude ``u0`` [rad]: seed 002 Eq. (2) (Gauss control
    matrix), the secular propagation with J2 and the linear ROE-to-RTN map
    (:func:`~roe_sep.core.relmotion.roe.rtn_position`), times the inverse of its rate at tau = 0, so that the
    velocity right after the impulse is the impulse (the mean-element model is off by O(J2) there).

    Parameters
    ----------
    tau : array_like, shape (...)
        The time since the impulse [s].
    a, inc : float
        The carrier's semi-major axis [m] and inclination [rad].
    u0 : array_like, shape (...)
        The carrier's mean argument of latitude at the impulse [rad] (broadcast with ``tau``).
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (..., 3, 3)
        Phi: r = Phi dv.
    """
    h = 1.0e-3  # s: the model's velocity right after the impulse, Phi'(0) = I + O(J2), made exactly I
    rate = (_response(h, a, inc, u0, j2) - _response(-h, a, inc, u0, j2)) / (2.0 * h)
    return _response(tau, a, inc, u0, j2) @ np.linalg.inv(rate)


def _response(tau, a, inc, u0, j2):
    """Phi of :func:`ejection_response` before its normalisation."""
    tau = np.asarray(tau, dtype=float)
    u0 = np.asarray(u0, dtype=float)
    rate = arg_latitude_rate(a, inc, j2)
    roe0 = np.swapaxes(control_matrix(u0), -1, -2) / (mean_motion(a) * a)  # (..., 3, 6): Eq. 2, one per row
    roe = propagate(roe0, tau[..., None], a, inc, j2)  # (..., 3, 6)
    return np.swapaxes(rtn_position(roe, (u0 + rate * tau)[..., None]) * a, -1, -2)  # (..., 3 RTN, 3 impulses)


def estimate_ejection(times: ArrayLike, pos_rtn: ArrayLike, cov: ArrayLike, t0_guess: ArrayLike, chief: tuple,
                      *, j2: bool = True, iterations: int = 10) -> EjectionEstimate:
    """The executed ejection from pose estimates: weighted batch least squares of r(t) = Phi(t - t0) dv
    (:func:`ejection_response`) in (dv, t0), Gauss-Newton from ``t0_guess`` (module docstring). Batched: leading
    axes of ``pos_rtn`` (and ``cov``, ``t0_guess``) are independent draws, solved in one vectorised pass.

    Parameters
    ----------
    times : array_like, shape (m,)
        The epochs of the poses [s].
    pos_rtn : array_like, shape (..., m, 3)
        The measured relative positions [m], RTN.
    cov : array_like, shape (..., m, 3, 3)
        Their covariances [m^2] (:func:`pose_covariance`).
    t0_guess : array_like, shape (...)
        The release epoch to start from [s] (e.g. the commanded ejection, or the last frame before the first pose).
    chief : tuple
        The carrier's (a [m], inc [rad], u [rad], t [s]): its mean argument of latitude u at the epoch t.
    j2 : bool
        With the J2 secular rates.
    iterations : int
        At most this many Gauss-Newton steps (stops when t0 moves by < 1 ns).

    Returns
    -------
    EjectionEstimate
        dv [m/s], its covariance, t0 [s], its sigma, chi-square and the number of poses.
    """
    t = np.asarray(times, dtype=float)
    z = np.asarray(pos_rtn, dtype=float)
    w = np.linalg.inv(np.asarray(cov, dtype=float))  # (..., m, 3, 3)
    a, inc, u_ref, t_ref = (float(x) for x in chief)
    rate = float(arg_latitude_rate(a, inc, j2))
    t0 = np.array(t0_guess, dtype=float) * np.ones(z.shape[:-2])
    h = 1.0e-3  # s, the central difference of Phi in tau

    def phi(t0_):  # (..., m, 3, 3)
        return ejection_response(t - t0_[..., None], a, inc, (u_ref + rate * (t0_ - t_ref))[..., None], j2)

    def linear_dv(p):  # the weighted least-squares dv at fixed t0
        n = np.einsum("...mki,...mkl,...mlj->...ij", p, w, p)
        b = np.einsum("...mki,...mkl,...ml->...i", p, w, z)
        return np.linalg.solve(n, b[..., None])[..., 0]

    p = phi(t0)
    dv = linear_dv(p)
    for _ in range(iterations):
        dpdt = (phi(t0 + h) - phi(t0 - h)) / (2.0 * h)  # d Phi / d t0 (= -d Phi / d tau)
        jac = np.concatenate([p, np.einsum("...mij,...j->...mi", dpdt, dv)[..., None]], axis=-1)  # (..., m, 3, 4)
        res = z - np.einsum("...mij,...j->...mi", p, dv)
        n = np.einsum("...mki,...mkl,...mlj->...ij", jac, w, jac)
        b = np.einsum("...mki,...mkl,...ml->...i", jac, w, res)
        step = np.linalg.solve(n, b[..., None])[..., 0]
        dv, t0 = dv + step[..., :3], t0 + step[..., 3]
        p = phi(t0)
        if np.all(np.abs(step[..., 3]) < 1.0e-9):
            break
    jac = np.concatenate([p, np.einsum("...mij,...j->...mi", (phi(t0 + h) - phi(t0 - h)) / (2.0 * h), dv)[..., None]],
                         axis=-1)
    full = np.linalg.inv(np.einsum("...mki,...mkl,...mlj->...ij", jac, w, jac))
    res = z - np.einsum("...mij,...j->...mi", p, dv)
    chi2 = np.einsum("...mk,...mkl,...ml->...", res, w, res)
    return EjectionEstimate(dv, full[..., :3, :3], t0, np.sqrt(full[..., 3, 3]), chi2, int(len(t)))
