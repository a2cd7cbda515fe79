"""Absolute near-circular orbit relations of the chief (carrier)."""

import numpy as np
from numpy.typing import ArrayLike

from ..constants import MU_EARTH, R_EARTH


def semi_major_axis(altitude: ArrayLike) -> np.ndarray:
    """Semi-major axis [m] of a circular orbit at ``altitude`` [m] above the equatorial radius (any shape)."""
    return R_EARTH + np.asarray(altitude, dtype=float)


def mean_motion(a: ArrayLike) -> np.ndarray:
    """Keplerian mean motion n = sqrt(mu / a^3) [rad/s] for semi-major axis ``a`` [m] (any shape)."""
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float) ** 3)


def circular_speed(a: ArrayLike) -> np.ndarray:
    """Orbital speed v = sqrt(mu / a) [m/s] of a circular orbit of semi-major axis ``a`` [m] (any shape; the ``v``
    of seed 002 Eqs. 23-24)."""
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float))


def orbital_period(a: ArrayLike) -> np.ndarray:
    """Orbital period 2*pi/n [s] of semi-major axis ``a`` [m] (any shape)."""
    return 2.0 * np.pi / mean_motion(a)

