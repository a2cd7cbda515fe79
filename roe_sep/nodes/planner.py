"""planner: the carrier's blind drift-stop, planned from the commanded ejection only (never from truth).

Subscribes ``/separation/ejection`` (roe_sep_msgs/EjectionEvent, latched) and publishes the drift-stop
``/separation/drift_stop_plan`` (roe_sep_msgs/ManeuverPlan, RELIABLE + TRANSIENT_LOCAL, depth 1) as soon as an
event arrives. Physics: :func:`roe_sep.core.separation.double_impulse.plan_drift_stop` (seed 002 Eqs. 9, 18).

Parameters (YAML via ``--ros-args --params-file``): :data:`roe_sep.nodes.parameters.PLANNER` (``planner --help``,
docs/parameters.md). ``strategy`` ``multi_impulse`` (seed 001 Sec. 3,
:func:`roe_sep.core.separation.multi_impulse.plan_carrier_burns`) publishes every carrier burn of the multi-impulse
plan (blind drift reduction with |p| of Eq. 21, then the tangential e-vector pair) as one ManeuverPlan with strategy
"multi_impulse" on the same topic.

Its decisions are :mod:`roe_sep.core.decisions.planner`'s, written out in docs/run.md, "Decisions" (and
docs/contingencies.md, "What the closed loop does about them"), each behind a parameter: ``drift_stop_retry``
replaces a drift-stop missing from the executed-maneuver record (``/sim/executed_maneuvers``) whole orbits later;
``drift_stop_makeup`` completes one that departs from its command; ``weak_ejection_hold`` withdraws the drift-stop
(an empty plan) when the carrier camera's bearings (``/sim/camera/bearing``, never the truth) exclude every nominal
ejection; with ``ejection_footage`` the ground filter estimates the executed ejection from the footage's 3D poses
(``/sim/camera/pose``, :func:`roe_sep.core.od.pose.estimate_ejection`), publishes it latched on
``/separation/ejection_estimate`` (geometry_msgs/TwistWithCovarianceStamped, dv [m/s] RTN and its covariance) and
the weak-ejection test uses it (the bearings: the fallback of a contact without footage; docs/run.md, "The
ejection camera"). Each finding is a WARN ``roe_sep/planner/contingency`` on ``/diagnostics`` (value ``contingency``:
``drift_stop_replaced``, ``drift_stop_completed`` or ``weak_ejection``, ``epoch_s``). This node only converts the
messages to events, calls those functions and carries out their actions.

Its decisions are kept outside the process (the decision record on ``/separation/decisions/planner``, read back by
a restarted planner: :mod:`.decision_record`, :func:`roe_sep.core.decisions.planner.on_restart`; docs/run.md,
"Decisions survive a restart").
"""

import dataclasses
import math
import time

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, TwistWithCovarianceStamped, Vector3Stamped
from roe_sep_msgs.msg import EjectionEvent, ImpulsiveManeuver, ManeuverPlan, OrbitalElements
from roe_sep_msgs.srv import PlanSeparation
from std_msgs.msg import String

from .. import interfaces
from ..core.decisions import planner as rules
from ..core.montecarlo.sweep import p_best
from ..core.od.pose import UNKNOWN
from ..core.relmotion.roe import wrap_angle
from ..core.separation.double_impulse import design, reduction_bounds
from ..core.separation.multi_impulse import MultiImpulseConfig
from .convert import (
    array_to_vector,
    elements_to_array,
    maneuver,
    maneuver_msg,
    planned_burn,
    roe_to_msg,
    sec_to_time,
    time_to_sec,
    vector_to_array,
)
from .decision_record import DecisionRecord
from .diagnostics import OK, publish_status, report
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import declare, scenario_of
from .sweep_store import cache_dir, p_best_stored


def ejection(event: EjectionEvent) -> rules.Ejection:
    """The ejection event as the decisions read it."""
    return rules.Ejection(event.header.stamp.sec, event.header.stamp.nanosec,
                          tuple(float(x) for x in elements_to_array(event.chief)), event.chief.mean_arg_latitude,
                          tuple(float(x) for x in vector_to_array(event.ejection.dv_rtn)),
                          event.ejection.mean_arg_latitude)


def plan_msg(action: rules.PublishPlan) -> ManeuverPlan:
    """The ManeuverPlan of a decision."""
    msg = ManeuverPlan(strategy=action.strategy, p_reduction=action.p_reduction)
    msg.ejection_epoch.sec, msg.ejection_epoch.nanosec = action.ejection_stamp
    msg.header.stamp.sec, msg.header.stamp.nanosec = action.stamp
    msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
    msg.maneuvers = [maneuver(b) for b in action.burns]
    if action.aimed is not None:
        a, e, inc, raan, argp, u = action.aimed.elements
        chief = OrbitalElements(semi_major_axis=a, eccentricity=e, inclination=inc, raan=raan, arg_perigee=argp,
                                mean_arg_latitude=u)
        msg.aimed = roe_to_msg(action.aimed.roe, chief, sec_to_time(action.aimed.t))
    return msg


def estimate_msg(action: rules.PublishEstimate) -> TwistWithCovarianceStamped:
    """The TwistWithCovarianceStamped of the footage's ejection estimate: linear = dv [m/s] RTN, its covariance in
    the linear block; the angular part is not estimated (zero, its variances -1 as sensor_msgs/Imu marks one)."""
    msg = TwistWithCovarianceStamped()
    msg.header.stamp.sec, msg.header.stamp.nanosec = action.stamp
    msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
    msg.twist.twist.linear = array_to_vector(action.dv)
    cov = [0.0] * 36
    for i in range(3):
        for j in range(3):
            cov[6 * i + j] = action.cov[3 * i + j]
        cov[6 * (i + 3) + i + 3] = UNKNOWN
    msg.twist.covariance = cov
    return msg


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
        self.recover_timeout = declare(self, "recover_timeout")
        self.p_mode = declare(self, "p_mode")
        p_fixed = declare(self, "p_reduction")
        scenario_file = declare(self, "scenario_file")
        samples = declare(self, "mc_samples")
        seed = declare(self, "mc_seed")
        self.j2 = declare(self, "j2")
        self.strategy = declare(self, "strategy")
        names = (("retry", "drift_stop_retry"), ("retry_tolerance", "retry_tolerance"),
                 ("retry_margin", "retry_margin"), ("makeup", "drift_stop_makeup"), ("makeup_z", "makeup_z"),
                 ("makeup_pointing", "makeup_pointing_deg"), ("hold", "weak_ejection_hold"),
                 ("camera_sigma", "camera_sigma_deg"), ("camera_floor", "camera_model_floor"),
                 ("hold_sigmas", "hold_sigmas"), ("hold_alpha", "hold_alpha"), ("hold_lead", "hold_lead"),
                 ("footage", "ejection_footage"), ("footage_window", "footage_window"),
                 ("cam", "collision_avoidance"), ("cam_latency", "cam_latency"), ("cam_dv", "cam_dv"),
                 ("cam_sigmas", "cam_sigmas"), ("pointing_sigma", "ejection_pointing_sigma_deg"),
                 ("completion", "ejection_completion"), ("completion_max_pulse", "completion_max_pulse"),
                 ("stuck_fraction", "stuck_fraction"))
        checks = {field: declare(self, name) for field, name in names}  # the contingency checks' parameters
        for field in ("makeup_pointing", "camera_sigma", "pointing_sigma"):
            checks[field] = math.radians(checks[field])
        self.scenario = scenario_of(scenario_file)

        multi, p = None, None  # p: computed from each commanded ejection (Eq. 21 for the multi-impulse plan)
        if self.strategy == "multi_impulse":
            multi = MultiImpulseConfig()
        elif self.p_mode == "fixed":
            p = float(p_fixed)
        elif self.p_mode == "monte_carlo":
            p = startup_p(self.scenario, samples, seed)
            self.get_logger().info(f"p = {p:g} m/s: p_best of a {samples}-sample Monte Carlo sweep")
        self.config = rules.PlannerConfig(self.strategy, self.k, self.p_mode, p, self.j2, self.scenario, multi=multi,
                                          **checks)

    def activate(self):
        """Publishers and services, then the read-back of the decision record; the subscriptions once it is over
        (:meth:`start`). The ``activate`` transition."""
        # the decisions' writer first: the recorder, which subscribes to each topic it finds with a writer, finds it
        # no later than the plan's (the simulator's clock waits for the recorder on the plan topic)
        self.record = DecisionRecord(self, self.create_publisher(String, interfaces.PLANNER_DECISIONS_TOPIC,
                                                                 interfaces.LATCHED),
                                     interfaces.PLANNER_DECISIONS_TOPIC, rules.PlannerState,
                                     timeout=self.recover_timeout, start=self.start)
        self.lockstep = Lockstep(self, on_step=self.on_step)
        self.plan_pub = self.lockstep.publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.estimate_pub = self.lockstep.publisher(TwistWithCovarianceStamped, interfaces.EJECTION_ESTIMATE_TOPIC,
                                                    interfaces.LATCHED)
        self.state = rules.PlannerState()  # everything the decisions know (core.decisions.planner)
        self.create_service(PlanSeparation, interfaces.PLAN_SERVICE, self.on_plan_request)
        self.record.subscription = self.create_subscription(String, interfaces.PLANNER_DECISIONS_TOPIC,
                                                            self.record.on_record, interfaces.LATCHED)

    def start(self, recovered):
        """The read-back is over (``recovered``: the state of the decision record, or None): subscribe the inputs,
        then latch the plan in force again."""
        def subscribe():
            ls = self.lockstep
            ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                         what="ejection event")
            ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_executed, interfaces.EXECUTED,
                         stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
            ls.subscribe(Vector3Stamped, interfaces.CAMERA_TOPIC, self.on_bearing, interfaces.STREAM,
                         what="camera bearing")
            ls.subscribe(PoseWithCovarianceStamped, interfaces.POSE_TOPIC, self.on_pose, interfaces.STREAM,
                         what="footage pose")
            # without lockstep steps (a free-running clock) the sim-time checks run on a timer
            self.free_timer = ls.free_running(self.now)

        self.activated_later(subscribe)
        if recovered is not None:
            self.apply(rules.on_restart(recovered, self.config))
        else:
            publish_status(self, self.diag_pub, OK, "waiting for the ejection event",
                           rules.values(self.state, self.config))

    def apply(self, outcome):
        """Take a decision's new state and carry out its actions (publish a plan, stop the camera, log, publish a
        status)."""
        before, (self.state, actions) = self.state, outcome
        if self.state is not before:
            self.record.publish(self.state, self.sim_time())
        for action in actions:
            if isinstance(action, rules.PublishPlan):
                self.plan_pub.publish(plan_msg(action))
            elif isinstance(action, rules.PublishEstimate):
                self.estimate_pub.publish(estimate_msg(action))
            elif isinstance(action, rules.StopBearings):
                self.lockstep.unsubscribe(interfaces.CAMERA_TOPIC)
            else:
                report(self, self.diag_pub, action)

    def on_ejection(self, event: EjectionEvent):
        self.apply(rules.on_ejection(self.state, ejection(event), self.config))

    def now(self):
        return self.get_clock().now().nanoseconds * 1e-9

    def sim_time(self):
        """s: the lockstep step's sim time, else the clock's."""
        ls = self.lockstep
        return ls.time if ls.active and ls.time is not None else self.now()

    def on_executed(self, m: ImpulsiveManeuver):
        self.apply(rules.on_executed(self.state, planned_burn(m), time.monotonic(), self.config))

    def on_bearing(self, msg: Vector3Stamped):
        """The carrier camera's measured line of sight (the simulator's sensor, noise included)."""
        self.apply(rules.on_bearing(self.state, time_to_sec(msg.header.stamp), vector_to_array(msg.vector),
                                    self.config))

    def on_pose(self, msg: PoseWithCovarianceStamped):
        """A 3D pose of the ejection footage (the simulator's sensor, noise included) and its covariance."""
        p, c = msg.pose.pose.position, msg.pose.covariance
        self.apply(rules.on_pose(self.state, time_to_sec(msg.header.stamp), (p.x, p.y, p.z),
                                 [c[6 * i + j] for i in range(3) for j in range(3)], self.config))

    def on_step(self, t):
        """Sim-time checks (each lockstep step; a timer without one): :func:`roe_sep.core.decisions.planner.on_step`."""
        self.apply(rules.on_step(self.state, t, time.monotonic(), self.lockstep.active, self.config))

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
                p = request.p_reduction if request.p_reduction >= 0 else self.config.p
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
        mcfg = dataclasses.replace(self.config.multi, u1_deg=math.degrees(request.u1),
                                   **{k: v for k, v in (("spl_dv", request.spl_dv), ("a_di_f", request.a_di_f)) if v})
        return multi_impulse.design(sep, mcfg, self.scenario.monte_carlo, self.j2)

    def make_plan(self, event: EjectionEvent, k=None, p=None) -> ManeuverPlan:
        """The ManeuverPlan for one event (:func:`roe_sep.core.decisions.planner.separation_plan`); raises ValueError
        on a malformed event (NaN, impossible orbit)."""
        return plan_msg(rules.separation_plan(ejection(event), self.config, k=k, p=p))


def main(args=None):
    from .spin import run

    return run(PlannerNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
