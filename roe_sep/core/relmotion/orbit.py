"""Absolute near-circular orbit relations of the chief (carrier)."""

import numpy as np

from ..constants import MU_EARTH, R_EARTH


def semi_major_axis(altitude):
    """Semi-major axis [m] of a circular orbit at ``altitude`` [m] above the equatorial radius."""
    return R_EARTH + np.asarray(altitude, dtype=float)


def mean_motion(a):
    """Keplerian mean motion n = sqrt(mu / a^3) [rad/s] for semi-major axis ``a`` [m]."""
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float) ** 3)


def circular_speed(a):
    """Orbital speed v = sqrt(mu / a) [m/s] of a circular orbit (the ``v`` of seed 002 Eqs. 23-24)."""
    return np.sqrt(MU_EARTH / np.asarray(a, dtype=float))


def orbital_period(a):
    """Orbital period 2*pi/n [s]."""
    return 2.0 * np.pi / mean_motion(a)

