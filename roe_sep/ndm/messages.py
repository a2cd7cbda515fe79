"""CCSDS Navigation Data Messages built and read with the ``ccsds-ndm`` library (its xsdata models of the official
NDM/XML 2.0.0 schemas): OPM 2.0 and OEM 2.0 (CCSDS 502.0-B-2), TDM 2.0 (503.0-B-2), CDM 1.0 (508.0-B-1).

No CCSDS text is formatted here: the library writes XML and KVN from the model objects. Two of its habits are kept
away from it, because other NDM readers (Orekit's among them) refuse the result: numpy scalars (it writes
``NP.FLOAT64(...)`` into the XML) and :class:`datetime` epochs (written with a space instead of the 'T'). Every
number goes in as a Python float (:func:`_f`) and every epoch as an ISO-8601 string (:func:`frames.utc_string`).

Units are the standards' ones: km, km/s, km^2... in OPM/OEM and the CDM state vector, m^2... in the CDM covariance
(RTN), deg and km in the TDM. Inputs here are SI (m, m/s, rad).
"""

import math
import os
import tempfile
from dataclasses import dataclass, field
from datetime import datetime, timedelta, timezone
from pathlib import Path

import numpy as np
from ccsds_ndm.mapping import NDMFileFormats
from ccsds_ndm.models import ndmxml2 as nd
from ccsds_ndm.ndm_io import NdmIo

from ..errors import NdmError, show
from . import frames
from .options import FORMATS
from .tdm_reader import read_observations

ORIGINATOR = "ROE_SEP"
SCHEMA_LOCATION = "https://sanaregistry.org/r/ndmxml_unqualified/ndmxml-2.0.0-master-2.0.xsd"
"""``xsi:noNamespaceSchemaLocation`` of every XML message: the SANA registry's master schema of NDM/XML 2.0.0 in its
unqualified variant (the elements carry no namespace), as CCSDS 505.0-B-2 prescribes for an NDM/XML instance."""
G0 = 9.80665
"""Standard gravity [m/s^2] of the rocket equation (Isp in seconds)."""


def _f(x) -> float:
    """A plain, finite Python float (the library writes numpy scalars as ``NP.FLOAT64(...)``)."""
    v = float(x)
    if not math.isfinite(v):
        raise ValueError(f"non-finite value {show(x)} cannot go into a CCSDS message")
    return v


def creation_date() -> str:
    """CREATION_DATE: now, UTC, ISO-8601 with 'T'."""
    return datetime.now(timezone.utc).strftime("%Y-%m-%dT%H:%M:%S.%f")


def _km(x):
    return nd.PositionType(value=_f(x) / 1000.0, units=nd.PositionUnits.KM)


def _kms(x):
    return nd.VelocityType(value=_f(x) / 1000.0, units=nd.VelocityUnits.KM_S)


def _header(comments=()):
    return nd.NdmHeader(comment=list(comments), creation_date=creation_date(), originator=ORIGINATOR)


def delta_mass(dv, mass, isp):
    """MAN_DELTA_MASS [kg] of an impulsive burn: -m (1 - exp(-|dv| / (Isp g0))) (Tsiolkovsky). OPM 2.0 XML
    requires a strictly negative value, so a zero burn is refused."""
    dm = -float(mass) * -math.expm1(-float(np.linalg.norm(dv)) / (float(isp) * G0))
    if not dm < 0.0:
        raise ValueError(f"burn of |dv| = {np.linalg.norm(dv)} m/s has no mass change (OPM requires < 0)")
    return dm


def _state_vector(cls, epoch, r, v, **extra):
    return cls(epoch=epoch, x=_km(r[0]), y=_km(r[1]), z=_km(r[2]), x_dot=_kms(v[0]), y_dot=_kms(v[1]),
               z_dot=_kms(v[2]), **extra)


@dataclass
class Burn:
    """One impulsive maneuver: sim time [s], Delta-v [m/s] in ``frame`` (``RTN`` of the executing spacecraft or
    ``EME2000``), mass change [kg] (< 0), comments."""

    t: float
    dv: np.ndarray
    frame: str
    delta_mass: float
    comments: list = field(default_factory=list)


@dataclass(frozen=True)
class SpacecraftParameters:
    """OPM spacecraft parameters (mandatory with maneuvers, 502.0-B-2 Sec. 3.2.4): mass [kg], drag area [m^2] and
    coefficient; solar radiation pressure area [m^2] and coefficient (0: not modelled by roe_sep)."""

    mass: float
    drag_area: float
    drag_coeff: float
    solar_rad_area: float = 0.0
    solar_rad_coeff: float = 0.0


def build_opm(object_name, object_id, epoch_utc, t, r, *, v, burns, spacecraft: SpacecraftParameters | None,
              comments=(), covariance=None):
    """OPM 2.0: the spacecraft's EME2000 state [m, m/s] at sim time ``t``, its parameters (None: none, allowed
    without maneuvers) and its maneuvers (:class:`Burn`); ``covariance``: the state's 6x6 [m, m/s] EME2000
    covariance (the OPM covariance section, km^2...), or None."""
    meta = nd.OpmMetadata(object_name=object_name, object_id=object_id, center_name=frames.CENTER,
                          ref_frame=frames.INERTIAL_FRAME, time_system=frames.TIME_SYSTEM)
    mans = [nd.ManeuverParametersType(
        comment=list(b.comments), man_epoch_ignition=frames.utc_string(epoch_utc, b.t),
        man_duration=nd.DurationType(value=0.0, units=nd.TimeUnits.S),
        man_delta_mass=nd.DeltamassType(value=_f(b.delta_mass), units=nd.MassUnits.KG), man_ref_frame=b.frame,
        man_dv_1=_kms(b.dv[0]), man_dv_2=_kms(b.dv[1]), man_dv_3=_kms(b.dv[2])) for b in burns]
    sc = spacecraft
    if sc is None and burns:
        raise ValueError("an OPM with maneuvers needs the spacecraft parameters (CCSDS 502.0-B-2 Sec. 3.2.4)")
    params = None if sc is None else nd.SpacecraftParametersType(
        comment=["solar radiation pressure is not modelled (area and coefficient 0)"] if not sc.solar_rad_coeff
        else [], mass=nd.MassType(value=_f(sc.mass), units=nd.MassUnits.KG),
        solar_rad_area=nd.AreaType(value=_f(sc.solar_rad_area), units=nd.AreaUnits.M_2),
        solar_rad_coeff=_f(sc.solar_rad_coeff), drag_area=nd.AreaType(value=_f(sc.drag_area), units=nd.AreaUnits.M_2),
        drag_coeff=_f(sc.drag_coeff))
    cov = None if covariance is None else _oem_covariance(None, covariance, frames.INERTIAL_FRAME)
    # The comments go into the state vector block, not before it at the data level: both are schema-valid and give
    # the same KVN, but Orekit's XML parser refuses a COMMENT directly under <data>.
    data = nd.OpmData(state_vector=_state_vector(
        nd.StateVectorType, frames.utc_string(epoch_utc, t), r, v, comment=list(comments)),
        spacecraft_parameters=params, maneuver_parameters=mans, covariance_matrix=cov)
    return nd.Opm(header=_header(), body=nd.OpmBody(segment=nd.OpmSegment(metadata=meta, data=data)))


@dataclass
class EphemerisSegment:
    """One OEM segment: object, sim times ``t`` (n,) [s], EME2000 ``r``, ``v`` (n, 3) [m, m/s], covariances as
    ``[(t, 6x6 [m, m/s]), ...]`` in ``cov_frame`` (None: the segment's REF_FRAME), comments."""

    object_name: str
    object_id: str
    t: np.ndarray
    r: np.ndarray
    v: np.ndarray
    covariances: list = field(default_factory=list)
    cov_frame: str = None
    comments: list = field(default_factory=list)


COV_NAMES = ("x", "y", "z", "x_dot", "y_dot", "z_dot")


def _oem_covariance(epoch, cov, frame):
    """OEM covariance block (lower triangle, km^2, km^2/s, km^2/s^2) of a 6x6 [m, m/s] covariance; with ``epoch``
    None the OPM's (no epoch: the state's)."""
    c = np.asarray(cov, dtype=float) / 1e6
    kw = {}
    for i in range(6):
        for j in range(i + 1):
            kind = (nd.PositionCovarianceType if i < 3 else
                    nd.PositionVelocityCovarianceType if j < 3 else nd.VelocityCovarianceType)
            kw[f"c{COV_NAMES[i]}_{COV_NAMES[j]}"] = kind(value=_f(c[i, j]))
    if epoch is None:
        return nd.OpmCovarianceMatrixType(cov_ref_frame=frame, **kw)
    return nd.OemCovarianceMatrixType(epoch=epoch, cov_ref_frame=frame, **kw)


OEM_HERMITE_DEGREE = 7
"""INTERPOLATION_DEGREE of the OEM segments (Hermite: 4 states, positions and velocities)."""


def build_oem(epoch_utc, segments, comments=()):
    """OEM 2.0 with one segment per :class:`EphemerisSegment`, declared ``INTERPOLATION = HERMITE`` of degree 7
    (positions and velocities of 4 neighbouring states; never above the segment's states - 1, as Orekit takes degree
    + 1 states for its Hermite and refuses a segment with fewer): the velocities are the time
    derivative of the positions (:func:`roe_sep.ndm.frames.chief_state`), so a reader's Hermite reproduces the
    trajectory between the states; a Lagrange reader of positions alone loses up to metres at 300 s spacing."""
    out = []
    for s in segments:
        t = np.asarray(s.t, dtype=float)
        if t.size < 2 or np.any(np.diff(t) <= 0.0):
            raise ValueError(f"OEM segment of {s.object_name}: needs >= 2 strictly increasing epochs, got {t.size}")
        meta = nd.OemMetadata(comment=list(s.comments), object_name=s.object_name, object_id=s.object_id,
                              center_name=frames.CENTER, ref_frame=frames.INERTIAL_FRAME,
                              time_system=frames.TIME_SYSTEM, start_time=frames.utc_string(epoch_utc, t[0]),
                              stop_time=frames.utc_string(epoch_utc, t[-1]), interpolation="HERMITE",
                              interpolation_degree=int(min(OEM_HERMITE_DEGREE, t.size - 1)))
        states = [_state_vector(nd.StateVectorAccType, frames.utc_string(epoch_utc, tk), rk, vk)
                  for tk, rk, vk in zip(t, s.r, s.v)]
        covs = [_oem_covariance(frames.utc_string(epoch_utc, tc), c, s.cov_frame) for tc, c in s.covariances]
        out.append(nd.OemSegment(metadata=meta, data=nd.OemData(state_vector=states, covariance_matrix=covs)))
    return nd.Oem(header=_header(comments), body=nd.OemBody(segment=out))


@dataclass
class TrackingPass:
    """One radar pass for a TDM segment: station, pass id, sim times ``t`` (n,) [s], ``z`` (n, 3) [range m,
    azimuth rad (from north towards east), elevation rad], 1-sigma noise [m, rad]."""

    station: str
    pass_id: int
    t: np.ndarray
    z: np.ndarray
    sigma_range: float
    sigma_angle: float
    target: str = "PICOSATELLITE"


SIGMA_RANGE_KEY = "SIGMA_RANGE_M"
SIGMA_ANGLE_KEY = "SIGMA_ANGLE_DEG"


def build_tdm(epoch_utc, passes, comments=()):
    """TDM 2.0, one segment per :class:`TrackingPass`: AZEL angles [deg], RANGE [km], PARTICIPANT_1 the station,
    PARTICIPANT_2 the target, two-way path 1,2,1, receive time tag: RANGE is half the round-trip light time times c
    (:func:`roe_sep.core.od.radar.two_way_look`), the angles those of the received signal.
    The TDM has no keyword for the measurement noise: it goes into metadata comments ``SIGMA_RANGE_M = ...``,
    ``SIGMA_ANGLE_DEG = ...`` (read back by :func:`read_tdm`)."""
    segs = []
    for p in passes:
        t = np.asarray(p.t, dtype=float)
        z = np.asarray(p.z, dtype=float)
        meta = nd.TdmMetadata(
            comment=[f"{SIGMA_RANGE_KEY} = {_f(p.sigma_range)!r}",
                     f"{SIGMA_ANGLE_KEY} = {_f(math.degrees(p.sigma_angle))!r}",
                     "RANGE: two-way light-time range c (tau_up + tau_down) / 2 at the receive time tag, "
                     "no corrections",
                     "ANGLE_1/2: azimuth/elevation of the received signal (the target at reflection), no refraction"],
            track_id=f"{p.station}_PASS_{int(p.pass_id)}", time_system=nd.TimeSystemType.UTC,
            start_time=frames.utc_string(epoch_utc, t[0]), stop_time=frames.utc_string(epoch_utc, t[-1]),
            participant_1=p.station, participant_2=p.target, mode=nd.ModeType.SEQUENTIAL, path="1,2,1",
            timetag_ref=nd.TimetagRefType.RECEIVE, range_units=nd.RangeUnitsType.KM, angle_type=nd.AngleTypeType.AZEL)
        obs = []
        for tk, zk in zip(t, z):
            ep = frames.utc_string(epoch_utc, tk)
            obs.append(nd.TrackingDataObservationType(epoch=ep, range=_f(zk[0]) / 1000.0))
            obs.append(nd.TrackingDataObservationType(epoch=ep, angle_1=nd.AngleType(
                value=_f(math.degrees(zk[1])), units=nd.AngleUnits.DEG)))
            obs.append(nd.TrackingDataObservationType(epoch=ep, angle_2=nd.AngleType(
                value=_f(math.degrees(zk[2])), units=nd.AngleUnits.DEG)))
        segs.append(nd.TdmSegment(metadata=meta, data=nd.TdmData(observation=obs)))
    return nd.Tdm(header=nd.TdmHeader(comment=list(comments), creation_date=creation_date(), originator=ORIGINATOR),
                  body=nd.TdmBody(segment=segs))


@dataclass
class ConjunctionObject:
    """One CDM object: name, designator, EME2000 state [m, m/s] at TCA, RTN covariance 6x6 [m, m/s] (None: not
    estimated, written as zeros with COVARIANCE_METHOD DEFAULT), maneuverable, comments."""

    name: str
    designator: str
    r: np.ndarray
    v: np.ndarray
    cov_rtn: np.ndarray = None
    maneuverable: bool = True
    comments: list = field(default_factory=list)


CDM_COV = ("r", "t", "n", "rdot", "tdot", "ndot")


def _cdm_covariance(cov):
    c = np.zeros((6, 6)) if cov is None else np.asarray(cov, dtype=float)
    kw = {}
    for i in range(6):
        for j in range(i + 1):
            kind, unit = ((nd.M2Type, nd.M2Units.M_2) if i < 3 else (nd.M2SType, nd.M2SUnits.M_2_S) if j < 3 else
                          (nd.M2S2Type, nd.M2S2Units.M_2_S_2))
            kw[f"c{CDM_COV[i]}_{CDM_COV[j]}"] = kind(value=_f(c[i, j]), units=unit)
    return nd.CdmCovarianceMatrixType(**kw)


def build_cdm(epoch_utc, tca, objects, message_id, comments=()):
    """CDM 1.0 of the closest approach at sim time ``tca`` between two :class:`ConjunctionObject` (object 1 first):
    MISS_DISTANCE [m] and RELATIVE_SPEED [m/s] from their states, the relative state in RTN of object 1."""
    o1, o2 = objects
    rho, rho_dot = frames.inertial_to_rtn(o1.r, o1.v, o2.r, o2.v)
    rel_v = np.asarray(o2.v) - np.asarray(o1.v)
    segs = []
    for which, o in zip((nd.ObjectType.OBJECT1, nd.ObjectType.OBJECT2), objects):
        meta = nd.CdmMetadata(
            comment=list(o.comments), object_value=which, object_designator=o.designator, catalog_name="NONE",
            object_name=o.name, international_designator="UNKNOWN", ephemeris_name="NONE",
            covariance_method=nd.CovarianceMethodType.DEFAULT if o.cov_rtn is None else
            nd.CovarianceMethodType.CALCULATED,
            maneuverable=nd.ManeuverableType.YES if o.maneuverable else nd.ManeuverableType.NO,
            ref_frame=nd.ReferenceFrameType.EME2000)
        sv = nd.CdmStateVectorType(**{k: nd.CdmPositionType(value=_f(o.r[i]) / 1000.0, units=nd.PositionUnits.KM)
                                      for i, k in enumerate("xyz")},
                                   **{k: nd.CdmVelocityType(value=_f(o.v[i]) / 1000.0, units=nd.VelocityUnits.KM_S)
                                      for i, k in enumerate(("x_dot", "y_dot", "z_dot"))})
        segs.append(nd.CdmSegment(metadata=meta, data=nd.CdmData(state_vector=sv,
                                                                covariance_matrix=_cdm_covariance(o.cov_rtn))))
    rel = nd.RelativeMetadataData(
        comment=list(comments), tca=frames.utc_string(epoch_utc, tca),
        miss_distance=nd.LengthType(value=_f(np.linalg.norm(rho)), units=nd.LengthUnits.M),
        relative_speed=nd.DvType(value=_f(np.linalg.norm(rel_v)), units=nd.DvUnits.M_S),
        relative_state_vector=nd.RelativeStateVectorType(
            relative_position_r=nd.LengthType(value=_f(rho[0]), units=nd.LengthUnits.M),
            relative_position_t=nd.LengthType(value=_f(rho[1]), units=nd.LengthUnits.M),
            relative_position_n=nd.LengthType(value=_f(rho[2]), units=nd.LengthUnits.M),
            relative_velocity_r=nd.DvType(value=_f(rho_dot[0]), units=nd.DvUnits.M_S),
            relative_velocity_t=nd.DvType(value=_f(rho_dot[1]), units=nd.DvUnits.M_S),
            relative_velocity_n=nd.DvType(value=_f(rho_dot[2]), units=nd.DvUnits.M_S)))
    header = nd.CdmHeader(creation_date=creation_date(), originator=ORIGINATOR, message_id=message_id)
    return nd.Cdm(header=header, body=nd.CdmBody(relative_metadata_data=rel, segment=segs))


# --- text and files -----------------------------------------------------------------------------------------------
def to_text(message, fmt="xml") -> str:
    """XML or KVN text of a message (the library's writers); XML names its schema (:data:`SCHEMA_LOCATION`)."""
    if fmt not in FORMATS:
        raise ValueError(f"format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    if fmt == "xml":
        return NdmIo().to_string(message, NDMFileFormats.XML, no_namespace_schema_location=SCHEMA_LOCATION)
    # The library's TDM KVN has a blank line between META_STOP and DATA_START; 503.0-B-2 allows blank lines, but
    # stricter readers (ccsds-ndm-py 0.0.9) refuse it there, so the keywords are kept adjacent.
    return NdmIo().to_string(message, NDMFileFormats.KVN).replace("META_STOP\n\nDATA_START", "META_STOP\nDATA_START")


def write_atomic(path, text):
    """Write ``text`` to ``path`` atomically: a temporary file in the same directory, fsync, then rename (a watcher
    sees either no file or the whole file)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes it private; the set is meant to be read by others
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_message(path, message, fmt="xml"):
    """:func:`to_text` then :func:`write_atomic`; returns the path."""
    return write_atomic(path, to_text(message, fmt))


def read_message(source):
    """Message object of an NDM file (XML or KVN, detected by the library) or of its text; NdmError (one line) on
    failure."""
    try:
        if isinstance(source, (str, os.PathLike)) and not str(source).lstrip().startswith(("<", "CCSDS_")):
            return NdmIo().from_path(source)
        return NdmIo().from_string(str(source))
    except Exception as exc:  # noqa: BLE001  (the library raises many kinds: report them as one)
        raise NdmError(" ".join(f"not a readable CCSDS NDM: {exc.__class__.__name__}: {exc}".split())) from None


def _num(x):
    return None if x is None else float(getattr(x, "value", x))


@dataclass(frozen=True)
class Measurement:
    """A radar measurement read from a TDM: sim time [s], station, pass id, z = [range m, az rad, el rad], its
    1-sigma noise [m, rad] and the tracked object (the participant the station's signal comes from)."""

    t: float
    station: str
    pass_id: int
    z: tuple
    sigma_range: float
    sigma_angle: float
    target: str | None = None


def _comment_value(comments, key):
    for c in comments:
        name, sep, value = str(c).partition("=")
        if sep and name.strip().upper() == key:
            return float(value)
    return None


TDM_SPAN_S = 31 * 86400.0
"""The span after the run's epoch a TDM's measurements may fall in [s]: the longest run (a horizon up to 30 days after
the drift-stop, :class:`roe_sep.core.config.MonteCarloConfig`, plus the day before it)."""


def read_tdm(source, epoch_utc, sigma_range=None, sigma_angle=None):
    """Radar measurements of a TDM (file path, text or the message :func:`read_message` read): RANGE with AZEL
    angles, grouped by time tag, read by :func:`roe_sep.ndm.tdm_reader.read_observations` (units, paths,
    corrections, time systems; epochs within :data:`TDM_SPAN_S` after ``epoch_utc``).

    Each measurement: the station is the path's last participant (it receives and points: a two-way path or a
    downlink), its stamp the receive time there (the radar's stamp), the range the one-way range, the target the
    participant before it; the pass id is the number after ``_PASS_`` in TRACK_ID (else the segment's 1-based
    index). Sigmas from the
    ``SIGMA_RANGE_M``/``SIGMA_ANGLE_DEG`` metadata comments, else the ``sigma_range`` [m] / ``sigma_angle`` [rad]
    given here. NdmError naming what is wrong: what the reader refuses, RADEC angles, an uplink path, a time tag
    without all three of range, azimuth and elevation, no measurement at all, or no sigma.
    """
    start = frames.parse_epoch(epoch_utc)
    msg = source if type(source).__name__ in ("Tdm", "TdmType") else read_message(source)
    obs = read_observations(msg, span=(start, start + timedelta(seconds=TDM_SPAN_S)))
    segments = msg.body.segment
    out = []
    for o in obs:
        where = f"TDM segment {o.segment}"
        md = segments[o.segment - 1].metadata
        if o.path[-1] != 1:
            raise NdmError(f"{where}: PATH {','.join(map(str, o.path))} ends at the spacecraft (the station must "
                           "receive)")
        if o.range_m is None or o.angle_1 is None:
            raise NdmError(f"{where}: epoch {frames.utc_string(o.timetag, 0.0)} lacks one of RANGE, ANGLE_1, ANGLE_2")
        if o.angle_type != "AZEL":
            raise NdmError(f"{where}: ANGLE_TYPE {o.angle_type} is not supported for radar measurements (AZEL)")
        sr = _comment_value(md.comment, SIGMA_RANGE_KEY)
        sa = _comment_value(md.comment, SIGMA_ANGLE_KEY)
        sr = sr if sr is not None else sigma_range
        sa = math.radians(sa) if sa is not None else sigma_angle
        if sr is None or sa is None or not (sr > 0 and sa > 0 and math.isfinite(sr) and math.isfinite(sa)):
            raise NdmError(f"{where}: no positive measurement sigma (comments {SIGMA_RANGE_KEY}, {SIGMA_ANGLE_KEY})")
        _, sep, tail = str(getattr(md, "track_id", None) or "").rpartition("_PASS_")
        pass_id = int(tail) if sep and tail.isdigit() and int(tail) < 2**32 else o.segment
        t = (o.receive_epoch - start).total_seconds()
        out.append(Measurement(t, o.participants[-1], pass_id, (o.range_m, o.angle_1, o.angle_2), float(sr),
                               float(sa), o.participants[-2]))
    if not out:
        raise NdmError("the TDM holds no RANGE/ANGLE_1/ANGLE_2 measurement")
    out.sort(key=lambda m: (m.t, m.station))
    return out
