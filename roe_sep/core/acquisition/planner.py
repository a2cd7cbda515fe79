"""Initial-condition acquisition: the carrier's burns from the radar OD estimate to the experiment's initial
conditions (ICs) with minimum delta-v, as a linear program (seed 001 Secs. 2.2-2.3 and 5; seed 002 Eqs. 2, 11, 25).

The ICs at the final epoch t_F (seed 001 Sec. 2.2, AVANTI requirement 1, and AC3), s the sign of the estimated dl
(leading stays leading): s a dl_F in [a_dl_min, a_dl_max] (optionally on a target), and s a dl >= a_dl_min
throughout; |a da_F| <= drift_tolerance; e/i vectors anti-parallel when leading (parallel when following), each and
the minimum R-N distance (seed 002 Eq. 25) at least ``min_ei``; both inside the camera field of view (seed 002
Eq. 11); carrier burns of at most ``max_burn_dv``, quantized to ``dv_quantum`` (BIROS, seed 001 Sec. 2.1).

Formulation. Candidate burns on a grid of epochs (``grid_per_orbit`` per orbit) along ``axes`` from t_earliest to
the end of the window, t_F the last one. The final ROE and s a dl at every grid epoch are affine in the burns
(:mod:`roe_sep.core.acquisition.lp_transfer`: Eq. 2, the secular model, drag the affine part). With the direction
i^ of the final di fixed every IC is linear:

    de_F = -s mu i^,  di_F . i^ = nu,  dl_F = s L,  mu, nu >= m_min,
    mu / cos(g/2) <= tan(fov_r) L,  nu / cos(g/2) <= tan(fov_n) L,

so minimising sum |dv| (L1, split variables p - m) is a linear program (HiGHS), laid out by :func:`_assemble`'s
named blocks. i^ is iterated from the burn-free final di to the planned one (J2 couples da into di_y). m_min =
:func:`ei_magnitude_floor` keeps Eq. (25) >= min_ei under the angle tolerance. The window is used whole and the
dl target is mid-range (measured in docs/campaigns.md); re-planning on each newer OD and a final trim
(:mod:`roe_sep.core.acquisition.trim`, its OD's radar arc kept free of burns by ``no_burns``) absorb OD errors.
The path constraint enters the continuous LP in a sparse recursive form with the same feasible set
(:func:`_recursive_path`; docs/benchmarks.md, issue 42).

Quantization. The LP optimum is re-solved as a mixed-integer program (HiGHS) in multiples of ``dv_quantum`` on the
LP's support and its neighbouring epochs, the equalities relaxed to tolerances a quantized plan can meet:
|a da_F| <= drift_tolerance (the da_F lattice spacing is 2 dv_quantum / n), e/i within ``ei_angle_tol_deg``, dl
within ``a_dl_target_tol``. The plan is verified end to end with :func:`~roe_sep.core.relmotion.trajectory.trajectory`.
"""

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from ...errors import AcquisitionInfeasible, InvalidAcquisitionConfig
from ..relmotion.dynamics import arg_latitude_rate, propagate
from ..relmotion.orbit import mean_motion
from ..relmotion.trajectory import Burn, Chief, trajectory
from ..safety.metrics import fov_limit, min_rn_distance
from .highs import solve_lp
from .lp_transfer import (
    carrier_burn_effects,
    grid_epochs,
    grid_response,
    parse_axes,
    response_at,
    sagitta,
    transition_matrices,
)

if TYPE_CHECKING:  # scipy.sparse is imported where the program is built: the nodes import this module for its config
    from scipy import sparse

R_EARTH_MIN = 6.4e6  # m, a semi-major axis below this is not a valid LEO chief
QUANTA_SLACK = 4  # a quantized solution within this many quanta of the LP optimum ends the search


@dataclass(frozen=True)
class AcquisitionConfig:
    """Requirements and planning knobs (defaults: seed 001's AVANTI ICs and BIROS propulsion limits)."""

    a_dl_min: float = 5000.0  # m, minimum mean along-track separation, at the end and throughout
    a_dl_max: float = 10000.0  # m, maximum mean along-track separation at the end
    a_dl_target: float = 7500.0  # m, aimed |a dl_F|; 0 = free in [a_dl_min, a_dl_max] (cheapest, ends at a bound)
    a_dl_target_tol: float = 200.0  # m, |a dl_F - target| allowed after quantization
    min_ei: float = 150.0  # m, minimum |a de|, |a di| and R-N distance (Eq. 25)
    fov_half_r_deg: float = 6.8  # deg, camera half field of view, radial
    fov_half_n_deg: float = 9.15  # deg, camera half field of view, normal
    max_burn_dv: float = 0.3  # m/s, per burn (Euclidean norm)
    dv_quantum: float = 0.001  # m/s, every burn component is a multiple of it
    axes: str = "TN"  # candidate burn axes, letters of R, T, N
    planning_margin: float | None = None  # s, first burn >= OD epoch + margin; None = one orbit
    window: float = 172800.0  # s, the ICs are reached at the last grid epoch <= OD epoch + window
    grid_per_orbit: int = 16  # candidate epochs per orbit
    drift_tolerance: float = 1.0  # m, |a da_F| allowed
    ei_angle_tol_deg: float = 1.0  # deg, e/i deviation from (anti-)parallel allowed after quantization
    j2: bool = True  # secular J2 in the prediction
    milp_time_limit: float = 5.0  # s, HiGHS time limit of each quantized re-solve


def validate_config(cfg: AcquisitionConfig) -> None:
    """Reject malformed fields with :class:`InvalidAcquisitionConfig` naming the field."""

    def number(name, positive=True, allow_zero=False):
        v = getattr(cfg, name)
        ok = isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
        if ok and positive:
            ok = v > 0 or (allow_zero and v == 0)
        if not ok:
            raise InvalidAcquisitionConfig(
                name, "a finite " + ("non-negative " if allow_zero else "positive " if positive else "") + "number", v)
        return float(v)

    lo, hi = number("a_dl_min"), number("a_dl_max")
    if hi <= lo:
        raise InvalidAcquisitionConfig("a_dl_max", f"above a_dl_min = {lo:g} m", hi)
    target = number("a_dl_target", allow_zero=True)
    if target and not lo <= target <= hi:
        raise InvalidAcquisitionConfig("a_dl_target", f"0 (free) or within [{lo:g}, {hi:g}] m", target)
    number("a_dl_target_tol")
    number("min_ei")
    for name in ("fov_half_r_deg", "fov_half_n_deg"):
        if not 0 < number(name) < 90:
            raise InvalidAcquisitionConfig(name, "an angle in (0, 90) deg", getattr(cfg, name))
    max_dv, quantum = number("max_burn_dv"), number("dv_quantum")
    if quantum > max_dv:
        raise InvalidAcquisitionConfig("dv_quantum", f"at most max_burn_dv = {max_dv:g} m/s", quantum)
    try:
        parse_axes(cfg.axes)
    except ValueError:
        raise InvalidAcquisitionConfig("axes", "distinct letters among R, T, N", cfg.axes) from None
    if cfg.planning_margin is not None:
        number("planning_margin", allow_zero=True)
    window = number("window")
    if cfg.planning_margin is not None and window <= cfg.planning_margin:
        raise InvalidAcquisitionConfig("window", f"longer than planning_margin = {cfg.planning_margin:g} s", window)
    g = cfg.grid_per_orbit
    if isinstance(g, bool) or not isinstance(g, (int, np.integer)) or not 1 <= g <= 360:
        raise InvalidAcquisitionConfig("grid_per_orbit", "an integer in [1, 360]", g)
    number("drift_tolerance")
    if not 0 < number("ei_angle_tol_deg") <= 20:
        raise InvalidAcquisitionConfig("ei_angle_tol_deg", "an angle in (0, 20] deg", cfg.ei_angle_tol_deg)
    if not isinstance(cfg.j2, (bool, np.bool_)):
        raise InvalidAcquisitionConfig("j2", "true or false", cfg.j2)
    number("milp_time_limit")


def ei_magnitude_floor(min_rn: float, angle_tol: float) -> float:
    """Smallest |a de|, |a di| that keeps seed 002 Eq. (25) >= ``min_rn`` when the vectors deviate from
    (anti-)parallel by up to ``angle_tol`` [rad].

    For magnitudes m and m' >= m at deviation g, Eq. (25) is smallest for m' = m: with |de +- di| = 2 m sin(g/2),
    2 m cos(g/2) it gives dr_min = m cos g / sqrt(1 + sin g); solved for m.
    """
    return min_rn * math.sqrt(1.0 + math.sin(angle_tol)) / math.cos(angle_tol)


def drift_nulling_dv_bound(a_da0: float, a_da_dot: float, duration: float, n: float, tol: float) -> float:
    """Lower bound on the L1 delta-v [m/s] of any plan ending with |a da_F| <= ``tol`` after ``duration`` [s].

    Only tangential impulses change da (seed 002 Eq. 2: a Delta da = 2 dvT / n), so sum |dvT| >= n/2 |required
    change| with the required change = the drifted value a da0 + a_da_dot * duration minus the tolerance.

    Parameters
    ----------
    a_da0, a_da_dot : float
        a da now [m] and its drift rate [m/s].
    duration, n, tol : float
        Time to the final epoch [s], mean motion [rad/s], the drift tolerance [m].

    Returns
    -------
    float
        The bound [m/s].
    """
    return 0.5 * n * max(0.0, abs(a_da0 + a_da_dot * duration) - tol)


def ei_deviation(roe: ArrayLike, leading: bool) -> np.ndarray:
    """Angle [rad] between de and the required direction: -di (anti-parallel) when ``leading``, +di otherwise."""
    r = np.asarray(roe, dtype=float)
    de, di = r[..., 2:4], r[..., 4:6] * (-1.0 if leading else 1.0)
    cross = de[..., 0] * di[..., 1] - de[..., 1] * di[..., 0]
    return np.abs(np.arctan2(cross, np.sum(de * di, axis=-1)))


@dataclass(frozen=True)
class AcquisitionPlan:
    """A quantized carrier plan and its verified prediction (all from :func:`trajectory`)."""

    epochs: np.ndarray  # s, burn epochs in execution order
    u: np.ndarray  # rad, chief mean argument of latitude at each burn (unwrapped)
    dv_carrier: np.ndarray  # (N, 3) m/s, the carrier's own burns in RTN (relative effect: -dv)
    t0: float  # s, OD epoch
    t_earliest: float  # s, first admissible burn epoch
    t_final: float  # s, t_F: the ICs hold from here (last grid epoch of the window)
    final_roe: np.ndarray  # dimensionless ROE at t_final
    leading: bool
    total_dv: float  # m/s, sum of the burns' Euclidean magnitudes
    total_dv_l1: float  # m/s, sum of |components| (the program's objective)
    lp_dv: float  # m/s, continuous LP optimum before quantization
    dv_lower_bound: float  # m/s, drift_nulling_dv_bound
    min_rn: float  # m, seed 002 Eq. (25) at t_final
    min_separation: float  # m, smallest s a dl from t0 to t_final (dense sampling)
    fov_r_margin: float  # m, tan(fov_r)|a dl_F| - a|de_F| (>= 0: in the field of view)
    fov_n_margin: float  # m, tan(fov_n)|a dl_F| - a|di_F|
    ei_angle_deg: float  # deg, deviation of the e/i vectors from (anti-)parallel at t_final
    residual: np.ndarray  # m, quantized minus continuous final a*ROE
    solve_time: float  # s, wall time of the planning (matrices, LP and quantized solves)
    lp_time: float  # s, wall time of the continuous LP solves (HiGHS)
    lp_solves: int  # LP and MILP solves
    candidates: int  # candidate (epoch, axis) pairs
    a: float  # m

    @property
    def n_burns(self) -> int:
        return len(self.epochs)

    @property
    def t_last_burn(self) -> float:
        return float(self.epochs[-1]) if len(self.epochs) else float("nan")

    @property
    def time_to_ic(self) -> float:
        return self.t_final - self.t0

    @property
    def fov_ok(self) -> bool:
        return self.fov_r_margin >= 0.0 and self.fov_n_margin >= 0.0

    def burns(self) -> list[Burn]:
        """The plan as :class:`Burn` (relative impulses, -dv_carrier) for :func:`trajectory`."""
        return [Burn(float(t), tuple(-dv)) for t, dv in zip(self.epochs, self.dv_carrier)]

    def summary(self) -> dict:
        """Key numbers (SI, meters for a*ROE) for logs, diagnostics and the CLI."""
        f = self.final_roe * self.a
        return {
            "total_dv": self.total_dv, "lp_dv": self.lp_dv, "dv_lower_bound": self.dv_lower_bound,
            "n_burns": self.n_burns, "time_to_ic": self.time_to_ic,
            "last_burn_after_od": self.t_last_burn - self.t0, "a_da_f": f[0], "a_dl_f": f[1],
            "a_de_f": math.hypot(f[2], f[3]), "a_di_f": math.hypot(f[4], f[5]), "ei_angle_deg": self.ei_angle_deg,
            "min_rn": self.min_rn, "min_separation": self.min_separation, "fov_ok": self.fov_ok,
            "residual_max": float(np.max(np.abs(self.residual))), "solve_time": self.solve_time,
            "lp_time": self.lp_time,
        }


@dataclass
class _Problem:
    """The affine maps of one acquisition problem, in meters (a*ROE) per dv quantum."""

    cfg: AcquisitionConfig
    epochs: np.ndarray  # (K,)
    axes: tuple
    final: np.ndarray  # (6, K*J) a*ROE at t_F per quantum of each candidate
    free_final: np.ndarray  # (6,) a*ROE at t_F without burns (drag included)
    path: np.ndarray | None  # (K, K*J) s a dl at each grid epoch (post-burn) per quantum (None: not built)
    path_pre: np.ndarray | None  # same, pre-burn (only differs with radial burns)
    free_path: np.ndarray  # (K,) s a dl at the grid epochs without burns
    path_floor: float  # m, a_dl_min plus the between-epoch sagitta
    epoch_of: np.ndarray  # (K*J,) grid index of each candidate
    barred: np.ndarray  # (K,) True where no burn may fly (``no_burns``)
    s: float  # sign of dl
    quanta_max: int  # largest burn in quanta
    ei_floor: float  # m
    rows: dict = field(default_factory=dict, repr=False)  # _path_and_burn_rows by candidate columns (the memo)
    path_lags: np.ndarray | None = None  # (2, K*J) s a dl per quantum at lags 0 and 1 (the recursive form's)


def _unit(v, what):
    norm = math.hypot(v[0], v[1])
    if not norm > 1.0:  # meters: below 1 m the direction is noise
        raise AcquisitionInfeasible(f"{what} is too small ({norm:.3g} m) to define the e/i direction")
    return np.array([v[0], v[1]]) / norm


def _build(roe0, chief, da_dot, cfg, t_earliest, *, no_burns=()):
    a = chief.a
    x0 = np.asarray(roe0, dtype=float)
    s = 1.0 if x0[1] > 0 else -1.0
    try:
        epochs = grid_epochs(t_earliest, chief.t0 + cfg.window, chief, cfg.grid_per_orbit, cfg.j2)
    except ValueError as exc:
        raise AcquisitionInfeasible(str(exc)) from exc
    if len(epochs) < 2:
        raise AcquisitionInfeasible(
            f"window too short: {len(epochs)} candidate burn epoch(s) between the earliest burn "
            f"(OD epoch + {t_earliest - chief.t0:.0f} s) and the end of the window (OD epoch + {cfg.window:.0f} s)")
    # the burn-free motion until the first opportunity must respect the minimum separation by itself
    early = np.linspace(chief.t0, epochs[0], 64)
    early_dl = s * a * propagate(x0, early - chief.t0, a, chief.inc, cfg.j2, da_dot=da_dot)[:, 1]
    if early_dl.min() < cfg.a_dl_min:
        raise AcquisitionInfeasible(
            f"the mean along-track separation is {early_dl.min():.0f} m before the first burn opportunity, below "
            f"a_dl_min = {cfg.a_dl_min:g} m: no plan can keep it above the minimum")
    axes = parse_axes(cfg.axes)
    k_count, j_count = len(epochs), len(axes)
    q = cfg.dv_quantum
    effects = carrier_burn_effects(epochs, axes, chief, cfg.j2) * q  # (K, J, 6) per quantum
    t_f = float(epochs[-1])
    final = a * response_at(effects, epochs, t_f, a, chief.inc, j2=cfg.j2).reshape(k_count * j_count, 6).T
    free = a * propagate(x0, np.concatenate([epochs, [t_f]]) - chief.t0, a, chief.inc, cfg.j2, da_dot=da_dot)
    step = float(epochs[1] - epochs[0])
    # s a dl per quantum one candidate on, at lags 0 and 1: the recursive form's coefficients (_recursive_path)
    lag_rows = transition_matrices(np.array([0.0, step]), a, chief.inc, cfg.j2)[:, 1, :]  # (2, 6)
    path_lags = s * a * np.einsum("mc,kjc->mkj", lag_rows, effects).reshape(2, -1)
    path = path_pre = None
    if not SPARSE_PATH:  # the dense rows: every grid epoch against every earlier candidate
        path = s * a * grid_response(effects, step, a, chief.inc, cfg.j2, component=1).reshape(k_count, -1)
        if 0 in axes:  # a radial burn moves dl at once: constrain the state just before each burn too
            path_pre = path.copy()
            own = np.repeat(np.arange(k_count), j_count)
            path_pre[own, np.arange(k_count * j_count)] = 0.0
    gamma = math.radians(cfg.ei_angle_tol_deg)
    return _Problem(
        cfg=cfg, epochs=epochs, axes=axes, final=final, free_final=free[-1], path=path, path_pre=path_pre,
        free_path=s * free[:-1, 1],
        path_floor=cfg.a_dl_min + a * sagitta(step, a, chief.inc, cfg.j2, da_dot) + 1e-6,
        epoch_of=np.repeat(np.arange(k_count), j_count), s=s,
        barred=np.any([(epochs >= lo) & (epochs <= hi) for lo, hi in no_burns], axis=0) if len(no_burns)
        else np.zeros(k_count, dtype=bool),
        quanta_max=int(math.floor(cfg.max_burn_dv / q + 1e-9)), ei_floor=ei_magnitude_floor(cfg.min_ei, gamma),
        path_lags=path_lags)


@dataclass(frozen=True)
class _Layout:
    """The LP's variables, in this order: v = [p (S), m (S), L, mu, nu].

    p, m >= 0 [quanta]: the positive and negative parts of the S candidate burns (a burn is p - m, its L1 cost
    p + m); L = s a dl_F [m]; mu = -s a de_F . i^ and nu = a di_F . i^ [m], the e/i magnitudes along the fixed
    direction i^ (module docstring, Formulation).
    """

    n_s: int  # candidate (epoch, axis) columns

    @property
    def size(self) -> int:
        return 2 * self.n_s + 3

    @property
    def l(self) -> int:  # noqa: E743 (the paper's name of the along-track separation)
        return 2 * self.n_s

    @property
    def mu(self) -> int:
        return 2 * self.n_s + 1

    @property
    def nu(self) -> int:
        return 2 * self.n_s + 2

    def row(self, burn_coef, extra=None) -> np.ndarray:
        """One dense row: ``burn_coef`` over [p, m] (a scalar or ``2 S`` values), ``extra`` {column: value}."""
        r = np.zeros(self.size)
        r[:2 * self.n_s] = burn_coef
        for idx, val in (extra or {}).items():
            r[idx] = val
        return r


@dataclass(frozen=True)
class _Rows:
    """A group of constraint rows lb <= a v <= ub (``a`` dense, over :class:`_Layout`'s variables)."""

    a: np.ndarray  # (R, 2 S + 3)
    lb: np.ndarray  # (R,)
    ub: np.ndarray  # (R,)


def _rows(lay: _Layout, specs) -> _Rows:
    """:class:`_Rows` from ``(burn_coef, extra, lb, ub)`` tuples (see :meth:`_Layout.row`)."""
    return _Rows(np.array([lay.row(coef, extra) for coef, extra, _, _ in specs]).reshape(len(specs), lay.size),
                 np.array([lb for _, _, lb, _ in specs], dtype=float),
                 np.array([ub for _, _, _, ub in specs], dtype=float))


def _drift_rows(lay: _Layout, dmat, c_f, tol) -> _Rows:
    """|a da_F| <= ``tol`` (AVANTI IC: almost no drift): one row over the burns' effect on a da_F (seed 002 Eq. 2)."""
    return _rows(lay, [(dmat[0], None, -tol - c_f[0], tol - c_f[0])])


def _along_track_rows(lay: _Layout, dmat, c_f, s) -> _Rows:
    """a dl_F = s L: the final mean along-track separation defines L (its range is in L's bounds)."""
    return _rows(lay, [(dmat[1], {lay.l: -s}, -c_f[1], -c_f[1])])


def _ei_direction_rows(lay: _Layout, dmat, c_f, ihat, *, s, exact, tg) -> _Rows:
    """de_F . i^ = -s mu and di_F . i^ = nu (e/i (anti-)parallel along i^, passive safety, seed 002 Eq. 25); then
    de_F . j^ = 0 (``exact``: the continuous LP), or the quantized program's tolerance cones
    |de_F . j^| <= tan(g/2) mu and |di_F . j^| <= tan(g/2) nu with ``tg`` = tan(g/2) (j^ = i^ turned by +90 deg)."""
    jhat = np.array([-ihat[1], ihat[0]])
    e_al, e_pp = ihat @ dmat[2:4], jhat @ dmat[2:4]
    i_al, i_pp = ihat @ dmat[4:6], jhat @ dmat[4:6]
    specs = [(e_al, {lay.mu: s}, -ihat @ c_f[2:4], -ihat @ c_f[2:4]),
             (i_al, {lay.nu: -1.0}, -ihat @ c_f[4:6], -ihat @ c_f[4:6])]
    if exact:
        specs.append((e_pp, None, -jhat @ c_f[2:4], -jhat @ c_f[2:4]))
    else:
        specs += [(e_pp, {lay.mu: -tg}, -np.inf, -jhat @ c_f[2:4]),
                  (-e_pp, {lay.mu: -tg}, -np.inf, jhat @ c_f[2:4]),
                  (i_pp, {lay.nu: -tg}, -np.inf, -jhat @ c_f[4:6]),
                  (-i_pp, {lay.nu: -tg}, -np.inf, jhat @ c_f[4:6])]
    return _rows(lay, specs)


def _fov_rows(lay: _Layout, cfg: AcquisitionConfig, cg) -> _Rows:
    """The camera field of view, seed 002 Eq. (11): |de| <= mu / cos(g/2) <= tan(fov_r) L, and likewise
    |di| <= nu / cos(g/2) <= tan(fov_n) L (``cg`` = cos(g/2))."""
    zero = np.zeros(2 * lay.n_s)
    return _rows(lay, [
        (zero, {lay.mu: 1.0 / cg, lay.l: -float(fov_limit(1.0, math.radians(cfg.fov_half_r_deg)))}, -np.inf, 0.0),
        (zero, {lay.nu: 1.0 / cg, lay.l: -float(fov_limit(1.0, math.radians(cfg.fov_half_n_deg)))}, -np.inf, 0.0)])


def _variable_bounds(pb: _Problem, lay: _Layout, cols, *, exact, target, ei):
    """Bounds lo <= v <= hi: 0 <= p, m <= quanta_max (0 at epochs in ``no_burns``); L in [a_dl_min, a_dl_max],
    or on ``a_dl_target`` (within ``a_dl_target_tol`` unless ``exact``) when ``target``; mu, nu >= the e/i floor
    (:func:`ei_magnitude_floor`), or 0 when ``ei`` is off (the diagnosis)."""
    cfg, n_s = pb.cfg, lay.n_s
    lo_v = np.zeros(lay.size)
    hi_v = np.full(lay.size, float(pb.quanta_max))
    barred = pb.barred[pb.epoch_of[cols]]
    hi_v[:n_s][barred] = hi_v[n_s:2 * n_s][barred] = 0.0
    if cfg.a_dl_target and target:
        span = 0.0 if exact else cfg.a_dl_target_tol
        lo_v[lay.l] = max(cfg.a_dl_min, cfg.a_dl_target - span)
        hi_v[lay.l] = min(cfg.a_dl_max, cfg.a_dl_target + span)
    else:
        lo_v[lay.l], hi_v[lay.l] = cfg.a_dl_min, cfg.a_dl_max
    lo_v[lay.mu] = lo_v[lay.nu] = pb.ei_floor if ei else 0.0
    hi_v[lay.mu] = hi_v[lay.nu] = np.inf
    if not ei:
        lo_v[lay.mu] = lo_v[lay.nu] = hi_v[lay.mu] = hi_v[lay.nu] = 0.0
    return lo_v, hi_v


def _objective(lay: _Layout) -> np.ndarray:
    """sum (p + m): the L1 delta-v in quanta (L, mu and nu cost nothing)."""
    return np.concatenate([np.ones(2 * lay.n_s), np.zeros(3)])


def _assemble(pb: _Problem, cols, ihat, exact, path=True, *, target=True, ei=True):
    """Objective, variable bounds and rows lb <= A v <= ub over the :class:`_Layout` v = [p, m, L, mu, nu].

    Rows in order: drift, along-track, e/i direction and field of view (``ei``), path (``path``), burn magnitude.
    ``exact``: the continuous LP (e/i exactly (anti-)parallel, dl on target); otherwise the quantized program with
    the tolerance cones. ``path``/``target``/``ei`` switch constraint groups off to diagnose infeasibility.
    """
    from scipy import sparse  # here, not at import: the nodes import this module for its config alone

    cfg = pb.cfg
    lay = _Layout(len(cols))
    f = pb.final[:, cols]
    dmat = np.hstack([f, -f])  # (6, 2S): effect of p and of m
    c_f = pb.free_final
    half = 0.5 * math.radians(cfg.ei_angle_tol_deg)
    groups = [_drift_rows(lay, dmat, c_f, cfg.drift_tolerance), _along_track_rows(lay, dmat, c_f, pb.s)]
    if ei:
        groups += [_ei_direction_rows(lay, dmat, c_f, ihat, s=pb.s, exact=exact, tg=math.tan(half)),
                   _fov_rows(lay, cfg, math.cos(half))]
    blocks = [sparse.csr_matrix(np.vstack([g.a for g in groups]))]
    lb = list(np.concatenate([g.lb for g in groups]))
    ub = list(np.concatenate([g.ub for g in groups]))
    if path:  # s a dl >= a_dl_min at every grid epoch (plus the sagitta between epochs)
        path_blocks, path_lb, burn_block, burn_ub = _path_and_burn_rows(pb, cols)
        blocks += path_blocks
        lb += path_lb
        ub += [np.inf] * len(path_lb)
    else:  # the dense path rows are not built (the recursive form's LP, a diagnosis)
        burn_block, burn_ub = _burn_magnitude_rows(pb, cols)
    blocks.append(burn_block)
    lb += [-np.inf] * len(burn_ub)
    ub += burn_ub
    a_mat = sparse.vstack(blocks).tocsr()
    lo_v, hi_v = _variable_bounds(pb, lay, cols, exact=exact, target=target, ei=ei)
    return _objective(lay), lo_v, hi_v, a_mat, np.array(lb, dtype=float), np.array(ub, dtype=float)


def signed_rows(sub: np.ndarray) -> "sparse.csr_matrix":
    """The rows ``[sub, -sub, 0]`` over v = [p, m, L, mu, nu] (three zero columns for L, mu, nu) of the dense
    ``sub`` ``(R, n)`` as a CSR matrix of its nonzeros. ``sub`` is converted once and each row's nonzeros are laid
    out twice, at their columns then at ``n`` + their columns negated: the same arrays (indptr, indices, data) as
    converting the dense ``[sub, -sub]`` (whose nonzeros per row are those of ``sub``, then the same negated) and
    appending an empty ``(R, 3)`` block, without building and scanning the doubled dense block."""
    from scipy import sparse

    a = sparse.csr_matrix(sub)
    n = sub.shape[1]
    count = np.diff(a.indptr)  # nonzeros per row
    first = np.arange(a.nnz) + np.repeat(a.indptr[:-1], count)  # entry p of row r at 2 indptr[r] + (p - indptr[r])
    second = first + np.repeat(count, count)  # its negated copy, after the row's first copies
    indices = np.empty(2 * a.nnz, dtype=a.indices.dtype)
    data = np.empty(2 * a.nnz)
    indices[first], indices[second] = a.indices, a.indices + n
    data[first], data[second] = a.data, -a.data
    return sparse.csr_matrix((data, indices, 2 * a.indptr), shape=(len(sub), 2 * n + 3))


def _dense_path(pb: _Problem, cols):
    """The dense path rows' columns ``cols`` (post-burn, and pre-burn with radial burns; ``(K, len(cols))`` each):
    ``pb.path``'s where it was built, else from the two lags of the recursive form (the secular dl is affine in the
    lag: path[i, c] = lag0 + (i - e) (lag1 - lag0) for i >= e, the candidate's epoch e; 0 before it)."""
    cols = np.asarray(cols)
    if pb.path is not None:
        return pb.path[:, cols], None if pb.path_pre is None else pb.path_pre[:, cols]
    own = pb.epoch_of[cols]
    lag = np.arange(len(pb.epochs))[:, None] - own[None, :]
    post = np.where(lag >= 0, pb.path_lags[0, cols] + lag * (pb.path_lags[1, cols] - pb.path_lags[0, cols]), 0.0)
    return post, (np.where(lag > 0, post, 0.0) if 0 in pb.axes else None)


def _path_rows(pb: _Problem, cols):
    """s a dl >= a_dl_min at every grid epoch, raised by the sagitta between epochs (module docstring, Formulation):
    the post-burn rows and, with radial burns, the pre-burn rows, as :func:`signed_rows` blocks with their lower
    bounds ``path_floor - free_path``."""
    blocks, lb = [], []
    for mat in _dense_path(pb, cols):
        if mat is None:
            continue
        blocks.append(signed_rows(mat))
        lb += list(pb.path_floor - pb.free_path)
    return blocks, lb


def _burn_magnitude_rows(pb: _Problem, cols):
    """|dvR| + |dvT| + |dvN| <= max_burn_dv per grid epoch (BIROS, seed 001 Sec. 2.1): sum (p + m) over the
    epoch's candidates <= quanta_max, one row per epoch among ``cols``; it bounds the Euclidean norm (exact for one
    axis). Returns the CSR block over [p, m, L, mu, nu] and the upper bounds."""
    from scipy import sparse

    n_s = len(cols)
    groups, member = np.unique(pb.epoch_of[cols], return_inverse=True)
    one = np.ones(n_s)
    per_epoch = sparse.csr_matrix((np.concatenate([one, one]),
                                   (np.concatenate([member, member]), np.arange(2 * n_s))),
                                  shape=(len(groups), 2 * n_s))
    return sparse.hstack([per_epoch, sparse.csr_matrix((len(groups), 3))]), [pb.quanta_max] * len(groups)


def _path_and_burn_rows(pb: _Problem, cols):
    """:func:`_path_rows` and :func:`_burn_magnitude_rows` (the rows the e/i direction leaves alone), memoised in
    ``pb.rows`` by ``cols`` (the LP is solved again for each e/i direction, and a plan's diagnosis relaxes other
    groups): the same matrices each time."""
    key = np.asarray(cols).tobytes()
    if key not in pb.rows:
        pb.rows[key] = (*_path_rows(pb, cols), *_burn_magnitude_rows(pb, cols))
    return pb.rows[key]


#: The continuous LP's path constraints in their sparse recursive form (:func:`_recursive_path`); False: the dense
#: rows of :func:`_path_rows` (``bench/bench_lp.py`` compares the two)
SPARSE_PATH = True


def _recursive_path(pb: _Problem, cols, n_v: int):
    """The path constraints s a dl_i >= path_floor at every grid epoch i in a sparse recursive form: the same
    feasible set as :func:`_path_rows`, over 2 K - 1 more variables (issue 42; docs/benchmarks.md).

    The secular model's dl row of Phi(t) is (c_a t, 1, 0, 0, c_ix t, 0) and its da and di rows the identity (seed
    002 Eq. 2), so the burns' part of s a dl at epoch i, Lambda_i, obeys Lambda_i = Lambda_(i-1) + B_(i-1) + the
    epoch's terms lag0_c x_c and B_i = B_(i-1) + (lag1_c - lag0_c) x_c (x_c = p_c - m_c), lag0 and lag1 the dense
    rows' own entries one candidate on (``path_lags``; no new physics). The bound Lambda_i >= path_floor -
    free_path replaces the dense row; with radial burns the pre-burn row is Lambda_i - the epoch's terms >= the
    same. About 2 K (2 + J) nonzeros in all, where the dense block has about K^2 J.

    Parameters
    ----------
    pb : _Problem
        The problem.
    cols : array_like of int
        The candidate columns of the LP.
    n_v : int
        The LP's variables before the new ones (2 S + 3).

    Returns
    -------
    tuple
        ``(a_eq, b_eq, a_ge, b_ge, lo, hi)``: the recursion rows (CSR, ``n_v + 2 K - 1`` columns) with their
        right-hand sides, the pre-burn rows ``a_ge v >= b_ge`` (None without radial burns) and the new variables'
        bounds (Lambda_0..K-1, then B_0..K-2).
    """
    from scipy import sparse

    cols = np.asarray(cols)
    k_count, n_s = len(pb.epochs), len(cols)
    own = pb.epoch_of[cols]  # each candidate's epoch
    lam0, b0 = n_v, n_v + k_count  # the columns of Lambda_0 and B_0
    w = n_v + 2 * k_count - 1
    x_idx = np.arange(n_s)
    nxt = np.minimum(own + 1, k_count - 1)
    if pb.path_lags is not None:
        c_lam, c_lag1 = pb.path_lags[0, cols], pb.path_lags[1, cols]
    else:  # the dense rows' own entries
        c_lam, c_lag1 = pb.path[own, cols], pb.path[nxt, cols]
    c_b = np.where(own + 1 < k_count, c_lag1 - c_lam, 0.0)  # lag 1 minus lag 0
    radial = (0 in pb.axes) if pb.path is None else pb.path_pre is not None
    rows, cidx, vals = [], [], []

    def put(r, c, v):
        r = np.atleast_1d(r)
        rows.append(r), cidx.append(np.broadcast_to(c, r.shape)), vals.append(np.broadcast_to(v, r.shape).astype(float))

    # Lambda rows 0..K-1: Lambda_i - Lambda_(i-1) - B_(i-1) - sum c_lam x = 0
    i = np.arange(k_count)
    put(i, lam0 + i, 1.0)
    put(i[1:], lam0 + i[1:] - 1, -1.0)
    put(i[1:], b0 + i[1:] - 1, -1.0)
    put(own, x_idx, -c_lam)
    put(own, n_s + x_idx, c_lam)
    # B rows K..2K-2: B_i - B_(i-1) - sum c_b x = 0 (i = 0..K-2)
    ib = np.arange(k_count - 1)
    put(k_count + ib, b0 + ib, 1.0)
    put(k_count + ib[1:], b0 + ib[1:] - 1, -1.0)
    keep = own < k_count - 1
    put(k_count + own[keep], x_idx[keep], -c_b[keep])
    put(k_count + own[keep], n_s + x_idx[keep], c_b[keep])
    r, c, v = (np.concatenate(z) for z in (rows, cidx, vals))
    a_eq = sparse.csr_matrix((v, (r, c)), shape=(2 * k_count - 1, w))
    floor = pb.path_floor - pb.free_path
    lo = np.concatenate([floor, np.full(k_count - 1, -np.inf)])
    hi = np.full(2 * k_count - 1, np.inf)
    a_ge = b_ge = None
    if radial:  # Lambda_i minus the epoch's own burns >= the floor: the state just before them
        r = np.concatenate([i, own, own])
        c = np.concatenate([lam0 + i, x_idx, n_s + x_idx])
        v = np.concatenate([np.ones(k_count), -c_lam, c_lam])
        a_ge, b_ge = sparse.csr_matrix((v, (r, c)), shape=(k_count, w)), floor
    return a_eq, np.zeros(2 * k_count - 1), a_ge, b_ge, lo, hi


def _linprog(pb, cols, ihat, use_linprog=False, **flags):
    """The continuous LP in linprog's form (a_ub v <= b_ub, a_eq v = b_eq), solved by :func:`.highs.solve_lp`; its
    path constraints in the sparse recursive form (:func:`_recursive_path`: the rows after :func:`_assemble`'s, over
    2 K - 1 more variables after its 2 S + 3) unless :data:`SPARSE_PATH` is off or ``path`` is (the diagnosis)."""
    from scipy import sparse

    recursive = SPARSE_PATH and flags.get("path", True)
    cost, lo_v, hi_v, a_mat, lb, ub = _assemble(pb, cols, ihat, exact=True,
                                                **{**flags, "path": flags.get("path", True) and not recursive})
    if recursive:
        n_v = len(cost)
        a_eq, b_eq, a_ge, b_ge, lo_p, hi_p = _recursive_path(pb, cols, n_v)
        w = a_eq.shape[1]
        blocks = [sparse.hstack([a_mat, sparse.csr_matrix((a_mat.shape[0], w - n_v))]), a_eq]
        lb, ub = [lb, b_eq], [ub, b_eq]
        if a_ge is not None:  # a_ge v >= b_ge
            blocks.append(a_ge)
            lb.append(b_ge)
            ub.append(np.full(len(b_ge), np.inf))
        a_mat, lb, ub = sparse.vstack(blocks).tocsr(), np.concatenate(lb), np.concatenate(ub)
        cost = np.concatenate([cost, np.zeros(w - n_v)])
        lo_v, hi_v = np.concatenate([lo_v, lo_p]), np.concatenate([hi_v, hi_p])
    eq = lb == ub
    up = ~eq & np.isfinite(ub)
    low = ~eq & np.isfinite(lb)
    a_ub = sparse.vstack([a_mat[np.flatnonzero(up)], -a_mat[np.flatnonzero(low)]]).tocsr()
    b_ub = np.concatenate([ub[up], -lb[low]])
    return solve_lp(cost, a_ub, b_ub, a_mat[np.flatnonzero(eq)], ub[eq], lo=lo_v, hi=hi_v, use_linprog=use_linprog)


def _milp(pb, cols, ihat):
    """The quantized program over the candidate columns ``cols`` (a neighbourhood of the LP's support, a few dozen):
    its path rows dense (:func:`_dense_path`), small at that size."""
    from scipy.optimize import Bounds, LinearConstraint, milp

    cost, lo_v, hi_v, a_mat, lb, ub = _assemble(pb, cols, ihat, exact=False)
    integrality = np.concatenate([np.ones(2 * len(cols)), np.zeros(3)])
    return milp(cost, integrality=integrality, bounds=Bounds(lo_v, hi_v), constraints=LinearConstraint(a_mat, lb, ub),
                options={"time_limit": pb.cfg.milp_time_limit, "mip_rel_gap": 1e-6})


def _diagnose(pb, cols, ihat, a_da0, a_da_dot, *, duration, n):
    """A reason for an infeasible LP, from the drift budget and from relaxing one group of constraints at a time."""
    cfg = pb.cfg
    need = drift_nulling_dv_bound(a_da0, a_da_dot, duration, n, cfg.drift_tolerance)
    if 1 not in pb.axes:
        return f"the da drift cannot be nulled without tangential burns (axes = {cfg.axes!r})"
    budget = len(pb.epochs) * cfg.max_burn_dv
    if need > budget:
        return (f"nulling the drift needs at least {need:.3f} m/s of tangential delta-v but {len(pb.epochs)} "
                f"burns of at most max_burn_dv = {cfg.max_burn_dv:g} m/s give {budget:.3f} m/s: window too short")
    if _linprog(pb, cols, ihat, path=False).status == 0:
        return (f"the mean along-track separation would fall below a_dl_min = {cfg.a_dl_min:g} m during the "
                f"acquisition")
    if cfg.a_dl_target and _linprog(pb, cols, ihat, target=False).status == 0:
        return (f"the along-track target a_dl_target = {cfg.a_dl_target:g} m cannot be reached within the window "
                f"with burns of at most max_burn_dv = {cfg.max_burn_dv:g} m/s")
    if _linprog(pb, cols, ihat, ei=False).status == 0:
        return ("the e/i vectors cannot be made (anti-)parallel, at least min_ei = "
                f"{cfg.min_ei:g} m and inside the field of view with the allowed axes {cfg.axes!r}")
    return (f"no combination of burns of at most max_burn_dv = {cfg.max_burn_dv:g} m/s on the axes {cfg.axes!r} "
            f"reaches an along-track separation in [{cfg.a_dl_min:g}, {cfg.a_dl_max:g}] m with no drift within the "
            f"window of {cfg.window:g} s")


def _check_drift_lattice(pb):
    """Quantized tangential burns leave a da_F on a lattice: a da_F = free + k (2 dv_quantum / n) for integer k
    (Eq. 2; no other burn component and no propagation changes da). Refuse at once when no lattice point lies within
    the drift tolerance."""
    if 1 not in pb.axes:
        return
    step = abs(float(pb.final[0, pb.axes.index(1)]))  # column of the first epoch's tangential burn
    free = float(pb.free_final[0])
    nearest = free + step * np.round(-free / step + np.array([-1.0, 0.0, 1.0]))
    tol = pb.cfg.drift_tolerance
    if np.min(np.abs(nearest)) > tol:
        closest = nearest[np.argmin(np.abs(nearest))]
        raise AcquisitionInfeasible(
            f"no plan quantized to dv_quantum = {pb.cfg.dv_quantum:g} m/s can null the drift: the final a da takes "
            f"values {step:.2f} m apart, the closest to zero is {closest:+.2f} m, outside drift_tolerance = "
            f"{tol:g} m (a tolerance of at least {0.5 * step:.2f} m always works)")


def _neighbourhood(pb, support, orbits, steps):
    """Candidate columns for the quantized re-solve: the LP's support epochs shifted by up to ``orbits`` whole
    orbits (same u: the e-vector effect is kept, dl moves by 3 dv t per quantum) and ``steps`` grid steps, plus every
    epoch of the last orbit (late tangential trims move dl little), on the support's axes and T."""
    k_count, j_count, g = len(pb.epochs), len(pb.axes), pb.cfg.grid_per_orbit
    shifts = (np.arange(-orbits, orbits + 1)[:, None] * g + np.arange(-steps, steps + 1)[None, :]).ravel()
    near = pb.epoch_of[support][:, None] + shifts[None, :]
    epochs = np.unique(np.concatenate([near[(near >= 0) & (near < k_count)], np.arange(max(k_count - g, 0), k_count)]))
    axes = np.unique(np.concatenate([support % j_count, [pb.axes.index(1)] if 1 in pb.axes else []]).astype(int))
    return (epochs[:, None] * j_count + axes[None, :]).ravel()


def check_inputs(roe0: ArrayLike, chief: Chief, da_dot: float) -> None:
    """Reject an unusable estimate (NaN, infinite, impossible orbit, no along-track separation).

    Parameters
    ----------
    roe0, chief, da_dot
        As for :func:`plan_acquisition`.

    Returns
    -------
    None
        :class:`AcquisitionInfeasible` (a ValueError) with the reason when unusable.
    """
    x = np.asarray(roe0, dtype=float)
    if x.shape != (6,) or not np.all(np.isfinite(x)):
        raise AcquisitionInfeasible(f"the ROE estimate is not six finite numbers: {np.asarray(roe0).tolist()}")
    for name, value in (("a", chief.a), ("inc", chief.inc), ("u0", chief.u0), ("t0", chief.t0), ("da_dot", da_dot)):
        if not math.isfinite(float(value)):
            raise AcquisitionInfeasible(f"{name} of the estimate is not finite: {value}")
    if chief.a < R_EARTH_MIN:
        raise AcquisitionInfeasible(f"chief semi-major axis {chief.a} m is not a valid low Earth orbit")
    if abs(x[1] * chief.a) < 1.0:
        raise AcquisitionInfeasible("the mean along-track separation is zero: leading or following is undefined")


def plan_acquisition(roe0: ArrayLike, chief: Chief, da_dot: float = 0.0, cfg: AcquisitionConfig = AcquisitionConfig(),
                     t_earliest: float | None = None, *,
                     no_burns: Sequence[tuple[float, float]] = ()) -> AcquisitionPlan:
    """Minimum-delta-v carrier plan from the estimate ``roe0`` (dimensionless, at ``chief.t0``) to the ICs.

    Parameters
    ----------
    roe0 : array_like, shape (6,)
        The estimated ROE (dimensionless) at ``chief.t0``.
    chief : Chief
        The chief's a, i and argument of latitude at the OD epoch.
    da_dot : float
        Estimated drift of da from differential drag [1/s] (the OD's a_da_dot / a).
    cfg : AcquisitionConfig
        The requirements and planning knobs.
    t_earliest : float, optional
        First admissible burn epoch [s] (default ``chief.t0 + planning_margin``; a node passes max(OD epoch, now)
        + margin).
    no_burns : sequence of (float, float)
        Intervals ``(start, end)`` [s] in which no burn may fly (the final OD's radar arc).

    Returns
    -------
    AcquisitionPlan
        The verified plan; :class:`AcquisitionInfeasible` (a ValueError) with the reason when none exists.
    """
    validate_config(cfg)
    check_inputs(roe0, chief, da_dot)
    a = float(chief.a)
    n = float(mean_motion(a))
    x0 = np.asarray(roe0, dtype=float)
    margin = cfg.planning_margin
    if margin is None:
        margin = 2.0 * math.pi / float(arg_latitude_rate(a, chief.inc, cfg.j2))
    if t_earliest is None:
        t_earliest = chief.t0 + margin
    if not math.isfinite(t_earliest) or t_earliest < chief.t0:
        raise AcquisitionInfeasible(f"t_earliest = {t_earliest} s precedes the OD epoch {chief.t0} s")
    start = time.perf_counter()
    pb = _build(x0, chief, da_dot, cfg, t_earliest, no_burns=tuple(no_burns))
    _check_drift_lattice(pb)
    all_cols = np.arange(pb.final.shape[1])
    ihat = _unit(pb.free_final[4:6], "the predicted relative inclination vector")

    # continuous LP, iterating the e/i direction to the planned di_F (J2 couples da into di_y)
    solves, lp_time = 0, 0.0
    for _ in range(6):
        tic = time.perf_counter()
        res = _linprog(pb, all_cols, ihat)
        lp_time += time.perf_counter() - tic
        solves += 1
        if res.status != 0:
            if res.status == 2:
                raise AcquisitionInfeasible(
                    "no acquisition plan: " + _diagnose(pb, all_cols, ihat, a * x0[0], a * da_dot,
                                                           duration=float(pb.epochs[-1]) - chief.t0, n=n))
            raise AcquisitionInfeasible(f"the linear program failed: {res.message}")
        d_lp = res.x[:len(all_cols)] - res.x[len(all_cols):2 * len(all_cols)]
        lp_final = pb.free_final + pb.final @ d_lp
        new = _unit(lp_final[4:6], "the planned relative inclination vector")
        turned = abs(math.atan2(ihat[0] * new[1] - ihat[1] * new[0], ihat @ new))
        ihat = new
        if turned < 1e-7:
            break
    lp_dv = float(res.fun) * cfg.dv_quantum

    # quantized re-solve on growing neighbourhoods of the LP's support; keep the cheapest quantized plan found
    support = np.flatnonzero(np.abs(d_lp) > 1e-6)
    quantized, best = None, np.inf
    for reach in ((1, 0), (2, 1), None):
        cols = all_cols if reach is None or not len(support) else _neighbourhood(pb, support, *reach)
        out = _milp(pb, cols, ihat)
        solves += 1
        if out.x is not None and out.fun < best - 0.5:
            best = out.fun
            quantized = np.zeros(len(all_cols))
            quantized[cols] = np.round(out.x[:len(cols)] - out.x[len(cols):2 * len(cols)])
        if best <= math.ceil(res.fun - 1e-9) + QUANTA_SLACK:  # the LP optimum is a lower bound of the integer one
            break
    if quantized is None:
        lattice = 2.0 * cfg.dv_quantum / n
        raise AcquisitionInfeasible(
            f"no plan quantized to dv_quantum = {cfg.dv_quantum:g} m/s meets the initial conditions (the final "
            f"a da takes values {lattice:.2f} m apart: drift_tolerance = {cfg.drift_tolerance:g} m may be too "
            f"small; ei_angle_tol_deg = {cfg.ei_angle_tol_deg:g}, a_dl_target_tol = {cfg.a_dl_target_tol:g} m)")
    solve_time = time.perf_counter() - start
    return _finish(pb, x0, chief, da_dot, cfg, t_earliest=t_earliest, quantized=quantized, lp_final=lp_final,
                   lp_dv=lp_dv, times=(solve_time, lp_time), solves=solves, n=n)


def _finish(pb, x0, chief, da_dot, cfg, *, t_earliest, quantized, lp_final, lp_dv, times, solves, n):
    """Combine the quantized candidates into burns, predict with :func:`trajectory` and verify every IC."""
    a = float(chief.a)
    k_count, j_count = len(pb.epochs), len(pb.axes)
    dv = np.zeros((k_count, 3))
    dv[:, list(pb.axes)] = quantized.reshape(k_count, j_count) * cfg.dv_quantum
    used = np.flatnonzero(np.any(dv != 0.0, axis=1))
    epochs, dv = pb.epochs[used], dv[used]
    burns = [Burn(float(t), tuple(-v)) for t, v in zip(epochs, dv)]
    t_f = float(pb.epochs[-1])
    period = 2.0 * math.pi / float(arg_latitude_rate(a, chief.inc, cfg.j2))
    dense = np.unique(np.concatenate([np.arange(chief.t0, t_f, period / 64.0), pb.epochs, [t_f]]))
    traj = trajectory(x0, chief.t0, burns, dense, chief, j2=cfg.j2, da_dot=da_dot)
    final = traj[-1]
    f = final * a
    leading = pb.s > 0
    de, di = math.hypot(f[2], f[3]), math.hypot(f[4], f[5])
    sep = float(np.min(pb.s * traj[:, 1] * a))
    rn = float(min_rn_distance(final) * a)
    angle = float(ei_deviation(final, leading))
    plan = AcquisitionPlan(
        epochs=epochs, u=np.asarray(chief.u_at(epochs, cfg.j2), dtype=float), dv_carrier=dv, t0=chief.t0,
        t_earliest=float(t_earliest), t_final=t_f, final_roe=final, leading=leading,
        total_dv=float(np.sum(np.linalg.norm(dv, axis=1))), total_dv_l1=float(np.sum(np.abs(dv))), lp_dv=lp_dv,
        dv_lower_bound=drift_nulling_dv_bound(a * x0[0], a * da_dot, t_f - chief.t0, n, cfg.drift_tolerance),
        min_rn=rn, min_separation=sep,
        fov_r_margin=float(fov_limit(f[1], math.radians(cfg.fov_half_r_deg))) - de,
        fov_n_margin=float(fov_limit(f[1], math.radians(cfg.fov_half_n_deg))) - di,
        ei_angle_deg=math.degrees(angle), residual=f - lp_final, solve_time=times[0], lp_time=times[1],
        lp_solves=solves,
        candidates=pb.final.shape[1], a=a)
    problems = verify(plan, cfg)
    if problems:
        raise AcquisitionInfeasible("the quantized plan fails verification: " + "; ".join(problems))
    return plan


def verify(plan: AcquisitionPlan, cfg: AcquisitionConfig, eps: float = 1e-6) -> list[str]:
    """Every IC and execution constraint of a plan, checked on its :func:`trajectory` prediction.

    Parameters
    ----------
    plan : AcquisitionPlan
        The plan.
    cfg : AcquisitionConfig
        The requirements.
    eps : float
        Absorbs floating-point round-off only [m, m/s].

    Returns
    -------
    list of str
        The violations (empty when the plan is good).
    """
    f = plan.final_roe * plan.a
    s = 1.0 if plan.leading else -1.0
    out = []
    mags = np.linalg.norm(plan.dv_carrier, axis=1) if plan.n_burns else np.zeros(0)
    if np.any(mags > cfg.max_burn_dv + 1e-12):
        out.append(f"burn of {mags.max():.6f} m/s exceeds max_burn_dv = {cfg.max_burn_dv:g} m/s")
    steps = plan.dv_carrier / cfg.dv_quantum
    if np.any(np.abs(steps - np.round(steps)) > 1e-6):
        out.append(f"a burn component is not a multiple of dv_quantum = {cfg.dv_quantum:g} m/s")
    if abs(f[0]) > cfg.drift_tolerance + eps:
        out.append(f"a da_F = {f[0]:.3f} m exceeds drift_tolerance = {cfg.drift_tolerance:g} m")
    lo, hi = cfg.a_dl_min, cfg.a_dl_max
    if cfg.a_dl_target:
        lo, hi = max(lo, cfg.a_dl_target - cfg.a_dl_target_tol), min(hi, cfg.a_dl_target + cfg.a_dl_target_tol)
    if not lo - eps <= s * f[1] <= hi + eps:
        out.append(f"|a dl_F| = {abs(f[1]):.1f} m outside [{lo:g}, {hi:g}] m")
    for name, mag in (("a de_F", math.hypot(f[2], f[3])), ("a di_F", math.hypot(f[4], f[5]))):
        if mag < cfg.min_ei - eps:
            out.append(f"{name} = {mag:.1f} m below min_ei = {cfg.min_ei:g} m")
    if plan.ei_angle_deg > cfg.ei_angle_tol_deg + 1e-9:
        out.append(f"e/i vectors {plan.ei_angle_deg:.3f} deg from (anti-)parallel (tolerance "
                   f"{cfg.ei_angle_tol_deg:g} deg)")
    if plan.min_rn < cfg.min_ei - eps:
        out.append(f"minimum R-N distance (Eq. 25) {plan.min_rn:.1f} m below min_ei = {cfg.min_ei:g} m")
    if plan.fov_r_margin < -eps or plan.fov_n_margin < -eps:
        out.append(f"outside the camera field of view (Eq. 11): margins R {plan.fov_r_margin:.1f} m, "
                   f"N {plan.fov_n_margin:.1f} m")
    if plan.min_separation < cfg.a_dl_min - eps:
        out.append(f"mean along-track separation falls to {plan.min_separation:.1f} m, below a_dl_min = "
                   f"{cfg.a_dl_min:g} m")
    if plan.n_burns and (plan.epochs[0] < plan.t_earliest - eps or plan.epochs[-1] > plan.t_final + eps):
        out.append("a burn lies outside [t_earliest, t_final]")
    return out


def acquisition_trajectory(plan: AcquisitionPlan, roe0: ArrayLike, chief: Chief, times: ArrayLike,
                           da_dot: float = 0.0, *, j2: bool = True) -> np.ndarray:
    """Dimensionless ROE along the plan via :func:`trajectory` (relative impulses -dv_carrier).

    Parameters
    ----------
    plan : AcquisitionPlan
        The plan.
    roe0 : array_like, shape (6,)
        The ROE at ``chief.t0``.
    chief : Chief
        The chief.
    times : array_like, shape (n,)
        Output times [s], >= plan.t0.
    da_dot, j2 : float, bool
        The differential-drag rate of da [1/s]; with the J2 secular rates.

    Returns
    -------
    numpy.ndarray, shape (n, 6)
        The ROE.
    """
    return trajectory(roe0, chief.t0, plan.burns(), times, chief, j2=j2, da_dot=da_dot)


__all__ = ["AcquisitionConfig", "AcquisitionInfeasible", "AcquisitionPlan", "InvalidAcquisitionConfig",
           "acquisition_trajectory", "check_inputs", "drift_nulling_dv_bound", "ei_deviation", "ei_magnitude_floor",
           "plan_acquisition", "validate_config", "verify"]
