"""Pure numpy/scipy flight dynamics and planning: no ROS imports anywhere in this package.

Conventions used throughout the core:

* ROE are the quasi-nonsingular set of seed 002 Eq. (1), ordered ``[da, dl, dex, dey, dix, diy]``, of the
  picosatellite (deputy) with respect to the carrier (chief, origin of the RTN frame). Functions take and return
  them *dimensionless* unless their name says ``a_`` (multiplied by the chief semi-major axis, meters).
* Arrays of ROE have shape ``(..., 6)``; every function broadcasts over leading sample axes.
* SI units: m, m/s, s, rad.
"""
