"""safety_monitor: passive safety, drift direction, along-track crossings, evaporation and field of view.

Evaluates the truth stream and, separately, the OD estimate (propagated to the present with the burns executed
since its epoch) every ``period`` seconds of sim time, and every plan before its first burn by predicting the
trajectory under it from the best knowledge the ground has (the OD estimate, else the commanded ejection; never
truth). Criteria and thresholds: :mod:`roe_sep.core.safety.monitor`. Publishes ``/safety/status`` (truth and estimate),
``/safety/plan_check`` (one verdict per plan; the simulator executes only approved plans) and ``/diagnostics``.

Contingencies: what the ground can see of one -- a carrier burn executed late, not at all, or off in
magnitude or direction from its approved plan, an OD inconsistent with its prediction from the commanded ejection
and the executed burns, an OD whose residuals are too large -- is raised as a named WARN on ``/diagnostics``
(``roe_sep/safety_monitor/contingency``, value ``contingency`` = the name, ``epoch_s``):
:mod:`roe_sep.core.safety.anomaly`. A failure of that detection is reported, never fatal.

Parameters: :data:`roe_sep.nodes.parameters.SAFETY_MONITOR` (``safety_monitor --help``, docs/parameters.md).
"""

import json
import math

import numpy as np
from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistWithCovarianceStamped
from roe_sep_msgs.msg import (
    EjectionEvent,
    ImpulsiveManeuver,
    ManeuverPlan,
    OrbitDetermination,
    RelativeOrbitalElements,
    SafetyStatus,
)

from .. import interfaces
from ..core.constants import ARCSEC
from ..core.relmotion.dynamics import drag_da_dot
from ..core.relmotion.maneuvers import delta_roe
from ..core.relmotion.orbit import mean_motion
from ..core.relmotion.trajectory import Chief, burn_segments, segments_at, state_at
from ..core.safety.anomaly import AnomalyLimits, AnomalyWatch
from ..core.safety.monitor import MonitorLimits, assess
from .convert import msg_to_roe, plan_burns, sec_to_time, time_to_sec, twist_linear, vector_to_array
from .diagnostics import WARN, StatusMessages, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import declare, scenario_of

PLAN_TOPICS = (interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.ACQUISITION_PLAN_TOPIC)
MEASURED_PURPOSES = ("collision_avoidance", "ejection_completion")  # burns of a plan made on the measured ejection
DIAG_KEYS = ("t_s", "along_track_m", "min_distance_m", "min_rn_m", "nearest_crossing_m")  # an assessment's status


class Knowledge:
    """A relative state the ground knows: dimensionless ROE at an epoch, the chief then, and a drag drift."""

    def __init__(self, roe, t, chief: Chief, da_dot):
        self.roe, self.t, self.chief, self.da_dot = roe, t, chief, da_dot
        self.arcs = None  # (burns, burn_segments) of the state under the burns executed since t (state_now)

    def state_now(self, executed, t_now, j2):
        """The ROE at ``t_now`` under the ``executed`` burns after ``t``: :func:`state_at`, with the coast arcs kept
        while no burn is added (an assessment per truth sample: one propagation each, the same values)."""
        burns = [b for b in executed if b.epoch > self.t]
        if self.arcs is None or self.arcs[0] != burns:
            self.arcs = (burns, burn_segments(self.roe, self.t, burns, self.chief, j2, da_dot=self.da_dot))
        arcs = self.arcs[1]
        if not t_now >= max(self.t, arcs[-1][0]):  # before t (an error) or before a burn: as it always was
            return state_at(self.roe, self.t, burns, t_now, self.chief, j2=j2, da_dot=self.da_dot)
        return segments_at(arcs[-1:], np.array([t_now]), self.t, self.chief, j2, da_dot=self.da_dot)[0]


def chief_of(msg: RelativeOrbitalElements, t):
    c = msg.chief
    return Chief(c.semi_major_axis, c.inclination, c.mean_arg_latitude, t)


class SafetyMonitorNode(ManagedNode):
    def __init__(self):
        super().__init__("safety_monitor")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        scenario_file = declare(self, "scenario_file")
        self.period = declare(self, "period")
        names = ("keep_out", "min_rn_distance", "crossing_min", "evaporation", "a_dl_min", "a_dl_max", "window",
                 "plan_horizon")
        values = {name: declare(self, name) for name in names}
        fov_r = declare(self, "fov_half_r_deg")
        fov_n = declare(self, "fov_half_n_deg")
        self.j2 = declare(self, "j2")
        self.limits = MonitorLimits(fov_half_r=math.radians(fov_r), fov_half_n=math.radians(fov_n),
                                    **{k: float(v) for k, v in values.items()})
        self.scenario = scenario_of(scenario_file)

        self.last_truth = -math.inf
        self.last_estimate = -math.inf
        self.estimate = None  # Knowledge from the OD
        self.ejection = None  # Knowledge from the commanded ejection, or from the measured one once there is one
        self.measured = None  # the footage's executed ejection: (dv (3,) [m/s], covariance (3, 3) [m^2/s^2])
        self.executed = []  # Burns executed so far
        anomaly = AnomalyLimits(declare(self, "burn_epoch_tolerance"), declare(self, "burn_magnitude_z"),
                                declare(self, "burn_pointing_deg"), declare(self, "od_alpha"),
                                declare(self, "od_model_sigma"), declare(self, "residual_alpha"))
        sep, mc = self.scenario.separation, self.scenario.monte_carlo
        self.watch = AnomalyWatch(anomaly, sep.spl_sigma, sep.thruster_sigma, mc.attitude_sigma_arcsec * ARCSEC,
                                  self.j2)
        self.checked = set()
        self.pending_plans = {}

    def activate(self):
        """Publishers, subscriptions, services (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self)
        self.status_pub = ls.publisher(SafetyStatus, interfaces.SAFETY_TOPIC, interfaces.STREAM)
        self.check_pub = ls.publisher(SafetyStatus, interfaces.PLAN_CHECK_TOPIC, interfaces.EXECUTED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.status_msgs, self.diag_msgs = {}, {}  # publish()'s messages, per publisher and per status part
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_executed, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        ls.subscribe(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_truth, interfaces.STREAM,
                     what="truth state", raw=True)  # every sample: decoded from its bytes (Lockstep.subscribe)
        ls.subscribe(OrbitDetermination, interfaces.OD_TOPIC, self.on_estimate, interfaces.LATCHED, what="OD estimate")
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                     what="ejection event")
        ls.subscribe(TwistWithCovarianceStamped, interfaces.EJECTION_ESTIMATE_TOPIC, self.on_measured_ejection,
                     interfaces.LATCHED, what="ejection estimate")
        for topic in PLAN_TOPICS:
            ls.subscribe(ManeuverPlan, topic, lambda m, tp=topic: self.on_plan(tp, m), interfaces.LATCHED,
                         what=f"plan on {topic}")

    # ---------------------------------------------------------------- helpers
    def nominal_da_dot(self, a):
        mc = self.scenario.monte_carlo
        return float(drag_da_dot(mc.delta_b, mc.density, a)) if mc.drag else 0.0

    def publish(self, source, t, res, plan_stamp=None, pub=None):
        """The assessment on ``pub`` (default ``/safety/status``) and its diagnostic status. Each publisher's
        SafetyStatus and each part's diagnostic messages are built once and refilled, every field set at every
        publication (rclpy serializes at publish: the bytes of new messages)."""
        pub = pub or self.status_pub
        msg = self.status_msgs.get(id(pub))
        if msg is None:
            msg = self.status_msgs[id(pub)] = SafetyStatus()
        msg.source, msg.safe, msg.approaching = source, res.safe, res.approaching
        msg.along_track_separation, msg.distance = res.along_track_separation, res.distance
        msg.min_rn_distance, msg.nearest_crossing = res.min_rn_distance, res.nearest_crossing
        msg.evaporated, msg.in_fov, msg.violations = res.evaporated, res.in_fov, list(res.failed)
        msg.header.stamp = sec_to_time(t)
        msg.plan_stamp = Time() if plan_stamp is None else plan_stamp
        pub.publish(msg)
        text = "all criteria pass" if not res.failed else "failed: " + ", ".join(res.failed)
        part = source.split(":")[0]
        diag = self.diag_msgs.get(part)
        if diag is None:
            diag = self.diag_msgs[part] = StatusMessages(self, self.diag_pub, DIAG_KEYS, part=part)
        diag.publish(res.level, f"{source}: {text}", {
            "t_s": f"{t:.0f}", "along_track_m": f"{res.along_track_separation:.1f}",
            "min_distance_m": f"{res.min_distance:.1f}", "min_rn_m": f"{res.min_rn_distance:.1f}",
            "nearest_crossing_m": f"{res.nearest_crossing:.1f}"})

    def reject(self, what, exc):
        self.get_logger().error(f"{what} rejected: {exc}")
        publish_status(self, self.diag_pub, 2, f"{what} rejected: {exc}", part="input")

    def detect(self, what, call):
        """Run one contingency detection (``call()`` -> detections) and raise each one found; a failure is reported
        (ERROR on /diagnostics), never fatal."""
        try:
            found = call()
        except Exception as exc:  # noqa: BLE001 -- a contingency must never crash the monitor
            self.reject(f"contingency detection on {what}", f"{type(exc).__name__}: {exc}")
            return
        for d in found:
            self.get_logger().warning(f"contingency detected: {d.name}: {d.text}")
            values = {"contingency": d.name, "epoch_s": f"{d.epoch:.1f}",
                      **{k: json.dumps(v) for k, v in d.values.items()}}
            publish_status(self, self.diag_pub, WARN, f"{d.name}: {d.text}", values, part="contingency",
                           stamp=d.epoch)

    def knowledge(self):
        """The newest ground knowledge: the OD estimate, else the ejection (the footage's measured one once there is
        one, else the commanded one)."""
        return self.estimate or self.ejection

    # ----------------------------------------------------------------- inputs
    def on_truth(self, msg: RelativeOrbitalElements):
        try:
            t = time_to_sec(msg.header.stamp)
            roe = msg_to_roe(msg)
            if not (math.isfinite(t) and np.isfinite(roe).all()):
                raise ValueError("non-finite state")
            self.detect("sim time", lambda: self.watch.at(t))
            if t - self.last_truth < self.period or not roe.any():  # nothing to assess before the release
                return
            self.last_truth = t
            chief = chief_of(msg, t)
            da_dot = self.estimate.da_dot if self.estimate else self.nominal_da_dot(chief.a)
            self.publish("truth", t, assess(roe, t, chief, self.limits, j2=self.j2, da_dot=da_dot))
            self.assess_estimate(t)
        except (ValueError, ZeroDivisionError) as exc:
            self.reject("truth state", exc)

    def assess_estimate(self, t_now):
        k = self.estimate
        if k is None or t_now - self.last_estimate < self.period:
            return
        self.last_estimate = t_now
        roe = k.state_now(self.executed, t_now, self.j2)
        chief = Chief(k.chief.a, k.chief.inc, float(k.chief.u_at(t_now, self.j2)), t_now)
        self.publish("estimate", t_now, assess(roe, t_now, chief, self.limits, j2=self.j2, da_dot=k.da_dot))

    def on_estimate(self, od: OrbitDetermination):
        try:
            est = od.estimate
            t = time_to_sec(est.header.stamp)
            roe = msg_to_roe(est)
            da_dot = od.a_da_dot / est.chief.semi_major_axis
            if not (math.isfinite(t) and np.all(np.isfinite(roe)) and math.isfinite(da_dot)):
                raise ValueError("non-finite estimate")
            self.estimate = Knowledge(roe, t, chief_of(est, t), da_dot)
            cov = np.asarray(est.covariance, dtype=float).reshape(6, 6)
            self.detect("OD estimate", lambda: self.watch.od(
                time_to_sec(od.header.stamp), t, roe, cov, self.estimate.chief, da_dot=da_dot,
                residual_rms=od.residual_rms,
                measurements=od.measurements))
            self.last_estimate = -math.inf
            self.assess_estimate(t)
            self.recheck_pending()
        except (ValueError, ZeroDivisionError) as exc:
            self.reject("OD estimate", exc)

    def on_ejection(self, ev: EjectionEvent):
        try:
            t = time_to_sec(ev.header.stamp)
            c = ev.chief
            chief = Chief(c.semi_major_axis, c.inclination, c.mean_arg_latitude, t)
            dv = vector_to_array(ev.ejection.dv_rtn)
            roe = delta_roe(dv, chief.u0, chief.a, mean_motion(chief.a))
            if not (math.isfinite(t) and np.all(np.isfinite(roe))):
                raise ValueError("non-finite ejection")
            self.ejection = Knowledge(roe, t, chief, self.nominal_da_dot(chief.a))
            self.detect("ejection event", lambda: self.watch.ejection(t, dv, chief, self.ejection.da_dot) or [])
            self.take_measured()
            self.recheck_pending()
        except (ValueError, ZeroDivisionError) as exc:
            self.reject("ejection event", exc)

    def on_measured_ejection(self, msg: TwistWithCovarianceStamped):
        """The executed ejection the planner's ground filter measured from the footage: from now on the knowledge of
        the ejection (plans are judged from it until an OD; issue 41 part 2)."""
        try:
            dv, cov = twist_linear(msg)
        except ValueError as exc:
            self.reject("ejection estimate", exc)
            return
        self.measured = (dv, cov)
        self.take_measured()
        self.recheck_pending()

    def take_measured(self):
        """The measured ejection replaces the commanded one's knowledge (both must have come)."""
        if self.measured is None or self.ejection is None:
            return
        dv, cov = self.measured
        k = self.ejection
        self.ejection = Knowledge(delta_roe(dv, k.chief.u0, k.chief.a, mean_motion(k.chief.a)), k.t, k.chief,
                                  k.da_dot)
        self.detect("ejection estimate", lambda: self.watch.measured_ejection(dv, cov) or [])

    def on_executed(self, m: ImpulsiveManeuver):
        try:
            if m.purpose != "ejection":
                self.executed.append(plan_burns([m])[0])
        except ValueError as exc:
            self.reject("executed maneuver", exc)
            return
        self.detect("executed maneuver", lambda: self.watch.executed(
            time_to_sec(m.epoch), vector_to_array(m.dv_rtn), m.spacecraft, m.purpose, m.mean_arg_latitude))

    def on_plan(self, topic, plan: ManeuverPlan):
        key = (topic, time_to_sec(plan.header.stamp))
        if key in self.checked:
            return
        self.pending_plans[key] = plan
        self.recheck_pending()

    def recheck_pending(self):
        for key, plan in list(self.pending_plans.items()):
            if self.check_plan(key, plan):
                del self.pending_plans[key]
                self.checked.add(key)

    def check_plan(self, key, plan: ManeuverPlan):
        """Predict the trajectory under ``plan`` from the newest knowledge; False while there is none."""
        topic, _ = key
        k = self.knowledge()
        if k is None or self.measured is None and any(m.purpose in MEASURED_PURPOSES for m in plan.maneuvers):
            return False  # a plan made on the measured ejection waits for it
        source = f"plan:{topic}"
        try:
            burns = plan_burns(plan.maneuvers)
            if not (burns or topic == interfaces.DRIFT_STOP_PLAN_TOPIC) \
                    or not all(math.isfinite(b.epoch) and np.all(np.isfinite(b.dv_rel)) for b in burns):
                raise ValueError("empty plan or non-finite burn")
            done = [b for b in self.executed if b.epoch > k.t]
            future = [b for b in burns if b.epoch >= k.t]
            # an empty drift-stop plan withdraws the drift-stop (the planner's hold): the drift checked as it is
            t_end = max((b.epoch for b in burns), default=max(k.t, time_to_sec(plan.header.stamp))) \
                + self.limits.plan_horizon
            res = assess(k.roe, k.t, k.chief, self.limits, done + future, t_end=t_end, j2=self.j2, da_dot=k.da_dot)
        except ValueError as exc:
            self.reject(f"plan on {topic}", exc)
            res = None
        if res is None:
            msg = SafetyStatus(source=source, safe=False, violations=["invalid_plan"], plan_stamp=plan.header.stamp)
            msg.header.stamp = plan.header.stamp
            self.check_pub.publish(msg)
            return True
        self.publish(source, k.t, res, plan_stamp=plan.header.stamp, pub=self.check_pub)
        if res.safe:  # the simulator flies it: its carrier burns are expected as planned
            self.detect(f"plan on {topic}", lambda: self.watch.plan(topic, [
                (time_to_sec(m.epoch), vector_to_array(m.dv_rtn), m.spacecraft, m.purpose) for m in plan.maneuvers],
                plan.p_reduction) or [])
        self.get_logger().info(f"{source} checked: {'safe' if res.safe else 'UNSAFE'} {res.failed or ''}")
        return True


def main(args=None):
    from .spin import run

    return run(SafetyMonitorNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
