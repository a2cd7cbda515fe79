"""The P* envelope of the tumbling: cluster conditions that hold for every tumbling state of a set of probability P*.

Seed 004 asks for conditions (3)-(5) 'with probability P*' of the stage's (OS) random attitude: a NS separated at dt
leaves along e(Omega dt, psi) = (cos theta, sin theta sin psi, -sin theta cos psi), Omega ~ Rayleigh(sigma), psi
uniform, shared by every NS of the stage (:mod:`~roe_sep.core.deployment.cluster`, seed 004 ref. [5]). The set

    S* = {Omega <= Omega*, any psi},   Omega* = sigma sqrt(-2 ln(1 - P*))   (Rayleigh CDF 1 - exp(-W^2/2 sigma^2))

has probability exactly P* (:func:`omega_bound`): conditions that all hold on S* hold *jointly* with P >= P*.

NS i relative to NS j at time t (to the OS: V_j = 0, no drag), tau = t - dt:

    r = V_i M(tau_i) e(Omega dt_i, psi) - V_j M(tau_j) e(Omega dt_j, psi) + D_i(tau_i) - D_j(tau_j)

(:mod:`~roe_sep.core.deployment.cluster_dynamics`: M the HCW matrix, D the drag offset). With s = sin psi the
in-plane part is u + s w and the normal part cos psi h, so over psi

    |r|^2 = alpha + 2 beta s + gamma s^2 on s in [-1, 1],  alpha = |u|^2 + h^2, beta = u.w, gamma = |w|^2 - h^2,

extrema in closed form (:func:`psi_extrema`). Over Omega: branch and bound on cells [Omega_c - delta, Omega_c +
delta], |dr/dOmega| bounded over a cell (|de/dtheta| = |d2e/dtheta2| = 1) by the smaller of::

    L1 = s_max(V_i dt_i M_i - V_j dt_j M_j)
         + min(V_j dt_j s_max(M_j), V_i dt_i s_max(M_i)) |dt_i - dt_j| (Omega_c + delta)
    L2 = |(a_i M_i - a_j M_j) e_x| + |b_i M_i - b_j M_j|_yz + delta sum_k V_k dt_k^2 (|M_k e_x| + |M_k|_yz),

a_k = V_k dt_k sin(Omega_c dt_k), b_k = V_k dt_k cos(Omega_c dt_k), |X|_yz = max(|X e_y|, |X e_z|): |r| stays within
L delta of its value at the cell centre. A centre that violates a condition fails it; a cell whose bound clears it is
done; others split, down to a depth limit after which the case fails (conservative). At the sampled times.
"""

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .cluster_dynamics import drag_offset, hcw_terms, singular_values

LEVEL0_CELLS = 4  # cells over [0, Omega*] at the first level
MAX_DEPTH = 14  # halvings of a cell before an undecided case counts as failed (cell width Omega* / 65536)
CHUNK_CASES = 64  # cases decided together: the working arrays stay in cache (bench/bench_cluster.py)


def omega_bound(sigma: float, p_required: float) -> float:
    """Omega* [rad/s] with P(Omega <= Omega*) = P* for Omega ~ Rayleigh(``sigma`` [rad/s]): sigma sqrt(-2 ln(1 - P*)),
    P* = ``p_required`` in [0, 1)."""
    return float(sigma * np.sqrt(-2.0 * np.log1p(-p_required)))


def psi_extrema(ux: ArrayLike, uy: ArrayLike, wx: ArrayLike, wy: ArrayLike,
                h: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """(min, max) over psi of |r|^2 = |u + s w|^2 + (1 - s^2) h^2, s = sin psi in [-1, 1] (module docstring).

    The quadratic alpha + 2 beta s + gamma s^2 takes its extrema at s = +-1 or at its vertex s0 = -beta/gamma when
    that lies inside: a minimum there if gamma > 0, a maximum if gamma < 0.

    Parameters
    ----------
    ux, uy : array_like
        In-plane components of u [m].
    wx, wy : array_like
        In-plane components of w [m].
    h : array_like
        The normal amplitude [m]; all five broadcast.

    Returns
    -------
    (lo, hi) : numpy.ndarray
        The extrema of |r|^2 [m^2] (lo >= 0).
    """
    alpha = ux * ux + uy * uy + h * h
    beta = ux * wx + uy * wy
    gamma = wx * wx + wy * wy - h * h
    f_plus, f_minus = alpha + 2.0 * beta + gamma, alpha - 2.0 * beta + gamma
    with np.errstate(divide="ignore", invalid="ignore"):
        s0 = np.clip(np.where(gamma != 0.0, -beta / gamma, 0.0), -1.0, 1.0)
    f0 = alpha + (2.0 * beta + gamma * s0) * s0
    lo = np.minimum(np.minimum(f_plus, f_minus), np.where(gamma > 0.0, f0, np.inf))
    hi = np.maximum(np.maximum(f_plus, f_minus), np.where(gamma < 0.0, f0, -np.inf))
    return np.maximum(lo, 0.0), hi


@dataclass
class _Cases:
    """Per (case, time), flattened: the Omega-independent terms of r and of the derivative bounds (l0, l1, l2)."""

    dti: np.ndarray
    dtj: np.ndarray
    vi_m: tuple  # V_i (m00, m01, m10, m11, m22)(tau_i)
    vj_m: tuple
    dd: np.ndarray  # (2, N): in-plane drag offset D_i - D_j
    l0: np.ndarray
    l1: np.ndarray
    l2: np.ndarray
    n_times: int


def _cases(vi, dti, pi, vj, dtj, *, pj, t, n):
    vi, dti, pi, vj, dtj, pj = (np.asarray(x, dtype=float)[:, None] for x in (vi, dti, pi, vj, dtj, pj))
    t = np.asarray(t, dtype=float)
    ti, tj = t - dti, t - dtj
    a, b = hcw_terms(ti, n), hcw_terms(tj, n)
    dd = drag_offset(ti, n, pi) - drag_offset(tj, n, pj)
    _, s_lin = singular_values(tuple(vi * dti * x - vj * dtj * y for x, y in zip(a, b)))
    _, s_i = singular_values(a)
    _, s_j = singular_values(b)
    l1 = np.minimum(vj * dtj * s_j, vi * dti * s_i) * np.abs(dti - dtj)

    def col_norms(m):  # |M e_x| + max(|M e_y|, |m22|)
        return np.hypot(m[0], m[2]) + np.maximum(np.hypot(m[1], m[3]), np.abs(m[4]))

    l2 = vi * dti**2 * col_norms(a) + vj * dtj**2 * col_norms(b)
    shape = t.shape

    def flat(x):
        return np.broadcast_to(x, shape).ravel()

    return _Cases(flat(dti), flat(dtj), tuple(flat(vi * x) for x in a), tuple(flat(vj * y) for y in b),
                  np.stack([flat(dd[..., 0]), flat(dd[..., 1])]), flat(s_lin), flat(l1), flat(l2), shape[1])


def _extrema_at(c: _Cases, k, omega):
    """At cells (flat case-time index ``k``, angular rate ``omega`` [rad/s]): (min, max) over psi of |r|^2 and the
    bound of |dr/dOmega| at the cell centre (module docstring, L_c); ``k`` None evaluates every case-time at every
    rate of ``omega`` (shape ``(N, len(omega))``)."""
    def at(x):
        return x[:, None] if k is None else x[k]

    dti, dtj = at(c.dti), at(c.dtj)
    ci, si = np.cos(omega * dti), np.sin(omega * dti)
    cj, sj = np.cos(omega * dtj), np.sin(omega * dtj)
    a, b = [at(x) for x in c.vi_m], [at(y) for y in c.vj_m]
    ux = a[0] * ci - b[0] * cj + at(c.dd[0])
    uy = a[2] * ci - b[2] * cj + at(c.dd[1])
    wx = a[1] * si - b[1] * sj
    wy = a[3] * si - b[3] * sj
    lo2, hi2 = psi_extrema(ux, uy, wx, wy, a[4] * si - b[4] * sj)
    # dr/dOmega = -(V_i dt_i sin(th_i) M_i - V_j dt_j sin(th_j) M_j) e_x + (same with cos) n_psi, n_psi in y-z
    si, sj, ci, cj = si * dti, sj * dtj, ci * dti, cj * dtj
    lx = np.hypot(a[0] * si - b[0] * sj, a[2] * si - b[2] * sj)
    lyz = np.maximum(np.hypot(a[1] * ci - b[1] * cj, a[3] * ci - b[3] * cj), np.abs(a[4] * ci - b[4] * cj))
    return lo2, hi2, lx + lyz


def _split(k, omega, delta):
    half = 0.5 * delta
    return np.repeat(k, 2), np.stack([omega - half, omega + half], axis=-1).ravel(), half


def conditions(vi: ArrayLike, dti: ArrayLike, pi: ArrayLike, vj: ArrayLike, dtj: ArrayLike, *, pj: ArrayLike,
               t: ArrayLike, n: float, omega_star: float, r_min: float,
               r_max: float | None = None) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Conditions (3)-(5) on S* for NS i against NS j (against the OS: V_j = 0, p_j = 0), per case, for every state
    of S* at every sampled time: clear (|r| >= ``r_min``), and with ``r_max``: within (|r| <= ``r_max``) and upper,
    an upper bound of max |r| [m] over the times and S*, tight to r_max / 1000 where the case is within (the minimax
    cost). :data:`CHUNK_CASES` cases are decided together.

    Parameters
    ----------
    vi, vj : array_like, shape (C,)
        Ejection speeds of NS i and j [m/s].
    dti, dtj : array_like, shape (C,)
        Their ejection delays [s from the program start].
    pi, pj : array_like, shape (C,)
        Their drag accelerations [m/s^2].
    t : array_like, shape (C, T)
        Sample times [s from the program start].
    n : float
        The platform's mean motion [rad/s].
    omega_star : float
        The bound of the angular rate Omega [rad/s] (:func:`omega_bound`).
    r_min : float
        The least allowed distance [m].
    r_max : float, optional
        The largest allowed distance [m].

    Returns
    -------
    (clear, within, upper)
        Boolean ``(C,)``, boolean ``(C,)`` and the upper bound ``(C,)`` [m] (the last two None without ``r_max``).
    """
    args = [np.asarray(x, dtype=float) for x in (vi, dti, pi, vj, dtj, pj)]
    t = np.asarray(t, dtype=float)
    out = []
    for start in range(0, t.shape[0], CHUNK_CASES):
        part = slice(start, start + CHUNK_CASES)
        parts = [np.broadcast_to(x, t.shape[:1])[part] for x in args]
        out.append(_decide(_cases(*parts[:5], pj=parts[5], t=t[part], n=n),
                           omega_star, r_min, r_max))
    clear = np.concatenate([o[0] for o in out])
    if r_max is None:
        return clear, None, None
    return clear, np.concatenate([o[1] for o in out]), np.concatenate([o[2] for o in out])


def _decide(c: _Cases, omega_star, r_min, r_max):
    n_cases = c.l0.size // c.n_times
    delta = 0.5 * omega_star / LEVEL0_CELLS
    omega = (2.0 * np.arange(LEVEL0_CELLS) + 1.0) * delta
    lo2, hi2, l_centre = (x.ravel() for x in _extrema_at(c, None, omega))
    k = np.repeat(np.arange(c.l0.size), LEVEL0_CELLS)
    omega = np.tile(omega, c.l0.size)
    margin = _margin(c, k, omega, delta, l_centre)
    clear = _clear(c, n_cases, k, omega, delta, value=np.sqrt(lo2), margin=margin, r_min=r_min)
    if r_max is None:
        return clear, None, None
    return (clear, *_within(c, n_cases, k, omega, delta, value=np.sqrt(hi2), margin=margin, r_max=r_max,
                            tol=1e-3 * r_max))


def _margin(c, k, omega, delta, l_centre):
    """L delta: the largest change of |r| over the cell, the smaller of the two bounds (module docstring)."""
    return np.minimum(c.l0[k] + c.l1[k] * (omega + delta), l_centre + c.l2[k] * delta) * delta


def _clear(c, n_cases, k, omega, delta, *, value, margin, r_min):
    failed = np.zeros(n_cases, dtype=bool)
    for level in range(MAX_DEPTH + 1):
        case = k // c.n_times
        failed[case[value < r_min]] = True  # a state of S* inside the keep-out radius
        open_ = (value - margin < r_min) & ~failed[case]
        if level == MAX_DEPTH:
            failed[case[open_]] = True
        if level == MAX_DEPTH or not np.any(open_):
            return ~failed
        k, omega, delta = _split(k[open_], omega[open_], delta)
        lo2, _, l_centre = _extrema_at(c, k, omega)
        value, margin = np.sqrt(lo2), _margin(c, k, omega, delta, l_centre)


def _within(c, n_cases, k, omega, delta, *, value, margin, r_max, tol):
    failed = np.zeros(n_cases, dtype=bool)
    lower, upper = np.zeros(n_cases), np.zeros(n_cases)
    for level in range(MAX_DEPTH + 1):
        case = k // c.n_times
        np.maximum.at(lower, case, value)
        failed |= lower > r_max  # a state of S* beyond r**
        bound = value + margin
        open_ = ((bound > r_max) | (bound > lower[case] + tol)) & ~failed[case]
        if level == MAX_DEPTH:
            failed[case[bound > r_max]] = True
            open_[:] = False
        np.maximum.at(upper, case[~open_], bound[~open_])
        if not np.any(open_):
            return ~failed, np.maximum(upper, lower)
        k, omega, delta = _split(k[open_], omega[open_], delta)
        _, hi2, l_centre = _extrema_at(c, k, omega)
        value, margin = np.sqrt(hi2), _margin(c, k, omega, delta, l_centre)
