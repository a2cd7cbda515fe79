"""Monte Carlo of the multi-impulse separation with the acceptance criteria AC1-AC3 of seed 001 Sec. 4.

Same dispersions as the double-impulse Monte Carlo (:func:`roe_sep.core.montecarlo.sweep.draw`): SPL factor f1 and the
attitude errors eps1 on the ejection, thruster factor f2 and eps2 on the (blind) drift reduction (seed 001 Eq. 2 =
seed 002 Eq. 22, the magnitude error on the unreduced burn as in seed 002 Eq. 18; a drift reduction split into
several burns shares one f2/eps2: a calibration error), differential
drag with its 20 % uncertainty. Keplerian + drag unless ``mc.j2``. Vectorized over samples.

* AC1: the relative semi-major axis right after the drift reduction is negative (outward drift for a leading
  picosatellite; sign flipped when following) in every sample.
* AC2: the nearest transit through the R = 0 plane, from the ejection to ``horizon`` after the drift reduction, is
  at an along-track distance of at least ``ac2_distance`` (2 km).
* AC3: the minimum R-N distance (seed 002 Eq. 25) after the drift reduction exceeds ``min_rn_distance`` for the
  nearly drift-free samples: those whose residual drift 1.5 n |a da| over ``horizon`` is below the radar
  separability a_dl_min (a sample drifting farther than that is protected by its drift, seed 001 Sec. 4).
"""

from dataclasses import dataclass

import numpy as np

from ..relmotion.dynamics import arg_latitude_rate, drag_da_dot, propagate
from ..relmotion.maneuvers import delta_roe, dispersed_dv, unreduced_burns
from ..safety.metrics import min_rn_distance, nearest_crossing
from ..separation.multi_impulse import MultiImpulseDesign
from .sweep import Draws, MonteCarloConfig, draw

AC2_DISTANCE = 2000.0  # m, seed 001 AC2


def drift_free_threshold(a_dl_min: float, n: float, horizon: float) -> float:
    """|a da| [m] below which a sample counts as 'almost no drift' for AC3: 1.5 n |a da| horizon < a_dl_min.

    Parameters
    ----------
    a_dl_min : float
        The least along-track separation [m].
    n : float
        The carrier's mean motion [rad/s].
    horizon : float
        The time after the drift reduction [s].

    Returns
    -------
    float
        The threshold of |a da| [m].
    """
    return a_dl_min / (1.5 * n * horizon)


@dataclass
class AcceptanceResult:
    """Per-sample states and acceptance criteria AC1-AC3 of the multi-impulse Monte Carlo (seed 001)."""

    design: MultiImpulseDesign
    mc: MonteCarloConfig
    draws: Draws
    roe_after_ejection: np.ndarray  # (N, 6) dimensionless
    roe_after_reduction: np.ndarray  # (N, 6)
    roe_horizon: np.ndarray  # (N, 6), ``horizon`` after the drift reduction
    crossing: np.ndarray  # (N,) m, nearest R = 0 transit
    min_rn: np.ndarray  # (N,) m
    drift_free: np.ndarray  # (N,) bool
    drift_free_a_da: float  # m
    ac1: np.ndarray  # (N,) bool
    ac2: np.ndarray
    ac3: np.ndarray  # True where satisfied or not applicable

    def to_dict(self) -> dict:
        """Fractions and counts of AC1-AC3, the drift-free threshold and extremes (distances in m)."""
        a = self.design.a
        n_free = int(np.count_nonzero(self.drift_free))
        return {
            "strategy": "multi_impulse",
            "samples": self.mc.samples,
            "seed": self.mc.seed,
            "drag": self.mc.drag,
            "j2": self.mc.j2,
            "ac1": float(np.mean(self.ac1)),
            "ac2": float(np.mean(self.ac2)),
            "ac3": float(np.mean(self.ac3[self.drift_free])) if n_free else 1.0,
            "n_ac1_fail": int(np.count_nonzero(~self.ac1)),
            "n_ac2_fail": int(np.count_nonzero(~self.ac2)),
            "n_ac3_fail": int(np.count_nonzero(~self.ac3)),
            "n_drift_free": n_free,
            "drift_free_a_da": self.drift_free_a_da,
            "ac2_distance": AC2_DISTANCE,
            "min_rn_fraction_all": float(np.mean(self.min_rn > self.design.config.min_rn_distance)),
            "a_da_after_reduction_max": float(np.max(self.roe_after_reduction[:, 0]) * a),
            "a_da_after_reduction_mean": float(np.mean(self.roe_after_reduction[:, 0]) * a),
            "a_dl_horizon_mean": float(np.mean(self.roe_horizon[:, 1]) * a),
            "crossing_min": float(np.min(self.crossing)),
            "min_rn_min": float(np.min(self.min_rn)),
        }


def run(design: MultiImpulseDesign, mc: MonteCarloConfig = MonteCarloConfig()) -> AcceptanceResult:
    """Dispersed ejection + drift reduction (the commanded plan of ``design``), then AC1-AC3 per sample."""
    mc.validate()
    d = draw(design, mc)
    a, n, inc, cfg = design.a, design.n, design.inc, design.config
    u_rate = arg_latitude_rate(a, inc, mc.j2)
    da_dot = drag_da_dot(mc.delta_b * d.db_factor, mc.density, a) if mc.drag else np.zeros_like(d.f1)
    roe1 = delta_roe(dispersed_dv(design.dv1_rtn, d.f1, d.eps1), design.u1, a, n)
    reductions = [b for b in design.plan.burns if b.purpose == "drift_reduction"]
    # the thruster error acts on the unreduced drift-stop (Eq. 18), shared over the split burns
    refs = unreduced_burns([b.dv_relative_rtn for b in reductions], design.plan.p) if reductions else []
    state, u_state, crossings = roe1, design.u1, []
    for b, ref in zip(reductions, refs):  # a handful of burns: the loop is over burns, never samples
        dt = (b.u - u_state) / u_rate
        crossings.append(nearest_crossing(state, u_state, dt, a, inc, j2=mc.j2, da_dot=da_dot,
                                          t_min=None if u_state == design.u1 else 1e-3)[0])
        state = propagate(state, dt, a, inc, mc.j2, da_dot=da_dot)
        state = state + delta_roe(dispersed_dv(b.dv_relative_rtn, d.f2, d.eps2, ref), b.u, a, n)
        u_state = b.u
    crossings.append(nearest_crossing(state, u_state, mc.horizon, a, inc, j2=mc.j2, da_dot=da_dot, t_min=1e-3)[0])
    crossing = np.min(np.stack(crossings), axis=0) * a
    roe_h = propagate(state, mc.horizon, a, inc, mc.j2, da_dot=da_dot)
    side = 1.0 if cfg.leading else -1.0
    min_rn = min_rn_distance(state) * a
    thr = float(drift_free_threshold(cfg.a_dl_min, n, mc.horizon))
    free = np.abs(state[:, 0] * a) < thr
    return AcceptanceResult(
        design=design, mc=mc, draws=d, roe_after_ejection=roe1, roe_after_reduction=state, roe_horizon=roe_h,
        crossing=crossing, min_rn=min_rn, drift_free=free, drift_free_a_da=thr,
        ac1=side * state[:, 0] < 0.0,
        ac2=crossing >= AC2_DISTANCE,
        ac3=~free | (min_rn > cfg.min_rn_distance),
    )
