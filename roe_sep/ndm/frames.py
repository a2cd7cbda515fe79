"""Frames and time scales of the exported navigation data: sim time -> UTC, the simulator's inertial frame (GCRF)
-> EME2000, carrier RTN <-> inertial states, Delta-v and covariances.

The simulator and the radar model (:mod:`roe_sep.core.od.radar`) work in the GCRF, with the Earth oriented by
:mod:`roe_sep.core.frames` (the one Earth-orientation model: ERFA's IAU 2000B, IERS EOP). CCSDS messages
state EME2000 (mean equator and equinox of J2000.0), which is the GCRF rotated by the constant frame bias
(:func:`roe_sep.core.frames.gcrf_to_eme2000`, 23 mas, 0.8 m at the carrier's radius).

Time: sim time t [s] counts SI seconds from the scenario's calendar epoch ``epoch_utc`` (UTC); the epoch of a
sample is epoch_utc + t. The runs span days, and no leap second is inserted inside one (the next after 2016-07-01
is 2016-12-31 23:59:60), so the UTC label is exact for the default scenario.

The carrier's state is its mean near-circular orbit used as osculating (radar.chief_position_velocity, the model
the radar and the OD share), with the velocity the time derivative of those positions: the mean elements advance at
the J2 secular rates (du/dt, d raan/dt of :mod:`roe_sep.core.relmotion.dynamics`), so

    v = (du/dt / n) v_circ + (d raan/dt) z x r     (v_circ = sqrt(mu / a) times the unit along-track vector).

The picosatellite is carrier + relative state, with the rotating-frame kinematics

    r_d = r_c + M rho,   v_d = v_c + M (rho_dot + omega x rho),   omega = (0, 0, |r_c x v_c| / |r_c|^2) in RTN,

M = [R T N] the RTN -> inertial rotation (radar.rtn_matrix) and rho, rho_dot the relative position and velocity
measured in the rotating RTN frame (the linear ROE map, seed 002 Eq. 2's basis).
"""

from datetime import datetime, timedelta, timezone

import numpy as np

from ..core.frames import gcrf_to_eme2000
from ..core.od.radar import chief_from_kepler, chief_position_velocity, rtn_matrix
from ..core.relmotion.dynamics import arg_latitude_rate, raan_rate
from ..core.relmotion.orbit import mean_motion
from ..core.relmotion.roe import roe_to_rtn

INERTIAL_FRAME = "EME2000"
"""REF_FRAME of every exported state (CCSDS 502.0-B-2 Annex A spelling)."""
LOCAL_FRAME = "RTN"
"""MAN_REF_FRAME / COV_REF_FRAME of the local orbital frame: radial, transverse (along-track), normal."""
TIME_SYSTEM = "UTC"
CENTER = "EARTH"


def parse_epoch(epoch_utc) -> datetime:
    """Timezone-aware UTC :class:`datetime` of an ISO-8601 string or datetime (a naive one is taken as UTC)."""
    if isinstance(epoch_utc, datetime):
        dt = epoch_utc
    else:
        text = str(epoch_utc).strip()
        if text.endswith(("Z", "z")):
            text = text[:-1] + "+00:00"
        try:
            dt = datetime.fromisoformat(text)
        except ValueError as exc:
            raise ValueError(f"epoch_utc must be an ISO-8601 UTC date-time, got {epoch_utc!r}") from exc
    if dt.tzinfo is None:
        dt = dt.replace(tzinfo=timezone.utc)
    return dt.astimezone(timezone.utc)


def utc_string(epoch_utc, t) -> str:
    """CCSDS epoch string ``YYYY-MM-DDThh:mm:ss.ffffff`` (UTC, ISO-8601 with the 'T') of sim time ``t`` [s]."""
    dt = parse_epoch(epoch_utc) + timedelta(seconds=float(t))
    return dt.strftime("%Y-%m-%dT%H:%M:%S.%f")


def sim_time(epoch_utc, ccsds_epoch) -> float:
    """Sim time [s] of a CCSDS UTC epoch string (``YYYY-MM-DDThh:mm:ss[.f]``, optional ``Z``; or ``YYYY-DDDThh..``
    day-of-year form). ValueError names the value."""
    text = str(ccsds_epoch).strip().rstrip("Zz")
    try:
        if len(text) >= 8 and text[4] == "-" and text[8:9] == "T" and text[5:8].isdigit():  # YYYY-DDDThh:mm:ss
            date = datetime.strptime(text[:8], "%Y-%j")
            rest = datetime.strptime(text[9:].split(".")[0], "%H:%M:%S")
            frac = float("0." + text.split(".")[1]) if "." in text[9:] else 0.0
            dt = date.replace(hour=rest.hour, minute=rest.minute, second=rest.second)
            dt = dt.replace(tzinfo=timezone.utc) + timedelta(seconds=frac)
        else:
            dt = parse_epoch(text)
    except ValueError as exc:
        raise ValueError(f"epoch {ccsds_epoch!r} is not a CCSDS UTC epoch (YYYY-MM-DDThh:mm:ss.ffffff)") from exc
    return (dt - parse_epoch(epoch_utc)).total_seconds()


def _apply(m, v):
    return np.einsum("...ij,...j->...i", m, v)


def _chief_gcrf(chief_kep):
    """GCRF position [m], the model's circular velocity [m/s] (its RTN frame) and the velocity consistent with the
    positions (module docstring), and the frame's rotation rates du/dt, d raan/dt [rad/s] of the mean elements."""
    a, inc, raan, u = chief_from_kepler(chief_kep)
    r, v = chief_position_velocity(a, inc, raan, u)
    u_dot, raan_dot = arg_latitude_rate(a, inc), raan_rate(a, inc)
    v_true = (u_dot / mean_motion(a))[..., None] * v + _z_cross(raan_dot, r)
    return r, v, v_true, u_dot, raan_dot


def _z_cross(w, r):
    """(w z) x r of ``(..., 3)`` vectors, z the GCRF pole."""
    w = np.asarray(w, dtype=float)
    return np.stack([-w * r[..., 1], w * r[..., 0], np.zeros_like(w * r[..., 0])], axis=-1)


def chief_state(chief_kep, epoch_utc, t):
    """Carrier position [m] and velocity [m/s] in EME2000 from its mean Keplerian elements ``[a, e, i, raan, argp,
    M]`` (GCRF) at sim time ``t``: radar.chief_position_velocity with the secular-rate velocity of the module
    docstring, then the frame bias (constant: ``epoch_utc`` and ``t`` are not needed for it)."""
    r, _, v, _, _ = _chief_gcrf(chief_kep)
    b = gcrf_to_eme2000()
    return _apply(b, r), _apply(b, v)


def angular_velocity(r, v):
    """|r x v| / |r|^2 [rad/s]: the rotation rate of the RTN frame about N (exact for any orbit at periapsis/
    apoapsis and for circular orbits; the R-T rotation rate of the osculating frame in general)."""
    r, v = np.asarray(r, dtype=float), np.asarray(v, dtype=float)
    return np.linalg.norm(np.cross(r, v), axis=-1) / np.sum(r * r, axis=-1)


def rtn_to_inertial(r_c, v_c, rho, rho_dot):
    """Inertial position and velocity of a deputy at RTN position ``rho`` [m] and rotating-frame velocity
    ``rho_dot`` [m/s] relative to a chief at (``r_c``, ``v_c``) (module docstring); all ``(..., 3)``."""
    m = rtn_matrix(r_c, v_c)
    w = angular_velocity(r_c, v_c)
    rho, rho_dot = np.asarray(rho, dtype=float), np.asarray(rho_dot, dtype=float)
    wxr = np.stack([-w * rho[..., 1], w * rho[..., 0], np.zeros_like(w * rho[..., 0])], axis=-1)
    return np.asarray(r_c) + _apply(m, rho), np.asarray(v_c) + _apply(m, rho_dot + wxr)


def inertial_to_rtn(r_c, v_c, r_d, v_d):
    """Inverse of :func:`rtn_to_inertial`: RTN position and rotating-frame velocity of the deputy."""
    m = rtn_matrix(r_c, v_c)
    w = angular_velocity(r_c, v_c)
    rho = _apply(np.swapaxes(m, -1, -2), np.asarray(r_d) - np.asarray(r_c))
    dv = _apply(np.swapaxes(m, -1, -2), np.asarray(v_d) - np.asarray(v_c))
    wxr = np.stack([-w * rho[..., 1], w * rho[..., 0], np.zeros_like(w * rho[..., 0])], axis=-1)
    return rho, dv - wxr


def dv_rtn_to_inertial(r, v, dv_rtn):
    """Impulsive Delta-v [m/s] in the inertial frame of (r, v) from its components in that spacecraft's own RTN
    frame: M dv (an impulse changes the velocity only, so no omega x rho term)."""
    return _apply(rtn_matrix(r, v), dv_rtn)


def dv_inertial_to_rtn(r, v, dv):
    """Inverse of :func:`dv_rtn_to_inertial`: M^T dv."""
    return _apply(np.swapaxes(rtn_matrix(r, v), -1, -2), dv)


def roe_rtn_state(roe, chief_kep):
    """RTN position [m] and rotating-frame velocity [m/s] of dimensionless ``roe`` relative to the chief with mean
    elements ``chief_kep``: a * roe_to_rtn(roe, u) (seed 002 Eq. 2's linear map), velocity scaled by a du/dt (the
    map's derivative along u times u's J2 secular rate, as the positions move)."""
    a, inc, _, u = chief_from_kepler(chief_kep)
    pos, vel = roe_to_rtn(roe, u)
    rate = arg_latitude_rate(a, inc)[..., None]
    a = np.asarray(a, dtype=float)[..., None]
    return pos * a, vel * a * rate


def deputy_state(roe, chief_kep, epoch_utc, t):
    """Picosatellite EME2000 position [m] and velocity [m/s] from its ROE and the chief's mean elements at ``t``:
    r_d = r_c + M rho, v_d = v_c + M rho_dot + Omega x (M rho), with M the RTN frame of the model's chief (the one
    the radar sees) turning at Omega = (du/dt) N + (d raan/dt) z as the mean elements advance."""
    r_c, v_model, v_c, u_dot, raan_dot = _chief_gcrf(chief_kep)
    rho, rho_dot = roe_rtn_state(roe, chief_kep)
    m = rtn_matrix(r_c, v_model)
    d = _apply(m, rho)
    spin = u_dot[..., None] * m[..., :, 2]
    r_d, v_d = r_c + d, v_c + _apply(m, rho_dot) + np.cross(spin, d) + _z_cross(raan_dot, d)
    b = gcrf_to_eme2000()
    return _apply(b, r_d), _apply(b, v_d)


def roe_to_rtn_jacobian(chief_kep):
    """6x6 d[rho, rho_dot]/d(roe) of :func:`roe_rtn_state` (the map is linear in the ROE)."""
    return np.stack([np.concatenate(roe_rtn_state(e, chief_kep)) for e in np.eye(6)], axis=-1)


def rtn_to_inertial_jacobian(r_c, v_c):
    """6x6 d[r_d, v_d]/d[rho, rho_dot] of :func:`rtn_to_inertial` at fixed chief: [[M, 0], [M W, M]], W = omega x."""
    m = rtn_matrix(r_c, v_c)
    w = float(angular_velocity(r_c, v_c))
    cross = np.array([[0.0, -w, 0.0], [w, 0.0, 0.0], [0.0, 0.0, 0.0]])
    out = np.zeros((6, 6))
    out[:3, :3] = m
    out[3:, 3:] = m
    out[3:, :3] = m @ cross
    return out


def roe_covariance_to_rtn(cov_roe, chief_kep):
    """Covariance of [rho (m), rho_dot (m/s)] in RTN from the dimensionless ROE covariance: J P J^T."""
    j = roe_to_rtn_jacobian(chief_kep)
    return j @ np.asarray(cov_roe, dtype=float) @ j.T


def roe_covariance_to_inertial(cov_roe, chief_kep, epoch_utc, t):
    """Covariance of the picosatellite's EME2000 state [m, m/s] from the dimensionless ROE covariance (the carrier's
    own state taken as known: it carries GPS)."""
    r_c, v_c = chief_state(chief_kep, epoch_utc, t)
    j = rtn_to_inertial_jacobian(r_c, v_c) @ roe_to_rtn_jacobian(chief_kep)
    return j @ np.asarray(cov_roe, dtype=float) @ j.T
