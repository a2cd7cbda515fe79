"""The radar sensor's pure parts and the OD's measurement records (seed 001 Sec. 5: radar tracking of the
picosatellite, TIRA separating the two spacecraft from 5 km on).

The sensor (``roe_sep.nodes.radar``) measures an epoch when the station sees the picosatellite above its mask and
the spacecraft are separable (:func:`trackable`), with Gaussian noise and a station's range bias
(:func:`noisy_measurement`); a pass is a run of such epochs of one station, and a pass in view that delivered
nothing is lost (:func:`pass_lost`). The OD (``roe_sep.nodes.radar_od``) keeps every measurement as a
:class:`RadarRecord`, wherever it came from (the sensor or a ground segment's TDM), and estimates from the counted
passes (:func:`counted_passes`).
"""

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .radar import add_noise, visible


class RadarRecord(NamedTuple):
    """One measurement as the OD keeps it."""

    t: float
    """Epoch [s] (sim time)."""
    station: int
    """Index of the station in the OD's station list."""
    pass_id: int
    """The station's pass (> 0: the sensor's; < 0: an external pass, -(pass_id + 1) of the TDM's)."""
    z: np.ndarray
    """[range [m], azimuth [rad], elevation [rad]]."""
    chief: np.ndarray
    """The chief's mean Keplerian elements ``[a, e, i, raan, argp, M]`` at the epoch."""
    earth: np.ndarray
    """The GCRS -> ITRS rotation ``(3, 3)`` at the epoch (:func:`roe_sep.core.frames.gcrs_to_itrs`)."""
    truth_t: float
    """Epoch [s] of the chief sample the chief was propagated from."""


def trackable(elevation: ArrayLike, separation: ArrayLike, mask: float, min_separation: float) -> np.ndarray:
    """The epochs a station measures: the picosatellite above the elevation ``mask`` [rad] (:func:`visible`) and
    at least ``min_separation`` [m] from the carrier (``separation`` [m]; seed 001: 5 km)."""
    return visible(elevation, mask) & (np.asarray(separation, dtype=float) >= min_separation)


def noisy_measurement(z_true: ArrayLike, sigma: ArrayLike, rng: np.random.Generator,
                      range_bias: float = 0.0) -> np.ndarray:
    """A measurement ``[range, az, el]``: ``z_true`` + N(0, ``sigma``) (:func:`add_noise`, one draw per component
    from ``rng``) + the station's ``range_bias`` [m] on the range."""
    z = add_noise(z_true, sigma, rng)
    z[..., 0] += range_bias
    return z


def pass_lost(measurements: int, epochs_in_view: int, min_pass: int) -> bool:
    """Whether a closed pass was lost: the station had the picosatellite in view and separable for at least
    ``min_pass`` epochs (enough for a pass that counts) and delivered no measurement."""
    return measurements == 0 and epochs_in_view >= min_pass


def counted_passes(records: list[RadarRecord], last_burn: float, closed: set,
                   min_pass: int) -> tuple[list[RadarRecord], set]:
    """The records the OD uses: after the latest burn ``last_burn`` [s] (epoch and chief sample), in passes
    ``(station, pass_id)`` that are ``closed`` (a set; an external pass is closed) with at least ``min_pass`` such
    records. Returns (records in their order, set of passes)."""
    recs = [r for r in records if r.t >= last_burn and r.truth_t >= last_burn]
    counts = {}
    for r in recs:
        counts[(r.station, r.pass_id)] = counts.get((r.station, r.pass_id), 0) + 1
    good = {key for key, c in counts.items() if c >= min_pass and (key[1] < 0 or key in closed)}
    return [r for r in recs if (r.station, r.pass_id) in good], good
