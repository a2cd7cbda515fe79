"""QoS profiles and topic names shared by every roe_sep node (documented in the README's topic table)."""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
"""Plans, events and other latched outputs: a late joiner (or a restarted node) receives the last message."""

DIAGNOSTICS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
"""``/diagnostics``, as diagnostic_updater publishes it."""

EJECTION_TOPIC = "/separation/ejection"
DRIFT_STOP_PLAN_TOPIC = "/separation/drift_stop_plan"
DIAGNOSTICS_TOPIC = "/diagnostics"
