"""The evaporation column of seed 002 Table 3, P(a dl > 50 km) 24 h after the drift-stop: what the stated set-up
gives and what the published column would require of it (issue 20).

The secular propagation (:func:`~roe_sep.core.relmotion.dynamics.propagate`) is linear in the ROE and in the drag
rate, and the drag rate of Eqs. (23)-(24) is linear in the differential ballistic coefficient. For one set of draws
(:func:`~roe_sep.core.montecarlo.sweep.draw`) the along-track separation ``horizon`` after the drift-stop is therefore
affine in each sample's dB factor,

    a dl_i(h) = L_i(h) + db_i s(h),

L_i the drag-free drift of sample i (ejection and Eq. 18 drift-stop with their dispersions, then h of drift), s(h)
the drift the nominal differential drag adds from the ejection to h after the stop. The evaporation fraction is then
recomputed for any horizon, any dB uncertainty (db' = 1 + (sigma'/sigma)(db - 1), the same normal deviates: common
random numbers) or any scale of the nominal dB without repeating the Monte Carlo, and :meth:`EvaporationModel.solve`
finds the value of one of them at which the fraction reaches a published one.
"""

from dataclasses import dataclass

import numpy as np

from ...errors import show
from ..relmotion.dynamics import drag_da_dot, propagate
from ..separation.double_impulse import DoubleImpulseDesign
from .sweep import Draws, MonteCarloConfig, drift_stop_delta_roe, ejection_roe, time_to_stop

PARAMETERS = ("horizon", "ballistic_sigma", "db_scale")
"""What :meth:`EvaporationModel.solve` can vary: the horizon after the drift-stop [s], the relative 1-sigma of dB,
and a factor on the nominal dB (equivalently on the density)."""


@dataclass(frozen=True)
class EvaporationModel:
    """The affine form a dl_i = L_i + db_i s of one p on one set of draws (see the module docstring)."""

    design: DoubleImpulseDesign
    mc: MonteCarloConfig
    p: float
    roe_stop: np.ndarray  # (N, 6) dimensionless, right after the drift-stop without drag
    drag_roe_stop: np.ndarray  # (6,) drift of the nominal drag from the ejection to the drift-stop
    unit_da_dot: float  # 1/s, the nominal dB's da_dot (0 without drag)
    db_factor: np.ndarray  # (N,) the drawn dB factors

    @property
    def samples(self) -> int:
        """N, the number of draws."""
        return self.db_factor.shape[0]

    def along_track(self, horizon: float | None = None, db: np.ndarray | None = None) -> np.ndarray:
        """a dl ``(N,)`` [m] ``horizon`` [s] after the drift-stop (default ``mc.horizon``) with dB factors ``db``
        ``(N,)`` (default: the drawn ones)."""
        d, mc = self.design, self.mc
        h = mc.horizon if horizon is None else float(horizon)
        db = self.db_factor if db is None else db
        free = propagate(self.roe_stop, h, d.a, d.inc, mc.j2, da_dot=0.0)[:, 1]
        drag = (propagate(self.drag_roe_stop, h, d.a, d.inc, mc.j2, da_dot=0.0)
                + propagate(np.zeros(6), h, d.a, d.inc, mc.j2, da_dot=self.unit_da_dot))[1]
        return (free + db * drag) * d.a

    def db(self, ballistic_sigma: float | None = None, db_scale: float = 1.0) -> np.ndarray:
        """dB factors ``(N,)`` with another relative 1-sigma (the same deviates; None: the drawn one) and a scale of
        the nominal dB."""
        if ballistic_sigma is None:
            return db_scale * self.db_factor
        sigma = self.mc.ballistic_sigma
        if sigma <= 0:
            raise ValueError("ballistic_sigma of the draws is 0: no deviates to rescale")
        return db_scale * (1.0 + (float(ballistic_sigma) / sigma) * (self.db_factor - 1.0))

    def count(self, horizon: float | None = None, ballistic_sigma: float | None = None, db_scale: float = 1.0) -> int:
        """Number of samples with |a dl| > ``mc.evaporation_distance`` (seed 002 Table 3's evaporation).

        Parameters
        ----------
        horizon : float, optional
            After the drift-stop [s] (default ``mc.horizon``).
        ballistic_sigma : float, optional
            Relative 1-sigma of dB (default the drawn one).
        db_scale : float
            Factor on the nominal dB.

        Returns
        -------
        int
            The count among the N samples.
        """
        dl = self.along_track(horizon, self.db(ballistic_sigma, db_scale))
        return int(np.count_nonzero(np.abs(dl) > self.mc.evaporation_distance))

    def fraction(self, **kw) -> float:
        """:meth:`count` over the number of samples (the keywords of :meth:`count`)."""
        return self.count(**kw) / self.samples

    def solve(self, target: float, parameter: str, lo: float, hi: float, rel_tol: float = 1e-4) -> float | None:
        """The smallest value of ``parameter`` (one of ``PARAMETERS``) in [lo, hi] at which the evaporation fraction
        reaches ``target``, by bisection (the fraction grows with each of them); ``None`` when it stays below
        ``target`` at ``hi``. The other two keep the set-up's values.

        Parameters
        ----------
        target : float
            The evaporation fraction, in [0, 1].
        parameter : str
            ``horizon`` [s], ``ballistic_sigma`` (relative) or ``db_scale``.
        lo, hi : float
            The bracket, in the parameter's unit.
        rel_tol : float
            The bisection stops at a bracket narrower than ``rel_tol * hi``.

        Returns
        -------
        float or None
            The value (the upper end of the final bracket), or None.
        """
        if parameter not in PARAMETERS:
            raise ValueError(f"parameter must be one of {PARAMETERS}, got {show(parameter)}")

        def frac(x):
            return self.fraction(**{parameter: x})

        if frac(hi) < target:
            return None
        if frac(lo) >= target:
            return float(lo)
        while hi - lo > rel_tol * hi:
            mid = 0.5 * (lo + hi)
            lo, hi = (lo, mid) if frac(mid) >= target else (mid, hi)
        return float(hi)


def evaporation_model(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws, p: float) -> EvaporationModel:
    """The affine evaporation model of reduction ``p`` [m/s] on the draws ``d`` (the sweep's functions for the
    ejection and the Eq. 18 drift-stop).

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        Drag, density, J2, horizon and evaporation distance.
    d : Draws
        The dispersions of N samples.
    p : float
        The reduction [m/s].

    Returns
    -------
    EvaporationModel
        a dl = L + dB s per sample, evaluated by its methods.
    """
    a, inc = design.a, design.inc
    dt_stop = time_to_stop(design, mc)
    roe_stop = propagate(ejection_roe(design, d), dt_stop, a, inc, mc.j2) + drift_stop_delta_roe(design, d, p)
    unit = float(drag_da_dot(mc.delta_b, mc.density, a)) if mc.drag else 0.0
    drag_stop = propagate(np.zeros(6), dt_stop, a, inc, mc.j2, da_dot=unit)
    return EvaporationModel(design, mc, float(p), roe_stop, drag_stop, unit, np.asarray(d.db_factor, dtype=float))
