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

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.orbit import orbital_period
from ..relmotion.roe import rtn_position
from ..relmotion.trajectory import Burn, Chief, trajectory
from .metrics import approaching, fov_limit, min_rn_distance, nearest_crossing

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


def assess(roe0: ArrayLike, t0: float, chief: Chief, limits: MonitorLimits, burns: Iterable[Burn] = (),
           t_end: float | None = None, j2: bool = True, da_dot: float = 0.0) -> Assessment:
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
    j2 : bool
        With the J2 secular rates.
    da_dot : float
        Differential-drag rate of da [1/s].

    Returns
    -------
    Assessment
        The distances [m] and the failed criteria.
    """
    a = chief.a
    t_end = t0 + limits.window if t_end is None else t_end
    n_samples = max(2, int(limits.samples_per_orbit * (t_end - t0) / orbital_period(a)) + 1)
    times = np.linspace(t0, t_end, n_samples)
    roes = trajectory(roe0, t0, burns, times, chief, j2, da_dot)
    pos = rtn_position(roes, chief.u_at(times, j2))
    dist = np.linalg.norm(pos, axis=-1) * a
    # keep-out counts returns: from the first sample outside the sphere on (a trajectory that starts at an
    # ejection begins at zero distance by construction); one that never leaves it is measured throughout
    outside = np.nonzero(dist >= limits.keep_out)[0]
    returning = dist[outside[0]:] if outside.size else dist
    burn_epochs = [b.epoch for b in burns if b.epoch >= t0]
    last_burn = max(burn_epochs, default=t0)
    # without a burn the state at last_burn = t0 is the first sample (times[0] is t0: the same propagation)
    start = trajectory(roe0, t0, burns, np.array([last_burn]), chief, j2, da_dot)[0] if burn_epochs else roes[0]
    crossing, _ = nearest_crossing(start, chief.u_at(last_burn, j2), t_end - last_burn, a, chief.inc, j2, da_dot)
    end = roes[-1] * a
    res = Assessment(
        approaching=bool(approaching(end)),
        along_track_separation=float(roes[0][1] * a),
        distance=float(dist[0]),
        min_distance=float(returning.min()),
        min_rn_distance=float(min_rn_distance(end)),
        nearest_crossing=float(crossing * a),
        evaporated=bool(abs(end[1]) > limits.evaporation),
        in_fov=bool(in_fov(end, limits)),
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
