"""Initial-condition acquisition (seed 001 Secs. 2.2-2.3 and 5): the minimum-delta-v carrier burns from the OD
estimate to the experiment's initial conditions, as a linear program on a grid of candidate burns.
"""
