"""Impulsive maneuvers in ROE: the Gauss-equation control matrix (seed 002 Eq. 2) and execution errors (Eq. 22)."""

import numpy as np


def control_matrix(u):
    """The 6x3 matrix G(u) of seed 002 Eq. (2): n a * Delta(delta alpha) = G(u) dv_RTN.

    Rows: da: +2 dvT;  dl: -2 dvR;  dex: dvR sin u + 2 dvT cos u;  dey: -dvR cos u + 2 dvT sin u;
    dix: dvN cos u;  diy: dvN sin u.   ``u`` may be an array: the result is ``(..., 6, 3)``.
    """
    u = np.asarray(u, dtype=float)
    s, c = np.sin(u), np.cos(u)
    z, one = np.zeros_like(u), np.ones_like(u)
    rows = [
        [z, 2.0 * one, z],
        [-2.0 * one, z, z],
        [s, 2.0 * c, z],
        [-c, 2.0 * s, z],
        [z, z, c],
        [z, z, s],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def delta_roe(dv_rtn, u, a, n):
    """Dimensionless ROE change from an impulsive velocity change of the picosatellite relative to the carrier.

    seed 002 Eq. (2): Delta(delta alpha) = G(u) dv / (n a). ``dv_rtn`` is ``(..., 3)`` [m/s] in the carrier RTN
    frame, ``u`` the mean argument of latitude [rad], ``a`` [m] and ``n`` [rad/s] the carrier's. A burn of the
    *carrier* changes the relative state by ``delta_roe(-dv_carrier, ...)``.
    """
    g = control_matrix(u)
    return np.einsum("...ij,...j->...i", g, np.asarray(dv_rtn, dtype=float)) / (n * a)


def dv_for_delta_roe(droe, u, a, n):
    """Inverse of :func:`delta_roe`: the single impulse at ``u`` that best produces ``droe`` (least squares).

    G(u) has orthogonal columns (G^T G = diag(5, 8, 1)), so the pseudo-inverse is diag(1/5, 1/8, 1) G^T. It is exact
    for any ROE change a single impulse at ``u`` can produce; otherwise it returns the least-squares impulse.
    """
    g = control_matrix(u)
    gt = np.swapaxes(g, -1, -2) * np.array([1.0 / 5.0, 1.0 / 8.0, 1.0])[:, None]
    return np.einsum("...ij,...j->...i", gt, np.asarray(droe, dtype=float)) * (n * a)


def dispersed_dv(dv_rtn, factor, eps):
    """Executed impulse under magnitude factor ``f`` and small attitude errors, seed 002 Eq. (22).

    dv_s = f [[1, ez, -ey], [-ez, 1, ex], [ey, -ex, 1]] dv, with ``eps = (ex, ey, ez)`` [rad], shape ``(..., 3)``,
    and ``factor`` shape ``(...)``.
    """
    dv = np.asarray(dv_rtn, dtype=float)
    e = np.asarray(eps, dtype=float)
    ex, ey, ez = e[..., 0], e[..., 1], e[..., 2]
    r, t, nn = dv[..., 0], dv[..., 1], dv[..., 2]
    rotated = np.stack([r + ez * t - ey * nn, -ez * r + t + ex * nn, ey * r - ex * t + nn], axis=-1)
    return np.asarray(factor, dtype=float)[..., None] * rotated
