"""Quasi-nonsingular relative orbital elements: definition (seed 002 Eq. 1) and the linear RTN mapping.

Element arrays are ``(..., 6)``:

* Keplerian elements ``[a, e, i, raan, argp, M]`` (m, 1, rad, rad, rad, rad), mean elements.
* ROE ``[da, dl, dex, dey, dix, diy]``, dimensionless, picosatellite (deputy) w.r.t. carrier (chief).
"""

import numpy as np
from numpy.typing import ArrayLike

ROE_NAMES = ("da", "dl", "dex", "dey", "dix", "diy")


def wrap_angle(x: ArrayLike) -> np.ndarray:
    """Wrap angles [rad] to [-pi, pi) (any shape)."""
    return (np.asarray(x, dtype=float) + np.pi) % (2.0 * np.pi) - np.pi


def kepler_to_roe(chief: ArrayLike, deputy: ArrayLike) -> np.ndarray:
    """ROE ``(..., 6)`` of ``deputy`` w.r.t. ``chief`` from mean Keplerian elements ``(..., 6)``, seed 002 Eq. (1).

    da = (a - a_c)/a_c,  dl = (u - u_c) + (raan - raan_c) cos i_c,  de = e_vec - e_vec_c,
    dix = i - i_c,  diy = (raan - raan_c) sin i_c,  with u = M + argp.
    """
    c = np.asarray(chief, dtype=float)
    d = np.asarray(deputy, dtype=float)
    a_c, e_c, i_c, raan_c, w_c, m_c = np.moveaxis(c, -1, 0)
    a, e, i, raan, w, m = np.moveaxis(d, -1, 0)
    draan = wrap_angle(raan - raan_c)
    return np.stack(
        [
            (a - a_c) / a_c,
            wrap_angle((m + w) - (m_c + w_c)) + draan * np.cos(i_c),
            e * np.cos(w) - e_c * np.cos(w_c),
            e * np.sin(w) - e_c * np.sin(w_c),
            i - i_c,
            draan * np.sin(i_c),
        ],
        axis=-1,
    )


def roe_to_kepler(chief: ArrayLike, roe: ArrayLike) -> np.ndarray:
    """Inverse of :func:`kepler_to_roe`: the deputy's mean Keplerian elements ``(..., 6)``.

    For a deputy with zero eccentricity the argument of perigee is undefined; it is returned as 0 and the mean
    argument of latitude is carried entirely by M.
    """
    c = np.asarray(chief, dtype=float)
    r = np.asarray(roe, dtype=float)
    a_c, e_c, i_c, raan_c, w_c, m_c = np.moveaxis(c, -1, 0)
    da, dl, dex, dey, dix, diy = np.moveaxis(r, -1, 0)
    draan = diy / np.sin(i_c)
    ex = e_c * np.cos(w_c) + dex
    ey = e_c * np.sin(w_c) + dey
    w = np.arctan2(ey, ex)
    u = (m_c + w_c) + dl - draan * np.cos(i_c)
    return np.stack(
        [a_c * (1.0 + da), np.hypot(ex, ey), i_c + dix, raan_c + draan, w, wrap_angle(u - w)],
        axis=-1,
    )


def roe_to_rtn(roe: ArrayLike, u: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Relative position and velocity in the chief RTN frame from ROE, linear (HCW-equivalent) model.

    Near-circular chief at mean argument of latitude ``u`` [rad]; D'Amico (2010), the mapping behind seed 002
    Eq. (2):

    r/a     = [da - dex cos u - dey sin u,   dl + 2 dex sin u - 2 dey cos u,   dix sin u - diy cos u]
    v/(a n) = [dex sin u - dey cos u,   -3/2 da + 2 dex cos u + 2 dey sin u,   dix cos u + diy sin u]

    ``dl`` is the current relative mean longitude (its secular drift is the propagator's job). Returns the
    dimensionless ``(r/a, v/(a n))``, each ``(..., 3)``: multiply by a and a*n for meters and m/s.
    """
    return _roe_to_rtn(roe, u, True)


def rtn_position(roe: ArrayLike, u: ArrayLike) -> np.ndarray:
    """The position r/a ``(..., 3)`` of :func:`roe_to_rtn` alone (its expressions, the same values), for callers
    that need no velocity."""
    return _roe_to_rtn(roe, u, False)[0]


def _roe_to_rtn(roe, u, velocity):
    r = np.asarray(roe, dtype=float)
    da, dl, dex, dey, dix, diy = components(r)
    s, c = np.sin(u), np.cos(u)
    pos = stack_last([da - dex * c - dey * s, dl + 2.0 * dex * s - 2.0 * dey * c, dix * s - diy * c])
    if not velocity:
        return pos, None
    vel = stack_last([dex * s - dey * c, -1.5 * da + 2.0 * dex * c + 2.0 * dey * s, dix * c + diy * s])
    return pos, vel


def components(x: np.ndarray) -> tuple:
    """What iterating ``numpy.moveaxis(x, -1, 0)`` gives, without its set-up: the views ``x[..., k]`` along the last
    axis (the NumPy floats of a 1-D ``x``, as iteration gives them: not 0-d arrays, whose ``** 2`` is ``x * x``
    where a float's is ``pow``)."""
    if x.ndim == 1:
        return tuple(x)
    return tuple(x[..., k] for k in range(x.shape[-1]))


def stack_last(parts: list) -> np.ndarray:
    """``numpy.stack(parts, axis=-1)``: the same values in a new C-contiguous array; for float64 arrays (or NumPy
    floats) of one shape without its general set-up, else by ``numpy.stack`` itself (which also raises for
    differing shapes)."""
    shape = getattr(parts[0], "shape", None)
    if shape is not None and all(getattr(p, "dtype", None) == np.float64 and p.shape == shape for p in parts):
        out = np.empty(shape + (len(parts),))
        for k, p in enumerate(parts):
            out[..., k] = p
        return out
    return np.stack(parts, axis=-1)


def rtn_to_roe(pos: ArrayLike, vel: ArrayLike, u: ArrayLike) -> np.ndarray:
    """Inverse of :func:`roe_to_rtn`: ROE from dimensionless RTN position r/a and velocity v/(a n).

    Closed form: da = 2 vT + 4 rR,  dl = rT - 2 vR,  with A = 2 vT + 3 rR and B = vR the in-plane components
    dex = A cos u + B sin u, dey = A sin u - B cos u; dix = rN sin u + vN cos u, diy = -rN cos u + vN sin u.

    Parameters
    ----------
    pos : array_like, shape (..., 3)
        Relative position r/a in the chief RTN frame (dimensionless: meters divided by the chief's a).
    vel : array_like, shape (..., 3)
        Relative velocity v/(a n) in the chief RTN frame (dimensionless: m/s divided by a n).
    u : array_like, shape (...)
        The chief's mean argument of latitude [rad].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        The dimensionless ROE ``[da, dl, dex, dey, dix, diy]``.
    """
    p = np.asarray(pos, dtype=float)
    v = np.asarray(vel, dtype=float)
    x, y, z = np.moveaxis(p, -1, 0)
    vx, vy, vz = np.moveaxis(v, -1, 0)
    s, c = np.sin(u), np.cos(u)
    big_a = 2.0 * vy + 3.0 * x
    return np.stack(
        [2.0 * vy + 4.0 * x, y - 2.0 * vx, big_a * c + vx * s, big_a * s - vx * c, z * s + vz * c, -z * c + vz * s],
        axis=-1,
    )


def e_vector_polar(roe: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Magnitude and phase [rad] of the relative eccentricity vector of ROE ``(..., 6)``: (de, phi), each ``(...)``,
    with de = |(dex, dey)|, seed 002 Eq. (1)."""
    r = np.asarray(roe, dtype=float)
    return np.hypot(r[..., 2], r[..., 3]), np.arctan2(r[..., 3], r[..., 2])


def i_vector_polar(roe: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Magnitude and phase [rad] of the relative inclination vector of ROE ``(..., 6)``: (di, theta), each ``(...)``,
    seed 002 Eq. (1)."""
    r = np.asarray(roe, dtype=float)
    return np.hypot(r[..., 4], r[..., 5]), np.arctan2(r[..., 5], r[..., 4])
