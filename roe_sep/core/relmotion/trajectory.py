"""The relative trajectory under a sequence of impulsive burns: one implementation for the simulator's truth,
the safety monitor's plan prediction and every planner's verification.

Burns are *relative* impulses (seed convention: velocity change of the picosatellite w.r.t. the carrier; a carrier
burn ``dv`` enters as ``-dv``). Between burns the secular model of :func:`~roe_sep.core.relmotion.dynamics.propagate`;
at a burn seed 002 Eq. (2) at the chief's mean argument of latitude of that instant.
"""

from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .dynamics import arg_latitude_rate, propagate
from .maneuvers import delta_roe
from .orbit import mean_motion


@dataclass(frozen=True)
class Burn:
    """One impulsive burn: epoch [s] and relative impulse ``(dv_R, dv_T, dv_N)`` [m/s] in RTN."""

    epoch: float
    dv_rel: tuple


@dataclass(frozen=True)
class Chief:
    """What the relative dynamics need of the chief: a [m], i [rad], u at epoch t0 [rad, s]."""

    a: float
    inc: float
    u0: float
    t0: float

    def u_at(self, t: ArrayLike, j2: bool = True) -> np.ndarray:
        """Mean argument of latitude [rad], not wrapped, at ``t`` [s] (any shape; secular rate with or without J2)."""
        return self.u0 + arg_latitude_rate(self.a, self.inc, j2) * (np.asarray(t, dtype=float) - self.t0)


def trajectory(roe0: ArrayLike, t0: float, burns: Iterable[Burn], times: ArrayLike, chief: Chief, *, j2: bool = True,
               da_dot: float = 0.0) -> np.ndarray:
    """ROE ``(len(times), 6)`` at ``times`` [s] (any order, all >= t0) from ``roe0`` at ``t0`` under ``burns``.

    A burn at epoch t_b acts on states at t >= t_b (a sample exactly at t_b sees the post-burn state); burns before
    ``t0`` are ignored.

    Parameters
    ----------
    roe0 : array_like, shape (6,)
        Dimensionless ROE at ``t0``.
    t0 : float
        Epoch of ``roe0`` [s].
    burns : iterable of Burn
        Relative impulses, any order.
    times : array_like, shape (m,)
        Epochs [s] of the output, each >= ``t0`` (ValueError otherwise).
    chief : Chief
        The chief's a, i and argument of latitude.
    j2 : bool
        With the J2 secular rates (:func:`~roe_sep.core.relmotion.dynamics.propagate`).
    da_dot : float
        Differential-drag rate of da [1/s].

    Returns
    -------
    numpy.ndarray, shape (m, 6)
        Dimensionless ROE at ``times``.
    """
    times = np.asarray(times, dtype=float)
    if np.any(times < t0):
        raise ValueError("trajectory times must not precede t0")
    return segments_at(burn_segments(roe0, t0, burns, chief, j2, da_dot=da_dot), times, t0, chief, j2, da_dot=da_dot)


def burn_segments(roe0: ArrayLike, t0: float, burns: Iterable[Burn], chief: Chief, j2: bool = True,
                  *, da_dot: float = 0.0) -> list:
    """The coast arcs of :func:`trajectory`: ``[(t_start, state, t_end)]``, the state at ``t0`` until the first
    burn (>= ``t0``), then the post-burn state at each burn's epoch until the next one (the last until ``inf``).

    A caller that samples the same ``roe0`` and burns at several times keeps these and samples them with
    :func:`segments_at` (the values of :func:`trajectory`, to the bit).

    Parameters
    ----------
    roe0, t0, burns, chief, j2, da_dot
        As for :func:`trajectory`.

    Returns
    -------
    list of (float, numpy.ndarray, float)
        Start epoch [s], dimensionless ROE ``(6,)`` there, end epoch [s] of each arc.
    """
    order = sorted((b for b in burns if b.epoch >= t0), key=lambda b: b.epoch)
    state, t_state = np.asarray(roe0, dtype=float), float(t0)
    n = mean_motion(chief.a)
    arcs = []
    for b in order:
        arcs.append((t_state, state, b.epoch))
        state = propagate(state, b.epoch - t_state, chief.a, chief.inc, j2, da_dot=da_dot)
        state = state + delta_roe(np.asarray(b.dv_rel, dtype=float), chief.u_at(b.epoch, j2), chief.a, n)
        t_state = b.epoch
    arcs.append((t_state, state, np.inf))
    return arcs


def segments_at(arcs: list, times: ArrayLike, t0: float, chief: Chief, j2: bool = True,
                *, da_dot: float = 0.0) -> np.ndarray:
    """ROE ``(len(times), 6)`` at ``times`` [s] (all >= ``t0``, unchecked) on the arcs of :func:`burn_segments`:
    each sample propagated from the start of its arc (a sample exactly at a burn epoch sees the post-burn state).

    Parameters
    ----------
    arcs : list
        :func:`burn_segments` of ``roe0`` at ``t0``.
    times : array_like, shape (m,)
        Epochs [s] of the output.
    t0 : float
        Epoch of ``roe0`` [s].
    chief, j2, da_dot
        As for :func:`trajectory`.

    Returns
    -------
    numpy.ndarray, shape (m, 6)
        Dimensionless ROE at ``times``.
    """
    times = np.asarray(times, dtype=float)
    if len(arcs) == 1 and times.ndim == 1:  # one coast arc (no burn): every sample of it, as the loop below
        t_state, state, hi = arcs[0]
        if (times < hi).all():
            return propagate(state, times - t_state, chief.a, chief.inc, j2, da_dot=da_dot)
    out = np.empty(times.shape + (6,))
    lo = -np.inf
    for k, (t_state, state, hi) in enumerate(arcs):
        sel = (times >= max(lo, t0)) & (times < hi) if k else (times < hi)
        if np.any(sel):
            out[sel] = propagate(state, times[sel] - t_state, chief.a, chief.inc, j2, da_dot=da_dot)
        lo = hi
    return out


def state_at(roe0: ArrayLike, t0: float, burns: Iterable[Burn], t: float, chief: Chief, *, j2: bool = True,
             da_dot: float = 0.0) -> np.ndarray:
    """The ROE at one time under ``burns``: :func:`trajectory` at ``times = [t]``.

    Parameters
    ----------
    roe0, t0, burns, chief, j2, da_dot
        As for :func:`trajectory`.
    t : float
        The epoch [s], >= ``t0``.

    Returns
    -------
    numpy.ndarray, shape (6,)
        Dimensionless ROE at ``t``.
    """
    return trajectory(roe0, t0, burns, np.array([t]), chief, j2=j2, da_dot=da_dot)[0]
