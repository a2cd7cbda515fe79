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

from ..relmotion.dynamics import arg_latitude_rate, propagate
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import mean_motion

AXES = {"R": 0, "T": 1, "N": 2}
"""RTN axis letters -> column of ``dv_rtn``."""

MAX_GRID_EPOCHS = 2500
"""Guard on the candidate grid (about 10 days at 16 per orbit): the path-constraint block is O(K^2) in memory."""


def parse_axes(axes):
    """RTN axis letters, e.g. ``"TN"``, -> sorted tuple of dv columns ``(1, 2)``; raises ValueError if malformed."""
    if not isinstance(axes, str) or not axes:
        raise ValueError(f"axes must be a non-empty string of R, T, N, got {axes!r}")
    letters = axes.upper()
    if any(c not in AXES for c in letters) or len(set(letters)) != len(letters):
        raise ValueError(f"axes must be distinct letters among R, T, N, got {axes!r}")
    return tuple(sorted(AXES[c] for c in letters))


def grid_epochs(t_start, t_end, chief, per_orbit, j2=True):
    """Candidate burn epochs [s] in ``[t_start, t_end]``: where the chief's mean argument of latitude is a multiple
    of 2 pi / ``per_orbit`` (secular rate of :meth:`Chief.u_at`), i.e. a uniform grid of spacing
    (2 pi / per_orbit) / (du/dt) aligned with round values of u (u = 0, 22.5 deg, ... for 16 per orbit)."""
    rate = float(arg_latitude_rate(chief.a, chief.inc, j2))
    du = 2.0 * math.pi / per_orbit
    u_start = float(chief.u_at(t_start, j2))
    first = t_start + (math.ceil(u_start / du - 1e-9) * du - u_start) / rate
    step = du / rate
    count = math.floor((t_end - first) / step + 1e-9) + 1
    if count > MAX_GRID_EPOCHS:
        raise ValueError(f"{count} candidate epochs exceed {MAX_GRID_EPOCHS}: shorten the window or the grid")
    return first + step * np.arange(max(count, 0))


def transition_matrices(dt, a, inc, j2=True):
    """The state transition Phi(dt) ``(..., 6, 6)`` of the secular model without drag: column c is
    :func:`propagate` of the unit ROE vector e_c over ``dt`` (the model is linear in the ROE for da_dot = 0)."""
    dt = np.asarray(dt, dtype=float)
    columns = propagate(np.eye(6), dt[..., None], a, inc, j2)  # (..., column c, component)
    return np.swapaxes(columns, -1, -2)


def drift_offset(dt, a, inc, j2=True, da_dot=0.0):
    """The affine (state-independent) part of :func:`propagate` over ``dt``: differential drag, ``(..., 6)``."""
    dt = np.asarray(dt, dtype=float)
    return propagate(np.zeros(6), dt, a, inc, j2, da_dot)


def carrier_burn_effects(epochs, axes, chief, j2=True):
    """Dimensionless ROE change per 1 m/s carrier burn along each axis, ``(K, len(axes), 6)``.

    seed 002 Eq. (2) through :func:`delta_roe` with the relative impulse ``-dv`` of a carrier burn, at the chief's
    mean argument of latitude of each epoch.
    """
    u = np.asarray(chief.u_at(np.asarray(epochs, dtype=float), j2))
    units = -np.eye(3)[list(axes)]  # (J, 3): relative impulse of a +1 m/s carrier burn along each axis
    return delta_roe(units[None, :, :], u[:, None], chief.a, mean_motion(chief.a))


def response_at(effects, epochs, t, a, inc, *, j2=True):
    """ROE change at one time ``t >= max(epochs)`` per unit burn: Phi(t - t_k) effects[k, j], ``(K, J, 6)``."""
    phi = transition_matrices(t - np.asarray(epochs, dtype=float), a, inc, j2)  # (K, 6, 6)
    return np.einsum("kcd,kjd->kjc", phi, effects)


def grid_response(effects, step, a, inc, j2=True, *, component=1):
    """Response of one ROE ``component`` at every grid epoch to every candidate burn on a *uniform* grid.

    ``R[i, k, j] = (Phi((i - k) step) effects[k, j])[component]`` for i >= k (a burn acts on the state at its own
    epoch, as in :func:`~roe_sep.core.relmotion.trajectory.trajectory`), 0 for i < k. Phi depends only on the lag i -
    k, so K transition matrices serve the whole lower-triangular block (vectorized, no loop over epochs).
    """
    k_count = effects.shape[0]
    rows = transition_matrices(step * np.arange(k_count), a, inc, j2)[:, component, :]  # (lag, 6)
    by_lag = np.einsum("mc,kjc->mkj", rows, effects)  # (lag, k, j)
    lag = np.arange(k_count)[:, None] - np.arange(k_count)[None, :]
    out = by_lag[np.maximum(lag, 0), np.arange(k_count)[None, :], :]
    out[lag < 0] = 0.0
    return out


def sagitta(step, a, inc, j2=True, da_dot=0.0, *, component=1):
    """Largest dip of a ROE ``component`` between two grid epochs below the chord through its end values.

    Between burns the secular model is at most quadratic in time (differential drag makes da linear, dl
    quadratic), so the dip is the sagitta |x(step/2) - (x(0) + x(step))/2| of the drag term; dimensionless.
    """
    x = drift_offset(np.array([0.0, 0.5 * step, step]), a, inc, j2, da_dot)[:, component]
    return float(abs(x[1] - 0.5 * (x[0] + x[2])))
