"""radar_od: radar tracking of the picosatellite (simulated from truth) and batch orbit determination (seed 001 Sec. 5).

Seed 001: TIRA can distinguish the two spacecraft only once they are at least 5 km apart, and a reliable orbit
determination needs several passes over about 12 h. This stub simulates those measurements and runs the OD:

* Every measurement epoch k * ``sample_interval`` is simulated from the first ``/sim/truth/roe`` sample at or
  after it, propagated back to the epoch (:func:`~roe_sep.core.relmotion.dynamics.propagate` with J2 and the
  truth's own drift of da between that sample and the one before, :func:`~roe_sep.core.od.radar.truth_da_rate`;
  :func:`~roe_sep.core.relmotion.dynamics.propagate_chief`), once that sample has arrived: under lockstep each
  truth sample advances the tracking to its stamp; run alone, the tracking advances to the earlier of ``/clock``
  (rosgraph_msgs/Clock, the node runs with ``use_sim_time``) and the latest truth sample, so a clock that runs
  ahead of the truth never has an epoch measured from a stale sample. Where a station sees the picosatellite above
  its mask and the spacecraft are >= ``min_separation`` apart a noisy ``roe_sep_msgs/RadarMeasurement`` is
  published on ``/radar/measurements`` (STREAM).
* A pass is a run of consecutive measurement epochs of one station; it counts once closed with >=
  ``min_pass_measurements`` measurements. When >= ``passes_required`` counted passes since the latest executed
  maneuver span >= ``min_arc`` (first measurement of the first to last of the last), the batch least squares of
  :mod:`roe_sep.core.od.batch` runs on their measurements (with the drift rate of the last solution before that
  maneuver as a priori information) and ``roe_sep_msgs/OrbitDetermination`` is published on
  ``/od/estimate`` (latched); it runs again after every further counted pass.
* ``/sim/executed_maneuvers`` (latched history): measurements before the latest burn, and those simulated from a
  truth message older than the burn, are not used.
* ``/ground/radar_measurements`` (RadarMeasurement, e.g. TDM files through ``ground_bridge``): external measurements
  join the records as passes of their own (:meth:`RadarODNode.on_external`); one wall second after the last of a
  batch the OD runs on all usable records.

Parameters: :data:`roe_sep.nodes.parameters.RADAR_OD` (``radar_od --help``, docs/parameters.md).
"""

import bisect
import json
import math
import operator

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from roe_sep_msgs.msg import ImpulsiveManeuver, OrbitDetermination, RadarMeasurement, RelativeOrbitalElements
from rosgraph_msgs.msg import Clock

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.constants import R_EARTH, SECONDS_PER_DAY
from ..core.od.batch import DragModel, DriftPrior, RadarBatch, batch_least_squares
from ..core.od.radar import (
    Station,
    add_noise,
    deputy_earth_fixed,
    gmst,
    julian_date,
    look_angles,
    relative_distance,
    truth_da_rate,
    visible,
)
from ..core.relmotion.dynamics import propagate, propagate_chief
from ..core.relmotion.roe import rtn_position, wrap_angle
from ..core.truth.contingency import RADAR_SIDE, RadarContingency
from ..core.truth.contingency import resolve as resolve_contingency
from ..core.truth.nonlinear import vallado_band
from ..validate import ROE_FIELDS
from .convert import array_to_elements, elements_to_array, msg_to_roe, roe_to_msg, sec_to_time, time_to_sec
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare, require

CHUNK = 10000  # measurement epochs propagated at once
_ROE_VALUES = operator.attrgetter(*ROE_FIELDS)  # a message's a*ROE [m], in ROE order


class RadarODNode(ManagedNode):
    def __init__(self):
        super().__init__("radar_od")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        names = declare(self, "stations")
        lats = declare(self, "station_latitudes_deg")
        lons = declare(self, "station_longitudes_deg")
        alts = declare(self, "station_altitudes_m")
        mask = declare(self, "elevation_mask_deg")
        sigma_range = declare(self, "sigma_range_m")
        sigma_angle = declare(self, "sigma_angle_deg")
        self.dt = declare(self, "sample_interval")
        self.min_sep = declare(self, "min_separation")
        self.passes_required = declare(self, "passes_required")
        self.min_arc = declare(self, "min_arc")
        self.min_pass = declare(self, "min_pass_measurements")
        seed = declare(self, "seed")
        self.use_prior = declare(self, "drift_prior")
        scale_height = declare(self, "density_scale_height_m")
        ratio = declare(self, "drag_ballistic_ratio")
        self.density_walk = declare(self, "density_walk")
        self.drag_terms = declare(self, "od_drag_terms")
        epoch = declare(self, "epoch_utc")
        scenario_file = declare(self, "scenario_file")
        contingency = declare(self, "contingency")

        self._check(names, lats, lons, alts)
        self.drag = (scale_height, ratio)
        try:
            self.jd0 = julian_date(epoch)
        except (ValueError, TypeError) as exc:
            raise ParameterError(f"parameter 'epoch_utc' must be an ISO-8601 UTC date-time, got {epoch!r}: {exc}") \
                from exc
        self.stations = [Station(s, math.radians(la), math.radians(lo), float(h))
                         for s, la, lo, h in zip(names, lats, lons, alts)]
        self.site_ef = [s.ecef for s in self.stations]
        self.site_enu = [s.enu for s in self.stations]
        self.mask = math.radians(mask)
        self.sigma = np.array([sigma_range, math.radians(sigma_angle), math.radians(sigma_angle)])
        self.rng = np.random.default_rng(seed)
        self.contingency = self._contingency(scenario_file, contingency, seed, names)

        self._forget()
        self.pass_ids = [0] * len(self.stations)  # passes started per station
        self.too_close = False  # a station sees the picosatellite, but closer than min_separation
        self.estimates = 0
        self.published = 0
        # track() calls of the current lockstep round, run together when the round's messages are done
        # (flush_tracks): one vectorized geometry pass per round instead of one per truth sample
        self.deferred = []
        self.clock = None  # latest /clock [s] (run alone)

    def _check(self, names, lats, lons, alts):
        """ParameterError unless every station has its coordinates (the table checks each parameter alone)."""
        n = len(names)
        for name, values in (("station_latitudes_deg", lats), ("station_longitudes_deg", lons),
                             ("station_altitudes_m", alts)):
            require(name, len(values) == n, values, f"{n} value(s), one per station of 'stations'")

    def _contingency(self, scenario_file, name, seed, stations):
        """The radar's side of the run's contingency (missed passes, a range bias), drawn from its own
        stream of the noise seed; None without one (or with one of the simulator's)."""
        try:
            chosen = resolve_contingency(load_scenario(scenario_file or None).contingency, name)
            if chosen is None or chosen.name not in RADAR_SIDE:
                return None
            drawn = RadarContingency(chosen, seed, stations)
        except ConfigError as exc:
            raise ParameterError(f"parameter 'contingency' (scenario_file {scenario_file!r}): {exc}") from exc
        self.get_logger().warn(f"contingency {drawn.name}: {drawn.values}")
        return drawn

    def _forget(self):
        """No truth, no tracking, no records: the state of a run not started."""
        self.truth = None  # (t [s], dimensionless ROE, chief mean Keplerian elements)
        # every truth sample's t [s], dimensionless ROE and chief elements, sorted by t
        self.history_t, self.history_roe, self.history_kep = [], [], []
        self.t_last = None  # last processed measurement epoch [s]
        self.last_burn = -math.inf
        self.burn_epochs = []  # every executed burn's epoch [s]
        self.burns_sorted = []  # the same, sorted
        self.open_pass = [False] * len(self.stations)
        self.pass_seen = [0] * len(self.stations)  # epochs of the open pass the station should have measured
        self.pass_start = [0.0] * len(self.stations)  # epoch [s] of the open pass's first such epoch
        self.records = []  # (t, station, pass_id, z, chief, theta, truth_t)
        self.last_solution = None  # (ODResult, carrier a [m]) of the latest estimate
        self.prior = None  # DriftPrior from the last solution before the latest burn

    def activate(self):
        """Publishers, subscriptions, services (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self)
        ls.on_batch_done = self.flush_tracks
        self.meas_pub = ls.publisher(RadarMeasurement, interfaces.RADAR_TOPIC, interfaces.STREAM)
        self.od_pub = ls.publisher(OrbitDetermination, interfaces.OD_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        # a burn and the truth right after it share a stamp: the burn is processed first
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_maneuver, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        ls.subscribe(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_truth, interfaces.STREAM,
                     what="truth message", raw=True)  # every sample: decoded from its bytes (Lockstep.subscribe)
        self.create_subscription(Clock, interfaces.CLOCK_TOPIC, self.on_clock, interfaces.CLOCK_SUB)
        self.create_subscription(RadarMeasurement, interfaces.EXTERNAL_RADAR_TOPIC, self.on_external,
                                 interfaces.BULK)
        self.external_timer = None
        publish_status(self, self.diag_pub, OK, "waiting for truth", self._values())

    def _values(self):
        values = {"measurements": self.published, "passes_tracked": sum(self.pass_ids),
                  "passes_since_burn": len(self.usable()[1]), "estimates": self.estimates,
                  "last_burn_s": self.last_burn}
        if self.contingency is not None:  # as applied so far (absent without one: a nominal status as before)
            values["contingency_applied"] = json.dumps(self.contingency.applied())
        return values

    # --- inputs ---------------------------------------------------------------------------------------------
    def on_truth(self, msg: RelativeOrbitalElements):
        try:
            truth = self.parse_truth(msg)
        except ValueError as exc:
            self.get_logger().error(f"truth message rejected: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"truth message rejected: {exc}", self._values())
            return
        if self.truth is None:
            self.get_logger().info(f"first truth at t = {truth[0]:.1f} s")
            publish_status(self, self.diag_pub, OK, "tracking", self._values())
        if self.truth is None or truth[0] >= self.truth[0]:
            self.truth = truth
        k = bisect.bisect_left(self.history_t, truth[0])
        if k < len(self.history_t) and self.history_t[k] == truth[0]:  # a burn's post-burn sample replaces its pre
            self.history_roe[k], self.history_kep[k] = truth[1], truth[2]
        else:
            self.history_t.insert(k, truth[0])
            self.history_roe.insert(k, truth[1])
            self.history_kep.insert(k, truth[2])
        if self.lockstep.active:  # lockstep: the truth stream is the clock (every sample, whatever the step)
            self.advance(truth[0])
        elif self.t_last is not None:  # run alone, the clock has started the tracking
            self.advance_alone()

    @staticmethod
    def parse_truth(msg: RelativeOrbitalElements):
        """(t, dimensionless ROE, chief elements); ValueError on NaN or an impossible orbit.

        The tests on the message's floats: the chief's a, e and i in their bounds (so finite), its other elements
        finite; the ROE finite exactly when the a*ROE are (divided by an a of the bounds). The arrays are those of
        :func:`elements_to_array` and :func:`msg_to_roe`."""
        c = msg.chief
        kep = elements_to_array(c)
        t = time_to_sec(msg.header.stamp)
        a, e, inc, raan, argp, u = (c.semi_major_axis, c.eccentricity, c.inclination, c.raan, c.arg_perigee,
                                    c.mean_arg_latitude)
        if not (R_EARTH + 1e5 < a < R_EARTH + 5e6 and 0.0 <= e < 0.1 and 0.0 <= inc <= math.pi
                and math.isfinite(raan) and math.isfinite(argp) and math.isfinite(u - argp)):
            raise ValueError(f"chief elements are not a near-circular low Earth orbit: {kep.tolist()}")
        roe = msg_to_roe(msg)
        if not all(map(math.isfinite, _ROE_VALUES(msg))):
            raise ValueError(f"ROE are not finite: {(roe * kep[0]).tolist()} m")
        return t, roe, kep

    def on_maneuver(self, msg: ImpulsiveManeuver):
        self.flush_tracks()  # the measurements before the burn see the burn history they saw when simulated
        t = time_to_sec(msg.epoch)
        self.burn_epochs.append(t)
        bisect.insort(self.burns_sorted, t)
        if t > self.last_burn:
            self.last_burn = t
            if self.last_solution is not None and self.last_solution[0].t_est <= t:
                self.prior = self.drift_prior(*self.last_solution)
            self.get_logger().info(f"{msg.spacecraft} {msg.purpose} burn at t = {t:.1f} s: earlier measurements "
                                   "are no longer used")

    def on_clock(self, msg: Clock):
        if self.lockstep.active:
            return
        now = time_to_sec(msg.clock)
        if self.clock is not None and now < self.clock - self.dt:
            self.get_logger().warn(f"sim time jumped back from {self.clock:.1f} s to {now:.1f} s: restarting")
            self.reset()
        self.clock = now
        if self.truth is None or self.t_last is None:
            self.t_last = now  # start: no back-fill
            return
        self.advance_alone()

    def advance_alone(self):
        """Run alone: measure up to the clock, but only the epochs that a truth sample at or after them has arrived
        for, each from the first such sample (what lockstep does, whichever of the clock and the truth comes
        first)."""
        frontier = min(self.clock, self.history_t[-1])
        if frontier > self.t_last:
            self.advance(frontier, from_history=True)

    def advance(self, now, from_history=False):
        """Measurements for every epoch k * ``sample_interval`` in (last, now]: from the truth in force, or
        (``from_history``) each from the first truth sample at or after it."""
        if self.t_last is not None and now < self.t_last - self.dt:
            self.get_logger().warn(f"sim time jumped back from {self.t_last:.1f} s to {now:.1f} s: restarting")
            self.reset()
        if self.truth is None or self.t_last is None:
            self.t_last = now  # start: no back-fill
            return
        first = math.floor(self.t_last / self.dt) + 1
        last = math.floor(now / self.dt)
        self.t_last = now
        for k0 in range(first, last + 1, CHUNK):  # a long clock jump in bounded pieces
            epochs = np.arange(k0, min(k0 + CHUNK, last + 1)) * self.dt
            if not from_history:
                self.track(epochs)
                continue
            # (k * dt may exceed the latest sample's stamp by a rounding error: that sample, then)
            source = np.minimum(np.searchsorted(self.history_t, epochs, side="left"), len(self.history_t) - 1)
            for k in np.unique(source):
                self.track(epochs[source == k], (self.history_t[k], self.history_roe[k], self.history_kep[k]))

    def reset(self):
        """Forget the run (a restarted simulator publishes its truth and burns again)."""
        self.flush_tracks()
        self._forget()

    # --- measurements --------------------------------------------------------------------------------------
    def track(self, epochs, truth=None):
        """Measurements at ``epochs`` [s] from ``truth`` (default: the truth in force) and the burns known now.
        Inside a lockstep round the work waits for the end of the round (:meth:`flush_tracks`), whatever else the
        round holds: the measurements, passes and estimates are those of tracking at once, in the same order."""
        self.deferred.append((epochs, self.truth if truth is None else truth, self.last_burn, self.t_last))
        if not self.lockstep.in_batch:
            self.flush_tracks()

    def flush_tracks(self):
        """Run the deferred :meth:`track` calls: the geometry of all their epochs in one vectorized pass (each epoch
        propagated from the truth sample it was deferred with), then the passes and measurements call by call.
        A failure drops these measurements with an ERROR on /diagnostics; the node goes on."""
        deferred, self.deferred = self.deferred, []
        try:
            self._track_all(deferred)
        except Exception as exc:  # noqa: BLE001 -- a node never dies on its input; it says what it dropped
            text = f"measurements of {len(deferred)} truth sample(s) dropped: {type(exc).__name__}: {exc}"
            self.get_logger().error(text)
            publish_status(self, self.diag_pub, ERROR, text, self._values())

    def _track_all(self, deferred):
        calls = []
        for epochs, truth, last_burn, now in deferred:
            if last_burn > truth[0]:  # burn executed, post-burn truth not in yet: no valid truth after the burn
                epochs = epochs[epochs < last_burn]
            if epochs.size:
                calls.append((epochs, truth, now))
        if not calls:
            return
        sizes = [c[0].size for c in calls]
        epochs = np.concatenate([c[0] for c in calls])
        t_tr = np.repeat([c[1][0] for c in calls], sizes)
        roe_tr = np.repeat(np.array([c[1][1] for c in calls]), sizes, axis=0)
        kep_tr = np.repeat(np.array([c[1][2] for c in calls]), sizes, axis=0)
        chief = propagate_chief(kep_tr, epochs - t_tr)
        rate = np.repeat([self.truth_rate(c[1][0], c[1][1]) for c in calls], sizes)
        roe = propagate(roe_tr, epochs - t_tr, kep_tr[:, 0], kep_tr[:, 2], True, rate)
        theta = gmst(self.jd0 + epochs / SECONDS_PER_DAY)
        # the relative position serves the separation and every station's observe(): formed once, as each forms it
        rel = rtn_position(roe, chief[:, 4] + chief[:, 5])
        sep = relative_distance(roe, kep_tr[:, 0], None, rel)
        r_ef = deputy_earth_fixed(roe, chief, theta, rel)
        z = [look_angles(r_ef, self.site_ef[s], self.site_enu[s]) for s in range(len(self.stations))]
        # the pass logic reads the epochs, the separation and the visibility one epoch at a time: as Python
        # values (the same floats and truth values), not NumPy scalars
        seen = [visible(zs[:, 2], self.mask).tolist() for zs in z]
        epochs, sep = epochs.tolist(), sep.tolist()
        start = 0
        for (_, truth, now), n in zip(calls, sizes):
            rows = slice(start, start + n)
            start += n
            self._passes(epochs[rows], truth[0], now, chief[rows], theta[rows], sep[rows], [zs[rows] for zs in z],
                         [vs[rows] for vs in seen])

    def truth_rate(self, t, roe):
        """The truth's drift of da [1/s] into its sample (``t``, ``roe``) from the sample before it
        (:func:`~roe_sep.core.od.radar.truth_da_rate`); 0 for the first sample or across a burn (one in
        (t_before, t]: the first burn epoch after t_before, in the sorted epochs, is <= t)."""
        k = bisect.bisect_left(self.history_t, t)
        if k == 0:
            return 0.0
        b = bisect.bisect_right(self.burns_sorted, self.history_t[k - 1])
        if b < len(self.burns_sorted) and self.burns_sorted[b] <= t:
            return 0.0
        return truth_da_rate(self.history_t[k - 1], self.history_roe[k - 1], t, roe)

    def _passes(self, epochs, t_tr, now, chief, theta, sep, z, seen):
        """Open and close passes, measure, estimate: one :meth:`track` call's epochs, station by station
        (``epochs``, ``sep`` and ``seen`` as lists)."""
        close_seen = False
        min_sep = self.min_sep
        for s in range(len(self.stations)):
            seen_s = seen[s]
            if not (self.open_pass[s] or any(seen_s)):
                continue  # nothing in view, no pass open: nothing below would happen
            close_seen |= any(v and d < min_sep for v, d in zip(seen_s, sep))
            for j, t in enumerate(epochs):
                if seen_s[j] and sep[j] >= min_sep:
                    if not self.open_pass[s]:
                        self.open_pass[s] = True
                        self.pass_ids[s] += 1
                        self.pass_seen[s], self.pass_start[s] = 0, float(t)
                        if self.contingency is not None:
                            self.contingency.pass_opened(s, self.pass_ids[s], float(t))
                    self.pass_seen[s] += 1
                    if self.contingency is None or not self.contingency.dropped(s, self.pass_ids[s], float(t)):
                        self.measure(t, s, z[s][j], chief[j], theta[j], t_tr)
                elif self.open_pass[s]:
                    self.open_pass[s] = False
                    self.pass_closed(s, self.pass_ids[s], now)
        if close_seen and not self.too_close:
            msg = f"waiting for separation: picosatellite visible but closer than {self.min_sep:g} m"
            self.get_logger().warn(msg)
            publish_status(self, self.diag_pub, WARN, msg, self._values())
        self.too_close = close_seen

    def measure(self, t, s, z_true, chief, theta, truth_t):
        z = add_noise(z_true, self.sigma, self.rng)
        if self.contingency is not None:
            z[0] += self.contingency.range_bias(s)  # a station's range bias (radar_bias)
        self.records.append((float(t), s, self.pass_ids[s], z, chief, float(theta), truth_t))
        name = self.stations[s].name
        m = RadarMeasurement(station=name, pass_id=self.pass_ids[s], range=float(z[0]), azimuth=float(z[1]),
                             elevation=float(z[2]), sigma_range=float(self.sigma[0]),
                             sigma_angle=float(self.sigma[1]))
        m.header.stamp = sec_to_time(t)
        m.header.frame_id = name
        self.meas_pub.publish(m)
        self.published += 1

    def pass_closed(self, s, pass_id, now):
        count = sum(1 for r in self.records if r[1] == s and r[2] == pass_id)
        name = self.stations[s].name
        self.get_logger().info(f"{name} pass {pass_id} closed: {count} measurements")
        if count == 0 and self.pass_seen[s] >= self.min_pass:
            self.pass_lost(s, pass_id)
        if count < self.min_pass:
            return
        publish_status(self, self.diag_pub, OK, f"{name} pass {pass_id}: {count} measurements", self._values())
        self.estimate(now)

    def pass_lost(self, s, pass_id):
        """A pass that the station had in view (the picosatellite above its mask and separable for at least
        ``min_pass_measurements`` epochs) closed without one measurement: the station delivered nothing, which its
        operators know at once. A named WARN ``roe_sep/radar_od/contingency`` (value ``contingency``
        ``radar_pass_missed``, ``epoch_s`` the pass's first epoch); the OD waits for the passes that follow."""
        name, t0 = self.stations[s].name, self.pass_start[s]
        text = (f"radar_pass_missed: {name} pass {pass_id} from t = {t0:.0f} s ({self.pass_seen[s]} epochs in view) "
                "delivered no measurement")
        self.get_logger().warn(text)
        publish_status(self, self.diag_pub, WARN, text, {"contingency": "radar_pass_missed", "epoch_s": f"{t0:.1f}",
                                                         "station": name, "pass_id": pass_id}, part="contingency")

    def on_external(self, msg: RadarMeasurement):
        """A ground segment's measurement: a record of the external pass -(pass_id + 1) of its station (never an
        open pass), the chief and sidereal angle from this node's truth and epoch as for its own; the OD runs one
        wall second after the last one arrived. Rejected with an ERROR on /diagnostics: no truth yet, an unknown
        station, non-finite values, or sigmas other than this node's (the batch weights every record alike)."""
        self.flush_tracks()
        t = time_to_sec(msg.header.stamp)
        z = np.array([msg.range, msg.azimuth, msg.elevation], dtype=float)
        names = [st.name for st in self.stations]
        problem = ("no truth received yet" if self.truth is None else
                   f"unknown station {msg.station!r} (stations: {names})" if msg.station not in names else
                   "non-finite values" if not (np.all(np.isfinite(z)) and math.isfinite(t)) else
                   f"sigmas {msg.sigma_range} m / {msg.sigma_angle} rad differ from this node's "
                   f"{self.sigma[0]} m / {self.sigma[1]} rad"
                   if not np.allclose([msg.sigma_range, msg.sigma_angle], self.sigma[:2], rtol=1e-9, atol=0.0)
                   else None)
        if problem:
            self.get_logger().error(f"external measurement at t = {t:.1f} s rejected: {problem}")
            publish_status(self, self.diag_pub, ERROR, f"external measurement rejected: {problem}", self._values())
            return
        # the chief from the first truth sample at or after the epoch (the latest if none): the sample from which
        # this node's own tracking simulated a measurement at that epoch, so a run's TDM fed back gives its OD
        k = min(bisect.bisect_left(self.history_t, t), len(self.history_t) - 1)
        t_tr, kep_tr = self.history_t[k], self.history_kep[k]
        chief = propagate_chief(kep_tr, np.array([t - t_tr]))[0]
        theta = float(gmst(self.jd0 + t / SECONDS_PER_DAY))
        self.records.append((t, names.index(msg.station), -int(msg.pass_id) - 1, z, chief, theta, t_tr))
        if self.external_timer is not None:
            self.external_timer.cancel()
            self.destroy_timer(self.external_timer)
        self.external_timer = self.create_timer(1.0, self._external_batch,
                                                clock=RclpyClock(clock_type=ClockType.STEADY_TIME))

    def _external_batch(self):
        self.external_timer.cancel()
        self.get_logger().info("external measurements received: orbit determination")
        self.flush_tracks()
        self.estimate(self.t_last)

    # --- orbit determination -------------------------------------------------------------------------------
    def usable(self):
        """Records after the latest burn (and from post-burn truth) in counted passes; (records, passes)."""
        recs = [r for r in self.records if r[0] >= self.last_burn and r[6] >= self.last_burn]
        counts = {}
        for r in recs:
            counts[(r[1], r[2])] = counts.get((r[1], r[2]), 0) + 1
        open_now = {(s, self.pass_ids[s]) for s in range(len(self.stations)) if self.open_pass[s]}
        good = {key for key, c in counts.items() if c >= self.min_pass and key not in open_now}
        return [r for r in recs if (r[1], r[2]) in good], good

    def estimate(self, now):
        """The batch OD on the usable records, published with header stamp ``now`` [s] (the sim time of the
        tracking that closed the pass)."""
        recs, passes = self.usable()
        if len(passes) < self.passes_required:
            return
        recs.sort(key=lambda r: r[0])
        if recs[-1][0] - recs[0][0] < self.min_arc:
            return
        s_idx = [r[1] for r in recs]
        batch = RadarBatch(t=np.array([r[0] for r in recs]), z=np.array([r[3] for r in recs]),
                           sigma=np.tile(self.sigma, (len(recs), 1)), chief=np.array([r[4] for r in recs]),
                           theta=np.array([r[5] for r in recs]), site_ef=np.array([self.site_ef[s] for s in s_idx]),
                           site_enu=np.array([self.site_enu[s] for s in s_idx]))
        prior = (self.prior.carried(float(np.max(batch.t)), self.density_walk)
                 if self.prior is not None and self.use_prior else None)
        try:
            result = batch_least_squares(batch, prior=prior, drag=self.drag_terms,
                                         model=self.drag_model(batch.chief[-1, 0]))
        except ValueError as exc:
            self.get_logger().error(f"orbit determination failed: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"orbit determination failed: {exc}", self._values())
            return
        self.od_pub.publish(self.od_msg(result, batch.chief[-1], len(passes), now))
        self.estimates += 1
        a = batch.chief[-1, 0]
        self.last_solution = (result, a)
        self.get_logger().info(
            f"OD #{self.estimates} at t = {result.t_est:.0f} s from {len(passes)} passes / {result.measurements} "
            f"measurements: a*ROE = {np.array2string(result.x[:6] * a, precision=1)} m, a*da_dot = "
            f"{result.x[6] * a:.3e} m/s, residual RMS {result.residual_rms:.2f}"
            + ("" if prior is None else f", drift prior from t = {self.prior.t:.0f} s"))
        publish_status(self, self.diag_pub, OK, f"estimate {self.estimates} published", self._values())

    def drag_model(self, a_chief):
        """The drift rate's drag model at the carrier's semi-major axis ``a_chief`` [m]: the configured scale
        height, else Vallado's for the carrier's altitude, and the ballistic ratio."""
        scale_height, ratio = self.drag
        return DragModel(scale_height or vallado_band(a_chief - R_EARTH)[2], ratio)

    def drift_prior(self, result, a_chief):
        """The a priori information of a solution for the batches after the next burn (:meth:`drag_model`)."""
        return DriftPrior.from_result(result, a_chief, self.drag_model(a_chief))

    def od_msg(self, result, chief_kep, passes, now):
        kep = np.array(chief_kep, dtype=float)
        kep[3:] = wrap_angle(kep[3:])
        chief = array_to_elements(kep)
        a = chief.semi_major_axis
        msg = OrbitDetermination(passes=passes, measurements=result.measurements,
                                 residual_rms=float(result.residual_rms), a_da_dot=float(result.x[6] * a),
                                 a_da_dot_sigma=float(math.sqrt(result.cov[6, 6]) * a))
        msg.header.stamp = sec_to_time(now)
        msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
        mean, cov = result.mean_state()  # the mean ROE as the project defines them (with drag's short-period de)
        msg.estimate = roe_to_msg(mean[:6], chief, sec_to_time(result.t_est), covariance=cov[:6, :6])
        msg.a_da_dot_covariance = [float(v) for v in cov[:6, 6] * a * a]
        return msg


def main(args=None):
    from .spin import run

    return run(RadarODNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
