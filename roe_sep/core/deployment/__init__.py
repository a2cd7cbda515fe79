"""Deployment analyses beyond the picosatellite case: the CubeSat deployment direction/velocity sweep of seed 003
(Sec. 4.2) and the adaptive separation program of a nanosatellite cluster from a tumbling stage (seed 004), with its
HCW/drag dynamics and the P* envelope of the tumbling.
"""
