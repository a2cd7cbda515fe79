"""Relative motion of a nanosatellite w.r.t. its platform for the cluster program (seed 004 Sec. 2): the HCW solution
in the seed's axes (x along the flight direction, y along the radius vector, z normal) and the along-track
differential drag. The only propagation used by :mod:`~roe_sep.core.deployment.cluster` and
:mod:`~roe_sep.core.deployment.cluster_envelope`.
"""

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import drag_da_dot
from ..relmotion.orbit import mean_motion


def drag_acceleration(delta_q: ArrayLike, rho: ArrayLike, a: float) -> np.ndarray:
    """Seed 004 P_x = rho V_s^2 dQ [m/s^2], along x, dQ = Q_OS - Q_NS (V_s = circular speed, co-rotation neglected).

    Equals (n a / 2) d(da)/dt of :func:`~roe_sep.core.relmotion.dynamics.drag_da_dot` with dB = B_NS - B_OS = -2 dQ.

    Parameters
    ----------
    delta_q : array_like
        dQ = Q_OS - Q_NS [m^2/kg], the seed's Q = c_d A / (2 m).
    rho : array_like
        Atmospheric density [kg/m^3].
    a : float
        The platform's semi-major axis [m].

    Returns
    -------
    numpy.ndarray
        P_x [m/s^2], the broadcast shape.
    """
    return 0.5 * mean_motion(a) * a * drag_da_dot(-2.0 * np.asarray(delta_q, dtype=float), rho, a)


def hcw_matrix(tau: ArrayLike, n: float) -> np.ndarray:
    """M(tau) ``(..., 3, 3)``: position [m] of a NS tau [s] after leaving the OS with velocity v: r = M v.

    HCW solution from the origin (seed 004 Eqs. 1-2 coefficients, x along-track, y radial, z normal):
    x = vx (4 sin(n tau)/n - 3 tau) + vy 2 (cos(n tau) - 1)/n,  y = vx 2 (1 - cos(n tau))/n + vy sin(n tau)/n,
    z = vz sin(n tau)/n.  Zero for tau < 0 (the NS is still on the OS). ``n`` [rad/s]; ``tau`` any shape.
    """
    m00, m01, m10, m11, m22 = hcw_terms(tau, n)
    z = np.zeros_like(m00)
    return np.stack([np.stack([m00, m01, z], -1), np.stack([m10, m11, z], -1), np.stack([z, z, m22], -1)], -2)


def hcw_terms(tau: ArrayLike, n: float) -> tuple[np.ndarray, ...]:
    """The non-zero entries (m00, m01, m10, m11, m22) of :func:`hcw_matrix`, zero for tau < 0 (block structure:
    the moment and bound functions use the entries directly)."""
    t = np.where(np.asarray(tau, dtype=float) > 0.0, tau, 0.0)
    s, c = np.sin(n * t), np.cos(n * t)
    return 4.0 * s / n - 3.0 * t, 2.0 * (c - 1.0) / n, 2.0 * (1.0 - c) / n, s / n, s / n


def drag_offset(tau: ArrayLike, n: float, p_x: ArrayLike) -> np.ndarray:
    """D(tau) ``(..., 3)``: position [m] due to a constant along-track acceleration ``p_x`` (seed 004 Eq. 1).

    x = 4 P/n^2 (1 - cos n tau) - 3/2 P tau^2,  y = 2 P/n (tau - sin(n tau)/n),  z = 0;  zero for tau < 0.

    Parameters
    ----------
    tau : array_like
        Time since the NS left the OS [s].
    n : float
        The platform's mean motion [rad/s].
    p_x : array_like
        Along-track acceleration [m/s^2] (:func:`drag_acceleration`); broadcast with ``tau``.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        (x, y, z) [m].
    """
    tau = np.asarray(tau, dtype=float)
    t = np.where(tau > 0.0, tau, 0.0)
    p = np.asarray(p_x, dtype=float)
    x = 4.0 * p / n**2 * (1.0 - np.cos(n * t)) - 1.5 * p * t**2
    y = 2.0 * p / n * (t - np.sin(n * t) / n)
    return np.stack([x, y, np.zeros_like(x + y)], axis=-1)


def singular_values(m: np.ndarray | tuple) -> tuple[np.ndarray, np.ndarray]:
    """(s_min, s_max) of a matrix with the block structure of :func:`hcw_matrix` (2x2 in-plane block and the normal
    entry), closed form; ``m`` is the matrix or the tuple of its entries (:func:`hcw_terms`, or any linear
    combination of such tuples)."""
    if isinstance(m, tuple):  # the entries of :func:`hcw_terms`
        a, b, c, d, z = m
    else:
        a, b, c, d, z = m[..., 0, 0], m[..., 0, 1], m[..., 1, 0], m[..., 1, 1], m[..., 2, 2]
    f = a * a + b * b + c * c + d * d
    g = np.sqrt((a * a + b * b - c * c - d * d) ** 2 + 4.0 * (a * c + b * d) ** 2)
    s_hi, s_lo = np.sqrt(0.5 * (f + g)), np.sqrt(np.maximum(0.5 * (f - g), 0.0))
    z = np.abs(z)
    return np.minimum(s_lo, z), np.maximum(s_hi, z)

