"""Nonlinear truth: carrier and picosatellite as two point masses in an inertial frame, integrated numerically.

Force model (per spacecraft, inertial equator-and-equinox-of-date frame of :mod:`roe_sep.core.od.radar`):

* Zonal geopotential to degree 2, 3 or 4 (EGM96 J2..J4): U = mu/r [1 - sum_n J_n (R_E/r)^n P_n(z/r)] (Vallado,
  *Fundamentals of Astrodynamics and Applications*, 4th ed., Eq. 8-19 restricted to m = 0); the acceleration is
  grad U, differentiated symbolically by heyoka (no hand-expanded gradients to get wrong).
* Atmospheric drag a = -1/2 B rho(h) |v_r| v_r (Vallado Eq. 8-28), B = c_d A / m per spacecraft, v_r = v -
  omega_E x r relative to an atmosphere co-rotating with the Earth, h = |r| - R_E (spherical altitude).
  Density: the exponential model rho = rho_ref exp(-(h - h_ref) / H) with the scale height H of Vallado's
  exponential atmosphere (Table 8-4) for the band containing h_ref. Vallado's table gives 0.55 g/km^3 at 515 km;
  the seeds (000/002) assume 1 g/km^3, so :meth:`Atmosphere.seeds` keeps Vallado's H = 63.822 km and scales the
  profile to rho_ref = 1e-12 kg/m^3 at 515 km (factor 1.82, within the solar-cycle spread of the real density).
  With that reference the model's differential drag :func:`~roe_sep.core.relmotion.dynamics.drag_da_dot` and this
  truth use the same density at the reference altitude.

Integrator: heyoka's adaptive Taylor method (Biscani & Izzo, MNRAS 2021), JIT-compiled with LLVM. Both spacecraft
form one 12-dimensional system so that they share every step: integration error is then common-mode and largely
cancels in the relative state. The compiled integrator is cached per process and configuration
(:func:`pair_integrator`, about 2-5 s to compile on first use); batch mode (SIMD lanes, one sample pair each) and a
thread pool over blocks of lanes run the Monte Carlo (:func:`propagate_pairs`) and the sweeps
(:func:`propagate_pairs_grid`).

State layout: ``(..., 12)`` = chief (carrier) position [m], velocity [m/s], then deputy (picosatellite) likewise.
Parameters: ``[B_chief, B_deputy, rho_ref, h_ref, H]`` (m^2/kg, m^2/kg, kg/m^3, m, m).
"""

import copy
import functools
import math
import os
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..constants import EARTH_ROTATION, J2, J3, J4, MU_EARTH, R_EARTH
from ..od.radar import rtn_matrix
from ..relmotion.roe import kepler_to_roe
from .mean_osc import cartesian_to_mean, mean_to_cartesian

ZONALS = {2: (J2,), 3: (J2, J3), 4: (J2, J3, J4)}

VALLADO_EXPONENTIAL = (
    # h0 [km], rho0 [kg/m^3], H [km]: Vallado (2013) Table 8-4, exponential atmosphere (CIRA-72 based), LEO rows
    (200.0, 2.789e-10, 37.105),
    (250.0, 7.248e-11, 45.546),
    (300.0, 2.418e-11, 53.628),
    (350.0, 9.518e-12, 53.298),
    (400.0, 3.725e-12, 58.515),
    (450.0, 1.585e-12, 60.828),
    (500.0, 6.967e-13, 63.822),
    (600.0, 1.454e-13, 71.835),
    (700.0, 3.614e-14, 88.667),
    (800.0, 1.170e-14, 124.64),
    (900.0, 5.245e-15, 181.05),
    (1000.0, 3.019e-15, 268.00),
)


def vallado_band(h):
    """Row ``(h0 [m], rho0 [kg/m^3], H [m])`` of Vallado Table 8-4 whose band [h0, next h0) contains ``h`` [m]."""
    h_km = float(h) / 1e3
    if not VALLADO_EXPONENTIAL[0][0] <= h_km < 1100.0:
        raise ValueError(f"altitude {h_km:.1f} km outside the tabulated 200-1100 km")
    row = [r for r in VALLADO_EXPONENTIAL if r[0] <= h_km][-1]
    return row[0] * 1e3, row[1], row[2] * 1e3


def vallado_density(h):
    """Vallado Table 8-4 density [kg/m^3] at altitude ``h`` [m]: rho = rho0 exp(-(h - h0)/H) (Vallado Eq. 8-33)."""
    h0, rho0, big_h = vallado_band(h)
    return rho0 * np.exp(-(float(h) - h0) / big_h)


@dataclass(frozen=True)
class Atmosphere:
    """Exponential density rho(h) = rho_ref exp(-(h - h_ref)/H) [kg/m^3], h the spherical altitude [m]."""

    rho_ref: float
    h_ref: float
    scale_height: float

    @classmethod
    def vallado(cls, h_ref):
        """Vallado Table 8-4 unscaled, referenced at ``h_ref`` [m]."""
        return cls(float(vallado_density(h_ref)), float(h_ref), vallado_band(h_ref)[2])

    @classmethod
    def scaled(cls, rho_ref, h_ref):
        """Vallado's scale height for the band of ``h_ref``, scaled so that rho(h_ref) = ``rho_ref`` (the seeds'
        1 g/km^3 at 515 km: Vallado's 0.551 g/km^3 times 1.82)."""
        return cls(float(rho_ref), float(h_ref), vallado_band(h_ref)[2])

    def density(self, h):
        """rho(h) [kg/m^3]."""
        return self.rho_ref * np.exp(-(np.asarray(h, dtype=float) - self.h_ref) / self.scale_height)

    def pars(self):
        return [self.rho_ref, self.h_ref, self.scale_height]


@dataclass(frozen=True)
class Maneuver:
    """An impulsive burn of one spacecraft: epoch [s], ``deputy`` (picosatellite) or not (carrier), and its *own*
    velocity change [m/s] in its own RTN frame at that epoch."""

    epoch: float
    dv_rtn: tuple
    deputy: bool

    def relative(self):
        """The relative impulse of the seed convention (picosatellite w.r.t. carrier): +dv or -dv."""
        dv = np.asarray(self.dv_rtn, dtype=float)
        return dv if self.deputy else -dv


# ---------------------------------------------------------------- dynamics (heyoka expressions)
def legendre(n, s):
    """Legendre polynomial P_n(s), n = 2..4, written with products only (heyoka's pow(s, k) recursion divides by
    s, which is 0 on the equator)."""
    s2 = s * s
    if n == 2:
        return 1.5 * s2 - 0.5
    if n == 3:
        return s * (2.5 * s2 - 1.5)
    if n == 4:
        return (35.0 * s2 * s2 - 30.0 * s2 + 3.0) / 8.0
    raise ValueError(f"zonal degree {n} not implemented")


def zonal_potential(x, y, z, zonals):
    """U = mu/r [1 - sum_n J_n (R_E/r)^n P_n(z/r)] (Vallado Eq. 8-19, zonal terms), heyoka expression."""
    import heyoka as hy

    r = hy.sqrt(x * x + y * y + z * z)
    s = z / r
    q = R_EARTH / r
    pert, qn = 0.0, q
    for n, jn in enumerate(ZONALS[zonals], start=2):
        qn = qn * q
        pert = pert + jn * qn * legendre(n, s)
    return MU_EARTH / r * (1.0 - pert)


def drag_acceleration(pos, vel, b, rho_ref, h_ref, scale_height):
    """a = -1/2 B rho(h) |v_r| v_r, v_r = v - omega_E x r (Vallado Eq. 8-28), heyoka expressions."""
    import heyoka as hy

    x, y, z = pos
    vrx, vry, vrz = vel[0] + EARTH_ROTATION * y, vel[1] - EARTH_ROTATION * x, vel[2]
    r = hy.sqrt(x * x + y * y + z * z)
    rho = rho_ref * hy.exp((h_ref + R_EARTH - r) / scale_height)
    k = -0.5 * b * rho * hy.sqrt(vrx * vrx + vry * vry + vrz * vrz)
    return k * vrx, k * vry, k * vrz


def pair_equations(zonals=4):
    """The 12 first-order ODEs of chief and deputy (heyoka ``(var, rhs)`` pairs), parameters as in the module doc."""
    import heyoka as hy

    rho_ref, h_ref, big_h = hy.par[2], hy.par[3], hy.par[4]
    sys = []
    for k, tag in enumerate(("c", "d")):
        x, y, z, vx, vy, vz = hy.make_vars(*(f"{q}_{tag}" for q in ("x", "y", "z", "vx", "vy", "vz")))
        u = zonal_potential(x, y, z, zonals)
        dx, dy, dz = drag_acceleration((x, y, z), (vx, vy, vz), hy.par[k], rho_ref, h_ref, big_h)
        sys += [(x, vx), (y, vy), (z, vz),
                (vx, hy.diff(u, x) + dx), (vy, hy.diff(u, y) + dy), (vz, hy.diff(u, z) + dz)]
    return sys


DEFAULT_TOL = 1e-15
SEGMENT = 3600.0  # s, the simulator truth integrates in segments ending on this grid (NonlinearTruth._extend)
"""Taylor integrator tolerance (relative/absolute, heyoka's default is machine epsilon ~2.2e-16)."""


@functools.lru_cache(maxsize=None)
def pair_integrator(zonals=4, batch_size=None, tol=DEFAULT_TOL):
    """The compiled Taylor integrator for one pair (``batch_size`` None) or ``batch_size`` pairs (SIMD lanes).

    Cached per process; callers get a template and :func:`copy.deepcopy` it (no recompilation). Measured LLVM
    compile times on this machine: single pair in heyoka's compact mode ~1 s (it runs 1.4x slower per step, which
    does not matter for one pair); the batch integrator of the Monte Carlo in full (non-compact) mode ~2-5 s for
    degree 2 and ~10 s for degree 4 (3x the cost per step of degree 2, hence ``MC_ZONALS`` = 2).
    """
    import heyoka as hy

    sys = pair_equations(zonals)
    if batch_size is None:
        return hy.taylor_adaptive(sys, np.zeros(12), pars=np.zeros(5), tol=tol, compact_mode=True)
    return hy.taylor_adaptive_batch(sys, np.zeros((12, batch_size)), pars=np.zeros((5, batch_size)), tol=tol)


def simd_size():
    """Recommended heyoka batch size (SIMD width in doubles: 4 with AVX2)."""
    import heyoka as hy

    return int(hy.recommended_simd_size())


# ---------------------------------------------------------------- states, burns, relative quantities
def pair_state(chief_mean, deputy_mean):
    """Initial inertial state ``(..., 12)`` of two spacecraft from their *mean* elements (mean -> osculating, first
    order J2, then Cartesian)."""
    rc, vc = mean_to_cartesian(chief_mean)
    rd, vd = mean_to_cartesian(deputy_mean)
    return np.concatenate([rc, vc, rd, vd], axis=-1)


def apply_impulse(state, dv_rtn, deputy):
    """Add an impulse [m/s] given in the executing spacecraft's own RTN frame to its inertial velocity.

    dv_inertial = [R T N] dv_rtn with R = r/|r|, T = N x R, N = h/|h| (:func:`~roe_sep.core.od.radar.rtn_matrix`).
    Vectorized over ``state`` ``(..., 12)``, ``dv_rtn`` ``(..., 3)`` and the boolean ``deputy`` ``(...)``.
    """
    s = np.array(state, dtype=float, copy=True)
    dv = np.asarray(dv_rtn, dtype=float)
    deputy = np.asarray(deputy, dtype=bool)
    for off, mine in ((0, ~deputy), (6, deputy)):
        rot = rtn_matrix(s[..., off:off + 3], s[..., off + 3:off + 6])
        dvi = np.einsum("...ij,...j->...i", rot, dv)
        s[..., off + 3:off + 6] += np.where(mine[..., None], dvi, 0.0)
    return s


def mean_elements(state):
    """Mean Keplerian elements ``(..., 2, 6)`` (chief, deputy) of pair states (osculating -> mean, first order J2)."""
    s = np.asarray(state, dtype=float)
    pos = np.stack([s[..., 0:3], s[..., 6:9]], axis=-2)
    vel = np.stack([s[..., 3:6], s[..., 9:12]], axis=-2)
    return cartesian_to_mean(pos, vel)


def mean_roe(state):
    """Dimensionless mean ROE ``(..., 6)`` of the deputy w.r.t. the chief from pair states: each spacecraft is
    converted to mean elements separately, then seed 002 Eq. (1) (:func:`~roe_sep.core.relmotion.roe.kepler_to_roe`)."""
    kep = mean_elements(state)
    return kepler_to_roe(kep[..., 0, :], kep[..., 1, :])


def relative_rtn(state):
    """Deputy position [m] and velocity [m/s] relative to the chief in the chief's rotating RTN frame.

    r_rel = M^T (r_d - r_c),  v_rel = M^T (v_d - v_c) - omega x r_rel,  omega = (0, 0, |h_c| / |r_c|^2) in RTN.
    """
    s = np.asarray(state, dtype=float)
    rc, vc = s[..., 0:3], s[..., 3:6]
    rot = rtn_matrix(rc, vc)
    dr = np.einsum("...ji,...j->...i", rot, s[..., 6:9] - rc)
    dv = np.einsum("...ji,...j->...i", rot, s[..., 9:12] - vc)
    w = np.linalg.norm(np.cross(rc, vc), axis=-1) / np.sum(rc * rc, axis=-1)
    return dr, dv - np.stack([-w * dr[..., 1], w * dr[..., 0], np.zeros_like(w)], axis=-1)


# ---------------------------------------------------------------- single pair
def _pars(b_chief, b_deputy, atmosphere: Atmosphere):
    return np.array([b_chief, b_deputy, *atmosphere.pars()], dtype=float)


def propagate_pair(state0, t0, times, maneuvers, b_chief, b_deputy, atmosphere: Atmosphere, zonals=4,
                   tol=DEFAULT_TOL):
    """Integrate one pair from ``state0`` at ``t0`` and return the states ``(len(times), 12)`` at ``times``.

    ``maneuvers`` (:class:`Maneuver`, epochs >= t0) are applied at their epochs; a sample exactly at a burn epoch
    sees the post-burn state (as :func:`roe_sep.core.relmotion.trajectory.trajectory`).
    """
    times = np.asarray(times, dtype=float)
    if np.any(times < t0):
        raise ValueError("propagation times must not precede t0")
    ta = copy.deepcopy(pair_integrator(zonals, None, tol))
    ta.time = float(t0)
    ta.state[:] = np.asarray(state0, dtype=float)
    ta.pars[:] = _pars(b_chief, b_deputy, atmosphere)
    out = np.empty(times.shape + (12,))
    order = np.argsort(times, kind="stable")
    burns = sorted((m for m in maneuvers if m.epoch >= t0), key=lambda m: m.epoch)
    edges = [m.epoch for m in burns] + [np.inf]
    k0 = 0
    for k, hi in enumerate(edges):
        idx = order[k0:][times[order[k0:]] < hi]
        if idx.size:
            out[idx] = _grid(ta, times[idx])
            k0 += idx.size
        if k < len(burns):
            _until(ta, burns[k].epoch)
            ta.state[:] = apply_impulse(ta.state, burns[k].dv_rtn, burns[k].deputy)
    return out


def _until(ta, t):
    if t > ta.time:
        res = ta.propagate_until(float(t))
        _check(res[0])


def _grid(ta, times):
    """States at sorted ``times`` >= ta.time, leaving the integrator at the last one."""
    _until(ta, times[0])
    res = ta.propagate_grid(np.asarray(times, dtype=float))
    _check(res[0])
    return np.asarray(res[-1]).copy()


def _check(outcome):
    import heyoka as hy

    if outcome not in (hy.taylor_outcome.time_limit, hy.taylor_outcome.success):
        raise RuntimeError(f"nonlinear propagation failed: {outcome}")


# ---------------------------------------------------------------- many pairs (Monte Carlo, sweeps)
def _batch_worker(template, states, pars, t0, grid, out, lo, hi):
    """Propagate lanes ``lo:hi`` of ``states`` ``(12, N)`` from t0, ``batch_size`` lanes at a time (one integrator
    per worker thread; heyoka releases the GIL while it integrates). ``grid`` is the end time (float: ``states`` is
    overwritten with the final states) or sorted output times ``(n_t,)`` (states at those times go to ``out``
    ``(n_t, 12, N)``)."""
    ta = copy.deepcopy(template)
    bs = ta.batch_size
    for j in range(lo, hi, bs):
        ta.set_time(float(t0))
        ta.state[:] = states[:, j:j + bs]
        ta.pars[:] = pars[:, j:j + bs]
        if out is None:
            ta.propagate_until(float(grid))
        else:
            ta.propagate_until(float(grid[0]))
            out[:, :, j:j + bs] = ta.propagate_grid(np.repeat(grid[:, None], bs, axis=1))[1]
        if not all(o[0].name in ("time_limit", "success") for o in ta.propagate_res):
            raise RuntimeError(f"nonlinear propagation failed in lanes {j}..{j + bs}: {ta.propagate_res}")
        states[:, j:j + bs] = ta.state


def _run_lanes(states0, t0, grid, b_chief, b_deputy, atmosphere, zonals, tol, workers):
    """The lane layout shared by :func:`propagate_pairs` and :func:`propagate_pairs_grid`: states and parameters
    ``(12 | 5, N)`` padded to a multiple of the batch size, blocks of lanes over a thread pool of ``workers``
    (default: the cores available). Returns ``(final states (12, N_pad), grid output (n_t, 12, N_pad) or None)``."""
    s0 = np.asarray(states0, dtype=float)
    n = s0.shape[0]
    template = pair_integrator(zonals, simd_size(), tol)
    bs = template.batch_size
    npad = -(-n // bs) * bs
    states = np.empty((12, npad))
    states[:, :n] = s0.T
    states[:, n:] = s0[-1:].T
    pars = np.empty((5, npad))
    pars[0, :n] = np.broadcast_to(np.asarray(b_chief, dtype=float), (n,))
    pars[1, :n] = np.broadcast_to(np.asarray(b_deputy, dtype=float), (n,))
    pars[:2, n:] = pars[:2, n - 1:n]
    pars[2:] = np.asarray(atmosphere.pars())[:, None]
    out = None if np.ndim(grid) == 0 else np.empty((len(grid), 12, npad))
    workers = workers or len(os.sched_getaffinity(0))
    blocks = np.linspace(0, npad // bs, workers + 1).astype(int) * bs
    with ThreadPoolExecutor(max_workers=workers) as pool:
        futures = [pool.submit(_batch_worker, template, states, pars, t0, grid, out, lo, hi)
                   for lo, hi in zip(blocks[:-1], blocks[1:]) if hi > lo]
        for f in futures:
            f.result()
    return states, out


def propagate_pairs(states0, t0, t1, b_chief, b_deputy, atmosphere: Atmosphere, zonals=4, tol=DEFAULT_TOL,
                    workers=None):
    """Propagate N pairs ``(N, 12)`` from ``t0`` to ``t1`` [s]: heyoka batch mode (``simd_size`` pairs per
    integrator call, each lane with its own adaptive steps) over a thread pool of ``workers`` (default: the
    cores available), the sample axis padded to a multiple of the batch size. ``b_chief``/``b_deputy`` broadcast
    to ``(N,)``. Returns ``(N, 12)``."""
    n = np.shape(states0)[0]
    states, _ = _run_lanes(states0, t0, float(t1), b_chief, b_deputy, atmosphere, zonals, tol, workers)
    return states[:, :n].T.copy()


def propagate_pairs_grid(states0, t0, times, b_chief, b_deputy, atmosphere: Atmosphere, zonals=4, tol=DEFAULT_TOL,
                         workers=None):
    """As :func:`propagate_pairs`, but the states of every pair at the sorted ``times`` >= ``t0`` [s] (heyoka's
    dense output, exact to the integrator tolerance between steps). Returns ``(N, len(times), 12)``."""
    times = np.asarray(times, dtype=float)
    if times.ndim != 1 or times.size == 0 or times[0] < t0 or np.any(np.diff(times) < 0.0):
        raise ValueError("times must be a non-empty sorted 1-D array starting at or after t0")
    n = np.shape(states0)[0]
    _, out = _run_lanes(states0, t0, times, b_chief, b_deputy, atmosphere, zonals, tol, workers)
    return np.moveaxis(out[:, :, :n], -1, 0).copy()


# ---------------------------------------------------------------- numpy reference (cross-check and benchmark)
def zonal_acceleration(pos, zonals=2):
    """Closed-form zonal accelerations [m/s^2] (Vallado Eq. 8-30 style expansions of grad U), numpy, ``(..., 3)``.

    J2: -3/2 J2 mu R^2/r^4 [x/r (1 - 5 s^2), y/r (1 - 5 s^2), z/r (3 - 5 s^2)]
    J3: -5/2 J3 mu R^3/r^5 [x/r (3 s - 7 s^3), y/r (3 s - 7 s^3), 6 s^2 - 7 s^4 - 3/5]
    J4: 15/8 J4 mu R^4/r^6 [x/r (1 - 14 s^2 + 21 s^4), y/r (...), z/r (5 - 70/3 s^2 + 21 s^4)],  s = z/r.
    Independent of the symbolic gradient used by the integrator (the tests compare the two).
    """
    p = np.asarray(pos, dtype=float)
    r = np.linalg.norm(p, axis=-1)
    xr, yr, s = p[..., 0] / r, p[..., 1] / r, p[..., 2] / r
    s2 = s * s
    k = -1.5 * J2 * MU_EARTH * R_EARTH**2 / r**4
    acc = np.stack([k * xr * (1 - 5 * s2), k * yr * (1 - 5 * s2), k * s * (3 - 5 * s2)], axis=-1)
    if zonals >= 3:
        k = -2.5 * J3 * MU_EARTH * R_EARTH**3 / r**5
        acc = acc + np.stack([k * xr * (3 * s - 7 * s * s2), k * yr * (3 * s - 7 * s * s2),
                              k * (6 * s2 - 7 * s2 * s2 - 0.6)], axis=-1)
    if zonals >= 4:
        k = 15.0 / 8.0 * J4 * MU_EARTH * R_EARTH**4 / r**6
        f = 1 - 14 * s2 + 21 * s2 * s2
        acc = acc + np.stack([k * xr * f, k * yr * f, k * s * (5 - 70.0 / 3.0 * s2 + 21 * s2 * s2)], axis=-1)
    return acc - (MU_EARTH / r**3)[..., None] * p


def pair_rhs(t, y, pars, zonals=2):
    """d/dt of pair states ``(12,)`` or ``(12, N)`` with the same force model as :func:`pair_equations`, numpy
    (for ``scipy.integrate.solve_ivp``). ``pars`` = ``[B_chief, B_deputy, rho_ref, h_ref, H]``."""
    y = np.asarray(y, dtype=float)
    out = np.empty_like(y)
    rho_ref, h_ref, big_h = pars[2], pars[3], pars[4]
    for k, off in enumerate((0, 6)):
        pos, vel = y[off:off + 3], y[off + 3:off + 6]
        r = np.sqrt(np.sum(pos * pos, axis=0))
        vr = np.stack([vel[0] + EARTH_ROTATION * pos[1], vel[1] - EARTH_ROTATION * pos[0], vel[2]])
        rho = rho_ref * np.exp((h_ref + R_EARTH - r) / big_h)
        drag = -0.5 * pars[k] * rho * np.sqrt(np.sum(vr * vr, axis=0)) * vr
        out[off:off + 3] = vel
        out[off + 3:off + 6] = np.moveaxis(zonal_acceleration(np.moveaxis(pos, 0, -1), zonals), -1, 0) + drag
    return out


# ---------------------------------------------------------------- the simulator's nonlinear truth
class NonlinearTruth:
    """Drop-in for :class:`roe_sep.core.truth.secular.TruthModel` with the numerical pair as truth (the ``sim`` node's
    ``dynamics: nonlinear``).

    Both spacecraft start on the chief's state (``chief0`` mean elements at ``t0``, mean -> osculating); before the
    ejection the picosatellite rides in the carrier (same B, identical states, ROE exactly zero). Burns are inertial
    velocity changes in the executing spacecraft's RTN frame (:func:`apply_impulse`). ROE are the *mean* ROE of
    the numerical states (:func:`mean_roe`), RTN the true relative state (:func:`relative_rtn`). Queries must not
    go back before the earliest time of the previous query (dense output of the steps since then is kept).
    ``da_dot`` is the secular model's value, reported in diagnostics only.
    """

    def __init__(self, chief0, t0, b_chief, b_deputy, atmosphere: Atmosphere, zonals=4, da_dot=0.0):
        self.chief0 = np.asarray(chief0, dtype=float)
        self.t0 = float(t0)
        self.da_dot = float(da_dot)
        self.b_deputy = float(b_deputy)
        self.separated = False
        self._ta = copy.deepcopy(pair_integrator(zonals, None, DEFAULT_TOL))
        self._ta.time = self.t0
        self._ta.state[:] = pair_state(self.chief0, self.chief0)
        self._ta.pars[:] = _pars(b_chief, b_chief, atmosphere)
        self._segments = []  # (t_from, t_to, heyoka continuous output)

    @property
    def a(self):
        return float(self.chief0[0])

    @property
    def inc(self):
        return float(self.chief0[2])

    def _extend(self, t):
        """Integrate up to (at least) ``t`` in segments that end on the fixed grid of ``SEGMENT`` seconds from
        ``t0``: the integrator's steps, hence the truth to the last bit, depend on the burns alone, never on how the
        queries are spaced (the lockstep step size, the pacing)."""
        t = float(t)
        while t > self._ta.time:
            t_from = self._ta.time
            t_to = self.t0 + (math.floor((t_from - self.t0) / SEGMENT + 1e-9) + 1) * SEGMENT
            res = self._ta.propagate_until(t_to, c_output=True)
            _check(res[0])
            self._segments.append((t_from, t_to, res[4]))

    def states(self, times):
        """Pair states ``(..., 12)`` at ``times`` [s] (scalar or array, each >= the previous query's earliest)."""
        t = np.asarray(times, dtype=float)
        flat = t.reshape(-1)
        self._extend(flat.max())
        self._segments = [s for s in self._segments if s[1] >= flat.min()]
        out = np.empty((flat.size, 12))
        done = np.zeros(flat.size, bool)
        for lo, hi, co in self._segments:
            sel = ~done & (flat >= lo) & (flat <= hi)
            if np.any(sel):
                out[sel] = np.asarray(co(flat[sel])).reshape(-1, 12)
                done |= sel
        at_now = ~done & (flat == self._ta.time)
        out[at_now] = self._ta.state
        done |= at_now
        if not np.all(done):
            raise ValueError(f"nonlinear truth queried before its dense output: t = {flat[~done].min():.3f} s")
        return out.reshape(t.shape + (12,))

    def chief_elements(self, t):
        """The carrier's mean Keplerian elements at ``t``."""
        return mean_elements(self.states(t))[..., 0, :]

    def u_at(self, t):
        """The carrier's mean argument of latitude [rad, 0..2pi) at ``t``."""
        k = self.chief_elements(t)
        return np.mod(k[..., 4] + k[..., 5], 2.0 * np.pi)

    def roe_at(self, t):
        """Dimensionless mean ROE at ``t``."""
        return mean_roe(self.states(t))

    def rtn_at(self, t):
        """True relative position [m] and velocity [m/s] in the carrier's RTN frame at ``t``."""
        return relative_rtn(self.states(t))

    def samples(self, t):
        """Carrier mean elements, mean ROE and the true RTN state at the times ``t`` (an array), in one pass."""
        st = self.states(np.asarray(t, dtype=float))
        mean = mean_elements(st)
        return mean[..., 0, :], kepler_to_roe(mean[..., 0, :], mean[..., 1, :]), relative_rtn(st)

    def distances(self, t_from, t_to, step):
        """Times and |r| [m] over ``[t_from, t_to]`` every ``step`` seconds (and at both ends)."""
        times = np.append(np.arange(t_from, t_to, step), t_to)
        return times, np.linalg.norm(self.rtn_at(times)[0], axis=-1)

    def apply(self, t, dv_rel, spacecraft="picosatellite"):
        """Execute a burn at ``t``: ``dv_rel`` is the relative impulse of the seed convention (the picosatellite's
        own dv; minus the carrier's own dv), ``spacecraft`` who burns, in its own RTN frame."""
        if spacecraft not in ("picosatellite", "carrier"):
            raise ValueError(f"unknown spacecraft {spacecraft!r}")
        deputy = spacecraft == "picosatellite"
        t = float(t)
        state = self.states(t)  # from the grid segment holding t (the integrator may have gone past it)
        dv = np.asarray(dv_rel, dtype=float) * (1.0 if deputy else -1.0)
        self._ta.time = t
        self._ta.state[:] = apply_impulse(state, dv, deputy)
        if deputy and not self.separated:
            self._ta.pars[1] = self.b_deputy
        self.separated = True
        self._segments = []
