"""radar_od: batch orbit determination of the picosatellite from radar measurements (seed 001 Sec. 5).

Seed 001: a reliable orbit determination needs several radar passes over about 12 h. This node estimates from the
measurements that arrive, wherever they come from; it never simulates one:

* ``/radar/measurements`` (RadarMeasurement) and ``/radar/passes`` (RadarPass): the radar sensor's
  (:mod:`.radar`) measurements and the ends of its passes. Each measurement becomes a
  :class:`~roe_sep.core.od.sensor.RadarRecord`; a pass counts once its end has arrived with all its measurements
  and it has >= ``min_pass_measurements`` of them. When >= ``passes_required`` counted passes since the latest
  executed maneuver span >= ``min_arc`` (first measurement of the first to last of the last), the batch least
  squares of :mod:`roe_sep.core.od.batch` runs on their measurements (with the drift rate of the last solution
  before that maneuver as a priori information) and ``roe_sep_msgs/OrbitDetermination`` is published on
  ``/od/estimate`` (latched), stamped with the pass end's time; it runs again after every further counted pass.
* ``/ground/radar_measurements`` (RadarMeasurement, e.g. TDM files through ``ground_bridge``): a ground segment's
  measurements join the records as passes of their own (:meth:`RadarODNode.on_external`); one wall second after the
  last of a batch the OD runs on all usable records.
* ``/radar/carrier_ranges`` (the radar's ``track_carrier``): ranges to the carrier, whose orbit its GPS gives:
  information on the range biases alone (:class:`~roe_sep.core.od.batch.CarrierRanges`). The biases are states
  with ``range_bias_sigma`` > 0, or from the first OD whose residual test, or its carrier ranges' test, fails
  (:func:`~roe_sep.core.od.batch.bias_state_switch`; a ``range_bias_estimated`` finding; issue 41 part 4).
* ``/separation/ejection(_estimate)``: without a full estimate ``prior_od_after`` after the release (an outage),
  each counted pass gives an OD with the prediction from the ejection on record and the carrier burns as a prior
  (:func:`~roe_sep.core.od.batch.predicted_prior`; an ``od_from_prediction`` finding; issue 41 part 3).
* ``/sim/truth/roe``: the carrier's orbit (chief elements) at each epoch; ``/sim/executed_maneuvers`` (latched): a
  burn applies to the estimates from its epoch on, the measurements before it are no longer used.

Under lockstep the inputs are counted: taken in their canonical order (docs/run.md), whatever the timing.

Parameters: :data:`roe_sep.nodes.parameters.RADAR_OD` (``radar_od --help``, docs/parameters.md).
"""

import bisect
import collections
import json
import math

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistWithCovarianceStamped
from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from roe_sep_msgs.msg import (
    EjectionEvent,
    ImpulsiveManeuver,
    OrbitDetermination,
    RadarMeasurement,
    RadarPass,
    RelativeOrbitalElements,
)

from .. import interfaces
from ..core.constants import R_EARTH
from ..core.frames import gcrs_to_itrs
from ..core.od.batch import (
    CarrierRanges,
    DragModel,
    DriftPrior,
    RadarBatch,
    RangeBiasPrior,
    batch_least_squares,
    bias_state_switch,
    carrier_bias_tail,
    predicted_prior,
    residual_tail,
    station_index,
    uses_prediction,
)
from ..core.od.radar import carrier_earth_fixed_state, two_way_look
from ..core.od.sensor import RadarRecord, chief_from_samples, counted_passes
from ..core.relmotion.roe import wrap_angle
from ..core.relmotion.trajectory import Chief
from ..core.truth.nonlinear import vallado_band
from .convert import (
    array_to_elements,
    ejection_prior,
    planned_burn,
    roe_to_msg,
    sec_to_time,
    time_to_sec,
    twist_linear,
)
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import declare, scenario_of
from .radar_stations import parse_truth, tracking_of


class RadarODNode(ManagedNode):
    def __init__(self):
        super().__init__("radar_od")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        self.stations, self.jd0, self.site_ef, self.site_enu, self.sigma = tracking_of(self)
        self.names = [st.name for st in self.stations]
        self.passes_required = declare(self, "passes_required")
        self.min_arc = declare(self, "min_arc")
        self.min_pass = declare(self, "min_pass_measurements")
        self.use_prior = declare(self, "drift_prior")
        scale_height = declare(self, "density_scale_height_m")
        ratio = declare(self, "drag_ballistic_ratio")
        self.density_walk = declare(self, "density_walk")
        self.drag_terms = declare(self, "od_drag_terms")
        self.bias_sigma = declare(self, "range_bias_sigma")
        self.bias_auto_sigma = declare(self, "range_bias_auto_sigma")
        self.bias_alpha = declare(self, "range_bias_alpha")
        self.gps_sigma = declare(self, "carrier_position_sigma")
        self.prior_od_after = declare(self, "prior_od_after")
        self.prior_floor = declare(self, "prior_od_floor")
        scenario_file = declare(self, "scenario_file")
        self.scenario = scenario_of(scenario_file)
        self.drag = (scale_height, ratio)
        self.estimates = 0
        self.received = 0
        self._forget()

    def _forget(self):
        """No truth, no records: the state of a run not started."""
        self.history_t, self.history_kep = [], []  # every truth sample's t [s] and chief elements, sorted by t
        self.burns = []  # executed burns' epochs [s] not applied yet, sorted
        self.burn_epochs = []  # every executed burn's epoch [s], sorted
        self.last_burn = -math.inf  # the latest applied burn (one at or before the latest estimate's time)
        self.records = []  # RadarRecord, in arrival order
        self.carrier_records = []  # RadarRecord of the carrier's ranges (the radar's track_carrier), in arrival order
        self.closed = set()  # (station index, pass_id) of the sensor's passes whose end has arrived
        self.arrived = collections.Counter()  # (station index, pass_id) -> measurements received
        self.ends = {}  # (station index, pass_id) -> (measurements, t [s]) of a pass end waiting for them
        self.last_solution = None  # (ODResult, carrier a [m]) of the latest estimate
        self.prior = None  # DriftPrior from the last solution before the latest burn
        self.range_bias = {}  # station name -> (bias [m], 1-sigma [m]) of the latest estimate (range_bias_sigma > 0)
        self.bias_switched = None  # the epoch [s] of the OD whose residual test switched the bias state on
        self.ejection = None  # EjectionPrior: the ejection on record (commanded, then the footage's)
        self.carrier_burns = []  # relative impulses (Burn) of the executed carrier burns, in arrival order
        self.full_estimates = 0  # estimates from enough passes over the arc, without the prediction
        self.prediction_from = None  # the epoch [s] of the first OD from the prediction (an outage)

    def activate(self):
        """Publishers, subscriptions (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self)
        self.od_pub = ls.publisher(OrbitDetermination, interfaces.OD_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_maneuver, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        ls.subscribe(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_truth, interfaces.STREAM,
                     what="truth message", raw=True)  # every sample: decoded from its bytes (Lockstep.subscribe)
        # a pass's measurements before its end (declaration order: the rank of equal stamps)
        ls.subscribe(RadarMeasurement, interfaces.RADAR_TOPIC, self.on_measurement, interfaces.STREAM,
                     what="radar measurement")
        ls.subscribe(RadarPass, interfaces.RADAR_PASS_TOPIC, self.on_pass, interfaces.STREAM, what="radar pass")
        ls.subscribe(RadarMeasurement, interfaces.CARRIER_RADAR_TOPIC, self.on_carrier, interfaces.STREAM,
                     what="carrier range")
        # the prediction a first OD after an outage starts from (issue 41 part 3): the ejection on record
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                     what="ejection event")
        ls.subscribe(TwistWithCovarianceStamped, interfaces.EJECTION_ESTIMATE_TOPIC, self.on_measured_ejection,
                     interfaces.LATCHED, what="ejection estimate")
        self.create_subscription(RadarMeasurement, interfaces.EXTERNAL_RADAR_TOPIC, self.on_external,
                                 interfaces.BULK)
        self.external_timer = None
        publish_status(self, self.diag_pub, OK, "waiting for measurements", self._values())

    def _values(self):
        values = {"measurements": self.received, "passes": len(self.closed),
                  "passes_since_burn": len(self.usable()[1]), "estimates": self.estimates,
                  "last_burn_s": self.last_burn}
        if self.range_bias:  # absent unless estimated: a nominal status as before
            values["range_bias_m"] = json.dumps({k: {"bias": b, "sigma": sb} for k, (b, sb) in self.range_bias.items()})
        return values

    # --- inputs ---------------------------------------------------------------------------------------------
    def on_truth(self, msg: RelativeOrbitalElements):
        """The carrier's chief elements at the sample's epoch (a burn's post-burn sample replaces its pre)."""
        try:
            t, _, kep = parse_truth(msg)
        except ValueError as exc:
            self.get_logger().error(f"truth message rejected: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"truth message rejected: {exc}", self._values())
            return
        k = bisect.bisect_left(self.history_t, t)
        if k < len(self.history_t) and self.history_t[k] == t:
            self.history_kep[k] = kep
        else:
            self.history_t.insert(k, t)
            self.history_kep.insert(k, kep)

    def on_ejection(self, event: EjectionEvent):
        """The commanded ejection with the SPL's errors (as the ic_planner takes it: :class:`EjectionPrior`); a
        measured one on record is kept."""
        try:
            prior = ejection_prior(event, self.scenario)
        except ValueError as exc:
            self._rejected("ejection event", event, exc)
            return
        if self.ejection is None or self.ejection.source == "commanded":
            self.ejection = prior

    def on_measured_ejection(self, msg: TwistWithCovarianceStamped):
        """The executed ejection the footage measured: it replaces the commanded one (needs its chief)."""
        try:
            dv, cov = twist_linear(msg)
        except ValueError as exc:
            self._rejected("ejection estimate", msg, exc)
            return
        if self.ejection is not None:
            self.ejection = self.ejection.measured(dv, cov)

    def on_maneuver(self, msg: ImpulsiveManeuver):
        """A burn: applied to the estimates from its epoch on (:meth:`apply_burns`), whenever it arrives."""
        t = time_to_sec(msg.epoch)
        if msg.spacecraft == "carrier":
            try:
                flown = planned_burn(msg).relative()
                if flown.epoch not in {b.epoch for b in self.carrier_burns}:
                    self.carrier_burns.append(flown)
            except ValueError as exc:
                self.get_logger().error(f"executed maneuver at t = {t:.1f} s rejected: {exc}")
                publish_status(self, self.diag_pub, ERROR, f"executed maneuver rejected: {exc}", self._values())
                return
        bisect.insort(self.burns, t)
        bisect.insort(self.burn_epochs, t)
        self.get_logger().info(f"{msg.spacecraft} {msg.purpose} burn at t = {t:.1f} s: earlier measurements "
                               "are no longer used")

    def apply_burns(self, now):
        """The burns at or before ``now`` [s], in epoch order: each restarts the arc; the drift rate of the last
        solution before it becomes the a priori information of the batches after it."""
        while self.burns and self.burns[0] <= now:
            t = self.burns.pop(0)
            if t > self.last_burn:
                self.last_burn = t
                if self.last_solution is not None and self.last_solution[0].t_est <= t:
                    self.prior = self.drift_prior(*self.last_solution)

    def record(self, msg: RadarMeasurement, pass_id):
        """The :class:`RadarRecord` of a measurement of pass ``pass_id`` with the chief and the Earth orientation
        (GCRS -> ITRS) at its epoch; ValueError naming the problem (no truth yet, an unknown station, non-finite
        values, sigmas other than this node's: the batch weights every record alike)."""
        t = time_to_sec(msg.header.stamp)
        z = np.array([msg.range, msg.azimuth, msg.elevation], dtype=float)
        problem = ("no truth received yet" if not self.history_t else
                   f"unknown station {msg.station!r} (stations: {self.names})" if msg.station not in self.names else
                   "non-finite values" if not (np.all(np.isfinite(z)) and math.isfinite(t)) else
                   f"sigmas {msg.sigma_range} m / {msg.sigma_angle} rad differ from this node's "
                   f"{self.sigma[0]} m / {self.sigma[1]} rad"
                   if not np.allclose([msg.sigma_range, msg.sigma_angle], self.sigma[:2], rtol=1e-9, atol=0.0)
                   else None)
        if problem:
            raise ValueError(problem)
        # the chief as the sensor simulated a measurement at that epoch: from the first truth sample at or after it
        # (the latest if none), blended with the one before (chief_from_samples)
        chief, t_tr = chief_from_samples(self.history_t, self.history_kep, self.burn_epochs, t)
        earth = gcrs_to_itrs(self.jd0, t)
        return RadarRecord(t=t, station=self.names.index(msg.station), pass_id=pass_id, z=z, chief=chief,
                           earth=earth, truth_t=t_tr)

    def _rejected(self, what, msg, exc):
        t = time_to_sec(msg.header.stamp)
        self.get_logger().error(f"{what} at t = {t:.1f} s rejected: {exc}")
        publish_status(self, self.diag_pub, ERROR, f"{what} rejected: {exc}", self._values())

    def on_measurement(self, msg: RadarMeasurement):
        """A measurement of the radar sensor: a record of its pass (which counts once its end has arrived)."""
        self.received += 1
        key = (self.names.index(msg.station) if msg.station in self.names else msg.station, int(msg.pass_id))
        self.arrived[key] += 1
        try:
            self.records.append(self.record(msg, int(msg.pass_id)))
        except ValueError as exc:
            self._rejected("radar measurement", msg, exc)
        if key in self.ends and self.arrived[key] >= self.ends[key][0]:  # run alone: the end came first
            self.pass_closed(key, self.ends.pop(key)[1])

    def on_carrier(self, msg: RadarMeasurement):
        """A station's range to the carrier (the radar's ``track_carrier``): information on its range bias."""
        try:
            self.carrier_records.append(self.record(msg, int(msg.pass_id)))
        except ValueError as exc:
            self._rejected("carrier range", msg, exc)

    def carrier_ranges(self, t_last):
        """The carrier's ranges up to ``t_last`` [s] as :class:`~roe_sep.core.od.batch.CarrierRanges` (a bias is
        constant: every one so far, burns or not), None without any."""
        recs = [r for r in self.carrier_records if r.t <= t_last]
        if not recs:
            return None
        chief = np.array([r.chief for r in recs])
        earth = np.array([r.earth for r in recs])
        site_ef = np.array([self.site_ef[r.station] for r in recs])
        site_enu = np.array([self.site_enu[r.station] for r in recs])
        h = two_way_look(carrier_earth_fixed_state(chief, earth), site_ef, site_enu)[..., 0]
        sigma = np.full(len(recs), math.hypot(self.sigma[0], self.gps_sigma))
        return CarrierRanges(site_ef=site_ef, residual=np.array([r.z[0] for r in recs]) - h, sigma=sigma)

    def on_pass(self, msg: RadarPass):
        """The end of one of the sensor's passes, stamped with the sensor's time: the pass counts, and the OD runs
        on it, once its measurements are in (at once under lockstep; run alone, when the last arrives)."""
        if msg.station not in self.names:
            self._rejected("radar pass end", msg, f"unknown station {msg.station!r} (stations: {self.names})")
            return
        key = (self.names.index(msg.station), int(msg.pass_id))
        if self.arrived[key] >= msg.measurements:
            self.pass_closed(key, time_to_sec(msg.header.stamp))
        else:
            self.ends[key] = (msg.measurements, time_to_sec(msg.header.stamp))

    def pass_closed(self, key, now):
        """Pass ``key`` (station index, pass_id) is complete at sim time ``now`` [s]: it counts, and with enough
        measurements the OD runs."""
        self.closed.add(key)
        count = sum(1 for r in self.records if (r.station, r.pass_id) == key)
        if count >= self.min_pass:
            self.estimate(now)

    def on_external(self, msg: RadarMeasurement):
        """A ground segment's measurement: a record of the external pass -(pass_id + 1) of its station (never an
        open pass); the OD runs one wall second after the last one arrived. Rejected with an ERROR on
        /diagnostics as :meth:`record` says."""
        try:
            self.records.append(self.record(msg, -int(msg.pass_id) - 1))
        except ValueError as exc:
            self._rejected("external measurement", msg, exc)
            return
        self.received += 1
        if self.external_timer is not None:
            self.external_timer.cancel()
            self.destroy_timer(self.external_timer)
        self.external_timer = self.create_timer(1.0, self._external_batch,
                                                clock=RclpyClock(clock_type=ClockType.STEADY_TIME))

    def _external_batch(self):
        self.external_timer.cancel()
        self.get_logger().info("external measurements received: orbit determination")
        self.estimate(self.history_t[-1])

    # --- orbit determination -------------------------------------------------------------------------------
    def usable(self):
        """Records after the latest burn (and from post-burn truth) in counted passes; (records, passes)
        (:func:`~roe_sep.core.od.sensor.counted_passes`)."""
        return counted_passes(self.records, self.last_burn, self.closed, self.min_pass)

    def estimate(self, now):
        """The batch OD on the usable records, published with header stamp ``now`` [s] (the sim time of the
        tracking that closed the pass), after the burns at or before ``now`` (:meth:`apply_burns`)."""
        self.apply_burns(now)
        recs, passes = self.usable()
        if not passes:
            return
        recs.sort(key=lambda r: r.t)
        full = len(passes) >= self.passes_required and recs[-1].t - recs[0].t >= self.min_arc
        use_prediction = self.prediction_due(now, full)
        if not (full or use_prediction):
            return
        s_idx = [r.station for r in recs]
        batch = RadarBatch(t=np.array([r.t for r in recs]), z=np.array([r.z for r in recs]),
                           sigma=np.tile(self.sigma, (len(recs), 1)), chief=np.array([r.chief for r in recs]),
                           earth=np.array([r.earth for r in recs]),
                           site_ef=np.array([self.site_ef[s] for s in s_idx]),
                           site_enu=np.array([self.site_enu[s] for s in s_idx]))
        t_last = float(np.max(batch.t))
        prior = (self.prior.carried(t_last, self.density_walk)
                 if self.prior is not None and self.use_prior and not use_prediction else None)
        try:
            predicted = self.predicted(t_last) if use_prediction else None
            carrier = self.carrier_ranges(t_last)  # the carrier's modelled ranges: once per estimate
            result = self.solve(batch, prior, self.bias_prior(), predicted, carrier)
            if self.bias_auto_sigma > 0.0 and bias_state_switch(result, self.bias_alpha, carrier):
                self.switch_bias_on(result, now, carrier)
                result = self.solve(batch, prior, self.bias_prior(), predicted, carrier)
        except ValueError as exc:
            self.get_logger().error(f"orbit determination failed: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"orbit determination failed: {exc}", self._values())
            return
        self.od_pub.publish(self.od_msg(result, batch.chief[-1], len(passes), now))
        self.estimates += 1
        self.full_estimates += int(full and not use_prediction)
        if use_prediction:
            if self.prediction_from is None:
                self.prediction_from = result.t_est
            self.report_prediction(result, len(passes), now)
        if result.range_bias:
            index, n = station_index(batch)
            first = [int(np.argmax(index == k)) for k in range(n)]
            sig = np.sqrt(np.diag(np.reshape(result.range_bias_cov, (n, n))))
            self.range_bias = {self.names[s_idx[j]]: (result.range_bias[k], float(sig[k]))
                               for k, j in enumerate(first)}
        a = batch.chief[-1, 0]
        self.last_solution = (result, a)
        self.get_logger().info(
            f"OD #{self.estimates} at t = {result.t_est:.0f} s from {len(passes)} passes / {result.measurements} "
            f"measurements: a*ROE = {np.array2string(result.x[:6] * a, precision=1)} m, a*da_dot = "
            f"{result.x[6] * a:.3e} m/s, residual RMS {result.residual_rms:.2f}"
            + ("" if prior is None else f", drift prior from t = {self.prior.t:.0f} s")
            + (f", with the prediction from the {self.ejection.source} ejection as its prior" if use_prediction else "")
            + "".join(f", {name} range bias {b:+.2f} +- {sb:.2f} m" for name, (b, sb) in self.range_bias.items()))
        publish_status(self, self.diag_pub, OK, f"estimate {self.estimates} published", self._values())

    def solve(self, batch, prior, bias, predicted, carrier):
        """The batch OD of ``batch`` with the drift ``prior``, the range-bias prior ``bias``, the state prior
        ``predicted`` and the carrier's ranges ``carrier`` (each or None; the ranges count only with ``bias``)."""
        return batch_least_squares(batch, prior=prior, drag=self.drag_terms,
                                   model=self.drag_model(batch.chief[-1, 0]), bias=bias, carrier=carrier,
                                   state_prior=predicted)

    def prediction_due(self, now, full):
        """Whether this OD takes the prediction as its prior (:func:`~roe_sep.core.od.batch.uses_prediction`)."""
        return uses_prediction(now, full, release=None if self.ejection is None else self.ejection.t,
                               after=self.prior_od_after, full_estimates=self.full_estimates,
                               first_prediction=self.prediction_from,
                               burn_epochs=[b.epoch for b in self.carrier_burns])

    def predicted(self, t_est):
        """The state prior at ``t_est`` [s]: the ejection on record (its ROE and covariance, the nominal drag and its
        sigma) carried through the carrier burns executed since (:func:`~roe_sep.core.od.batch.predicted_prior`)."""
        ej = self.ejection
        od = ej.solution(t_est)
        a = od.kep[0]
        chief = Chief(a, od.kep[2], od.u, od.epoch)
        # the ejection's six ROE come from its three dv components: a floor on each (prior_od_floor) stands for
        # what Eq. 2 leaves out (the release's position offset, mean and osculating elements, unmodelled drag on
        # the e/i vectors over the outage) and makes the prior positive definite
        cov0 = np.reshape(od.covariance, (6, 6)) + self.prior_floor**2 * np.eye(6)
        return predicted_prior(np.array(od.roe), cov0 / a**2, chief, od.a_da_dot / a, od.a_da_dot_sigma / a,
                               burns=self.carrier_burns, t=t_est)

    def report_prediction(self, result, passes, now):
        """An OD from the prediction and ``passes`` pass(es): an ``od_from_prediction`` finding."""
        a = result.a_est
        text = (f"od_from_prediction: OD at t = {result.t_est:.0f} s from {passes} pass(es) after "
                f"{(now - self.ejection.t) / 3600.0:.1f} h without one, with the prediction from the "
                f"{self.ejection.source} ejection and {len(self.carrier_burns)} carrier burn(s) as its prior: "
                f"a dl = {result.x[1] * a:.0f} +- {math.sqrt(result.cov[1, 1]) * a:.0f} m")
        publish_status(self, self.diag_pub, WARN, text, {"contingency": "od_from_prediction", "epoch_s": now,
                                                          "passes": passes}, part="contingency")

    def bias_prior(self):
        """The range-bias state's prior: ``range_bias_sigma`` when set, else ``range_bias_auto_sigma`` once the
        residual test has switched it on (:func:`~roe_sep.core.od.batch.bias_state_switch`), else None."""
        if self.bias_sigma > 0.0:
            return RangeBiasPrior(self.bias_sigma)
        return RangeBiasPrior(self.bias_auto_sigma) if self.bias_switched is not None else None

    def switch_bias_on(self, result, now, carrier):
        """The residual test of ``result`` (or the ``carrier``'s ranges') rejected the model: the range biases are
        estimated from this OD on (a ``range_bias_estimated`` finding on ``roe_sep/radar_od/contingency``)."""
        self.bias_switched = result.t_est
        p = residual_tail(result.residual_rms, result.measurements)
        p_c = 1.0 if carrier is None else carrier_bias_tail(carrier)
        text = (f"OD at t = {result.t_est:.0f} s: residual RMS {result.residual_rms:.2f} sigma over "
                f"{result.measurements} measurements (p = {p:.1e})"
                + ("" if carrier is None else f", carrier ranges p = {p_c:.1e}")
                + f" (level {self.bias_alpha:g}): range biases estimated from now on (a priori 1-sigma "
                f"{self.bias_auto_sigma:g} m)")
        self.get_logger().warning(text)
        publish_status(self, self.diag_pub, WARN, text, {"contingency": "range_bias_estimated", "epoch_s": now,
                                                          "p": p, "p_carrier": p_c}, part="contingency")

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
