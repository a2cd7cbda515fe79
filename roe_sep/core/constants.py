"""Physical constants (SI). Earth values are those of the EGM96/WGS-84 model pair."""

import math

MU_EARTH = 3.986004418e14
"""Earth gravitational parameter GM [m^3/s^2] (WGS-84)."""

R_EARTH = 6378137.0
"""Earth equatorial radius [m] (WGS-84); altitude above it defines the circular-orbit semi-major axis."""

J2 = 1.08262668e-3
"""Second zonal harmonic of the Earth's gravity field (EGM96, unnormalized)."""

J3 = -2.53265649e-6
"""Third zonal harmonic, EGM96 unnormalized (J3 = -sqrt(7) C30)."""

J4 = -1.61962159e-6
"""Fourth zonal harmonic, EGM96 unnormalized (J4 = -3 C40)."""

EARTH_ROTATION = 7.292115e-5
"""Earth rotation rate omega_E [rad/s] (WGS-84 / Vallado)."""
SPEED_OF_LIGHT = 299792458.0
"""Speed of light in vacuum [m/s] (exact, SI)."""

ARCSEC = math.pi / (180.0 * 3600.0)
"""One arc second [rad]."""

SECONDS_PER_DAY = 86400.0
