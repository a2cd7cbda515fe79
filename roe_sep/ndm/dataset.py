"""The CCSDS set of a run from its messages: OPMs of the approved plans and of the executed carrier burns, the OEM
(carrier and picosatellite truth, picosatellite OD estimates with covariance), the TDM of the radar measurements
and the CDM of the run's closest approach.

Inputs are message objects as decoded from a bag (mcap_ros2) or received by a node (rclpy): only their fields are
read (duck typing), so the bag export and the ``ground_bridge`` node write byte-for-byte the same content from the
same messages (apart from CREATION_DATE).
"""

import math
from pathlib import Path

import numpy as np

from .. import interfaces
from ..core.relmotion.dynamics import propagate, propagate_chief
from ..core.relmotion.roe import roe_to_rtn
from ..stamps import time_to_sec
from ..validate import ROE_FIELDS
from . import frames
from .messages import (
    Burn,
    ConjunctionObject,
    EphemerisSegment,
    SpacecraftParameters,
    TrackingPass,
    build_cdm,
    build_oem,
    build_opm,
    build_tdm,
    delta_mass,
    write_message,
)
from .options import TOPICS, Options, RunMessages  # noqa: F401  (re-exported)


def kepler(el) -> np.ndarray:
    """``[a, e, i, raan, argp, M]`` of an OrbitalElements message (M = u - argp): :func:`kepler_rows` of one."""
    return kepler_rows([el])[0]


def roe_of(msg) -> np.ndarray:
    """Dimensionless ROE of a RelativeOrbitalElements message: :func:`roe_rows` of one."""
    return roe_rows([msg])[0]


def kepler_rows(els) -> np.ndarray:
    """``[a, e, i, raan, argp, M]`` (M = u - argp) of each OrbitalElements message, ``(n, 6)``, in one array
    operation."""
    x = np.array([(el.semi_major_axis, el.eccentricity, el.inclination, el.raan, el.arg_perigee,
                   el.mean_arg_latitude) for el in els], dtype=float).reshape(-1, 6)
    x[:, 5] -= x[:, 4]
    return x


def roe_rows(msgs) -> np.ndarray:
    """Dimensionless ROE (a*ROE / a) of each RelativeOrbitalElements message, ``(n, 6)``, in one array operation."""
    x = np.array([tuple(getattr(m, k) for k in ROE_FIELDS) + (m.chief.semi_major_axis,) for m in msgs],
                 dtype=float).reshape(-1, 7)
    return x[:, :6] / x[:, 6:]


def vec(v) -> np.ndarray:
    return np.array([v.x, v.y, v.z], dtype=float)


class Truth:
    """The simulator's truth samples: times, ROE and chief elements, sorted, with :meth:`chief_at` (secular
    propagation of the nearest earlier sample's chief elements, radar_od's model)."""

    def __init__(self, msgs):
        rows = sorted(((time_to_sec(m.header.stamp), k, m) for k, m in enumerate(msgs)), key=lambda r: (r[0], r[1]))
        self.t = np.array([r[0] for r in rows])
        ms = [r[2] for r in rows]
        self.roe = roe_rows(ms)
        self.chief = kepler_rows([m.chief for m in ms])

    def __len__(self):
        return self.t.size

    def chief_at(self, t):
        t = np.atleast_1d(np.asarray(t, dtype=float))
        k = np.clip(np.searchsorted(self.t, t, side="right") - 1, 0, self.t.size - 1)
        return propagate_chief(self.chief[k], t - self.t[k])


def approved(run: RunMessages):
    """Approved plans, ``[(topic, plan), ...]`` in check order: a plan whose ``/safety/plan_check`` says safe."""
    ok = {(c.source, round(time_to_sec(c.plan_stamp), 6)) for c in run[interfaces.PLAN_CHECK_TOPIC] if c.safe}
    out = []
    for topic in (interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.ACQUISITION_PLAN_TOPIC):
        seen = set()
        for p in run[topic]:
            key = round(time_to_sec(p.header.stamp), 6)
            if (f"plan:{topic}", key) in ok and key not in seen:
                seen.add(key)
                out.append((topic, p))
    return sorted(out, key=lambda tp: time_to_sec(tp[1].header.stamp))


def spacecraft(opts: Options) -> SpacecraftParameters:
    return SpacecraftParameters(opts.carrier_mass, opts.carrier_drag_area, opts.carrier_drag_coeff)


def _burns(maneuvers, truth: Truth, opts: Options, frame):
    """:class:`Burn` list of carrier maneuver messages in ``frame`` (RTN or EME2000 via the carrier state), the
    mass decreasing burn after burn; zero burns are no maneuver and are left out."""
    out = []
    mass = opts.carrier_mass
    for m in maneuvers:
        t = time_to_sec(m.epoch)
        dv = vec(m.dv_rtn)
        if not np.any(dv):
            continue
        comments = [f"{m.purpose} burn of the {m.spacecraft} (roe_sep), dv RTN [m/s] = "
                    + " ".join(repr(float(x)) for x in dv)]
        if frame != frames.LOCAL_FRAME:
            r, v = frames.chief_state(truth.chief_at(t)[0], opts.epoch_utc, t)
            dv = frames.dv_rtn_to_inertial(r, v, dv)
        dm = delta_mass(dv, mass, opts.carrier_isp)
        mass += dm
        out.append(Burn(t, dv, frame, dm, comments))
    return out


def plan_opm(plan, truth: Truth, opts: Options, frame=frames.LOCAL_FRAME, label="plan"):
    """OPM of a plan's carrier burns: the carrier's EME2000 state at the first burn's epoch and every burn in
    ``frame`` (``RTN``, the carrier's own; or ``EME2000``)."""
    carrier = [m for m in plan.maneuvers if m.spacecraft == "carrier"]
    if not carrier:
        return None
    t0 = time_to_sec(carrier[0].epoch)
    r, v = frames.chief_state(truth.chief_at(t0)[0], opts.epoch_utc, t0)
    comments = [f"roe_sep {label}: strategy {plan.strategy}, computed at sim time {time_to_sec(plan.header.stamp)!r} s",
                "carrier state: mean near-circular orbit of the simulator (GCRF, frame bias to EME2000)",
                f"MAN_DELTA_MASS from the rocket equation, m = {opts.carrier_mass!r} kg, Isp = {opts.carrier_isp!r} s"]
    return build_opm(opts.carrier_name, opts.carrier_name, opts.epoch_utc, t0, r, v=v,
                     burns=_burns(carrier, truth, opts, frame), spacecraft=spacecraft(opts), comments=comments)


def executed_opm(run: RunMessages, truth: Truth, opts: Options):
    """OPM of the carrier burns as executed (``/sim/executed_maneuvers``, with the execution errors), RTN."""
    done = sorted({(time_to_sec(m.epoch), m.purpose): m for m in run[interfaces.EXECUTED_TOPIC]
                   if m.spacecraft == "carrier"}.items())
    if not done:
        return None
    ms = [m for _, m in done]
    t0 = time_to_sec(ms[0].epoch)
    r, v = frames.chief_state(truth.chief_at(t0)[0], opts.epoch_utc, t0)
    return build_opm(opts.carrier_name, opts.carrier_name, opts.epoch_utc, t0, r, v=v,
                     burns=_burns(ms, truth, opts, frames.LOCAL_FRAME), spacecraft=spacecraft(opts),
                     comments=["roe_sep: carrier burns as executed by the simulator (execution and attitude errors "
                               "included)"])


def _ejection_epoch(run: RunMessages, truth: Truth):
    ej = [time_to_sec(m.epoch) for m in run[interfaces.EXECUTED_TOPIC] if m.purpose == "ejection"]
    if ej:
        return min(ej)
    sep = np.nonzero(np.any(truth.roe != 0.0, axis=1))[0]
    return float(truth.t[sep[0]]) if sep.size else None


def thin(t, step):
    """Indices of ``t`` (increasing) keeping the first, the last, and each sample at least ``step`` after the
    previous kept one."""
    keep, last = [], -math.inf
    for k, tk in enumerate(t):
        if tk - last >= step - 1e-9 or k == len(t) - 1:
            keep.append(k)
            last = tk
    return np.array(keep, dtype=int)


def _burn_segments(truth: Truth, bounds, step):
    """Index arrays of the truth samples of each [lo, hi) of consecutive ``bounds`` (a sample at lo, repeated at a
    burn, counts by its last copy: the post-burn state), thinned to ``step``; segments of fewer than 2 left out."""
    out = []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        idx = np.nonzero((truth.t >= lo) & (truth.t < hi))[0]
        if idx.size and np.sum(truth.t[idx] == lo) > 1:
            idx = idx[np.sum(truth.t[idx] == lo) - 1:]
        idx = idx[thin(truth.t[idx], step)] if idx.size else idx
        if idx.size >= 2:
            out.append(idx)
    return out


def truth_segments(run: RunMessages, truth: Truth, opts: Options):
    """OEM segments of the truth: the carrier from the start, the picosatellite from the ejection, a new segment
    at every burn of either (the simulator publishes a truth sample right at each burn: same epoch, new state; the
    velocity jumps there, so no interpolation may span it)."""
    if len(truth) < 2:
        return []
    executed = run[interfaces.EXECUTED_TOPIC]
    carrier_burns = sorted({time_to_sec(m.epoch) for m in executed if m.spacecraft == "carrier"})
    segs = []
    for idx in _burn_segments(truth, [float(truth.t[0])] + [b for b in carrier_burns if b > truth.t[0]] + [math.inf],
                              opts.oem_step):
        r, v = frames.chief_state(truth.chief[idx], opts.epoch_utc, truth.t[idx])
        segs.append(EphemerisSegment(opts.carrier_name, opts.carrier_name, truth.t[idx], r, v,
                                     comments=["truth: the simulator's carrier (chief) orbit"]))
    t_ej = _ejection_epoch(run, truth)
    if t_ej is None:
        return segs
    burns = sorted({time_to_sec(m.epoch) for m in executed})
    for idx in _burn_segments(truth, [b for b in burns if b >= t_ej] + [math.inf], opts.oem_step):
        rd, vd = frames.deputy_state(truth.roe[idx], truth.chief[idx], opts.epoch_utc, truth.t[idx])
        segs.append(EphemerisSegment(opts.picosat_name, opts.picosat_name, truth.t[idx], rd, vd,
                                     comments=["truth: the simulator's picosatellite"]))
    return segs


def od_segments(run: RunMessages, truth: Truth, opts: Options):
    """One OEM segment per OD solution: the estimate propagated (secular model, estimated drag drift) from its
    epoch to the next solution's (or the run's end), the covariance at its epoch in EME2000."""
    ods = sorted(run[interfaces.OD_TOPIC], key=lambda o: time_to_sec(o.estimate.header.stamp))
    t_end = float(truth.t[-1]) if len(truth) else None
    segs = []
    for k, od in enumerate(ods):
        est = od.estimate
        t0 = time_to_sec(est.header.stamp)
        t1 = time_to_sec(ods[k + 1].estimate.header.stamp) if k + 1 < len(ods) else (t_end or t0)
        if t1 <= t0:
            continue
        t = np.append(np.arange(t0, t1, opts.od_step), t1)
        if t[-1] - t[-2] < 1e-6:
            t = t[:-1]
        kep0 = kepler(est.chief)
        a = kep0[0]
        roe = propagate(roe_of(est), t - t0, a, kep0[2], True, da_dot=od.a_da_dot / a)
        chief = propagate_chief(kep0, t - t0)
        rd, vd = frames.deputy_state(roe, chief, opts.epoch_utc, t)
        cov = np.asarray(est.covariance, dtype=float).reshape(6, 6) / (a * a)
        segs.append(EphemerisSegment(
            f"{opts.picosat_name}", f"{opts.picosat_name}-OD", t, rd, vd,
            [(t0, frames.roe_covariance_to_inertial(cov, kep0, opts.epoch_utc, t0))],
            comments=[f"OD estimate {k + 1}: {od.passes} radar passes, {od.measurements} measurements, residual "
                      f"RMS {od.residual_rms!r}, a*da_dot = {od.a_da_dot!r} m/s",
                      "covariance: picosatellite state given the carrier's (GPS), from the ROE covariance"]))
    return segs


def radar_passes(run: RunMessages):
    """:class:`TrackingPass` per (station, pass id) of the radar measurements."""
    groups = {}
    for m in run[interfaces.RADAR_TOPIC]:
        groups.setdefault((m.station, m.pass_id), []).append(m)
    out = []
    for (station, pass_id), ms in sorted(groups.items(), key=lambda kv: time_to_sec(kv[1][0].header.stamp)):
        ms = sorted(ms, key=lambda m: time_to_sec(m.header.stamp))
        out.append(TrackingPass(station, pass_id, np.array([time_to_sec(m.header.stamp) for m in ms]),
                                np.array([[m.range, m.azimuth, m.elevation] for m in ms]),
                                ms[0].sigma_range, ms[0].sigma_angle))
    return out


def closest_approach(run: RunMessages, truth: Truth, opts: Options):
    """(t, ROE, chief) of the truth's closest approach after the departure, the simulator's definition: the
    smallest local minimum of |r| once |r| exceeded ``departure_distance`` (the receding start of the separation is
    no approach). |r| of the linear ROE map, sampled every ``ca_step`` s by secular propagation from each truth
    sample to the next; None without a departure or a later minimum."""
    if len(truth) < 2:
        return None
    span = np.diff(truth.t)
    ks = np.nonzero(span > 0.0)[0]
    if not ks.size:
        return None
    # every sample's grid 0, ca_step, ... < span (np.arange's points), all samples in one vectorized pass
    counts = np.ceil(span[ks] / opts.ca_step).astype(int)
    k = np.repeat(ks, counts)
    first = np.repeat(np.cumsum(counts) - counts, counts)
    dt = (np.arange(k.size) - first) * opts.ca_step
    t = truth.t[k] + dt
    roe = propagate(truth.roe[k], dt, truth.chief[k, 0], truth.chief[k, 2], True, da_dot=0.0)
    chief = propagate_chief(truth.chief[k], dt)
    dist = np.linalg.norm(roe_to_rtn(roe, chief[:, 4] + chief[:, 5])[0], axis=-1) * chief[:, 0]
    away = np.nonzero(dist >= opts.departure_distance)[0]
    if not away.size:
        return None
    d = dist[away[0]:]
    inner = np.nonzero((d[1:-1] <= d[:-2]) & (d[1:-1] < d[2:]))[0] + 1
    if not inner.size:
        return None
    k = away[0] + inner[np.argmin(d[inner])]
    return t[k], roe[k], chief[k]


def _od_covariance_at(run: RunMessages, t):
    """RTN covariance input: the last OD estimate's ROE covariance (dimensionless) propagated to ``t`` with the
    linear secular model, or None without an estimate before ``t``."""
    ods = [o for o in run[interfaces.OD_TOPIC] if time_to_sec(o.estimate.header.stamp) <= t]
    if not ods:
        return None
    est = max(ods, key=lambda o: time_to_sec(o.estimate.header.stamp)).estimate
    kep = kepler(est.chief)
    stm = propagate(np.eye(6), t - time_to_sec(est.header.stamp), kep[0], kep[2], True, da_dot=0.0).T
    cov = np.asarray(est.covariance, dtype=float).reshape(6, 6) / kep[0] ** 2
    return stm @ cov @ stm.T


def conjunction_cdm(run: RunMessages, truth: Truth, opts: Options):
    """CDM of the run's closest approach (truth), object 1 the carrier, object 2 the picosatellite with the
    covariance of the last OD estimate before the TCA (none before the first estimate)."""
    ca = closest_approach(run, truth, opts)
    if ca is None:
        return None
    tca, roe, chief = ca
    r, v = frames.chief_state(chief, opts.epoch_utc, tca)
    rd, vd = frames.deputy_state(roe, chief, opts.epoch_utc, tca)
    cov = _od_covariance_at(run, tca)
    cov_rtn = None if cov is None else frames.roe_covariance_to_rtn(cov, chief)
    objs = [ConjunctionObject(opts.carrier_name, "1", r, v, None, True, ["state known (GPS): zero covariance"]),
            ConjunctionObject(opts.picosat_name, "2", rd, vd, cov_rtn, False,
                              ["covariance: last radar OD estimate before TCA" if cov is not None else
                               "no OD estimate before TCA: zero covariance"])]
    return build_cdm(opts.epoch_utc, tca, objs, "ROE_SEP_CLOSEST_APPROACH",
                     ["closest approach of the run after the departure (simulator truth)"])


def messages_of(run: RunMessages, opts: Options = Options(), ephemerides=True):
    """``{file stem: message}`` of the set (stems without the format suffix); the OEM, TDM and CDM only with
    ``ephemerides`` (the OPMs alone are cheap to rebuild at every plan and burn)."""
    truth = Truth(run[interfaces.TRUTH_ROE_TOPIC])
    out = {}
    if len(truth) == 0:
        return out
    for k, (topic, plan) in enumerate(approved(run), start=1):
        name = f"plan{k:02d}_{plan.strategy}"
        for frame, suffix in ((frames.LOCAL_FRAME, ""), (frames.INERTIAL_FRAME, "_eme2000")):
            opm = plan_opm(plan, truth, opts, frame, f"approved plan {k} ({topic})")
            if opm is not None:
                out[f"{name}{suffix}.opm"] = opm
    opm = executed_opm(run, truth, opts)
    if opm is not None:
        out["executed_carrier.opm"] = opm
    if not ephemerides:
        return out
    segs = truth_segments(run, truth, opts) + od_segments(run, truth, opts)
    if segs:
        out["ephemeris.oem"] = build_oem(opts.epoch_utc, segs, ["roe_sep run: truth and radar OD estimates"])
    passes = radar_passes(run)
    if passes:
        out["radar.tdm"] = build_tdm(opts.epoch_utc, passes, ["roe_sep radar measurements of the picosatellite"])
    cdm = conjunction_cdm(run, truth, opts)
    if cdm is not None:
        out["closest_approach.cdm"] = cdm
    return out


def write_set(run: RunMessages, out_dir, fmt="xml", opts: Options = Options()):
    """Write the set into ``out_dir`` (atomically, file by file); returns the written paths."""
    out_dir = Path(out_dir)
    return [write_message(out_dir / f"{stem}.{fmt}", msg, fmt) for stem, msg in messages_of(run, opts).items()]
