"""roe_sep: safe release of a picosatellite from a small carrier satellite, designed in relative orbital elements."""

__version__ = "0.1.0"
