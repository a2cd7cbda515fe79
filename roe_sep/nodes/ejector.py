"""ejector: the spring (SPL) ejection event.

Commands the ejection of the scenario's design (:func:`roe_sep.core.separation.double_impulse.design`: fixed |dv|,
direction
from the aimed e/i vectors, seed 002 Eqs. 9-12) at the configured epoch, or at the first time the carrier's mean
argument of latitude reaches u1 after ``not_before``, read from the carrier state in the truth stream (on board the
carrier knows its own orbit from GPS). Publishes ``/separation/ejection`` (roe_sep_msgs/EjectionEvent, latched)
a little ahead of the epoch; the simulator applies it at the epoch with the mechanism's real dispersion.

Parameters: :data:`roe_sep.nodes.parameters.EJECTOR` (``ejector --help``, docs/parameters.md).
"""

import math

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from roe_sep_msgs.msg import EjectionEvent, RelativeOrbitalElements

from .. import interfaces
from ..core.config import ConfigError, load_scenario
from ..core.relmotion.dynamics import propagate_chief
from ..core.separation.double_impulse import InfeasibleDesignError, design
from ..core.truth.secular import time_to_arg_latitude
from .convert import array_to_elements, elements_to_array, maneuver_msg, sec_to_time, time_to_sec
from .diagnostics import ERROR, OK, publish_status
from .lockstep import Lockstep
from .params import ParameterError, declare


class EjectorNode(Node):
    def __init__(self):
        super().__init__("ejector")
        scenario_file = declare(self, "scenario_file")
        self.epoch = declare(self, "ejection_epoch")
        self.not_before = declare(self, "not_before")
        self.lead = declare(self, "lead_time")
        strategy = declare(self, "strategy")
        try:
            scenario = load_scenario(scenario_file or None)
            if strategy == "multi_impulse":
                from ..core.separation import multi_impulse

                self.design = multi_impulse.design(scenario.separation, mc=scenario.monte_carlo)
            else:
                self.design = design(scenario.separation)
        except (ConfigError, InfeasibleDesignError) as exc:
            raise ParameterError(f"parameter 'scenario_file': {exc}") from exc
        self.sent = False
        self.lockstep = ls = Lockstep(self)
        self.pub = ls.publisher(EjectionEvent, interfaces.EJECTION_TOPIC, interfaces.LATCHED)
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        ls.subscribe(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_state, interfaces.STREAM,
                     what="carrier state")
        # a restarted ejector finds its own latched event and does not eject twice
        ls.subscribe(EjectionEvent, interfaces.EJECTION_TOPIC, self.on_existing_event, interfaces.LATCHED,
                     what="ejection event")
        publish_status(self, self.diag_pub, OK, "waiting for the ejection epoch")

    def on_existing_event(self, _event: EjectionEvent):
        self.sent = True

    def on_state(self, msg: RelativeOrbitalElements):
        t = time_to_sec(msg.header.stamp)
        kep = elements_to_array(msg.chief)
        if not (math.isfinite(t) and all(math.isfinite(x) for x in kep) and kep[0] > 0):
            publish_status(self, self.diag_pub, ERROR, "carrier state rejected: not finite")
            return
        if self.sent:
            if self.lockstep.active:  # nothing left to command: no step waits for this node's truth any more
                self.lockstep.unsubscribe(interfaces.TRUTH_ROE_TOPIC)
            return
        if self.epoch >= 0:
            t_ej = self.epoch
        else:
            t_from = max(t, self.not_before)
            at_from = propagate_chief(kep, t_from - t)
            t_ej = t_from + time_to_arg_latitude(at_from[4] + at_from[5], self.design.u1, kep[0], kep[2])
        if t_ej - t > self.lead:
            return
        if t_ej < t:
            publish_status(self, self.diag_pub, ERROR, f"ejection epoch {t_ej:.1f} s already passed at t = {t:.1f} s: "
                           "not ejecting late (check lead_time against the truth sample spacing)")
            self.sent = True
            return
        self.publish_event(t_ej, kep, t)

    def publish_event(self, t_ej, kep, t_state):
        chief = array_to_elements(propagate_chief(kep, t_ej - t_state))
        d = self.design
        ev = EjectionEvent(dv_magnitude=float(d.config.spl_dv), chief=chief)
        ev.header.stamp = sec_to_time(t_ej)
        ev.header.frame_id = interfaces.CARRIER_RTN_FRAME
        ev.ejection = maneuver_msg(t_ej, chief.mean_arg_latitude, d.dv1_rtn, "picosatellite", "ejection")
        self.pub.publish(ev)
        self.sent = True
        u_deg = math.degrees(chief.mean_arg_latitude)
        self.get_logger().info(f"ejection commanded at t = {t_ej:.1f} s, u = {u_deg:.2f} deg, "
                               f"dv RTN = {d.dv1_rtn.round(6).tolist()} m/s")
        publish_status(self, self.diag_pub, OK, "ejection commanded", {"epoch_s": f"{t_ej:.3f}"})


def main(args=None):
    from .spin import run

    return run(EjectorNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
