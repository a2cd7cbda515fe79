"""Operations planning of the separation day (seed 001 Sec. 5): ground contacts, radar passes, eclipses, the camera
Sun angle and the ranked candidate separation windows (skyfield, shipped ephemeris).
"""
