"""ic_planner: the carrier's burns from the radar OD estimate to the experiment's initial conditions (seed 001).

Subscribes ``/od/estimate`` (roe_sep_msgs/OrbitDetermination, latched) and publishes the minimum-delta-v carrier
plan on ``/acquisition/plan`` (roe_sep_msgs/ManeuverPlan, RELIABLE + TRANSIENT_LOCAL, depth 1; strategy
``ic_acquisition``, one ``carrier``/``ic_acquisition`` maneuver per burn epoch, ``aimed`` = the predicted ROE at the
IC epoch t_F with the chief's elements there) and ``/diagnostics``. Physics: :func:`roe_sep.core.acquisition.planner.
plan_acquisition` (linear program + quantized re-solve, verified with the shared trajectory). Run it with
``use_sim_time:=true``: "now" is the simulator's clock.

When a plan is (re)computed, trimmed or deferred -- the rules of :mod:`roe_sep.core.decisions.ic_planner`, written
out in docs/run.md, "Decisions": every newer OD solution after the separation plan re-plans the rest of the
acquisition towards the IC epoch t_F fixed by the first plan, unless its burns would fall in the final OD's radar arc,
it knows the drift worse than the plan in force, or a committed burn keeps that plan; the final OD trims the drift
once; a departing burn re-plans (or re-trims). A bad estimate or an infeasible acquisition is an ERROR on
/diagnostics; the node keeps running and the plan in force stays published. This node only converts the messages to
events, calls those functions and carries out their actions.

Its decisions are kept outside the process: after each one the decision record (the
:class:`~roe_sep.core.decisions.ic_planner.IcPlannerState`) on ``/separation/decisions/ic_planner`` (std_msgs/String,
JSON, latched; ground_bridge keeps it). A (re)started ic_planner reads it back before it subscribes its inputs
(:mod:`.decision_record`, ``recover_timeout``) and latches the plan in force again as it was published
(:func:`roe_sep.core.decisions.ic_planner.on_restart`: never one a re-plan or trim replaced); the latched OD and
executed record then come again and change nothing. Without a record it recovers the IC epoch from its own latched
plan (while a writer of it lives) and the flown burns from the latched executed-maneuver topic.

Parameters (YAML via ``--ros-args --params-file``): :data:`roe_sep.nodes.parameters.IC_PLANNER` (``ic_planner
--help``, docs/parameters.md); the rules between them (a_dl_min < a_dl_max, a_dl_target within them, dv_quantum <=
max_burn_dv, planning_margin < window) are :func:`roe_sep.core.acquisition.planner.validate_config`'s.
"""

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import TwistWithCovarianceStamped
from roe_sep_msgs.msg import EjectionEvent, ImpulsiveManeuver, ManeuverPlan, OrbitDetermination
from std_msgs.msg import String

from .. import interfaces
from ..core.acquisition.planner import AcquisitionConfig, InvalidAcquisitionConfig, validate_config
from ..core.decisions import ic_planner as rules
from ..core.od.radar import DEFAULT_EPOCH_UTC, julian_date
from ..core.relmotion.roe import wrap_angle
from .convert import (
    array_to_elements,
    ejection_prior,
    elements_to_array,
    maneuver,
    msg_to_roe,
    planned_burn,
    roe_to_msg,
    sec_to_time,
    time_to_sec,
    twist_linear,
)
from .decision_record import DecisionRecord
from .diagnostics import OK, publish_status, report
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare, scenario_of


def od_solution(msg: OrbitDetermination) -> rules.OdSolution:
    """The OD message as the decisions read it."""
    est = msg.estimate
    return rules.OdSolution(time_to_sec(msg.header.stamp), time_to_sec(est.header.stamp),
                            tuple(float(x) for x in elements_to_array(est.chief)), est.chief.mean_arg_latitude,
                            tuple(float(x) for x in msg_to_roe(est)), tuple(float(x) for x in est.covariance),
                            a_da_dot=msg.a_da_dot, a_da_dot_sigma=msg.a_da_dot_sigma)


class IcPlannerNode(ManagedNode):
    def __init__(self):
        super().__init__("ic_planner")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        names = ("a_dl_min", "a_dl_max", "a_dl_target", "a_dl_target_tol", "min_ei", "fov_half_r_deg",
                 "fov_half_n_deg", "max_burn_dv", "dv_quantum", "axes", "planning_margin", "window", "grid_per_orbit",
                 "drift_tolerance", "ei_angle_tol_deg", "j2")
        values = {name: declare(self, name) for name in names}
        self.recover_timeout = declare(self, "recover_timeout")
        jd0 = julian_date(DEFAULT_EPOCH_UTC)  # sim time 0, as the simulator's and radar_od's default
        extra = {name: declare(self, name) for name in ("trim", "burn_sigma", "final_od_arc", "replan_on_burn",
                                                        "ei_margin_sigmas", "ic_drift_tolerance")}
        extra["blind_after"] = declare(self, "blind_acquisition_after")
        scenario_file = declare(self, "scenario_file")
        self.scenario = scenario_of(scenario_file)
        try:
            cfg = AcquisitionConfig(**values)
            validate_config(cfg)
        except InvalidAcquisitionConfig as exc:
            raise ParameterError(f"parameter '{exc.name}' must be {exc.must}, got {exc.value!r}") from exc
        self.config = rules.IcPlannerConfig(cfg, **extra, jd0=jd0)

    def activate(self):
        """Publishers, then the read-back of the decision record; the subscriptions once it is over (:meth:`start`).
        The ``activate`` transition."""
        self.state = rules.IcPlannerState()  # everything the decisions know (core.decisions.ic_planner)
        # the decisions' writer first (as the planner's: the recorder finds it no later than the plan's)
        self.record = DecisionRecord(self, self.create_publisher(String, interfaces.IC_PLANNER_DECISIONS_TOPIC,
                                                                 interfaces.LATCHED),
                                     interfaces.IC_PLANNER_DECISIONS_TOPIC, rules.IcPlannerState,
                                     timeout=self.recover_timeout, start=self.start)
        self.lockstep = Lockstep(self, on_step=self.on_step)
        self.plan_pub = self.lockstep.publisher(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.record.subscription = self.create_subscription(String, interfaces.IC_PLANNER_DECISIONS_TOPIC,
                                                            self.record.on_record, interfaces.LATCHED)

    def start(self, recovered):
        """The read-back is over (``recovered``: the state of the decision record, or None): subscribe the inputs,
        then latch the plan in force again."""
        def subscribe():
            ls = self.lockstep
            ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_executed, interfaces.EXECUTED,
                         stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
            # the acquisition starts once the separation plan (drift-stop, or the multi-impulse burns) is flown
            ls.subscribe(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, self.on_separation_plan, interfaces.LATCHED)
            # a restarted ic_planner keeps the IC epoch of the acquisition in progress: its own latched plan
            ls.subscribe(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, self.on_own_plan, interfaces.LATCHED)
            ls.subscribe(OrbitDetermination, interfaces.OD_TOPIC, self.on_estimate, interfaces.LATCHED,
                         what="OD estimate")
            # what a blind acquisition starts from (issue 41 part 3): the ejection, measured where the footage has it
            ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                         what="ejection event")
            ls.subscribe(TwistWithCovarianceStamped, interfaces.EJECTION_ESTIMATE_TOPIC, self.on_measured,
                         interfaces.LATCHED, what="ejection estimate")
            # without lockstep steps (a free-running clock) the blind acquisition's check runs on a timer
            self.free_timer = ls.free_running(self.now)

        self.activated_later(subscribe)
        if recovered is not None:
            self.apply(rules.on_restart(recovered, self.config))
        else:
            publish_status(self, self.diag_pub, OK, "waiting for an OD estimate", rules.values(self.state))

    def apply(self, outcome):
        """Take a decision's new state and carry out its actions (publish a plan, log, publish a status)."""
        before, (self.state, actions) = self.state, outcome
        if self.state is not before:
            ls = self.lockstep
            self.record.publish(self.state, ls.time if ls.active and ls.time is not None else self.now())
        for action in actions:
            if isinstance(action, rules.PublishPlan):
                self.plan_pub.publish(self.plan_msg(action))
            else:
                report(self, self.diag_pub, action)

    def on_executed(self, m: ImpulsiveManeuver):
        self.apply(rules.on_executed(self.state, planned_burn(m), self.config))

    def on_ejection(self, event: EjectionEvent):
        """The commanded ejection with the SPL's magnitude and direction errors (the scenario's spl_sigma and
        attitude_sigma_arcsec) and the nominal differential drag (its ballistic_sigma): the blind acquisition's
        prior (:class:`roe_sep.core.decisions.ic_planner.EjectionPrior`)."""
        try:
            prior = ejection_prior(event, self.scenario)
        except ValueError as exc:
            publish_status(self, self.diag_pub, 2, f"ejection event rejected: {exc}", part="input")
            return
        self.apply(rules.on_ejection(self.state, prior, self.config))

    def on_measured(self, msg: TwistWithCovarianceStamped):
        """The executed ejection the planner's ground filter measured from the footage."""
        try:
            dv, cov = twist_linear(msg)
        except ValueError as exc:
            publish_status(self, self.diag_pub, 2, f"ejection estimate rejected: {exc}", part="input")
            return
        self.apply(rules.on_measured(self.state, dv, cov.reshape(-1), self.config))

    def on_step(self, t):
        """Sim-time checks (each lockstep step; a timer without one): the blind acquisition
        (:func:`roe_sep.core.decisions.ic_planner.on_step`)."""
        self.apply(rules.on_step(self.state, t, self.config))

    def on_separation_plan(self, plan: ManeuverPlan):
        self.apply(rules.on_separation_plan(self.state, [time_to_sec(m.epoch) for m in plan.maneuvers], self.config))

    def on_own_plan(self, plan: ManeuverPlan):
        self.apply(rules.on_own_plan(self.state, [planned_burn(m) for m in plan.maneuvers],
                                     time_to_sec(plan.aimed.header.stamp), self.config))

    def now(self):
        return self.get_clock().now().nanoseconds * 1e-9

    def on_estimate(self, msg: OrbitDetermination):
        # lockstep: the planner decides at the epoch of the solution, whatever the step that carried it
        now = time_to_sec(msg.header.stamp) if self.lockstep.active else self.now()
        self.apply(rules.on_od(self.state, od_solution(msg), now, self.config))

    def plan_msg(self, action: rules.PublishPlan) -> ManeuverPlan:
        """The ManeuverPlan of a decision: its burns, ``aimed`` the predicted ROE at the IC epoch with the chief's
        elements there."""
        out = ManeuverPlan(strategy="ic_acquisition", p_reduction=0.0)
        out.header.stamp = sec_to_time(action.stamp)
        out.header.frame_id = interfaces.CARRIER_RTN_FRAME
        out.maneuvers = [maneuver(b) for b in action.burns]
        aimed_chief = array_to_elements(action.aimed_kep)
        aimed_chief.mean_arg_latitude = float(wrap_angle(aimed_chief.mean_arg_latitude))
        out.aimed = roe_to_msg(action.aimed_roe, aimed_chief, sec_to_time(action.t_final))
        return out


def main(args=None):
    from .spin import run

    return run(IcPlannerNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
