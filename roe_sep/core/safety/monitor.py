"""Safety assessment of a relative orbit over a prediction window: the criteria the safety monitor publishes.

Criteria (each a named pass/fail; ``ERROR`` ones decide ``safe``):

* ``keep_out`` (ERROR): once outside the keep-out sphere, the predicted distance never returns inside it (dense
  sampling of the linear RTN map along the secular trajectory).
* ``passive_safety`` (ERROR): relative e/i separation (seed 002 Eq. 25) of at least ``min_rn_distance``, or, where the
  e/i vectors do not separate the orbits (e.g. between ejection and drift-stop), no transit through the R = 0 plane
  closer than ``crossing_min`` along-track in the window (seed 002 Fig. 8 / seed 001 AC2).
* ``evaporation`` (ERROR): mean along-track separation |a dl| at the end of the window within ``evaporation``
  (seed 002: 50 km).
* ``drift_direction`` (WARN): the mean along-track separation is not shrinking (da dl <= 0).
* ``radar_separability`` (WARN): |a dl| >= ``a_dl_min`` (TIRA needs 5 km).
* ``fov`` (WARN): inside the camera field of view and range (seed 002 Eq. 11, |a dl| <= ``a_dl_max``).
"""

import functools
from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import _elements
from ..relmotion.trajectory import Burn, Chief, trajectory
from .metrics import ChiefRates, fov_limit, min_rn_distance_one, nearest_crossing_one

ERROR_CRITERIA = ("keep_out", "passive_safety", "evaporation")
WARN_CRITERIA = ("drift_direction", "radar_separability", "fov")


@dataclass(frozen=True)
class MonitorLimits:
    """Thresholds of the criteria [m, rad, s]."""

    keep_out: float = 1000.0
    min_rn_distance: float = 150.0
    crossing_min: float = 1500.0
    evaporation: float = 50e3
    a_dl_min: float = 5000.0
    a_dl_max: float = 10000.0
    fov_half_r: float = np.radians(6.8)
    fov_half_n: float = np.radians(9.15)
    window: float = 5700.0  # s, prediction window of a state assessment (about one orbit)
    plan_horizon: float = 86400.0  # s, prediction after a plan's last burn
    samples_per_orbit: int = 360


@dataclass
class Assessment:
    """Result of one assessment; distances in meters."""

    approaching: bool
    along_track_separation: float  # m, a dl at the assessed epoch
    distance: float  # m, |r| at the assessed epoch
    min_distance: float  # m, minimum |r| over the window once outside the keep-out sphere
    min_rn_distance: float  # m, Eq. (25) at the end state
    nearest_crossing: float  # m, inf when no R = 0 transit in the window
    evaporated: bool
    in_fov: bool
    failed: list = field(default_factory=list)  # names of failed criteria

    @property
    def safe(self) -> bool:
        """No ERROR criterion failed."""
        return not any(name in ERROR_CRITERIA for name in self.failed)

    @property
    def level(self) -> int:
        """0 OK, 1 WARN, 2 ERROR (diagnostic_msgs levels)."""
        if not self.safe:
            return 2
        return 1 if self.failed else 0


def in_fov(roe: ArrayLike, limits: MonitorLimits) -> np.ndarray:
    """Seed 002 Eq. (11) at the state's own separation and the camera range (a dl within a_dl_max): a*ROE
    ``(..., 6)`` in m -> a boolean ``(...)``."""
    r = np.asarray(roe, dtype=float)
    dl = np.abs(r[..., 1])
    de, di = np.hypot(r[..., 2], r[..., 3]), np.hypot(r[..., 4], r[..., 5])
    return (dl <= limits.a_dl_max) & (de <= fov_limit(dl, limits.fov_half_r)) & (di <= fov_limit(dl, limits.fov_half_n))


@functools.lru_cache(maxsize=16)
def _arange(num: int) -> np.ndarray:
    y = np.arange(0, num, dtype=float)
    y.flags.writeable = False
    return y


def linspace(start: float, stop: float, num: int) -> np.ndarray:
    """``numpy.linspace(start, stop, num)`` for scalar ``start``, ``stop`` and ``num`` >= 2, with its arithmetic:
    ``arange(num) * step + start`` (``step = (stop - start) / (num - 1)``; a zero step as ``/ div * delta``),
    the last sample ``stop``; without its general set-up (array conversion, dtype and axis handling).

    Parameters
    ----------
    start, stop : float
        The first and last sample.
    num : int
        The number of samples, at least 2.

    Returns
    -------
    numpy.ndarray, shape (num,)
        The samples, those of ``numpy.linspace`` to the bit.
    """
    div = num - 1
    delta = float(stop) - float(start)
    step = delta / div
    if step == 0:
        y = _arange(num) / div
        y *= delta
    else:
        y = _arange(num) * step
    y += float(start)
    y[-1] = stop
    return y


def _in_fov_one(end: list, limits: MonitorLimits) -> bool:
    """:func:`in_fov` of one a*ROE state given as six floats: its expressions, element by element."""
    dl = abs(end[1])
    return bool(dl <= limits.a_dl_max and np.hypot(end[2], end[3]) <= fov_limit(dl, limits.fov_half_r)
                and np.hypot(end[4], end[5]) <= fov_limit(dl, limits.fov_half_n))


def assess(roe0: ArrayLike, t0: float, chief: Chief, limits: MonitorLimits, burns: Iterable[Burn] = (),
           *, t_end: float | None = None, j2: bool = True, da_dot: float = 0.0) -> Assessment:
    """Assess the trajectory from dimensionless ``roe0`` at ``t0`` [s] under ``burns`` up to ``t_end``.

    ``t_end`` defaults to ``t0 + limits.window`` (a state), a plan check passes its last burn + ``plan_horizon``.
    The passive-safety, drift and evaporation criteria use the end state; keep-out covers the whole window and the
    R = 0 transits the part after the last burn (from a tenth of an orbit on, so that a state taken right at an
    ejection does not count its own starting point).

    Parameters
    ----------
    roe0 : array_like, shape (6,)
        Dimensionless ROE at ``t0``.
    t0 : float
        Epoch of ``roe0`` [s].
    chief : Chief
        The chief's a, i and argument of latitude.
    limits : MonitorLimits
        The thresholds.
    burns : iterable of Burn
        Relative impulses (a plan's, or none for a state).
    t_end : float, optional
        End of the window [s]; default ``t0 + limits.window``.
    j2, da_dot : bool, float
        With the J2 secular rates; the differential-drag rate of da [1/s].

    Returns
    -------
    Assessment
        The distances [m] and the failed criteria.
    """
    a, inc = chief.a, chief.inc
    rates = ChiefRates.of(a, inc, j2)  # the chief's rates, looked up once for the calls below
    t_end = t0 + limits.window if t_end is None else t_end
    n_samples = max(2, int(limits.samples_per_orbit * (t_end - t0) / (2.0 * np.pi / rates.n)) + 1)  # per orbit
    times = linspace(t0, t_end, n_samples)
    burn_epochs = [b.epoch for b in burns if b.epoch >= t0]
    if burn_epochs or not (times < np.inf).all():
        # under burns: the trajectory's arcs; its columns are the elements below
        roes = trajectory(roe0, t0, burns, times, chief, j2=j2, da_dot=da_dot)
        el = tuple(roes.T)
        last_burn = max(burn_epochs, default=t0)
        start = trajectory(roe0, t0, burns, np.array([last_burn]), chief, j2=j2, da_dot=da_dot)[0] if burn_epochs \
            else roes[0]
    else:
        # one coast arc: the trajectory's propagation from roe0 (segments_at), its six elements kept apart
        if (times < t0).any():
            raise ValueError("trajectory times must not precede t0")
        el = _elements(tuple(np.asarray(roe0, dtype=float)), times - float(t0), np.asarray(da_dot, dtype=float),
                       rates.rates)
        last_burn = t0
        start = np.array([e[0] for e in el])  # the state at t0 (times[0] is t0): the same propagation
    # rtn_position of the samples (its expressions) and their norm as numpy.linalg.norm forms it along the last
    # axis, sqrt((R^2 + T^2) + N^2), without stacking the (n, 6) states and the (n, 3) positions
    da, dl, dex, dey, dix, diy = el
    u = chief.u0 + rates.u_dot * (times - chief.t0)  # chief.u_at(times, j2)
    sn, cs = np.sin(u), np.cos(u)
    pos_r = da - dex * cs - dey * sn
    pos_t = dl + 2.0 * dex * sn - 2.0 * dey * cs
    pos_n = dix * sn - diy * cs
    dist = np.sqrt(pos_r * pos_r + pos_t * pos_t + pos_n * pos_n) * a
    # keep-out counts returns: from the first sample outside the sphere on (a trajectory that starts at an
    # ejection begins at zero distance by construction); one that never leaves it is measured throughout
    outside = np.nonzero(dist >= limits.keep_out)[0]
    returning = dist[outside[0]:] if outside.size else dist
    u_last = chief.u0 + rates.u_dot * (float(last_burn) - chief.t0)  # chief.u_at(last_burn, j2)
    crossing, _ = nearest_crossing_one(start, u_last, t_end - last_burn, rates, da_dot)
    end = [float(e[-1] * a) for e in el]  # the end state in m, the criteria's expressions on its floats
    res = Assessment(
        approaching=bool(end[0] * end[1] > 0.0),
        along_track_separation=float(dl[0] * a),
        distance=float(dist[0]),
        min_distance=float(returning.min()),
        min_rn_distance=min_rn_distance_one(*end[2:]),
        nearest_crossing=float(crossing * a),
        evaporated=bool(abs(end[1]) > limits.evaporation),
        in_fov=_in_fov_one(end, limits),
    )
    checks = {
        "keep_out": res.min_distance >= limits.keep_out,
        "passive_safety": res.min_rn_distance >= limits.min_rn_distance or res.nearest_crossing >= limits.crossing_min,
        "evaporation": not res.evaporated,
        "drift_direction": not res.approaching,
        "radar_separability": abs(end[1]) >= limits.a_dl_min,
        "fov": res.in_fov,
    }
    res.failed = [name for name, ok in checks.items() if not ok]
    return res
