"""The carrier camera's check of the ejection before the blind drift-stop, without ROS: the bearing measurement
model, the bearings the commanded ejection predicts for a fraction f1 of its impulse, and the test whether the bearing
history says the SPL delivered far less than commanded (a weak ejection, ``spl_weak``).

Why bearings can say anything about f1: in the linear relative motion (seed 002 Eq. 2 and the secular propagation,
J2 included) a single impulse from a common origin gives a trajectory proportional to the impulse, so a scaled
ejection flies the same lines of sight (angles-only cannot observe the scale of a pure impulse). The differential
drag (seed 002 Eqs. 23-24) adds an along-track offset of about 0.75 n a da_dot t^2 (47 m 2.4 h after the ejection
of the default scenario) that does not scale with the impulse: against a trajectory f1 times smaller it turns the
line of sight 1/f1 times more. The default scenario's numbers (secular model, the drift-stop 8554 s after the
ejection): the largest bearing difference to the nominal ejection is 0.13 deg for f1 = 0.5, 0.30 deg for 0.3,
1.1 deg for 0.1 and 5 deg for 0.02; 0.03 deg for f1 = 0.8. So a camera of a few hundredths of a degree separates
f1 <~ 0.3 from the nominal SPL (f1 ~ N(1, 0.1), Eq. 22), not f1 = 0.5 against the model's own error and the drag's
20 % uncertainty (docs/contingencies.md).

The carrier points the camera along the line of sight the commanded ejection predicts: by the scale invariance a
weak ejection stays near it (a few degrees at most), within the field of view of Eq. 11.
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy import stats

from ..relmotion.roe import roe_to_rtn
from ..relmotion.trajectory import Burn, Chief, trajectory


@dataclass(frozen=True)
class EjectionCheck:
    """The camera's verdict on the ejection: the best-fitting fraction ``f1`` of the commanded impulse, the
    chi-square ``gain`` of it over the best nominal fraction, the ``samples`` used, and ``weak`` (hold the
    drift-stop)."""

    f1: float
    gain: float
    samples: int
    weak: bool


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


def predicted_los(f1: float, dv_commanded: ArrayLike, t_ejection: float, chief: Chief, da_dot: float,
                  times: ArrayLike, j2: bool = True) -> np.ndarray:
    """The unit lines of sight ``(m, 3)`` (carrier RTN) at ``times`` [s] after an ejection of ``f1`` times the
    commanded impulse at ``t_ejection`` [s]: seed 002 Eq. 2 for the impulse, the secular propagation with the
    differential drag ``da_dot`` (Eqs. 23-24), the linear RTN map.

    Parameters
    ----------
    f1 : float
        The fraction of the commanded impulse delivered.
    dv_commanded : array_like, shape (3,)
        The commanded ejection [m/s], the picosatellite's, RTN.
    t_ejection : float
        The ejection epoch [s] (the deployer's release).
    chief : Chief
        The carrier's a [m], i [rad] and mean argument of latitude u0 [rad] at t0 [s].
    da_dot : float
        The differential-drag rate of da [1/s].
    times : array_like, shape (m,)
        The epochs [s], after ``t_ejection``.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (m, 3)
        The unit lines of sight (NaN rows where the position is zero).
    """
    t = np.asarray(times, dtype=float)
    burn = Burn(float(t_ejection), tuple(float(f1) * np.asarray(dv_commanded, dtype=float)))
    roe = trajectory(np.zeros(6), float(t_ejection), [burn], t, chief, j2, da_dot)
    pos, _ = roe_to_rtn(roe * chief.a, chief.u_at(t, j2))
    with np.errstate(invalid="ignore", divide="ignore"):
        return pos / np.linalg.norm(pos, axis=1, keepdims=True)


def bearing_cost(measured: ArrayLike, predicted: ArrayLike, sigma: float) -> float:
    """Chi-square of measured against predicted unit lines of sight ``(m, 3)``: the sum of the squared angle errors
    (both axes) over ``sigma`` [rad] squared, rows with a NaN left out."""
    d = np.asarray(measured, dtype=float) - np.asarray(predicted, dtype=float)
    ok = np.all(np.isfinite(d), axis=1)
    return float(np.sum(d[ok] ** 2)) / (sigma * sigma)


def check_ejection(times: ArrayLike, measured: ArrayLike, dv_commanded: ArrayLike, t_ejection: float,
                   chief: Chief, da_dot: float, sigma: float, spl_sigma: float, hold_fraction: float,
                   alpha: float, j2: bool = True) -> EjectionCheck:
    """Whether the camera's bearing history says the ejection was weak: the fraction f1 (a grid of 0.01 in [0,
    1.5]) whose predicted lines of sight (:func:`predicted_los`) fit the measured ones best, against the best one
    within three sigmas of the nominal SPL (f1 ~ N(1, ``spl_sigma``), seed 002 Eq. 22). ``weak`` when the best f1 is
    below ``hold_fraction`` and fits better by more than the chi-square(1) quantile 1 - ``alpha``.

    Parameters
    ----------
    times : array_like, shape (m,)
        The measurement epochs [s], after ``t_ejection``.
    measured : array_like, shape (m, 3)
        The measured unit lines of sight, carrier RTN (:func:`camera_bearing`).
    dv_commanded : array_like, shape (3,)
        The commanded ejection [m/s], RTN.
    t_ejection : float
        The ejection epoch [s] (the deployer's release switch).
    chief : Chief
        The carrier's a [m], i [rad] and mean argument of latitude u0 [rad] at t0 [s].
    da_dot : float
        The nominal differential-drag rate of da [1/s].
    sigma : float
        The 1-sigma bearing error per axis [rad], the model's error included.
    spl_sigma : float
        The SPL's 1-sigma magnitude error (fraction).
    hold_fraction : float
        The largest f1 that holds the drift-stop.
    alpha : float
        The false-alarm probability of the test (chi-square, 1 dof).
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    EjectionCheck
        The best f1, its chi-square gain over the nominal SPL, the samples used and the verdict.
    """
    t = np.asarray(times, dtype=float)
    meas = np.asarray(measured, dtype=float).reshape(-1, 3)
    keep = np.all(np.isfinite(meas), axis=1) & (t > t_ejection)
    t, meas = t[keep], meas[keep]
    if len(t) == 0:
        return EjectionCheck(math.nan, 0.0, 0, False)
    grid = np.round(np.arange(0.0, 1.5 + 1e-9, 0.01), 2)
    cost = np.array([bearing_cost(meas, predicted_los(f, dv_commanded, t_ejection, chief, da_dot, t, j2), sigma)
                     for f in grid])
    best = int(np.argmin(cost))
    nominal = np.abs(grid - 1.0) <= 3.0 * spl_sigma
    gain = float(np.min(cost[nominal]) - cost[best])
    weak = bool(grid[best] < hold_fraction and gain > float(stats.chi2.isf(alpha, 1)))
    return EjectionCheck(float(grid[best]), gain, int(len(t)), weak)
