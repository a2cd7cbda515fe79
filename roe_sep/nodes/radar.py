"""radar: the radar sensor, ground stations tracking the picosatellite, simulated from truth (seed 001 Sec. 5).

Seed 001: TIRA can distinguish the two spacecraft only once they are at least 5 km apart. This node simulates the
stations' measurements; ``radar_od`` estimates from them (or from a ground segment's TDM files, without this node):

* Every measurement epoch k * ``sample_interval`` is simulated from the first ``/sim/truth/roe`` sample at or
  after it and the sample before it, each carried to the epoch (J2 secular rates and the truth's own drift of da
  between the two, :func:`~roe_sep.core.od.radar.truth_da_rate`) and blended linearly in time
  (:func:`~roe_sep.core.od.sensor.truth_between`; the later sample alone across a burn,
  :func:`~roe_sep.core.od.sensor.sample_pair`), once the later sample has arrived: under lockstep each
  truth sample advances the tracking to its stamp; run alone, the tracking advances to the earlier of ``/clock``
  (rosgraph_msgs/Clock, the node runs with ``use_sim_time``) and the latest truth sample, so a clock that runs
  ahead of the truth never has an epoch measured from a stale sample. Where a station sees the picosatellite above
  its mask and the spacecraft are >= ``min_separation`` apart (:func:`~roe_sep.core.od.sensor.trackable`) a noisy
  ``roe_sep_msgs/RadarMeasurement`` is published on ``/radar/measurements`` (STREAM,
  :func:`~roe_sep.core.od.sensor.noisy_measurement`): the two-way light-time range at the receive time tag and the
  angles of the received signal (:func:`~roe_sep.core.od.radar.two_way_look`, the Earth oriented by
  :func:`~roe_sep.core.frames.gcrs_to_itrs`), as the TDM declares them.
* A pass is a run of consecutive measurement epochs of one station; when it ends, ``roe_sep_msgs/RadarPass`` on
  ``/radar/passes`` (STREAM) says so, stamped with the tracking's sim time, after its last measurement.
* ``/sim/executed_maneuvers`` (latched history): no measurement is simulated from a truth sample older than a burn
  for an epoch after it.
* ``track_carrier``: each station also ranges the carrier at the same epochs (``/radar/carrier_ranges``; zero ROE,
  :func:`~roe_sep.core.od.radar.carrier_earth_fixed_state`; a noise stream of its own) for radar_od's biases.
* Contingencies (``contingency``: radar_pass_missed, radar_bias): lost passes and a station's range bias, drawn
  from the noise seed's own stream (:class:`~roe_sep.core.truth.contingency.RadarContingency`); a pass in view
  that delivered nothing is reported on ``/diagnostics`` (:func:`~roe_sep.core.od.sensor.pass_lost`).

Parameters: :data:`roe_sep.nodes.parameters.RADAR` (``radar --help``, docs/parameters.md).
"""

import bisect
import json
import math

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from roe_sep_msgs.msg import ImpulsiveManeuver, RadarMeasurement, RadarPass, RelativeOrbitalElements
from rosgraph_msgs.msg import Clock

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.frames import gcrs_to_itrs
from ..core.od.radar import (
    carrier_earth_fixed_state,
    deputy_earth_fixed_state,
    relative_distance,
    truth_da_rate,
    two_way_look,
    visible,
)
from ..core.od.sensor import (
    TruthSamples,
    noisy_measurement,
    pass_lost,
    sample_pair,
    trackable,
    truth_between,
)
from ..core.relmotion.roe import rtn_position
from ..core.truth.contingency import RADAR_SIDE, RadarContingency
from ..core.truth.contingency import resolve as resolve_contingency
from .convert import sec_to_time, time_to_sec
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare
from .radar_stations import parse_truth, tracking_of

CHUNK = 10000  # measurement epochs propagated at once
CARRIER_STREAM = 2  # the carrier ranges' noise: a stream of the noise seed of its own (graph.RADAR_STREAM is 1)


class RadarNode(ManagedNode):
    def __init__(self):
        super().__init__("radar")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        self.stations, self.jd0, self.site_ef, self.site_enu, self.sigma = tracking_of(self)
        self.mask = math.radians(declare(self, "elevation_mask_deg"))
        self.dt = declare(self, "sample_interval")
        self.min_sep = declare(self, "min_separation")
        self.min_pass = declare(self, "min_pass_measurements")
        seed = declare(self, "seed")
        scenario_file = declare(self, "scenario_file")
        contingency = declare(self, "contingency")
        self.rng = np.random.default_rng(seed)
        self.track_carrier = declare(self, "track_carrier")
        self.carrier_rng = np.random.default_rng([seed, CARRIER_STREAM])  # the picosatellite's noise unchanged
        self.contingency = self._contingency(scenario_file, contingency, seed, [s.name for s in self.stations])

        self._forget()
        self.pass_ids = [0] * len(self.stations)  # passes started per station
        self.too_close = False  # a station sees the picosatellite, but closer than min_separation
        self.published = 0
        # track() calls of the current lockstep round, run together when the round's messages are done
        # (flush_tracks): one vectorized geometry pass per round instead of one per truth sample
        self.deferred = []
        self.clock = None  # latest /clock [s] (run alone)

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
        """No truth, no tracking: the state of a run not started."""
        self.truth = None  # (t [s], dimensionless ROE, chief mean Keplerian elements)
        # every truth sample's t [s], dimensionless ROE and chief elements, sorted by t
        self.history_t, self.history_roe, self.history_kep = [], [], []
        self.t_last = None  # last processed measurement epoch [s]
        self.last_burn = -math.inf
        self.burns_sorted = []  # every executed burn's epoch [s], sorted
        self.open_pass = [False] * len(self.stations)
        self.pass_seen = [0] * len(self.stations)  # epochs of the open pass the station should have measured
        self.pass_start = [0.0] * len(self.stations)  # epoch [s] of the open pass's first such epoch
        self.pass_count = [0] * len(self.stations)  # measurements published in the open (or last) pass

    def activate(self):
        """Publishers, subscriptions (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self)
        ls.on_batch_done = self.flush_tracks
        self.meas_pub = ls.publisher(RadarMeasurement, interfaces.RADAR_TOPIC, interfaces.STREAM)
        self.pass_pub = ls.publisher(RadarPass, interfaces.RADAR_PASS_TOPIC, interfaces.STREAM)
        # always offered (the simulator waits for its readers, and the recorder subscribes to published topics)
        self.carrier_pub = ls.publisher(RadarMeasurement, interfaces.CARRIER_RADAR_TOPIC, interfaces.STREAM)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        # a burn and the truth right after it share a stamp: the burn is processed first
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_maneuver, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        ls.subscribe(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_truth, interfaces.STREAM,
                     what="truth message", raw=True)  # every sample: decoded from its bytes (Lockstep.subscribe)
        self.create_subscription(Clock, interfaces.CLOCK_TOPIC, self.on_clock, interfaces.CLOCK_SUB)
        publish_status(self, self.diag_pub, OK, "waiting for truth", self._values())

    def _values(self):
        values = {"measurements": self.published, "passes_tracked": sum(self.pass_ids)}
        if self.contingency is not None:  # as applied so far (absent without one: a nominal status as before)
            values["contingency_applied"] = json.dumps(self.contingency.applied())
        return values

    # --- inputs ---------------------------------------------------------------------------------------------
    def on_truth(self, msg: RelativeOrbitalElements):
        try:
            truth = parse_truth(msg)
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

    def on_maneuver(self, msg: ImpulsiveManeuver):
        self.flush_tracks()  # the measurements before the burn see the burn history they saw when simulated
        t = time_to_sec(msg.epoch)
        bisect.insort(self.burns_sorted, t)
        self.last_burn = max(self.last_burn, t)

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
        round holds: the measurements and passes are those of tracking at once, in the same order."""
        truth = self.truth if truth is None else truth
        self.deferred.append((epochs, truth, self.last_burn, self.t_last, self.sample_before(truth[0])))
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
        for epochs, truth, last_burn, now, before in deferred:
            if last_burn > truth[0]:  # burn executed, post-burn truth not in yet: no valid truth after the burn
                epochs = epochs[epochs < last_burn]
            if epochs.size:
                calls.append((epochs, truth, now, truth if before is None else before))
        if not calls:
            return
        sizes = [c[0].size for c in calls]
        epochs = np.concatenate([c[0] for c in calls])

        def samples(j):  # the calls' j-th sample (truth, or the one before it) repeated over their epochs
            return TruthSamples(*(np.repeat(np.array([c[j][x] for c in calls]), sizes, axis=0) for x in range(3)))

        rate = np.repeat([truth_da_rate(c[3][0], c[3][1], c[1][0], c[1][1]) for c in calls], sizes)
        after = samples(1)
        roe, chief = truth_between(epochs, after, samples(3), rate)
        kep_tr = after.kep
        earth = gcrs_to_itrs(self.jd0, epochs)
        # the relative position serves the separation and every station's look angles: formed once
        rel = rtn_position(roe, chief[:, 4] + chief[:, 5])
        sep = relative_distance(roe, kep_tr[:, 0], None, rel)
        state_ef = deputy_earth_fixed_state(roe, chief, earth, rel)
        z = [two_way_look(state_ef, self.site_ef[s], self.site_enu[s]) for s in range(len(self.stations))]
        if self.track_carrier:  # the carrier's ranges at the same epochs, beside the picosatellite's triplets
            carrier_ef = carrier_earth_fixed_state(chief, earth)
            z = [np.column_stack([zs, two_way_look(carrier_ef, self.site_ef[s], self.site_enu[s])])
                 for s, zs in enumerate(z)]
        # the pass logic reads the epochs and the visibility one epoch at a time: as Python values (the same
        # floats and truth values), not NumPy scalars
        seen = [visible(zs[:, 2], self.mask).tolist() for zs in z]
        good = [trackable(zs[:, 2], sep, self.mask, self.min_sep).tolist() for zs in z]
        epochs = epochs.tolist()
        start = 0
        for (_, _, now, _), n in zip(calls, sizes):
            rows = slice(start, start + n)
            start += n
            self._passes(epochs[rows], now, [zs[rows] for zs in z], [vs[rows] for vs in seen],
                         [gs[rows] for gs in good])

    def sample_before(self, t):
        """The truth sample ``(t, roe, kep)`` before the one at ``t`` that the measurements between them are blended
        from (:func:`~roe_sep.core.od.sensor.sample_pair`, :func:`~roe_sep.core.od.sensor.truth_between`); None for
        the first sample or across a burn."""
        k, j = sample_pair(self.history_t, self.burns_sorted, t)
        return None if j == k else (self.history_t[j], self.history_roe[j], self.history_kep[j])

    def _passes(self, epochs, now, z, seen, good):
        """Open and close passes and measure: one :meth:`track` call's epochs, station by station (``epochs``, and
        per station ``seen`` above the mask and ``good``, :func:`~roe_sep.core.od.sensor.trackable`, as lists)."""
        close_seen = False
        for s in range(len(self.stations)):
            good_s = good[s]
            if not (self.open_pass[s] or any(seen[s])):
                continue  # nothing in view, no pass open: nothing below would happen
            close_seen |= any(v and not g for v, g in zip(seen[s], good_s))
            for j, t in enumerate(epochs):
                if good_s[j]:
                    if not self.open_pass[s]:
                        self.open_pass[s] = True
                        self.pass_ids[s] += 1
                        self.pass_seen[s], self.pass_start[s], self.pass_count[s] = 0, float(t), 0
                        if self.contingency is not None:
                            self.contingency.pass_opened(s, self.pass_ids[s], float(t))
                    self.pass_seen[s] += 1
                    if self.contingency is None or not self.contingency.dropped(s, self.pass_ids[s], float(t)):
                        self.measure(t, s, z[s][j])
                elif self.open_pass[s]:
                    self.open_pass[s] = False
                    self.pass_closed(s, now)
        if close_seen and not self.too_close:
            msg = f"waiting for separation: picosatellite visible but closer than {self.min_sep:g} m"
            self.get_logger().warn(msg)
            publish_status(self, self.diag_pub, WARN, msg, self._values())
        self.too_close = close_seen

    def measure(self, t, s, z_true):
        """The measurement of station ``s`` at ``t`` [s] from its true ``z_true`` (range, azimuth, elevation, and
        with ``track_carrier`` the carrier's three after them), published with the noise and the contingency's
        bias."""
        bias = 0.0 if self.contingency is None else self.contingency.range_bias(s)  # radar_bias
        z = noisy_measurement(z_true[:3], self.sigma, self.rng, bias)
        if self.track_carrier:
            zc = noisy_measurement(z_true[3:], self.sigma, self.carrier_rng, bias)
            self.carrier_pub.publish(self.message(t, s, zc))
        self.meas_pub.publish(self.message(t, s, z))
        self.published += 1
        self.pass_count[s] += 1

    def message(self, t, s, z):
        """The RadarMeasurement of station ``s``'s open pass at ``t`` [s]: ``z`` (range, azimuth, elevation) and this
        sensor's sigmas."""
        name = self.stations[s].name
        m = RadarMeasurement(station=name, pass_id=self.pass_ids[s], range=float(z[0]), azimuth=float(z[1]),
                             elevation=float(z[2]), sigma_range=float(self.sigma[0]),
                             sigma_angle=float(self.sigma[1]))
        m.header.stamp = sec_to_time(t)
        m.header.frame_id = name
        return m

    def pass_closed(self, s, now):
        """The end of station ``s``'s open pass at the tracking's sim time ``now`` [s]: RadarPass on
        ``/radar/passes``, a status, and :meth:`report_lost` for a pass in view that delivered nothing."""
        name, pass_id, count = self.stations[s].name, self.pass_ids[s], self.pass_count[s]
        msg = RadarPass(station=name, pass_id=pass_id, measurements=count, epochs_in_view=self.pass_seen[s])
        msg.header.stamp = sec_to_time(now)
        msg.header.frame_id = name
        self.pass_pub.publish(msg)
        self.get_logger().info(f"{name} pass {pass_id} closed: {count} measurements")
        if pass_lost(count, self.pass_seen[s], self.min_pass):
            self.report_lost(s, pass_id)
        if count >= self.min_pass:
            publish_status(self, self.diag_pub, OK, f"{name} pass {pass_id}: {count} measurements", self._values())

    def report_lost(self, s, pass_id):
        """A pass that the station had in view (the picosatellite above its mask and separable for at least
        ``min_pass_measurements`` epochs) closed without one measurement: the station delivered nothing, which its
        operators know at once. A named WARN ``roe_sep/radar/contingency`` (value ``contingency``
        ``radar_pass_missed``, ``epoch_s`` the pass's first epoch); the OD waits for the passes that follow."""
        name, t0 = self.stations[s].name, self.pass_start[s]
        text = (f"radar_pass_missed: {name} pass {pass_id} from t = {t0:.0f} s ({self.pass_seen[s]} epochs in view) "
                "delivered no measurement")
        self.get_logger().warn(text)
        publish_status(self, self.diag_pub, WARN, text, {"contingency": "radar_pass_missed", "epoch_s": f"{t0:.1f}",
                                                         "station": name, "pass_id": pass_id}, part="contingency")


def main(args=None):
    from .spin import run

    return run(RadarNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
