"""planner: the carrier's blind drift-stop, planned from the commanded ejection only (never from truth).

Subscribes ``/separation/ejection`` (roe_sep_msgs/EjectionEvent, latched) and publishes the drift-stop
``/separation/drift_stop_plan`` (roe_sep_msgs/ManeuverPlan, RELIABLE + TRANSIENT_LOCAL, depth 1) as soon as an
event arrives. Physics: :func:`roe_sep.core.separation.double_impulse.plan_drift_stop` (seed 002 Eqs. 9, 18).

Parameters (YAML via ``--ros-args --params-file``): :data:`roe_sep.nodes.parameters.PLANNER` (``planner --help``,
docs/parameters.md). ``strategy`` ``multi_impulse`` (seed 001 Sec. 3,
:func:`roe_sep.core.separation.multi_impulse.plan_carrier_burns`) publishes every carrier burn of the multi-impulse
plan (blind drift reduction with |p| of Eq. 21, then the tangential e-vector pair) as one ManeuverPlan with strategy
"multi_impulse" on the same topic.

Two contingency mitigations (docs/contingencies.md, "What the closed loop does about them"), each a parameter:

* ``drift_stop_retry``: when the executed-maneuver record (``/sim/executed_maneuvers``) holds no drift-stop
  ``retry_tolerance`` after the epoch of the drift-stop in force (missed or late), the same drift-stop (seed 002
  Eqs. 9, 18) is re-published whole orbits later, at its argument of latitude, the first such epoch at least
  ``retry_margin`` after the finding, stamped with the finding's epoch: a new plan, checked by the safety monitor
  like any other; the along-track separation grows meanwhile at the post-ejection rate (Eq. 13).
* ``drift_stop_makeup``: when the record's drift-stop departs from its command (magnitude beyond ``makeup_z``
  sigmas of the thruster's error, direction beyond ``makeup_pointing_deg``: the monitor's ``burn_magnitude``,
  ``burn_pointing``), the rest, commanded minus executed, flies whole orbits later at the same argument of latitude
  (seed 002 Eq. 2 is linear in the burn at a given u: the two burns together give the designed e/i vectors and
  drift), the first such epoch at least ``retry_margin`` after the finding: ``drift_stop_completed``.
* ``weak_ejection_hold``: the carrier camera's bearings of the picosatellite (``/sim/camera/bearing``, the
  simulator's sensor: unit lines of sight with their noise; the planner never reads the truth) from the release to
  ``hold_lead`` before the drift-stop are tested against the commanded ejection
  (:func:`~roe_sep.core.safety.ejection_check.check_ejection`: the bearings see the SPL's fraction over the drag's,
  f1 / g; held when they exclude every nominal pair); a weak ejection withdraws the drift-stop: an empty plan,
  after which the ic_planner starts the acquisition from the first OD. Each finding is a WARN
  ``roe_sep/planner/contingency`` on ``/diagnostics`` (value ``contingency``: ``drift_stop_replaced``,
  ``drift_stop_completed`` or ``weak_ejection``, ``epoch_s``).

A restarted planner re-publishes the plan of the latched ejection event and recovers what was executed from the
latched executed-maneuver record before it may find a drift-stop missing (:meth:`PlannerNode.record_recovered`).
"""

import dataclasses
import math
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from roe_sep_msgs.msg import EjectionEvent, ImpulsiveManeuver, ManeuverPlan
from roe_sep_msgs.srv import PlanSeparation

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.montecarlo.sweep import p_best
from ..core.relmotion.dynamics import arg_latitude_rate, drag_da_dot, propagate_chief, raan_rate
from ..core.relmotion.orbit import angle_between
from ..core.relmotion.roe import wrap_angle
from ..core.safety.anomaly import magnitude_z
from ..core.safety.ejection_check import check_ejection, nominal_fraction
from ..core.separation.double_impulse import design, plan_drift_stop, reduction_bounds
from ..core.separation.multi_impulse import MultiImpulseConfig, multi_config, plan_carrier_burns
from ..core.truth.secular import error_references
from .convert import elements_to_array, maneuver_msg, roe_to_msg, sec_to_time, time_to_sec, vector_to_array
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare, finite
from .sweep_store import cache_dir, p_best_stored

RECORD_SETTLE = 2.0  # wall s a restarted planner (no lockstep) lets the latched executed record arrive in full


def startup_p(scenario, samples, seed):
    """The drift-stop reduction |p| [m/s] of p_mode 'monte_carlo': p_best of a ``samples``-sample sweep with
    ``seed`` (seed 002 Table 3), memoised in the process and stored on disk (:func:`cache_dir`,
    :func:`~roe_sep.nodes.sweep_store.p_best_stored`): identical in every run of a scenario, computed once."""
    mc = dataclasses.replace(scenario.monte_carlo, samples=samples, seed=seed)
    directory = cache_dir()
    if directory is None:
        return p_best(scenario.separation, mc, tuple(scenario.p_values))
    return p_best_stored(scenario.separation, mc, tuple(scenario.p_values), directory)


class PlannerNode(ManagedNode):
    def __init__(self):
        super().__init__("planner")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        self.k = declare(self, "k")
        self.p_mode = declare(self, "p_mode")
        p_fixed = declare(self, "p_reduction")
        scenario_file = declare(self, "scenario_file")
        samples = declare(self, "mc_samples")
        seed = declare(self, "mc_seed")
        self.j2 = declare(self, "j2")
        self.strategy = declare(self, "strategy")
        self.retry = declare(self, "drift_stop_retry")
        self.retry_tolerance = declare(self, "retry_tolerance")
        self.retry_margin = declare(self, "retry_margin")
        self.makeup = declare(self, "drift_stop_makeup")
        self.makeup_z = declare(self, "makeup_z")
        self.makeup_pointing = math.radians(declare(self, "makeup_pointing_deg"))
        self.hold = declare(self, "weak_ejection_hold")
        self.camera_sigma = math.radians(declare(self, "camera_sigma_deg"))
        self.camera_floor = declare(self, "camera_model_floor")
        self.hold_sigmas = declare(self, "hold_sigmas")
        self.hold_alpha = declare(self, "hold_alpha")
        self.hold_lead = declare(self, "hold_lead")
        try:
            self.scenario = load_scenario(scenario_file or None)
        except ConfigError as exc:
            raise ParameterError(f"parameter 'scenario_file': {exc}") from exc

        if self.strategy == "multi_impulse":
            self.multi = MultiImpulseConfig()
            self.p = None  # Eq. (21) from each commanded ejection
        elif self.p_mode == "fixed":
            self.p = float(p_fixed)
        elif self.p_mode == "monte_carlo":
            self.p = startup_p(self.scenario, samples, seed)
            self.get_logger().info(f"p = {self.p:g} m/s: p_best of a {samples}-sample Monte Carlo sweep")
        else:
            self.p = None  # computed from each commanded ejection

    def activate(self):
        """Publishers, subscriptions, services (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self, on_step=self.on_step)
        self.plan_pub = ls.publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                     what="ejection event")
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_executed, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        ls.subscribe(Vector3Stamped, interfaces.CAMERA_TOPIC, self.on_bearing, interfaces.STREAM,
                     what="camera bearing")
        self.in_force = None  # (event, k (None: the default), p [m/s], drift-stop epoch [s]) of the plan in force
        self.executed_stops = []  # (epoch [s], carrier dv RTN (3,) [m/s]) of the executed drift-stops on record
        self.released = None  # s, the deployer's release (the executed ejection's epoch on record)
        self.record_since = None  # steady s: the executed ejection arrived (a restarted planner's record recovered)
        self.bearings = []  # (t [s], measured unit line of sight (3,)) of the camera
        self.camera_done = False  # the camera's decision is made (or not needed)
        self.retried = set()  # drift-stop epochs (to the ms) already replaced
        # without lockstep steps (a free-running clock) the sim-time checks run on a timer
        self.free_timer = self.create_timer(1.0, self._free_running_step)
        self.create_service(PlanSeparation, interfaces.PLAN_SERVICE, self.on_plan_request)
        self.plans = 0
        publish_status(self, self.diag_pub, OK, "waiting for the ejection event", self._values())

    def _values(self):
        return {"strategy": self.strategy, "k": self.k, "p_mode": self.p_mode,
                "p": "per event" if self.p is None else self.p,
                "plans": self.plans}

    def on_ejection(self, event: EjectionEvent):
        try:
            plan = self.make_plan(event)
        except ValueError as exc:
            self.get_logger().error(f"ejection event rejected: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"ejection event rejected: {exc}", self._values())
            return
        self.plan_pub.publish(plan)
        self.plans += 1
        if self.strategy != "multi_impulse":
            self.in_force = (event, None, plan.p_reduction, time_to_sec(plan.maneuvers[0].epoch))
        burn = plan.maneuvers[0]
        self.get_logger().info(
            f"drift-stop planned at t = {time_to_sec(burn.epoch):.1f} s, carrier dv RTN = "
            f"({burn.dv_rtn.x:+.6f}, {burn.dv_rtn.y:+.6f}, {burn.dv_rtn.z:+.6f}) m/s, p = {plan.p_reduction:g} m/s")
        publish_status(self, self.diag_pub, OK, "drift-stop plan published", self._values())

    def now(self):
        return self.get_clock().now().nanoseconds * 1e-9

    def _free_running_step(self):
        """The sim-time checks each second of sim time without lockstep steps. Once a step message has come
        (lockstep mode is never left) each step runs them and the timer is cancelled: it had nothing left to do, and
        the EventsExecutor still fired it about 50 times per 600 s step of sim time (24,000 callbacks a run)."""
        if self.lockstep.active:
            self.free_timer.cancel()
            return
        self.on_step(self.now())

    def on_executed(self, m: ImpulsiveManeuver):
        t = time_to_sec(m.epoch)
        if m.spacecraft == "carrier" and m.purpose == "drift_stop":
            self.executed_stops.append((t, vector_to_array(m.dv_rtn)))
        elif m.purpose == "ejection" and self.released is None:
            self.released = t  # the release switch: when, not how fast
            self.record_since = time.monotonic()

    def record_recovered(self):
        """Whether the executed-maneuver record is complete enough to say a drift-stop is missing: the executed
        ejection is on it (the record is latched and in order, and no drift-stop flies before the ejection), and,
        without lockstep (where every round holds every message the simulator counted, the latched history of a
        restarted planner included), ``RECORD_SETTLE`` wall seconds have passed since it arrived, so that the rest
        of the latched history has been taken too."""
        if self.released is None:
            return False
        return self.lockstep.active or time.monotonic() - self.record_since >= RECORD_SETTLE

    def on_bearing(self, msg: Vector3Stamped):
        """The carrier camera's measured line of sight (the simulator's sensor, noise included), kept until the
        decision."""
        if self.hold and not self.camera_done:
            self.bearings.append((time_to_sec(msg.header.stamp), vector_to_array(msg.vector)))

    def on_step(self, t):
        """Sim-time checks (each lockstep step; a timer without one): the camera's decision before the drift-stop,
        a missing drift-stop's replacement."""
        if self.in_force is None:
            return
        try:
            if not self.camera_done and t >= self.in_force[3] - self.hold_lead:
                self.camera_decision(t)
            if self.retry and self.in_force is not None:
                self.check_missing(t)
            if self.makeup and self.in_force is not None:
                self.check_executed(t)
        except ValueError as exc:
            self.get_logger().error(f"drift-stop check failed: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"drift-stop check failed: {exc}", self._values())

    def finding(self, name, t, text, values=None):
        """A contingency the planner acted on: logged and a named WARN on /diagnostics."""
        self.get_logger().warning(f"{name}: {text}")
        publish_status(self, self.diag_pub, WARN, f"{name}: {text}",
                       {"contingency": name, "epoch_s": f"{t:.1f}", **(values or {})}, part="contingency", stamp=t)

    def camera_decision(self, t):
        """Test the camera's bearings against the commanded ejection; withdraw the drift-stop of a weak one."""
        self.camera_done = True
        self.lockstep.unsubscribe(interfaces.CAMERA_TOPIC)  # the same whether or not the hold is on
        event, _, _, t_stop = self.in_force
        if not self.hold or self.released is None or t >= t_stop or not self.bearings:
            return
        chief = elements_to_array(event.chief)
        chief = propagate_chief(chief, self.released - time_to_sec(event.header.stamp), self.j2)
        mc = self.scenario.monte_carlo
        da_dot = float(drag_da_dot(mc.delta_b, mc.density, chief[0])) if mc.drag else 0.0
        times = np.array([b[0] for b in self.bearings])
        los = np.array([b[1] for b in self.bearings])
        bound = nominal_fraction(self.scenario.separation.spl_sigma, mc.ballistic_sigma, self.hold_sigmas)
        check = check_ejection(times, los, vector_to_array(event.ejection.dv_rtn), self.released, chief, da_dot,
                               self.camera_sigma, self.camera_floor, bound, self.hold_alpha, self.j2)
        self.bearings = []
        self.get_logger().info(f"camera check of the ejection: best f1/g = {check.f1:.2f} (nominal >= "
                               f"{bound:.3f}), chi-square gain {check.gain:.1f}, {check.samples} bearings: "
                               f"{'drift-stop held' if check.weak else 'drift-stop flies'}")
        if not check.weak:
            return
        hold = ManeuverPlan(strategy="double_impulse", ejection_epoch=event.header.stamp, p_reduction=0.0)
        hold.header.stamp = sec_to_time(t)
        hold.header.frame_id = interfaces.CARRIER_RTN_FRAME
        self.plan_pub.publish(hold)
        self.plans += 1
        self.in_force = None
        self.finding("weak_ejection", t, f"the camera's bearings fit f1 = {check.f1:.2f} of the commanded ejection "
                     f"at the nominal drag (chi-square gain {check.gain:.1f} over the nominal set f1/g >= "
                     f"{bound:.3f}, {check.samples} bearings): drift-stop "
                     f"at t = {t_stop:.0f} s withdrawn, the acquisition starts from the first OD",
                     {"f1": f"{check.f1:.3f}", "gain": f"{check.gain:.2f}", "samples": check.samples})

    def orbits_later(self, event, t, t_burn):
        """Whole orbits after ``t_burn`` [s] (at least one) to the first epoch ``retry_margin`` after the finding at
        ``t`` [s], and the orbit's period [s] (du/dt of the event's chief): where a replaced or completed drift-stop
        flies at its argument of latitude."""
        chief = event.chief
        period = 2.0 * math.pi / float(arg_latitude_rate(chief.semi_major_axis, chief.inclination, self.j2))
        return max(1, math.ceil((t + self.retry_margin - t_burn) / period - 1e-9)), period

    def check_missing(self, t):
        """Replace the drift-stop in force when the record shows none ``retry_tolerance`` after its epoch."""
        event, k, p, t_stop = self.in_force
        key = round(t_stop, 3)
        if t <= t_stop + self.retry_tolerance or key in self.retried or not self.record_recovered():
            return
        if any(e >= t_stop - self.retry_tolerance for e, _ in self.executed_stops):
            return
        self.retried.add(key)
        k = self.k if k is None else k
        orbits, _ = self.orbits_later(event, t, t_stop)
        plan = self.make_plan(event, k=k + 2 * orbits, p=p)
        plan.header.stamp = sec_to_time(t)  # a new plan, from the finding on
        self.plan_pub.publish(plan)
        self.plans += 1
        t_new = time_to_sec(plan.maneuvers[0].epoch)
        self.in_force = (event, k + 2 * orbits, p, t_new)
        self.finding("drift_stop_replaced", t, f"no drift-stop on record {t - t_stop:.0f} s after its epoch "
                     f"t = {t_stop:.1f} s: the same drift-stop {orbits} orbit(s) later, at t = {t_new:.1f} s",
                     {"planned_epoch_s": f"{t_stop:.1f}", "replacement_epoch_s": f"{t_new:.1f}"})

    def check_executed(self, t):
        """Complete the drift-stop in force when the record's drift-stop departs from its command: the rest,
        commanded minus executed, whole orbits later at the same argument of latitude."""
        event, k, p, t_stop = self.in_force
        done = [(e, dv) for e, dv in self.executed_stops if e >= t_stop - self.retry_tolerance]
        if not done or self.strategy == "multi_impulse" or not self.record_recovered():
            return
        if len(done) > 1:  # a completion already flew (a restarted planner's record)
            self.in_force = None
            return
        t_exec, dv_exec = done[0]
        plan = self.make_plan(event, k=k, p=p)
        burn = plan.maneuvers[0]
        dv_cmd = vector_to_array(burn.dv_rtn)
        ref = error_references(["drift_stop"], [dv_cmd], plan.p_reduction)[0]
        z = magnitude_z(dv_exec, dv_cmd, ref, self.scenario.separation.thruster_sigma)
        off = float(angle_between(dv_exec, dv_cmd))
        self.in_force = None  # one drift-stop, checked once
        if (z is None or abs(z) <= self.makeup_z) and off <= self.makeup_pointing:
            return
        t_cmd = time_to_sec(burn.epoch)
        orbits, period = self.orbits_later(event, t, t_cmd)
        t_new = t_cmd + orbits * period
        rest = dv_cmd - dv_exec
        out = ManeuverPlan(strategy="double_impulse", ejection_epoch=event.header.stamp, p_reduction=0.0)
        out.header.stamp = sec_to_time(t)  # a new plan, from the finding on
        out.header.frame_id = interfaces.CARRIER_RTN_FRAME
        out.maneuvers = [maneuver_msg(t_new, burn.mean_arg_latitude, rest, "carrier", "drift_stop")]
        out.aimed = plan.aimed
        self.plan_pub.publish(out)
        self.plans += 1
        self.finding("drift_stop_completed", t, f"the drift-stop at t = {t_exec:.1f} s executed "
                     f"{float(np.linalg.norm(dv_exec)):.4f} m/s of {float(np.linalg.norm(dv_cmd)):.4f} m/s "
                     f"({'n/a' if z is None else f'{z:+.1f}'} sigma, {math.degrees(off):.2f} deg off): the rest, "
                     f"{float(np.linalg.norm(rest)):.4f} m/s, {orbits} orbit(s) later at t = {t_new:.1f} s",
                     {"executed_epoch_s": f"{t_exec:.1f}", "completion_epoch_s": f"{t_new:.1f}",
                      "rest_m_s": f"{float(np.linalg.norm(rest)):.4f}"})

    def on_plan_request(self, request, response):
        """PlanSeparation service: design the separation for a requested configuration (zero = default)."""
        try:
            if self.strategy == "multi_impulse":
                d, plan_kw = self._multi_design(request), {}
            else:
                changes = {name: value for name, value in (
                    ("altitude", request.altitude), ("spl_dv", request.spl_dv), ("a_de_f", request.a_de_f),
                    ("a_di_f", request.a_di_f), ("k", request.k or self.k)) if value}
                changes["u1_deg"] = math.degrees(request.u1)
                changes["leading"] = not request.following
                d = design(dataclasses.replace(self.scenario.separation, **changes))
                p = request.p_reduction if request.p_reduction >= 0 else self.p
                plan_kw = {"k": d.k, "p": reduction_bounds(d.dv1_rtn[1], d.config)[0] if p is None else p}
            event = EjectionEvent(dv_magnitude=d.config.spl_dv)
            event.header.stamp = request.ejection_epoch
            event.ejection = maneuver_msg(time_to_sec(request.ejection_epoch), d.u1, d.dv1_rtn, "picosatellite",
                                          "ejection")
            event.chief.semi_major_axis, event.chief.inclination = d.a, d.inc
            event.chief.mean_arg_latitude = float(wrap_angle(d.u1))
            plan = self.make_plan(event, **plan_kw)
            plan.maneuvers = [event.ejection, *plan.maneuvers]
            response.success, response.message, response.plan = True, "ok", plan
        except ValueError as exc:
            response.success, response.message = False, str(exc)
        return response

    def _multi_design(self, request):
        """The multi-impulse design of a PlanSeparation request: SPL size, u1, a_di_f, altitude, side from the
        request (zero = default; ``k``, ``a_de_f`` and ``p_reduction`` do not apply)."""
        from ..core.separation import multi_impulse

        sep = dataclasses.replace(self.scenario.separation, leading=not request.following,
                                  **({"altitude": request.altitude} if request.altitude else {}))
        mcfg = dataclasses.replace(self.multi, u1_deg=math.degrees(request.u1),
                                   **{k: v for k, v in (("spl_dv", request.spl_dv), ("a_di_f", request.a_di_f)) if v})
        return multi_impulse.design(sep, mcfg, self.scenario.monte_carlo, self.j2)

    def make_plan(self, event: EjectionEvent, k=None, p=None) -> ManeuverPlan:
        """The ManeuverPlan for one event; raises ValueError on a malformed event (NaN, impossible orbit)."""
        chief = event.chief
        a, inc = chief.semi_major_axis, chief.inclination
        if not (finite(a) and a > 6.4e6 and finite(inc) and finite(chief.raan)):
            raise ValueError(f"chief elements are not a valid low Earth orbit (a = {a} m, i = {inc} rad)")
        dv1 = vector_to_array(event.ejection.dv_rtn)
        u1 = event.ejection.mean_arg_latitude
        epoch1 = time_to_sec(event.header.stamp)
        if not np.all(np.isfinite(dv1)):
            raise ValueError(f"ejection dv is not finite: {dv1.tolist()}")
        if self.strategy == "multi_impulse":
            return self._multi_plan(event, dv1, u1, epoch1, a, inc)
        if p is None:
            p = reduction_bounds(dv1[1], self.scenario.separation)[0] if self.p is None else self.p
        stop = plan_drift_stop(dv1, u1, epoch1, a, inc, k or self.k, p, self.j2)

        msg = ManeuverPlan(strategy="double_impulse", ejection_epoch=event.header.stamp, p_reduction=float(stop.p))
        msg.header.stamp = event.header.stamp  # the plan describes the separation from the ejection epoch on
        msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
        msg.maneuvers = [maneuver_msg(stop.epoch, stop.u2, stop.dv_carrier_rtn, "carrier", "drift_stop")]
        dt = stop.epoch - epoch1
        aimed_chief = type(chief)(
            semi_major_axis=a, eccentricity=chief.eccentricity, inclination=inc,
            raan=float(wrap_angle(chief.raan + (raan_rate(a, inc) * dt if self.j2 else 0.0))),
            arg_perigee=chief.arg_perigee, mean_arg_latitude=float(wrap_angle(stop.u2)))
        msg.aimed = roe_to_msg(stop.aimed_roe, aimed_chief, sec_to_time(stop.epoch))
        return msg

    def _multi_plan(self, event, dv1, u1, epoch1, a, inc) -> ManeuverPlan:
        """Every carrier burn of the multi-impulse plan for the commanded ejection (seed 001 Sec. 3)."""
        sep = multi_config(self.scenario.separation, self.multi)
        mc = self.scenario.monte_carlo  # the pair is planned on the nominal differential drag
        da_dot = float(drag_da_dot(mc.delta_b, mc.density, a)) if mc.drag else 0.0
        plan = plan_carrier_burns(dv1, u1, epoch1, a, inc, sep, self.multi, self.j2, da_dot)
        msg = ManeuverPlan(strategy="multi_impulse", ejection_epoch=event.header.stamp, p_reduction=float(plan.p))
        msg.header.stamp = event.header.stamp  # the plan describes the separation from the ejection epoch on
        msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
        msg.maneuvers = [maneuver_msg(b.epoch, b.u, b.dv_carrier_rtn, "carrier", b.purpose) for b in plan.burns]
        chief = event.chief
        dt = plan.ic_epoch - epoch1
        aimed_chief = type(chief)(
            semi_major_axis=a, eccentricity=chief.eccentricity, inclination=inc,
            raan=float(wrap_angle(chief.raan + (raan_rate(a, inc) * dt if self.j2 else 0.0))),
            arg_perigee=chief.arg_perigee, mean_arg_latitude=float(wrap_angle(plan.burns[-1].u)))
        msg.aimed = roe_to_msg(plan.roe_final, aimed_chief, sec_to_time(plan.ic_epoch))
        return msg


def main(args=None):
    from .spin import run

    return run(PlannerNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
