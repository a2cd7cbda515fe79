"""Operational plan of the separation day (seed 001 Sec. 5): contacts, radar passes, eclipses, camera Sun angle and
the ranked candidate separation windows.

Astronomy with skyfield: the DE421 ephemeris and the Earth-orientation file come from the ``skyfield-data`` package
and the timescale from skyfield's built-in tables, so nothing is downloaded at run time. The carrier orbit is a TLE
(SGP4) or, without one, mean elements turned into an SGP4 element set (``sgp4init``; circular, sun-synchronous, the
ascending node placed at the configured local time).

Rules of seed 001 Sec. 5 (and Sec. 2.1 items 3-4) applied to every candidate, one ejection instant per pole
crossing (u = 90 or 270 deg) inside a ground contact:

1. inside a ground-station contact (the footage is downlinked live; overlaps reported);
2. sunlit (the RGB camera records the ejection);
3. the camera is not blinded: Sun at least ``sun_exclusion_deg`` from the boresight (the ejection direction);
4. the first TIRA pass no earlier than ``radar_min_delay_orbits`` (5 km along-track needed to separate the two
   objects), ideally ~2 orbits later, with a backup pass shortly after it;
5. a confirming radar pass ~12 h after the first (reliable orbit determination over 12 h).

Hard rules (1-4 first pass) make a window eligible; the rest rank it (backup, confirmation, delay closest to
2 orbits, the longest remaining contact).
"""

import datetime as _dt
import math
import sys
from dataclasses import dataclass, replace
from os import PathLike
from pathlib import Path
from typing import TYPE_CHECKING, TextIO

import numpy as np
from numpy.typing import ArrayLike

from ...errors import ConfigError, show
from ..constants import MU_EARTH, R_EARTH
from ..od.radar import raan_from_sun
from ..relmotion.dynamics import sun_synchronous_inclination
from ..relmotion.orbit import angle_between, mean_motion, orbital_period, semi_major_axis

if TYPE_CHECKING:  # skyfield is imported where it is used (it loads ephemeris data)
    from skyfield.jpllib import SpiceKernel
    from skyfield.sgp4lib import EarthSatellite
    from skyfield.timelib import Time, Timescale
    from skyfield.toposlib import GeographicPosition


def config_file(name: str) -> Path:
    """A file of the package's ``config/``: the source tree's (``<repo>/config``, the editable install), else the
    installed one, ``<prefix>/share/roe_sep/config`` (setup.py data_files: a colcon install, where this module is
    ``<prefix>/lib/pythonX.Y/site-packages/roe_sep/core/ops/plan.py``, or a pip install into ``sys.prefix``)."""
    here = Path(__file__).resolve()
    prefix = here.parents[min(6, len(here.parents) - 1)]
    candidates = [here.parents[3] / "config" / name, prefix / "share" / "roe_sep" / "config" / name,
                  Path(sys.prefix) / "share" / "roe_sep" / "config" / name]
    return next((c for c in candidates if c.is_file()), candidates[0])


DEFAULT_OPS_CONFIG = config_file("ops.yaml")
MIN_PERIGEE = 100e3  # m: a TLE whose perigee is lower describes no orbit
MAX_TLE_AGE_DAYS = 30.0  # SGP4 element sets degrade within days (drag); a plan this far from the epoch is refused


@dataclass(frozen=True)
class OpsConfig:
    stations: dict  # code -> {name, lat_deg, lon_deg, height_m, min_elevation_deg}
    radar: dict
    camera: dict
    rules: dict
    orbit: dict
    tle: tuple | None = None  # (line1, line2)


# every numeric key of config/ops.yaml: (lo, hi, lo_open, hi_open, unit); a key outside its range is refused
_SITE_KEYS = {"lat_deg": (-90.0, 90.0, False, False, "deg"), "lon_deg": (-180.0, 360.0, False, False, "deg"),
              "height_m": (-500.0, 9000.0, False, False, "m"), "min_elevation_deg": (0.0, 90.0, False, True, "deg")}
_RULE_KEYS = {"pole_tolerance_deg": (0.0, 45.0, False, False, "deg"),
              "radar_min_delay_orbits": (0.0, 30.0, False, False, "orbits"),
              "radar_target_delay_orbits": (0.0, 30.0, False, False, "orbits"),
              "radar_backup_max_h": (0.0, 48.0, False, False, "h"), "confirm_after_h": (0.0, 48.0, False, False, "h"),
              "confirm_before_h": (0.0, 72.0, False, False, "h"), "time_step_s": (0.0, 600.0, True, False, "s")}
_CAMERA_KEYS = {"sun_exclusion_deg": (0.0, 180.0, False, False, "deg")}
_ORBIT_KEYS = {"altitude_m": (150e3, 2000e3, False, False, "m"), "inclination_deg": (0.0, 180.0, True, True, "deg"),
               "ltan_h": (0.0, 24.0, False, True, "h"), "u0_deg": (-360.0, 360.0, False, False, "deg")}


def _check_section(where, section, keys, required=(), other=()):
    """Refuse unknown keys and numbers out of range in one mapping of the ops configuration (ConfigError)."""
    from ...checks import check_number

    unknown = sorted(set(section) - set(keys) - set(other))
    if unknown:
        raise ConfigError(f"{where}: unknown key(s) {unknown}; known keys: {sorted(set(keys) | set(other))}")
    missing = [k for k in required if k not in section]
    if missing:
        raise ConfigError(f"{where}: missing key(s) {missing}")
    for key, (lo, hi, lo_open, hi_open, unit) in keys.items():
        if key in section and not (key == "inclination_deg" and section[key] is None):
            try:
                check_number(f"{where}.{key}", section[key], lo, hi, lo_open=lo_open, hi_open=hi_open, unit=unit)
            except ValueError as exc:
                raise ConfigError(str(exc)) from None


def ops_config_from_dict(data: dict) -> OpsConfig:
    """Validate a parsed ops YAML: every section, key and number is checked (ConfigError naming the key)."""
    if not isinstance(data, dict):
        raise ConfigError(f"expected a mapping at the top level, got {type(data).__name__}")
    sections = ("stations", "radar", "camera", "rules", "orbit")
    unknown = sorted(set(data) - set(sections))
    if unknown:
        raise ConfigError(f"unknown section(s) {unknown}; known: {list(sections)}")
    for section in sections:
        if not isinstance(data.get(section), dict):
            raise ConfigError(f"section '{section}' missing or not a mapping")
    for group in ("stations", "radar"):
        if not data[group]:
            raise ConfigError(f"{group}: at least one site is required")
        for code, st in data[group].items():
            if not isinstance(st, dict):
                raise ConfigError(f"{group}.{code}: expected a mapping of {sorted(_SITE_KEYS)}")
            _check_section(f"{group}.{code}", st, _SITE_KEYS, required=tuple(_SITE_KEYS), other=("name",))
    _check_section("camera", data["camera"], _CAMERA_KEYS, other=("boresight_rtn",))
    b = data["camera"].get("boresight_rtn", "ejection")
    if b != "ejection":
        vec = b if isinstance(b, list) and len(b) == 3 else None
        if vec is None or any(isinstance(x, bool) or not isinstance(x, (int, float)) for x in vec) \
                or not np.all(np.isfinite(vec)) or np.linalg.norm(vec) == 0:
            raise ConfigError(f"camera.boresight_rtn: expected 'ejection' or three finite numbers [R, T, N] not all "
                              f"zero, got {show(b)}")
    _check_section("rules", data["rules"], _RULE_KEYS)
    rules = data["rules"]
    if rules.get("confirm_before_h", 16.0) <= rules.get("confirm_after_h", 11.0):
        raise ConfigError(f"rules.confirm_before_h ({rules.get('confirm_before_h', 16.0)}) must be larger than "
                          f"rules.confirm_after_h ({rules.get('confirm_after_h', 11.0)})")
    _check_section("orbit", data["orbit"], _ORBIT_KEYS, required=("altitude_m", "ltan_h"))
    return OpsConfig(data["stations"], data["radar"], data["camera"], data["rules"], data["orbit"])


def load_ops_config(path: str | PathLike | None = None) -> OpsConfig:
    """Read ``config/ops.yaml`` (or ``path``); every missing or unknown section, key or bad number is named."""
    from ..config import load_yaml_config

    return load_yaml_config(Path(path) if path else DEFAULT_OPS_CONFIG, ops_config_from_dict, "ops configuration")


def check_tle_checksum(path: str | PathLike, number: int, line: str) -> None:
    """ValueError naming ``line`` ``number`` (1 or 2) of the TLE in ``path`` unless its column 69 holds the
    modulo-10 checksum of columns 1-68 (digits count their value, each minus sign 1; sgp4's ``compute_checksum``).

    Parameters
    ----------
    path : str or os.PathLike
        The TLE file (named in the error).
    number : int
        The line's number in the TLE, 1 or 2.
    line : str
        The element line: 69 characters, the last its checksum digit.

    Returns
    -------
    None
    """
    from sgp4.io import compute_checksum

    given = line[68:69]
    if len(line) != 69 or not given.isdigit():
        raise ValueError(f"--tle {path}: line {number} is {len(line)} characters long, not 69 ending in its checksum "
                         "digit")
    if int(given) != compute_checksum(line):
        raise ValueError(f"--tle {path}: line {number} fails its checksum (column 69 says {given}, the line sums to "
                         f"{compute_checksum(line)} modulo 10)")


def read_tle(path: str | PathLike) -> tuple[str, str]:
    """The two element lines of a TLE file (an optional name line is skipped); each line's checksum checked, then
    the elements by SGP4's parser."""
    from sgp4.api import Satrec

    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as exc:
        raise ValueError(f"--tle {path}: cannot read it: {exc.strerror}") from None
    except UnicodeDecodeError:
        raise ValueError(f"--tle {path}: not a text file") from None
    lines = [ln.rstrip() for ln in text.splitlines() if ln.strip()]
    l1 = [ln for ln in lines if ln.startswith("1 ")]
    l2 = [ln for ln in lines if ln.startswith("2 ")]
    if len(l1) != 1 or len(l2) != 1:
        raise ValueError(f"--tle {path}: expected one TLE (lines starting with '1 ' and '2 ')")
    for number, line in ((1, l1[0]), (2, l2[0])):
        check_tle_checksum(path, number, line)
    try:
        sat = Satrec.twoline2rv(l1[0], l2[0])
    except Exception as exc:  # noqa: BLE001  (sgp4 raises ValueError or IndexError on malformed lines)
        raise ValueError(f"--tle {path}: not a valid TLE ({exc})") from None
    if not (math.isfinite(sat.no_kozai) and sat.no_kozai > 0 and 0 <= sat.ecco < 1):
        raise ValueError(f"--tle {path}: not a valid TLE (mean motion {sat.no_kozai}, eccentricity {sat.ecco})")
    a = (MU_EARTH / (sat.no_kozai / 60.0) ** 2) ** (1.0 / 3.0)  # m, from the mean motion [rad/min]
    perigee = a * (1.0 - sat.ecco) - R_EARTH
    if perigee < MIN_PERIGEE:
        raise ValueError(f"--tle {path}: perigee altitude {perigee / 1e3:.0f} km (mean motion "
                         f"{sat.no_kozai * 1440 / (2 * math.pi):.3f} rev/day) is below {MIN_PERIGEE / 1e3:.0f} km: "
                         "not an orbit")
    return l1[0], l2[0]


def tle_epoch(cfg: OpsConfig) -> _dt.datetime:
    """The epoch of the configured TLE (UTC)."""
    from sgp4.api import Satrec
    from sgp4.conveniences import sat_epoch_datetime

    return sat_epoch_datetime(Satrec.twoline2rv(*cfg.tle))


def with_tle(cfg: OpsConfig, path: str | PathLike) -> OpsConfig:
    """``cfg`` with the TLE of the file ``path`` (:func:`read_tle`)."""
    return replace(cfg, tle=read_tle(path))


def _skyfield():
    import warnings

    with warnings.catch_warnings():  # skyfield_data warns about its IERS file; only DE421 is used from it
        warnings.simplefilter("ignore", RuntimeWarning)
        from skyfield_data import get_skyfield_data_path

        data_dir = get_skyfield_data_path()
    from skyfield.api import load
    from skyfield.jpllib import SpiceKernel

    ts = load.timescale(builtin=True)
    eph = SpiceKernel(str(Path(data_dir) / "de421.bsp"))
    return ts, eph


def carrier_satellite(cfg: OpsConfig, epoch: _dt.datetime, ts: "Timescale", eph: "SpiceKernel") -> "EarthSatellite":
    """skyfield EarthSatellite of the carrier: from the TLE, or mean elements via ``sgp4init`` at ``epoch``.

    Parameters
    ----------
    cfg : OpsConfig
        The TLE, or the orbit (altitude, LTAN) of the mean elements.
    epoch : datetime.datetime
        The epoch (UTC) of the mean elements without a TLE.
    ts : skyfield.timelib.Timescale
        The time scale.
    eph : skyfield.jpllib.SpiceKernel
        The ephemeris (the Sun's position sets the node of the LTAN).

    Returns
    -------
    skyfield.sgp4lib.EarthSatellite
        The carrier, propagated by SGP4.
    """
    from sgp4.api import WGS72, Satrec
    from skyfield.api import EarthSatellite

    if cfg.tle:
        return EarthSatellite(cfg.tle[0], cfg.tle[1], "carrier", ts)
    o = cfg.orbit
    a = float(semi_major_axis(float(o["altitude_m"])))
    inc = float(sun_synchronous_inclination(a)) if o.get("inclination_deg") is None else math.radians(
        float(o["inclination_deg"]))
    t = ts.from_datetime(epoch)
    ra, _, _ = (eph["earth"].at(t).observe(eph["sun"])).radec(epoch="date")
    raan = float(raan_from_sun(ra.radians, float(o["ltan_h"])))
    n_rad_min = float(mean_motion(a)) * 60.0
    sat = Satrec()
    jd_epoch = t.tt - 2433281.5 - (t.tt - t.ut1)  # days since 1949-12-31 00:00 UT
    sat.sgp4init(WGS72, "i", 1, jd_epoch, 0.0, 0.0, 0.0, 1e-7, 0.0, inc, math.radians(float(o.get("u0_deg", 0.0))),
                 n_rad_min, raan)
    return EarthSatellite.from_satrec(sat, ts)


def intervals(mask: ArrayLike, times: list) -> list[tuple]:
    """[start, end] pairs of the runs where boolean ``mask`` is true on the grid ``times`` (datetimes)."""
    m = np.asarray(mask, dtype=bool)
    edges = np.flatnonzero(np.diff(m.astype(int)))
    starts = ([0] if m[0] else []) + [i + 1 for i in edges if not m[i]]
    ends = [i for i in edges if m[i]] + ([len(m) - 1] if m[-1] else [])
    return [(times[s], times[e]) for s, e in zip(starts, ends)]


def argument_of_latitude(r: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Osculating argument of latitude ``(N,)`` [rad] from inertial position/velocity ``(3, N)`` (any consistent
    units): angle of r from the node."""
    h = np.cross(r, v, axis=0)
    node = np.array([-h[1], h[0], np.zeros_like(h[0])])
    node = node / np.linalg.norm(node, axis=0)
    hn = h / np.linalg.norm(h, axis=0)
    y = np.cross(hn, node, axis=0)
    return np.arctan2(np.sum(r * y, axis=0), np.sum(r * node, axis=0)) % (2.0 * math.pi)


def rtn_to_inertial(r: np.ndarray, v: np.ndarray, vec_rtn: ArrayLike) -> np.ndarray:
    """Inertial direction ``(3, N)`` of an RTN vector (R = r/|r|, N = h/|h|, T = N x R).

    Parameters
    ----------
    r, v : numpy.ndarray, shape (3, N)
        Inertial position and velocity (any consistent units).
    vec_rtn : array_like, shape (3,)
        The vector's R, T, N components.

    Returns
    -------
    numpy.ndarray, shape (3, N)
        The vector in the inertial frame, in the unit of ``vec_rtn``.
    """
    rh = r / np.linalg.norm(r, axis=0)
    h = np.cross(r, v, axis=0)
    nh = h / np.linalg.norm(h, axis=0)
    th = np.cross(nh, rh, axis=0)
    return vec_rtn[0] * rh + vec_rtn[1] * th + vec_rtn[2] * nh


def passes(sat: "EarthSatellite", site: "GeographicPosition", t0: "Time", t1: "Time", min_el: float) -> list[tuple]:
    """Visibility passes (rise, set, max elevation [deg]) of ``sat`` above ``min_el`` at ``site``.

    Parameters
    ----------
    sat : skyfield.sgp4lib.EarthSatellite
        The satellite.
    site : skyfield.toposlib.GeographicPosition
        The ground station.
    t0, t1 : skyfield.timelib.Time
        The window.
    min_el : float
        The least elevation [deg].

    Returns
    -------
    list of (Time, Time, float)
        Rise, set and maximum elevation [deg] of each pass; one in progress at ``t0`` or ``t1`` is cut there.
    """
    t, ev = sat.find_events(site, t0, t1, altitude_degrees=min_el)
    out, rise, peak = [], t0 if len(ev) and ev[0] != 0 else None, 0.0
    for ti, e in zip(t, ev):
        if e == 0:
            rise, peak = ti, 0.0
        elif e == 1 and rise is not None:
            peak = max(peak, (sat - site).at(ti).altaz()[0].degrees)
        elif e == 2 and rise is not None:
            out.append((rise, ti, peak))
            rise = None
    if rise is not None:
        out.append((rise, t1, peak))
    return out


def _iso(t):
    return t.utc_strftime("%Y-%m-%dT%H:%M:%SZ") if hasattr(t, "utc_strftime") else t.strftime("%Y-%m-%dT%H:%M:%SZ")


def plan(cfg: OpsConfig, date: _dt.date, days: float = 2.0, boresight_rtn: ArrayLike | None = None) -> dict:
    """The operational plan from 00:00 UTC of ``date`` for ``days``: contacts, radar passes, eclipses, windows.

    Parameters
    ----------
    cfg : OpsConfig
        Sites, camera, rules and the carrier's orbit or TLE.
    date : datetime.date
        The first day (UTC).
    days : float
        The length of the plan [day], in (0, 7].
    boresight_rtn : array_like, shape (3,), optional
        The camera boresight in RTN (any length); default the configured one (the ejection direction).

    Returns
    -------
    dict
        The plan (times ISO-8601 UTC, angles in deg, durations in s), as ``roe-sep ops --json`` prints it.
    """
    from skyfield.api import wgs84

    if not (isinstance(days, (int, float)) and 0 < days <= 7):
        raise ValueError(f"days must be in (0, 7], got {show(days)}")
    start = _dt.datetime(date.year, date.month, date.day, tzinfo=_dt.timezone.utc)
    if cfg.tle:
        age = (start - tle_epoch(cfg)).total_seconds() / 86400.0
        if not -MAX_TLE_AGE_DAYS <= age <= MAX_TLE_AGE_DAYS - days:
            raise ValueError(f"--tle: the plan from {date.isoformat()} (+{days:g} d) lies {age:+.1f} days from the TLE "
                             f"epoch {tle_epoch(cfg):%Y-%m-%d %H:%M} UTC; SGP4 predictions are allowed within "
                             f"{MAX_TLE_AGE_DAYS:g} days of it")
    ts, eph = _skyfield()
    t0, t1 = ts.from_datetime(start), ts.from_datetime(start + _dt.timedelta(days=days))
    sat = carrier_satellite(cfg, start, ts, eph)
    rules = cfg.rules
    period = float(orbital_period(semi_major_axis(float(cfg.orbit["altitude_m"])))) if not cfg.tle else \
        2.0 * math.pi / (sat.model.no_kozai / 60.0)

    def site(s):
        return wgs84.latlon(s["lat_deg"], s["lon_deg"], elevation_m=s["height_m"])

    def pass_list(sites, key):
        """Every pass above each site's minimum elevation, in time order."""
        out = [{key: code, "start": _iso(rise), "end": _iso(set_), "t_start": rise.tt, "t_end": set_.tt,
                "duration_s": float((set_.tt - rise.tt) * 86400.0), "max_elevation_deg": float(peak)}
               for code, s in sites.items()
               for rise, set_, peak in passes(sat, site(s), t0, t1, s["min_elevation_deg"])]
        return sorted(out, key=lambda c: c["t_start"])

    contacts = pass_list(cfg.stations, "station")
    radar = pass_list(cfg.radar, "radar")

    step = float(rules.get("time_step_s", 20.0))
    grid = ts.tt_jd(t0.tt + np.arange(0.0, days * 86400.0 + step, step) / 86400.0)
    geo = sat.at(grid)
    r, v = geo.position.km, geo.velocity.km_per_s
    sunlit = geo.is_sunlit(eph)
    sun_vec = (eph["sun"] - eph["earth"]).at(grid).position.km - r
    u = argument_of_latitude(r, v)
    bore = np.asarray(boresight_rtn if boresight_rtn is not None else _boresight(cfg), dtype=float)
    sun_angle = np.degrees(angle_between(rtn_to_inertial(r, v, bore), sun_vec, axis=0))
    dts = grid.utc_datetime()
    eclipses = [{"start": _iso(a), "end": _iso(b), "duration_s": (b - a).total_seconds()}
                for a, b in intervals(~sunlit, dts)]

    # candidate ejections: each pole crossing (u = 90 or 270 deg) inside a contact
    tol = math.radians(float(rules.get("pole_tolerance_deg", 0.0)))
    windows = []
    for pole, target in (("north", math.pi / 2), ("south", 3 * math.pi / 2)):
        d = (u - target + math.pi) % (2 * math.pi) - math.pi
        idx = np.flatnonzero((d[:-1] < 0) & (d[1:] >= 0))
        for i in idx:
            frac = -d[i] / (d[i + 1] - d[i])
            tt = grid.tt[i] + frac * step / 86400.0
            # a window opens tol before the crossing: report the crossing itself (the design's u1)
            inside = [c for c in contacts if c["t_start"] <= tt <= c["t_end"]]
            if not inside:
                continue
            j = i if frac < 0.5 else i + 1
            windows.append(_judge(tt, pole, inside, radar, bool(sunlit[j]), sun_angle=float(sun_angle[j]),
                                  period=period, rules=rules,
                                  camera=cfg.camera, ts=ts, tol=tol))
    windows.sort(key=lambda w: (not w["eligible"], -w["score"]))
    for k, w in enumerate(windows, 1):
        w["rank"] = k
    for c in contacts + radar:
        c.pop("t_start")
        c.pop("t_end")
    return {
        "date": date.isoformat(),
        "days": days,
        "orbit": "tle" if cfg.tle else {**cfg.orbit, "period_s": period},
        "period_s": period,
        "camera_boresight_rtn": bore.tolist(),
        "contacts": contacts,
        "radar_passes": radar,
        "eclipses": eclipses,
        "windows": windows,
        "ephemeris": "DE421 (skyfield-data), builtin timescale",
    }


def _boresight(cfg: OpsConfig):
    b = cfg.camera.get("boresight_rtn", "ejection")
    if b == "ejection":
        from ..separation.multi_impulse import design

        dv = design().dv1_rtn
        return dv / np.linalg.norm(dv)
    vec = np.asarray(b, dtype=float)
    if vec.shape != (3,) or not np.all(np.isfinite(vec)) or np.linalg.norm(vec) == 0:
        raise ValueError(f"camera.boresight_rtn must be 'ejection' or three finite numbers, got {show(b)}")
    return vec / np.linalg.norm(vec)


def _judge(tt, pole, inside, radar, sunlit, *, sun_angle, period, rules, camera, ts, tol):
    """Apply the seed 001 Sec. 5 rules to one candidate ejection at TT Julian date ``tt``."""
    t_iso = _iso(ts.tt_jd(tt))
    reasons, eligible = [], True
    stations = [c["station"] for c in inside]
    remaining = max((c["t_end"] - tt) * 86400.0 for c in inside)
    reasons.append(f"inside contact of {'+'.join(stations)} ({remaining / 60:.1f} min left)")
    reasons.append(f"{pole} pole, u = {90 if pole == 'north' else 270} deg")
    if sunlit:
        reasons.append("sunlit")
    else:
        reasons.append("REJECT: in eclipse (camera cannot record)")
        eligible = False
    excl = float(camera.get("sun_exclusion_deg", 30.0))
    if sun_angle >= excl:
        reasons.append(f"camera not blinded (Sun {sun_angle:.0f} deg from boresight)")
    else:
        reasons.append(f"REJECT: camera blinded (Sun {sun_angle:.0f} deg < {excl:g} deg from boresight)")
        eligible = False
    later = [p for p in radar if p["t_start"] > tt]
    dmin = float(rules.get("radar_min_delay_orbits", 1.5)) * period
    first = next((p for p in later if (p["t_start"] - tt) * 86400.0 >= dmin), None)
    too_early = [p for p in later if (p["t_start"] - tt) * 86400.0 < dmin]
    if too_early:
        reasons.append(f"radar pass at {too_early[0]['start'][11:16]} too early "
                       f"({(too_early[0]['t_start'] - tt) * 24:.2f} h < {dmin / 3600:.2f} h): not yet 5 km apart")
    backup = confirm = None
    score = 0.0
    if first is None:
        reasons.append("REJECT: no radar pass after the minimum delay within the plan")
        eligible = False
    else:
        delay = (first["t_start"] - tt) * 86400.0
        reasons.append(f"first radar pass {first['start'][11:16]} ({delay / period:.2f} orbits later)")
        backup = next((p for p in later if p is not first and 0 < (p["t_start"] - first["t_start"]) * 24
                       <= float(rules.get("radar_backup_max_h", 3.0))), None)
        confirm = next((p for p in later if float(rules.get("confirm_after_h", 11.0))
                        <= (p["t_start"] - first["t_start"]) * 24 <= float(rules.get("confirm_before_h", 16.0))), None)
        reasons.append(f"backup radar pass {backup['start'][11:16]}" if backup else "no backup radar pass")
        reasons.append(f"confirming radar pass {confirm['start'][:16]}" if confirm else "no confirming pass ~12 h on")
        target = float(rules.get("radar_target_delay_orbits", 2.0)) * period
        score = 2.0 * (backup is not None) + 2.0 * (confirm is not None) - abs(delay - target) / period \
            + remaining / 600.0
    return {
        "start": t_iso, "station": "+".join(stations), "stations": stations, "pole": pole,
        "contact_remaining_s": float(remaining), "sunlit": sunlit, "sun_angle_deg": sun_angle,
        "first_radar": first["start"] if first else None, "backup_radar": backup["start"] if backup else None,
        "confirm_radar": confirm["start"] if confirm else None, "eligible": eligible, "score": float(score),
        "reasons": reasons, "t_tt": float(tt),
    }


def print_plan(rep: dict, out: TextIO) -> None:
    """Write the plan of :func:`plan` to ``out`` as the human table of ``roe-sep ops``."""
    w = out.write
    w(f"Operational plan {rep['date']} (+{rep['days']:g} d), orbit period {rep['period_s'] / 60:.1f} min, "
      f"{rep['ephemeris']}\n")
    w(f"  contacts: {len(rep['contacts'])}   radar passes: {len(rep['radar_passes'])}   "
      f"eclipses: {len(rep['eclipses'])}\n")
    w("  radar passes: " + ", ".join(f"{p['start'][5:16]}" for p in rep["radar_passes"]) + "\n")
    w("  ranked separation windows:\n")
    for win in rep["windows"][:8]:
        w(f"  {win['rank']:2d}. {win['start']}  {win['station']:12s} {'ok ' if win['eligible'] else 'NO '} "
          f"score {win['score']:+.2f}\n")
        for r in win["reasons"]:
            w(f"        - {r}\n")
