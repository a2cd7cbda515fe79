"""sim: the dynamics simulator that closes the loop on sim time.

Publishes ``/clock`` faster than real time, propagates the truth relative orbit (``dynamics: secular``, the
default: :class:`roe_sep.core.truth.secular.TruthModel`, J2 + true differential drag; ``dynamics: nonlinear``:
:class:`roe_sep.core.truth.nonlinear.NonlinearTruth`, both spacecraft integrated numerically with J2-J4 and drag, ROE
published as mean ROE of the numerical states), applies the commanded ejection with its real dispersion and executes
every planned carrier burn at its epoch with execution and attitude errors (seed 002 Eq. 22, seeded). A plan's
burns are executed only once the safety monitor has approved that plan (``require_plan_approval``); while a burn
waits for its approval the clock holds, up to ``approval_timeout`` wall seconds, after which the burn is dropped.

Publishes the truth ROE (``/sim/truth/roe``) and RTN state (``/sim/truth/rtn``) every ``truth_period`` and right after
each burn, every executed burn on ``/sim/executed_maneuvers`` (as executed, errors included) and ``/diagnostics``
with the running minimum distance.
"""

import dataclasses
import json
import math
import time

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from rclpy.node import Node
from roe_sep_msgs.msg import (
    EjectionEvent,
    ImpulsiveManeuver,
    LockstepAck,
    LockstepStep,
    ManeuverPlan,
    OrbitDetermination,
    RelativeOrbitalElements,
    RelativeState,
    SafetyStatus,
)
from rosgraph_msgs.msg import Clock

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.constants import ARCSEC
from ..core.od.radar import DEFAULT_EPOCH_UTC, julian_date, raan_from_ltan
from ..core.relmotion.dynamics import drag_da_dot
from ..core.separation.double_impulse import InfeasibleDesignError, design
from ..core.truth.secular import ExecutionErrors, TruthModel, chief_from_u, error_references
from .convert import (
    array_to_elements,
    array_to_vector,
    maneuver_msg,
    relative_dv,
    roe_to_msg,
    sec_to_time,
    time_to_sec,
    vector_to_array,
)
from .diagnostics import ERROR, OK, WARN, publish_status
from .lockstep import ACK_QOS, STEP_QOS, Lockstep
from .params import ParameterError, declare, finite, require

PLAN_TOPICS = (interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.ACQUISITION_PLAN_TOPIC)
ACQUISITION_PLANNER = "roe_sep/ic_planner"  # its /diagnostics status name
EJECTION_TIMING_STREAM = 2  # the ejection delay's stream of a run seed (graph.RADAR_STREAM = 1: the radar noise)
DEFAULT_DURATION = 280800.0  # s: 3.25 days, through OD and the initial-condition acquisition and half a day on


@dataclasses.dataclass
class PendingBurn:
    epoch: float
    maneuver: ImpulsiveManeuver
    topic: str
    plan_stamp: float
    error_reference: np.ndarray | None = None  # the unreduced drift-stop its magnitude error acts on (Eq. 18)


class SimNode(Node):
    def __init__(self):
        super().__init__("sim")
        self.final_timer = None  # repeats the final status (see _status)
        scenario_file = declare(self, "scenario_file", "", "scenario YAML ('' = embedded default)")
        self.seed = declare(self, "seed", 0, "seed of the ejection/burn/drag dispersions")
        self.disperse = declare(self, "disperse", True, "apply execution errors, the drag uncertainty and the "
                                                        "ejection delay")
        self.ejection_delay_max = declare(
            self, "ejection_delay_max", 10.0, "s, the release mechanism fires uniformly within this delay after "
            "the commanded ejection epoch (an assumption: no seed gives a value; 0: on time)")
        self.duration = declare(self, "duration", DEFAULT_DURATION, "s, sim time at which the run ends")
        self.time_step = declare(self, "time_step", 600.0, "s of sim time per clock tick (lockstep: per step)")
        tick_period = declare(self, "tick_period", 0.01, "wall s between clock ticks")
        self.truth_period = declare(self, "truth_period", 60.0, "s, sim-time period of the truth topics")
        u0_deg = declare(self, "u0_deg", 50.0, "deg, carrier mean argument of latitude at sim time 0")
        ltan = declare(self, "ltan_hours", 9.5, "h, local time of the carrier's ascending node (BIROS: 09:30)")
        epoch = declare(self, "epoch_utc", DEFAULT_EPOCH_UTC, "ISO-8601 UTC calendar epoch of sim time 0")
        self.require_approval = declare(self, "require_plan_approval", True,
                                        "execute a plan only after the safety monitor approved it")
        self.approval_timeout = declare(self, "approval_timeout", 10.0, "wall s a burn may wait for its approval")
        self.distance_step = declare(self, "distance_step", 10.0, "s, sampling of the minimum-distance tracking")
        self.departure = declare(self, "departure_distance", 1000.0,
                                 "m, closest approaches are tracked once the picosatellite is this far away")
        self.j2 = declare(self, "j2", True, "secular J2 in the truth dynamics (secular dynamics only)")
        self.dynamics = declare(self, "dynamics", "nonlinear",
                                "truth: 'secular' (ROE model) or 'nonlinear' (both spacecraft integrated numerically)")
        wait_for = declare(self, "wait_for", [""], "'topic=count' items: hold the clock at 0 until each topic has "
                                                  "that many subscribers (every node up)")
        self.start_timeout = declare(self, "start_timeout", 60.0, "wall s to wait for those subscribers at most")
        participants = declare(self, "lockstep_participants", [""],
                               "node names of the lockstep participants ([] or ['']: free-running clock)")
        self.real_time_factor = declare(self, "real_time_factor", 0.0,
                                        "lockstep: sim s per wall s at most (0: as fast as the machine allows)")
        self.step_timeout = declare(self, "step_timeout", 120.0,
                                    "lockstep: wall s a step may wait for a participant before the run fails")

        for name, value in (("duration", self.duration), ("time_step", self.time_step),
                            ("tick_period", tick_period), ("truth_period", self.truth_period),
                            ("approval_timeout", self.approval_timeout), ("distance_step", self.distance_step),
                            ("departure_distance", self.departure)):
            require(name, finite(value) and value > 0, value, "a positive number")
        require("u0_deg", finite(u0_deg), u0_deg, "a finite angle [deg]")
        require("ltan_hours", finite(ltan) and 0 <= ltan < 24, ltan, "a local time in [0, 24) h")
        try:
            raan = float(raan_from_ltan(ltan, julian_date(epoch)))
        except ValueError as exc:
            raise ParameterError(f"parameter 'epoch_utc' must be an ISO-8601 UTC date-time, got {epoch!r}: {exc}") \
                from exc
        require("seed", isinstance(self.seed, int), self.seed, "an integer")
        require("dynamics", self.dynamics in ("secular", "nonlinear"), self.dynamics, "'secular' or 'nonlinear'")
        self.wait_for = {}
        for item in (w for w in wait_for if w):
            topic, _, count = item.partition("=")
            require("wait_for", topic.startswith("/") and count.isdigit(), wait_for,
                    "a list of 'topic=count' items, e.g. ['/sim/truth/roe=4']")
            self.wait_for[topic] = int(count)
        require("start_timeout", finite(self.start_timeout) and self.start_timeout >= 0, self.start_timeout,
                "a non-negative number [s]")
        require("real_time_factor", finite(self.real_time_factor) and self.real_time_factor >= 0,
                self.real_time_factor, "a non-negative number (0: as fast as possible)")
        require("step_timeout", finite(self.step_timeout) and self.step_timeout > 0, self.step_timeout,
                "a positive number [s]")
        self.participants = sorted({p for p in participants if p})
        require("lockstep_participants", all(isinstance(p, str) and p != "sim" for p in self.participants),
                list(participants), "a list of node names other than 'sim'")
        for name, value in (("disperse", self.disperse), ("require_plan_approval", self.require_approval),
                            ("j2", self.j2)):
            require(name, isinstance(value, bool), value, "true or false")
        try:
            scenario = load_scenario(scenario_file or None)
            carrier = design(scenario.separation)
        except (ConfigError, InfeasibleDesignError) as exc:
            raise ParameterError(f"parameter 'scenario_file': {exc}") from exc

        sep, mc = scenario.separation, scenario.monte_carlo
        a, inc = carrier.a, carrier.inc
        rng = np.random.default_rng(self.seed)
        db_factor = rng.normal(1.0, mc.ballistic_sigma) if self.disperse else 1.0
        da_dot = float(drag_da_dot(mc.delta_b * db_factor, mc.density, a)) if mc.drag else 0.0
        chief0 = chief_from_u(a, inc, raan, math.radians(u0_deg))
        if self.dynamics == "nonlinear":
            from ..core.truth.nonlinear import Atmosphere, NonlinearTruth

            b_c = mc.carrier.ballistic if mc.drag else 0.0
            b_d = b_c + mc.delta_b * db_factor if mc.drag else 0.0
            self.truth = NonlinearTruth(chief0, 0.0, b_c, b_d, Atmosphere.normalised(mc.density, chief0),
                                        da_dot=da_dot)
        else:
            self.truth = TruthModel(chief0, 0.0, da_dot, self.j2)
        require("ejection_delay_max", finite(self.ejection_delay_max) and 0.0 <= self.ejection_delay_max <= 600.0,
                self.ejection_delay_max, "a delay in [0, 600] s")
        # its own stream of the run seed, so the other dispersions keep their draws
        timing = np.random.default_rng(np.random.SeedSequence([int(self.seed), EJECTION_TIMING_STREAM]))
        self.ejection_delay = float(timing.uniform(0.0, self.ejection_delay_max)) if self.disperse else 0.0
        self.errors = ExecutionErrors(rng, sep.spl_sigma if self.disperse else 0.0,
                                      sep.thruster_sigma if self.disperse else 0.0,
                                      mc.attitude_sigma_arcsec * ARCSEC if self.disperse else 0.0)
        self.dispersions = {"drag_factor": float(db_factor), "ejection_delay_s": self.ejection_delay, "configured": {
            "disperse": self.disperse, "ballistic_sigma": mc.ballistic_sigma, "ejection_delay_max_s":
            self.ejection_delay_max, **{k: getattr(self.errors, k) for k in ("spl_sigma", "thruster_sigma",
                                                                             "attitude_sigma")}}}

        self.t = 0.0
        self.next_truth = 0.0
        self.ejections = {}  # stamp -> epoch of pending ejection events
        self.seen_ejections = set()
        self.pending: list[PendingBurn] = []
        self.flown = set()  # (topic, purpose, epoch) of every executed burn
        self.plan_stamps = {}  # topic -> stamp of the plan in force
        self.approvals = {}  # (topic, plan stamp) -> bool
        self.holds = {}  # what the clock waits for -> wall time the wait began (see _holding)
        self.burns = 0
        self.min_dist = (math.inf, math.nan)
        self.departed = False
        self.tail = (np.empty(0), np.empty(0))  # last samples of the previous step (local minima across steps)
        self.next_status = 3600.0
        self.done = False
        self.waiting_since = time.monotonic()
        self.ejected_at = None  # set by the ejection until the drift-stop plan answering it arrives
        self.od_seen = set()

        # the simulator reads its inputs through the lockstep buffer too (it coordinates, so it does not acknowledge)
        self.lockstep = Lockstep(self, acknowledge=False)
        self.lockstep.on_round_done = self._round_check
        ls = self.lockstep
        self.clock_pub = self.create_publisher(Clock, interfaces.CLOCK_TOPIC, 10)
        self.roe_pub = ls.publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
        self.rtn_pub = ls.publisher(RelativeState, interfaces.TRUTH_RTN_TOPIC, interfaces.STREAM)
        self.exec_pub = ls.publisher(ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_ejection, interfaces.LATCHED,
                     what="ejection event")
        for topic in PLAN_TOPICS:
            ls.subscribe(ManeuverPlan, topic, lambda m, tp=topic: self.on_plan(tp, m), interfaces.LATCHED,
                         what=f"plan on {topic}")
        ls.subscribe(SafetyStatus, interfaces.PLAN_CHECK_TOPIC, self.on_plan_check, interfaces.EXECUTED,
                     what="plan check")
        ls.subscribe(OrbitDetermination, interfaces.OD_TOPIC, self.on_od, interfaces.LATCHED, what="OD solution")
        if self.participants:
            self.step_pub = self.create_publisher(LockstepStep, interfaces.LOCKSTEP_STEP_TOPIC, STEP_QOS)
            self.create_subscription(LockstepAck, interfaces.LOCKSTEP_ACK_TOPIC, self.on_ack, ACK_QOS)
            self.acks = {}  # participant -> its latest LockstepAck
            self.step_index, self.round, self.t_prev = 0, 0, 0.0
            self.round_counts = {}
            self.round_sent = None  # wall time the current round was published (None: not started)
            self.wall_start = None
            self.continue_timer = None
            self.steps_published = 0
            self.timer = self.create_timer(0.05, self.lockstep_watch)
        else:
            self.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, self.on_diagnostics, 100)
            self.timer = self.create_timer(tick_period, self.tick)
        self.get_logger().info(
            f"truth: a = {a:.1f} m, i = {math.degrees(inc):.3f} deg, raan = {math.degrees(raan):.2f} deg, "
            f"differential drag a*da_dot = "
            f"{da_dot * a * 86400:.1f} m/day, {self.duration / 86400:.2f} days, "
            + (f"lockstep with {self.participants}" if self.participants
               else f"free-running at {self.time_step / tick_period:.0f}x"))
        self._status(OK, "running")

    # ----------------------------------------------------------------- inputs
    def on_ejection(self, ev: EjectionEvent):
        key = time_to_sec(ev.header.stamp)
        dv = vector_to_array(ev.ejection.dv_rtn)
        if key in self.seen_ejections:
            return
        if not (math.isfinite(key) and np.all(np.isfinite(dv))) or ev.ejection.spacecraft != "picosatellite":
            self._status(ERROR, f"ejection event rejected (epoch {key}, dv {dv.tolist()}, "
                                f"spacecraft {ev.ejection.spacecraft!r})")
            return
        if self.truth.separated:
            self._status(WARN, "second ejection event ignored: the picosatellite is already released")
            return
        self.seen_ejections.add(key)
        # the spring fires ejection_delay after the commanded epoch (the executed maneuver says when)
        self.pending.append(PendingBurn(key + self.ejection_delay, ev.ejection, interfaces.EJECTION_TOPIC, key))

    def on_plan(self, topic, plan: ManeuverPlan):
        stamp = time_to_sec(plan.header.stamp)
        if self.plan_stamps.get(topic) == stamp:
            return
        try:
            burns = [PendingBurn(time_to_sec(m.epoch), m, topic, stamp) for m in plan.maneuvers]
            for b in burns:
                relative_dv(b.maneuver)
                if not (math.isfinite(b.epoch) and np.all(np.isfinite(vector_to_array(b.maneuver.dv_rtn)))):
                    raise ValueError("non-finite epoch or dv")
            refs = error_references([b.maneuver.purpose for b in burns],
                                    [vector_to_array(b.maneuver.dv_rtn) for b in burns], plan.p_reduction)
            for b, ref in zip(burns, refs):
                b.error_reference = ref
        except ValueError as exc:
            self._status(ERROR, f"plan on {topic} rejected: {exc}")
            return
        # a new plan replaces the burns of the previous plan on the same topic that are not executed yet; a burn
        # already flown is never flown again (a restarted planner re-publishes the plan it made before)
        burns = [b for b in burns if self._key(b) not in self.flown]
        self.pending = [b for b in self.pending if b.topic != topic] + burns
        self.plan_stamps[topic] = stamp
        if topic == interfaces.DRIFT_STOP_PLAN_TOPIC:
            self.holds.pop("drift_stop", None)
        self.get_logger().info(f"plan on {topic}: {len(burns)} burn(s) from t = "
                               f"{min((b.epoch for b in burns), default=math.nan):.0f} s")

    @staticmethod
    def _key(burn: PendingBurn):
        return burn.topic, burn.maneuver.purpose, round(burn.epoch, 3)

    def on_plan_check(self, check: SafetyStatus):
        if check.source.startswith("plan:"):
            self.approvals[(check.source[5:], time_to_sec(check.plan_stamp))] = bool(check.safe)

    # ------------------------------------------------------------------ loop
    def ready(self):
        """Start the clock once every node is up (``wait_for``: subscribers per topic, from the ROS graph), so that
        nobody misses the first seconds; after ``start_timeout`` start anyway (WARN)."""
        if self.waiting_since is None:
            return True
        missing = {t: n for t, n in self.wait_for.items() if self.count_subscribers(t) < n}
        if not missing:
            self.waiting_since = None
            return True
        if time.monotonic() - self.waiting_since > self.start_timeout:
            self.waiting_since = None
            self._status(WARN, f"started after {self.start_timeout:g} s without the subscribers {missing}")
            return True
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
        return False

    def _holding(self, reason):
        """The one wall-clock wait of the clock: True while ``reason`` (the drift-stop plan, an approval, the
        acquisition decision) has been awaited for at most ``approval_timeout`` wall seconds (the wait starts now
        unless it began earlier); False once that has run out, and the wait is forgotten."""
        since = self.holds.setdefault(reason, time.monotonic())
        if time.monotonic() - since > self.approval_timeout:
            del self.holds[reason]
            return False
        return True

    def awaiting_drift_stop(self):
        """After the ejection the ground owes the drift-stop plan: hold the clock until one answering it has
        arrived (at most ``approval_timeout`` wall seconds), as for a plan awaiting its safety check."""
        if self.ejected_at is None or interfaces.DRIFT_STOP_PLAN_TOPIC in self.plan_stamps:
            return False
        if not self._holding("drift_stop"):
            self.ejected_at = None
            self._status(ERROR, f"no drift-stop plan within {self.approval_timeout:g} s of the ejection")
            return False
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
        return True

    def on_od(self, od: OrbitDetermination):
        """Free-running clock only: a new OD solution opens the wall-clock hold for the acquisition planner's decision
        (under lockstep the reaction rounds of the step already wait for it)."""
        if self.participants:
            return
        stamp = time_to_sec(od.header.stamp)
        if stamp not in self.od_seen:
            self.od_seen.add(stamp)
            self.holds["acquisition"] = time.monotonic()

    def on_diagnostics(self, array: DiagnosticArray):
        if any(s.name == ACQUISITION_PLANNER for s in array.status):
            self.holds.pop("acquisition", None)  # the acquisition planner has decided on the newest OD solution

    def awaiting_acquisition(self):
        """After a new OD solution the acquisition planner owes a decision (a plan, or why not: it ends every
        decision with a /diagnostics status): hold the clock until it arrives, at most ``approval_timeout``."""
        if "acquisition" not in self.holds:
            return False
        if not self._holding("acquisition"):
            self._status(ERROR, f"no decision of {ACQUISITION_PLANNER} within {self.approval_timeout:g} s of an "
                                "OD solution")
            return False
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
        return True

    def tick(self):
        if self.done or not self.ready() or self.awaiting_drift_stop() or self.awaiting_acquisition():
            return
        t_next = min(self.t + self.time_step, self.duration)
        while True:
            due = sorted((b for b in self.pending if b.epoch <= t_next), key=lambda b: b.epoch)
            if not due:
                break
            burn = due[0]
            verdict = self._approval(burn)
            if verdict is None:  # hold the clock until the monitor has spoken or the wait times out
                self._advance(max(self.t, min(burn.epoch, t_next)))
                self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
                return
            self.pending.remove(burn)
            if verdict:
                self._execute(burn)
        self._advance(t_next)
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
        if self.t >= self.duration:
            self.done = True
            self._status(OK, "scenario complete")
            self.get_logger().info("scenario complete")

    # ------------------------------------------------------------- lockstep
    def lockstep_watch(self):
        """Wall-clock watchdog of the lockstep clock: starts the run once every participant is up, asks again for
        a lost acknowledgement, and fails the run with the silent participants named when a step waits longer
        than ``step_timeout`` (a fault detector only: it never changes what is simulated)."""
        if self.done:
            return
        now = time.monotonic()
        if self.round_sent is None:  # not started: every participant and subscriber up?
            if self.ready_lockstep(now):
                self.wall_start = now
                self._publish_step()
            return
        waited = now - self.round_sent
        if self.continue_timer is not None:
            return
        limit = self.start_timeout if self.step_index == 0 else self.step_timeout
        if waited > limit:
            missing = [p for p in self.participants if self._acked(p) is False]
            step = f"step {self.step_index} round {self.round} (t = {self.t:.0f} s)"
            self._fault(f"lockstep: no acknowledgement of {step} from {', '.join(missing) or 'nobody'} within "
                        f"{limit:g} s" if missing else f"lockstep: {step} incomplete after {limit:g} s: the "
                        f"simulator still waits for counted messages {self._own_missing()}")
        elif waited > 1.0 and now - self.round_resent > 1.0:
            self.round_resent = now
            self.step_pub.publish(self.step_msg)  # a participant that missed it acknowledges again

    def ready_lockstep(self, now):
        missing = {t: n for t, n in self.wait_for.items() if self.count_subscribers(t) < n}
        if self.count_subscribers(interfaces.LOCKSTEP_STEP_TOPIC) < len(self.participants):
            missing[interfaces.LOCKSTEP_STEP_TOPIC] = len(self.participants)
        if self.count_publishers(interfaces.LOCKSTEP_ACK_TOPIC) < len(self.participants):
            missing[interfaces.LOCKSTEP_ACK_TOPIC + " (publishers)"] = len(self.participants)
        if not missing:
            return True
        if now - self.waiting_since > self.start_timeout:
            self._fault(f"lockstep: participants not up within {self.start_timeout:g} s: missing {missing}")
        return False

    def _own_missing(self):
        counts = self.lockstep.last_counts
        return {t: counts.get(t, 0) - self.lockstep.received[t] for t in self.lockstep.inputs
                if counts.get(t, 0) > self.lockstep.received[t]}

    def _fault(self, reason):
        self.done = True
        self.get_logger().error(reason)
        self._status(ERROR, f"scenario aborted: {reason}")

    def _acked(self, name):
        ack = self.acks.get(name)
        return ack is not None and (ack.step, ack.round) == (self.step_index, self.round)

    def on_ack(self, ack: LockstepAck):
        if ack.node not in self.participants:
            return
        prev = self.acks.get(ack.node)
        if prev is None or (ack.step, ack.round) >= (prev.step, prev.round):
            self.acks[ack.node] = ack
        self._round_check()

    def _totals(self):
        """Messages published so far per counted topic: the simulator's and every participant's latest count."""
        totals = dict(self.lockstep.published)
        for ack in self.acks.values():
            for topic, n in zip(ack.topics, ack.published):
                totals[topic] = totals.get(topic, 0) + n
        return totals

    def _publish_step(self, final=False):
        totals = self._totals()
        topics = sorted(totals)
        msg = LockstepStep(step=self.step_index, round=self.round, period_start=float(self.t_prev), topics=topics,
                           counts=[int(totals[t]) for t in topics], final=final)
        msg.header.stamp = sec_to_time(self.t)
        self.step_msg, self.round_counts = msg, totals
        self.round_sent = self.round_resent = time.monotonic()
        self.steps_published += 1
        self.step_pub.publish(msg)
        if not final:
            self.lockstep.on_step_msg(msg)  # the simulator's own inputs of this round

    def _round_check(self):
        """After every acknowledgement: the round is over when every participant and the simulator itself have
        processed it; a reaction (new messages on a topic someone reads) opens the next round of the same step,
        else sim time advances."""
        if not self.participants or self.done or self.round_sent is None or self.continue_timer is not None:
            return
        if self.lockstep.last != (self.step_index, self.round):
            return
        if not all(self._acked(p) for p in self.participants):
            return
        totals = self._totals()
        read = set(self.lockstep.inputs)
        for ack in self.acks.values():
            read.update(ack.inputs)
        if any(totals.get(t, 0) != self.round_counts.get(t, 0) for t in read):
            self.round += 1
            self._publish_step()
            return
        self._continue()

    def _continue(self):
        """Advance to the next step now, or when the real-time factor allows."""
        if self.continue_timer is not None:
            self.destroy_timer(self.continue_timer)
            self.continue_timer = None
        if self.t >= self.duration:
            self.done = True
            self._publish_step(final=True)
            self._status(OK, "scenario complete")
            self.get_logger().info(f"scenario complete: {self.steps_published} lockstep messages in "
                                   f"{time.monotonic() - self.wall_start:.1f} s")
            return
        t_next = min(self.t + self.time_step, self.duration)
        if self.real_time_factor > 0:
            wait = self.wall_start + t_next / self.real_time_factor - time.monotonic()
            if wait > 0:
                self.continue_timer = self.create_timer(wait, self._continue)
                return
        self._step_to(t_next)
        self.step_index += 1
        self.round = 0
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))
        self._publish_step()

    def _step_to(self, t_next):
        """Fly the burns due up to ``t_next`` (in epoch order) and move the truth there."""
        self.t_prev = self.t
        for burn in sorted((b for b in self.pending if b.epoch <= t_next), key=lambda b: b.epoch):
            self.pending.remove(burn)
            if self._verdict(burn):
                self._execute(burn)
        self._advance(t_next)

    def _verdict(self, burn):
        """Lockstep: the safety monitor has checked every plan before sim time reaches its burns, so a missing
        check is a fault of the plan, not a matter of waiting: the burn is not executed (ERROR)."""
        if burn.topic == interfaces.EJECTION_TOPIC or not self.require_approval:
            return True
        verdict = self.approvals.get((burn.topic, burn.plan_stamp))
        if verdict is None:
            self._status(ERROR, f"burn at t = {burn.epoch:.0f} s of the plan on {burn.topic} not executed: the "
                                "safety monitor did not check the plan")
        elif not verdict:
            self._status(ERROR, f"burn at t = {burn.epoch:.0f} s of the plan on {burn.topic} not executed: "
                                "the safety monitor flagged the plan")
        return bool(verdict)

    def _approval(self, burn):
        """True: execute; False: drop; None: wait."""
        if burn.topic == interfaces.EJECTION_TOPIC or not self.require_approval:
            return True
        verdict = self.approvals.get((burn.topic, burn.plan_stamp))
        if verdict is not None:
            self.holds.pop("approval", None)
            if not verdict:
                self._status(ERROR, f"burn at t = {burn.epoch:.0f} s of the plan on {burn.topic} not executed: "
                                    "the safety monitor flagged the plan")
            return verdict
        if not self._holding("approval"):
            self._status(ERROR, f"burn at t = {burn.epoch:.0f} s of the plan on {burn.topic} not executed: no safety "
                                f"check within {self.approval_timeout:g} s")
            return False
        return None

    def _advance(self, t_to):
        """Move the truth to ``t_to``, publishing the truth samples, tracking the minimum distance and reporting
        the hourly status at its own epoch (so that every output is the same whatever the step size)."""
        while self.next_status <= t_to:
            self._advance_to(self.next_status)
            self.next_status += 3600.0
            self._status(OK, "running")
        self._advance_to(t_to)

    def _advance_to(self, t_to):
        if t_to <= self.t:
            return
        if self.truth.separated:
            times, dist = self.truth.distances(self.t, t_to, self.distance_step)
            self._track_closest_approach(times, dist)
        epochs = []
        while self.next_truth <= t_to:
            epochs.append(self.next_truth)
            self.next_truth += self.truth_period
        if epochs:
            self._publish_truth(epochs)
        self.t = t_to

    def _track_closest_approach(self, times, dist):
        """Closest approach after the departure: the smallest local minimum of |r| once it exceeded
        ``departure_distance`` (the receding start of the separation itself is no approach)."""
        if self.tail[0].size and times.size and times[0] <= self.tail[0][-1]:  # consecutive steps share an end
            times, dist = times[1:], dist[1:]
        times = np.concatenate([self.tail[0], times])
        dist = np.concatenate([self.tail[1], dist])
        if not self.departed:
            out = np.nonzero(dist >= self.departure)[0]
            if out.size == 0:
                self.tail = (times[-2:], dist[-2:])
                return
            self.departed = True
            times, dist = times[out[0]:], dist[out[0]:]
        inner = np.nonzero((dist[1:-1] <= dist[:-2]) & (dist[1:-1] < dist[2:]))[0] + 1
        if inner.size:
            k = inner[np.argmin(dist[inner])]
            if dist[k] < self.min_dist[0]:
                self.min_dist = (float(dist[k]), float(times[k]))
        self.tail = (times[-2:], dist[-2:])

    def _execute(self, burn: PendingBurn):
        m = burn.maneuver
        t_exec = max(burn.epoch, self.t)
        if burn.epoch < self.t - 1e-6:
            self._status(WARN, f"{m.purpose} burn executed late at t = {self.t:.0f} s (planned {burn.epoch:.0f} s)")
        self._advance(t_exec)
        executed = self.errors.executed(vector_to_array(m.dv_rtn), m.spacecraft, burn.error_reference)
        done = maneuver_msg(t_exec, float(self.truth.u_at(t_exec)), executed, m.spacecraft, m.purpose)
        if self.dynamics == "nonlinear":
            self.truth.apply(t_exec, relative_dv(done), m.spacecraft)
        else:
            self.truth.apply(t_exec, relative_dv(done))
        self.flown.add(self._key(burn))
        if m.purpose == "ejection":
            self.ejected_at = t_exec
        self.burns += 1
        self.exec_pub.publish(done)
        self._publish_truth([t_exec])
        self.get_logger().info(f"t = {t_exec:.0f} s: executed {m.purpose} of the {m.spacecraft}, dv RTN = "
                               f"({executed[0]:+.4f}, {executed[1]:+.4f}, {executed[2]:+.4f}) m/s")
        self._status(OK, f"executed {m.purpose} burn")

    def _publish_truth(self, epochs):
        """The truth topics at each of ``epochs`` [s] (evaluated in one vectorized pass)."""
        kep, roe, (pos, vel) = self.truth.samples(np.asarray(epochs, dtype=float))
        for j, t in enumerate(epochs):
            stamp = sec_to_time(t)
            self.roe_pub.publish(roe_to_msg(roe[j], array_to_elements(kep[j]), stamp, frame_id=interfaces.TRUTH_FRAME))
            state = RelativeState(position=array_to_vector(pos[j]), velocity=array_to_vector(vel[j]))
            state.header.stamp = stamp
            state.header.frame_id = interfaces.CARRIER_RTN_FRAME
            self.rtn_pub.publish(state)

    def _status(self, level, message):
        publish_status(self, self.diag_pub, level, message, stamp=self.t, values={
            "sim_time_s": f"{self.t:.1f}",
            "burns_executed": self.burns,
            "min_distance_m": f"{self.min_dist[0]:.3f}",
            "min_distance_time_s": f"{self.min_dist[1]:.1f}",
            "truth_a_da_dot_m_per_day": f"{self.truth.da_dot * self.truth.a * 86400:.3f}",
            "dispersions_applied": json.dumps({**self.dispersions, "burns": self.errors.applied}),
        })
        if message.startswith(("scenario complete", "scenario aborted")) and self.final_timer is None:
            # the end of the run is repeated every wall second, as diagnostics are, until the node stops: a
            # watcher that joined late (the runner's observer, a launch event handler) still learns it
            self.final_timer = self.create_timer(1.0, lambda: self._status(level, message),
                                                 clock=RclpyClock(clock_type=ClockType.STEADY_TIME))
        if level == WARN:
            self.get_logger().warning(message)
        elif level == ERROR:
            self.get_logger().error(message)


def main(args=None):
    from .spin import run

    return run(SimNode, args)


if __name__ == "__main__":
    raise SystemExit(main())
