"""``ground_bridge``: the run's CCSDS navigation data messages for a ground segment, as the run goes, and TDM files
from a ground segment as radar measurements.

Out (``output_dir``, the runner sets OUT/ccsds; '' = ``ccsds_YYYY_MM_DD-HH_MM_SS`` in the working directory): the
same set as ``roe-sep export`` (:mod:`roe_sep.ndm.dataset`), from the same topics. An OPM pair (RTN and EME2000
maneuvers) as soon as the safety monitor approves a plan, the executed-burns OPM after each burn, and the OEM, TDM
and CDM every ``write_period`` s of sim time (0: never), at most every ``min_write_interval`` s of wall time (the
XML OEM of a whole run takes about 0.4 s to serialize, so not at every message; under the as-fast-as-possible
lockstep clock a simulated day passes in seconds, and the periodic updates were about 1.4 of a default run's 12
CPU-s). The complete set is written as soon as the simulator reports the scenario's end (its final status on
``/diagnostics``, :mod:`.scenario_end`), while the processes of the run stop, and at shutdown once more only if a
message of the set arrived after it (:class:`~roe_sep.ndm.live.LiveSet`); that final set starts as soon as the
executor stops (``executor_stopped``, while the process's recorder closes its bag) and ``destroy_node`` waits for
it. Every file is written atomically (temporary file + rename).

In (``input_dir``, '' = off): every ``*.xml``, ``*.kvn`` or ``*.tdm`` file that appears there is read as a TDM
(:func:`roe_sep.ndm.messages.read_tdm`, sim time from ``epoch_utc``) and its measurements are published on
``/ground/radar_measurements`` (RadarMeasurement, the ``/radar/measurements`` layout; ``radar_od`` takes them in
alongside its own); the file then moves to ``input_dir/processed/``. A file that is not a valid TDM moves to
``input_dir/rejected/`` with ``<name>.reason`` beside it (the reason, one line) and an ERROR on ``/diagnostics``
naming the file and the reason: whatever reading it raises, the node (and the recorder of its process) keeps running.

Decisions kept (docs/run.md, "Decisions"): the last decision record of each planner (``/separation/decisions/planner``
and ``/separation/decisions/ic_planner``, std_msgs/String, latched) latched again from this node's own writer of the
topic: a latched sample lives only as long as its writer, so a planner killed and
restarted reads back what it decided from here (:mod:`.decision_record`).

Parameters: :data:`roe_sep.nodes.parameters.GROUND_BRIDGE` (``ground_bridge --help``, docs/parameters.md).
"""

import math
import shutil
import time
from datetime import datetime
from pathlib import Path

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.clock import Clock as RclpyClock
from rclpy.clock import ClockType
from rclpy.node import Node
from roe_sep_msgs.msg import (
    EjectionEvent,
    ImpulsiveManeuver,
    ManeuverPlan,
    OrbitDetermination,
    RadarMeasurement,
    RelativeOrbitalElements,
    SafetyStatus,
)
from rosgraph_msgs.msg import Clock
from std_msgs.msg import String

from .. import interfaces
from ..core.decisions.common import read_record
from ..errors import RoeSepError
from ..ndm import frames
from ..ndm.live import LiveSet
from ..ndm.options import Options
from .convert import sec_to_time, time_to_sec
from .diagnostics import ERROR, OK, publish_status
from .params import ParameterError, declare, scenario_of
from .scenario_end import final_status_of

EXTERNAL_RADAR_TOPIC = interfaces.EXTERNAL_RADAR_TOPIC
INPUT_SUFFIXES = (".xml", ".kvn", ".tdm", ".txt")


def periodic_due(sim_since, write_period, wall_since, min_write_interval):
    """Whether the OEM/TDM/CDM update is due: ``write_period`` s of sim time (> 0) and ``min_write_interval`` s of
    wall time since the last one (``*_since``)."""
    return write_period > 0 and sim_since >= write_period and wall_since >= min_write_interval


class GroundBridgeNode(Node):
    def __init__(self):
        super().__init__("ground_bridge")
        self.messages_received = 0  # the shutdown drain runs while it rises (roe_sep.nodes.spin)
        out = declare(self, "output_dir") or datetime.now().strftime("ccsds_%Y_%m_%d-%H_%M_%S")
        self.fmt = declare(self, "format")
        epoch = declare(self, "epoch_utc")
        scenario_file = declare(self, "scenario_file")
        isp = declare(self, "carrier_isp")
        self.write_period = declare(self, "write_period")
        self.min_write_interval = declare(self, "min_write_interval")
        inp = declare(self, "input_dir")
        poll = declare(self, "poll_period")
        sigma_range = declare(self, "default_sigma_range_m")
        sigma_angle = declare(self, "default_sigma_angle_deg")

        self.opts = self._check(out, epoch, scenario_file, isp, poll, sigma_range=sigma_range, sigma_angle=sigma_angle)
        self.out = Path(out)
        self.out.mkdir(parents=True, exist_ok=True)
        self.sigma = (float(sigma_range), math.radians(sigma_angle))
        self.t = 0.0
        self.live = LiveSet(self.out, self.fmt, self.opts, lambda: self.t, self._not_written)
        self.dirty = False  # something the periodic files depend on arrived
        self.last_periodic = 0.0  # sim time of the last periodic update
        self.last_periodic_wall = time.monotonic()  # and its wall time (the node's start before the first)
        self.files_in = 0
        self.files_rejected = 0
        self.unmovable = set()  # rejected files that could not be moved aside
        self.input = Path(inp) if inp else None
        self._interface(float(poll))
        self._status(OK, f"writing {self.fmt} files to {self.out}" +
                     (f", watching {self.input} for TDM files" if self.input else ""))

    def keep(self, topic, msg: String):
        """A planner's decision record: kept, and latched again from this node's writer (its own copy coming back
        changes nothing)."""
        if msg.data in (self.kept[topic], ""):
            return
        try:
            read_record(msg.data, topic.rsplit("/", 1)[-1])
        except ValueError as exc:  # never kept: a restarted planner would read it back
            self._status(ERROR, f"decision record on {topic} rejected: {exc}")
            return
        self.kept[topic] = msg.data
        self.keepers[topic].publish(msg)

    def _check(self, out, epoch, scenario_file, isp, poll, *, sigma_range, sigma_angle):
        """Check the parameters (ParameterError naming the first bad one); the set's options."""
        try:
            frames.parse_epoch(epoch)
        except ValueError as exc:
            raise ParameterError(f"parameter 'epoch_utc': {exc}") from exc
        carrier = scenario_of(scenario_file).monte_carlo.carrier
        return Options(epoch_utc=str(epoch), carrier_mass=carrier.mass, carrier_drag_area=carrier.area,
                       carrier_drag_coeff=carrier.cd, carrier_isp=float(isp))

    def _interface(self, poll):
        """Publishers, subscriptions and the input directory's poll timer."""
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.ext_pub = self.create_publisher(RadarMeasurement, EXTERNAL_RADAR_TOPIC, interfaces.BULK)
        # the streams every sample of which goes into a file (OEM, TDM) with a keep-all reader: a 100-deep one
        # drops about half of a 223-sample burst arriving faster than the executor takes it
        subs = ((RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, interfaces.BULK, False),
                (EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED, False),
                (ManeuverPlan, interfaces.DRIFT_STOP_PLAN_TOPIC, interfaces.LATCHED, False),
                (ManeuverPlan, interfaces.ACQUISITION_PLAN_TOPIC, interfaces.LATCHED, False),
                (SafetyStatus, interfaces.PLAN_CHECK_TOPIC, interfaces.EXECUTED, True),
                (ImpulsiveManeuver, interfaces.EXECUTED_TOPIC, interfaces.EXECUTED, True),
                (OrbitDetermination, interfaces.OD_TOPIC, interfaces.LATCHED, False),
                (RadarMeasurement, interfaces.RADAR_TOPIC, interfaces.BULK, False))
        for cls, topic, qos, urgent in subs:
            self.create_subscription(cls, topic, lambda m, t=topic, u=urgent: self.on_message(t, m, u), qos)
        self.create_subscription(Clock, interfaces.CLOCK_TOPIC, self.on_clock, interfaces.CLOCK_SUB)
        self.kept, self.keepers = {}, {}  # decisions topic -> the last record, this node's writer of it
        for topic in interfaces.DECISIONS_TOPICS:
            self.keepers[topic] = self.create_publisher(String, topic, interfaces.LATCHED)
            self.kept[topic] = ""
            self.keepers[topic].publish(String(data=""))  # nothing kept yet: a starting planner need not wait
            self.create_subscription(String, topic, lambda m, t=topic: self.keep(t, m), interfaces.LATCHED)
        # the scenario's end, from the bytes (a run's ~950 statuses, of which only the final ones are decoded)
        self.create_subscription(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, self.on_diagnostics,
                                 interfaces.DIAGNOSTICS, raw=True)
        if self.input is not None:
            for sub in ("", "processed", "rejected"):
                (self.input / sub).mkdir(parents=True, exist_ok=True)
            # wall clock: the directory is polled also while the sim clock holds or has stopped
            self.create_timer(poll, self.scan_input, clock=RclpyClock(clock_type=ClockType.STEADY_TIME))

    def _values(self):
        return {"output_dir": str(self.out), "files_written": len(self.live.written), "tdm_files_in": self.files_in,
                "tdm_files_rejected": self.files_rejected, "sim_time_s": f"{self.t:.1f}"}

    def _status(self, level, message):
        publish_status(self, self.diag_pub, level, message, self._values())

    # --- out ------------------------------------------------------------------------------------------------------
    def on_message(self, topic, msg, urgent):
        self.messages_received += 1
        self.live.add(topic, msg)
        self.dirty = True
        if urgent:  # plan approved or burn executed: the OPMs change now
            self.live.request(periodic=False)

    def on_clock(self, msg: Clock):
        self.t = time_to_sec(msg.clock)
        wall = time.monotonic()
        if self.dirty and periodic_due(self.t - self.last_periodic, self.write_period,
                                       wall - self.last_periodic_wall, self.min_write_interval):
            self.last_periodic = self.t
            self.last_periodic_wall = wall
            self.dirty = False
            self.live.request(periodic=True)

    def on_diagnostics(self, data: bytes):
        """The simulator's final status (repeated every wall second until it stops): no state comes any more, so the
        complete set of what arrived since the last one is written now, not after the run's processes have stopped
        (a message of the set that still arrives later is in the final set at shutdown)."""
        if self.dirty and final_status_of(data) is not None:
            self.dirty = False
            self.live.request(periodic=True)

    def _not_written(self, exc):
        """A write of the writer thread failed."""
        self.get_logger().error(f"CCSDS set not written: {exc.__class__.__name__}: {exc}")
        if rclpy.ok():
            self._status(ERROR, f"CCSDS set not written: {exc}")

    def executor_stopped(self):
        """No callback runs any more (:func:`roe_sep.nodes.spin.serve`): the messages are complete, the final set
        starts in the writer thread while the process's other nodes shut down (the recorder closes its bag)."""
        self.live.finish()

    def destroy_node(self):
        """The final, complete set (:meth:`~roe_sep.ndm.live.LiveSet.close`)."""
        self.live.close()
        if self.live.run[interfaces.TRUTH_ROE_TOPIC]:
            text = f"final CCSDS set: {len(self.live.written)} files in {self.out}"
            if rclpy.ok():
                self.get_logger().info(text)
            else:  # after SIGINT the context is gone and /rosout with it
                print(f"[INFO] [ground_bridge]: {text}", flush=True)
        super().destroy_node()

    # --- in -------------------------------------------------------------------------------------------------------
    def scan_input(self):
        """Every new file of ``input_dir``, each on its own: whatever reading or publishing it raises (a library's
        AttributeError as much as an NdmError) rejects that file (:meth:`_reject`), never the node."""
        for path in sorted(self.input.iterdir()):
            if (not path.is_file() or path.name.startswith(".") or path.suffix.lower() not in INPUT_SUFFIXES
                    or path in self.unmovable):
                continue
            try:
                n = self._publish_tdm(path)
            except Exception as exc:  # noqa: BLE001  (a bad file never stops the node, nor its process's recorder)
                self._reject(path, exc)
                continue
            self.files_in += 1
            target = self._move(path, "processed")
            self._status(OK, f"TDM {path.name}: {n} measurements published on {EXTERNAL_RADAR_TOPIC}")
            self.get_logger().info(f"TDM {path.name}: {n} measurements published, moved to {target}")

    def _publish_tdm(self, path):
        """The measurements of the TDM ``path`` on ``/ground/radar_measurements``; how many."""
        from ..ndm.messages import read_tdm

        meas = read_tdm(path, self.opts.epoch_utc, *self.sigma)
        msgs = []
        for m in meas:  # every message built before the first is sent: a bad value sends none
            msg = RadarMeasurement(station=m.station, pass_id=int(m.pass_id), range=float(m.z[0]),
                                   azimuth=float(m.z[1]), elevation=float(m.z[2]),
                                   sigma_range=float(m.sigma_range), sigma_angle=float(m.sigma_angle))
            msg.header.stamp = sec_to_time(m.t)
            msg.header.frame_id = m.station
            msgs.append(msg)
        for msg in msgs:
            self.ext_pub.publish(msg)
        return len(msgs)

    def _reject(self, path, exc):
        """``path`` to ``input_dir/rejected/`` with ``<name>.reason`` beside it (the reason, one line), an ERROR on
        ``/diagnostics`` naming both; a file that cannot be moved is left where it is and skipped from then on."""
        self.files_rejected += 1
        said = str(exc) if isinstance(exc, RoeSepError) else f"{exc.__class__.__name__}: {exc}"
        reason = " ".join(said.split())
        try:
            target = self._move(path, "rejected")
            target.with_name(target.name + ".reason").write_text(reason + "\n")
            where = f"moved to {target}"
        except OSError as err:
            self.unmovable.add(path)
            where = f"left in place ({err.__class__.__name__}: {err})"
        text = f"TDM {path.name} rejected ({reason}); {where}"
        self.get_logger().error(text)
        self._status(ERROR, text)

    def _move(self, path, sub):
        target = self.input / sub / path.name
        if target.exists():
            target = target.with_name(f"{path.stem}.{time.time_ns()}{path.suffix}")
        shutil.move(str(path), str(target))
        return target


def main(args=None):
    from .spin import run

    return run(GroundBridgeNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
