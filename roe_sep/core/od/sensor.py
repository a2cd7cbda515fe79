"""The radar sensor's pure parts and the OD's measurement records (seed 001 Sec. 5: radar tracking of the
picosatellite, TIRA separating the two spacecraft from 5 km on).

The sensor (``roe_sep.nodes.radar``) measures an epoch when the station sees the picosatellite above its mask and
the spacecraft are separable (:func:`trackable`), with Gaussian noise and a station's range bias
(:func:`noisy_measurement`); a pass is a run of such epochs of one station, and a pass in view that delivered
nothing is lost (:func:`pass_lost`). The OD (``roe_sep.nodes.radar_od``) keeps every measurement as a
:class:`RadarRecord`, wherever it came from (the sensor or a ground segment's TDM), and estimates from the counted
passes (:func:`counted_passes`).
"""

import bisect
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import propagate, propagate_chief
from ..relmotion.roe import wrap_angle
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


class TruthSamples(NamedTuple):
    """Truth samples, one per epoch of a vectorized call: their times, ROE and chief elements."""

    t: np.ndarray
    """Sample epochs [s], shape (n,)."""
    roe: np.ndarray
    """Dimensionless ROE ``[da, dl, dex, dey, dix, diy]``, shape (n, 6)."""
    kep: np.ndarray
    """The chief's mean Keplerian elements ``[a, e, i, raan, argp, M]``, shape (n, 6)."""


def sample_pair(history_t: Sequence[float], burns: Sequence[float], t: float) -> tuple[int, int]:
    """Indices of the truth samples an epoch ``t`` is simulated from (:func:`truth_between`): the first sample at or
    after ``t`` (the latest if none) and the one before it, or that sample again for the first sample or across a
    burn (one in (t_before, t_after]: the truth is not continuous there).

    Parameters
    ----------
    history_t : sequence of float
        Every truth sample's epoch [s], sorted (a burn's post-burn sample has replaced its pre-burn one).
    burns : sequence of float
        Every executed burn's epoch [s], sorted.
    t : float
        The epoch [s].

    Returns
    -------
    tuple of int
        (after, before) indices into ``history_t``; ``before == after`` where there is no earlier sample to blend.
    """
    k = min(bisect.bisect_left(history_t, t), len(history_t) - 1)
    if k == 0:
        return 0, 0
    b = bisect.bisect_right(burns, history_t[k - 1])
    return (k, k) if b < len(burns) and burns[b] <= history_t[k] else (k, k - 1)


def _weight_before(epochs: np.ndarray, after: TruthSamples, before: TruthSamples) -> np.ndarray:
    """1 - s of :func:`truth_between`: the earlier sample's weight at each epoch, shape (n, 1)."""
    span = after.t - before.t
    s = np.where(span > 0.0, np.clip((epochs - before.t) / np.where(span > 0.0, span, 1.0), 0.0, 1.0), 1.0)
    return (1.0 - s)[:, None]


def chief_between(epochs: ArrayLike, after: TruthSamples, before: TruthSamples) -> np.ndarray:
    """The chief's elements of :func:`truth_between` alone (the samples' ``roe`` are not read).

    Parameters
    ----------
    epochs : array_like, shape (n,)
        Epochs [s].
    after, before : TruthSamples
        As for :func:`truth_between`.

    Returns
    -------
    numpy.ndarray, shape (n, 6)
        The chief's mean elements ``[a, e, i, raan, argp, M]`` at the epochs.
    """
    epochs = np.asarray(epochs, dtype=float)
    w = _weight_before(epochs, after, before)
    kep_a = propagate_chief(after.kep, epochs - after.t)
    kep_b = propagate_chief(before.kep, epochs - before.t)
    kep = kep_a.copy()
    kep[:, :3] += w * (kep_b[:, :3] - kep_a[:, :3])
    kep[:, 3] += w[:, 0] * wrap_angle(kep_b[:, 3] - kep_a[:, 3])
    kep[:, 5] += w[:, 0] * wrap_angle(kep_b[:, 4] + kep_b[:, 5] - kep_a[:, 4] - kep_a[:, 5])
    return kep


def chief_from_samples(history_t: Sequence[float], history_kep: ArrayLike, burns: Sequence[float],
                       t: float) -> tuple[np.ndarray, float]:
    """The chief's elements at one epoch from a sorted history of samples: the pair of :func:`sample_pair`
    blended by :func:`chief_between` (how the sensor simulated a measurement at ``t``).

    Parameters
    ----------
    history_t, burns : sequence of float
        As for :func:`sample_pair`.
    history_kep : array_like, shape (n, 6)
        The samples' mean elements ``[a, e, i, raan, argp, M]``.
    t : float
        The epoch [s].

    Returns
    -------
    tuple
        (the elements (6,), the later sample's epoch [s]).
    """
    k, j = sample_pair(history_t, burns, t)
    kep = np.asarray(history_kep, dtype=float)
    pair = (TruthSamples(np.array([history_t[i]], dtype=float), None, kep[i:i + 1]) for i in (k, j))
    return chief_between(np.array([t], dtype=float), *pair)[0], float(history_t[k])


def truth_between(epochs: ArrayLike, after: TruthSamples, before: TruthSamples, da_dot: ArrayLike) -> tuple:
    """The truth at measurement epochs between two samples: each sample carried to the epoch with the J2 secular
    rates (:func:`~roe_sep.core.relmotion.dynamics.propagate` with the truth's own drift of da ``da_dot``,
    :func:`~roe_sep.core.relmotion.dynamics.propagate_chief`), weighted linearly in time,

        x(t) = (1 - s) x_before(t) + s x_after(t),   s = (t - t_before) / (t_after - t_before),

    with s clipped to [0, 1] and s = 1 where ``before`` is ``after`` (no earlier sample, or a burn between them).
    The truth's samples do not lie on one secular arc (its nonlinear motion, drag, the mean-osculating map), so
    carrying the later sample alone jumps at every sample by the difference between the two carried states (up to
    16 m of range in the reference run, against the radar's 10 m): the blend is continuous, exact at both samples,
    and leaves an error of second order in the arcs' difference, which is what an ephemeris interpolated through the
    same samples (the OEM of :mod:`roe_sep.ndm.dataset`) reproduces. The chief (:func:`chief_between`): a, e, i
    and raan blend as above; its mean argument of latitude u = argp + M blends through the wrapped difference, argp
    staying the later sample's (M = u - argp).

    Parameters
    ----------
    epochs : array_like, shape (n,)
        Measurement epochs [s].
    after, before : TruthSamples
        The first sample at or after each epoch, and the sample before it (``after`` itself where there is none).
    da_dot : array_like, shape (n,)
        The truth's drift of da [1/s] between the two samples (:func:`~roe_sep.core.od.radar.truth_da_rate`).

    Returns
    -------
    tuple
        (ROE (n, 6), chief elements (n, 6)) at the epochs.
    """
    epochs = np.asarray(epochs, dtype=float)
    da_dot = np.asarray(da_dot, dtype=float)
    w = _weight_before(epochs, after, before)
    roe_a = propagate(after.roe, epochs - after.t, after.kep[:, 0], after.kep[:, 2], True, da_dot=da_dot)
    roe_b = propagate(before.roe, epochs - before.t, before.kep[:, 0], before.kep[:, 2], True, da_dot=da_dot)
    return roe_a + w * (roe_b - roe_a), chief_between(epochs, after, before)


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
