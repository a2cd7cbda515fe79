"""Absolute near-circular orbit relations of the chief (carrier)."""

import functools
import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ..constants import MU_EARTH, R_EARTH


def semi_major_axis(altitude: ArrayLike) -> np.ndarray:
    """Semi-major axis [m] of a circular orbit at ``altitude`` [m] above the equatorial radius (any shape)."""
    return R_EARTH + np.asarray(altitude, dtype=float)


def per_chief(n_floats: int) -> Callable[[Callable], Callable]:
    """Decorator: ``fn(x_1, ..., x_n, *flags)`` computed once per value for a chief's scalar floats (its a, i) and
    the flags (``bool``), afresh when any of the first ``n_floats`` arguments is not a float (arrays of samples).
    The cached value is the one ``fn`` returns (the same expressions); the floats' signs are part of the key, since
    -0.0 == 0.0 would otherwise share an entry."""

    def decorate(fn):
        @functools.lru_cache(maxsize=64)
        def cached(_signs, floats, flags):
            return fn(*floats, *flags)

        @functools.wraps(fn)
        def call(*args):
            floats = args[:n_floats]
            if all(isinstance(x, float) for x in floats):
                return cached(tuple(math.copysign(1.0, x) for x in floats), floats, tuple(map(bool, args[n_floats:])))
            return fn(*args)

        return call

    return decorate


def mean_motion(a: ArrayLike) -> np.ndarray:
    """Keplerian mean motion n = sqrt(mu / a^3) [rad/s] for semi-major axis ``a`` [m] (any shape; a chief's float
    once per value, :func:`per_chief`)."""
    return _mean_motion(a)


@per_chief(1)
def _mean_motion(a):
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float) ** 3)


def circular_speed(a: ArrayLike) -> np.ndarray:
    """Orbital speed v = sqrt(mu / a) [m/s] of a circular orbit of semi-major axis ``a`` [m] (any shape; the ``v``
    of seed 002 Eqs. 23-24)."""
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float))


def orbital_period(a: ArrayLike) -> np.ndarray:
    """Orbital period 2*pi/n [s] of semi-major axis ``a`` [m] (any shape)."""
    return 2.0 * np.pi / mean_motion(a)



def angle_between(a: ArrayLike, b: ArrayLike, axis: int = -1) -> np.ndarray:
    """The angle [rad] between vectors ``a`` and ``b`` along ``axis`` (broadcast), 0 where either vector is zero:
    2 atan2(|a/|a| - b/|b||, |a/|a| + b/|b||) (Kahan's form, accurate near 0 and pi, where acos of the normalized dot
    product loses half the digits: 1.5e-8 rad for parallel vectors).

    Parameters
    ----------
    a, b : array_like
        The vectors, their components along ``axis``.
    axis : int
        The component axis.

    Returns
    -------
    numpy.ndarray
        The angles [rad], the broadcast shape without ``axis`` (a 0-d array for two vectors).
    """
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    na = np.linalg.norm(a, axis=axis, keepdims=True)
    nb = np.linalg.norm(b, axis=axis, keepdims=True)
    ua = np.divide(a, na, out=np.zeros(np.broadcast_shapes(a.shape, na.shape)), where=na > 0.0)
    ub = np.divide(b, nb, out=np.zeros(np.broadcast_shapes(b.shape, nb.shape)), where=nb > 0.0)
    angle = 2.0 * np.arctan2(np.linalg.norm(ua - ub, axis=axis), np.linalg.norm(ua + ub, axis=axis))
    zero = np.squeeze((na == 0.0) | (nb == 0.0), axis=axis)
    return np.where(zero, 0.0, angle)
