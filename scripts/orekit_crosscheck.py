#!/usr/bin/env python3
"""roe_sep checked against Orekit, a tool we did not write (issue 40 part 6), both ways.

**residuals** (our files, Orekit's Earth). Orekit reads a run's OEM and TDM with its own parsers, its IERS 2010
frames and the IERS EOP (UT1 - UTC, polar motion, nutation corrections) of the ``finals2000A`` file that
astropy-iers-data ships (handed to Orekit's DataProvidersManager through a DirectoryCrawler on a temporary
directory: nothing is downloaded; the leap seconds are skyfield's table, :func:`orekit_check.start_orekit`). For
every RANGE of the TDM it computes the range with Orekit's own measurement model (``estimation.measurements.Range``
of a ``GroundStation`` on the WGS-84 ellipsoid of the ITRF) from the OEM state of the tracked participant, with the
light time the TDM declares (``PATH = 1,2,1``: two-way; ``TIMETAG_REF = RECEIVE``: the time tag is the reception).
The OEM is interpolated twice: positions only (Orekit's Hermite interpolator with ``USE_P``, a Lagrange polynomial
of degree ``INTERPOLATION_DEGREE``) and with the velocities (the OEM's own ephemeris propagator, Orekit's
``USE_PV`` Hermite interpolation). The residual is TDM minus Orekit, per pass.

**generate** (Orekit's files, our reader). Orekit propagates a carrier and a picosatellite (its numerical
propagator, Dormand-Prince 8(5,3), the J2 field of EIGEN-5C about the ITRF's pole), generates two-way ranges and
azimuth/elevation from TIRA every 10 s above the elevation mask with seeded Gaussian noise (its measurement
generation package: ``Generator``, ``RangeBuilder``, ``AngularAzElBuilder``, an ``ElevationDetector`` scheduler)
and writes them with its own TDM writer; the carrier's ephemeris with its own OEM writer; the truth (both states at
every time tag, EME2000) as JSON.

    scripts/orekit_crosscheck.py residuals OEM TDM [--json]
    scripts/orekit_crosscheck.py generate --seed N --out DIR [--format kvn|xml] [--hours H]
"""

import argparse
import functools
import json
import math
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import orekit_check  # noqa: E402  (the JVM, the leap seconds and the Earth body, shared)

SIGMA_RANGE_KEY = "SIGMA_RANGE_M"
SIGMA_ANGLE_KEY = "SIGMA_ANGLE_DEG"
ELEVATION_MASK_DEG = 10.0
"""The radar's elevation mask (roe_sep.nodes.parameters: radar ``elevation_mask_deg``)."""
SIGMA_RANGE_M = 10.0
SIGMA_ANGLE_DEG = 0.01
"""The radar's 1-sigma noise (the radar node's ``sigma_range_m`` and ``sigma_angle_deg`` defaults)."""
STEP_S = 10.0
"""The radar's measurement period [s] (the reference run's TDM: a time tag every 10 s)."""
PASS_GAP_S = 600.0
"""Measurements farther apart than this [s] are two passes (a LEO pass lasts under 15 min, passes are >= 90 min
apart)."""
MASS_KG = {"CARRIER": 140.0, "PICOSATELLITE": 1.0}


_CONTEXT = None


def context(finals=None):
    """The Orekit data context of :func:`orekit_check.start_orekit` with the IERS EOP of ``finals`` (a finals2000A
    file; default: astropy-iers-data's), started once per process."""
    global _CONTEXT
    if _CONTEXT is None:
        ctx = orekit_check.start_orekit()
        from java.io import File
        from org.orekit.data import DirectoryCrawler

        if finals is None:
            from astropy_iers_data import IERS_A_FILE as finals
        tmp = tempfile.mkdtemp(prefix="orekit_eop_")
        os.symlink(os.path.abspath(finals), os.path.join(tmp, "finals2000A.all"))  # the name Orekit looks for
        ctx.getDataProvidersManager().addProvider(DirectoryCrawler(File(tmp)))
        _CONTEXT = ctx
    return _CONTEXT


@functools.lru_cache(maxsize=1)
def eop_span(ctx):
    """(first, last) UTC ISO dates of the EOP Orekit loaded (IERS 2010)."""
    from org.orekit.utils import IERSConventions

    eop = ctx.getFrames().getEOPHistory(IERSConventions.IERS_2010, False)
    utc = ctx.getTimeScales().getUTC()
    return str(eop.getStartDate().toString(utc)), str(eop.getEndDate().toString(utc))


def ground_station(ctx, name, lat, lon, alt):
    """Orekit's ``GroundStation`` at geodetic ``lat``/``lon`` [rad], ``alt`` [m] on the WGS-84 ellipsoid of the ITRF
    (IERS 2010 conventions, full EOP with tidal corrections); its offset and clock parameters are zero."""
    from org.orekit.bodies import GeodeticPoint, OneAxisEllipsoid
    from org.orekit.estimation.measurements import GroundStation
    from org.orekit.frames import TopocentricFrame
    from org.orekit.utils import Constants, IERSConventions

    itrf = ctx.getFrames().getITRF(IERSConventions.IERS_2010, False)
    earth = OneAxisEllipsoid(Constants.WGS84_EARTH_EQUATORIAL_RADIUS, Constants.WGS84_EARTH_FLATTENING, itrf)
    return GroundStation(TopocentricFrame(earth, GeodeticPoint(float(lat), float(lon), float(alt)), name))


def _set_reference_dates(station, date):
    """Orekit's station parameter drivers need a reference date before a measurement is computed (values 0)."""
    for getter in dir(station):
        if getter.startswith("get") and getter.endswith("Driver"):
            driver = getattr(station, getter)()
            if driver.getReferenceDate() is None:
                driver.setReferenceDate(date)


def tira(ctx):
    """TIRA as roe_sep places it (:data:`roe_sep.core.od.radar.TIRA`: geodetic, WGS-84)."""
    from roe_sep.core.od.radar import TIRA

    return ground_station(ctx, TIRA.name, TIRA.lat, TIRA.lon, TIRA.alt)


class Segments:
    """The OEM segments of one object, interpolated by Orekit from their states: positions only (``USE_P``, the
    Lagrange polynomial through ``INTERPOLATION_DEGREE + 1`` states centred on the date) or with the velocities
    (the OEM's own ephemeris propagator: Orekit's Hermite interpolation, ``USE_PV``)."""

    def __init__(self, oem, object_id):
        self.segments = []
        for seg in oem.getSegments():
            md = seg.getMetadata()
            if str(md.getObjectID()) != object_id:
                continue
            lines = list(seg.getData().getEphemeridesDataLines())
            self.segments.append((md.getStartTime(), md.getStopTime(), lines, int(md.getInterpolationDegree()),
                                  seg.getInertialFrame(), seg.getMu()))
        if not self.segments:
            raise ValueError(f"the OEM has no segment of {object_id}")
        self.propagator = oem.getSatellites().get(object_id).getPropagator()

    def state(self, date, velocities):
        """Orekit's ``SpacecraftState`` of the object at ``date`` (the segment holding it; the last one at a
        boundary, the post-burn state)."""
        from java.util import ArrayList
        from org.orekit.orbits import CartesianOrbit
        from org.orekit.propagation import SpacecraftState
        from org.orekit.utils import CartesianDerivativesFilter, TimeStampedPVCoordinatesHermiteInterpolator

        if velocities:
            return self.propagator.propagate(date)
        for start, stop, lines, degree, frame, mu in reversed(self.segments):
            if date.durationFrom(start) >= 0.0 and date.durationFrom(stop) <= 0.0:
                n = min(degree + 1, len(lines))
                dt = np.array([line.getDate().durationFrom(date) for line in lines])
                k = int(np.clip(np.searchsorted(dt, 0.0) - n // 2, 0, len(lines) - n))
                sample = ArrayList()
                for line in lines[k:k + n]:
                    sample.add(line)
                pv = TimeStampedPVCoordinatesHermiteInterpolator(n, CartesianDerivativesFilter.USE_P).interpolate(
                    date, sample)
                return SpacecraftState(CartesianOrbit(pv, frame, mu))
        raise ValueError(f"no OEM segment holds {date}")


def _comment_value(comments, key):
    """The number of a ``KEY = value`` comment (Orekit's KVN lexer reads the comment's underscores as blanks)."""
    for c in comments:
        k, _, v = str(c).partition("=")
        if "_".join(k.split()) == key:
            return float(v)
    return None


def range_residuals(ctx, oem_path, tdm_path, station=None, light_time=True):
    """Per TDM segment (pass): TDM RANGE minus Orekit's range of the OEM's tracked object from ``station`` (default
    TIRA), positions-only and with-velocities interpolation; the light time as the segment declares it
    (``light_time`` False: the geometric distance at the time tag instead, a negative control).

    Returns
    -------
    list of dict
        ``track_id``, ``path``, ``timetag_ref``, ``sigma_range_m`` (the segment's ``SIGMA_RANGE_M`` comment),
        ``t`` (s after the pass's first time tag), ``positions`` and ``velocities`` (residuals [m]) per pass.
    """
    from org.orekit.data import DataSource
    from org.orekit.estimation.measurements import ObservableSatellite, Range
    from org.orekit.files.ccsds.ndm import ParserBuilder

    builder = ParserBuilder(ctx)
    oem = builder.buildOemParser().parseMessage(DataSource(str(oem_path)))
    tdm = builder.buildTdmParser().parseMessage(DataSource(str(tdm_path)))
    station = tira(ctx) if station is None else station
    sat = ObservableSatellite(0)
    objects = {}
    out = []
    for seg in tdm.getSegments():
        md = seg.getMetadata()
        path = [int(p) for p in md.getPath()]
        names = {int(k): str(v) for k, v in dict(md.getParticipants()).items()}
        if len(path) == 3 and path[0] == path[2]:
            two_way = True
        elif len(path) == 2:
            two_way = False
        else:
            raise ValueError(f"{md.getTrackId()}: PATH {path} is neither one- nor two-way")
        if str(md.getTimetagRef().name()) != "RECEIVE" or path[-1] != 1:
            raise ValueError(f"{md.getTrackId()}: only ranges received at PARTICIPANT_1 are computed here")
        target = names[path[1]]
        eph = objects.setdefault(target, Segments(oem, target))
        rows = []
        for o in seg.getData().getObservations():
            if str(o.getType().name()) != "RANGE":
                continue
            date = o.getEpoch()
            _set_reference_dates(station, date)
            model = Range(station, two_way, date, 0.0, 1.0, 1.0, sat)  # Orekit: date = reception for two-way
            states = [eph.state(date, v) for v in (False, True)]
            got = [float(o.getMeasurement()) - (
                float(model.estimateWithoutDerivatives([s]).getEstimatedValue()[0]) if light_time else
                float(station.getBaseFrame().getRange(s.getPosition(), s.getFrame(), date))) for s in states]
            rows.append((float(date.durationFrom(seg.getData().getObservations()[0].getEpoch())), *got))
        rows = np.array(rows)
        out.append({"track_id": str(md.getTrackId()), "target": target, "path": path,
                    "timetag_ref": str(md.getTimetagRef().name()),
                    "sigma_range_m": _comment_value(md.getComments(), SIGMA_RANGE_KEY),
                    "t": rows[:, 0].tolist(), "positions": rows[:, 1].tolist(), "velocities": rows[:, 2].tolist()})
    return out


# --- B: Orekit propagates, measures and writes ------------------------------------------------------------------
def scenario_geometry(seed):
    """A seeded geometry of the default scenario (roe_sep's SeparationConfig defaults): the carrier's circular
    sun-synchronous orbit at the scenario's altitude, node at 09:30 LTAN (the sim's ``ltan_hours``), a start epoch in
    the day after the scenario's epoch and an argument of latitude, both uniform; the picosatellite's mean ROE
    those of the scenario's drift-stop design, each drawn about its aimed value: a*dl uniform between the radar's
    separability ``a_dl_min`` and the camera's range ``a_dl_max``, a*|de| and a*|di| uniform within +-50 % of
    ``a_de_f`` and ``a_di_f`` with uniform phases, a*da uniform in +-10 m (the residual drift a drift stop leaves).

    Returns
    -------
    dict
        ``epoch_utc`` (ISO), ``chief_mean`` [a, e, i, raan, argp, M] (m, rad), ``roe`` (dimensionless), ``seed``.
    """
    from datetime import datetime, timedelta

    from roe_sep.core.od.radar import DEFAULT_EPOCH_UTC, julian_date, raan_from_ltan
    from roe_sep.core.relmotion.dynamics import sun_synchronous_inclination
    from roe_sep.core.relmotion.orbit import semi_major_axis
    from roe_sep.core.separation.double_impulse import SeparationConfig

    cfg = SeparationConfig()
    rng = np.random.default_rng(seed)
    a = float(semi_major_axis(cfg.altitude))
    start = datetime.fromisoformat(DEFAULT_EPOCH_UTC) + timedelta(seconds=STEP_S * math.floor(float(rng.uniform(
        0.0, 86400.0)) / STEP_S))  # on the radar's whole-step grid, as the carrier's OEM states
    epoch = start.isoformat()
    chief = np.array([a, 0.0, float(sun_synchronous_inclination(a)), float(raan_from_ltan(9.5, julian_date(epoch))),
                      0.0, float(rng.uniform(0.0, 2.0 * math.pi))])
    de, di = (v * float(rng.uniform(0.5, 1.5)) for v in (cfg.a_de_f, cfg.a_di_f))
    phi_e, phi_i = rng.uniform(0.0, 2.0 * math.pi, 2)
    a_roe = np.array([float(rng.uniform(-10.0, 10.0)), float(rng.uniform(cfg.a_dl_min, cfg.a_dl_max)),
                      de * math.cos(phi_e), de * math.sin(phi_e), di * math.cos(phi_i), di * math.sin(phi_i)])
    return {"seed": int(seed), "epoch_utc": epoch, "chief_mean": chief.tolist(), "roe": (a_roe / a).tolist()}


def _absolute(ctx, iso):
    from org.orekit.time import AbsoluteDate

    return AbsoluteDate(str(iso), ctx.getTimeScales().getUTC())


def numerical_propagator(ctx, position, velocity, date, mass):
    """Orekit's numerical propagator from an EME2000 state: Dormand-Prince 8(5,3) (1 mm position tolerance), the
    J2 term of EIGEN-5C about the ITRF's pole (``J2OnlyPerturbation``)."""
    from org.hipparchus.geometry.euclidean.threed import Vector3D
    from org.hipparchus.ode.nonstiff import DormandPrince853Integrator
    from org.orekit.forces.gravity import J2OnlyPerturbation
    from org.orekit.orbits import CartesianOrbit, OrbitType
    from org.orekit.propagation import SpacecraftState
    from org.orekit.propagation.numerical import NumericalPropagator
    from org.orekit.utils import Constants, IERSConventions, PVCoordinates

    frames = ctx.getFrames()
    orbit = CartesianOrbit(PVCoordinates(Vector3D(*map(float, position)), Vector3D(*map(float, velocity))),
                           frames.getEME2000(), date, Constants.EIGEN5C_EARTH_MU)
    tol = NumericalPropagator.tolerances(1e-3, orbit, OrbitType.CARTESIAN)
    prop = NumericalPropagator(DormandPrince853Integrator(1e-3, 300.0, tol[0], tol[1]))
    prop.setOrbitType(OrbitType.CARTESIAN)
    prop.addForceModel(J2OnlyPerturbation(Constants.EIGEN5C_EARTH_MU, Constants.EIGEN5C_EARTH_EQUATORIAL_RADIUS,
                                          -Constants.EIGEN5C_EARTH_C20,
                                          frames.getITRF(IERSConventions.IERS_2010, False)))
    prop.setInitialState(SpacecraftState(orbit).withMass(float(mass)))
    return prop


def _noise(seed, sigmas):
    from org.hipparchus.linear import MatrixUtils
    from org.hipparchus.random import CorrelatedRandomVectorGenerator, GaussianRandomGenerator, Well19937a

    cov = MatrixUtils.createRealDiagonalMatrix([float(s) ** 2 for s in sigmas])
    return CorrelatedRandomVectorGenerator([0.0] * len(sigmas), cov, 1e-10, GaussianRandomGenerator(
        Well19937a(int(seed))))


def generate_measurements(ctx, ephemeris, station, start, end, seed):
    """Orekit's measurement generation: two-way range and azimuth/elevation of ``ephemeris`` from ``station`` every
    :data:`STEP_S` (whole UTC steps) while its elevation exceeds the mask, with seeded Gaussian noise.

    Returns
    -------
    list of (AbsoluteDate, range m, azimuth rad, elevation rad)
    """
    from org.orekit.estimation.measurements.generation import (
        AngularAzElBuilder,
        EventBasedScheduler,
        GatheringSubscriber,
        Generator,
        RangeBuilder,
        SignSemantic,
    )
    from org.orekit.propagation.events import ElevationDetector
    from org.orekit.propagation.events.handlers import ContinueOnEvent
    from org.orekit.time import FixedStepSelector

    utc = ctx.getTimeScales().getUTC()
    gen = Generator()
    sat = gen.addPropagator(ephemeris)
    sa = math.radians(SIGMA_ANGLE_DEG)
    builders = [RangeBuilder(_noise(seed, [SIGMA_RANGE_M]), station, True, SIGMA_RANGE_M, 1.0, sat),
                AngularAzElBuilder(_noise(seed + 1, [sa, sa]), station, [sa, sa], [1.0, 1.0], sat)]
    for b in builders:
        # a handler that does not stop at the first set, and a check step that misses no pass
        detector = ElevationDetector(station.getBaseFrame()).withConstantElevation(
            math.radians(ELEVATION_MASK_DEG)).withHandler(ContinueOnEvent()).withMaxCheck(STEP_S)
        gen.addScheduler(EventBasedScheduler(b, FixedStepSelector(STEP_S, utc), ephemeris, detector,
                                             SignSemantic.FEASIBLE_MEASUREMENT_WHEN_POSITIVE))
    gathering = GatheringSubscriber()
    gen.addSubscriber(gathering)
    gen.generate(start, end)
    rows = {}
    for m in gathering.getGeneratedMeasurements():
        key = float(m.getDate().durationFrom(start))
        rows.setdefault(key, [m.getDate(), None, None, None])
        value = list(m.getObservedValue())
        if len(value) == 1:
            rows[key][1] = float(value[0])
        else:
            rows[key][2], rows[key][3] = float(value[0]), float(value[1])
    return [tuple(r) for _, r in sorted(rows.items()) if None not in r]


def _passes(rows):
    out, last = [], None
    for r in rows:
        if last is None or r[0].durationFrom(last) > PASS_GAP_S:
            out.append([])
        out[-1].append(r)
        last = r[0]
    return out


def _generator(ctx, fmt, name):
    from java.lang import StringBuilder
    from org.orekit.files.ccsds.utils.generation import KvnGenerator, XmlGenerator
    from org.orekit.utils import Constants

    sb = StringBuilder()
    if fmt == "xml":
        return sb, XmlGenerator(sb, XmlGenerator.DEFAULT_INDENT, name, Constants.JULIAN_DAY, True, None)
    return sb, KvnGenerator(sb, 25, name, Constants.JULIAN_DAY, 0)


def write_tdm(ctx, rows, path, fmt, *, station_name, target):
    """Orekit's TDM writer (TDM 2.0): one segment per pass, ``PATH = 1,2,1``, ``TIMETAG_REF = RECEIVE``, RANGE in km,
    AZEL angles, the noise in the ``SIGMA_RANGE_M``/``SIGMA_ANGLE_DEG`` comments roe_sep's TDMs carry."""
    from java.util import ArrayList
    from org.orekit.files.ccsds.definitions import TimeSystem
    from org.orekit.files.ccsds.ndm import WriterBuilder
    from org.orekit.files.ccsds.ndm.tdm import (
        AngleType,
        Observation,
        ObservationsBlock,
        ObservationType,
        RangeUnits,
        Tdm,
        TdmHeader,
        TdmMetadata,
        TimetagReference,
        TrackingMode,
    )
    from org.orekit.files.ccsds.section import Segment
    from org.orekit.utils import IERSConventions

    header = TdmHeader()
    header.setFormatVersion(2.0)
    header.setCreationDate(rows[0][0])
    header.setOriginator("OREKIT")
    segments = ArrayList()
    for k, p in enumerate(_passes(rows), start=1):
        md = TdmMetadata()
        md.addComment(f"{SIGMA_RANGE_KEY} = {SIGMA_RANGE_M!r}")
        md.addComment(f"{SIGMA_ANGLE_KEY} = {SIGMA_ANGLE_DEG!r}")
        md.addComment("generated by Orekit (numerical propagation, J2; two-way range, AZEL of the received signal)")
        md.setTrackId(f"{station_name}_PASS_{k}")
        md.setTimeSystem(TimeSystem.UTC)
        md.setStartTime(p[0][0])
        md.setStopTime(p[-1][0])
        md.addParticipant(1, station_name)
        md.addParticipant(2, target)
        md.setMode(TrackingMode.SEQUENTIAL)
        md.setPath([1, 2, 1])
        md.setTimetagRef(TimetagReference.RECEIVE)
        md.setRangeUnits(RangeUnits.km)
        md.setAngleType(AngleType.AZEL)
        data = ObservationsBlock()
        for date, rng, az, el in p:
            data.addObservation(Observation(ObservationType.RANGE, date, rng))
            data.addObservation(Observation(ObservationType.ANGLE_1, date, az))
            data.addObservation(Observation(ObservationType.ANGLE_2, date, el))
        segments.add(Segment(md, data))
    tdm = Tdm(header, segments, IERSConventions.IERS_2010, ctx)
    sb, gen = _generator(ctx, fmt, str(path))
    WriterBuilder(ctx).buildTdmWriter().writeMessage(gen, tdm)
    gen.close()
    Path(path).write_text(str(sb.toString()), encoding="utf-8")


def write_oem(ctx, states, path, fmt, *, object_id):
    """Orekit's OEM writer (OEM 2.0, EME2000, UTC): one segment of ``states`` (SpacecraftState), Hermite
    interpolation of degree 7 declared. (The message is built and written whole: Orekit 13.1's
    ``EphemerisOemWriter`` leaves the ``<segment>`` element out of its XML.)"""
    from java.util import ArrayList
    from org.orekit.files.ccsds.definitions import BodyFacade, CenterName, FrameFacade, TimeSystem
    from org.orekit.files.ccsds.ndm import WriterBuilder
    from org.orekit.files.ccsds.ndm.odm import OdmHeader
    from org.orekit.files.ccsds.ndm.odm.oem import InterpolationMethod, Oem, OemData, OemMetadata, OemSegment
    from org.orekit.utils import Constants, IERSConventions

    eme = ctx.getFrames().getEME2000()
    header = OdmHeader()
    header.setFormatVersion(2.0)
    header.setOriginator("OREKIT")
    header.setCreationDate(states[0].getDate())
    md = OemMetadata(7)
    md.setObjectName(object_id)
    md.setObjectID(object_id)
    md.setCenter(BodyFacade.create(CenterName.EARTH, ctx))
    md.setReferenceFrame(FrameFacade.map(eme))
    md.setTimeSystem(TimeSystem.UTC)
    md.setStartTime(states[0].getDate())
    md.setStopTime(states[-1].getDate())
    md.setInterpolationMethod(InterpolationMethod.HERMITE)
    md.setInterpolationDegree(7)
    data = OemData()
    for s in states:
        data.addData(s.getPVCoordinates(eme), False)
    segments = ArrayList()
    segments.add(OemSegment(md, data, Constants.EIGEN5C_EARTH_MU))
    oem = Oem(header, segments, IERSConventions.IERS_2010, ctx, Constants.EIGEN5C_EARTH_MU)
    sb, gen = _generator(ctx, fmt, str(path))
    WriterBuilder(ctx).buildOemWriter().writeMessage(gen, oem)
    gen.close()
    Path(path).write_text(str(sb.toString()), encoding="utf-8")


def _pv(state, frame):
    pv = state.getPVCoordinates(frame)
    return orekit_check._vec(pv.getPosition()), orekit_check._vec(pv.getVelocity())


def generate(seed, out, fmt="kvn", hours=24.0, carrier_step=STEP_S):
    """Files of one seeded geometry (:func:`scenario_geometry`) made by Orekit into ``out``: ``radar.tdm.<fmt>``
    (the picosatellite tracked from TIRA), ``carrier.oem.<fmt>`` (the carrier every ``carrier_step`` s, its GPS
    ephemeris) and ``truth.json`` (the geometry, both spacecraft's EME2000 states at every time tag ``t`` [s after the
    geometry's epoch], the passes, the EOP span used).

    Returns
    -------
    dict
        The truth document (also written).
    """
    from org.orekit.propagation import SpacecraftState  # noqa: F401  (JVM classes loaded)

    from roe_sep.core.relmotion.roe import roe_to_kepler
    from roe_sep.core.truth.mean_osc import mean_to_cartesian

    ctx = context()
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    geo = scenario_geometry(seed)
    start = _absolute(ctx, geo["epoch_utc"])
    end = start.shiftedBy(float(hours) * 3600.0)
    eme = ctx.getFrames().getEME2000()
    chief = np.array(geo["chief_mean"])
    states = {"CARRIER": mean_to_cartesian(chief),
              "PICOSATELLITE": mean_to_cartesian(roe_to_kepler(chief, np.array(geo["roe"])))}
    ephem = {}
    for name, (r, v) in states.items():
        prop = numerical_propagator(ctx, r, v, start, MASS_KG[name])
        handler = prop.getEphemerisGenerator()
        prop.propagate(start, end)
        ephem[name] = handler.getGeneratedEphemeris()
    station = tira(ctx)
    _set_reference_dates(station, start)
    rows = generate_measurements(ctx, ephem["PICOSATELLITE"], station, start, end, seed=1000003 * int(seed) + 7)
    write_tdm(ctx, rows, out / f"radar.tdm.{fmt}", fmt, station_name="TIRA", target="PICOSATELLITE")
    n = int(float(hours) * 3600.0 / carrier_step) + 1
    write_oem(ctx, [ephem["CARRIER"].propagate(start.shiftedBy(k * carrier_step)) for k in range(n)],
              out / f"carrier.oem.{fmt}", fmt, object_id="CARRIER")
    t = np.array([float(r[0].durationFrom(start)) for r in rows])
    truth = {"geometry": geo, "eop": list(eop_span(ctx)), "measurements": len(rows),
             "passes": [[float(p[0][0].durationFrom(start)), float(p[-1][0].durationFrom(start)), len(p)]
                        for p in _passes(rows)],
             "t": t.tolist()}
    for name, e in ephem.items():
        pvs = [_pv(e.propagate(r[0]), eme) for r in rows]
        truth[name.lower()] = {"position_m": [p for p, _ in pvs], "velocity_m_s": [v for _, v in pvs]}
    (out / "truth.json").write_text(json.dumps(truth, allow_nan=False), encoding="utf-8")
    return truth


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("residuals", help="range residuals of a TDM against Orekit's range from an OEM")
    r.add_argument("oem")
    r.add_argument("tdm")
    r.add_argument("--json", action="store_true")
    g = sub.add_parser("generate", help="Orekit's TDM, carrier OEM and truth of a seeded geometry")
    g.add_argument("--seed", type=int, required=True)
    g.add_argument("--out", required=True)
    g.add_argument("--format", choices=("kvn", "xml"), default="kvn")
    g.add_argument("--hours", type=float, default=24.0)
    args = ap.parse_args(argv)
    try:
        ctx = context()
    except orekit_check.OrekitUnavailable as exc:
        print(f"orekit_crosscheck: {exc}", file=sys.stderr)
        return 2
    if args.cmd == "generate":
        truth = generate(args.seed, args.out, args.format, args.hours)
        print(f"{args.out}: {truth['measurements']} measurements in {len(truth['passes'])} passes")
        return 0
    passes = range_residuals(ctx, args.oem, args.tdm)
    if args.json:
        print(json.dumps(passes, allow_nan=False))
        return 0
    for p in passes:
        for kind in ("positions", "velocities"):
            x = np.array(p[kind])
            print(f"{p['track_id']:16s} {kind:10s} n {x.size:3d} mean {x.mean():+9.3f} m  std {x.std(ddof=1):8.3f} m")
    return 0


if __name__ == "__main__":
    sys.exit(main())
