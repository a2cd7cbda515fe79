"""The relative OD offline (``roe-sep od``): tracking files in, the picosatellite's orbit relative to the carrier out.

The same batch least squares the ``radar_od`` node runs (:func:`roe_sep.core.od.batch.batch_least_squares`), fed
the same way: every measurement of the TDMs (:func:`roe_sep.ndm.messages.read_tdm`, which reads what
:mod:`roe_sep.ndm.tdm_reader` accepts) becomes a :class:`~roe_sep.core.od.sensor.RadarRecord` with the carrier's
mean elements at its epoch; the records after the latest carrier maneuver, in passes with enough measurements
(:func:`~roe_sep.core.od.sensor.counted_passes`), form one :class:`~roe_sep.core.od.batch.RadarBatch`.

The carrier's orbit comes from its own OEM (its GPS ephemeris, EME2000): each state is turned into the mean
near-circular elements the measurement model uses as osculating (:func:`chief_elements`, the inverse of
:func:`roe_sep.ndm.frames.chief_state`: a = |r|, the plane of two neighbouring positions with the J2 nodal turn
between them, u of r in it) and carried to the measurement epoch from the first state at or after it in its
segment and from the state before it with the J2 secular rates, blended linearly in time
(:func:`carrier_at`, :func:`~roe_sep.core.od.sensor.chief_between`), as radar_od carries its truth samples.
That is radar_od's measurement model (``model="circular"``, the default), the one a closed-loop run's files were
made with. ``model="osculating"`` (files of a numerical propagator, e.g. Orekit's): each state (position and
velocity) gives the carrier's first-order Brouwer mean elements with their eccentricity
(:func:`~roe_sep.core.truth.mean_osc.cartesian_to_mean`), a measurement takes the state itself (between states:
its neighbours carried and blended, :func:`carrier_state_at`) and the picosatellite is that state plus the osculating
difference of the two spacecraft's mean elements (:mod:`roe_sep.core.od.osculating`,
:class:`~roe_sep.core.od.batch.OsculatingBatch`); the estimate's state and covariance and the prediction follow
the same map (:func:`estimate`, :func:`prediction`).

Editing: after each fit, a measurement whose whitened residual triplet has a chi-square (3 degrees of freedom)
beyond the ``1 - edit_p`` quantile is rejected and the batch solved again, until none is (at most 20 rounds).
Consistency of the post-fit residuals: their chi-square over its degrees of freedom (3 m - 7) against the
chi-square distribution's 95 % band, which a model and sigmas that fit the data meet.
"""

import math
from dataclasses import dataclass, field, replace
from datetime import timedelta

import numpy as np
from scipy import stats

from ..core.constants import R_EARTH
from ..core.frames import gcrf_to_eme2000, gcrs_to_itrs
from ..core.od import osculating
from ..core.od.batch import (
    STATE_SIZE,
    DragModel,
    ODResult,
    OsculatingBatch,
    RadarBatch,
    batch_least_squares,
    measurement_residual,
    predict,
)
from ..core.od.radar import julian_date
from ..core.od.sensor import RadarRecord, chief_from_samples, counted_passes
from ..core.relmotion.dynamics import propagate, propagate_chief, raan_rate
from ..core.truth.mean_osc import cartesian_to_mean
from ..core.truth.nonlinear import vallado_band
from ..errors import NdmError
from . import frames
from .messages import read_message, read_tdm
from .tdm_reader import TIME_SYSTEMS, parse_tdm_epoch, read_observations, to_utc

EDIT_P = 1e-4
"""Default probability of a consistent measurement triplet being rejected by the editing (chi-square, 3 dof)."""
CARRIER_GAP_S = 3600.0
"""Largest gap [s] between an OEM state and a measurement epoch the carrier's elements are carried across."""
MODELS = ("circular", "osculating")
"""The measurement models (module docstring): radar_od's, and the carrier's states with the osculating map."""


@dataclass(frozen=True)
class CarrierSegment:
    """One OEM segment of the carrier: sim times ``t`` (n,) [s] and its mean elements ``kep`` (n, 6); for the
    osculating model also its ``state`` (n, 2, 3), GCRF position [m] and velocity [m/s] (else None)."""

    t: np.ndarray
    kep: np.ndarray
    state: np.ndarray | None = None


@dataclass
class OfflineOD:
    """What :func:`solve` found: the solution, its batch and records, the per-measurement whitened residuals, the
    rejected measurements (dicts: epoch, station, pass, reason), the drag model and the epoch of sim time 0."""

    result: ODResult
    batch: RadarBatch
    records: list
    residuals: np.ndarray
    rejected: list = field(default_factory=list)
    model: DragModel | None = None
    epoch_utc: str = ""
    pass_names: dict = field(default_factory=dict)
    carrier: list = field(default_factory=list)


def chief_elements(t, r):
    """Mean near-circular elements ``[a, 0, i, raan, 0, u]`` ``(n, 6)`` of one ephemeris segment's positions: the
    circular orbits (:func:`roe_sep.core.od.radar.chief_position_velocity`) through each ``r`` [m] whose planes turn
    about the pole at the J2 nodal rate (:func:`~roe_sep.core.relmotion.dynamics.raan_rate`), as the carrier's mean
    elements do. The plane at t_k is that of r_k and its neighbour r_j turned back by -raan_dot (t_j - t_k): the
    positions alone, whatever velocity the file carries (a circular one, or the derivative of the positions with
    the nodal term, whose r x v leans by up to raan_dot / n = 2e-4 rad).

    Parameters
    ----------
    t, r : array_like, shapes (n,), (n, 3)
        Times [s] (n >= 2, increasing) and positions [m] in the simulator's inertial frame.

    Returns
    -------
    numpy.ndarray, shape (n, 6)
        a [m], e = 0, i, raan, argp = 0, M = u [rad].
    """
    t, r = np.asarray(t, dtype=float), np.asarray(r, dtype=float)
    a = np.linalg.norm(r, axis=-1)
    j = np.arange(t.size) + 1
    j[-1] = t.size - 2
    sign = np.where(j > np.arange(t.size), 1.0, -1.0)[:, None]
    h = sign * np.cross(r, r[j])
    for _ in range(2):  # the nodal rate from the plane's inclination (once without the turn: to 2e-4 rad)
        inc = np.arccos(np.clip(h[:, 2] / np.linalg.norm(h, axis=-1), -1.0, 1.0))
        turn = -raan_rate(a, inc) * (t[j] - t)
        c, s_ = np.cos(turn), np.sin(turn)
        rj = np.stack([c * r[j, 0] - s_ * r[j, 1], s_ * r[j, 0] + c * r[j, 1], r[j, 2]], axis=-1)
        h = sign * np.cross(r, rj)
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    inc = np.arccos(np.clip(h[:, 2], -1.0, 1.0))
    raan = np.arctan2(h[:, 0], -h[:, 1])
    node = np.stack([np.cos(raan), np.sin(raan), np.zeros_like(raan)], axis=-1)
    u = np.arctan2(np.sum(r * np.cross(h, node), axis=-1), np.sum(r * node, axis=-1))
    zero = np.zeros_like(a)
    return np.stack([a, zero, inc, np.mod(raan, 2 * np.pi), zero, np.mod(u, 2 * np.pi)], axis=-1)


def _eme2000_to_sim(epoch_utc, t):
    """Rotation ``(..., 3, 3)`` from EME2000 to the simulator's inertial frame, the GCRF, at sim times ``t``: the
    transpose of the frame bias (:func:`roe_sep.core.frames.gcrf_to_eme2000`, constant)."""
    return np.broadcast_to(gcrf_to_eme2000().T, np.shape(t) + (3, 3))


def earth_rotation(epoch_utc, t):
    """The Earth's orientation at sim times ``t`` [s] as :class:`~roe_sep.core.od.batch.RadarBatch` takes it (the
    radar_od node's: the GCRS -> ITRS rotation of :func:`roe_sep.core.frames.gcrs_to_itrs`)."""
    return gcrs_to_itrs(julian_date(frames.parse_epoch(epoch_utc)), np.asarray(t, dtype=float))


def _read(path):
    """:func:`~roe_sep.ndm.messages.read_message` of a file, its NdmError naming the file."""
    try:
        return read_message(path)
    except NdmError as exc:
        raise NdmError(f"{path}: {exc}") from None


def _num(x):
    return float(getattr(x, "value", x))


def read_carrier_oem(path, epoch_utc, target=None, carrier=None, model="circular"):
    """The carrier's :class:`CarrierSegment` list of an OEM: the segments of object ``carrier`` (default: the one
    object other than ``target``, the TDMs' tracked object), EME2000 states in km and km/s, time systems of
    :mod:`roe_sep.ndm.tdm_reader`; the elements of ``model`` (module docstring: :func:`chief_elements` of the
    positions, or the Brouwer mean elements of the states, kept with them). NdmError (one line) for another frame
    or centre, an ambiguous or missing carrier, or a segment of fewer than 2 states."""
    msg = _read(path)
    if type(msg).__name__ not in ("Oem", "OemType"):
        raise NdmError(f"{path}: expected an OEM, got {type(msg).__name__.removesuffix('Type').upper()}")
    segs = msg.body.segment
    names = sorted({str(s.metadata.object_name).strip() for s in segs})
    if carrier is None:
        others = [n for n in names if n != target]
        if len(others) != 1:
            raise NdmError(f"{path}: which object is the carrier? OBJECT_NAMEs {names} (tracked: {target}); give "
                           "--carrier NAME")
        carrier = others[0]
    elif carrier not in names:
        raise NdmError(f"{path}: no OBJECT_NAME {carrier} (the file has {names})")
    out = []
    for k, seg in enumerate(segs, start=1):
        md = seg.metadata
        if str(md.object_name).strip() != carrier:
            continue
        where = f"{path}: OEM segment {k}"
        frame = str(getattr(md.ref_frame, "value", md.ref_frame)).strip().upper()
        center = str(md.center_name).strip().upper()
        ts = str(getattr(md.time_system, "value", md.time_system)).strip().upper()
        if frame != frames.INERTIAL_FRAME or center != frames.CENTER:
            raise NdmError(f"{where}: REF_FRAME {frame} / CENTER_NAME {center} is not supported (EME2000, EARTH)")
        if ts not in TIME_SYSTEMS:
            raise NdmError(f"{where}: TIME_SYSTEM {ts} is not supported ({', '.join(TIME_SYSTEMS)})")
        sv = seg.data.state_vector
        if len(sv) < 2:
            raise NdmError(f"{where}: {len(sv)} state(s), at least 2 needed")
        start = frames.parse_epoch(epoch_utc)
        t = np.array([(to_utc(parse_tdm_epoch(s.epoch), ts) - start).total_seconds() for s in sv])
        r = np.array([[_num(s.x), _num(s.y), _num(s.z)] for s in sv]) * 1000.0
        v = np.array([[_num(s.x_dot), _num(s.y_dot), _num(s.z_dot)] for s in sv]) * 1000.0
        if not (np.all(np.isfinite(r)) and np.all(np.diff(t) > 0.0)):
            raise NdmError(f"{where}: states must be finite, their epochs strictly increasing")
        if not np.all(np.isfinite(v)):
            raise NdmError(f"{where}: velocities must be finite")
        to_sim = _eme2000_to_sim(epoch_utc, t)
        r, v = np.einsum("...ij,...j->...i", to_sim, r), np.einsum("...ij,...j->...i", to_sim, v)
        kep = cartesian_to_mean(r, v) if model == "osculating" else chief_elements(t, r)
        if not np.all((kep[:, 0] > R_EARTH + 1e5) & (kep[:, 0] < R_EARTH + 5e6)):
            raise NdmError(f"{where}: the carrier is not in low Earth orbit (a from {kep[:, 0].min():.0f} m)")
        out.append(CarrierSegment(t, kep, np.stack([r, v], axis=-2) if model == "osculating" else None))
    return out


def auto_model(path) -> str:
    """The measurement model for a carrier OEM (``roe-sep od --model auto``): ``circular`` for one of roe_sep's own
    runs (``ORIGINATOR`` ROE_SEP: its radar simulated the measurements with that model), ``osculating`` for any
    other (a ground segment's GPS ephemeris, a numerical propagator's), whose carrier moves as a real orbit does."""
    originator = str(getattr(_read(path).header, "originator", "") or "").strip().upper()
    return "circular" if originator == "ROE_SEP" else "osculating"


def model_of(od: OfflineOD) -> str:
    """The measurement model a solution was fitted with (:data:`MODELS`)."""
    return "osculating" if isinstance(od.batch, OsculatingBatch) else "circular"


def _bracket(segments, t):
    """(segment, k) of the carrier's first OEM state at or after sim time ``t`` [s] in the segment that holds ``t``;
    None outside every segment or farther than :data:`CARRIER_GAP_S` from that state."""
    for seg in segments:
        if seg.t[0] <= t <= seg.t[-1]:
            k = int(np.searchsorted(seg.t, t))
            return None if abs(seg.t[k] - t) > CARRIER_GAP_S else (seg, k)
    return None


def carrier_at(segments, t):
    """The carrier's mean elements at sim time ``t`` [s] from the first state at or after ``t`` of the segment that
    holds it and the state before it, each carried to ``t`` and blended linearly in time
    (:func:`~roe_sep.core.od.sensor.chief_from_samples`; a segment ends at a maneuver: none is crossed), as radar_od
    carries its truth samples (the sensor simulated its measurements from them, so a closed-loop run's files are read
    as they were made), and the later state's time; None outside every segment."""
    found = _bracket(segments, t)
    if found is None:
        return None
    seg = found[0]
    return chief_from_samples(seg.t, seg.kep, (), t)  # no burn inside a segment


def carrier_state_at(segments, t):
    """The osculating model's carrier at sim time ``t`` [s] (segments with states): its mean elements and GCRF
    state ``(2, 3)`` carried from the first state at or after ``t`` of the segment holding it
    (:func:`~roe_sep.core.od.osculating.carrier_state`: that state itself when ``t`` is its epoch) blended with the
    state before it (:func:`~roe_sep.core.od.osculating.carrier_between`), and that state's time; None outside every
    segment or farther than :data:`CARRIER_GAP_S` from its states."""
    found = _bracket(segments, t)
    if found is None:
        return None
    seg, k = found
    if seg.t[k] == t:
        return seg.kep[k], seg.state[k], float(seg.t[k])
    kep, state = osculating.carrier_between(seg.state[k - 1:k + 1], seg.kep[k - 1:k + 1], seg.t[k - 1:k + 1], t)
    return kep, state, float(seg.t[k])


def tdm_epoch(paths, target=None):
    """ISO UTC string of the earliest time tag of the TDMs (the offline OD's sim time 0, less a minute), the
    tracked object (the participant the station's signal comes from): ``target`` if given (NdmError if no TDM
    tracks it), else the one object the TDMs track (NdmError naming them if they track several), and the messages
    read."""
    first, tracked, msgs = None, set(), []
    for p in paths:
        msgs.append(_read(p))
        for o in read_observations(msgs[-1]):
            first = o.timetag if first is None else min(first, o.timetag)
            tracked.add(o.participants[-2] if o.path[-1] == 1 else o.participants[-1])
    if first is None:
        raise NdmError(f"{paths[0]}: no observation")
    if target is None and len(tracked) > 1:
        raise NdmError(f"the TDMs track {len(tracked)} objects ({', '.join(sorted(tracked))}): give --target NAME "
                       "(the picosatellite)")
    if target is not None and target not in tracked:
        raise NdmError(f"no TDM tracks --target {target} (they track {', '.join(sorted(tracked))})")
    return (first - timedelta(seconds=60.0)).strftime("%Y-%m-%dT%H:%M:%S.%f"), target or tracked.pop(), msgs


@dataclass(frozen=True)
class Settings:
    """What the offline OD is told: stations (:class:`~roe_sep.core.od.radar.Station`), default sigmas [m, rad]
    for TDMs without them, measurements a pass needs, passes the OD needs, maneuver epochs (UTC datetimes), the
    arc's limits (UTC or None), the drag model's scale height (0: Vallado's) and ballistic ratio, the drag terms,
    the editing probability, the measurement model (:data:`MODELS`, or ``auto``: :func:`auto_model`)."""

    stations: tuple
    sigma_range: float
    sigma_angle: float
    min_pass: int
    min_passes: int = 2
    maneuvers: tuple = ()
    since: object = None
    until: object = None
    scale_height: float = 0.0
    ballistic_ratio: float = 1.5217
    drag: bool = True
    edit_p: float = EDIT_P
    model: str = "circular"


def _records(tdms, epoch_utc, carrier, s: Settings, *, target, msgs):
    """RadarRecords of every measurement of ``target`` in the TDMs (``msgs``, read from ``tdms``; pass ids
    negative: external passes), rejections (another object, outside the arc), and the passes' names; NdmError for
    an unknown station or an epoch outside the carrier OEM."""
    names = [st.name for st in s.stations]
    start = frames.parse_epoch(epoch_utc)
    lo = -math.inf if s.since is None else (s.since - start).total_seconds()
    hi = math.inf if s.until is None else (s.until - start).total_seconds()
    records, rejected, pass_names = [], [], {}
    for f, path in enumerate(tdms):
        for m in read_tdm(msgs[f], epoch_utc, s.sigma_range, s.sigma_angle):
            if m.target != target:
                rejected.append(_rej(epoch_utc, m.t, m.station, -1, f"tracks {m.target}, not {target}"))
                continue
            if m.station not in names:
                raise NdmError(f"{path}: station {m.station} is not known (stations: {', '.join(names)}; add it "
                               "with --station NAME,LAT_DEG,LON_DEG,ALT_M)")
            key = (f, m.station, m.pass_id)
            pid = pass_names.setdefault(key, (len(pass_names), f"{m.station} pass {m.pass_id}"
                                              + (f" ({path})" if len(tdms) > 1 else "")))[0]
            if not lo <= m.t <= hi:
                rejected.append(_rej(epoch_utc, m.t, m.station, pid, "outside --since/--until"))
                continue
            at = carrier_state_at(carrier, m.t) if s.model == "osculating" else carrier_at(carrier, m.t)
            if at is None:
                raise NdmError(f"{path}: epoch {frames.utc_string(epoch_utc, m.t)} is outside the carrier OEM's "
                               "span (or more than 1 h from its states)")
            records.append((RadarRecord(t=m.t, station=names.index(m.station), pass_id=-pid - 1,
                                        z=np.array(m.z, dtype=float), chief=at[0],
                                        earth=earth_rotation(epoch_utc, m.t), truth_t=at[-1]),
                            (m.sigma_range, m.sigma_angle, at[1] if len(at) == 3 else None)))
    return records, rejected, {v[0]: v[1] for v in pass_names.values()}


def _rej(epoch_utc, t, station, pid, reason):
    return {"epoch": frames.utc_string(epoch_utc, t), "station": station, "pass": pid, "reason": reason}


def _batch(recs, extra, s: Settings):
    """The RadarBatch of the records (``extra``: each one's sigmas and carrier state); an OsculatingBatch with the
    carrier's states for the osculating model."""
    fields = dict(t=np.array([r.t for r in recs]), z=np.array([r.z for r in recs]),
                  sigma=np.array([[sr, sa, sa] for sr, sa, _ in extra]), chief=np.array([r.chief for r in recs]),
                  earth=np.array([r.earth for r in recs]),
                  site_ef=np.array([s.stations[r.station].ecef for r in recs]),
                  site_enu=np.array([s.stations[r.station].enu for r in recs]))
    if s.model == "osculating":
        return OsculatingBatch(**fields, carrier=np.array([c for _, _, c in extra]))
    return RadarBatch(**fields)


def solve(tdms, carrier_oem, s: Settings, carrier_name=None, target=None) -> OfflineOD:
    """The offline OD of the TDM files ``tdms`` with the carrier of ``carrier_oem`` (OEM object ``carrier_name``,
    default the one other than the tracked ``target``, :func:`tdm_epoch`) (module docstring): the records, the arc
    after the latest maneuver, the passes that count, the fit with editing. NdmError (or the batch's ValueError)
    naming what is wrong."""
    epoch_utc, target, msgs = tdm_epoch(tdms, target)
    if s.model == "auto":  # after the TDMs: a bad TDM is named before the carrier's file is read
        s = replace(s, model=auto_model(carrier_oem))
    if s.model not in MODELS:
        raise NdmError(f"measurement model {s.model!r} is not one of {', '.join(MODELS)}")
    carrier = read_carrier_oem(carrier_oem, epoch_utc, target, carrier_name, s.model)
    if not carrier:
        raise NdmError(f"{carrier_oem}: no carrier segment")
    pairs, rejected, pass_names = _records(tdms, epoch_utc, carrier, s, target=target, msgs=msgs)
    if not pairs:
        raise NdmError("no measurement within --since/--until")
    start = frames.parse_epoch(epoch_utc)
    t_last = max(r.t for r, _ in pairs)
    burns = [(b - start).total_seconds() for b in s.maneuvers]
    last_burn = max((b for b in burns if b <= t_last), default=-math.inf)
    recs = [r for r, _ in pairs]
    used, passes = counted_passes(recs, last_burn, set(), s.min_pass)
    kept = {id(r) for r in used}
    for r in recs:
        if id(r) not in kept:
            reason = (f"before the latest maneuver ({frames.utc_string(epoch_utc, last_burn)})" if r.t < last_burn
                      else f"its pass has fewer than {s.min_pass} measurements")
            rejected.append(_rej(epoch_utc, r.t, s.stations[r.station].name, -r.pass_id - 1, reason))
    if len(passes) < s.min_passes:
        after = ("" if last_burn == -math.inf else
                 f" after the latest maneuver ({frames.utc_string(epoch_utc, last_burn)})")
        raise NdmError(f"{len(passes)} pass{'' if len(passes) == 1 else 'es'} count{'s' if len(passes) == 1 else ''}"
                       f"{after}, at least {s.min_passes} needed (--min-passes; passes of >= {s.min_pass} "
                       "measurements)")
    sig = {id(r): sg for r, sg in pairs}
    used.sort(key=lambda r: r.t)
    if 3 * len(used) < STATE_SIZE + 1:
        raise NdmError(f"too few measurements: {len(used)} usable (range/az/el triplets) of {len(recs)} for "
                       f"{STATE_SIZE} unknowns and a residual")
    a_c = float(used[-1].chief[0])
    model = DragModel(s.scale_height or vallado_band(a_c - R_EARTH)[2], s.ballistic_ratio)
    limit = float(stats.chi2.ppf(1.0 - s.edit_p, 3))
    for _ in range(20):
        batch = _batch(used, [sig[id(r)] for r in used], s)
        result = batch_least_squares(batch, drag=s.drag, model=model)
        w = measurement_residual(batch.z, predict(result.x, batch, result.t_est, True, s.drag,
                                                  model=model)) / batch.sigma
        chi = np.sum(w * w, axis=1)
        bad = np.flatnonzero(chi > limit)
        if not bad.size:
            break
        for k in bad:
            r = used[k]
            rejected.append(_rej(epoch_utc, r.t, s.stations[r.station].name, -r.pass_id - 1,
                                 f"residual chi-square {chi[k]:.1f} > {limit:.1f} (3 dof, p = {s.edit_p:g})"))
        used = [r for k, r in enumerate(used) if k not in set(bad.tolist())]
        if 3 * len(used) < STATE_SIZE + 1:
            raise NdmError(f"too few measurements after editing: {len(used)}")
    rejected.sort(key=lambda d: d["epoch"])
    return OfflineOD(result=result, batch=batch, records=used, residuals=w, rejected=rejected, model=model,
                     epoch_utc=epoch_utc, pass_names=pass_names, carrier=carrier)


def consistency(od: OfflineOD) -> dict:
    """Chi-square of the post-fit whitened residuals, its degrees of freedom (3 m - 7), their ratio and the
    chi-square distribution's central 95 % band of the ratio."""
    chi2 = float(np.sum(od.residuals**2))
    dof = int(od.residuals.size - STATE_SIZE)
    lo, hi = (float(stats.chi2.ppf(q, dof)) / dof for q in (0.025, 0.975))
    ratio = chi2 / dof
    return {"chi2": chi2, "dof": dof, "chi2_per_dof": ratio, "band95": [lo, hi], "in_band": bool(lo <= ratio <= hi)}


def pass_residuals(od: OfflineOD) -> list:
    """Per pass: its name, measurements, first and last epoch, and the mean and RMS of the post-fit residuals of
    range [m], azimuth and elevation [deg]."""
    raw = od.residuals * od.batch.sigma
    pids = np.array([-r.pass_id - 1 for r in od.records])
    out = []
    for pid in sorted(set(pids.tolist()), key=lambda p: od.batch.t[pids == p].min()):
        k = pids == pid
        res = raw[k] * np.array([1.0, 180.0 / math.pi, 180.0 / math.pi])
        row = {"pass": od.pass_names[pid], "n": int(k.sum()),
               "start": frames.utc_string(od.epoch_utc, od.batch.t[k].min()),
               "stop": frames.utc_string(od.epoch_utc, od.batch.t[k].max())}
        for j, name in enumerate(("range_m", "az_deg", "el_deg")):
            row[f"{name}_mean"] = float(res[:, j].mean())
            row[f"{name}_rms"] = float(np.sqrt(np.mean(res[:, j] ** 2)))
        out.append(row)
    return out


def estimate(od: OfflineOD) -> dict:
    """The solution as the radar_od node publishes it (mean a*ROE [m] at t_est with drag's short-periodic de,
    :meth:`~roe_sep.core.od.batch.ODResult.mean_state`; a*da_dot [m/s]) with 1-sigma, the carrier's mean elements
    at t_est, and the picosatellite's EME2000 state [m, m/s] with its 6x6 covariance (the carrier's state known).

    The state through the fit's own measurement model: radar_od's linear map (:func:`roe_sep.ndm.frames.deputy_state`,
    covariance J P J^T with its Jacobian), or for an :class:`~roe_sep.core.od.batch.OsculatingBatch` the carrier's
    state at t_est plus the osculating difference (:func:`roe_sep.core.od.osculating.deputy_state`), covariance
    J P J^T with that map's Jacobian (:func:`~roe_sep.core.od.osculating.roe_jacobian`), rotated to EME2000 by the
    frame bias: what is written is what was estimated."""
    res = od.result
    mean, cov = res.mean_state()
    k = int(np.argmax(od.batch.t))
    extra = {}
    if isinstance(od.batch, OsculatingBatch):
        chief, state = osculating.carrier_state(od.batch.carrier[k], od.batch.chief[k], res.t_est - od.batch.t[k])
        bias = gcrf_to_eme2000()
        r, v = osculating.deputy_state(mean[:6], chief, state) @ bias.T
        jac = np.kron(np.eye(2), bias) @ osculating.roe_jacobian(mean[:6], chief)
        cov_i = jac @ cov[:6, :6] @ jac.T
        extra["carrier_state"] = state
    else:
        chief = propagate_chief(od.batch.chief[k], np.array([res.t_est - od.batch.t[k]]))[0]
        r, v = frames.deputy_state(mean[:6], chief, od.epoch_utc, res.t_est)
        cov_i = frames.roe_covariance_to_inertial(cov[:6, :6], chief, od.epoch_utc, res.t_est)
    a = float(chief[0])
    return {"epoch": frames.utc_string(od.epoch_utc, res.t_est), "t_est": res.t_est, "a_roe_m": (mean[:6] * a).tolist(),
            "a_roe_sigma_m": (np.sqrt(np.diag(cov)[:6]) * a).tolist(), "a_da_dot_m_s": float(mean[6] * a),
            "a_da_dot_sigma_m_s": float(math.sqrt(cov[6, 6]) * a), "covariance_a_roe_m2": (cov * a * a).tolist(),
            "chief": chief.tolist(), "r_m": np.asarray(r).tolist(), "v_m_s": np.asarray(v).tolist(),
            "covariance_eme2000": cov_i, "iterations": res.iterations, "measurements": res.measurements,
            "mean_state": mean} | extra


def prediction(od: OfflineOD, est: dict, span_s: float, step_s: float):
    """Sim times, EME2000 positions and velocities of the picosatellite from the estimate over ``span_s`` [s]
    every ``step_s``: the mean ROE propagated with the estimated drift (as the run's OD segments,
    :func:`roe_sep.ndm.dataset.od_segments`), the carrier from its elements at t_est (J2 secular). With the
    osculating model (``est["carrier_state"]``, :func:`estimate`) the picosatellite is the carrier's state at t_est
    carried by :func:`~roe_sep.core.od.osculating.carrier_state` plus the osculating difference of the mean elements
    (:func:`~roe_sep.core.od.osculating.deputy_state`): the estimate's state at t_est, the carrier's absolute
    position then within the first-order theory's short-period error (its round trip misses a state by ~30 m), the
    relative one within ~0.1 m of that map."""
    t0 = est["t_est"]
    t = np.append(np.arange(t0, t0 + span_s, step_s), t0 + span_s)
    t = t[np.concatenate([[True], np.diff(t) > 1e-6])]
    kep0 = np.asarray(est["chief"])
    a = kep0[0]
    mean = est["mean_state"]
    roe = propagate(mean[:6], t - t0, a, kep0[2], True, da_dot=mean[6])
    chief = propagate_chief(kep0, t - t0)
    if "carrier_state" in est:
        bias = gcrf_to_eme2000()
        x = osculating.deputy_state(roe, chief, osculating.carrier_state(est["carrier_state"], kep0, t - t0)[1])
        return t, x[:, 0] @ bias.T, x[:, 1] @ bias.T
    r, v = frames.deputy_state(roe, chief, od.epoch_utc, t)
    return t, r, v
