"""Passive-safety and visibility metrics of a relative orbit (seeds 000/002)."""

import math
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import (
    SecularRates,
    _elements,
    _in_plane,
    arg_latitude_rate,
    propagate,
    secular_rates,
)
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import roe_to_rtn, wrap_angle


def min_rn_distance(roe: ArrayLike) -> np.ndarray:
    """Minimum distance in the plane normal to the flight direction (R-N), seed 002 Eq. (25), of ROE ``(..., 6)``:
    ``(...)``, in the unit of the ROE (dimensionless ROE: multiply by a for meters; a*ROE in m: meters).

    dr_min = sqrt(2) |de . di| / (de^2 + di^2 + |de + di| |de - di|)^(1/2), valid for da = 0; (anti-)parallel
    e/i vectors give min(de, di), perpendicular ones give 0.
    """
    r = np.asarray(roe, dtype=float)
    dex, dey, dix, diy = r[..., 2], r[..., 3], r[..., 4], r[..., 5]
    dot = dex * dix + dey * diy
    de2, di2 = dex * dex + dey * dey, dix * dix + diy * diy
    px, py, mx, my = dex + dix, dey + diy, dex - dix, dey - diy
    plus = np.sqrt(px * px + py * py)
    minus = np.sqrt(mx * mx + my * my)
    denom = np.sqrt(de2 + di2 + plus * minus)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(denom > 0.0, np.sqrt(2.0) * np.abs(dot) / denom, 0.0)


def min_rn_distance_one(dex: float, dey: float, dix: float, diy: float) -> float:
    """:func:`min_rn_distance` of one state given as the floats of its e/i components: the same expressions in the
    same order, evaluated on floats (IEEE sums, products, quotients and square roots are correctly rounded: the
    same bits as the array's), without the array set-up.

    Parameters
    ----------
    dex, dey, dix, diy : float
        The relative eccentricity and inclination vectors' components (dimensionless, or a*ROE in m).

    Returns
    -------
    float
        Eq. (25), in the unit of the components; 0 where it is undefined, as :func:`min_rn_distance`.
    """
    dot = dex * dix + dey * diy
    de2, di2 = dex * dex + dey * dey, dix * dix + diy * diy
    px, py, mx, my = dex + dix, dey + diy, dex - dix, dey - diy
    plus = math.sqrt(px * px + py * py)
    minus = math.sqrt(mx * mx + my * my)
    denom = math.sqrt(de2 + di2 + plus * minus)
    return _SQRT2 * abs(dot) / denom if denom > 0.0 else 0.0


_SQRT2 = float(np.sqrt(2.0))


def fov_limit(dl: ArrayLike, half_angle: ArrayLike) -> np.ndarray:
    """Largest oscillation amplitude that stays in a camera half field of view: tan(half) |dl|, seed 002 Eq. (11).

    Curvature neglected, as in the seed. ``half_angle`` [rad]; the result has the unit of ``dl`` and the broadcast
    shape.
    """
    return np.tan(half_angle) * np.abs(np.asarray(dl, dtype=float))


def approaching(roe: ArrayLike) -> np.ndarray:
    """True where the mean along-track separation shrinks: d(dl)/dt = -3/2 n da has the opposite sign of dl; ROE
    ``(..., 6)`` (dimensionless or in m), a boolean ``(...)``.

    Equivalent to da * dl > 0 (seed 002: 'approaching drift' is a da > 0 with the picosatellite leading).
    """
    r = np.asarray(roe, dtype=float)
    return r[..., 0] * r[..., 1] > 0.0


def nearest_crossing(roe0: ArrayLike, u0: ArrayLike, duration: float, a: float, inc: float, *, j2: bool = True,
                     da_dot: ArrayLike = 0.0, t_min: float | None = None,
                     iterations: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Smallest along-track distance |T| at a transit through the R = 0 plane in ``(t_min, duration]`` seconds.

    Seed 002 Fig. 8 / seed 001 AC2. In each revolution m the transit candidates come from the Keplerian
    solution of R/a = da - |de| cos(u - phi) = 0 with the elements at that revolution's start,
    u = phi +- arccos(da/|de|), and are refined by Newton iterations on the full secular model (:func:`propagate`
    then :func:`roe_to_rtn`: J2 and drag included). ``t_min`` excludes the trivial transit at t = 0 after an
    ejection. An orbit without radial motion (da = de = 0) lies in the R = 0 plane: its distance is |T| at ``t_min``.

    Parameters
    ----------
    roe0 : array_like, shape (..., 6)
        Dimensionless ROE at t = 0.
    u0 : array_like, shape (...)
        The chief's mean argument of latitude at t = 0 [rad].
    duration : float
        End of the window [s].
    a, inc : float
        The chief's semi-major axis [m] and inclination [rad].
    j2, da_dot : bool; array_like, shape (...)
        With the J2 secular rates; the differential-drag rate of da [1/s].
    t_min, iterations : float, optional; int
        Start of the window [s] (exclusive; default a tenth of an orbit); Newton iterations per candidate.

    Returns
    -------
    t_abs : numpy.ndarray, shape (...)
        The dimensionless |T|/a of the nearest transit (``inf`` where no transit occurs in the window).
    t : numpy.ndarray, shape (...)
        Its time [s] (``nan`` there).
    """
    r0 = np.asarray(roe0, dtype=float)
    batch = r0.shape[:-1]
    if not batch and np.ndim(u0) == 0 and np.ndim(da_dot) == 0:
        return nearest_crossing_one(r0, u0, duration, ChiefRates.of(a, inc, j2), da_dot, t_min=t_min,
                                    iterations=iterations)
    u0 = np.broadcast_to(np.asarray(u0, dtype=float), batch)
    dad = np.broadcast_to(np.asarray(da_dot, dtype=float), batch)
    # the six elements apart, contiguous (no strided (..., 6) views, no stack)
    el = tuple(np.ascontiguousarray(r0[..., k]) for k in range(6))
    flat = (np.abs(r0[..., 0]) < 1e-12) & (np.hypot(r0[..., 2], r0[..., 3]) < 1e-12)
    return _crossing(r0, el, u0, dad, duration, chief=ChiefRates.of(a, inc, j2), t_min=t_min, iterations=iterations,
                     n_batch=len(batch), flat=flat)


class ChiefRates(NamedTuple):
    """What the relative dynamics of one chief use again and again: a [m], i [rad], J2 on/off, its
    :func:`~roe_sep.core.relmotion.dynamics.secular_rates`, du/dt and n (the values of those functions)."""

    a: float
    inc: float
    j2: bool
    rates: SecularRates
    u_dot: float
    n: float

    @classmethod
    def of(cls, a: float, inc: float, j2: bool = True) -> "ChiefRates":
        """The chief's rates (each the value of its function: cached per chief for floats).

        Parameters
        ----------
        a, inc : float
            The chief's semi-major axis [m] and inclination [rad].
        j2 : bool
            With the J2 secular rates.

        Returns
        -------
        ChiefRates
            a, inc, j2, :func:`secular_rates`, :func:`arg_latitude_rate` and :func:`mean_motion`.
        """
        return cls(a, inc, j2, secular_rates(a, inc, j2), arg_latitude_rate(a, inc, j2), mean_motion(a))


def nearest_crossing_one(r0: ArrayLike, u0: float, duration: float, chief: ChiefRates, da_dot: float = 0.0,
                         *, t_min: float | None = None, iterations: int = 3) -> tuple[np.floating, np.ndarray]:
    """:func:`nearest_crossing` of one state, the chief's rates given: the same operations on the same values,
    element by element, without the batch's broadcasting and gathers (a state assessment's transits are 2-3
    revolutions, a few candidates). An element is the same computed in a batch or alone (elementwise operations,
    the nearest transit picked by argmin as in the batch).

    Parameters
    ----------
    r0 : array_like, shape (6,)
        Dimensionless ROE at t = 0.
    u0 : float
        The chief's mean argument of latitude at t = 0 [rad].
    duration : float
        End of the window [s].
    chief : ChiefRates
        The chief's a, i, J2 flag and rates (:meth:`ChiefRates.of`).
    da_dot : float
        Differential-drag rate of da [1/s].
    t_min, iterations : float, optional; int
        As for :func:`nearest_crossing`.

    Returns
    -------
    t_abs : numpy.floating
        The dimensionless |T|/a of the nearest transit (``inf`` if none), as :func:`nearest_crossing` returns it.
    t : numpy.ndarray, shape ()
        Its time [s] (``nan`` if none).
    """
    r0 = np.asarray(r0, dtype=float)
    el = r0.tolist()
    flat = abs(el[0]) < 1e-12 and np.hypot(el[2], el[3]) < 1e-12
    return _crossing(r0, el, float(u0), np.asarray(da_dot, dtype=float), duration, chief=chief, t_min=t_min,
                     iterations=iterations, n_batch=0, flat=flat)


def _crossing(r0, el, u0, dad, duration, *, chief: "ChiefRates", t_min, iterations, n_batch, flat):
    """The body of :func:`nearest_crossing` and :func:`nearest_crossing_one`: ``el`` the six elements apart (arrays
    of the batch's shape, or the floats of one state), ``n_batch`` the batch's dimensions, ``flat`` where there is
    no radial motion (a boolean array, or one bool). Candidates lie on a leading axis, samples last."""
    a, inc, j2, rates, u_dot, n = chief
    period = 2.0 * np.pi / u_dot
    if t_min is None:
        t_min = 0.1 * period
    da0, dex0, dey0 = el[0], el[2], el[3]
    lead = (-1,) + (1,) * n_batch
    with np.errstate(invalid="ignore", divide="ignore"):  # circular (de = 0) samples give NaN: masked below
        t_rev = (period * np.arange(int(np.ceil(duration / period)) + 1)).reshape(lead)
        da_s, dex_s, dey_s = _in_plane(da0, dex0, dey0, t_rev, dad, rates=rates)
        de, phi = np.hypot(dex_s, dey_s), np.arctan2(dey_s, dex_s)
        psi = np.arccos(np.clip(da_s / de, -1.0, 1.0))
        u_start = u0 + u_dot * t_rev
        cand = np.concatenate([phi + psi, phi - psi], axis=0)
        u_start2 = np.concatenate([u_start, u_start], axis=0)
        # one candidate of each kind per revolution, within half a revolution of that revolution's start
        t = np.concatenate([t_rev, t_rev]) + wrap_angle(cand - u_start2) / u_dot
        for _ in range(iterations):  # Newton on R = 0 with the full secular model (only the R and T components of
            da, dex, dey = _in_plane(da0, dex0, dey0, t, dad, rates=rates)  # roe_to_rtn, with its expressions)
            u = u0 + u_dot * t
            s, c = np.sin(u), np.cos(u)
            pos_r = da - dex * c - dey * s
            vel_r = dex * s - dey * c
            t = t - pos_r / (vel_r * n)
        da, dl, dex, dey, _, _ = _elements(el, t, dad, rates, out_of_plane=False)
        u = u0 + u_dot * t
        s, c = np.sin(u), np.cos(u)
        pos_r = da - dex * c - dey * s
        pos_t = dl + 2.0 * dex * s - 2.0 * dey * c
    ok = np.isfinite(t) & (t > t_min) & (t <= duration) & (np.abs(pos_r) < 1e-9)
    t_abs = np.where(ok, np.abs(pos_t), np.inf)
    idx = np.argmin(t_abs, axis=0)[None]
    best = np.take_along_axis(t_abs, idx, axis=0)[0]
    t_best = np.where(np.isfinite(best), np.take_along_axis(t, idx, axis=0)[0], np.nan)
    # an orbit with no radial motion at all (da = 0, de = 0) stays in the R = 0 plane: it "transits" everywhere,
    # at the along-track distance it has at t_min
    if np.any(flat):
        pos_min, _ = roe_to_rtn(propagate(r0, t_min, a, inc, j2, da_dot=dad), u0 + u_dot * t_min)
        best = np.where(flat, np.abs(pos_min[..., 1]), best)
        t_best = np.where(flat, t_min, t_best)
    return best, t_best
