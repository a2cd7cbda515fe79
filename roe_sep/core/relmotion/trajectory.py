"""The relative trajectory under a sequence of impulsive burns: one implementation for the simulator's truth,
the safety monitor's plan prediction and every planner's verification.

Burns are *relative* impulses (seed convention: velocity change of the picosatellite w.r.t. the carrier; a carrier
burn ``dv`` enters as ``-dv``). Between burns the secular model of :func:`~roe_sep.core.relmotion.dynamics.propagate`;
at a burn seed 002 Eq. (2) at the chief's mean argument of latitude of that instant.
"""

from dataclasses import dataclass

import numpy as np

from .dynamics import arg_latitude_rate, propagate
from .maneuvers import delta_roe
from .orbit import mean_motion


@dataclass(frozen=True)
class Burn:
    """One impulsive burn: epoch [s] and relative impulse [m/s] in RTN."""

    epoch: float
    dv_rel: tuple


@dataclass(frozen=True)
class Chief:
    """What the relative dynamics need of the chief: a [m], i [rad], u at epoch t0 [rad, s]."""

    a: float
    inc: float
    u0: float
    t0: float

    def u_at(self, t, j2=True):
        """Mean argument of latitude at ``t`` [s] (secular rate with or without J2)."""
        return self.u0 + arg_latitude_rate(self.a, self.inc, j2) * (np.asarray(t, dtype=float) - self.t0)


def trajectory(roe0, t0, burns, times, chief: Chief, j2=True, da_dot=0.0):
    """ROE ``(len(times), 6)`` at ``times`` [s] (any order, all >= t0) from ``roe0`` at ``t0`` under ``burns``.

    A burn at epoch t_b acts on states at t >= t_b (a sample exactly at t_b sees the post-burn state).
    """
    times = np.asarray(times, dtype=float)
    if np.any(times < t0):
        raise ValueError("trajectory times must not precede t0")
    order = sorted((b for b in burns if b.epoch >= t0), key=lambda b: b.epoch)
    out = np.empty(times.shape + (6,))
    state, t_state = np.asarray(roe0, dtype=float), float(t0)
    n = mean_motion(chief.a)
    edges = [b.epoch for b in order] + [np.inf]
    lo = -np.inf
    for k, hi in enumerate(edges):
        sel = (times >= max(lo, t0)) & (times < hi) if k else (times < hi)
        if np.any(sel):
            out[sel] = propagate(state, times[sel] - t_state, chief.a, chief.inc, j2, da_dot)
        if k < len(order):
            b = order[k]
            state = propagate(state, b.epoch - t_state, chief.a, chief.inc, j2, da_dot)
            state = state + delta_roe(np.asarray(b.dv_rel, dtype=float), chief.u_at(b.epoch, j2), chief.a, n)
            t_state = b.epoch
        lo = hi
    return out


def state_at(roe0, t0, burns, t, chief: Chief, j2=True, da_dot=0.0):
    """ROE at one time ``t`` under ``burns`` (see :func:`trajectory`)."""
    return trajectory(roe0, t0, burns, np.array([t]), chief, j2, da_dot)[0]
