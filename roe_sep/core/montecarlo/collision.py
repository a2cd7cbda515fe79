"""Collision probability of the double-impulse separation: the chance that the picosatellite, once it has left the
carrier (beyond ``departure_distance``, as the simulator's closest-approach tracking), comes back within a hard-body
radius ``R`` of it before the horizon. Pure numpy.

Trajectory model: the Monte Carlo's (:mod:`roe_sep.core.montecarlo.sweep`: dispersed ejection, Eq. 22; secular ROE
with drag, Eqs. 23-24; dispersed drift-stop with reduction p; ``horizon`` of drift after it), the relative position
the linear ROE -> RTN map (:func:`~roe_sep.core.relmotion.roe.roe_to_rtn`). Arc A (ejection to drift-stop) is
evaluated from :func:`~.sweep.pre_stop`'s state at the drift-stop (the secular model is a flow, exact backwards),
arc B from :func:`~.sweep.after_stop`'s: the physics is the sweep's.

Minimum distance (:func:`min_distance`): f(t) = |r(t)|^2 sampled ``steps_per_orbit`` times per orbit (the drift-stop
epoch a grid point), from where it first decreases after exceeding ``departure_distance`` to the horizon. Every grid
interval is then refined by a branch and bound with a second-order bound: on an interval of length h, f(t) >= min(f0,
f1) - M h^2/8 with M >= max f'' = 2 max(|v|^2 + r . a), from per-sample bounds of the relative speed V and acceleration
A over the arc derived from the model's rates (:func:`_bounds`). An interval whose bound is above the best sampled value
(minus the tolerance) is dropped, the others halved until none is left: an evaluated point at most ``tol = tol_abs +
tol_rel * d`` above the model's true minimum (a certified bound). The rising part between the departure and the window
start is certified to stay above ``R`` the same way.

Estimators of P(d_min <= R):

* ``mc``: brute force on the dispersions of ``roe-sep mc`` (the same SeedSequence blocks, :mod:`.streaming`):
  k hits of n, Wilson 95 % interval.
* ``is``: importance sampling in the standard-normal dispersion space z (9 dimensions: f1, f2, the two attitude
  error triples, the dB factor). A Gaussian proposal N(mu, C) is tuned by the multilevel cross-entropy method
  (Rubinstein & Kroese 2004, :func:`cross_entropy`) until gamma reaches R. Where one Gaussian cannot follow the failure
  set down to R (gamma stalls), the estimate is made at the smallest gamma reached, an upper bound of P(d <= R). The
  final estimate uses fresh samples from the proposal: p = mean(1{d <= R} w), w = phi(z) / q(z), with the 95 % normal
  interval from its standard error and ESS = (sum h)^2 / sum h^2, h = 1{d <= R} w (one Gaussian: one failure region).
"""

import dataclasses
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..constants import ARCSEC
from ..relmotion.dynamics import arg_latitude_rate, eccentricity_vector_rotation_rate, j2_kappa, propagate
from ..relmotion.orbit import mean_motion
from ..relmotion.roe import roe_to_rtn
from ..separation.double_impulse import DoubleImpulseDesign
from .stats import normal_interval, wilson_interval
from .streaming import BLOCK_SIZE, ExactSum, block_draws
from .sweep import Draws, MonteCarloConfig, after_stop, pre_stop

DIMENSIONS = ("f1", "f2", "eps1_x", "eps1_y", "eps1_z", "eps2_x", "eps2_y", "eps2_z", "dB")
N_DIM = len(DIMENSIONS)
SUB_BATCH = 2000  # samples per grid evaluation (bounds the working memory)


@dataclass(frozen=True)
class CollisionConfig:
    """What ``roe-sep collision`` asks: hard-body radius, drift-stop reduction and the distance evaluation."""

    hard_body_radius: float  # m
    p: float  # m/s, drift-stop reduction
    departure_distance: float = 1000.0  # m, the simulator's default
    steps_per_orbit: int = 16  # initial grid of the branch and bound (its result does not depend on it)
    tol_abs: float = 1e-4  # m
    tol_rel: float = 1e-5

    def validate(self) -> None:
        """Raise ValueError naming the first bad setting (the radius as its command-line option)."""
        r, dep = self.hard_body_radius, self.departure_distance
        if not (math.isfinite(dep) and dep > 0):
            raise ValueError(f"departure_distance must be a positive number of meters, got {dep}")
        if not (math.isfinite(r) and 0 < r < 0.5 * dep):
            raise ValueError(f"--hard-body-radius must be in (0, {0.5 * dep:g}) m (half the departure distance), "
                             f"got {r}")
        if not (math.isfinite(self.p) and self.p >= 0):
            raise ValueError(f"--p must be a finite non-negative number [m/s], got {self.p}")
        if self.steps_per_orbit < 4:
            raise ValueError(f"steps_per_orbit must be >= 4, got {self.steps_per_orbit}")


# ----------------------------------------------------------------------------------------------------------------
# dispersions <-> standard normal


def _loc_scale(design, mc):
    cfg, att = design.config, mc.attitude_sigma_arcsec * ARCSEC
    loc = np.array([1.0, 1.0, 0, 0, 0, 0, 0, 0, 1.0])
    scale = np.array([cfg.spl_sigma, cfg.thruster_sigma, att, att, att, att, att, att, mc.ballistic_sigma])
    return loc, scale


def draws_from_normal(design: DoubleImpulseDesign, mc: MonteCarloConfig, z: ArrayLike) -> Draws:
    """Draws of :func:`.sweep.draw` from standard normals ``z`` (n, 9): x = loc + scale z, as numpy's normal().

    Parameters
    ----------
    design : DoubleImpulseDesign
        The nominal design.
    mc : MonteCarloConfig
        Dispersions, drag, J2, horizon.
    z : array_like, shape (n, 9)
        Standard normals in the order of ``DIMENSIONS``.

    Returns
    -------
    Draws
        n samples.
    """
    loc, scale = _loc_scale(design, mc)
    x = loc + scale * np.asarray(z, dtype=float)
    return Draws(f1=x[:, 0], f2=x[:, 1], eps1=x[:, 2:5], eps2=x[:, 5:8], db_factor=x[:, 8])


def normal_from_draws(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws) -> np.ndarray:
    """Inverse of :func:`draws_from_normal`.

    Parameters
    ----------
    design, mc
        As for :func:`draws_from_normal`.
    d : Draws
        n samples.

    Returns
    -------
    numpy.ndarray, shape (n, 9)
        Their standard normals.
    """
    loc, scale = _loc_scale(design, mc)
    x = np.column_stack([d.f1, d.f2, d.eps1, d.eps2, d.db_factor])
    return (x - loc) / scale


# ----------------------------------------------------------------------------------------------------------------
# trajectory and its certified minimum distance


@dataclass
class Arcs:
    """Per-sample states of the two arcs and the bounds of the branch and bound."""

    a: float
    inc: float
    j2: bool
    u1: float  # rad
    u_rate: float  # rad/s
    t_stop: float  # s after the ejection
    t_end: float
    roe: np.ndarray  # (2, N, 6): arc A and arc B, each the state at t_stop
    da_dot: np.ndarray  # (N,)
    speed: np.ndarray  # (2, N) m/s, bound of |v| on each arc
    accel: np.ndarray  # (2, N) m/s^2, bound of |a| on each arc


def _bounds(roe, da_dot, a, inc, j2, *, duration):
    """(V, A): bounds of the relative speed [m/s] and acceleration [m/s^2] of the model over an arc of
    ``duration`` around ``roe`` (from the derivative of r/a = M(u) roe(t), roe_to_rtn, with the rates of
    :func:`~roe_sep.core.relmotion.dynamics.propagate`), 5 % margin."""
    n = mean_motion(a)
    w = arg_latitude_rate(a, inc, j2)
    kap = j2_kappa(a) if j2 else 0.0
    we = abs(eccentricity_vector_rotation_rate(a, inc)) if j2 else 0.0
    p_fac, s2i = 3.0 * math.cos(inc) ** 2 - 1.0, math.sin(2.0 * inc)
    da0 = np.abs(roe[:, 0])
    da = np.maximum(da0 + np.abs(da_dot) * duration, da0)
    de = np.hypot(roe[:, 2], roe[:, 3])
    dix = np.abs(roe[:, 4])
    diy_rate = 3.5 * kap * abs(s2i) * da + 2.0 * kap * math.sin(inc) ** 2 * dix
    di = np.hypot(roe[:, 4], np.abs(roe[:, 5]) + diy_rate * duration)
    dl_rate = abs(1.5 * n + 7.0 * kap * p_fac) * da + 7.0 * kap * abs(s2i) * dix
    ww = w + we
    # in-plane: |(de sin x, 2 de cos x)| <= 2 de, plus the drift and the rates of the elements
    v_rt = np.abs(da_dot) + dl_rate + 2.0 * ww * de
    v_n = w * di + diy_rate
    acc_r = ww**2 * de
    acc_t = abs(1.5 * n + 7.0 * kap * p_fac) * np.abs(da_dot) + 2.0 * ww**2 * de
    acc_n = w**2 * di + 2.0 * w * diy_rate
    return 1.05 * a * np.hypot(v_rt, v_n), 1.05 * a * np.sqrt(acc_r**2 + acc_t**2 + acc_n**2)


def arcs(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws, p: float) -> Arcs:
    """The two arcs of every sample (ejection to drift-stop, drift-stop to the horizon) with the speed and
    acceleration bounds of the branch and bound.

    Parameters
    ----------
    design, mc
        As for :func:`draws_from_normal`.
    d : Draws
        n samples.
    p : float
        The drift-stop reduction [m/s].

    Returns
    -------
    Arcs
        Per-sample ROE ``(2, n, 6)`` at the drift-stop and the bounds ``(2, n)`` [m/s, m/s^2].
    """
    pre = pre_stop(design, mc, d)
    out = after_stop(design, mc, d, pre, p)
    a, inc = design.a, design.inc
    roe = np.stack([pre.roe_before_stop, out.roe_after_stop])
    va, aa = _bounds(pre.roe_before_stop, pre.da_dot, a, inc, mc.j2, duration=pre.dt_stop)
    # arc A is evaluated backwards from t_stop: bound with the state at its start as well (the larger of the two)
    roe1 = propagate(pre.roe_before_stop, -pre.dt_stop, a, inc, mc.j2, da_dot=pre.da_dot)
    va1, aa1 = _bounds(roe1, pre.da_dot, a, inc, mc.j2, duration=pre.dt_stop)
    vb, ab = _bounds(out.roe_after_stop, pre.da_dot, a, inc, mc.j2, duration=mc.horizon)
    return Arcs(a, inc, mc.j2, design.u1, arg_latitude_rate(a, inc, mc.j2), pre.dt_stop, pre.dt_stop + mc.horizon,
                roe, pre.da_dot, np.stack([np.maximum(va, va1), vb]), np.stack([np.maximum(aa, aa1), ab]))


def _dist2(arc: Arcs, idx, t):
    """|r|^2 [m^2] of samples ``idx`` at times ``t`` [s after the ejection] (same shapes or broadcastable)."""
    which = (np.asarray(t) >= arc.t_stop).astype(np.intp)
    roe = arc.roe[which, idx]
    st = propagate(roe, t - arc.t_stop, arc.a, arc.inc, arc.j2, da_dot=arc.da_dot[idx])
    pos, _ = roe_to_rtn(st, arc.u1 + arc.u_rate * t)
    return np.sum(pos * pos, axis=-1) * arc.a**2


def time_grid(arc: Arcs, steps_per_orbit: int) -> np.ndarray:
    """Grid times [s]: both arcs at about ``steps_per_orbit`` points per orbit, the drift-stop epoch included."""
    h = 2.0 * math.pi / arc.u_rate / steps_per_orbit
    ta = np.linspace(0.0, arc.t_stop, int(math.ceil(arc.t_stop / h)) + 1)
    tb = np.linspace(arc.t_stop, arc.t_end, int(math.ceil((arc.t_end - arc.t_stop) / h)) + 1)
    return np.concatenate([ta, tb[1:]])


def _lower_bound(arc, idx, t0, t1, f0, *, f1):
    """Lower bound of |r|^2 on [t0, t1] (one arc): min(f0, f1) - M h^2 / 8, M = 2 (V^2 + r_max A)."""
    which = (t0 >= arc.t_stop).astype(np.intp)
    v, acc = arc.speed[which, idx], arc.accel[which, idx]
    h = t1 - t0
    r_max = np.sqrt(np.maximum(f0, f1)) + 0.5 * v * h
    return np.minimum(f0, f1) - (v * v + r_max * acc) * h * h / 4.0


def _branch_and_bound(arc, idx, t0, t1, f0, *, f1, best, tol_abs, tol_rel, max_levels=80):
    """Refine intervals (sample ``idx``, [t0, t1], end values f0, f1) until none can hold a value below
    ``best[idx] - tol`` (squared distances); ``best`` (per sample, m^2) is lowered in place."""
    for _ in range(max_levels):
        d = np.sqrt(best[idx])
        thr = np.maximum(d - (tol_abs + tol_rel * d), 0.0) ** 2
        keep = _lower_bound(arc, idx, t0, t1, f0, f1=f1) < thr
        if not np.any(keep):
            return
        idx, t0, t1, f0, f1 = idx[keep], t0[keep], t1[keep], f0[keep], f1[keep]
        tm = 0.5 * (t0 + t1)
        fm = _dist2(arc, idx, tm)
        np.minimum.at(best, idx, fm)
        idx, t0, t1, f0, f1 = (np.concatenate(x) for x in ((idx, idx), (t0, tm), (tm, t1), (f0, fm), (fm, f1)))
    raise RuntimeError("minimum distance: the branch and bound did not converge")


def min_distance(design: DoubleImpulseDesign, mc: MonteCarloConfig, d: Draws, cfg: CollisionConfig) -> np.ndarray:
    """Closest approach [m] after the departure for every sample (``inf``: never left the departure sphere or never
    came back towards the carrier), certified to ``tol`` (module docstring).

    Parameters
    ----------
    design, mc
        As for :func:`draws_from_normal`.
    d : Draws
        n samples.
    cfg : CollisionConfig
        Reduction, departure distance, grid and tolerances.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The closest approach of each sample [m].
    """
    n = d.f1.shape[0]
    out = np.empty(n)
    for lo in range(0, n, SUB_BATCH):
        sub = Draws(*(getattr(d, f.name)[lo:lo + SUB_BATCH] for f in dataclasses.fields(Draws)))
        out[lo:lo + SUB_BATCH] = _min_distance(design, mc, sub, cfg)
    return out


def _grid_dist2(arc: Arcs, t):
    """|r|^2 [m^2] of every sample on the grid ``t`` (n, K): each arc broadcast over its own times."""
    out = np.empty((arc.da_dot.size, t.size))
    for j, sel in enumerate((t < arc.t_stop, t >= arc.t_stop)):
        tt = t[sel][None, :]
        st = propagate(arc.roe[j][:, None, :], tt - arc.t_stop, arc.a, arc.inc, arc.j2, da_dot=arc.da_dot[:, None])
        pos, _ = roe_to_rtn(st, arc.u1 + arc.u_rate * tt)
        out[:, sel] = np.sum(pos * pos, axis=-1) * arc.a**2
    return out


def _min_distance(design, mc, d, cfg):
    arc = arcs(design, mc, d, cfg.p)
    n = d.f1.shape[0]
    t = time_grid(arc, cfg.steps_per_orbit)
    f = _grid_dist2(arc, t)  # (n, K)
    dep2, r2 = cfg.departure_distance**2, cfg.hard_body_radius**2
    outside = f >= dep2
    departed = np.any(outside, axis=1)
    k_dep = np.argmax(outside, axis=1)
    k = np.arange(t.size)[None, :]
    falling = (k >= k_dep[:, None]) & (np.diff(f, axis=1, append=np.inf) < 0.0)
    returned = departed & np.any(falling, axis=1)
    k_s = np.where(returned, np.argmax(falling, axis=1), t.size)
    best = np.where(k >= k_s[:, None], f, np.inf).min(axis=1)
    # the receding part, from the departure to the window start: certified not to dip within R (else that dip is
    # the closest approach); the interval of the departure itself starts at departure_distance
    ii, kk = np.nonzero((k[:, :-1] >= k_dep[:, None] - 1) & (k[:, :-1] < k_s[:, None]) & departed[:, None])
    rise = np.full(n, r2)
    _branch_and_bound(arc, ii, t[kk], t[kk + 1], np.maximum(f[ii, kk], dep2), f1=f[ii, kk + 1], best=rise, tol_abs=0.0,
                      tol_rel=0.0)
    ii, kk = np.nonzero((k[:, :-1] >= k_s[:, None]) & returned[:, None])
    _branch_and_bound(arc, ii, t[kk], t[kk + 1], f[ii, kk], f1=f[ii, kk + 1], best=best, tol_abs=cfg.tol_abs,
                      tol_rel=cfg.tol_rel)
    best = np.where(rise < r2, np.minimum(rise, best), best)
    return np.where(returned | (rise < r2), np.sqrt(best), np.inf)


# ----------------------------------------------------------------------------------------------------------------
# estimators


@dataclass
class CollisionStats:
    """Running sums of one estimator over chunks (exact, so the chunking and the workers never change a digit)."""

    n: int = 0
    hits: int = 0
    departed_never: int = 0
    d_min: float = math.inf  # smallest closest approach seen [m]
    sum_h: ExactSum = None  # importance sampling: h = 1{d <= R} w
    sum_h2: ExactSum = None

    def __post_init__(self):
        self.sum_h = self.sum_h or ExactSum()
        self.sum_h2 = self.sum_h2 or ExactSum()

    def merge(self, o: "CollisionStats") -> "CollisionStats":
        """Add the sums of ``o`` (other samples of the same estimator); returns ``self``."""
        self.n += o.n
        self.hits += o.hits
        self.departed_never += o.departed_never
        self.d_min = min(self.d_min, o.d_min)
        self.sum_h.merge(o.sum_h)
        self.sum_h2.merge(o.sum_h2)
        return self


@dataclass(frozen=True)
class Proposal:
    """Gaussian importance density N(mean, cov) in the standard-normal dispersion space."""

    mean: np.ndarray
    cov: np.ndarray

    def chol(self) -> np.ndarray:
        """The lower Cholesky factor ``(9, 9)`` of the covariance."""
        return np.linalg.cholesky(self.cov)

    def sample(self, rng: np.random.Generator, n: int) -> np.ndarray:
        """``n`` points ``(n, 9)`` of the proposal."""
        return self.mean + rng.standard_normal((n, self.mean.size)) @ self.chol().T

    def log_weight(self, z: np.ndarray) -> np.ndarray:
        """log phi(z) - log q(z) ``(n,)`` of points ``z`` ``(n, 9)``."""
        c = self.chol()
        y = np.linalg.solve(c, (z - self.mean).T).T
        return -0.5 * np.sum(z * z, axis=1) + 0.5 * np.sum(y * y, axis=1) + np.sum(np.log(np.diag(c)))


IS_STREAM = 0x15  # spawn-key tag of the importance-sampling streams (disjoint from the mc blocks)


def _chunk_draws(chunk, design, mc, proposal, block):
    """(draws, log weights or None, block sizes) of a chunk: the mc blocks, or the proposal's own blocks."""
    first, count = chunk
    parts, logw = [], []
    for b in range(first, first + count):
        if proposal is None:
            parts.append(block_draws(design, mc, b, block))
            continue
        size = min(block, mc.samples - b * block)
        rng = np.random.default_rng(np.random.SeedSequence(mc.seed, spawn_key=(IS_STREAM, 1, b)))
        z = proposal.sample(rng, size)
        parts.append(draws_from_normal(design, mc, z))
        logw.append(proposal.log_weight(z))
    d = Draws(*(np.concatenate([getattr(x, f.name) for x in parts]) for f in dataclasses.fields(Draws)))
    return d, (np.concatenate(logw) if logw else None), [x.f1.shape[0] for x in parts]


def evaluate_chunk(chunk: tuple[int, int], design: DoubleImpulseDesign, mc: MonteCarloConfig, cfg: CollisionConfig,
                   proposal: Proposal | None = None, *, block: int = BLOCK_SIZE) -> CollisionStats:
    """Collision statistics of one chunk ``(first block, number of blocks)``; ``proposal`` None: brute force.

    Parameters
    ----------
    chunk : (int, int)
        ``(first block, number of blocks)``.
    design, mc
        As for :func:`draws_from_normal`.
    cfg : CollisionConfig
        Hard-body radius, reduction, tolerances.
    proposal : Proposal, optional
        The importance density (its own random streams); None: the Monte Carlo blocks of ``mc``.
    block : int
        Samples per random-number block.

    Returns
    -------
    CollisionStats
        Counts and the exact sums of the chunk.
    """
    d, logw, sizes = _chunk_draws(chunk, design, mc, proposal, block)
    dist = min_distance(design, mc, d, cfg)
    hit = dist <= cfg.hard_body_radius
    st = CollisionStats(n=int(dist.size), hits=int(np.count_nonzero(hit)),
                        departed_never=int(np.count_nonzero(~np.isfinite(dist))),
                        d_min=float(np.min(dist)))
    if logw is not None:
        h = np.where(hit, np.exp(logw), 0.0)
        ends = np.cumsum([0] + sizes)
        for lo, hi in zip(ends[:-1], ends[1:]):  # one sum per block: fixed terms, exact merge
            st.sum_h.add(np.sum(h[lo:hi]))
            st.sum_h2.add(np.sum(h[lo:hi] ** 2))
    return st


def _fit(z, w, min_std):
    """Gaussian of the samples ``z`` (weights ``w`` or equal), principal standard deviations >= ``min_std``."""
    w = np.full(z.shape[0], 1.0) if w is None else w
    w = w / w.sum()
    mean = w @ z
    dz = z - mean
    lam, vec = np.linalg.eigh((dz * w[:, None]).T @ dz)
    return Proposal(mean, (vec * np.maximum(lam, min_std**2)) @ vec.T)


def cross_entropy(design: DoubleImpulseDesign, mc: MonteCarloConfig, cfg: CollisionConfig,
                  samples_per_level: int = 2000, rho: float = 0.1, *, max_levels: int = 25,
                  progress: Callable[[int, float], object] | None = None, min_std: float = 1.0,
                  patience: int = 4) -> tuple[Proposal, list, bool]:
    """Multilevel cross-entropy tuning of the Gaussian proposal (module docstring).

    Level t samples ``samples_per_level`` points of the current proposal; gamma_t = max(R, rho-quantile of d_min); the
    next proposal is the (unweighted) mean and covariance of the elite set {d_min <= gamma_t}, every principal standard
    deviation kept >= ``min_std`` (the weights phi/q stay bounded). ``reached`` is False when gamma stopped decreasing
    for ``patience`` levels or ``max_levels`` ran out before R: the caller then bounds P(d <= R) by P(d <= the smallest
    gamma). ValueError when fewer than max(10, rho n) samples of a level come back after the departure.

    Parameters
    ----------
    design, mc, cfg
        As for :func:`draws_from_normal`; ``cfg`` gives the hard-body radius R [m] the levels aim at.
    samples_per_level : int
        Points per level.
    rho : float
        The elite quantile, in (0, 1).
    max_levels : int
        The most levels.
    progress : callable, optional
        Called with (level, gamma [m]) after each level.
    min_std : float
        The least principal standard deviation of a proposal (standard-normal units).
    patience : int
        Levels without a lower gamma before giving up.

    Returns
    -------
    (Proposal, list of dict, bool)
        The proposal, the levels ({gamma [m], elites}) and whether gamma reached R.
    """
    dim = N_DIM
    prop = Proposal(np.zeros(dim), np.eye(dim))
    levels, best, best_gamma, since = [], prop, math.inf, 0
    for level in range(max_levels):
        rng = np.random.default_rng(np.random.SeedSequence(mc.seed, spawn_key=(IS_STREAM, 0, level)))
        z = prop.sample(rng, samples_per_level)
        dist = min_distance(design, mc, draws_from_normal(design, mc, z), cfg)
        finite = np.isfinite(dist)
        need = max(10, math.ceil(rho * samples_per_level))
        if np.count_nonzero(finite) < need:  # the input, not a fault: a departure too far for these samples
            raise ValueError(f"cross-entropy level {level}: {np.count_nonzero(finite)} of {samples_per_level} samples "
                             f"come back after leaving the departure distance {cfg.departure_distance:g} m, at least "
                             f"{need} needed (a smaller departure distance or more samples per level)")
        gamma = max(cfg.hard_body_radius, float(np.quantile(dist[finite], rho)))
        elite = dist <= gamma
        # steering levels: the plain elite mean and covariance; the last level (gamma = R) and the bound level use
        # the likelihood ratios phi/q of the sampling proposal: the CE fit of phi restricted to the failure set
        w = np.exp(prop.log_weight(z[elite])) if gamma <= cfg.hard_body_radius else None
        fitted = _fit(z[elite], w, min_std)
        w_best = np.exp(prop.log_weight(z[elite]))
        levels.append({"gamma": gamma, "elites": int(np.count_nonzero(elite))})
        if progress is not None:
            progress(level, gamma)
        if gamma <= cfg.hard_body_radius:
            return fitted, levels, True
        if gamma < best_gamma:
            best, best_gamma, since = _fit(z[elite], w_best, min_std), gamma, 0
        else:
            since += 1
            if since >= patience:
                break
        prop = fitted
    return best, levels, False


def estimate(stats: CollisionStats, cfg: CollisionConfig, method: str) -> dict:
    """p, its 95 % interval, the samples behind it and the effective sample size (module docstring).

    Parameters
    ----------
    stats : CollisionStats
        The merged statistics of every chunk.
    cfg : CollisionConfig
        Radius [m], reduction [m/s] and departure distance [m], reported.
    method : str
        ``mc`` (brute force: Wilson interval) or an importance-sampling method (normal interval of the weighted
        mean).

    Returns
    -------
    dict
        ``p``, ``ci95``, ``relative_half_width``, ``samples``, ``ess``, ``hits``, the closest approach [m] and the
        settings.
    """
    n = stats.n
    if method == "mc":
        p = stats.hits / n
        lo, hi = wilson_interval(stats.hits, n)
        ess = float(n)
    else:
        s1, s2 = stats.sum_h.value(), stats.sum_h2.value()
        p = s1 / n
        var = max(s2 / n - p * p, 0.0) / n
        lo, hi = normal_interval(p, math.sqrt(var))
        lo = max(lo, 0.0)
        ess = s1 * s1 / s2 if s2 > 0 else 0.0
    return {
        "p": p,
        "ci95": [lo, hi],
        "relative_half_width": (hi - lo) / (2.0 * p) if p > 0 else None,
        "samples": n,
        "method": method,
        "ess": ess,
        "hits": stats.hits,
        "never_returned": stats.departed_never,
        "closest_approach_min": stats.d_min if math.isfinite(stats.d_min) else None,
        "hard_body_radius": cfg.hard_body_radius,
        "p_reduction": cfg.p,
        "departure_distance": cfg.departure_distance,
    }


# ----------------------------------------------------------------------------------------------------------------
# design point: the most probable collision (FORM), and the bound it gives


def closest_approach(design: DoubleImpulseDesign, mc: MonteCarloConfig, cfg: CollisionConfig, z: ArrayLike) -> float:
    """Certified closest approach [m] of one point ``z`` (9,) of the standard-normal dispersion space (``1e4`` for
    a sample that never comes back: finite, for an optimizer).

    Parameters
    ----------
    design, mc
        As for :func:`draws_from_normal`.
    cfg : CollisionConfig
        Reduction, departure distance, tolerances.
    z : array_like, shape (9,)
        The point.

    Returns
    -------
    float
        The closest approach [m].
    """
    v = float(min_distance(design, mc, draws_from_normal(design, mc, np.atleast_2d(z)), cfg)[0])
    return v if math.isfinite(v) else 1e4


def design_point(design: DoubleImpulseDesign, mc: MonteCarloConfig, cfg: CollisionConfig, starts: ArrayLike,
                 maxiter: int = 60) -> tuple[np.ndarray | None, float | None, list]:
    """The design point of reliability analysis (Hasofer-Lind): the point of the failure set {d(z) <= R} nearest
    to the origin of the standard-normal space, i.e. the most probable collision, by SLSQP (min |z|^2 subject to
    d(z) <= R, forward-difference constraint gradient) from each start (e.g. the closest samples of a stalled
    cross-entropy proposal). Returns ``(z*, rho*, runs)`` with ``rho* = |z*|`` over the runs that end in the
    failure set (``None`` if none does) and per run (start radius, start distance, end radius, end distance).

    Meaning: every z with |z| < rho_true (the true minimum) is collision-free, so P(d <= R) <=
    P(chi2_9 >= rho_true^2). A local optimizer from several starts finds a feasible z with |z| >= rho_true, so
    the bound computed from the rho* found is as good as the search: it is exact if the runs found the global
    minimum (they are independent starts; their spread is reported), not a certificate.

    Parameters
    ----------
    design, mc
        As for :func:`draws_from_normal`.
    cfg : CollisionConfig
        The hard-body radius R [m].
    starts : array_like, shape (k, 9)
        Start points in the standard-normal space.
    maxiter : int
        SLSQP iterations per start.

    Returns
    -------
    (numpy.ndarray or None, float or None, list of dict)
        z* ``(9,)``, rho* = |z*| and the runs.
    """
    from scipy.optimize import minimize  # only here: scipy.optimize is not needed by the sampling

    r = cfg.hard_body_radius
    runs, best = [], None
    for z0 in np.atleast_2d(starts):
        res = minimize(lambda z: z @ z, z0, jac=lambda z: 2.0 * z, method="SLSQP",
                       constraints=[{"type": "ineq", "fun": lambda z: r - closest_approach(design, mc, cfg, z)}],
                       options={"maxiter": maxiter, "ftol": 1e-10, "eps": 1e-5})
        dz = closest_approach(design, mc, cfg, res.x)
        rho = float(np.linalg.norm(res.x))
        runs.append({"start_radius": float(np.linalg.norm(z0)), "start_distance": closest_approach(design, mc, cfg, z0),
                     "radius": rho, "distance": dz})
        if dz <= r * (1.0 + 1e-6) and (best is None or rho < best[1]):
            best = (res.x, rho)
    if best is None:
        return None, None, runs
    return best[0], best[1], runs


def ball_bound(rho: float, dim: int = N_DIM) -> float:
    """P(|z| >= rho) for z ~ N(0, I_dim): the Gaussian mass outside the ball of radius ``rho`` (chi-square tail)."""
    from scipy.stats import chi2

    return float(chi2.sf(rho * rho, dim))
