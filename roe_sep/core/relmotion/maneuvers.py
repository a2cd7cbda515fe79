"""Impulsive maneuvers in ROE: the Gauss-equation control matrix (seed 002 Eq. 2) and execution errors (Eqs. 18, 22)."""

import numpy as np
from numpy.typing import ArrayLike


def control_matrix(u: ArrayLike) -> np.ndarray:
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


def delta_roe(dv_rtn: ArrayLike, u: ArrayLike, a: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Dimensionless ROE change from an impulsive velocity change of the picosatellite relative to the carrier.

    seed 002 Eq. (2): Delta(delta alpha) = G(u) dv / (n a). A burn of the *carrier* changes the relative state by
    ``delta_roe(-dv_carrier, ...)``.

    Parameters
    ----------
    dv_rtn : array_like, shape (..., 3)
        The impulse [m/s] in the carrier RTN frame.
    u : array_like, shape (...)
        The carrier's mean argument of latitude at the burn [rad].
    a : array_like
        The carrier's semi-major axis [m].
    n : array_like
        The carrier's mean motion [rad/s].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The change of the dimensionless ROE.
    """
    g = control_matrix(u)
    return np.einsum("...ij,...j->...i", g, np.asarray(dv_rtn, dtype=float)) / (n * a)


def dv_for_delta_roe(droe: ArrayLike, u: ArrayLike, a: ArrayLike, n: ArrayLike) -> np.ndarray:
    """Inverse of :func:`delta_roe`: the single impulse at ``u`` that best produces ``droe`` (least squares).

    G(u) has orthogonal columns (G^T G = diag(5, 8, 1)), so the pseudo-inverse is diag(1/5, 1/8, 1) G^T. It is exact
    for any ROE change a single impulse at ``u`` can produce; otherwise it returns the least-squares impulse.

    Parameters
    ----------
    droe : array_like, shape (..., 6)
        The wanted change of the dimensionless ROE.
    u : array_like, shape (...)
        The carrier's mean argument of latitude at the burn [rad].
    a : array_like
        The carrier's semi-major axis [m].
    n : array_like
        The carrier's mean motion [rad/s].

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The impulse [m/s] in the carrier RTN frame.
    """
    g = control_matrix(u)
    gt = np.swapaxes(g, -1, -2) * np.array([1.0 / 5.0, 1.0 / 8.0, 1.0])[:, None]
    return np.einsum("...ij,...j->...i", gt, np.asarray(droe, dtype=float)) * (n * a)


def dispersed_dv(dv_rtn: ArrayLike, factor: ArrayLike, eps: ArrayLike,
                 reference: ArrayLike | None = None) -> np.ndarray:
    """The executed impulse: the one dispersed-burn function of the project (seed 002 Eqs. 18 and 22).

    dv_s = R(eps) [dv + (f - 1) dv_ref],  R(eps) = [[1, ez, -ey], [-ez, 1, ex], [ey, -ex, 1]],

    ``dv_rtn`` the commanded burn ``(..., 3)`` [m/s], ``factor`` f ``(...)``, ``eps = (ex, ey, ez)`` [rad]
    ``(..., 3)``. ``reference`` dv_ref is the burn the magnitude error is a fraction of; ``None`` means the
    commanded burn itself, which is Eq. (22) exactly: dv_s = f R(eps) dv (the ejection, every burn that is not
    a reduced drift-stop).

    For a drift-stop commanded with a reduction |p|, ``reference`` is the *unreduced* burn (:func:`unreduced_burns`):
    seed 002 Eq. (18), δv*_T2 = δv_T2 + e2 − |p|, adds the error e2 = (f2 − 1) δv_T2 to the nominal δv_T2 of
    Eq. (16) and subtracts |p| after it, and Eqs. (20)-(21) size e2 on that unreduced δv_T2 (so does seed 000,
    Eqs. 19, 21). The attitude error rotates the whole commanded burn (the thruster points once).

    Parameters
    ----------
    dv_rtn : array_like, shape (..., 3)
        The commanded burn [m/s] in RTN.
    factor : array_like, shape (...)
        The magnitude factor f (1 + the magnitude error as a fraction).
    eps : array_like, shape (..., 3)
        The attitude error angles ``(ex, ey, ez)`` [rad].
    reference : array_like, shape (..., 3), optional
        The burn dv_ref [m/s] the magnitude error is a fraction of; None: ``dv_rtn`` itself.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The executed burn [m/s] in RTN.
    """
    dv = np.asarray(dv_rtn, dtype=float)
    if reference is not None:
        dv = dv + (np.asarray(factor, dtype=float)[..., None] - 1.0) * np.asarray(reference, dtype=float)
        factor = 1.0
    e = np.asarray(eps, dtype=float)
    ex, ey, ez = e[..., 0], e[..., 1], e[..., 2]
    r, t, nn = dv[..., 0], dv[..., 1], dv[..., 2]
    rotated = np.stack([r + ez * t - ey * nn, -ez * r + t + ex * nn, ey * r - ex * t + nn], axis=-1)
    return np.asarray(factor, dtype=float)[..., None] * rotated


def unreduced_burns(dv_parts: ArrayLike, p: float) -> np.ndarray:
    """The burns a thruster's magnitude error acts on for a drift-stop commanded with reduction |p| (Eq. 18).

    ``dv_parts`` ``(k, 3)`` [m/s]: the commanded drift-stop, one burn or split into k burns (the multi-impulse
    scheme's drift reduction over consecutive orbits); the reduction |p| was taken off their tangential
    components. Returns the burns with the tangential magnitude enlarged again by |p| in total, shared in
    proportion to each part's tangential size (one burn: exactly the unreduced dv_T2 of Eqs. 9/16); radial and
    normal parts unchanged. The reference of :func:`dispersed_dv`. Valid for |p| below the unreduced tangential
    burn (Eq. 20, first line: the commanded burn keeps its sign); parts without a tangential component are
    returned unchanged. ``p`` [m/s]; the result is a new ``(k, 3)`` array [m/s].
    """
    parts = np.array(dv_parts, dtype=float, ndmin=2)
    t = parts[:, 1]
    total = np.sum(np.abs(t))
    if total > 0.0:
        parts[:, 1] = t + np.sign(t) * abs(float(p)) * np.abs(t) / total
    return parts
