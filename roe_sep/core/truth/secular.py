"""The simulator's truth: chief mean elements and the relative orbit, with burns applied as they are executed.

Before the ejection the picosatellite rides in the carrier (ROE zero, no differential drag); from the ejection on
the relative orbit follows the secular model (:func:`~roe_sep.core.relmotion.dynamics.propagate`: Keplerian drift, J2
and the *true* differential drag ``da_dot``) and each executed burn adds seed 002 Eq. (2) at the chief's argument of
latitude of that instant.
"""

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import arg_latitude_rate, propagate, propagate_chief
from ..relmotion.maneuvers import delta_roe, dispersed_dv, unreduced_burns
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import roe_to_rtn
from ..relmotion.trajectory import Chief


@dataclass
class TruthModel:
    """Mutable truth state. ``chief0``: mean Keplerian ``[a, e, i, raan, argp, M]`` at ``t0`` [s]."""

    chief0: np.ndarray
    t0: float
    da_dot: float  # 1/s, true differential-drag drift of da after the ejection
    j2: bool = True
    roe: np.ndarray = field(default_factory=lambda: np.zeros(6))
    t_state: float = 0.0
    separated: bool = False
    storm: object = None  # a contingency's DensityStorm: da_dot times its factor in its window after the ejection
    ejected_at: float | None = None  # s, the separation (the storm's window starts from it)

    def __post_init__(self):
        self.chief0 = np.asarray(self.chief0, dtype=float)
        self.t_state = self.t0

    @property
    def a(self) -> float:
        """The chief's semi-major axis [m]."""
        return float(self.chief0[0])

    @property
    def inc(self) -> float:
        """The chief's inclination [rad]."""
        return float(self.chief0[2])

    def chief(self) -> Chief:
        """The chief as the relative dynamics need it (u at ``t0`` = argp + M)."""
        return Chief(self.a, self.inc, float(self.chief0[4] + self.chief0[5]), self.t0)

    def chief_elements(self, t: ArrayLike) -> np.ndarray:
        """Chief mean Keplerian elements ``(..., 6)`` at ``t`` [s] (any shape)."""
        return propagate_chief(self.chief0, np.asarray(t, dtype=float) - self.t0, self.j2)

    def u_at(self, t: ArrayLike) -> np.ndarray:
        """The chief's mean argument of latitude [rad], not wrapped, at ``t`` [s]."""
        return self.chief().u_at(t, self.j2)

    def roe_at(self, t: ArrayLike) -> np.ndarray:
        """Dimensionless ROE ``(..., 6)`` at ``t`` [s] >= the last event (scalar or array of times)."""
        dt = np.asarray(t, dtype=float) - self.t_state
        if not self.separated:
            return np.zeros(np.shape(dt) + (6,))
        if self.storm is not None:
            return self._roe_in_storm(np.asarray(t, dtype=float))
        return propagate(self.roe if np.ndim(dt) == 0 else self.roe[None, :], dt, self.a, self.inc, self.j2,
                         da_dot=self.da_dot)

    def _roe_in_storm(self, t: np.ndarray) -> np.ndarray:
        """:meth:`roe_at` with the storm: the differential drag ``da_dot`` times the density factor, constant between
        the window's edges, propagated piecewise from the last event across them."""
        flat = t.reshape(-1)
        out = np.empty((flat.size, 6))
        anchor, t_a = self.roe, self.t_state
        edges = [e for e in self.storm.window(self.ejected_at) if e > t_a] + [math.inf]
        done = np.zeros(flat.size, bool)
        for edge in edges:
            da_dot = self.da_dot * float(self.storm.factor_at(t_a, self.ejected_at))
            sel = ~done & (flat <= edge)
            if np.any(sel):
                out[sel] = propagate(anchor[None, :], flat[sel] - t_a, self.a, self.inc, self.j2, da_dot=da_dot)
                done |= sel
            if edge < math.inf:
                anchor, t_a = propagate(anchor, edge - t_a, self.a, self.inc, self.j2, da_dot=da_dot), edge
        return out.reshape(t.shape + (6,))

    def samples(self, t: ArrayLike) -> tuple:
        """Carrier mean elements ``(T, 6)``, ROE ``(T, 6)`` and the RTN state (position [m], velocity [m/s], each
        ``(T, 3)``) at the times ``t`` ``(T,)`` [s], as the nonlinear truth's."""
        t = np.asarray(t, dtype=float)
        return self.chief_elements(t), self.roe_at(t), self.rtn_at(t)

    def rtn_at(self, t: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Relative position [m] and velocity [m/s], each ``(..., 3)``, in the carrier RTN frame at ``t`` [s]."""
        pos, vel = roe_to_rtn(self.roe_at(t), self.u_at(t))
        return pos * self.a, vel * self.a * mean_motion(self.a)

    def distances(self, t_from: float, t_to: float, step: float) -> tuple[np.ndarray, np.ndarray]:
        """Times and |r| [m] over ``[t_from, t_to]`` sampled every ``step`` seconds (and at both ends).

        Parameters
        ----------
        t_from, t_to : float
            The window [s], ``t_from`` >= the last event.
        step : float
            The sampling [s].

        Returns
        -------
        (numpy.ndarray, numpy.ndarray), each shape (T,)
            Times [s] and distances [m].
        """
        times = np.append(np.arange(t_from, t_to, step), t_to)
        return times, np.linalg.norm(self.rtn_at(times)[0], axis=-1)

    def apply(self, t: float, dv_rel: ArrayLike, spacecraft: str | None = None) -> None:
        """Execute a relative impulse ``(3,)`` [m/s] RTN at ``t`` [s] (the ejection: the picosatellite's; a carrier
        burn: minus its own); ``spacecraft`` (which one burnt) changes nothing here: the relative orbit is all this
        model has.

        Parameters
        ----------
        t : float
            The epoch [s], >= the last event.
        dv_rel : array_like, shape (3,)
            The relative impulse [m/s] RTN of the seed convention.
        spacecraft : str or None
            Who burns (``picosatellite`` or ``carrier``); ignored.

        Returns
        -------
        None
        """
        state = self.roe_at(t)
        if not self.separated:
            self.ejected_at = float(t)
        self.roe = state + delta_roe(np.asarray(dv_rel, dtype=float), self.u_at(t), self.a, mean_motion(self.a))
        self.t_state = float(t)
        self.separated = True


REDUCED_PURPOSES = ("drift_stop", "drift_reduction")
"""Purposes of the burns commanded with the drift-stop reduction |p| of seed 002 Eq. (18) (the double impulse's
drift-stop, the multi-impulse scheme's drift-reduction burns)."""


def error_references(purposes: Sequence[str], dvs: Sequence[ArrayLike], p: float) -> list:
    """Per burn of one plan, the burn its magnitude error acts on (the ``reference`` of
    :func:`~roe_sep.core.relmotion.maneuvers.dispersed_dv`): for the burns of ``REDUCED_PURPOSES`` together the
    unreduced drift-stop (:func:`~roe_sep.core.relmotion.maneuvers.unreduced_burns` with the plan's |p|, seed 002
    Eq. 18), ``None`` (the commanded burn itself, Eq. 22) for every other burn.

    Parameters
    ----------
    purposes : sequence of str
        Each burn's purpose.
    dvs : sequence of array_like, each shape (3,)
        Each burn as commanded [m/s].
    p : float
        The plan's reduction |p| [m/s], finite and non-negative.

    Returns
    -------
    list of numpy.ndarray or None
        Per burn, the reference burn ``(3,)`` [m/s] or None.
    """
    if not np.isfinite(p) or p < 0:
        raise ValueError(f"p_reduction must be a finite non-negative number [m/s], got {p}")
    idx = [k for k, purpose in enumerate(purposes) if purpose in REDUCED_PURPOSES]
    refs = [None] * len(purposes)
    if idx and p:
        for k, ref in zip(idx, unreduced_burns([dvs[k] for k in idx], p)):
            refs[k] = ref
    return refs


@dataclass
class ExecutionErrors:
    """Seeded execution errors of seed 002 Eqs. (18) and (22): magnitude factor and attitude errors per burn."""

    rng: np.random.Generator
    spl_sigma: float
    thruster_sigma: float
    attitude_sigma: float  # rad, per axis
    applied: list = field(default_factory=list)  # (spacecraft, factor, eps) of every burn, as drawn

    def executed(self, dv_own: ArrayLike, spacecraft: str, reference: ArrayLike | None = None) -> np.ndarray:
        """The burn as executed: :func:`~roe_sep.core.relmotion.maneuvers.dispersed_dv` with f ~ N(1, sigma of the SPL
        or of the carrier thruster); ``reference`` the unreduced burn of a reduced drift-stop
        (:func:`error_references`), ``None``: the error is a fraction of ``dv_own`` itself.

        Parameters
        ----------
        dv_own : array_like, shape (3,)
            The commanded burn [m/s], RTN, of the spacecraft itself.
        spacecraft : str
            ``picosatellite`` (the SPL's sigma) or the carrier.
        reference : array_like, shape (3,), optional
            The burn the magnitude error is a fraction of [m/s].

        Returns
        -------
        numpy.ndarray, shape (3,)
            The executed burn [m/s].
        """
        sigma = self.spl_sigma if spacecraft == "picosatellite" else self.thruster_sigma
        factor = self.rng.normal(1.0, sigma)
        eps = self.rng.normal(0.0, self.attitude_sigma, 3)
        self.applied.append((spacecraft, float(factor), [float(e) for e in eps]))
        return dispersed_dv(dv_own, factor, eps, reference)


def chief_from_u(a: float, inc: float, raan: float, u: float) -> np.ndarray:
    """Circular chief mean elements ``[a, 0, i, raan, 0, u]`` (argument of perigee 0, M = u).

    Parameters
    ----------
    a : float
        Semi-major axis [m].
    inc, raan, u : float
        Inclination, right ascension of the ascending node and mean argument of latitude [rad].

    Returns
    -------
    numpy.ndarray, shape (6,)
        ``[a, e, i, raan, argp, M]`` (m, 1, rad, rad, rad, rad).
    """
    return np.array([a, 0.0, inc, raan, 0.0, u], dtype=float)


def time_to_arg_latitude(u_now: float, u_target: float, a: float, inc: float, j2: bool = True) -> float:
    """Seconds until the chief's mean argument of latitude next reaches ``u_target`` (in [0, one period)).

    Parameters
    ----------
    u_now, u_target : float
        Mean arguments of latitude [rad].
    a : float
        Semi-major axis [m].
    inc : float
        Inclination [rad].
    j2 : bool
        With the J2 secular rate.

    Returns
    -------
    float
        The time [s].
    """
    return float(np.mod(u_target - u_now, 2.0 * np.pi) / arg_latitude_rate(a, inc, j2))
