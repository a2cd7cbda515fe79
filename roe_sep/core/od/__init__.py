"""Orbit determination from radar tracking (seed 001 Sec. 5): station and radar geometry, frames and the measurement
model, and the batch weighted least-squares estimate of the relative orbit with its covariance.
"""
