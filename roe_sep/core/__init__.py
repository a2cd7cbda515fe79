"""Pure numpy/scipy flight dynamics and planning: no ROS imports anywhere in this package.

Conventions used throughout the core:

* ROE are the quasi-nonsingular set of seed 002 Eq. (1), ordered ``[da, dl, dex, dey, dix, diy]``, of the
  picosatellite (deputy) with respect to the carrier (chief, origin of the RTN frame). Functions take and return
  them *dimensionless* unless their name says ``a_`` (multiplied by the chief semi-major axis, meters).
* Arrays of ROE have shape ``(..., 6)``; every function broadcasts over leading sample axes.
* SI units: m, m/s, s, rad.

Subpackages, by domain (lower ones never import higher ones):

* ``constants``, ``config``: physical constants; the scenario configuration (YAML -> validated dataclasses).
* ``relmotion``: chief orbit, ROE, maneuvers, secular dynamics, trajectories (seed 002 Eqs. 1-2, 22-24).
* ``safety``: passive-safety and visibility metrics, the monitor's assessment (Eqs. 11, 25).
* ``separation``: double-impulse (seeds 000/002) and multi-impulse (seed 001) designs.
* ``montecarlo``: dispersions, the p sweep (Table 3), the multi-impulse acceptance criteria.
* ``od``: radar geometry, measurement model, batch least-squares OD (seed 001 Sec. 5).
* ``acquisition``: minimum-delta-v initial-condition acquisition (LP).
* ``ops``: the operational plan of the separation day.
* ``truth``: secular and nonlinear truth, mean/osculating elements, model validation.
* ``deployment``: the seed-003 deployment sweep and the seed-004 cluster program.
"""
