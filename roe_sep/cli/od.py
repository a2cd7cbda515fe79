"""``roe-sep od --tdm FILE [FILE...] --carrier-oem FILE [--out DIR] [--json]``: the batch OD of the picosatellite
relative to the carrier from tracking files, offline (:mod:`roe_sep.ndm.offline_od`: the radar_od node's batch least
squares on the TDMs' range and angles, the carrier from its own OEM).

Prints the estimate (mean a*ROE with 1-sigma, the drift rate), the post-fit residuals per pass, their chi-square
per degree of freedom against its 95 % band, and the rejected measurements with their reasons; ``--out`` writes the
estimate with its covariance as an OPM and its prediction as an OEM.
"""

import argparse
import math
from pathlib import Path

from ..core.od.radar import Station
from ..errors import NdmError
from ..ndm import frames
from ..nodes.parameters import RADAR_OD
from .common import emit, finite_float, positive_int

DEFAULTS = {p.name: p.default for p in RADAR_OD}
ROE_NAMES = ("a*da", "a*dl", "a*dex", "a*dey", "a*dix", "a*diy")
MODELS = ("auto", "circular", "osculating")  # auto and roe_sep.ndm.offline_od.MODELS (not imported to build the parser)
PREDICT_STEP_S = 300.0  # s: the run's OD segments' step (ndm.options.Options.od_step)


def station(text):
    """argparse ``type=``: ``NAME,LAT_DEG,LON_DEG,ALT_M`` (geodetic, WGS-84)."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        lat, lon, alt = (float(x) for x in parts[1:])
    except ValueError:
        lat = math.nan
    if len(parts) != 4 or not parts[0] or not (-90 <= lat <= 90 and -180 <= lon <= 360 and -500 <= alt <= 9000):
        raise argparse.ArgumentTypeError("expected NAME,LAT_DEG,LON_DEG,ALT_M (latitude in [-90, 90], longitude in "
                                         f"[-180, 360], height in [-500, 9000] m), got {text!r}")
    return Station(parts[0], math.radians(lat), math.radians(lon), alt)


def utc_epoch(text):
    """argparse ``type=``: an ISO-8601 UTC date-time."""
    try:
        return frames.parse_epoch(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected an ISO-8601 UTC date-time, got {text!r}") from None


def maneuver_epochs(paths):
    """MAN_EPOCH_IGNITION of every maneuver of the OPM files (UTC datetimes)."""
    from ..ndm.messages import read_message
    from ..ndm.tdm_reader import TIME_SYSTEMS, parse_tdm_epoch, to_utc

    out = []
    for p in paths:
        msg = read_message(p)
        if type(msg).__name__ not in ("Opm", "OpmType"):
            raise NdmError(f"{p}: --maneuvers expects an OPM, got {type(msg).__name__.removesuffix('Type').upper()}")
        md, data = msg.body.segment.metadata, msg.body.segment.data
        ts = str(getattr(md.time_system, "value", md.time_system)).strip().upper()
        if ts not in TIME_SYSTEMS:
            raise NdmError(f"{p}: TIME_SYSTEM {ts} is not supported ({', '.join(TIME_SYSTEMS)})")
        out += [to_utc(parse_tdm_epoch(m.man_epoch_ignition), ts).replace(tzinfo=None)
                for m in data.maneuver_parameters]
    return tuple(frames.parse_epoch(e) for e in out)


def cmd_od(args):
    from ..ndm import offline_od as oo

    for path in [*args.tdm, *([args.carrier_oem] if args.carrier_oem else []), *(args.maneuvers or [])]:
        if not Path(path).is_file():
            raise NdmError(f"{path}: no such file")
    if args.carrier_oem is None:
        raise NdmError("no carrier orbit: give the carrier's ephemeris with --carrier-oem FILE (an OEM, EME2000; a "
                       "TDM's tracking of the carrier is not its orbit)")
    if args.since and args.until and args.until <= args.since:
        raise ValueError(f"--until {args.until.isoformat()} is not after --since {args.since.isoformat()}")
    stations = tuple(args.station) if args.station else tuple(
        Station(n, math.radians(la), math.radians(lo), float(h)) for n, la, lo, h in zip(
            DEFAULTS["stations"], DEFAULTS["station_latitudes_deg"], DEFAULTS["station_longitudes_deg"],
            DEFAULTS["station_altitudes_m"]))
    settings = oo.Settings(stations=stations, sigma_range=args.sigma_range, sigma_angle=math.radians(args.sigma_angle),
                           min_pass=args.min_pass, min_passes=args.min_passes,
                           maneuvers=maneuver_epochs(args.maneuvers or []),
                           since=args.since, until=args.until, scale_height=DEFAULTS["density_scale_height_m"],
                           ballistic_ratio=DEFAULTS["drag_ballistic_ratio"], drag=DEFAULTS["od_drag_terms"],
                           edit_p=args.edit_p,
                           model=args.model)
    od = oo.solve(args.tdm, args.carrier_oem, settings, args.carrier, args.target)
    est = oo.estimate(od)
    rep = {"tdm": [str(p) for p in args.tdm], "carrier_oem": str(args.carrier_oem), "model": oo.model_of(od),
           "estimate": {k: est[k] for k in ("epoch", "a_roe_m", "a_roe_sigma_m", "a_da_dot_m_s", "a_da_dot_sigma_m_s",
                                            "covariance_a_roe_m2", "r_m", "v_m_s", "iterations")}
           | {"covariance_eme2000": est["covariance_eme2000"].tolist()},
           "measurements": {"used": len(od.records), "rejected": len(od.rejected),
                            "passes": len({r.pass_id for r in od.records})},
           "passes": oo.pass_residuals(od), "consistency": oo.consistency(od), "rejected": od.rejected, "files": []}
    if args.out:
        rep["files"] = _write(od, est, args)

    def human(r):
        e = r["estimate"]
        m = r["measurements"]
        print(f"roe-sep od: {m['used']} measurements in {m['passes']} passes ({m['rejected']} rejected), "
              f"{e['iterations']} Gauss-Newton iterations")
        print(f"estimate at {e['epoch']} UTC: mean a*ROE [m] relative to the carrier, 1-sigma")
        for name, x, s in zip(ROE_NAMES, e["a_roe_m"], e["a_roe_sigma_m"]):
            print(f"  {name:6s} {x:+14.3f} ± {s:.3f}")
        print(f"  a*da_dot {e['a_da_dot_m_s']:+.4e} ± {e['a_da_dot_sigma_m_s']:.1e} m/s")
        print("post-fit residuals per pass (mean / rms):")
        print(f"  {'pass':24s} {'n':>4s} {'range m':>17s} {'azimuth mdeg':>17s} {'elevation mdeg':>17s}  start")
        for p in r["passes"]:
            print(f"  {p['pass']:24s} {p['n']:4d} {p['range_m_mean']:+8.2f} / {p['range_m_rms']:6.2f} "
                  f"{1e3 * p['az_deg_mean']:+8.2f} / {1e3 * p['az_deg_rms']:6.2f} "
                  f"{1e3 * p['el_deg_mean']:+8.2f} / {1e3 * p['el_deg_rms']:6.2f}  {p['start']}")
        c = r["consistency"]
        print(f"consistency: chi-square {c['chi2']:.1f} / {c['dof']} dof = {c['chi2_per_dof']:.3f}, 95 % band "
              f"[{c['band95'][0]:.3f}, {c['band95'][1]:.3f}]: {'in band' if c['in_band'] else 'OUT OF BAND'}")
        print(f"rejected: {len(r['rejected'])}")
        reasons = {}
        for x in r["rejected"]:
            reasons.setdefault(x["reason"], []).append(x)
        for reason, xs in reasons.items():
            print(f"  {len(xs):4d} {reason} (first {xs[0]['epoch']}, {xs[0]['station']})")
        for f in r["files"]:
            print(f"  wrote {f}")

    emit(rep, args.json, human)
    return 0


def _write(od, est, args):
    """The OPM of the estimate (with its covariance) and the OEM of its prediction, in ``args.out``."""
    from ..ndm.messages import EphemerisSegment, build_oem, build_opm, write_message

    out = Path(args.out)
    name = "PICOSATELLITE"
    comments = [f"roe-sep od: batch OD relative to the carrier from {len(od.records)} measurements, epoch "
                f"{est['epoch']}; covariance: the picosatellite's state given the carrier's (its OEM)",
                f"mean a*ROE [m] = {[round(x, 3) for x in est['a_roe_m']]}, a*da_dot = {est['a_da_dot_m_s']!r} m/s"]
    opm = build_opm(name, f"{name}-OD", od.epoch_utc, est["t_est"], est["r_m"], v=est["v_m_s"], burns=[],
                    spacecraft=None, comments=comments, covariance=est["covariance_eme2000"])
    ext = f".{args.format}"  # as roe-sep export names its files
    paths = [write_message(out / f"od_estimate.opm{ext}", opm, args.format)]
    from ..ndm.offline_od import prediction

    t, r, v = prediction(od, est, args.predict * 3600.0, PREDICT_STEP_S)
    seg = EphemerisSegment(name, f"{name}-OD", t, r, v, [(est["t_est"], est["covariance_eme2000"])],
                           comments=[f"prediction of the roe-sep od estimate at {est['epoch']} (secular model, "
                                     "estimated drift)"])
    paths.append(write_message(out / f"od_prediction.oem{ext}", build_oem(od.epoch_utc, [seg]), args.format))
    return [str(p) for p in paths]


def register(subparsers):
    p = subparsers.add_parser("od", help="relative OD of the picosatellite from TDM files and the carrier's OEM")
    p.add_argument("--tdm", nargs="+", required=True, metavar="FILE", help="tracking data messages (TDM 1.0/2.0, "
                   "KVN or XML): range and AZEL angles of the picosatellite")
    p.add_argument("--carrier-oem", metavar="FILE", help="the carrier's ephemeris (OEM, EME2000; e.g. the "
                   "ephemeris.oem of `roe-sep export`)")
    p.add_argument("--carrier", metavar="NAME", help="the carrier's OBJECT_NAME in the OEM (default: its one "
                   "object other than the tracked one)")
    p.add_argument("--target", metavar="NAME", help="the picosatellite's participant name in the TDMs (default: "
                   "the one object they track)")
    p.add_argument("--maneuvers", nargs="+", metavar="OPM", help="OPM files of the carrier's executed maneuvers: "
                   "measurements before the latest one are not used")
    p.add_argument("--since", type=utc_epoch, help="ISO-8601 UTC: use measurements from this epoch on")
    p.add_argument("--until", type=utc_epoch, help="ISO-8601 UTC: use measurements up to this epoch")
    p.add_argument("--station", type=station, action="append", metavar="NAME,LAT,LON,ALT",
                   help="a station of the TDMs (geodetic deg, deg, m; repeat for several; default: radar_od's, TIRA)")
    p.add_argument("--sigma-range", type=finite_float(1e-3, 1e4, unit="m"), default=DEFAULTS["sigma_range_m"],
                   help="m, range 1-sigma of a TDM without SIGMA_RANGE_M (default 10)")
    p.add_argument("--sigma-angle", type=finite_float(1e-6, 0.9, unit="deg"), default=DEFAULTS["sigma_angle_deg"],
                   help="deg, angle 1-sigma of a TDM without SIGMA_ANGLE_DEG (default 0.01)")
    p.add_argument("--min-pass", type=positive_int, default=DEFAULTS["min_pass_measurements"],
                   help="measurements for a pass to count (default 5)")
    p.add_argument("--min-passes", type=positive_int, default=DEFAULTS["passes_required"],
                   help="counted passes the OD needs (default 2, radar_od's passes_required)")
    p.add_argument("--edit-p", type=finite_float(0.0, 0.5, lo_open=True), default=1e-4,
                   help="probability of rejecting a consistent measurement (chi-square, 3 dof; default 1e-4)")
    p.add_argument("--model", choices=MODELS, default="auto",
                   help="measurement model: circular (radar_od's: the carrier's mean near-circular elements as "
                   "osculating and the linear ROE map; a closed-loop run's files), osculating (the carrier's OEM "
                   "states and Brouwer mean elements, the osculating difference of the two spacecraft's mean "
                   "elements; real tracking, files of a numerical propagator) or auto (default: circular for a "
                   "carrier OEM of roe_sep, ORIGINATOR ROE_SEP; osculating for any other)")
    p.add_argument("--predict", type=finite_float(0.0, 720.0, lo_open=True, unit="h"), default=24.0,
                   help="h, span of the OEM prediction (default 24)")
    p.add_argument("--out", help="directory for od_estimate.opm.xml and od_prediction.oem.xml (.kvn with --format kvn)")
    p.add_argument("--format", choices=("xml", "kvn"), default="xml", help="NDM/XML (default) or KVN")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_od)
