"""ic_planner: the carrier's burns from the radar OD estimate to the experiment's initial conditions (seed 001).

Subscribes ``/od/estimate`` (roe_sep_msgs/OrbitDetermination, latched) and publishes the minimum-delta-v carrier
plan on ``/acquisition/plan`` (roe_sep_msgs/ManeuverPlan, RELIABLE + TRANSIENT_LOCAL, depth 1; strategy
``ic_acquisition``, one ``carrier``/``ic_acquisition`` maneuver per burn epoch, ``aimed`` = the predicted ROE at the
IC epoch t_F with the chief's elements there) and ``/diagnostics``. Physics: :func:`roe_sep.core.acquisition.planner.
plan_acquisition` (linear program + quantized re-solve, verified with the shared trajectory). Run it with
``use_sim_time:=true``: "now" is the simulator's clock.

When a plan is (re)computed -- what a flight-dynamics team wants from a stream of OD solutions:

* Every *newer* solution (ordered by ``header.stamp``, then ``estimate.header.stamp``) is the best knowledge and
  re-plans; a re-delivered or older one is ignored. With ``trim``, a solution that predicts a da at t_F less well
  (its 1-sigma from the covariance and the drift-rate sigma) than the plan in force knows it (its OD's, with the
  execution errors of the burns flown since, ``burn_sigma``) is not used either: a two-pass solution after a burn
  can be tens of meters off. The plan starts from the estimate propagated to now
  with every carrier burn flown since its epoch (``/sim/executed_maneuvers``, latched), so a correction never repeats
  a burn.
* The first plan fixes the IC epoch t_F (the last grid epoch within OD epoch + ``window``); later solutions
  re-plan the rest of the acquisition as corrections aimed at the same t_F, as a real campaign does.
* The final OD's radar arc (:func:`~roe_sep.core.acquisition.trim.final_od_arc` of the predicted TIRA passes: three
  passes spanning ``final_od_arc``, ending with the last pass before t_F) stays free of burns: no plan puts one
  there, and a solution whose re-plan would start in it is not used.
* The solution after the arc's last pass is the final OD (without a predicted arc: the first newer solution within
  two planning margins of t_F): with ``trim`` it predicts a da at t_F and adds one tangential trim burn at or after
  now + planning_margin when that prediction is not safely inside ``ic_drift_tolerance``
  (:mod:`roe_sep.core.acquisition.trim`; a trim past t_F moves t_F to one grid step after it). The plan in force
  keeps its other burns; later solutions are not used.
* With ``replan_on_burn``, an executed acquisition burn that departs from its plan by more than half the trim
  lattice in a da (its execution error, known from the executed-maneuver record: the carrier's burns as its GPS
  measures them) re-plans the rest from the last OD and that record, or re-trims once the final OD has decided:
  the radar gives the next OD only after a burn-free arc of three passes, more than a day later.
* A re-plan never moves a burn that is committed: one of the plan in force due within ``planning_margin`` from
  now (or executed without its record having arrived yet) keeps the plan in force (WARN on /diagnostics). A
  departing burn's re-plan that a committed burn deferred is made when that burn's execution record arrives.
* The first burn of a new plan is at or after max(OD epoch, now) + planning_margin; only an OD made after the
  separation plan's last burn (``/separation/drift_stop_plan``: the drift-stop, or the multi-impulse burns) starts
  the acquisition.
* A bad estimate (NaN, impossible orbit) or an infeasible acquisition is logged and reported as ERROR on
  /diagnostics; the node keeps running and the plan in force (if any) stays published.

A restarted ic_planner recovers the IC epoch from its own latched plan and the flown burns from the latched
executed-maneuver topic, so it continues the acquisition in progress.

Parameters (YAML via ``--ros-args --params-file``): :data:`roe_sep.nodes.parameters.IC_PLANNER` (``ic_planner
--help``, docs/parameters.md); the rules between them (a_dl_min < a_dl_max, a_dl_target within them, dv_quantum <=
max_burn_dv, planning_margin < window) are :func:`roe_sep.core.acquisition.planner.validate_config`'s.
"""

import dataclasses
import math
import traceback

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from roe_sep_msgs.msg import ImpulsiveManeuver, ManeuverPlan, OrbitDetermination

from .. import interfaces
from ..core.acquisition.lp_transfer import grid_epochs
from ..core.acquisition.planner import (
    AcquisitionConfig,
    AcquisitionInfeasible,
    InvalidAcquisitionConfig,
    check_inputs,
    plan_acquisition,
    validate_config,
)
from ..core.acquisition.trim import (
    CLUSTER_GAP,
    a_da_change,
    burns_drift_sigma,
    drift_lattice,
    ei_margin,
    final_od_arc,
    plan_trim,
    predicted_drift_sigma,
    radar_passes,
    trim_problems,
)
from ..core.constants import SECONDS_PER_DAY
from ..core.od.radar import DEFAULT_EPOCH_UTC, julian_date
from ..core.relmotion.dynamics import propagate_chief
from ..core.relmotion.roe import wrap_angle
from ..core.relmotion.trajectory import Chief, state_at
from .convert import (
    array_to_elements,
    elements_to_array,
    maneuver_msg,
    msg_to_roe,
    plan_burns,
    roe_to_msg,
    sec_to_time,
    time_to_sec,
)
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import Lockstep
from .managed import ManagedNode
from .params import ParameterError, declare

PASS_SLACK = 900.0  # s, between a predicted pass and its OD solution (the 5 km separation, the solution's delay)


class IcPlannerNode(ManagedNode):
    def __init__(self):
        super().__init__("ic_planner")

    def configure(self):
        """Parameters and start-up work (the managed node's ``configure`` transition)."""
        names = ("a_dl_min", "a_dl_max", "a_dl_target", "a_dl_target_tol", "min_ei", "fov_half_r_deg",
                 "fov_half_n_deg", "max_burn_dv", "dv_quantum", "axes", "planning_margin", "window", "grid_per_orbit",
                 "drift_tolerance", "ei_angle_tol_deg", "j2")
        values = {name: declare(self, name) for name in names}
        self.jd0 = julian_date(DEFAULT_EPOCH_UTC)  # sim time 0, as the simulator's and radar_od's default
        self.trim = declare(self, "trim")
        self.burn_sigma = declare(self, "burn_sigma")
        self.final_od_arc = declare(self, "final_od_arc")
        self.replan_on_burn = declare(self, "replan_on_burn")
        self.ei_margin_sigmas = declare(self, "ei_margin_sigmas")
        self.ic_drift_tolerance = declare(self, "ic_drift_tolerance")
        try:
            self.cfg = AcquisitionConfig(**values)
            validate_config(self.cfg)
        except InvalidAcquisitionConfig as exc:
            raise ParameterError(f"parameter '{exc.name}' must be {exc.must}, got {exc.value!r}") from exc

    def activate(self):
        """Publishers, subscriptions, services (the ``activate`` transition)."""
        self.lockstep = ls = Lockstep(self)
        self.plan_pub = ls.publisher(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, self.on_executed, interfaces.EXECUTED,
                     stamp=lambda m: time_to_sec(m.epoch), what="executed maneuver")
        # the acquisition starts once the separation plan (drift-stop, or the multi-impulse burns) is flown
        ls.subscribe(ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, self.on_separation_plan, interfaces.LATCHED)
        self.separation_end = -math.inf  # s, epoch of the separation plan's last burn
        # a restarted ic_planner keeps the IC epoch of the acquisition in progress: its own latched plan
        ls.subscribe(ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, self.on_own_plan, interfaces.LATCHED)
        ls.subscribe(OrbitDetermination, interfaces.OD_TOPIC, self.on_estimate, interfaces.LATCHED, what="OD estimate")
        self.executed = []  # carrier burns flown so far (relative impulses), from the simulator/executor
        self.t_final = None  # s, IC epoch of the acquisition in progress (fixed by its first plan)
        self.last_key = None  # (solution stamp, estimate epoch) of the newest OD seen
        self.burn_epochs = None  # s, burn epochs of the plan in force (None: no plan yet)
        self.plan_in_force = None  # its ManeuverPlan (the trim keeps its other burns)
        self.final_decided = False  # the final OD's trim decision is made: the acquisition is complete
        self.plan_sigma = None  # m, 1-sigma of a da at t_F from the OD of the plan in force (with ``trim``)
        self.plan_od_epoch = None  # s, that OD's epoch
        self.last_od = None  # the newest OD solution after the separation plan (re-plans after a burn start from it)
        self.replan_pending = False  # a departing burn's re-plan waits for a committed burn (the next burn re-plans)
        self.summary = {}
        self.plans = 0
        self.arcs = {}  # radar_arc's results by (OD chief elements, OD epoch and t_F)
        publish_status(self, self.diag_pub, OK, "waiting for an OD estimate", self._values())

    def _values(self):
        return {"plans": self.plans, **{k: (f"{v:.6g}" if isinstance(v, float) else v)
                                        for k, v in self.summary.items()}}

    def on_executed(self, m: ImpulsiveManeuver):
        if m.spacecraft == "carrier":
            try:
                self.executed.extend(plan_burns([m]))
            except ValueError as exc:
                publish_status(self, self.diag_pub, ERROR, f"executed maneuver rejected: {exc}", self._values())
                return
            if self.replan_on_burn and m.purpose == "ic_acquisition":
                self._guarded("re-plan after a burn rejected", "re-plan after a burn failed", self.after_burn, m)

    def after_burn(self, m: ImpulsiveManeuver):
        """An executed acquisition burn that departs from its plan (execution error) by more than half the trim
        lattice in a da (seed 002 Eq. 2: a Delta da = 2 dvT / n) changes where the plan in force ends: re-plan the
        rest from the last OD and the executed-maneuver record (the carrier's GPS-calibrated burns), or, once the
        final OD decided, re-trim. Without this the departure waits for the next OD, which the radar gives only
        after a burn-free arc of three passes (more than a day after a burn, or never once the final arc began)."""
        t = time_to_sec(m.epoch)
        msg = self.last_od
        if msg is None or self.plan_in_force is None or self.t_final is None or t >= self.t_final:
            return
        planned = next((p for p in self.plan_in_force.maneuvers
                        if p.spacecraft == "carrier" and abs(time_to_sec(p.epoch) - t) < 1e-3), None)
        if planned is None:
            return
        a = msg.estimate.chief.semi_major_axis
        departure = abs(float(a_da_change(m.dv_rtn.y - planned.dv_rtn.y, a)))
        departed = departure > 0.5 * drift_lattice(a, self.cfg.dv_quantum)
        if not (departed or self.replan_pending):
            return
        t_od = time_to_sec(msg.estimate.header.stamp)
        why = (f"burn at t = {t:.1f} s departed from its plan by {departure:.2f} m of a da" if departed else
               f"burn at t = {t:.1f} s flown, the committed burn that deferred an earlier departure's re-plan")
        text = f"{why}: {'re-trim' if self.final_decided else 're-plan'} from the OD at t = {t_od:.1f} s"
        self.get_logger().info(text)
        publish_status(self, self.diag_pub, OK, text, self._values())
        self.replan_pending = False
        if self.final_decided:
            self.final_trim(msg, t_od, t, after_burn=True)
        else:
            # a committed burn (the plan's next, within planning_margin) keeps the plan in force: its own execution
            # record re-plans then, from the same knowledge plus both burns
            self.replan_pending = bool(self.decide(msg, t_od, t))

    def on_separation_plan(self, plan: ManeuverPlan):
        self.separation_end = max((time_to_sec(m.epoch) for m in plan.maneuvers), default=-math.inf)

    def on_own_plan(self, plan: ManeuverPlan):
        if self.t_final is None and plan.maneuvers:
            self.t_final = time_to_sec(plan.aimed.header.stamp)
            self.burn_epochs = [time_to_sec(m.epoch) for m in plan.maneuvers]
            self.plan_in_force = plan

    def now(self):
        return self.get_clock().now().nanoseconds * 1e-9

    def on_estimate(self, msg: OrbitDetermination):
        key = (time_to_sec(msg.header.stamp), time_to_sec(msg.estimate.header.stamp))
        if self.last_key is not None and key <= self.last_key:
            self.get_logger().debug(f"OD solution {key} is not newer than {self.last_key}: ignored")
            return
        self.last_key = key
        # lockstep: the planner decides at the epoch of the solution, whatever the step that carried it
        t_od, now = key[1], (key[0] if self.lockstep.active else self.now())
        if self.separation_end >= t_od:
            text = (f"OD at t = {t_od:.1f} s not used: the separation plan flies until t = {self.separation_end:.1f} s;"
                    " the acquisition starts from an OD made after it")
            self.get_logger().info(text)
            publish_status(self, self.diag_pub, OK, text, self._values())
            return
        self.last_od = msg
        self.decide(msg, t_od, now)

    def decide(self, msg: OrbitDetermination, t_od, now):
        """What the OD ``msg`` (epoch ``t_od``) does at ``now``: the final trim, a re-plan, or nothing (module
        docstring). True when a committed burn of the plan in force kept it (the re-plan is deferred), else
        None."""
        arc = self.radar_arc(msg, self.t_final) if self.t_final is not None else None
        final_band = self.t_final is not None and now < self.t_final < now + 2.0 * self.cfg.planning_margin
        if self.trim and (t_od >= arc[1] - PASS_SLACK if arc else final_band):
            if not self.final_decided:  # once (a departing burn re-trims through after_burn)
                self.final_trim(msg, t_od, now)
            return
        keep_arc = arc is None or max(t_od, now) + self.cfg.planning_margin <= arc[0]
        if not keep_arc:
            missed = self._guarded("OD estimate rejected", "acquisition check failed", self.plan_problems, msg, now)
            if missed is None:
                return
            if not missed:
                text = (f"OD at t = {t_od:.1f} s not used: the plan in force meets the initial conditions by it, and "
                        f"its burns would fall in the final OD's radar arc [{arc[0]:.0f}, {arc[2]:.0f}] s (the final "
                        f"OD comes after the pass at t = {arc[1]:.0f} s)")
                self.get_logger().info(text)
                publish_status(self, self.diag_pub, OK, text, self._values())
                return
            self.get_logger().info(f"OD at t = {t_od:.1f} s: the plan in force would miss the initial conditions "
                                   f"({'; '.join(missed)}): re-planned within the final OD's radar arc")
        sigma, known = self.drift_sigma(msg, self.t_final), self.plan_knowledge(msg)
        if sigma is not None and known is not None and sigma > known:
            text = (f"OD at t = {t_od:.1f} s not used: its a da at the IC epoch is known to {sigma:.2f} m (1-sigma), "
                    f"the plan in force's to {known:.2f} m")
            self.get_logger().info(text)
            publish_status(self, self.diag_pub, OK, text, self._values())
            return
        blocking = self._committed_burn(t_od, now)
        if blocking is not None:
            text = (f"OD at t = {t_od:.1f} s not used: the burn at t = {blocking:.1f} s of the plan in force is "
                    f"{'executed after the OD epoch' if blocking < now else 'committed (within planning_margin)'}")
            self.get_logger().warn(text)
            publish_status(self, self.diag_pub, WARN, text, self._values())
            return True
        made = self._guarded("OD estimate rejected", "acquisition planning failed", self.make_plan, msg, now,
                             keep_arc)
        if made is None:
            return
        plan_msg, plan = made
        if not plan_msg.maneuvers:  # the ICs are met without a burn: nothing to fly (an empty plan is no plan)
            text = (f"OD at t = {t_od:.1f} s: the initial conditions are met at t = {plan.t_final:.1f} s without a "
                    "further burn; the plan in force stays")
            self.get_logger().info(text)
            publish_status(self, self.diag_pub, OK, text, self._values())
            return
        self.plan_pub.publish(plan_msg)
        self.replan_pending = False
        self.plan_in_force = plan_msg
        self.plan_sigma = self.drift_sigma(msg, plan.t_final)
        self.plan_od_epoch = t_od
        self.burn_epochs = [float(t) for t in plan.epochs]
        if self.t_final is None:
            self.t_final = float(plan.t_final)
        self.plans += 1
        self.summary = {k: v for k, v in plan.summary().items()
                        if k in ("total_dv", "n_burns", "time_to_ic", "a_dl_f", "a_da_f", "min_rn", "fov_ok",
                                 "solve_time")}
        self.get_logger().info(
            f"IC acquisition planned from the OD at t = {t_od:.1f} s: {plan.n_burns} burns, total dv = "
            f"{plan.total_dv:.3f} m/s (LP {plan.lp_dv:.4f}), ICs at t = {plan.t_final:.1f} s, "
            f"a dl_F = {plan.final_roe[1] * plan.a:.0f} m, min R-N = {plan.min_rn:.0f} m")
        publish_status(self, self.diag_pub, OK, "acquisition plan published", self._values())

    def final_trim(self, msg: OrbitDetermination, t_od, now, after_burn=False):
        """The final OD's drift trim (module docstring), from the first newer solution within two planning margins of
        t_F whose flown burns are all on record (``decide`` calls it once; ``after_burn``: again, after a burn that
        departed from its plan, publishing only a trim)."""
        if self.t_final is not None and now >= self.t_final:
            self.final_decided = True
            text = (f"OD at t = {t_od:.1f} s not used: it arrives after the IC epoch t = {self.t_final:.1f} s "
                    "without a final OD trim decision before it")
            self.get_logger().warn(text)
            publish_status(self, self.diag_pub, WARN, text, self._values())
            return
        flown = {round(b.epoch, 3) for b in self.executed}
        if any(t_od <= t < now and round(t, 3) not in flown for t in self.burn_epochs or ()):
            return  # a burn flown after the OD epoch is not on record yet: the next solution decides
        kept = [m for m in (self.plan_in_force.maneuvers if self.plan_in_force else ())
                if time_to_sec(m.epoch) >= now and round(time_to_sec(m.epoch), 3) not in flown]
        decision = self._guarded("final OD rejected", "drift trim failed", self.trim_decision, msg, now, kept)
        if decision is None:
            return
        self.final_decided = True
        if after_burn and not decision.trim:
            return
        self.summary.update({f"final_{k}": v for k, v in decision.summary().items()})
        text = (f"final OD at t = {t_od:.1f} s: predicted a da at the IC epoch {decision.predicted_a_da:+.2f} m "
                f"(1-sigma {decision.sigma_a_da:.2f} m, trim threshold {decision.threshold:.2f} m): ")
        if not decision.trim:
            self.get_logger().info(text + "no trim")
            publish_status(self, self.diag_pub, OK, text + "no trim", self._values())
            return
        out = ManeuverPlan(strategy="ic_acquisition", p_reduction=0.0)
        out.header.stamp = sec_to_time(now)
        out.header.frame_id = interfaces.CARRIER_RTN_FRAME
        out.maneuvers = [*kept, maneuver_msg(decision.epoch, float(wrap_angle(decision.u)),
                                             (0.0, decision.dv_t, 0.0), "carrier", "ic_acquisition")]
        out.aimed = self.aimed(msg, decision.final_roe, decision.t_final)
        self.plan_pub.publish(out)
        self.plan_in_force, self.t_final = out, decision.t_final
        self.burn_epochs = [time_to_sec(m.epoch) for m in out.maneuvers]
        self.plans += 1
        text += f"trim of {decision.dv_t:+.3f} m/s at t = {decision.epoch:.1f} s, IC epoch t = {decision.t_final:.1f} s"
        if decision.problems:  # missed anyway: the trim nulls the drift to hold the formation
            text += f"; the initial conditions are missed even so ({'; '.join(decision.problems)}): drift nulled"
            self.get_logger().warn(text)
            publish_status(self, self.diag_pub, WARN, text, self._values())
            return
        self.get_logger().info(text)
        publish_status(self, self.diag_pub, OK, text, self._values())

    def plan_problems(self, msg: OrbitDetermination, now):
        """The initial conditions that the plan in force misses at t_F by this OD
        (:func:`~roe_sep.core.acquisition.trim.trim_problems`, and the drift when its prediction is beyond the
        tolerance: a smaller one is the final trim's); [] when it meets them."""
        roe0, chief, da_dot = self.start_state(msg, now)
        flown = {round(b.epoch, 3) for b in self.executed}
        kept = [m for m in (self.plan_in_force.maneuvers if self.plan_in_force else ())
                if time_to_sec(m.epoch) >= chief.t0 and round(time_to_sec(m.epoch), 3) not in flown]
        burns = plan_burns(kept) + [b for b in self.executed if b.epoch > chief.t0]
        final = state_at(roe0, chief.t0, burns, max(self.t_final, chief.t0), chief, self.cfg.j2, da_dot)
        problems = trim_problems(final, chief.a, self.cfg, roe0[1] > 0)
        a_da = float(final[0]) * chief.a
        if abs(a_da) > self.ic_drift_tolerance:  # this OD's best estimate already misses the drift: no waiting for
            # a final OD that may not come (the radar resolves the pair only beyond min_separation)
            problems.append(f"|a da_F| = {abs(a_da):.1f} m beyond ic_drift_tolerance = {self.ic_drift_tolerance:g} m")
        return problems

    def trim_decision(self, msg: OrbitDetermination, now, kept):
        """:func:`plan_trim` from the OD with the maneuvers ``kept`` of the plan in force still to fly and the burns
        flown after the decision time (under lockstep the solution arrives after the burns of its step)."""
        roe0, chief, da_dot = self.start_state(msg, now)
        sigma_a_da = math.sqrt(max(msg.estimate.covariance[0], 0.0))
        to_fly = plan_burns(kept)
        burns = to_fly + [b for b in self.executed if b.epoch > chief.t0]
        return plan_trim(roe0, chief, da_dot, burns, self.t_final, now + self.cfg.planning_margin,
                         sigma_a_da, msg.a_da_dot_sigma, self.ic_drift_tolerance, self.cfg,
                         t_od=time_to_sec(msg.estimate.header.stamp),
                         sigma_burns=burns_drift_sigma([b.dv_rel[1] for b in to_fly], chief.a, self.burn_sigma))

    def _guarded(self, rejected, failed, fn, *args):
        """``fn(*args)``, or None with the reason logged and on /diagnostics: a ValueError is a bad estimate or no
        solution (``rejected``), anything else a bug (``failed``) that must not take the node down."""
        try:
            return fn(*args)
        except ValueError as exc:
            self.get_logger().error(f"{rejected}: {exc}")
            publish_status(self, self.diag_pub, ERROR, f"{rejected}: {exc}", self._values())
        except Exception as exc:  # noqa: BLE001 -- reported, never fatal
            self.get_logger().error(f"{failed}: {exc!r}\n{traceback.format_exc()}")
            publish_status(self, self.diag_pub, ERROR, f"{failed}: {exc!r}", self._values())
        return None

    def _committed_burn(self, t_od, now):
        """A burn of the plan in force that a re-plan must not touch: due within ``planning_margin`` from now, or
        executed after the OD epoch without the executed-maneuver record having arrived yet (see the module
        docstring); None when re-planning is free."""
        flown = {round(b.epoch, 3) for b in self.executed}
        for t in self.burn_epochs or ():
            if round(t, 3) in flown:  # flown (a re-plan after a burn starts at that burn's epoch)
                continue
            if now <= t < now + self.cfg.planning_margin or t_od <= t < now:
                return t
        if self.t_final is not None and now + 2.0 * self.cfg.planning_margin > self.t_final:
            return self.t_final  # the acquisition is (nearly) complete: no new acquisition from here
        return None

    def make_plan(self, msg: OrbitDetermination, now, keep_arc=True):
        """ManeuverPlan and core plan for one OD solution; raises ValueError on a bad estimate or no solution."""
        roe0, chief, da_dot = self.start_state(msg, now)
        t_start = chief.t0
        # corrections of an acquisition in progress aim at its IC epoch; a first plan opens a new window
        cfg = self.cfg if self.t_final is None else dataclasses.replace(self.cfg, window=self.t_final - t_start)
        t_f = self.t_final
        if t_f is None:
            t_f = float(grid_epochs(t_start, t_start + cfg.window, chief, cfg.grid_per_orbit, cfg.j2)[-1])
        arc = self.radar_arc(msg, t_f) if keep_arc else None
        kwargs = dict(t_earliest=t_start + self.cfg.planning_margin, no_burns=[(arc[0], arc[2])] if arc else ())
        margin = ei_margin(msg_to_roe(msg.estimate) * chief.a, msg.estimate.covariance, self.ei_margin_sigmas)
        try:  # the e/i magnitudes planned with the OD's uncertainty as margin above min_ei (ei_margin_sigmas)
            plan = plan_acquisition(roe0, chief, da_dot, dataclasses.replace(cfg, min_ei=cfg.min_ei + margin),
                                    **kwargs)
        except AcquisitionInfeasible:
            if margin == 0.0:
                raise
            plan = plan_acquisition(roe0, chief, da_dot, cfg, **kwargs)

        out = ManeuverPlan(strategy="ic_acquisition", p_reduction=0.0)
        out.header.stamp = sec_to_time(t_start)  # the plan describes the burns from its start state on
        out.header.frame_id = interfaces.CARRIER_RTN_FRAME
        out.maneuvers = [maneuver_msg(float(t), float(wrap_angle(u)), dv, "carrier", "ic_acquisition")
                         for t, u, dv in zip(plan.epochs, plan.u, plan.dv_carrier)]
        out.aimed = self.aimed(msg, plan.final_roe, plan.t_final)
        return out, plan

    def drift_sigma(self, msg: OrbitDetermination, t_final):
        """1-sigma [m] of a da at ``t_final`` predicted from the OD (:func:`predicted_drift_sigma`); None without
        ``trim`` (the plans of an acquisition without the final OD re-plan on every newer solution) or t_F."""
        if not self.trim or t_final is None:
            return None
        sigma_a_da = math.sqrt(max(msg.estimate.covariance[0], 0.0))
        return predicted_drift_sigma(sigma_a_da, msg.a_da_dot_sigma, t_final - time_to_sec(msg.estimate.header.stamp))

    def plan_knowledge(self, msg: OrbitDetermination):
        """1-sigma [m] of a da at t_F as the plan in force knows it now: its OD's, with the execution errors of the
        carrier burns flown since that OD (``burn_sigma`` of each one's a da change 2 |dvT| / n, seed 002 Eq. 2);
        None without a plan (or without ``trim``)."""
        if self.plan_sigma is None:
            return None
        flown = [b.dv_rel[1] for b in self.executed if b.epoch > self.plan_od_epoch]
        return math.hypot(self.plan_sigma,
                          burns_drift_sigma(flown, msg.estimate.chief.semi_major_axis, self.burn_sigma))

    def radar_arc(self, msg: OrbitDetermination, t_final):
        """``(start, last_rise, end)`` [s] of the final OD's burn-free radar arc for the IC epoch ``t_final``
        (:func:`final_od_arc` of the predicted TIRA passes of the OD's chief); None with ``trim`` or ``final_od_arc``
        off, or without one."""
        if not (self.trim and self.final_od_arc):
            return None
        t_od = time_to_sec(msg.estimate.header.stamp)
        kep = elements_to_array(msg.estimate.chief)
        # one OD and IC epoch give one arc: decide and make_plan (and every re-plan from the same OD) ask again
        key = (kep.tobytes(), np.array([t_od, t_final], dtype=float).tobytes())
        if key not in self.arcs:
            passes = radar_passes(kep, t_od, t_final - 2.0 * SECONDS_PER_DAY, t_final + 3.0 * CLUSTER_GAP, self.jd0,
                                  j2=self.cfg.j2)
            # the last pass before t_F ends the arc, three passes (not its cluster's last pass: see the trim module)
            if len(self.arcs) >= 16:
                self.arcs.clear()
            self.arcs[key] = final_od_arc(passes, t_final, self.final_od_arc)
        return self.arcs[key]

    def start_state(self, msg: OrbitDetermination, now):
        """The best knowledge at max(OD epoch, now, the latest burn on record): the estimate plus every carrier burn
        flown since its epoch, as
        (ROE, Chief there, da_dot [1/s]); raises ValueError on a bad estimate."""
        el = msg.estimate.chief
        a = el.semi_major_axis
        if not (math.isfinite(a) and a > 6.4e6):
            raise ValueError(f"chief semi-major axis {a} m is not a valid low Earth orbit")
        t_od = time_to_sec(msg.estimate.header.stamp)
        od_chief = Chief(a=a, inc=el.inclination, u0=el.mean_arg_latitude, t0=t_od)
        roe_od = msg_to_roe(msg.estimate)
        da_dot = msg.a_da_dot / a
        check_inputs(roe_od, od_chief, da_dot)
        # every burn on record, also one flown after ``now`` (a solution stamped before a burn it arrives after)
        t_start = max(t_od, now, *(b.epoch for b in self.executed))
        flown = [b for b in self.executed if t_od < b.epoch <= t_start]
        roe0 = state_at(roe_od, t_od, flown, t_start, od_chief, self.cfg.j2, da_dot)
        return roe0, Chief(a=a, inc=el.inclination, u0=float(od_chief.u_at(t_start, self.cfg.j2)), t0=t_start), da_dot

    def aimed(self, msg: OrbitDetermination, final_roe, t_final):
        """The plan's ``aimed`` field: the predicted ROE at the IC epoch with the chief's elements there."""
        el = msg.estimate.chief
        kep = propagate_chief(elements_to_array(el), t_final - time_to_sec(msg.estimate.header.stamp), self.cfg.j2)
        kep[3:] = wrap_angle(kep[3:])
        aimed_chief = array_to_elements(kep)
        aimed_chief.mean_arg_latitude = float(wrap_angle(aimed_chief.mean_arg_latitude))
        return roe_to_msg(final_roe, aimed_chief, sec_to_time(t_final))


def main(args=None):
    from .spin import run

    return run(IcPlannerNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
