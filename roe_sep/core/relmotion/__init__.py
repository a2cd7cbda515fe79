"""Relative motion and its dynamics: the chief orbit, quasi-nonsingular ROE (seed 002 Eq. 1) and their linear
RTN map, impulsive maneuvers (Gauss equations, Eq. 2; execution errors, Eq. 22), the secular ROE propagation with
Keplerian drift, J2 and differential drag (Eqs. 23-24), and the relative trajectory under a sequence of burns.

The lowest layer of the core: every other subpackage builds on it.
"""
