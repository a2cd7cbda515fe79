"""planner: the carrier's blind drift-stop, planned from the commanded ejection only (never from truth).

Subscribes ``/separation/ejection`` (roe_sep_msgs/EjectionEvent, latched) and publishes the drift-stop
``/separation/drift_stop_plan`` (roe_sep_msgs/ManeuverPlan, RELIABLE + TRANSIENT_LOCAL, depth 1) as soon as an
event arrives. Physics: :func:`roe_sep.core.separation.double_impulse.plan_drift_stop` (seed 002 Eqs. 9, 18).

Parameters (YAML via ``--ros-args --params-file``): :data:`roe_sep.nodes.parameters.PLANNER` (``planner --help``,
docs/parameters.md). ``strategy`` ``multi_impulse`` (seed 001 Sec. 3,
:func:`roe_sep.core.separation.multi_impulse.plan_carrier_burns`) publishes every carrier burn of the multi-impulse
plan (blind drift reduction with |p| of Eq. 21, then the tangential e-vector pair) as one ManeuverPlan with strategy
"multi_impulse" on the same topic.
"""

import dataclasses
import math
import os

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from roe_sep_msgs.msg import EjectionEvent, ManeuverPlan
from roe_sep_msgs.srv import PlanSeparation

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.montecarlo.sweep import p_best, p_best_stored
from ..core.relmotion.dynamics import drag_da_dot, raan_rate
from ..core.relmotion.roe import wrap_angle
from ..core.separation.double_impulse import design, plan_drift_stop, reduction_bounds
from ..core.separation.multi_impulse import MultiImpulseConfig, multi_config, plan_carrier_burns
from .convert import maneuver_msg, roe_to_msg, sec_to_time, time_to_sec, vector_to_array
from .diagnostics import ERROR, OK, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare, finite


def cache_dir():
    """Where the start-up sweep's result is stored between processes: ``ROE_SEP_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/roe_sep`` (``~/.cache/roe_sep``); None (not stored) when ``ROE_SEP_CACHE_DIR`` is ``off``."""
    env = os.environ.get("ROE_SEP_CACHE_DIR")
    if env:
        return None if env == "off" else env
    return os.path.join(os.environ.get("XDG_CACHE_HOME") or os.path.expanduser("~/.cache"), "roe_sep")


def startup_p(scenario, samples, seed):
    """The drift-stop reduction |p| [m/s] of p_mode 'monte_carlo': p_best of a ``samples``-sample sweep with
    ``seed`` (seed 002 Table 3), memoised in the process and stored on disk (:func:`cache_dir`,
    :func:`roe_sep.core.montecarlo.sweep.p_best_stored`): identical in every run of a scenario, computed once."""
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
        self.lockstep = ls = Lockstep(self)
        self.plan_pub = ls.publisher(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                     what="ejection event")
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
        burn = plan.maneuvers[0]
        self.get_logger().info(
            f"drift-stop planned at t = {time_to_sec(burn.epoch):.1f} s, carrier dv RTN = "
            f"({burn.dv_rtn.x:+.6f}, {burn.dv_rtn.y:+.6f}, {burn.dv_rtn.z:+.6f}) m/s, p = {plan.p_reduction:g} m/s")
        publish_status(self, self.diag_pub, OK, "drift-stop plan published", self._values())

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
    raise SystemExit(main())
