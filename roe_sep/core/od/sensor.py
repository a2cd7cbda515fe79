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
    """The epochs a station measures: the picosatellite above the station's mask (:func:`visible`) and far enough
    from the carrier to be told apart (seed 001 Sec. 5: 5 km).

    Parameters
    ----------
    elevation : array_like
        The picosatellite's elevation [rad] seen from the station, one per epoch.
    separation : array_like
        The carrier-picosatellite distance [m] at the same epochs.
    mask, min_separation : float
        The elevation mask [rad] and the least separation [m].

    Returns
    -------
    numpy.ndarray of bool
        True where the station measures, the shape of the broadcast inputs.
    """
    return visible(elevation, mask) & (np.asarray(separation, dtype=float) >= min_separation)


def noisy_measurement(z_true: ArrayLike, sigma: ArrayLike, rng: np.random.Generator,
                      range_bias: float = 0.0) -> np.ndarray:
    """A measurement ``[range, az, el]``: the true one plus Gaussian noise and the station's range bias.

    Parameters
    ----------
    z_true : array_like, shape (..., 3)
        The true ``[range [m], azimuth [rad], elevation [rad]]``.
    sigma : array_like, shape (3,)
        The 1-sigma noise of each component (same units).
    rng : numpy.random.Generator
        The noise source: one draw per component (:func:`add_noise`).
    range_bias : float
        The station's range bias [m], added to every range.

    Returns
    -------
    numpy.ndarray, shape (..., 3)
        The measurement.
    """
    z = add_noise(z_true, sigma, rng)
    z[..., 0] += range_bias
    return z


def pass_lost(measurements: int, epochs_in_view: int, min_pass: int) -> bool:
    """Whether a closed pass was lost: the station had the picosatellite in view and separable long enough for a
    pass that counts, and delivered no measurement.

    Parameters
    ----------
    measurements : int
        The measurements the pass delivered.
    epochs_in_view : int
        The epochs of the pass at which the station could measure (:func:`trackable`).
    min_pass : int
        The least measurements of a pass the OD counts.

    Returns
    -------
    bool
        True for a lost pass.
    """
    return measurements == 0 and epochs_in_view >= min_pass


def counted_passes(records: list[RadarRecord], last_burn: float, closed: set,
                   min_pass: int) -> tuple[list[RadarRecord], set]:
    """The records the OD uses: after the latest burn, in closed passes with enough of them.

    Parameters
    ----------
    records : list of RadarRecord
        Every measurement kept, in arrival order.
    last_burn : float
        The latest burn's epoch [s]: a record's epoch and its chief sample (``truth_t``) must not precede it.
    closed : set of (int, int)
        The sensor's passes ``(station, pass_id)`` that have ended; an external pass (``pass_id < 0``) is closed.
    min_pass : int
        The least records a pass needs to count.

    Returns
    -------
    tuple
        ``(records, passes)``: the records used, in their order, and the set of passes ``(station, pass_id)``
        they come from.
    """
    recs = [r for r in records if r.t >= last_burn and r.truth_t >= last_burn]
    counts = {}
    for r in recs:
        counts[(r.station, r.pass_id)] = counts.get((r.station, r.pass_id), 0) + 1
    good = {key for key, c in counts.items() if c >= min_pass and (key[1] < 0 or key in closed)}
    return [r for r in recs if (r.station, r.pass_id) in good], good
