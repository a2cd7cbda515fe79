"""sim: the dynamics simulator that closes the loop on sim time -- its ROS interface.

Publishes ``/clock`` faster than real time, propagates the truth relative orbit (``dynamics: nonlinear``, the
default: :class:`roe_sep.core.truth.nonlinear.NonlinearTruth`, both spacecraft integrated numerically with J2-J4 and
drag, ROE published as mean ROE of the numerical states; ``dynamics: secular``:
:class:`roe_sep.core.truth.secular.TruthModel`, J2 + true differential drag), applies the commanded ejection with
its real dispersion and executes every planned carrier burn at its epoch with execution and attitude errors (seed
002 Eq. 22, seeded). A plan's burns are executed only once the safety monitor has approved that plan
(``require_plan_approval``); while a burn waits for its approval the clock holds, up to ``approval_timeout`` wall
seconds, after which the burn is dropped.

Publishes the truth ROE (``/sim/truth/roe``) and RTN state (``/sim/truth/rtn``) every ``truth_period`` and right after
each burn, every executed burn on ``/sim/executed_maneuvers`` (as executed, errors included), the carrier camera's
bearings of the picosatellite (``/sim/camera/bearing``: a sensor, so its noise is the simulator's,
:class:`roe_sep.core.truth.simulated.Camera`; every ``camera_period`` from the release for ``camera_duration``), the
ejection footage's 3D poses (``/sim/camera/pose``, :class:`roe_sep.core.truth.simulated.PoseFootage`,
:mod:`roe_sep.core.od.pose`: every ``pose_frame_period`` for ``pose_window`` after the release, while the
picosatellite is in the field of view, within the pose range and lit) and
``/diagnostics`` with the running minimum distance.

Parameters: :data:`roe_sep.nodes.parameters.SIM` (``sim --help``, docs/parameters.md). The parts: the truth over
the run (:mod:`roe_sep.core.truth.simulated`), the burn execution
(:mod:`roe_sep.core.truth.execution`), the clock (:class:`~.lockstep.Coordinator` with lockstep participants, else
:class:`~.free_running.FreeRunningClock`); this node holds the parameters, the topics and the conversions.
"""

import json
import math
import time

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PoseWithCovarianceStamped, Vector3Stamped
from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from rclpy.node import Node
from roe_sep_msgs.msg import (
    EjectionEvent,
    ImpulsiveManeuver,
    ManeuverPlan,
    OrbitDetermination,
    RelativeOrbitalElements,
    RelativeState,
    SafetyStatus,
)
from rosgraph_msgs.msg import Clock

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.od.pose import UNKNOWN, PoseCamera, carrier_lit
from ..core.od.radar import julian_date, raan_from_ltan
from ..core.separation.double_impulse import InfeasibleDesignError, design
from ..core.truth.contingency import resolve as resolve_contingency
from ..core.truth.execution import BurnExecution
from ..core.truth.secular import chief_from_u
from ..core.truth.simulated import Camera, PoseFootage, SimulatedTruth, camera_rng, dispersed_truth, pose_rng
from .convert import (
    TruthMessages,
    array_to_vector,
    maneuver_msg,
    sec_to_time,
    time_to_sec,
    vector_to_array,
)
from .diagnostics import ERROR, OK, WARN, publish_status
from .free_running import FreeRunningClock
from .lockstep import Coordinator, Lockstep
from .parameters import DEFAULT_DURATION  # noqa: F401  (re-exported: the launch files read it here)
from .params import ParameterError, declare

PLAN_TOPICS = (interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.ACQUISITION_PLAN_TOPIC)
LEVELS = {"WARN": WARN, "ERROR": ERROR}  # the core's report levels


class SimNode(Node):
    def __init__(self):
        super().__init__("sim")
        self.final_timer = None  # repeats the final status (see status)
        scenario_file = declare(self, "scenario_file")
        self.seed = declare(self, "seed")
        self.disperse = declare(self, "disperse")
        self.ejection_delay_max = declare(self, "ejection_delay_max")
        contingency = declare(self, "contingency")
        self.duration = declare(self, "duration")
        self.time_step = declare(self, "time_step")
        tick_period = declare(self, "tick_period")
        self.truth_period = declare(self, "truth_period")
        camera_period = declare(self, "camera_period")
        camera_sigma = math.radians(declare(self, "camera_sigma_deg"))
        camera_duration = declare(self, "camera_duration")
        pose_window = declare(self, "pose_window")
        cam = PoseCamera(sigma0=declare(self, "pose_sigma0"), pixels=declare(self, "pose_pixels"),
                         centroid_px=declare(self, "pose_centroid_px"), frame_period=declare(self, "pose_frame_period"))
        u0_deg = declare(self, "u0_deg")
        ltan = declare(self, "ltan_hours")
        epoch = declare(self, "epoch_utc")
        self.require_approval = declare(self, "require_plan_approval")
        self.approval_timeout = declare(self, "approval_timeout")
        self.distance_step = declare(self, "distance_step")
        self.departure = declare(self, "departure_distance")
        self.j2 = declare(self, "j2")
        self.dynamics = declare(self, "dynamics")
        wait_for = declare(self, "wait_for")
        self.start_timeout = declare(self, "start_timeout")
        participants = declare(self, "lockstep_participants")
        self.real_time_factor = declare(self, "real_time_factor")
        self.step_timeout = declare(self, "step_timeout")

        raan, scenario, carrier = self._check(ltan, epoch, wait_for, participants, scenario_file)
        try:
            chosen = resolve_contingency(scenario.contingency, contingency)
        except ConfigError as exc:
            raise ParameterError(f"parameter 'contingency': {exc}") from exc
        self.world = world = dispersed_truth(scenario, carrier, raan, math.radians(u0_deg), self.seed,
                                             disperse=self.disperse, dynamics=self.dynamics, j2=self.j2,
                                             ejection_delay_max=self.ejection_delay_max,
                                             contingency=chosen)
        self.truth = SimulatedTruth(world.model, self.truth_period, self.distance_step, self.departure,
                                    self._publish_truth, on_hour=lambda: self.status(OK, "running"))
        # the carrier camera: its own stream of the seed, so a run draws what it drew without it
        self.truth.camera = Camera(camera_period, camera_sigma, camera_duration, camera_rng(self.seed),
                                   self._publish_bearings)
        # the ejection footage: 3D poses of the picosatellite while in view and lit (its own stream of the seed)
        chief0, jd0 = chief_from_u(carrier.a, carrier.inc, raan, math.radians(u0_deg)), float(julian_date(epoch))
        self.truth.footage = PoseFootage(cam, pose_window, pose_rng(self.seed),
                                         lambda t: carrier_lit(chief0, t, jd0, self.j2), self._publish_poses)
        self.commanded_dv = None  # the commanded ejection (the camera's boresight)
        self.execution = BurnExecution(self.truth, world.errors, world.ejection_delay, self.require_approval,
                                       lambda level, text: self.status(LEVELS[level], text),
                                       contingency=world.contingency)
        self.done = False
        self.waiting_since = time.monotonic()
        self._interface(tick_period)
        self.get_logger().info(
            f"truth: a = {carrier.a:.1f} m, i = {math.degrees(carrier.inc):.3f} deg, raan = {math.degrees(raan):.2f} "
            f"deg, differential drag a*da_dot = "
            f"{world.da_dot * carrier.a * 86400:.1f} m/day, {self.duration / 86400:.2f} days, "
            + (f"lockstep with {self.participants}" if self.participants
               else f"free-running at {self.time_step / tick_period:.0f}x")
            + ("" if world.contingency is None else f"; contingency {world.contingency.name} "
               f"{json.dumps(world.contingency.values)}"))
        self.status(OK, "running")

    def _check(self, ltan, epoch, wait_for, participants, scenario_file):
        """What the parameter table cannot check alone (ParameterError naming the parameter); set ``wait_for`` and
        ``participants``; the carrier's node [rad], the scenario and its separation design."""
        try:
            raan = float(raan_from_ltan(ltan, julian_date(epoch)))
        except ValueError as exc:
            raise ParameterError(f"parameter 'epoch_utc' must be an ISO-8601 UTC date-time, got {epoch!r}: {exc}") \
                from exc
        self.wait_for = {}
        for item in (w for w in wait_for if w):
            topic, _, count = item.partition("=")
            self.wait_for[topic] = int(count)
        self.participants = sorted({p for p in participants if p})
        try:
            scenario = load_scenario(scenario_file or None)
            carrier = design(scenario.separation)
        except (ConfigError, InfeasibleDesignError) as exc:
            raise ParameterError(f"parameter 'scenario_file': {exc}") from exc
        return raan, scenario, carrier

    def _interface(self, tick_period):
        """Publishers, subscriptions and the clock; the simulator reads its inputs through the lockstep buffer too
        (it coordinates, so it does not acknowledge)."""
        self.lockstep = ls = Lockstep(self, acknowledge=False)
        self.clock_pub = self.create_publisher(Clock, interfaces.CLOCK_TOPIC, interfaces.RECORDED_DEPTH)
        self.roe_pub = ls.publisher(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.STREAM)
        self.rtn_pub = ls.publisher(RelativeState, interfaces.TRUTH_RTN_TOPIC, interfaces.STREAM)
        self._truth_messages = TruthMessages()  # the truth's two messages of each sample, serialized
        self.camera_pub = ls.publisher(Vector3Stamped, interfaces.CAMERA_TOPIC, interfaces.STREAM)
        self.pose_pub = ls.publisher(PoseWithCovarianceStamped, interfaces.POSE_TOPIC, interfaces.STREAM)
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
            self.free = None
            self.coordinator = Coordinator(self, self.participants, self.step_timeout, self.real_time_factor)
        else:
            self.coordinator = None
            self.free = FreeRunningClock(self)
            self.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, self.on_diagnostics, 100)
            self.timer = self.create_timer(tick_period, self.free.tick)

    @property
    def t(self):
        """Sim time [s]."""
        return self.truth.t

    # ----------------------------------------------------------------- inputs
    def on_ejection(self, ev: EjectionEvent):
        self.commanded_dv = vector_to_array(ev.ejection.dv_rtn)
        self.execution.eject(time_to_sec(ev.header.stamp), vector_to_array(ev.ejection.dv_rtn),
                             ev.ejection.spacecraft, ev.ejection.purpose)

    def on_plan(self, topic, plan: ManeuverPlan):
        maneuvers = [(time_to_sec(m.epoch), vector_to_array(m.dv_rtn), m.spacecraft, m.purpose)
                     for m in plan.maneuvers]
        try:
            burns = self.execution.plan(topic, time_to_sec(plan.header.stamp), maneuvers, plan.p_reduction)
        except ValueError as exc:
            self.status(ERROR, f"plan on {topic} rejected: {exc}")
            return
        if burns is None:  # the plan in force again
            return
        if self.free is not None:
            self.free.on_plan(topic)
        self.get_logger().info(f"plan on {topic}: {len(burns)} burn(s) from t = "
                               f"{min((b.epoch for b in burns), default=math.nan):.0f} s")

    def on_plan_check(self, check: SafetyStatus):
        if check.source.startswith("plan:"):
            self.execution.check(check.source[5:], time_to_sec(check.plan_stamp), check.safe)

    def on_od(self, od: OrbitDetermination):
        """Free-running clock only: a new OD solution opens the wall-clock hold for the acquisition planner's decision
        (under lockstep the reaction rounds of the step already wait for it)."""
        if self.free is not None:
            self.free.on_od(time_to_sec(od.header.stamp))

    def on_diagnostics(self, array: DiagnosticArray):
        self.free.on_diagnostics({s.name for s in array.status})

    # ------------------------------------------------------------------ the clocks' actions
    def publish_clock(self):
        self.clock_pub.publish(Clock(clock=sec_to_time(self.t)))

    def advance(self, t_to):
        """Move the truth to ``t_to`` [s] (its samples published, the hourly status at its own epoch)."""
        self.truth.advance(t_to)

    def step_to(self, t_next):
        """Lockstep: fly the burns due up to ``t_next`` (in epoch order) and move the truth there. The safety
        monitor has checked every plan before sim time reaches its burns, so a missing check is a fault of the
        plan, not a matter of waiting: the burn is not executed (ERROR)."""
        for burn in self.execution.due(t_next):
            self.execution.take(burn)
            verdict = self.execution.verdict(burn)
            if verdict is None:
                self.status(ERROR, f"{self.execution.describe(burn)} not executed: the safety monitor did not "
                                   "check the plan")
            if verdict:
                self.execute(burn)
        self.advance(t_next)

    def execute(self, burn):
        done = self.execution.execute(burn)
        if done.purpose == "ejection":
            self.truth.camera.release(done.epoch)  # the camera tracks the picosatellite from its release on
            if self.commanded_dv is not None:  # the footage looks along the commanded ejection
                self.truth.footage.release(done.epoch, self.commanded_dv)
        self.exec_pub.publish(maneuver_msg(done.epoch, done.u, done.dv_rtn, done.spacecraft, done.purpose))
        self.truth.publish([done.epoch])
        dv = done.dv_rtn
        self.get_logger().info(f"t = {done.epoch:.0f} s: executed {done.purpose} of the {done.spacecraft}, dv RTN = "
                               f"({dv[0]:+.4f}, {dv[1]:+.4f}, {dv[2]:+.4f}) m/s")
        self.status(OK, f"executed {done.purpose} burn")

    def fault(self, reason):
        self.done = True
        self.get_logger().error(reason)
        self.status(ERROR, f"scenario aborted: {reason}")

    # ------------------------------------------------------------------ outputs
    def _publish_truth(self, epochs, samples):
        """The truth topics at each of ``epochs`` [s] from the truth's ``samples`` at them: the messages of all samples
        serialized in one vectorised pass (:class:`~.convert.TruthMessages`), published sample by sample."""
        for roe, rtn in self._truth_messages(epochs, samples):
            self.roe_pub.publish(roe)
            self.rtn_pub.publish(rtn)

    def _publish_bearings(self, epochs, los):
        """The camera's measured lines of sight (carrier RTN, noise included) at ``epochs`` [s]."""
        for t, u in zip(epochs, los):
            msg = Vector3Stamped(vector=array_to_vector(u))
            msg.header.stamp = sec_to_time(t)
            msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
            self.camera_pub.publish(msg)

    def _publish_poses(self, epochs, positions, covariances):
        """The footage's poses (carrier RTN [m], noise included) and their covariances [m^2] at ``epochs`` [s]; the
        orientation is not measured (identity, its variances -1 as sensor_msgs/Imu marks one)."""
        for t, p, c in zip(epochs, positions, covariances):
            msg = PoseWithCovarianceStamped()
            msg.header.stamp = sec_to_time(t)
            msg.header.frame_id = interfaces.CARRIER_RTN_FRAME
            msg.pose.pose.position.x, msg.pose.pose.position.y, msg.pose.pose.position.z = (float(x) for x in p)
            msg.pose.pose.orientation.w = 1.0
            cov = [0.0] * 36
            for i in range(3):
                for j in range(3):
                    cov[6 * i + j] = float(c[i, j])
                cov[6 * (i + 3) + i + 3] = UNKNOWN
            msg.pose.covariance = cov
            self.pose_pub.publish(msg)

    def status(self, level, message):
        model = self.truth.model
        min_dist = self.truth.closest.min_dist
        publish_status(self, self.diag_pub, level, message, stamp=self.t, values={
            "sim_time_s": f"{self.t:.1f}",
            "burns_executed": self.execution.burns,
            "min_distance_m": f"{min_dist[0]:.3f}",
            "min_distance_time_s": f"{min_dist[1]:.1f}",
            "truth_a_da_dot_m_per_day": f"{model.da_dot * model.a * 86400:.3f}",
            "dispersions_applied": json.dumps(self.world.applied()),
            # the contingency as applied; absent without one, so a nominal run's status is as before
            **({} if self.world.contingency is None else
               {"contingency_applied": json.dumps(self.world.contingency.applied())}),
        })
        if message.startswith(("scenario complete", "scenario aborted")) and self.final_timer is None:
            # the end of the run is repeated every wall second, as diagnostics are, until the node stops: a
            # watcher that joined late (the runner's observer, a launch event handler) still learns it
            self.final_timer = self.create_timer(1.0, lambda: self.status(level, message),
                                                 clock=RclpyClock(clock_type=ClockType.STEADY_TIME))
        if level == WARN:
            self.get_logger().warning(message)
        elif level == ERROR:
            self.get_logger().error(message)


def main(args=None):
    from .spin import run

    return run(SimNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
