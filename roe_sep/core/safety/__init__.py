"""Passive safety and visibility of a relative orbit: the metrics of seeds 000/002 (minimum R-N distance Eq. 25,
nearest R = 0 transit, drift direction, camera field of view Eq. 11) and the safety monitor's assessment of a
predicted trajectory against them.
"""
