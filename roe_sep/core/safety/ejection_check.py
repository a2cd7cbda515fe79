"""The carrier camera's check of the ejection before the blind drift-stop, without ROS: the bearing measurement
model (the simulator's camera), the lines of sight the commanded ejection predicts for a fraction f1 of its impulse,
and the test whether the bearing history says the SPL delivered far less than commanded (a weak ejection,
``spl_weak``), which the planner acts on. Measurements and history: docs/contingencies.md, "A weak ejection holds
the blind drift-stop".

What bearings observe. In the linear relative motion (seed 002 Eq. 2, the secular propagation with J2) a single
impulse from a common origin flies lines of sight that do not depend on its scale; the differential drag (seed 002
Eqs. 23-24) adds an along-track offset of about 0.75 n a da_dot t^2 that does not scale. The relative position is
f1 X(t) + g Y(t) (X the commanded impulse's, Y the nominal drag's, g the true drag over the nominal), so its
direction depends on g / f1 alone: the camera measures the *apparent* fraction f1 / g.

The nominal set: f1 ~ N(1, ``spl_sigma``) (seed 002 Eq. 22) and g ~ N(1, ``ballistic_sigma``) give f1 / g >=
(1 - k spl_sigma) / (1 + k ballistic_sigma) for k sigmas of both (:func:`nominal_fraction`).

The model (:func:`predicted_los`): the camera sees the osculating relative position in the carrier's osculating RTN
frame. The impulse is applied to the carrier's osculating state, both spacecraft are turned into mean elements
(first-order Brouwer-Lyddane, :mod:`roe_sep.core.truth.mean_osc`), the mean ROE propagate secularly (J2, drag) and
are turned back into the osculating relative position. A position floor ``floor`` gives a bearing error of
sqrt(sigma^2 + (floor / rho)^2) per axis at the predicted range rho, besides the camera's sigma (an assumption:
centroid and attitude knowledge; no seed gives it).

The test (:func:`check_ejection`): the best apparent fraction on a grid against the best one in the nominal set
(>= the bound); weak when the chi-square gain exceeds the chi-square(1) quantile 1 - alpha. The carrier points the
camera along the predicted line of sight: a weak ejection stays near it, within the field of view of Eq. 11.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import propagate_chief
from ..relmotion.roe import roe_to_kepler
from ..relmotion.trajectory import Chief, trajectory
from ..truth.nonlinear import apply_impulse, mean_roe, pair_state, relative_rtn

FRACTIONS = np.round(np.arange(0.0, 2.0 + 1e-9, 0.01), 2)
"""The grid of apparent fractions f1 / g the test fits (0.01 steps)."""


CAMERA_SIGMA_DEG = 0.02
"""deg, 1-sigma bearing error per axis of the carrier camera: the simulator's sensor and what the planner's test
assumes by default (centroid and attitude knowledge; an assumption, no seed gives it)."""


@dataclass(frozen=True)
class EjectionCheck:
    """The camera's verdict on the ejection: the best-fitting apparent fraction ``f1`` (f1 / g, the SPL's fraction
    over the drag's) of the commanded impulse, the chi-square ``gain`` of it over the best one in the nominal set,
    the ``samples`` used, the nominal set's lower ``bound`` and ``weak`` (hold the drift-stop)."""

    f1: float
    gain: float
    samples: int
    weak: bool
    bound: float


def camera_bearing(pos_rtn: ArrayLike, sigma: float, rng: np.random.Generator) -> np.ndarray:
    """The camera's measured line of sight ``(m, 3)`` (unit vectors, carrier RTN) to the picosatellite at the
    relative positions ``pos_rtn`` ``(m, 3)`` [m]: the true direction turned by independent normal angles of
    ``sigma`` [rad] about two axes normal to it (the centroid and attitude errors of one image).

    Parameters
    ----------
    pos_rtn : array_like, shape (m, 3)
        The picosatellite's position relative to the carrier [m], RTN.
    sigma : float
        The 1-sigma bearing error per axis [rad].
    rng : numpy.random.Generator
        The noise's generator (two normal draws per sample).

    Returns
    -------
    numpy.ndarray, shape (m, 3)
        The measured unit lines of sight (NaN rows for a zero position).
    """
    p = np.atleast_2d(np.asarray(pos_rtn, dtype=float))
    r = np.linalg.norm(p, axis=1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = p / r
    e1, e2 = normal_axes(u)
    w = rng.normal(0.0, sigma, size=(len(p), 2))
    out = u + w[:, :1] * e1 + w[:, 1:] * e2
    return out / np.linalg.norm(out, axis=1, keepdims=True)


def normal_axes(u: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Two unit axes ``(m, 3)`` each, normal to the unit vectors ``u`` ``(m, 3)`` and to each other."""
    u = np.atleast_2d(np.asarray(u, dtype=float))
    ref = np.where(np.abs(u[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 0.0, 1.0]])
    e1 = np.cross(u, ref)
    e1 /= np.linalg.norm(e1, axis=1, keepdims=True)
    return e1, np.cross(u, e1)


def nominal_fraction(spl_sigma: float, drag_sigma: float, sigmas: float = 3.0) -> float:
    """The smallest apparent fraction f1 / g of a nominal ejection: (1 - k ``spl_sigma``) / (1 + k ``drag_sigma``)
    with k = ``sigmas``, not below 0 (0.4375 for 0.1, 0.2 and 3).

    Parameters
    ----------
    spl_sigma : float
        The SPL's 1-sigma magnitude error (fraction, seed 002 Eq. 22).
    drag_sigma : float
        The differential ballistic coefficient's relative 1-sigma error.
    sigmas : float
        k: the nominal set's half-width in sigmas of both.

    Returns
    -------
    float
        The bound (dimensionless).
    """
    return max(0.0, (1.0 - sigmas * spl_sigma) / (1.0 + sigmas * drag_sigma))


def predicted_los(fractions: ArrayLike, dv_commanded: ArrayLike, t_ejection: float, chief_mean: ArrayLike,
                  da_dot: float, *, times: ArrayLike, j2: bool = True) -> np.ndarray:
    """The unit lines of sight ``(F, m, 3)`` (carrier osculating RTN) at ``times`` [s] after ejections of each of
    ``fractions`` ``(F,)`` times the commanded impulse at ``t_ejection`` [s]: the impulse on the carrier's osculating
    state, mean ROE of the pair (first-order Brouwer-Lyddane, Eq. 1), their secular propagation with J2 and the
    differential drag ``da_dot`` (seed 002 Eqs. 23-24), back to the osculating relative position (module docstring).

    Parameters
    ----------
    fractions : array_like, shape (F,)
        The fractions of the commanded impulse delivered.
    dv_commanded : array_like, shape (3,)
        The commanded ejection [m/s], the picosatellite's, RTN.
    t_ejection : float
        The ejection epoch [s] (the deployer's release).
    chief_mean : array_like, shape (6,)
        The carrier's mean elements [a m, e, i rad, raan rad, argp rad, M rad] at ``t_ejection``.
    da_dot : float
        The differential-drag rate of da [1/s].
    times : array_like, shape (m,)
        The epochs [s], after ``t_ejection``.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (F, m, 3)
        The unit lines of sight (NaN rows where the position is zero).
    """
    pos = _positions(fractions, dv_commanded, t_ejection, chief_mean, da_dot, times=times, j2=j2)
    with np.errstate(invalid="ignore", divide="ignore"):
        return pos / np.linalg.norm(pos, axis=-1, keepdims=True)


def predicted_positions(fractions: ArrayLike, dv_commanded: ArrayLike, t_ejection: float, chief_mean: ArrayLike,
                        da_dot: float, *, times: ArrayLike, j2: bool = True) -> np.ndarray:
    """The osculating relative positions ``(F, m, 3)`` [m] (carrier osculating RTN) whose directions
    :func:`predicted_los` gives: the same parameters (see there), the same model.

    Parameters
    ----------
    fractions, dv_commanded : array_like, shapes (F,) and (3,)
        The fractions of the commanded impulse [m/s, RTN] delivered.
    t_ejection, chief_mean : float, array_like of shape (6,)
        The ejection epoch [s]; the carrier's mean elements there.
    da_dot : float
        The differential-drag rate of da [1/s].
    times : array_like, shape (m,)
        The epochs [s], after ``t_ejection``.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (F, m, 3)
        The relative positions [m].
    """
    return _positions(fractions, dv_commanded, t_ejection, chief_mean, da_dot, times=times, j2=j2)


def _positions(fractions, dv_commanded, t_ejection, chief_mean, da_dot, *, times, j2):
    """The relative positions ``(F, m, 3)`` [m] of :func:`predicted_los`."""
    f = np.atleast_1d(np.asarray(fractions, dtype=float))
    t = np.atleast_1d(np.asarray(times, dtype=float))
    kep = np.asarray(chief_mean, dtype=float)
    dv = np.asarray(dv_commanded, dtype=float)
    start = np.broadcast_to(pair_state(kep, kep), f.shape + (12,))
    roe0 = mean_roe(apply_impulse(start, f[:, None] * dv, np.ones(f.shape, dtype=bool)))  # (F, 6)
    chief = Chief(float(kep[0]), float(kep[2]), float(kep[4] + kep[5]), float(t_ejection))
    roe = np.stack([trajectory(r, float(t_ejection), [], t, chief, j2=j2, da_dot=da_dot) for r in roe0])  # (F, m, 6)
    kc = propagate_chief(kep, t - float(t_ejection), j2)
    kc[..., 3:] = np.mod(kc[..., 3:], 2.0 * math.pi)  # the conversions want angles in one turn
    kc = np.broadcast_to(kc, roe.shape)
    return relative_rtn(pair_state(kc, roe_to_kepler(kc, roe)))[0]


def bearing_cost(measured: ArrayLike, predicted: ArrayLike, sigma: ArrayLike) -> np.ndarray:
    """Chi-square of measured against predicted unit lines of sight: the sum of the squared angle errors (both
    axes) over ``sigma`` squared, rows with a NaN left out.

    Parameters
    ----------
    measured : array_like, shape (m, 3)
        The measured unit lines of sight.
    predicted : array_like, shape (..., m, 3)
        The predicted unit lines of sight (one set per leading index).
    sigma : array_like, scalar or shape (m,)
        The 1-sigma angle error per axis [rad], one for all or one per sample.

    Returns
    -------
    numpy.ndarray, shape (...)
        The chi-square of each predicted set.
    """
    d = np.asarray(predicted, dtype=float) - np.asarray(measured, dtype=float)
    w = np.broadcast_to(1.0 / np.asarray(sigma, dtype=float) ** 2, d.shape[-2:-1])
    ok = np.all(np.isfinite(d), axis=-1)
    return np.sum(np.where(ok, np.sum(np.where(ok[..., None], d, 0.0) ** 2, axis=-1) * w, 0.0), axis=-1)


def check_ejection(times: ArrayLike, measured: ArrayLike, dv_commanded: ArrayLike, t_ejection: float,
                   chief_mean: ArrayLike, *, da_dot: float, sigma: float, floor: float, bound: float, alpha: float,
                   j2: bool = True) -> EjectionCheck:
    """Whether the camera's bearing history says the ejection was weak: the apparent fraction f1 / g on
    :data:`FRACTIONS` whose predicted lines of sight (:func:`predicted_los`, the nominal drag) fit the measured ones
    best, against the best one in the nominal set (>= ``bound``, :func:`nominal_fraction`). ``weak`` when the best is
    below ``bound`` and fits better by more than the chi-square(1) quantile 1 - ``alpha`` (module docstring).

    Parameters
    ----------
    times, measured : array_like, shapes (m,) and (m, 3)
        The measurement epochs [s] after ``t_ejection``; the measured unit lines of sight, carrier RTN
        (:func:`camera_bearing`).
    dv_commanded, t_ejection : array_like, shape (3,); float
        The commanded ejection [m/s], RTN; its epoch [s] (the deployer's release switch).
    chief_mean : array_like, shape (6,)
        The carrier's mean elements [a m, e, i rad, raan rad, argp rad, M rad] at ``t_ejection``.
    da_dot : float
        The nominal differential-drag rate of da [1/s].
    sigma, floor : float
        The camera's 1-sigma bearing error per axis [rad]; the model's 1-sigma position error [m] against the truth.
    bound, alpha : float
        The smallest apparent fraction of a nominal ejection (:func:`nominal_fraction`); the test's false-alarm
        probability (chi-square, 1 dof).
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    EjectionCheck
        The best apparent fraction, its chi-square gain, the samples used, the verdict and the bound.
    """
    t = np.asarray(times, dtype=float).reshape(-1)
    meas = np.asarray(measured, dtype=float).reshape(-1, 3)
    keep = np.all(np.isfinite(meas), axis=1) & (t > t_ejection)
    t, meas = t[keep], meas[keep]
    if len(t) == 0:
        return EjectionCheck(math.nan, 0.0, 0, False, float(bound))
    los = predicted_los(FRACTIONS, dv_commanded, t_ejection, chief_mean, da_dot, times=t, j2=j2)
    rho = np.linalg.norm(_positions(1.0, dv_commanded, t_ejection, chief_mean, da_dot, times=t, j2=j2)[0], axis=-1)
    sig = np.sqrt(sigma * sigma + (floor / np.maximum(rho, 1e-3)) ** 2)
    cost = bearing_cost(meas, los, sig)
    cost = np.where(np.isfinite(cost), cost, np.inf)
    best = int(np.argmin(cost))
    nominal = FRACTIONS >= bound - 1e-12
    gain = float(np.min(cost[nominal]) - cost[best])
    from scipy.special import chdtri  # here, not at import: the parameter tables import this module's constants

    weak = bool(FRACTIONS[best] < bound and gain > float(chdtri(1, alpha)))  # chi2.isf(alpha, 1): the same floats
    return EjectionCheck(float(FRACTIONS[best]), gain, int(len(t)), weak, float(bound))

