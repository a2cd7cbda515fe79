"""The ROS interface of roe_sep in one place: topic and service names, QoS profiles and frame ids, shared by the
nodes, the run report, the bag tools and the tests (docs/ros_interface.md: its topic table is generated from the
nodes by :mod:`roe_sep.docgen`).

Below the nodes in the layering (core <- interfaces, bag <- nodes <- run/report <- cli): offline tools read topic
names from here without importing any node.
"""

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

RECORDED_DEPTH = 5000
"""Depth of the streams a run publishes every step (truth, measurements, status, ``/diagnostics``, ``/clock``, the
lockstep step messages) and of the recorder's readers: a reliable KEEP_LAST writer drops its oldest message once a
reader in another process (the recorder, the ground_bridge: the listeners of the default layout, which the lockstep
clock does not wait for) lags by more than its depth, and the bag would miss it. 5,000 messages is about 500 steps,
3 s of a default run's stepping, where a depth of 100 (10 steps) lost messages to a 0.5 s stall of the listeners."""

LATCHED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST,
    depth=1,
    reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
"""Plans, events and other latched outputs: a late joiner (or a restarted node) receives the last message."""

DIAGNOSTICS = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=RECORDED_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
"""``/diagnostics``: reliable and volatile as diagnostic_updater publishes it, deeper (:data:`RECORDED_DEPTH`: the
run report reads the statuses from the bag)."""

STREAM = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=RECORDED_DEPTH, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.VOLATILE,
)
"""Periodic streams (truth, measurements, safety status): reliable, deep enough for a fast sim clock and a recorder
that lags (:data:`RECORDED_DEPTH`)."""

BULK = QoSProfile(history=HistoryPolicy.KEEP_ALL, reliability=ReliabilityPolicy.RELIABLE,
                  durability=DurabilityPolicy.VOLATILE)
"""Bursts that must all arrive (a TDM file's measurements, published at once): reliable, every sample kept."""

EXECUTED = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=50, reliability=ReliabilityPolicy.RELIABLE,
    durability=DurabilityPolicy.TRANSIENT_LOCAL,
)
"""Executed maneuvers: every burn of the run stays available to late joiners (the report, a replay)."""

CLOCK_SUB = QoSProfile(
    history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.BEST_EFFORT,
    durability=DurabilityPolicy.VOLATILE,
)
"""Subscribing to ``/clock``: best effort matches a reliable or best-effort publisher; a node that processes every
epoch in (last, now] at each tick loses nothing when a tick is dropped."""

CLOCK_TOPIC = "/clock"  # rosgraph_msgs/Clock, published by the sim (rclpy's own sim-time subscriber uses it)
EJECTION_TOPIC = "/separation/ejection"  # EjectionEvent, LATCHED, ejector
DRIFT_STOP_PLAN_TOPIC = "/separation/drift_stop_plan"  # ManeuverPlan, LATCHED, planner
TRUTH_ROE_TOPIC = "/sim/truth/roe"  # RelativeOrbitalElements, STREAM, sim
TRUTH_RTN_TOPIC = "/sim/truth/rtn"  # RelativeState, STREAM, sim
CAMERA_TOPIC = "/sim/camera/bearing"  # geometry_msgs/Vector3Stamped, STREAM, sim: the carrier camera's measured unit
# line of sight to the picosatellite in the carrier RTN frame, stamped with its epoch (noise included, no truth)
POSE_TOPIC = "/sim/camera/pose"  # geometry_msgs/PoseWithCovarianceStamped, STREAM, sim: the ejection footage's 3D pose
# of the picosatellite (relative position in the carrier RTN frame [m] and its covariance; orientation unused)
EJECTION_ESTIMATE_TOPIC = "/separation/ejection_estimate"  # geometry_msgs/TwistWithCovarianceStamped, LATCHED,
# planner: the executed ejection dv [m/s] RTN estimated from the footage, its covariance, stamped at the release
EXECUTED_TOPIC = "/sim/executed_maneuvers"  # ImpulsiveManeuver, EXECUTED, sim (as executed, with errors)
RADAR_TOPIC = "/radar/measurements"  # RadarMeasurement, STREAM, radar -> radar_od
CARRIER_RADAR_TOPIC = "/radar/carrier_ranges"  # RadarMeasurement, STREAM, radar (track_carrier) -> radar_od
RADAR_PASS_TOPIC = "/radar/passes"  # RadarPass, STREAM, radar -> radar_od: a pass ended (after its measurements)
EXTERNAL_RADAR_TOPIC = "/ground/radar_measurements"  # RadarMeasurement, BULK, ground_bridge (TDM in) -> radar_od
OD_TOPIC = "/od/estimate"  # OrbitDetermination, LATCHED, radar_od
ACQUISITION_PLAN_TOPIC = "/acquisition/plan"  # ManeuverPlan, LATCHED, ic_planner
# std_msgs/String (a JSON decision record), LATCHED: each planner's decisions, kept again by ground_bridge (restarts)
PLANNER_DECISIONS_TOPIC = "/separation/decisions/planner"
IC_PLANNER_DECISIONS_TOPIC = "/separation/decisions/ic_planner"
DECISIONS_TOPICS = (PLANNER_DECISIONS_TOPIC, IC_PLANNER_DECISIONS_TOPIC)
SAFETY_TOPIC = "/safety/status"  # SafetyStatus, STREAM, safety_monitor (truth and estimate)
PLAN_CHECK_TOPIC = "/safety/plan_check"  # SafetyStatus, EXECUTED (keeps the last 50 checks), safety_monitor
DIAGNOSTICS_TOPIC = "/diagnostics"
LOCKSTEP_STEP_TOPIC = "/lockstep/step"  # LockstepStep, sim: the lockstep clock (docs/run.md)
LOCKSTEP_ACK_TOPIC = "/lockstep/ack"  # LockstepAck, every participant
PLAN_SERVICE = "/separation/plan"  # roe_sep_msgs/srv/PlanSeparation, planner

CARRIER_RTN_FRAME = "carrier_rtn"
"""Radial-tangential-normal frame of the carrier (chief): relative states, ROE estimates, plans and events."""
TRUTH_FRAME = "truth"
"""Frame id of the simulator's true ROE (``/sim/truth/roe``): the same RTN frame, marked as truth, not an estimate."""
