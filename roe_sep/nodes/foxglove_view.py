"""``foxglove_view``: a live view of a run (or a replay) in Foxglove, over the Foxglove WebSocket protocol.

Every topic with a publisher (found every 0.5 s, as the recorder finds them) is forwarded as it arrives: the
serialized CDR bytes on a channel of the same name with the ``ros2msg`` schema of its type (the bag's schema text,
:mod:`roe_sep.bag.definitions`), so Foxglove decodes and plots every field. ``/foxglove/scene`` adds a 3-D scene in
the carrier's RTN frame (``carrier_rtn``, x = R, y = T, z = N, meters) from ``/sim/truth/roe``: the relative
trajectory so far, the keep-out sphere and the e/i ellipse (the closed relative orbit of the current ROE over one
revolution without the along-track drift, seed 002 Eq. 2's linear map). Log times are the node clock (sim time
with ``use_sim_time``). The last message of each latched topic (plans, the ejection) is sent again to a client
that subscribes later. The server listens on 127.0.0.1 only (``port``, 0 = any free port; the port taken is
logged and reported on ``/diagnostics``). The layout ``config/foxglove_layout.json`` shows ROE over time,
distance, safety state and the plan timeline.

Parameters: :data:`roe_sep.nodes.parameters.FOXGLOVE_VIEW` (``foxglove_view --help``, docs/parameters.md);
``keep_out_radius`` can be changed while it runs.
"""

import math
import threading

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from roe_sep_msgs.msg import RelativeOrbitalElements

from .. import interfaces
from ..bag import definitions
from ..bag import qos as bag_qos
from ..core.relmotion.roe import roe_to_rtn
from .convert import msg_to_roe, time_to_sec
from .diagnostics import ERROR, OK, publish_status
from .params import declare

SCENE_TOPIC = "/foxglove/scene"
HOST = "127.0.0.1"
TRAJECTORY_POINTS = 2000
ELLIPSE_POINTS = 73


def ellipse_points(roe, a):
    """RTN positions [m] of the e/i ellipse: a * roe_to_rtn(roe, u) over one revolution with da = 0 and dl held
    (the closed relative orbit the ROE describe without drift), ``(ELLIPSE_POINTS, 3)``."""
    r = np.array(roe, dtype=float)
    r[0] = 0.0
    u = np.linspace(0.0, 2.0 * math.pi, ELLIPSE_POINTS)
    return roe_to_rtn(np.broadcast_to(r, (u.size, 6)), u)[0] * a


class FoxgloveViewNode(Node):
    def __init__(self):
        super().__init__("foxglove_view")
        import foxglove  # lazily: only this node needs the SDK

        self.fg = foxglove
        port = declare(self, "port")
        self.keep_out = declare(self, "keep_out_radius", attr="keep_out")
        self.diag_pub = self.create_publisher(DiagnosticArray, interfaces.DIAGNOSTICS_TOPIC, interfaces.DIAGNOSTICS)
        self.latched, self.resend, self.lock = {}, set(), threading.Lock()
        view = self

        class Listener(foxglove.ServerListener):
            def on_subscribe(self, client, channel):  # server thread: the node's timer sends
                with view.lock:
                    view.resend.add(channel.topic)

        try:
            self.server = foxglove.start_server(name="roe_sep", host=HOST, port=port, server_listener=Listener())
        except Exception as exc:  # noqa: BLE001  (port in use, ...)
            from .params import ParameterError

            raise ParameterError(f"parameter 'port': cannot serve on {HOST}:{port}: {exc}") from exc
        self.port = self.server.port
        self.channels, self.subs, self.skipped = {}, {}, set()
        from foxglove.channels import SceneUpdateChannel

        self.scene = SceneUpdateChannel(SCENE_TOPIC)
        self.trail = []
        self.create_subscription(RelativeOrbitalElements, interfaces.TRUTH_ROE_TOPIC, self.on_truth,
                                 interfaces.STREAM)
        self.create_timer(0.5, self.discover)
        self.create_timer(0.2, self.resend_latched)
        self.get_logger().info(f"Foxglove WebSocket server on ws://{HOST}:{self.port}")
        publish_status(self, self.diag_pub, OK, f"Foxglove WebSocket server on ws://{HOST}:{self.port}",
                       {"port": self.port})
        self.discover()

    # --- every topic, as serialized ------------------------------------------------------------------------------
    def discover(self):
        try:
            for name, types in self.get_topic_names_and_types():
                if name in self.subs or name in self.skipped or name.startswith("/foxglove"):
                    continue
                publishers = self.get_publishers_info_by_topic(name)
                if publishers:
                    self.forward(name, types[0], publishers)
        except Exception as exc:  # noqa: BLE001  (graph queries fail during shutdown)
            self.get_logger().warning(f"topic discovery failed: {exc}")

    def forward(self, name, type_name, publishers):
        try:
            cls = definitions.message_class(type_name)
            text = definitions.full_text(type_name)
        except Exception as exc:  # noqa: BLE001  (a type not installed here: skip it, say so)
            self.skipped.add(name)
            publish_status(self, self.diag_pub, ERROR, f"not forwarding {name}: {exc}", {"port": self.port})
            return
        reliable, transient = bag_qos.request_for_offers([bag_qos.from_rclpy(p.qos_profile) for p in publishers])
        profile = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100,
                             reliability=ReliabilityPolicy.RELIABLE if reliable else ReliabilityPolicy.BEST_EFFORT,
                             durability=DurabilityPolicy.TRANSIENT_LOCAL if transient else DurabilityPolicy.VOLATILE)
        schema = self.fg.Schema(name=definitions.canonical_type(type_name), encoding="ros2msg",
                                data=text.encode("utf-8"))
        self.channels[name] = self.fg.Channel(name, schema=schema, message_encoding="cdr")
        self.subs[name] = self.create_subscription(
            cls, name, lambda data, t=name, keep=transient: self.on_raw(t, data, keep), profile, raw=True)

    def on_raw(self, topic, data, latched=False):
        data = bytes(data)
        if latched:  # plans, events: a client that subscribes later gets the last one too
            self.latched[topic] = data
        self.channels[topic].log(data, log_time=self._now())

    def resend_latched(self):
        """The last message of each latched topic again, for the clients that just subscribed to it (the others
        see it twice, as a re-published latched message)."""
        with self.lock:
            topics, self.resend = self.resend, set()
        for topic in topics:
            if topic in self.latched:
                self.channels[topic].log(self.latched[topic], log_time=self._now())

    def _now(self):
        return self.get_clock().now().nanoseconds

    # --- the 3-D scene -------------------------------------------------------------------------------------------
    def on_truth(self, msg: RelativeOrbitalElements):
        m = self.fg.messages
        a = msg.chief.semi_major_axis
        roe = msg_to_roe(msg)
        if not (np.all(np.isfinite(roe)) and a > 0):
            return
        pos = roe_to_rtn(roe, msg.chief.mean_arg_latitude)[0] * a
        self.trail.append(pos)
        del self.trail[:-TRAJECTORY_POINTS]
        t = time_to_sec(msg.header.stamp)
        stamp = m.Timestamp(int(math.floor(t)), int(round((t - math.floor(t)) * 1e9)) % 1_000_000_000)

        def line(points, color, width, entity):
            return m.SceneEntity(
                timestamp=stamp, frame_id=interfaces.CARRIER_RTN_FRAME, id=entity,
                lines=[m.LinePrimitive(type=m.LinePrimitiveLineType.LineStrip, thickness=width,
                                       scale_invariant=True, color=color,
                                       points=[m.Point3(x=float(p[0]), y=float(p[1]), z=float(p[2]))
                                               for p in points])])

        d = 2.0 * self.keep_out
        entities = [
            line(self.trail, m.Color(r=0.2, g=0.6, b=1.0, a=1.0), 2.0, "trajectory"),
            line(ellipse_points(roe, a), m.Color(r=1.0, g=0.6, b=0.1, a=1.0), 2.0, "ei_ellipse"),
            m.SceneEntity(timestamp=stamp, frame_id=interfaces.CARRIER_RTN_FRAME, id="keep_out",
                          spheres=[m.SpherePrimitive(pose=m.Pose(position=m.Vector3(x=0.0, y=0.0, z=0.0),
                                                                 orientation=m.Quaternion(x=0.0, y=0.0, z=0.0,
                                                                                          w=1.0)),
                                                     size=m.Vector3(x=d, y=d, z=d),
                                                     color=m.Color(r=1.0, g=0.1, b=0.1, a=0.3))]),
        ]
        self.scene.log(m.SceneUpdate(entities=entities), log_time=self._now())

    def destroy_node(self):
        try:
            self.server.stop()
        finally:
            super().destroy_node()


def main(args=None):
    from .spin import run

    return run(FoxgloveViewNode, args)


if __name__ == "__main__":
    from ..process_exit import exit_process

    exit_process(main())
