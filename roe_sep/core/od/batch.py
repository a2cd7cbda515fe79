"""Batch weighted least-squares orbit determination of the relative orbit from radar passes (seed 001 Sec. 5).

State x = [da, dl, dex, dey, dix, diy, da_dot]: the dimensionless ROE at the estimate epoch ``t_est`` and the
differential-drag drift of da [1/s] (:func:`~roe_sep.core.relmotion.dynamics.drag_da_dot`). The carrier's own orbit is
known (it carries GPS): its mean elements at each measurement epoch are inputs.

Model (Tapley, Schutz, Born, *Statistical Orbit Determination*, 2004, Ch. 4): z_k = h_k(x) + v_k, v_k ~ N(0, R_k),
R_k = diag(sigma_range^2, sigma_angle^2, sigma_angle^2), h_k(x) = observe(model_roe(x, t_k), chief_k, earth_k,
station_k). The mean ROE at t_k (:func:`propagate_state`, :func:`model_roe`): the secular propagation (J2 and the
drift x[6] of da) plus differential drag's drift of dix through the co-rotating atmosphere
(:func:`~roe_sep.core.relmotion.dynamics.drag_dix_dot`, King-Hele 1964) and its short-periodic relative e vector
(x[6] / n)(sin u_k, -cos u_k) (:func:`~roe_sep.core.relmotion.dynamics.drag_short_period_de`). With a
:class:`DragModel` (density scale height H) also the e vector's secular drag drift d de/dt = k (a da_dot e_c +
a_d_dot de), k = 1 / (2 H) + 1 / (2 a) (:func:`drag_de_drift`, King-Hele 1964), and the drift rate's growth over
the batch, da_dot(t) = x[6] (1 + gamma (t - t_est)) (:meth:`DragModel.growth`, :func:`drift_growth`).

Gauss-Newton: dx = (H^T W H)^-1 H^T W (z - h(x)), W = R^-1, H = dh/dx by central differences, solved by SVD of the
column-scaled, whitened H (ill-conditioning detected, not rounded away); azimuth residuals wrapped to [-pi, pi);
P = (H^T W H)^-1 at the solution. The model is almost linear in x over its uncertainty, so the NEES (:func:`nees`)
is chi-square with 7 degrees of freedom. The state is secular; :meth:`ODResult.mean_state` adds the short-periodic de.

Drift rate across burns (:class:`DragModel`, :class:`DriftPrior`): every batch starts after the latest burn, but the
drift rate does not jump (seed 002 Eq. 24 in time): da_dot = beta g, g = exp(-(a_c - a_ref) / H) (1 - R a da / H),
R = B_d / (B_d - B_c) (Vallado Eq. 8-33). The solution before a burn gives beta's marginal (x[6] / g, P[6, 6] / g^2)
as an a priori pseudo-measurement, one more whitened row (Tapley et al. Sec. 4.6, Eq. 4.6.1); ``density_walk``
widens its variance by (beta density_walk)^2 dt / 1 day (state noise compensation, Sec. 6.9). What each term is
worth, measured: docs/campaigns.md, "The OD model's terms, measured".
"""

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..constants import SECONDS_PER_DAY
from ..relmotion.dynamics import (
    drag_dix_dot,
    drag_short_period_de,
    j2_kappa,
    propagate,
    propagate_chief,
    propagate_elements,
)
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import roe_to_rtn, wrap_angle
from ..relmotion.trajectory import Burn, Chief, state_at
from .osculating import deputy_state
from .radar import chief_from_kepler, chief_position_velocity, observe, rtn_matrix, two_way_look, two_way_position

STATE_SIZE = 7
MAX_CONDITION = 1e10
"""Largest condition number of the whitened, column-scaled design matrix accepted (normal matrix: its square)."""


@dataclass(frozen=True)
class RadarBatch:
    """Measurements of one OD batch, one row per epoch (any order, any stations).

    ``t`` (m,) sim time [s]; ``z`` (m, 3) [range m, az rad, el rad]; ``sigma`` (m, 3) their 1-sigma noise;
    ``chief`` (m, 6) the carrier's mean Keplerian elements at ``t``; ``earth`` (m, 3, 3) the GCRS -> ITRS rotation
    (:func:`roe_sep.core.frames.gcrs_to_itrs`); ``site_ef`` (m, 3) station Earth-fixed position [m]; ``site_enu``
    (m, 3, 3) its ENU rotation.
    """

    t: np.ndarray
    z: np.ndarray
    sigma: np.ndarray
    chief: np.ndarray
    earth: np.ndarray
    site_ef: np.ndarray
    site_enu: np.ndarray


@dataclass(frozen=True)
class OsculatingBatch(RadarBatch):
    """A :class:`RadarBatch` whose carrier is known by its own ephemeris: ``carrier`` (m, 2, 3) its inertial
    position [m] and velocity [m/s] at ``t``, ``chief`` its first-order Brouwer mean elements there (eccentricity
    kept). :func:`predict` then places the picosatellite with the osculating model of
    :mod:`roe_sep.core.od.osculating` (the carrier's state plus the osculating difference of the two spacecraft's
    mean elements) instead of the circular carrier and the linear ROE map; the mean ROE propagation
    (:func:`model_roe`) is the same. The offline OD of files from a numerical propagator uses it
    (:mod:`roe_sep.ndm.offline_od`, ``--model osculating``); radar_od's plain :class:`RadarBatch` is unchanged."""

    carrier: np.ndarray


@dataclass(frozen=True)
class ODResult:
    """Estimate ``x`` (7,) at ``t_est`` [s] with covariance ``cov`` (7, 7) (secular ROE, dimensionless, and da_dot
    [1/s]), the post-fit normalized residual RMS, Gauss-Newton ``iterations``, the number of measurement triplets
    used, and the carrier's mean semi-major axis ``a_est`` [m] and argument of latitude ``u_est`` [rad] at
    ``t_est``."""

    x: np.ndarray
    cov: np.ndarray
    t_est: float
    residual_rms: float
    iterations: int
    measurements: int
    a_est: float = 0.0
    u_est: float = 0.0
    drag: bool = True
    range_bias: tuple = ()
    """Estimated range bias [m] of each station (:class:`RangeBiasPrior`, in :func:`station_index` order); empty when
    not estimated."""
    range_bias_cov: tuple = ()
    """Their covariance [m^2], row-major; ``cov`` is the state's marginal (the biases' uncertainty included)."""

    def mean_state(self) -> tuple[np.ndarray, np.ndarray]:
        """(state, covariance) of the mean ROE at ``t_est`` as the project defines them (first-order J2 mean
        elements, which keep drag's short-periodic de: :func:`mean_roe_map`) and da_dot: J x, J P J^T."""
        jac = mean_roe_map(self.a_est, self.u_est) if self.drag else np.eye(STATE_SIZE)
        return jac @ self.x, jac @ self.cov @ jac.T


@dataclass(frozen=True)
class DragModel:
    """The drift rate's dependence on the carrier's height and the deputy's (module docstring): density scale
    height ``scale_height`` H [m] and ballistic ratio ``ballistic_ratio`` R = B_d / (B_d - B_c)."""

    scale_height: float
    ballistic_ratio: float

    def growth(self, a_chief_dot: ArrayLike, a_da_dot: ArrayLike) -> np.ndarray:
        """d ln g / dt [1/s] = -(a_c_dot + R a_c da_dot) / H: the relative growth of the drift rate as the carrier
        decays at ``a_chief_dot`` [m/s] (denser air) and the deputy's own drift ``a_da_dot`` [m/s] (a_c da_dot)
        takes it lower still (the time derivative of :meth:`factor` at first order in a da / H)."""
        return -(np.asarray(a_chief_dot, dtype=float)
                 + self.ballistic_ratio * np.asarray(a_da_dot, dtype=float)) / self.scale_height

    def factor(self, a_chief: ArrayLike, a_ref: float, da: ArrayLike) -> np.ndarray:
        """g = exp(-(a_c - a_ref) / H) (1 - R a_c da / H): da_dot over beta (broadcasts).

        Parameters
        ----------
        a_chief, a_ref : array_like, float
            The carrier's mean semi-major axis and the reference one [m].
        da : array_like
            The dimensionless da.

        Returns
        -------
        numpy.ndarray
            g.
        """
        a_chief = np.asarray(a_chief, dtype=float)
        return (np.exp(-(a_chief - a_ref) / self.scale_height)
                * (1.0 - self.ballistic_ratio * a_chief * np.asarray(da, dtype=float) / self.scale_height))


@dataclass(frozen=True)
class DriftPrior:
    """A priori information on the drag constant beta = da_dot / g [1/s] (module docstring): its value, variance
    [1/s^2], the reference carrier semi-major axis ``a_ref`` [m] of g, the epoch ``t`` [s] of the solution it comes
    from and the drag model."""

    beta: float
    variance: float
    a_ref: float
    t: float
    model: DragModel

    @classmethod
    def from_result(cls, result: "ODResult", a_chief: float, model: DragModel) -> "DriftPrior":
        """The marginal of a solution's drift rate as beta.

        Parameters
        ----------
        result : ODResult
            The solution.
        a_chief : float
            Its carrier's semi-major axis [m] (the reference of g).
        model : DragModel
            The drag model.

        Returns
        -------
        DriftPrior
            beta, its variance, the reference and the solution's epoch.
        """
        g = float(model.factor(a_chief, a_chief, result.x[0]))
        return cls(float(result.x[6]) / g, float(result.cov[6, 6]) / g**2, float(a_chief), float(result.t_est), model)

    def carried(self, t: float, density_walk: float = 0.0) -> "DriftPrior":
        """The same information at epoch ``t`` [s]: the variance grows by (beta density_walk)^2 |t - t0| / 1 day
        (``density_walk``: relative 1-sigma of the orbit-mean density per sqrt(day), a random walk)."""
        walk = (self.beta * density_walk) ** 2 * abs(float(t) - self.t) / SECONDS_PER_DAY
        return DriftPrior(self.beta, self.variance + walk, self.a_ref, float(t), self.model)

    def residual_row(self, x: np.ndarray, a_chief: float) -> tuple[float, np.ndarray]:
        """Whitened a priori residual (beta - x[6] / g(x)) / sigma_beta and its partials d(x[6] / g) / dx over
        sigma_beta ``(7,)`` at state ``x`` and carrier ``a_chief`` [m]."""
        m = self.model
        g = float(m.factor(a_chief, self.a_ref, x[0]))
        dg_dda = -float(np.exp(-(a_chief - self.a_ref) / m.scale_height)) * m.ballistic_ratio * a_chief / m.scale_height
        sigma = np.sqrt(self.variance)
        row = np.zeros(STATE_SIZE)
        row[6] = 1.0 / g
        row[0] = -x[6] * dg_dda / g**2
        return (self.beta - x[6] / g) / sigma, row / sigma


@dataclass(frozen=True)
class StatePrior:
    """A priori information on the whole state at the batch's estimate epoch (issue 41 part 3): a prediction
    ``x`` (7,) [dimensionless ROE, da_dot 1/s] with covariance ``cov`` (7, 7), e.g. the ejection on record carried
    through an outage (:func:`predicted_prior`). It enters as seven whitened pseudo-measurement rows C^-1 (x_p - x),
    cov = C C^T (Tapley et al. Sec. 4.6, Eq. 4.6.1), so that one radar pass, which alone does not determine the
    drift rate, gives a solution."""

    x: np.ndarray
    cov: np.ndarray

    def rows(self, x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The whitened residual (7,) and its partials (7, 7) at state ``x``; ValueError for a covariance that is
        not positive definite."""
        try:
            c = np.linalg.cholesky(np.asarray(self.cov, dtype=float))
        except np.linalg.LinAlgError as exc:
            raise ValueError(f"the state prior's covariance is not positive definite: {exc}") from None
        w = np.linalg.inv(c)
        return w @ (np.asarray(self.x, dtype=float) - x), w


def predicted_prior(roe0: ArrayLike, cov0: ArrayLike, chief: Chief, da_dot: float, da_dot_sigma: float, *,
                    burns: Iterable[Burn], t: float, j2: bool = True) -> StatePrior:
    """The state prior at ``t`` [s] of a prediction from ``roe0`` at the chief's epoch through the executed
    ``burns``, with a constant drift rate: the secular model (:func:`~roe_sep.core.relmotion.trajectory.state_at`)
    is affine in the ROE and in da_dot, so its Jacobian Phi from unit differences is exact and P = Phi P0 Phi^T
    carries the ROE covariance and the drift rate's variance (the drag's along-track error grows as
    0.75 n sigma t^2).

    Parameters
    ----------
    roe0 : array_like, shape (6,)
        The dimensionless ROE at ``chief.t0``.
    cov0 : array_like, shape (6, 6)
        Their covariance (dimensionless squared).
    chief : Chief
        The chief at ``roe0``'s epoch.
    da_dot, da_dot_sigma : float
        The drift rate of da [1/s] and its 1-sigma.
    burns : iterable of Burn
        The relative impulses executed between ``chief.t0`` and ``t``.
    t : float
        The prior's epoch [s], >= ``chief.t0``.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    StatePrior
        x = [ROE at t, da_dot] and its covariance.
    """
    burns = [b for b in burns if chief.t0 < b.epoch <= t]
    x0 = np.append(np.asarray(roe0, dtype=float), float(da_dot))

    def state(x):
        return np.append(state_at(x[:6], chief.t0, burns, t, chief, j2=j2, da_dot=float(x[6])), x[6])

    x = state(x0)
    step = 1e-6
    phi = np.column_stack([(state(x0 + step * e) - x) / step for e in np.eye(STATE_SIZE)])
    p0 = np.zeros((STATE_SIZE, STATE_SIZE))
    p0[:6, :6] = np.asarray(cov0, dtype=float)
    p0[6, 6] = float(da_dot_sigma) ** 2
    cov = phi @ p0 @ phi.T
    return StatePrior(x, 0.5 * (cov + cov.T))


def uses_prediction(now: float, full: bool, *, release: float | None, after: float, full_estimates: int,
                    first_prediction: float | None, burn_epochs: Iterable[float]) -> bool:
    """Whether an OD takes the prediction (:func:`predicted_prior`) as its prior (issue 41 part 3): without a full
    estimate (``full``: enough passes over the arc; ``full_estimates`` made so far) ``after`` (> 0) after the
    ``release`` (a radar outage); then every OD until the first carrier burn after the first such OD (the
    acquisition's), whose arc the drift prior of the last solution carries on. A two-pass arc alone knows the drift
    rate far worse than the prediction: dropped there, the acquisition kept the single-pass plan and its later
    re-plans filled the final OD's arc (10 of 100 runs of the 24-h outage missed the ICs; docs/contingencies.md).

    Parameters
    ----------
    now : float
        The sim time [s] of the OD.
    full : bool
        Whether its passes alone make a full estimate.
    release : float or None
        The release epoch [s] on record (None: no ejection on record, no prediction).
    after : float
        ``prior_od_after`` [s] (<= 0: never).
    full_estimates : int
        The full estimates made without the prediction so far.
    first_prediction : float or None
        The epoch [s] of the first OD from the prediction, None before.
    burn_epochs : iterable of float
        The epochs [s] of the executed carrier burns.

    Returns
    -------
    bool
        True when the OD takes the prediction as its prior.
    """
    if after <= 0.0 or release is None:
        return False
    if first_prediction is not None:
        return not any(t > first_prediction for t in burn_epochs)
    return not full and full_estimates == 0 and now >= release + after


@dataclass(frozen=True)
class RangeBiasPrior:
    """A constant range bias per station, estimated with the state (issue 41 part 4): each station's bias b_s [m]
    enters its ranges as z = h(x) + b_s + noise, with the a priori information b_s ~ N(0, sigma squared), sigma =
    ``sigma`` (a pseudo-measurement row b_s / sigma). A bias the state would otherwise absorb (a +30 m bias shifts
    a 3-pass OD by 7-18 formal sigma) is told apart by the passes' different geometries (the range's direction in
    the RTN frame turns from pass to pass while a bias does not); ``sigma`` [m] > 0."""

    sigma: float


@dataclass(frozen=True)
class CarrierRanges:
    """The stations' ranges to the carrier, whose orbit its GPS gives (issue 41 part 4): with the carrier's modelled
    range h_c (its GPS orbit through the same two-way measurement model), z_c - h_c = b_s + v, v ~ N(0, sigma^2),
    sigma^2 = sigma_range^2 + sigma_gps^2, measures each station's bias b_s free of the relative orbit. With a
    :class:`RangeBiasPrior`, each becomes one more whitened row of the batch, (z_c - h_c - b_s) / sigma, with the
    partial 1 / sigma on b_s alone; a station without ranges of the picosatellite in the batch has no bias state,
    and its carrier ranges are left out. ``site_ef`` (k, 3) the station's Earth-fixed position [m], ``residual``
    (k,) z_c - h_c [m], ``sigma`` (k,) [m] > 0."""

    site_ef: np.ndarray
    residual: np.ndarray
    sigma: np.ndarray

    def rows(self, batch: RadarBatch) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(station index (j,) in :func:`station_index` order, residual (j,) [m], sigma (j,) [m]) of the ranges at
        the batch's stations."""
        sites = np.unique(np.round(np.asarray(batch.site_ef, dtype=float), 3), axis=0)
        own = np.round(np.asarray(self.site_ef, dtype=float).reshape(-1, 3), 3)
        match = np.all(own[:, None, :] == sites[None, :, :], axis=2)  # (k, n_sites)
        keep = match.any(axis=1)
        return (np.argmax(match[keep], axis=1), np.asarray(self.residual, dtype=float).reshape(-1)[keep],
                np.asarray(self.sigma, dtype=float).reshape(-1)[keep])


def residual_tail(residual_rms: float, measurements: int, parameters: int = STATE_SIZE) -> float:
    """The post-fit residual test (Tapley et al. Sec. 4.16): with m measurement triplets whitened by their sigmas,
    3 m r^2 (r the residual RMS in sigmas) is chi-square with 3 m - ``parameters`` degrees of freedom when the
    model holds; its upper tail P(chi2 >= 3 m r^2). A range bias of one to five range sigmas left out of the state
    drives it below 1e-4 (docs/contingencies.md).

    Parameters
    ----------
    residual_rms : float
        The post-fit residual RMS in measurement sigmas (dimensionless).
    measurements : int
        The number m of measurement triplets.
    parameters : int
        The estimated parameters (the state's 7, plus one per estimated range bias).

    Returns
    -------
    float
        The tail probability; 1.0 when there are no degrees of freedom or the RMS is not finite.
    """
    # scipy.special's chdtrc is what scipy.stats.chi2.sf calls; scipy.stats costs about 0.3 CPU-s to import
    from scipy.special import chdtrc

    m = int(measurements)
    dof = 3 * m - int(parameters)
    if dof <= 0 or not np.isfinite(residual_rms):
        return 1.0
    return float(chdtrc(dof, 3.0 * m * float(residual_rms) ** 2))


def carrier_bias_tail(carrier: CarrierRanges) -> float:
    """The carrier's ranges' own test of a range bias: per station s, with weights w = 1 / sigma^2, the weighted
    mean residual's (sum w r)^2 / sum w is chi-square(1) without a bias (the residuals are z_c - h_c = b_s + v);
    summed over the stations, chi-square(stations). A few dozen ranges see a bias of one range sigma.

    Parameters
    ----------
    carrier : CarrierRanges
        The ranges.

    Returns
    -------
    float
        The upper tail P(chi2 >= statistic); 1.0 without ranges.
    """
    from scipy.special import chdtrc

    res = np.asarray(carrier.residual, dtype=float).reshape(-1)
    if not res.size:
        return 1.0
    w = 1.0 / np.square(np.asarray(carrier.sigma, dtype=float).reshape(-1))
    _, index = np.unique(np.round(np.asarray(carrier.site_ef, dtype=float).reshape(-1, 3), 3), axis=0,
                         return_inverse=True)
    index = np.asarray(index).reshape(-1)
    n = int(index.max()) + 1
    stat = float(np.sum(np.bincount(index, w * res, n) ** 2 / np.bincount(index, w, n)))
    return float(chdtrc(n, stat))


def bias_state_switch(result: "ODResult", alpha: float, carrier: CarrierRanges | None = None) -> bool:
    """Whether an OD solved without range biases calls for them (issue 41 part 4): its residual test
    (:func:`residual_tail`), or the carrier's ranges' (:func:`carrier_bias_tail`) where the radar gives them,
    rejects the model at level ``alpha``. A solution with biases never switches.

    Parameters
    ----------
    result : ODResult
        The solution.
    alpha : float
        The tests' level (the anomaly watch's ``residual_alpha``, 1e-4).
    carrier : CarrierRanges, optional
        The carrier's ranges so far.

    Returns
    -------
    bool
        True when the biases should be estimated from now on.
    """
    if result.range_bias:
        return False
    if carrier is not None and carrier_bias_tail(carrier) < alpha:
        return True
    return residual_tail(result.residual_rms, result.measurements) < alpha


def station_index(batch: RadarBatch) -> tuple[np.ndarray, int]:
    """Each measurement's station (its Earth-fixed site to the millimetre, in order of first appearance after
    sorting) and the number of stations.

    Parameters
    ----------
    batch : RadarBatch
        The measurements.

    Returns
    -------
    tuple
        (index (m,) int, number of stations).
    """
    sites, index = np.unique(np.round(np.asarray(batch.site_ef, dtype=float), 3), axis=0, return_inverse=True)
    return np.asarray(index).reshape(-1), int(sites.shape[0])


def _bias_columns(index: np.ndarray, n_bias: int, w: np.ndarray) -> np.ndarray:
    """dh/db of the whitened measurements ``(3 m, n_bias)``: w on the range rows of each station, 0 elsewhere."""
    cols = np.zeros((index.size, 3, n_bias))
    cols[np.arange(index.size), 0, index] = 1.0
    return cols.reshape(-1, n_bias) * w[:, None]


def measurement_residual(z: ArrayLike, z_model: ArrayLike) -> np.ndarray:
    """z - h with the azimuth difference wrapped to [-pi, pi) (``(..., 3)``)."""
    r = np.asarray(z, dtype=float) - np.asarray(z_model, dtype=float)
    r[..., 1] = wrap_angle(r[..., 1])
    return r


def _chief_a_inc(batch: RadarBatch):
    """a [m] and i [rad] of the chief at the batch's latest epoch (the secular ROE model's constants)."""
    k = np.argmax(batch.t)
    return batch.chief[k, 0], batch.chief[k, 2]


def chief_decay(batch: RadarBatch) -> float:
    """The carrier's mean semi-major axis rate [m/s] over the batch: the least-squares slope of its mean a (its own
    GPS orbit) against time; 0 over less than one orbital period (the slope would be the short-periodic remainder
    of the mean elements rather than the decay)."""
    t = np.asarray(batch.t, dtype=float)
    a = np.asarray(batch.chief[:, 0], dtype=float)
    if t.size < 2 or np.ptp(t) < 2.0 * np.pi / mean_motion(float(np.mean(a))):
        return 0.0
    return float(np.polyfit(t - t.mean(), a - a.mean(), 1)[0])


def chief_eccentricity(batch: RadarBatch, t_ref: float) -> tuple[np.ndarray, np.ndarray]:
    """The carrier's mean eccentricity vector e_c = e (cos argp, sin argp) at ``t_ref`` [s] and its rate [1/s],
    ``((2,), (2,))``: the least-squares line of its mean elements (its own GPS orbit) against time over the batch;
    over less than one orbital period their mean and no rate (as :func:`chief_decay`). The J2 perigee rotation and
    J3 turn e_c about the frozen eccentricity at about 6e-5 per day in the default scenario, the same order as e_c
    over a batch: a line, not a constant."""
    t = np.asarray(batch.t, dtype=float)
    kep = np.asarray(batch.chief, dtype=float)
    ecc = kep[:, 1:2] * np.stack([np.cos(kep[:, 4]), np.sin(kep[:, 4])], axis=-1)
    if t.size < 2 or np.ptp(t) < 2.0 * np.pi / mean_motion(float(np.mean(kep[:, 0]))):
        return ecc.mean(axis=0), np.zeros(2)
    slope, at_ref = np.polyfit(t - float(t_ref), ecc, 1)
    return at_ref, slope


def drag_de_drift(x: ArrayLike, de: ArrayLike, dt: ArrayLike, a: float, scale_height: float, *, ecc: ArrayLike,
                  ecc_rate: ArrayLike = (0.0, 0.0), a_chief_dot: float = 0.0, growth: ArrayLike = 0.0) -> np.ndarray:
    """Secular change of the relative eccentricity vector by drag. Drag decays a near-circular orbit's e vector with
    its semi-major axis, d e_vec / dt = k a_dot e_vec, k = 1 / (2 H) + 1 / (2 a) (King-Hele, *Theory of Satellite
    Orbits in an Atmosphere*, 1964, Ch. 4, first order in e and a e / H), so for the pair (de = e_d - e_c)

        d de / dt = k (a da_dot e_c + a_d_dot de),   a_d_dot = a_c_dot + a da_dot,

    integrated in closed form with da_dot(t) = x[6] (1 + gamma t) and e_c(t) = e_c + e_c_dot t, de held at ``de``.

    Parameters
    ----------
    x, de, dt : array_like, shapes (..., 7), (..., 2), (...)
        States, their relative e vectors, the times [s].
    a, scale_height : float
        The chief's semi-major axis and the density scale height H [m].
    ecc, ecc_rate : array_like, shape (2,)
        The carrier's mean e vector at dt = 0 and its rate [1/s] (:func:`chief_eccentricity`).
    a_chief_dot, growth : float, array_like
        The carrier's decay [m/s] and the drift growth gamma [1/s].

    Returns
    -------
    numpy.ndarray, shape (..., 2)
        The change of de.
    """
    x = np.asarray(x, dtype=float)
    dt = np.asarray(dt, dtype=float)[..., None]
    gamma = np.asarray(growth, dtype=float)[..., None]
    rate = x[..., 6, None]
    e0, e1 = np.asarray(ecc, dtype=float), np.asarray(ecc_rate, dtype=float)
    k = 0.5 / scale_height + 0.5 / a
    # int_0^dt da_dot(t) e_c(t) dt and int_0^dt a_d_dot(t) dt
    carrier = rate * (e0 * dt + (e1 + gamma * e0) * dt**2 / 2.0 + gamma * e1 * dt**3 / 3.0)
    decay = (a_chief_dot + a * rate) * dt + a * rate * gamma * dt**2 / 2.0
    return k * (a * carrier + decay * np.asarray(de, dtype=float))


def drift_growth(x: ArrayLike, batch: RadarBatch, model: DragModel | None,
                 decay: float | None = None) -> np.ndarray | float:
    """gamma [1/s] (:meth:`DragModel.growth`) of states over ``batch``: the carrier's decay and the state's own
    drift a_c x[6]; 0 without a drag ``model``.

    Parameters
    ----------
    x : array_like, shape (..., 7)
        States.
    batch : RadarBatch
        The measurements and the carrier's mean elements.
    model, decay : DragModel or None, float, optional
        The drag model; the carrier's decay [m/s] (default :func:`chief_decay`).

    Returns
    -------
    numpy.ndarray, shape (...), or float
        gamma [1/s].
    """
    x = np.asarray(x, dtype=float)
    if model is None:
        return np.zeros(x.shape[:-1])
    a = _chief_a_inc(batch)[0]
    return model.growth(chief_decay(batch) if decay is None else decay, a * x[..., 6])


def propagate_state(x: ArrayLike, dt: ArrayLike, a: float, inc: float, j2: bool = True, *, drag: bool = True,
                    growth: ArrayLike = 0.0) -> np.ndarray:
    """ROE ``(..., 6)`` of states ``x`` ``(..., 7)`` after ``dt`` [s] (``a`` [m], ``inc`` [rad] the chief's):
    :func:`propagate` with da_dot = x[6] at dt = 0, and

    * the drift rate's growth (``growth`` gamma [1/s], :meth:`DragModel.growth`): da_dot(dt) = x[6] (1 + gamma dt),
      which adds x[6] gamma dt^2 / 2 to da and its integral x[6] gamma dt^3 / 6 to dl and diy through the same
      rates as da (Eq. of :func:`~roe_sep.core.relmotion.dynamics.propagate_elements`);
    * the relative inclination drift that the same differential drag drives (:func:`drag_dix_dot`), dix_dot, with
      its J2 couplings into dl (d dl/dt = ... - 7 kappa sin 2i dix: - 7/2 kappa sin 2i dix_dot dt^2) and diy
      (d diy/dt = ... + 2 kappa sin^2 i dix: + kappa sin^2 i dix_dot dt^2);

    Parameters
    ----------
    x, dt, a, inc, j2
        As above; with the J2 secular rates.
    drag, growth : bool, array_like
        False: :func:`propagate` alone (to reproduce solutions recorded without the drag terms); gamma [1/s].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The dimensionless ROE.
    """
    x = np.asarray(x, dtype=float)
    dt = np.asarray(dt, dtype=float)
    roe = propagate(x[..., :6], dt, a, inc, j2, da_dot=x[..., 6])
    if not drag:
        return roe
    curve = x[..., 6] * np.asarray(growth, dtype=float)  # d2 da / dt2 [1/s^2]
    if np.any(curve != 0.0):
        # a zero state at the constant rate c dt / 3 integrates da to (c dt / 3) dt^2 / 2 = c dt^3 / 6: the
        # growth's integral, so its dl and diy are the growth's

        grow = propagate_elements((0.0,) * 6, dt, a, inc, j2, da_dot=curve * dt / 3.0)
        roe[..., 0] += 0.5 * curve * dt * dt
        roe[..., 1] += grow[1]
        roe[..., 5] += grow[5]
    dix_dot = drag_dix_dot(x[..., 6], a, inc)
    roe[..., 4] += dix_dot * dt
    if j2:
        kappa = j2_kappa(a)
        roe[..., 1] -= 3.5 * kappa * np.sin(2.0 * inc) * dix_dot * dt * dt
        roe[..., 5] += kappa * np.sin(inc) ** 2 * dix_dot * dt * dt
    return roe


def mean_roe_map(a: float, u: float) -> np.ndarray:
    """J ``(7, 7)``: secular state -> mean ROE and da_dot of a carrier at semi-major axis ``a`` [m] and mean
    argument of latitude ``u`` [rad]: the identity plus the da_dot column of drag's short-periodic de
    (:func:`drag_short_period_de` is linear in da_dot: (sin u, -cos u) / n)."""
    jac = np.eye(STATE_SIZE)
    jac[2:4, 6] = drag_short_period_de(1.0, a, u)
    return jac


def model_roe(x: ArrayLike, batch: RadarBatch, t_est: float, j2: bool = True, drag: bool = True, *,
              model: DragModel | None = None, decay: float | None = None, ecc: tuple | None = None) -> np.ndarray:
    """Mean ROE at the measurement epochs: :func:`propagate_state` (a, i of the chief at the batch's latest epoch;
    the drift rate's growth, :func:`drift_growth`) plus drag's short-periodic de at each epoch's mean argument of
    latitude (:func:`drag_short_period_de`). ``decay``, ``ecc``: constants of the batch, when the caller has them.

    Parameters
    ----------
    x : array_like, shape (..., 7)
        States at ``t_est``.
    batch : RadarBatch
        The measurements and the carrier's mean elements.
    t_est : float
        The estimate epoch [s].
    j2, drag : bool
        With the J2 secular rates; with the drag terms.
    model, decay, ecc : DragModel, float, tuple, optional
        The drag model (growth; none without it), :func:`chief_decay` and :func:`chief_eccentricity`.

    Returns
    -------
    numpy.ndarray, shape (..., m, 6)
        The dimensionless mean ROE.
    """
    x = np.asarray(x, dtype=float)
    a, inc = _chief_a_inc(batch)
    growth = drift_growth(x, batch, model if drag else None, decay)[..., None]
    roe = propagate_state(x[..., None, :], batch.t - t_est, a, inc, j2, drag=drag, growth=growth)
    if not drag:
        return roe
    if model is not None:
        ecc, ecc_rate = chief_eccentricity(batch, t_est) if ecc is None else ecc
        roe[..., 2:4] += drag_de_drift(x[..., None, :], roe[..., 2:4], batch.t - t_est, a, model.scale_height, ecc=ecc,
                                       ecc_rate=ecc_rate, a_chief_dot=chief_decay(batch) if decay is None else decay,
                                       growth=growth)
    u = batch.chief[:, 4] + batch.chief[:, 5]
    roe[..., 2:4] += drag_short_period_de(x[..., None, 6], a, u)
    return roe


def predict(x: ArrayLike, batch: RadarBatch, t_est: float, j2: bool = True, drag: bool = True, *,
            model: DragModel | None = None, decay: float | None = None, ecc: tuple | None = None) -> np.ndarray:
    """h(x): the mean ROE of :func:`model_roe` observed with :func:`observe`; of an :class:`OsculatingBatch`, the
    picosatellite's state of :func:`roe_sep.core.od.osculating.deputy_state` (rotated by ``earth``) observed with
    :func:`~roe_sep.core.od.radar.two_way_look`.

    Parameters
    ----------
    x, batch, t_est, j2, drag, model, decay, ecc
        As for :func:`model_roe`.

    Returns
    -------
    numpy.ndarray, shape (..., m, 3)
        Modeled [range, az, el] [m, rad, rad].
    """
    roe = model_roe(x, batch, t_est, j2, drag, model=model, decay=decay, ecc=ecc)
    if isinstance(batch, OsculatingBatch):  # the carrier's ephemeris and the osculating map (its docstring)
        state = np.einsum("...ij,...kj->...ki", batch.earth, deputy_state(roe, batch.chief, batch.carrier))
        return two_way_look(state, batch.site_ef, batch.site_enu)
    return observe(roe, batch.chief, batch.earth, batch.site_ef, batch.site_enu)


def state_steps(a: float) -> np.ndarray:
    """Finite-difference steps of the 7 states: 1 m of each a*ROE, and 1e-6 m/s of a*da_dot (6 m of a*dl after
    a day), small against the hundreds of meters the look angles need to become nonlinear at LEO ranges."""
    return np.array([1.0] * 6 + [1e-6]) / a


def jacobian(x: ArrayLike, batch: RadarBatch, t_est: float, j2: bool = True, drag: bool = True, *,
             model: DragModel | None = None, decay: float | None = None, ecc: tuple | None = None) -> np.ndarray:
    """H = dh/dx by central differences (h(x + s e_j) - h(x - s e_j)) / 2 s, azimuth wrapped.

    Parameters
    ----------
    x : array_like, shape (7,)
        The state.
    batch, t_est, j2, drag, model, decay, ecc
        As for :func:`model_roe`.

    Returns
    -------
    numpy.ndarray, shape (m, 3, 7)
        H.
    """
    s = state_steps(_chief_a_inc(batch)[0])
    pert = np.concatenate([np.diag(s), -np.diag(s)]) + np.asarray(x, dtype=float)
    z = predict(pert, batch, t_est, j2, drag, model=model, decay=decay, ecc=ecc)  # (14, m, 3)
    diff = measurement_residual(z[:STATE_SIZE], z[STATE_SIZE:])  # (7, m, 3)
    return np.moveaxis(diff / (2.0 * s[:, None, None]), 0, -1)


def initial_guess(batch: RadarBatch, t_est: float, j2: bool = True, drag: bool = True) -> np.ndarray:
    """Linear starting point: every measurement inverted to a relative RTN position, then unweighted least squares.

    r_rel/a = [R T N]^T (W^T two_way_position(z) - r_chief) / a (W: ``earth``; the light time taken out with the
    chief's velocity) is linear in x, exactly: the secular
    propagation and the ROE -> RTN map are linear, so its design matrix is the model evaluated on the 7 unit states.
    (An :class:`OsculatingBatch`: r_chief, v_chief its carrier's states, the linear map a start for Gauss-Newton.)

    Parameters
    ----------
    batch, t_est, j2, drag
        As for :func:`model_roe`.

    Returns
    -------
    numpy.ndarray, shape (7,)
        The state.
    """
    a, inc, raan, u = chief_from_kepler(batch.chief)
    if isinstance(batch, OsculatingBatch):  # the carrier's own states
        rc, vc = batch.carrier[:, 0], batch.carrier[:, 1]
    else:
        rc, vc = chief_position_velocity(a, inc, raan, u)
    v_ef = np.einsum("...ij,...j->...i", batch.earth, vc)
    r_eci = np.einsum("...ji,...j->...i", batch.earth, two_way_position(batch.z, v_ef, batch.site_ef, batch.site_enu))
    rel = np.einsum("...ji,...j->...i", rtn_matrix(rc, vc), r_eci - rc) / a[:, None]
    unit = np.eye(STATE_SIZE)
    roe = model_roe(unit, batch, t_est, j2, drag)
    design = np.moveaxis(roe_to_rtn(roe, u)[0], 0, -1).reshape(-1, STATE_SIZE)  # (3m, 7)
    scale = np.linalg.norm(design, axis=0)
    scale[scale == 0.0] = 1.0  # an unobservable component stays 0 here; batch_least_squares reports it
    y = np.linalg.lstsq(design / scale, rel.reshape(-1), rcond=None)[0]
    return y / scale


def _check(batch: RadarBatch):
    m = np.shape(batch.t)[0] if np.ndim(batch.t) == 1 else -1
    if m < 0:
        raise ValueError("measurement epochs must be a 1-D array")
    shapes = {"z": (m, 3), "sigma": (m, 3), "chief": (m, 6), "earth": (m, 3, 3), "site_ef": (m, 3),
              "site_enu": (m, 3, 3)}
    for name, shape in shapes.items():
        if np.shape(getattr(batch, name)) != shape:
            raise ValueError(f"{name} has shape {np.shape(getattr(batch, name))}, expected {shape}")
    if 3 * m < STATE_SIZE + 1:
        raise ValueError(f"not enough measurements: {m} range/az/el triplets ({3 * m} values) for {STATE_SIZE} "
                         "unknowns and a residual")
    names = ("t", "z", "sigma", "chief", "earth", "site_ef", "site_enu")
    if isinstance(batch, OsculatingBatch):
        names += ("carrier",)
        if np.shape(batch.carrier) != (m, 2, 3):
            raise ValueError(f"carrier has shape {np.shape(batch.carrier)}, expected {(m, 2, 3)}")
    for name in names:
        if not np.all(np.isfinite(getattr(batch, name))):
            raise ValueError(f"measurement batch has non-finite values in {name!r}")
    if np.any(np.asarray(batch.sigma) <= 0.0):
        raise ValueError("measurement sigmas must be positive")


def batch_least_squares(batch: RadarBatch, t_est: float | None = None, x0: ArrayLike | None = None, j2: bool = True,
                        max_iterations: int = 20, *, tol: float = 1e-6, prior: DriftPrior | None = None,
                        drag: bool = True, model: DragModel | None = None,
                        bias: RangeBiasPrior | None = None, carrier: CarrierRanges | None = None,
                        state_prior: StatePrior | None = None) -> ODResult:
    """Gauss-Newton weighted least squares of x = [ROE at t_est (6), da_dot] (module docstring); converged when the
    step's Mahalanobis length sqrt(dx^T H^T W H dx) is below ``tol`` (a fraction of one sigma).

    Parameters
    ----------
    batch : RadarBatch
        The measurements and the carrier's mean elements.
    t_est, x0 : float, array_like, optional
        The estimate epoch [s] (default the last measurement's) and the start (default :func:`initial_guess`).
    j2, drag : bool
        With the J2 secular rates; with the model's drag terms.
    max_iterations, tol : int, float
        The Gauss-Newton limits.
    prior, model : DriftPrior, DragModel, optional
        The a priori row (already carried to ``t_est``); the drift rate's growth (:func:`drift_growth`).
    bias : RangeBiasPrior, optional
        Estimate a range bias per station with its a priori information (the result's ``range_bias``).
    carrier : CarrierRanges, optional
        The stations' ranges to the carrier: more information on the biases (ignored without ``bias``).
    state_prior : StatePrior, optional
        A priori information on the whole state at ``t_est`` (a prediction: one pass then gives a solution).

    Returns
    -------
    ODResult
        The solution; ValueError with the reason for too few or non-finite measurements, an unobservable state
        (singular normal matrix) or no convergence.
    """
    _check(batch)
    t_est = float(np.max(batch.t)) if t_est is None else float(t_est)
    x = initial_guess(batch, t_est, j2, drag) if x0 is None else np.array(x0, dtype=float)
    w = 1.0 / np.asarray(batch.sigma, dtype=float).reshape(-1)
    a_chief = _chief_a_inc(batch)[0]
    decay = chief_decay(batch)
    ecc = chief_eccentricity(batch, t_est) if drag and model is not None else None  # constants of the batch
    index, n_bias = station_index(batch) if bias is not None else (None, 0)
    b = np.zeros(n_bias)  # the stations' range biases [m]
    c_index, c_res, c_sigma = carrier.rows(batch) if n_bias and carrier is not None else (np.zeros(0, int),) * 3
    c_rows = np.zeros((c_index.size, STATE_SIZE + n_bias))  # the carrier's rows: partials on their station's bias
    c_rows[np.arange(c_index.size), STATE_SIZE + c_index] = 1.0 / c_sigma if c_index.size else 0.0

    def unbiased(b: np.ndarray) -> np.ndarray:
        if not n_bias:
            return batch.z
        z = np.array(batch.z, dtype=float)
        z[:, 0] -= b[index]
        return z

    def whitened(x: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
        r = measurement_residual(unbiased(b), predict(x, batch, t_est, j2, drag, model=model, decay=decay,
                                                      ecc=ecc)).reshape(-1) * w
        rows = []  # the a priori rows: (residuals, partials over the state and the biases)
        if prior is not None:
            r_p, h_p = prior.residual_row(x, a_chief)
            rows.append((np.atleast_1d(r_p), np.append(h_p, np.zeros(n_bias))[None, :]))
        if state_prior is not None:
            r_s, h_s = state_prior.rows(x)
            rows.append((r_s, np.hstack([h_s, np.zeros((STATE_SIZE, n_bias))])))
        if not rows:
            return r, None
        return np.concatenate([r, *(q for q, _ in rows)]), np.vstack([h for _, h in rows])

    for iteration in range(1, max_iterations + 1):
        r, h_p = whitened(x, b)
        h = jacobian(x, batch, t_est, j2, drag, model=model, decay=decay, ecc=ecc).reshape(-1, STATE_SIZE) * w[:, None]
        if n_bias:
            h = np.hstack([h, _bias_columns(index, n_bias, w)])
        if h_p is not None:
            h = np.vstack([h, h_p])
        if n_bias:  # the biases' a priori rows, then the carrier's ranges
            r = np.concatenate([r, -b / bias.sigma, (c_res - b[c_index]) / c_sigma])
            h = np.vstack([h, np.hstack([np.zeros((n_bias, STATE_SIZE)), np.eye(n_bias) / bias.sigma]), c_rows])
        scale = np.linalg.norm(h, axis=0)
        if not np.all(scale > 0.0):
            raise ValueError(f"singular normal matrix: state component(s) {np.nonzero(~(scale > 0.0))[0].tolist()}"
                             " have zero partials (not observable from these measurements)")
        u_, sv, vt = np.linalg.svd(h / scale, full_matrices=False)
        cond = sv[0] / sv[-1] if sv[-1] > 0.0 else np.inf
        if not cond < MAX_CONDITION:
            raise ValueError(f"singular normal matrix (condition number {cond:.3g} of the scaled design matrix): "
                             "the measurements do not determine the relative orbit and da_dot")
        dy = vt.T @ ((u_.T @ r) / sv)
        step = dy / scale
        x = x + step[:STATE_SIZE]
        b = b + step[STATE_SIZE:]
        if np.linalg.norm(sv * (vt @ dy)) < tol:
            break
    else:
        raise ValueError(f"Gauss-Newton did not converge in {max_iterations} iterations")
    r = measurement_residual(unbiased(b), predict(x, batch, t_est, j2, drag, model=model, decay=decay,
                                                  ecc=ecc)).reshape(-1) * w
    full = (vt.T / sv**2) @ vt / np.outer(scale, scale)  # at the last step's Jacobian (a priori rows included)
    full = 0.5 * (full + full.T)
    k = np.argmax(batch.t)
    chief_est = propagate_chief(batch.chief[k], t_est - batch.t[k])
    return ODResult(x=x, cov=full[:STATE_SIZE, :STATE_SIZE], t_est=t_est,
                    residual_rms=float(np.sqrt(np.mean(r * r))), iterations=iteration,
                    measurements=int(np.shape(batch.t)[0]), a_est=float(chief_est[0]),
                    u_est=float(chief_est[4] + chief_est[5]), drag=drag,
                    range_bias=tuple(float(v) for v in b),
                    range_bias_cov=tuple(float(v) for v in full[STATE_SIZE:, STATE_SIZE:].reshape(-1)))


def nees(x_est: ArrayLike, x_true: ArrayLike, cov: ArrayLike) -> float:
    """Normalized estimation error squared e^T P^-1 e, e = x_est - x_true (chi-square with dim(x) degrees of
    freedom for a consistent estimator; Bar-Shalom, Li, Kirubarajan 2001, Sec. 5.4).

    Parameters
    ----------
    x_est, x_true, cov : array_like, shapes (n,), (n,), (n, n)
        The estimate, the truth and the estimate's covariance.

    Returns
    -------
    float
        The NEES.
    """
    e = np.asarray(x_est, dtype=float) - np.asarray(x_true, dtype=float)
    return float(e @ np.linalg.solve(np.asarray(cov, dtype=float), e))

