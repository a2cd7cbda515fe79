"""Mean <-> osculating Keplerian elements (first-order J2, Brouwer-Lyddane) and Keplerian <-> Cartesian states.

The ROE model of :mod:`roe_sep.core.relmotion.dynamics` lives in *mean* elements; a numerically integrated spacecraft
has *osculating* ones. The conversion is Brouwer's first-order J2 theory in Lyddane's form as tabulated by Schaub &
Junkins, *Analytical Mechanics of Space Systems* (AIAA, 2003), Appendix F, Eqs. (F.1)-(F.22): one mapping whose
sign of gamma_2 = +-(J2/2)(R_E/a)^2 selects mean -> osculating (+) or osculating -> mean (-, first order: the same
formulas evaluated at the osculating elements). It contains the short-period terms and Brouwer's long-period
terms; the Lyddane form (e dM, d1..d4) keeps it regular at e -> 0, which a near-circular formation needs.

The pitfall (why this module exists): ROE formed directly from osculating elements carry the differential J2
short-period terms. For two spacecraft dl apart in the same orbit, a_osc - a_mean = (3/2) J2 R_E^2 / a sin^2 i
cos 2u (Eq. F.7 at e = 0) differs between them by about 3 J2 (R_E/a)^2 a sin^2 i dl sin 2u: about 55 m of a*da at
a dl = 10 km, 515 km altitude, sun-synchronous, twice per orbit. Read as a *mean* a*da it is a spurious drift of
3 pi 55 m ~ 0.5 km per orbit. Only mean-to-mean differences are comparable with the ROE model; the conversion
must be applied to each spacecraft separately (never to the difference), with the same theory for both.

Element arrays are ``(..., 6)`` ``[a, e, i, raan, argp, M]`` (m, 1, rad); all functions are vectorized.
"""

import numpy as np
from numpy.typing import ArrayLike

from ..constants import J2, MU_EARTH, R_EARTH


def solve_kepler(m: ArrayLike, e: ArrayLike, iterations: int = 8) -> np.ndarray:
    """Eccentric anomaly E from Kepler's equation M = E - e sin E (Newton, start E = M; quadratic convergence,
    8 iterations exhaust double precision for e < 0.1).

    Parameters
    ----------
    m : array_like
        Mean anomaly [rad].
    e : array_like
        Eccentricity, broadcast with ``m``.
    iterations : int
        Newton steps.

    Returns
    -------
    numpy.ndarray
        E [rad], the broadcast shape.
    """
    m, e = np.asarray(m, dtype=float), np.asarray(e, dtype=float)
    big_e = m + 0.0 * e
    for _ in range(iterations):
        big_e = big_e - (big_e - e * np.sin(big_e) - m) / (1.0 - e * np.cos(big_e))
    return big_e


def true_from_mean(m: ArrayLike, e: ArrayLike) -> np.ndarray:
    """True anomaly f from mean anomaly M: tan(f/2) = sqrt((1+e)/(1-e)) tan(E/2) (Vallado Alg. 2 / Eq. 2-14)."""
    big_e = solve_kepler(m, e)
    return 2.0 * np.arctan2(np.sqrt(1.0 + e) * np.sin(big_e / 2.0), np.sqrt(1.0 - e) * np.cos(big_e / 2.0))


def mean_from_true(f: ArrayLike, e: ArrayLike) -> np.ndarray:
    """Mean anomaly M from true anomaly f: E = 2 atan(sqrt((1-e)/(1+e)) tan(f/2)), M = E - e sin E."""
    f, e = np.asarray(f, dtype=float), np.asarray(e, dtype=float)
    big_e = 2.0 * np.arctan2(np.sqrt(1.0 - e) * np.sin(f / 2.0), np.sqrt(1.0 + e) * np.cos(f / 2.0))
    return big_e - e * np.sin(big_e)


def kepler_to_cartesian(kep: ArrayLike, mu: float = MU_EARTH) -> tuple[np.ndarray, np.ndarray]:
    """Inertial position [m] and velocity [m/s] from osculating ``[a, e, i, raan, argp, M]`` (Vallado Alg. 10).

    r = p / (1 + e cos f) (cos u P + sin u Q),  v = sqrt(mu/p) (-(sin u + e sin argp) P + (cos u + e cos argp) Q),
    with u = argp + f, P = (cos raan, sin raan, 0) and Q = (-cos i sin raan, cos i cos raan, sin i) the node and
    in-plane normal-to-node directions. Returns two ``(..., 3)`` arrays.
    """
    k = np.asarray(kep, dtype=float)
    a, e, inc, raan, argp, m = np.moveaxis(k, -1, 0)
    f = true_from_mean(m, e)
    p = a * (1.0 - e * e)
    u = argp + f
    r = p / (1.0 + e * np.cos(f))
    co, so, ci, si = np.cos(raan), np.sin(raan), np.cos(inc), np.sin(inc)
    big_p = np.stack([co, so, np.zeros_like(co)], axis=-1)
    big_q = np.stack([-ci * so, ci * co, si], axis=-1)
    cu, su = np.cos(u), np.sin(u)
    pos = r[..., None] * (cu[..., None] * big_p + su[..., None] * big_q)
    sq = np.sqrt(mu / p)
    vp = -sq * (su + e * np.sin(argp))
    vq = sq * (cu + e * np.cos(argp))
    return pos, vp[..., None] * big_p + vq[..., None] * big_q


def cartesian_to_kepler(pos: ArrayLike, vel: ArrayLike, mu: float = MU_EARTH) -> np.ndarray:
    """Osculating ``[a, e, i, raan, argp, M]`` from inertial position/velocity (Vallado Alg. 9, nodal-frame form).

    h = r x v, i = acos(h_z/|h|), raan = atan2(h_x, -h_y); e_vec = ((v^2 - mu/r) r - (r.v) v)/mu; a from the vis-viva
    energy. The argument of latitude u and the components of e_vec along the node (e cos argp) and normal to it in
    the plane (e sin argp) are computed directly, so a circular orbit gives argp = 0, M = u without a singularity.

    Parameters
    ----------
    pos : array_like, shape (..., 3)
        Inertial position [m].
    vel : array_like, shape (..., 3)
        Inertial velocity [m/s].
    mu : float
        Gravitational parameter [m^3/s^2].

    Returns
    -------
    numpy.ndarray, shape (..., 6)
        ``[a, e, i, raan, argp, M]`` (m, 1, rad, rad, rad, rad), raan and argp in [0, 2 pi).
    """
    r = np.asarray(pos, dtype=float)
    v = np.asarray(vel, dtype=float)
    h = np.cross(r, v)
    hn = np.linalg.norm(h, axis=-1)
    rn = np.linalg.norm(r, axis=-1)
    inc = np.arccos(np.clip(h[..., 2] / hn, -1.0, 1.0))
    raan = np.arctan2(h[..., 0], -h[..., 1])
    node = np.stack([np.cos(raan), np.sin(raan), np.zeros_like(raan)], axis=-1)
    normal = np.cross(h / hn[..., None], node)
    ev = ((np.sum(v * v, axis=-1) - mu / rn)[..., None] * r - np.sum(r * v, axis=-1)[..., None] * v) / mu
    ex, ey = np.sum(ev * node, axis=-1), np.sum(ev * normal, axis=-1)
    e = np.hypot(ex, ey)
    argp = np.arctan2(ey, ex)
    u = np.arctan2(np.sum(r * normal, axis=-1), np.sum(r * node, axis=-1))
    a = 1.0 / (2.0 / rn - np.sum(v * v, axis=-1) / mu)
    two_pi = 2.0 * np.pi
    return np.stack([a, e, inc, np.mod(raan, two_pi), np.mod(argp, two_pi),
                     np.mod(mean_from_true(u - argp, e), two_pi)], axis=-1)


def j2_gamma(a: ArrayLike, sign: float) -> np.ndarray:
    """gamma_2 = sign (J2/2) (R_E/a)^2, Schaub & Junkins Eq. (F.1)/(F.2): sign +1 mean -> osculating, -1 back."""
    return sign * 0.5 * J2 * (R_EARTH / np.asarray(a, dtype=float)) ** 2


def brouwer_lyddane(kep: ArrayLike, sign: float) -> np.ndarray:
    """Schaub & Junkins Appendix F, Eqs. (F.3)-(F.22): the first-order J2 map of ``[a, e, i, raan, argp, M]``.

    ``sign`` = +1: mean -> osculating; -1: osculating -> mean. Singular only at the critical inclination
    (1 - 5 cos^2 i = 0, Brouwer's long-period terms) and at i = 0; regular at e = 0.
    """
    k = np.asarray(kep, dtype=float)
    a, e, inc, raan, argp, m = np.moveaxis(k, -1, 0)
    g2 = j2_gamma(a, sign)
    eta = np.sqrt(1.0 - e * e)
    eta2, eta3 = eta * eta, eta**3
    eta4, eta6 = eta2 * eta2, eta2**3
    g2p = g2 / eta4  # (F.3)
    f = true_from_mean(m, e)  # (F.4)-(F.5)
    aor = (1.0 + e * np.cos(f)) / eta2  # (F.6)
    c = np.cos(inc)
    c2 = c * c
    c4, c6 = c2 * c2, c2**3
    s2 = 1.0 - c2
    k5 = 1.0 - 5.0 * c2
    cf, sf = np.cos(f), np.sin(f)
    w2 = 2.0 * argp
    cos_w2f, sin_w2f = np.cos(w2 + f), np.sin(w2 + f)
    cos_w22f, sin_w22f = np.cos(w2 + 2.0 * f), np.sin(w2 + 2.0 * f)
    cos_w23f, sin_w23f = np.cos(w2 + 3.0 * f), np.sin(w2 + 3.0 * f)
    long_period = 1.0 - 11.0 * c2 - 40.0 * c4 / k5
    eq_center = f - m + e * sf  # f - M + e sin f

    a_new = a + a * g2 * ((3.0 * c2 - 1.0) * (aor**3 - 1.0 / eta3) + 3.0 * s2 * aor**3 * cos_w22f)  # (F.7)
    de1 = g2p / 8.0 * e * eta2 * long_period * np.cos(w2)  # (F.8)
    de = de1 + eta2 / 2.0 * (  # (F.9)
        g2 * ((3.0 * c2 - 1.0) / eta6 * (e * eta + e / (1.0 + eta) + 3.0 * cf + 3.0 * e * cf**2 + e * e * cf**3)
              + 3.0 * s2 / eta6 * (e + 3.0 * cf + 3.0 * e * cf**2 + e * e * cf**3) * cos_w22f)
        - g2p * s2 * (3.0 * cos_w2f + cos_w23f))
    di = (-e * de1 / (eta2 * np.tan(inc))  # (F.10)
          + g2p / 2.0 * c * np.sqrt(s2) * (3.0 * cos_w22f + 3.0 * e * cos_w2f + e * cos_w23f))
    short_raan = 6.0 * eq_center - 3.0 * sin_w22f - 3.0 * e * sin_w2f - e * sin_w23f
    lpo = (m + argp + raan + g2p / 8.0 * eta3 * long_period  # (F.11): M' + argp' + raan'
           - g2p / 16.0 * (2.0 + e * e - 11.0 * (2.0 + 3.0 * e * e) * c2 - 40.0 * (2.0 + 5.0 * e * e) * c4 / k5
                           - 400.0 * e * e * c6 / k5**2)
           + g2p / 4.0 * (-6.0 * k5 * eq_center + (3.0 - 5.0 * c2) * (3.0 * sin_w22f + 3.0 * e * sin_w2f
                                                                     + e * sin_w23f))
           - g2p / 8.0 * e * e * c * (11.0 + 80.0 * c2 / k5 + 200.0 * c4 / k5**2)
           - g2p / 2.0 * c * short_raan)
    aeor2 = (aor * eta) ** 2
    e_dm = (g2p / 8.0 * e * eta3 * long_period  # (F.12)
            - g2p / 4.0 * eta3 * (2.0 * (3.0 * c2 - 1.0) * (aeor2 + aor + 1.0) * sf
                                  + 3.0 * s2 * ((-aeor2 - aor + 1.0) * sin_w2f + (aeor2 + aor + 1.0 / 3.0) * sin_w23f)))
    draan = (-g2p / 8.0 * e * e * c * (11.0 + 80.0 * c2 / k5 + 200.0 * c4 / k5**2)  # (F.13)
             - g2p / 2.0 * c * short_raan)
    d1 = (e + de) * np.sin(m) + e_dm * np.cos(m)  # (F.14)
    d2 = (e + de) * np.cos(m) - e_dm * np.sin(m)  # (F.15)
    m_new = np.arctan2(d1, d2)  # (F.16)
    e_new = np.hypot(d1, d2)  # (F.17)
    sh, ch = np.sin(inc / 2.0), np.cos(inc / 2.0)
    d3 = (sh + ch * di / 2.0) * np.sin(raan) + sh * draan * np.cos(raan)  # (F.18)
    d4 = (sh + ch * di / 2.0) * np.cos(raan) - sh * draan * np.sin(raan)  # (F.19)
    raan_new = np.arctan2(d3, d4)  # (F.20)
    inc_new = 2.0 * np.arcsin(np.clip(np.hypot(d3, d4), 0.0, 1.0))  # (F.21)
    argp_new = lpo - m_new - raan_new  # (F.22)
    two_pi = 2.0 * np.pi
    return np.stack([a_new, e_new, inc_new, np.mod(raan_new, two_pi), np.mod(argp_new, two_pi),
                     np.mod(m_new, two_pi)], axis=-1)


def mean_to_osculating(kep_mean: ArrayLike) -> np.ndarray:
    """Osculating elements of mean ``[a, e, i, raan, argp, M]``: :func:`brouwer_lyddane` with gamma_2 > 0."""
    return brouwer_lyddane(kep_mean, +1.0)


def osculating_to_mean(kep_osc: ArrayLike) -> np.ndarray:
    """Mean elements of osculating ``[a, e, i, raan, argp, M]``: :func:`brouwer_lyddane` with gamma_2 < 0 (first
    order; the residual is O(J2^2), a few meters in a, common to two close spacecraft)."""
    return brouwer_lyddane(kep_osc, -1.0)


def mean_to_cartesian(kep_mean: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Inertial position/velocity of mean elements: :func:`mean_to_osculating` then :func:`kepler_to_cartesian`."""
    return kepler_to_cartesian(mean_to_osculating(kep_mean))


def cartesian_to_mean(pos: ArrayLike, vel: ArrayLike) -> np.ndarray:
    """Mean elements of an inertial state: :func:`cartesian_to_kepler` then :func:`osculating_to_mean`."""
    return osculating_to_mean(cartesian_to_kepler(pos, vel))
