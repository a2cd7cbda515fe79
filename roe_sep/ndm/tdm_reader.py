"""Range and angle observations of a Tracking Data Message as a station sends it (CCSDS 503.0-B-2, TDM 2.0; TDM 1.0
files too, which ``ccsds-ndm`` reads into its 1.0 model: a keyword missing there is taken as absent).

What is read (:func:`read_observations`), per segment and per time tag: ``RANGE`` (``RANGE_UNITS`` km, s or RU),
``ANGLE_1``/``ANGLE_2`` (``ANGLE_TYPE`` AZEL or RADEC), on a one-way (``PATH = a,b``) or two-way (``PATH = a,b,a``)
path, time tags in UTC, TAI, GPS or TT. What the values become is one :class:`Observation` each (SI, UTC).

What is refused, with one :class:`~roe_sep.errors.NdmError` line naming the keyword and its value: any other time
system, angle type or path (three-way, relays, ``PATH_1``/``PATH_2``), a segment without range or angles (Doppler
only, clocks, meteo), RU without an S- or X-band transmit frequency, a ``RANGE_MODULUS`` that leaves a station's
range ambiguous, an epoch outside the span the file is used for.
"""

import dataclasses
import math
from dataclasses import dataclass
from datetime import datetime, timedelta, timezone

from ..errors import NdmError, show
from . import frames

C_LIGHT = 299792458.0
"""Speed of light in vacuum [m/s] (IAU/SI)."""
TIME_SYSTEMS = ("UTC", "TAI", "GPS", "TT")
GPS_MINUS_TAI_S = -19.0
"""GPS time = TAI - 19 s (IS-GPS-200)."""
TT_MINUS_TAI_S = 32.184
"""TT = TAI + 32.184 s (IAU 1991 Resolution A4)."""
ANGLE_TYPES = ("AZEL", "RADEC")
RADEC_FRAMES = ("EME2000", "ICRF", "GCRF")
RANGE_UNITS = ("KM", "S", "RU")
RU_FACTOR = {"S": 0.5, "X": 221.0 / (749.0 * 2.0)}
"""Range units per cycle of the uplink frequency, by uplink band: 1 RU = 1 / (K f_T) s of round-trip light time
(the DSN range unit, to which CCSDS 503.0-B-2's ``RANGE_UNITS = RU`` refers)."""
BANDS_HZ = {"S": (2.0e9, 4.0e9), "X": (7.0e9, 8.5e9)}
MIN_UNAMBIGUOUS_M = 1.0e7
"""A RANGE_MODULUS below this one-way range [m] leaves a station's range to a LEO satellite ambiguous."""
MEASUREMENTS = ("range", "angle_1", "angle_2")
"""The data keywords read; the others (Doppler, frequencies, meteo...) are left aside, TRANSMIT_FREQ_n serving RU."""


@dataclass(frozen=True)
class Observation:
    """One time tag of a TDM segment, as the OD needs it.

    ``timetag``: the file's time tag (UTC), at the participant ``timetag_ref`` says: ``TRANSMIT`` (the path's first
    participant sends) or ``RECEIVE`` (its last receives). ``epoch``: when the signal is at the spacecraft (the
    path's middle participant; a one-way path's other end than PARTICIPANT_1), the epoch of the geometry.
    ``receive_epoch``: when the path's last participant receives. ``range_m``: the one-way geometric range [m]
    (two-way: half the round-trip light-time range), corrections and delays applied; None without RANGE.
    ``angle_1``/``angle_2`` [rad]: azimuth/elevation (AZEL) or right ascension/declination (RADEC, in
    ``reference_frame``); None without angles. ``path``: participant numbers; ``participants``: their names.
    """

    epoch: datetime
    timetag: datetime
    receive_epoch: datetime
    timetag_ref: str
    path: tuple
    participants: tuple
    range_m: float | None
    angle_type: str | None
    angle_1: float | None
    angle_2: float | None
    reference_frame: str | None
    segment: int


def _get(md, name):
    """A metadata value as plain text or number (the 1.0 model lacks some keywords: None)."""
    value = getattr(md, name, None)
    return getattr(value, "value", value)


def _upper(md, name):
    value = _get(md, name)
    return None if value is None else str(value).strip().upper()


def parse_tdm_epoch(text) -> datetime:
    """Naive datetime of a CCSDS epoch ``YYYY-MM-DDThh:mm:ss[.f]`` or ``YYYY-DDDThh:mm:ss[.f]`` (no time scale)."""
    return frames.parse_epoch(frames.utc_string("2000-01-01T00:00:00", frames.sim_time("2000-01-01T00:00:00", text)))


def to_utc(dt: datetime, time_system: str) -> datetime:
    """UTC of a datetime in ``time_system`` (UTC, TAI, GPS, TT): TAI-UTC from ERFA's leap-second table
    (``eraDat`` via ``erfa.taiutc``), GPS = TAI - 19 s, TT = TAI + 32.184 s."""
    if time_system == "UTC":
        return dt
    import erfa

    shift = {"TAI": 0.0, "GPS": -GPS_MINUS_TAI_S, "TT": -TT_MINUS_TAI_S}[time_system]
    tai = dt + timedelta(seconds=shift)
    sec = tai.second + tai.microsecond * 1e-6
    jd1, jd2 = erfa.dtf2d("TAI", tai.year, tai.month, tai.day, tai.hour, tai.minute, sec)
    u1, u2 = erfa.taiutc(jd1, jd2)
    y, mo, d, hmsf = erfa.d2dtf("UTC", 6, u1, u2)
    h, mi, s, f = (int(x) for x in hmsf)
    return datetime(int(y), int(mo), int(d), h, mi, min(s, 59), f, tzinfo=timezone.utc)


def _path(md, where):
    """The path's participant numbers and the names of all participants; NdmError for what is not one- or
    two-way."""
    for extra in ("path_1", "path_2"):
        if _get(md, extra) is not None:
            raise NdmError(f"{where}: {extra.upper()} {_get(md, extra)} is not supported (one PATH, one- or two-way)")
    text = _get(md, "path")
    names = tuple(_get(md, f"participant_{i}") for i in range(1, 6))
    try:
        path = tuple(int(p) for p in str(text).split(","))
    except ValueError:
        raise NdmError(f"{where}: PATH {text} is not supported (a,b or a,b,a)") from None
    if not (len(path) == 2 and path[0] != path[1] or len(path) == 3 and path[0] == path[2] != path[1]):
        raise NdmError(f"{where}: PATH {text} is not supported (one-way a,b or two-way a,b,a)")
    if path[0] != 1 and path[-1] != 1:
        raise NdmError(f"{where}: PATH {text} does not start or end at PARTICIPANT_1 (the station)")
    if any(not 1 <= p <= 5 or names[p - 1] is None for p in path):
        raise NdmError(f"{where}: PATH {text} names a participant the segment does not define")
    return path, tuple(names[p - 1] for p in path)


def _range_seconds(value, units, freq, band, where, *, legs):
    """Light time [s] along the whole path (``legs`` 1 or 2) of a RANGE value in ``units``: KM (a one-way range, as
    503.0-B-2 gives a range in km on any path), S (the path's light time) or RU (likewise, in range units)."""
    if units == "KM":
        return value * 1000.0 * legs / C_LIGHT
    if units == "S":
        return value
    if freq is None or not freq > 0:
        raise NdmError(f"{where}: RANGE_UNITS RU needs the path's TRANSMIT_FREQ at or before each range")
    band = band or next((b for b, (lo, hi) in BANDS_HZ.items() if lo <= freq <= hi), None)
    if band not in RU_FACTOR:
        raise NdmError(f"{where}: RANGE_UNITS RU with uplink {band or show(freq) + ' Hz'} is not supported (S, X)")
    return value / (RU_FACTOR[band] * freq)


def _metadata(md, where):
    """The segment's checked metadata as a dict (NdmError naming the first keyword refused)."""
    ts = _upper(md, "time_system")
    if ts not in TIME_SYSTEMS:
        raise NdmError(f"{where}: TIME_SYSTEM {ts} is not supported ({', '.join(TIME_SYSTEMS)})")
    angle_type = _upper(md, "angle_type")
    if angle_type is not None and angle_type not in ANGLE_TYPES:
        raise NdmError(f"{where}: ANGLE_TYPE {angle_type} is not supported ({', '.join(ANGLE_TYPES)})")
    frame = _upper(md, "reference_frame")
    if angle_type == "RADEC" and frame not in RADEC_FRAMES:
        raise NdmError(f"{where}: REFERENCE_FRAME {frame} is not supported for RADEC ({', '.join(RADEC_FRAMES)})")
    units = _upper(md, "range_units") or "KM"
    if units not in RANGE_UNITS:
        raise NdmError(f"{where}: RANGE_UNITS {units} is not supported (km, s, RU)")
    ref = _upper(md, "timetag_ref") or "RECEIVE"
    if ref not in ("TRANSMIT", "RECEIVE"):
        raise NdmError(f"{where}: TIMETAG_REF {ref} is not supported (TRANSMIT, RECEIVE)")
    band = _upper(md, "transmit_band")
    applied = _upper(md, "corrections_applied") == "YES"
    path, names = _path(md, where)
    delays = sum(float(_get(md, f"transmit_delay_{p}") or 0.0) for p in path[:-1]) + \
        sum(float(_get(md, f"receive_delay_{p}") or 0.0) for p in path[1:])
    corr = {k: 0.0 if applied else float(_get(md, f"correction_{k}") or 0.0) for k in MEASUREMENTS}
    return dict(ts=ts, angle_type=angle_type, frame=frame, units=units, ref=ref, band=band, path=path, names=names,
                delays=delays, corr=corr, modulus=float(_get(md, "range_modulus") or 0.0))


def _rows(seg, where):
    """Per time tag (in file order): the measurements and the transmit frequency [Hz] in force (FREQ keywords of the
    path's first participant, the latest at or before the tag); the names of the measurement keywords refused."""
    rows, freq, others = {}, {}, set()
    for ob in seg.data.observation:
        for f in dataclasses.fields(ob):
            value = getattr(ob, f.name)
            if f.name == "epoch" or value is None:
                continue
            value = float(getattr(value, "value", value))
            base = f.name.rstrip("0123456789").rstrip("_")
            if f.name in MEASUREMENTS:
                rows.setdefault(ob.epoch, {})[f.name] = value
            elif base == "transmit_freq":
                freq.setdefault(f.name, []).append((parse_tdm_epoch(ob.epoch), value))
            others.add(f.name.upper())
    if not rows:
        kinds = ", ".join(sorted(others)) or "none"
        raise NdmError(f"{where}: no RANGE, ANGLE_1 or ANGLE_2 to read (its data: {kinds})")
    return rows, freq


def _in_force(series, epoch):
    """The value of (datetime, value) pairs at the latest one at or before the CCSDS ``epoch`` (None before the
    first)."""
    if not series:
        return None
    at = parse_tdm_epoch(epoch)
    before = [(e, v) for e, v in series if e <= at]
    return max(before, key=lambda p: p[0])[1] if before else None


def read_observations(msg, span=None) -> list:
    """The :class:`Observation` of every time tag with RANGE or angles of a TDM message (as
    :func:`roe_sep.ndm.messages.read_message` reads it).

    ``span`` (two UTC datetimes or ISO strings, optional): the epochs the file is used for; an observation outside
    refused. Range: the value + CORRECTION_RANGE unless CORRECTIONS_APPLIED = YES, as light time (km / c, s, or RU
    / (K f_T), K of the uplink band), minus the path's TRANSMIT_DELAY/RECEIVE_DELAY, times c / legs (one-way range);
    the epochs follow ±range/c from the time tag (CCSDS 503.0-B-2 §3.3, §3.5). Angles: degrees + CORRECTION_ANGLE_n
    likewise, as radians. NdmError (one line, the keyword and its value) for anything else (module docstring).
    """
    if type(msg).__name__ not in ("Tdm", "TdmType"):
        raise NdmError(f"expected a TDM, got {type(msg).__name__.removesuffix('Type').upper()}")
    lo, hi = (frames.parse_epoch(s) for s in span) if span is not None else (None, None)
    out = []
    for k, seg in enumerate(msg.body.segment, start=1):
        where = f"TDM segment {k}"
        m = _metadata(seg.metadata, where)
        rows, freqs = _rows(seg, where)
        legs = len(m["path"]) - 1
        for tag, row in rows.items():
            try:
                timetag = to_utc(parse_tdm_epoch(tag), m["ts"])
            except (ValueError, KeyError) as exc:
                raise NdmError(f"{where}: {exc}") from None
            if lo is not None and not lo <= timetag <= hi:
                raise NdmError(f"{where}: epoch {tag} {m['ts']} is outside the span {lo.isoformat()} to "
                               f"{hi.isoformat()} the file is used for")
            out.append(_observation(row, tag, timetag, m, k, legs=legs, freqs=freqs))
    return out


def _observation(row, tag, timetag, m, k, *, legs, freqs):
    """One :class:`Observation` of a time tag's ``row`` (metadata ``m``, segment ``k``)."""
    where = f"TDM segment {k}, epoch {tag}"
    rng = row.get("range")
    range_m = None
    if rng is not None:
        value = rng + m["corr"]["range"]
        if m["modulus"] > 0:
            span_s = _range_seconds(m["modulus"], m["units"], _in_force(freqs.get(f"transmit_freq_{m['path'][0]}",
                                                                                 []), tag), m["band"], where, legs=legs)
            if span_s * C_LIGHT / legs < MIN_UNAMBIGUOUS_M:
                raise NdmError(f"{where}: RANGE_MODULUS {show(m['modulus'])} {m['units']} leaves the range "
                               f"ambiguous (under {MIN_UNAMBIGUOUS_M / 1000:.0f} km)")
        freq = _in_force(freqs.get(f"transmit_freq_{m['path'][0]}", []), tag)
        seconds = _range_seconds(value, m["units"], freq, m["band"], where, legs=legs) - m["delays"]
        range_m = seconds * C_LIGHT / legs
        if not (math.isfinite(range_m) and range_m > 0):
            raise NdmError(f"{where}: RANGE {show(rng)} {m['units']} is not a positive range ({show(range_m)} m)")
    a1, a2 = row.get("angle_1"), row.get("angle_2")
    if (a1 is None) != (a2 is None):
        raise NdmError(f"{where}: ANGLE_1 and ANGLE_2 come in pairs")
    if a1 is not None:
        if m["angle_type"] is None:
            raise NdmError(f"{where}: angles without ANGLE_TYPE")
        a1, a2 = (math.radians(a + m["corr"][n]) for a, n in ((a1, "angle_1"), (a2, "angle_2")))
        if not (math.isfinite(a1) and math.isfinite(a2) and abs(a2) <= math.pi / 2):
            raise NdmError(f"{where}: ANGLE_2 {show(math.degrees(a2))} deg is outside [-90, 90]")
        a1 %= 2 * math.pi
    tau = 0.0 if range_m is None else range_m / C_LIGHT  # one-way light time
    transmit = 0.0 if m["ref"] == "TRANSMIT" else -legs * tau  # [s] after the time tag
    at_spacecraft = timetag + timedelta(seconds=transmit + (0.0 if m["path"] == (m["path"][0], 1) else tau))
    receive = timetag + timedelta(seconds=transmit + legs * tau)
    return Observation(epoch=at_spacecraft, timetag=timetag, receive_epoch=receive, timetag_ref=m["ref"],
                       path=m["path"], participants=m["names"], range_m=range_m, angle_type=m["angle_type"],
                       angle_1=a1, angle_2=a2, reference_frame=m["frame"], segment=k)
