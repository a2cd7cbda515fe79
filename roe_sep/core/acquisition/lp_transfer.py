"""Linear maps from candidate impulsive carrier burns on a time grid to the relative state: the building blocks of
linear-programming maneuver planners.

Two facts make the relative state affine in the burns:

* an impulse changes the ROE linearly, seed 002 Eq. (2) (:func:`~roe_sep.core.relmotion.maneuvers.delta_roe`; a carrier
  burn ``dv`` acts as the relative impulse ``-dv``);
* the secular model of :func:`~roe_sep.core.relmotion.dynamics.propagate` (Keplerian drift, J2, differential drag) is
  affine in the ROE: ``propagate(x, dt, da_dot) = Phi(dt) x + propagate(0, dt, da_dot)``, where the drag term does not
  depend on the state.

So the ROE at a time t after burns ``dv_k`` at epochs ``t_k <= t`` are
``x(t) = propagate(x0, t - t0, da_dot) + sum_k Phi(t - t_k) delta_roe(-dv_k, u_k)``. Every matrix here is built by
propagating vectors with :func:`propagate` itself (never a re-derived transition matrix), so planners built on
them predict exactly what :func:`~roe_sep.core.relmotion.trajectory.trajectory` later verifies.
"""

import math

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import arg_latitude_rate, propagate
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import mean_motion
from ..relmotion.trajectory import Chief

AXES = {"R": 0, "T": 1, "N": 2}
"""RTN axis letters -> column of ``dv_rtn``."""

MAX_GRID_EPOCHS = 2500
"""Guard on the candidate grid (about 10 days at 16 per orbit): the dense path-constraint block (``grid_response``,
built only with the acquisition LP's ``SPARSE_PATH`` off) is O(K^2) in memory."""


def parse_axes(axes: str) -> tuple[int, ...]:
    """RTN axis letters, e.g. ``"TN"``, -> sorted tuple of dv columns ``(1, 2)``; raises ValueError if malformed."""
    if not isinstance(axes, str) or not axes:
        raise ValueError(f"axes must be a non-empty string of R, T, N, got {axes!r}")
    letters = axes.upper()
    if any(c not in AXES for c in letters) or len(set(letters)) != len(letters):
        raise ValueError(f"axes must be distinct letters among R, T, N, got {axes!r}")
    return tuple(sorted(AXES[c] for c in letters))


def grid_epochs(t_start: float, t_end: float, chief: Chief, per_orbit: int, j2: bool = True) -> np.ndarray:
    """Candidate burn epochs [s] in ``[t_start, t_end]``: where the chief's mean argument of latitude is a multiple
    of 2 pi / ``per_orbit`` (secular rate of :meth:`Chief.u_at`), i.e. a uniform grid of spacing
    (2 pi / per_orbit) / (du/dt) aligned with round values of u (u = 0, 22.5 deg, ... for 16 per orbit).

    Parameters
    ----------
    t_start, t_end : float
        The interval [s].
    chief : Chief
        The chief's a, i and argument of latitude.
    per_orbit : int
        Grid epochs per orbit.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (K,)
        The epochs [s]; ValueError beyond :data:`MAX_GRID_EPOCHS`.
    """
    rate = float(arg_latitude_rate(chief.a, chief.inc, j2))
    du = 2.0 * math.pi / per_orbit
    u_start = float(chief.u_at(t_start, j2))
    first = t_start + (math.ceil(u_start / du - 1e-9) * du - u_start) / rate
    step = du / rate
    count = math.floor((t_end - first) / step + 1e-9) + 1
    if count > MAX_GRID_EPOCHS:
        raise ValueError(f"{count} candidate epochs exceed {MAX_GRID_EPOCHS}: shorten the window or the grid")
    return first + step * np.arange(max(count, 0))


def transition_matrices(dt: ArrayLike, a: float, inc: float, j2: bool = True) -> np.ndarray:
    """The state transition Phi(dt) ``(..., 6, 6)`` of the secular model without drag: column c is
    :func:`propagate` of the unit ROE vector e_c over ``dt`` (the model is linear in the ROE for da_dot = 0).

    Parameters
    ----------
    dt : array_like, shape (...)
        Propagation times [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (..., 6, 6)
        Phi(dt).
    """
    dt = np.asarray(dt, dtype=float)
    columns = propagate(np.eye(6), dt[..., None], a, inc, j2)  # (..., column c, component)
    return np.swapaxes(columns, -1, -2)


def drift_offset(dt: ArrayLike, a: float, inc: float, j2: bool = True, da_dot: float = 0.0) -> np.ndarray:
    """The affine (state-independent) part of :func:`propagate` over ``dt``: differential drag, ``(..., 6)``.

    Parameters
    ----------
    dt : array_like, shape (...)
        Propagation times [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2, da_dot : bool, float
        With the J2 secular rates; the differential-drag rate of da [1/s].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The dimensionless ROE offset.
    """
    dt = np.asarray(dt, dtype=float)
    return propagate(np.zeros(6), dt, a, inc, j2, da_dot=da_dot)


def carrier_burn_effects(epochs: ArrayLike, axes: tuple[int, ...], chief: Chief, j2: bool = True) -> np.ndarray:
    """Dimensionless ROE change per 1 m/s carrier burn along each axis, ``(K, len(axes), 6)``.

    seed 002 Eq. (2) through :func:`delta_roe` with the relative impulse ``-dv`` of a carrier burn, at the chief's
    mean argument of latitude of each epoch.

    Parameters
    ----------
    epochs : array_like, shape (K,)
        Burn epochs [s].
    axes : tuple of int
        The dv columns (:func:`parse_axes`).
    chief : Chief
        The chief's a, i and argument of latitude.
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (K, J, 6)
        The effects.
    """
    u = np.asarray(chief.u_at(np.asarray(epochs, dtype=float), j2))
    units = -np.eye(3)[list(axes)]  # (J, 3): relative impulse of a +1 m/s carrier burn along each axis
    return delta_roe(units[None, :, :], u[:, None], chief.a, mean_motion(chief.a))


def response_at(effects: np.ndarray, epochs: ArrayLike, t: float, a: float, inc: float, *,
                j2: bool = True) -> np.ndarray:
    """ROE change at one time ``t >= max(epochs)`` per unit burn: Phi(t - t_k) effects[k, j], ``(K, J, 6)``.

    Parameters
    ----------
    effects : numpy.ndarray, shape (K, J, 6)
        :func:`carrier_burn_effects`.
    epochs : array_like, shape (K,)
        Their epochs [s].
    t : float
        The time [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (K, J, 6)
        The responses.
    """
    phi = transition_matrices(t - np.asarray(epochs, dtype=float), a, inc, j2)  # (K, 6, 6)
    return np.einsum("kcd,kjd->kjc", phi, effects)


def grid_response(effects: np.ndarray, step: float, a: float, inc: float, j2: bool = True, *,
                  component: int = 1) -> np.ndarray:
    """Response of one ROE ``component`` at every grid epoch to every candidate burn on a *uniform* grid.

    ``R[i, k, j] = (Phi((i - k) step) effects[k, j])[component]`` for i >= k (a burn acts on the state at its own
    epoch, as in :func:`~roe_sep.core.relmotion.trajectory.trajectory`), 0 for i < k. Phi depends only on the lag i -
    k, so K transition matrices serve the whole lower-triangular block (vectorized, no loop over epochs).

    Parameters
    ----------
    effects : numpy.ndarray, shape (K, J, 6)
        :func:`carrier_burn_effects` on the grid.
    step : float
        The grid spacing [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2, component : bool, int
        With the J2 secular rates; the ROE component.

    Returns
    -------
    numpy.ndarray, shape (K, K, J)
        R.
    """
    k_count = effects.shape[0]
    rows = transition_matrices(step * np.arange(k_count), a, inc, j2)[:, component, :]  # (lag, 6)
    by_lag = np.einsum("mc,kjc->mkj", rows, effects)  # (lag, k, j)
    lag = np.arange(k_count)[:, None] - np.arange(k_count)[None, :]
    out = by_lag[np.maximum(lag, 0), np.arange(k_count)[None, :], :]
    out[lag < 0] = 0.0
    return out


def sagitta(step: float, a: float, inc: float, j2: bool = True, da_dot: float = 0.0, *,
            component: int = 1) -> float:
    """Largest dip of a ROE ``component`` between two grid epochs below the chord through its end values.

    Between burns the secular model is at most quadratic in time (differential drag makes da linear, dl
    quadratic), so the dip is the sagitta |x(step/2) - (x(0) + x(step))/2| of the drag term.

    Parameters
    ----------
    step : float
        The grid spacing [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2, da_dot : bool, float
        With the J2 secular rates; the differential-drag rate of da [1/s].
    component : int
        The ROE component.

    Returns
    -------
    float
        The sagitta (dimensionless).
    """
    x = drift_offset(np.array([0.0, 0.5 * step, step]), a, inc, j2, da_dot)[:, component]
    return float(abs(x[1] - 0.5 * (x[0] + x[2])))
