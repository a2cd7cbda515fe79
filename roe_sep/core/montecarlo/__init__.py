"""Monte Carlo of the separation designs: the seeds' dispersions (seed 002 Eq. 22 and Sec. "Monte Carlo
simulation"), the drift-stop reduction sweep of Table 3, and the multi-impulse acceptance criteria AC1-AC3 (seed 001
Sec. 4).
"""
