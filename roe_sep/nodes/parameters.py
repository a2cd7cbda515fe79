"""Every node parameter in one place: one table of :class:`Param` records per executable (:data:`TABLES`).

From the tables come the ``ParameterDescriptor`` of every declared parameter (type, description with the unit and
the rule, ``floating_point_range``/``integer_range``, ``read_only``: :func:`roe_sep.nodes.params.declare`), every
check a node makes of a parameter at start-up (:func:`problem`: the range, the choices, a non-empty list, the form of
a string), the check of ``roe-sep run --params`` / ``roe-sep campaign --params`` before anything starts
(:func:`check_overrides`), each executable's ``--help`` (:func:`usage`) and ``docs/parameters.md``
(``python -m roe_sep.nodes.parameters --markdown > docs/parameters.md``; a test fails when the file is stale).

Ranges are inclusive (``FloatingPointRange`` and ``IntegerRange`` are), so "positive" is written as the smallest
value that still makes sense. A parameter is ``read_only`` when a change after the node started (or configured, for
a managed node) would have no effect: ``ros2 param set`` then refuses it instead of accepting a value nobody reads.
The few that a node reads at every use are writable, within their range and rule (rclpy refuses the rest).

This module is pure Python (no rclpy): the command line checks parameter files with it without starting ROS.
"""

import dataclasses
import math
import sys
from collections.abc import Callable

from ..checks import SEED_MAX
from ..core.acquisition.planner import AcquisitionConfig, parse_axes
from ..core.deployment.sweep import MODELS, USSA76_DENSITY_400KM
from ..core.od.pose import FOOTAGE_WINDOW, FRAME_PERIOD, POSE_CENTROID_PX, POSE_PIXELS, POSE_SIGMA0
from ..core.od.radar import DEFAULT_EPOCH_UTC, julian_date
from ..core.safety.anomaly import AnomalyLimits
from ..core.safety.ejection_check import CAMERA_SIGMA_DEG
from ..core.safety.monitor import MonitorLimits
from ..core.truth.contingency import NAMES as CONTINGENCIES
from ..core.truth.contingency import NONE as NO_CONTINGENCY
from ..errors import show
from ..graph import MANAGED
from ..ndm.options import FORMATS

TYPES = ("bool", "int", "double", "string", "string[]", "double[]")
P_MODES = ("monte_carlo", "three_sigma", "fixed")
STRATEGIES = ("double_impulse", "multi_impulse")
DYNAMICS = ("secular", "nonlinear")
DEFAULT_DURATION = 280800.0  # s: 3.25 days, through OD and the initial-condition acquisition and half a day on
MC_SAMPLES_MAX = 2_000_000
ROS_PARAMETERS = ("use_sim_time", "start_type_description_service")  # declared by rclpy in every node


@dataclasses.dataclass(frozen=True)
class Param:
    """One node parameter. ``range`` (lo, hi) or, for an integer, (lo, hi, step) is inclusive; ``choices`` the
    allowed strings; ``rule`` the rule in words where the range and choices do not say it all (with ``check``, a
    predicate on the value); ``nonempty`` for a list that must have an element."""

    name: str
    type: str
    default: object
    description: str
    unit: str = ""
    range: tuple | None = None
    choices: tuple = ()
    rule: str = ""
    check: Callable | None = None
    nonempty: bool = False
    read_only: bool = True


def _number(x):
    return str(x) if isinstance(x, int) else f"{x:g}".replace("e+0", "e").replace("e+", "e").replace("e-0", "e-")


def rule_text(p: Param) -> str:
    """The rule of a parameter in words: ``an odd integer in [1, 99]``, ``a number in [0, 1] m/s``, ..."""
    if p.rule:
        return p.rule
    unit = f" {p.unit}" if p.unit else ""
    if p.type == "bool":
        return "true or false"
    if p.choices:
        return "one of " + ", ".join(f"'{c}'" for c in p.choices)
    if p.type == "int" and p.range:
        lo, hi, *step = p.range
        kind = {(2, 1): "an odd integer", (2, 0): "an even integer"}.get((step[0], lo % 2), "an integer") \
            if step else "an integer"
        return f"{kind} in [{lo}, {hi}]{unit}"
    if p.type == "double" and p.range:
        return f"a number in [{_number(p.range[0])}, {_number(p.range[1])}]{unit}"
    if p.type == "double[]":
        each = f", each in [{_number(p.range[0])}, {_number(p.range[1])}]{unit}" if p.range else ""
        return ("a non-empty list of numbers" if p.nonempty else "a list of numbers") + each
    if p.type == "string[]":
        return "a non-empty list of strings" if p.nonempty else "a list of strings"
    return "a non-empty string" if p.nonempty else "a string"


def _type_ok(p: Param, value) -> bool:
    scalar = {"bool": lambda v: isinstance(v, bool),
              "int": lambda v: isinstance(v, int) and not isinstance(v, bool),
              "double": lambda v: isinstance(v, float),
              "string": lambda v: isinstance(v, str)}
    if p.type in scalar:
        return scalar[p.type](value)
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        return False
    item = scalar["string" if p.type == "string[]" else "double"]
    return all(item(v) for v in value)


def type_text(p: Param) -> str:
    """The rule of a parameter with how its type is written (a value of another type is refused)."""
    hint = {"double": ", written with a decimal point (600.0, not 600)",
            "double[]": ", written with decimal points ([300.0], not [300])"}.get(p.type, "")
    return rule_text(p) + hint


def problem(p: Param, value):
    """What is wrong with ``value`` for ``p`` (``must be ...``), None if nothing."""
    if not _type_ok(p, value):
        return f"must be {type_text(p)}"
    bad = False
    if p.type in ("int", "double") and p.range:
        bad = not (isinstance(value, int) or math.isfinite(value)) or not p.range[0] <= value <= p.range[1]
        if not bad and p.type == "int" and len(p.range) == 3:
            bad = (value - p.range[0]) % p.range[2] != 0
    elif p.type == "double[]":
        values = list(value)
        bad = (p.nonempty and not values) or not all(math.isfinite(v) for v in values) or \
            (p.range is not None and not all(p.range[0] <= v <= p.range[1] for v in values))
    elif p.choices:
        bad = value not in p.choices
    elif p.nonempty:
        bad = not value
    if not bad and p.check is not None:
        bad = not p.check(value)
    return f"must be {rule_text(p)}" if bad else None


# ------------------------------------------------------------------------------------------------ rules as predicates
def _iso_epoch(value) -> bool:
    try:
        julian_date(value)
    except (ValueError, TypeError, OverflowError):
        return False
    return True


def _axes(value) -> bool:
    try:
        parse_axes(value)
    except ValueError:
        return False
    return True


def _topic_counts(values) -> bool:
    """'topic=count' items (empty items allowed: a YAML list cannot be empty in a ROS params file)."""
    return all(not v or (v.startswith("/") and v.partition("=")[2].isdigit()) for v in values)


def _node_names(values) -> bool:
    return all(v != "sim" for v in values)


def _topic_names(values) -> bool:
    return all(v.strip() for v in values)


def _distinct_names(values) -> bool:
    return all(values) and len(set(values)) == len(values)


# ------------------------------------------------------------------------------------------------ the tables
SCENARIO_FILE = Param("scenario_file", "string", "", "scenario YAML ('' = the embedded default, config/scenario.yaml)",
                      rule="'' or the path of a scenario YAML (read at start-up)")
AUTOSTART = Param("autostart", "bool", True, "configure and activate in the constructor (false: stay unconfigured "
                  "for a lifecycle manager or `ros2 lifecycle set`)")
J2 = "secular J2 in the {}"
RECOVER_TIMEOUT = Param("recover_timeout", "double", 5.0, "wall seconds a (re)started node waits at most for its "
                        "decision record, kept by ground_bridge, before it plans anything (ground_bridge answers at "
                        "once, with an empty record in a fresh run); a node started without ground_bridge waits it "
                        "in full; 0: no read-back (docs/run.md, Decisions)", "s", range=(0.0, 60.0))


def _contingency(side):
    return Param("contingency", "string", "", f"the run's contingency, injected by the {side} ("
                 "docs/contingencies.md): '' = the scenario's contingency block (none without one), 'none' = none, "
                 "else that contingency with the block's parameters when the block names it, else its defaults "
                 "(roe-sep run/campaign --contingency NAME sets it)", choices=("", NO_CONTINGENCY, *CONTINGENCIES))


_ACQ = AcquisitionConfig()
_LIM = MonitorLimits()
_ANOM = AnomalyLimits()

PLANNER = (
    AUTOSTART,
    RECOVER_TIMEOUT,
    Param("k", "int", 3, "half revolutions from the ejection to the drift-stop (odd: the drift-stop is at the "
          "opposite side of the orbit, seed 002 Eq. 18); 99 is more than 2.5 days", range=(1, 99, 2)),
    Param("p_mode", "string", "monte_carlo", "choice of the tangential reduction |p|: 'monte_carlo' (p_best of the "
          "start-up sweep of the scenario), 'three_sigma' (e1 + e2 of seed 002 Eq. 21 for the commanded ejection), "
          "'fixed' (p_reduction)", choices=P_MODES),
    Param("p_reduction", "double", 0.0, "|p| when p_mode is 'fixed' (beyond 1 m/s a reduction exceeds any "
          "drift-stop burn of the design)", "m/s", range=(0.0, 1.0)),
    SCENARIO_FILE,
    Param("mc_samples", "int", 100000, "samples of the start-up Monte Carlo sweep (p_mode 'monte_carlo'); at most "
          "2,000,000: the sweep holds about 1.3 kB per sample (1.3 GB and 12 s per million samples, measured) and "
          "the simulator's clock waits for it", range=(1, MC_SAMPLES_MAX)),
    Param("mc_seed", "int", 0, "seed of the start-up Monte Carlo sweep", range=(0, SEED_MAX)),
    Param("j2", "bool", True, J2.format("drift-stop epoch and the predicted ROE")),
    Param("strategy", "string", "double_impulse", "'double_impulse' (ejection + drift-stop) or 'multi_impulse' "
          "(seed 001 Sec. 3: every carrier burn of the multi-impulse plan, each <= 0.3 m/s, quantized to 1 mm/s; k "
          "and p_mode do not apply)", choices=STRATEGIES),
    Param("drift_stop_retry", "bool", True, "a drift-stop with no executed carrier burn on the executed-maneuver "
          "record retry_tolerance after its epoch (missed, or late: the safety monitor's burn_missing) is replaced "
          "by the same drift-stop whole orbits later, at its argument of latitude, the first such epoch at least "
          "retry_margin after the finding (seed 002 Table 1 safety #4, Eq. 13); false: no replacement "
          "(docs/contingencies.md)"),
    Param("retry_tolerance", "double", _ANOM.epoch_tolerance, "a drift-stop is missing this long after its epoch "
          "(the safety monitor's burn_epoch_tolerance)", "s", range=(1.0, 86400.0)),
    Param("retry_margin", "double", 11400.0, "the replacement drift-stop is at least this long after the finding "
          "(two orbits: the uplink at a ground contact, as the ic_planner's planning_margin)", "s",
          range=(0.0, 864000.0)),
    Param("drift_stop_makeup", "bool", True, "a drift-stop executed off its command (the record's burn more than "
          "makeup_z sigmas of the thruster's magnitude error off in magnitude, or more than makeup_pointing_deg off "
          "in direction: the safety monitor's burn_magnitude, burn_pointing) is completed by the rest, commanded "
          "minus executed, whole orbits later at its argument of latitude, at least retry_margin after the finding "
          "(Eq. 2 is linear in the burn at a given u); false: the acquisition alone takes it out "
          "(docs/contingencies.md)"),
    Param("makeup_z", "double", _ANOM.magnitude_z, "sigmas of the thruster's magnitude error beyond which an executed "
          "drift-stop is completed (the safety monitor's burn_magnitude_z)", range=(0.5, 100.0)),
    Param("makeup_pointing_deg", "double", _ANOM.pointing_deg, "direction error beyond which an executed drift-stop "
          "is completed (the safety monitor's burn_pointing_deg)", "deg", range=(0.001, 90.0)),
    Param("weak_ejection_hold", "bool", True, "the carrier camera's bearings (/sim/camera/bearing) from the release "
          "to hold_lead before the drift-stop are tested against the commanded ejection "
          "(core.safety.ejection_check); a weak ejection withdraws the blind drift-stop (an empty plan: the "
          "acquisition then starts from the first OD); false: the drift-stop flies whatever the camera sees "
          "(docs/contingencies.md)"),
    Param("camera_sigma_deg", "double", CAMERA_SIGMA_DEG, "1-sigma bearing error per axis the test assumes (the "
          "simulator's camera_sigma_deg, the same default; change both together)", "deg", range=(1.0e-5, 5.0)),
    Param("camera_model_floor", "double", 1.0, "1-sigma position error of the bearing model against the nonlinear "
          "truth (measured below 0.9 m over the 2 h before the drift-stop), an angle of floor / range added to the "
          "camera's", "m", range=(0.0, 1000.0)),
    Param("hold_sigmas", "double", 3.0, "the nominal set: f1 / g >= (1 - k spl_sigma) / (1 + k ballistic_sigma) "
          "with k this (0.4375 with the default scenario): the bearings see the SPL's fraction f1 over the drag's "
          "g only; the drift-stop is held when they exclude the whole set", range=(0.0, 10.0)),
    Param("hold_alpha", "double", 1.0e-3, "false-alarm probability of the weak-ejection test (chi-square, 1 dof, "
          "the best apparent fraction f1 / g against the best in the nominal set)", range=(1.0e-12, 0.5)),
    Param("hold_lead", "double", 1800.0, "the camera's decision is made this long before the drift-stop (its last "
          "bearing then; the withdrawal's uplink)", "s", range=(0.0, 86400.0)),
    Param("ejection_footage", "bool", True, "the ground filter (core.od.pose) estimates the executed ejection dv "
          "from the footage's 3D poses (/sim/camera/pose) and publishes it on /separation/ejection_estimate; the "
          "weak-ejection test then uses the estimate's fraction f1 of the commanded dv; false, or a contact "
          "without footage (no pose): the bearings-only test (the fallback)"),
    Param("footage_window", "double", FOOTAGE_WINDOW, "the footage of the ejection contact is complete this long "
          "after its first pose: the filter runs then (the simulator's pose_window, the same default)", "s",
          range=(1.0, 86400.0)),
    Param("collision_avoidance", "bool", True, "once the footage's estimate is made, an ejection off its command "
          "whose measured trajectory comes back inside the keep-out gets a carrier along-track CAM of cam_dv, "
          "cam_latency later (core.decisions.cam.cam_decision; docs/run.md, \"The ejection camera\")"),
    Param("cam_latency", "double", 300.0, "from the footage's estimate (the end of the footage, the last minutes "
          "of seed 001's ejection contact) to the CAM: a time-tagged command uplinked before the contact ends", "s",
          range=(0.0, 86400.0)),
    Param("cam_dv", "double", 0.1, "the CAM's along-track dv, its sign the one with the larger predicted "
          "clearance", "m/s", range=(0.001, 5.0)),
    Param("cam_sigmas", "double", 3.0, "the CAM is decided and checked on the measured trajectory's distance less "
          "this many of its 1-sigma", range=(0.0, 10.0)),
    Param("ejection_pointing_sigma_deg", "double", 1.0, "1-sigma direction error of a nominal ejection (the SPL's "
          "mounting and the carrier's attitude): an ejection more than 3 sigma off it, or 3 sigma of the "
          "scenario's spl_sigma off in magnitude, is off its command", "deg", range=(0.001, 90.0)),
    Param("ejection_completion", "bool", True, "an ejection off its command (not stuck) is completed by the "
          "carrier (commanded minus measured at the release's u, whole orbits later), the CAM undone after it, and "
          "the designed drift-stop flown after both (core.decisions.planner.ejection_response); false: the CAM "
          "alone, added to the plan in force"),
    Param("completion_max_pulse", "double", 0.3, "the completion is split into pulses of at most this on "
          "successive orbits", "m/s", range=(0.001, 10.0)),
    Param("stuck_fraction", "double", 0.05, "a measured ejection below this fraction of the commanded one is a "
          "stuck picosatellite (seed 004's jamming): reported, its drift-stop withdrawn, no completion",
          range=(0.0, 1.0)),
)

SIM = (
    SCENARIO_FILE,
    Param("seed", "int", 0, "seed of the ejection, burn and drag dispersions", range=(0, SEED_MAX)),
    Param("disperse", "bool", True, "apply the execution errors, the drag uncertainty and the ejection delay"),
    Param("ejection_delay_max", "double", 10.0, "the release mechanism fires uniformly within this delay after the "
          "commanded ejection epoch (an assumption: no seed gives a value; 0: on time)", "s", range=(0.0, 600.0)),
    _contingency("simulator (spl_weak, drift_stop_delayed, drift_stop_missed, burn_underperformance, "
                 "ejection_pointing, carrier_safe_mode, drift_stop_overperformance, density_storm; the others: none "
                 "here)"),
    Param("duration", "double", DEFAULT_DURATION, "sim time at which the run ends (default 3.25 days: OD, the "
          "initial-condition acquisition and half a day on)", "s", range=(1.0, 1.0e9)),
    Param("time_step", "double", 600.0, "sim time per clock tick (lockstep: per step)", "s", range=(1.0e-3, 86400.0)),
    Param("tick_period", "double", 0.01, "wall time between clock ticks (free-running clock)", "s",
          range=(1.0e-4, 10.0)),
    Param("truth_period", "double", 60.0, "sim-time period of the truth topics", "s", range=(0.1, 86400.0)),
    Param("camera_period", "double", 60.0, "sim time between the carrier camera's bearings of the picosatellite "
          "(/sim/camera/bearing, from the release on; 0: no camera)", "s", range=(0.0, 3600.0)),
    Param("camera_sigma_deg", "double", CAMERA_SIGMA_DEG, "1-sigma bearing error of the carrier camera per axis "
          "(centroid and attitude knowledge; an assumption, no seed gives it); the noise is its own stream of the "
          "seed; the planner's camera_sigma_deg assumes the same default", "deg",
          range=(0.0, 5.0)),
    Param("pose_window", "double", FOOTAGE_WINDOW, "the ejection footage (/sim/camera/pose: 3D poses of the "
          "picosatellite, core.od.pose) covers this long after the release: half the 9-min ejection contact of "
          "seed 001 Sec. 5, the ejection mid-contact (0: a contact without footage)", "s", range=(0.0, 3600.0)),
    Param("pose_frame_period", "double", FRAME_PERIOD, "sim time between the footage's processed frames, on the "
          "sim-time grid (an assumption: 1 Hz of the video)", "s", range=(0.01, 60.0)),
    Param("pose_sigma0", "double", POSE_SIGMA0, "the pose error's floor at zero range (calibration, mounting): "
          "seed 001 Sec. 2.3's sub-centimetre level", "m", range=(0.0, 10.0)),
    Param("pose_pixels", "double", POSE_PIXELS, "pixels of the ejection camera across its normal field of view "
          "(2 x 9.15 deg; an assumption: a 1280 x 1024 sensor, no seed gives it)", range=(16.0, 100000.0)),
    Param("pose_centroid_px", "double", POSE_CENTROID_PX, "1-sigma of the pose fit's silhouette edge (sub-pixel "
          "model fitting; an assumption): the lateral error c p rho and the depth error c p rho^2 / size", "pixel",
          range=(0.0, 100.0)),
    Param("camera_duration", "double", 14400.0, "the camera tracks the picosatellite this long after the release "
          "(the blind drift-stop of the default design is 2.4 h after it)", "s", range=(0.0, 1.0e7)),
    Param("u0_deg", "double", 50.0, "carrier mean argument of latitude at sim time 0", "deg",
          range=(-360.0, 360.0)),
    Param("ltan_hours", "double", 9.5, "local time of the carrier's ascending node (BIROS: 09:30)", "h",
          range=(0.0, 24.0)),
    Param("epoch_utc", "string", DEFAULT_EPOCH_UTC, "UTC calendar epoch of sim time 0",
          rule="an ISO-8601 UTC date-time, e.g. '2016-07-01T00:00:00'", check=_iso_epoch),
    Param("require_plan_approval", "bool", True, "execute a plan only after the safety monitor approved it"),
    Param("approval_timeout", "double", 10.0, "wall time a burn may wait for its approval (the clock holds); then "
          "the burn is dropped", "s", range=(0.01, 86400.0)),
    Param("distance_step", "double", 10.0, "sampling of the minimum-distance tracking", "s", range=(0.1, 3600.0)),
    Param("departure_distance", "double", 1000.0, "closest approaches are tracked once the picosatellite is this "
          "far away", "m", range=(1.0, 1.0e6)),
    Param("j2", "bool", True, J2.format("truth dynamics (dynamics 'secular' only)")),
    Param("dynamics", "string", "nonlinear", "truth: 'nonlinear' (both spacecraft integrated numerically with "
          "J2-J4 and drag, mean ROE published) or 'secular' (the ROE model with J2 and the true differential drag)",
          choices=DYNAMICS),
    Param("wait_for", "string[]", [], "hold the clock at 0 until each topic has that many subscribers (every node "
          "up); [] or ['']: start at once", rule="a list of 'topic=count' items, e.g. ['/sim/truth/roe=4']",
          check=_topic_counts),
    Param("start_timeout", "double", 60.0, "wall time to wait for those subscribers at most", "s",
          range=(0.0, 86400.0)),
    Param("lockstep_participants", "string[]", [], "node names of the lockstep participants ([] or ['']: "
          "free-running clock)", rule="a list of node names other than 'sim'", check=_node_names),
    Param("real_time_factor", "double", 0.0, "lockstep: sim seconds per wall second at most (0: as fast as the "
          "machine allows)", range=(0.0, 1.0e9)),
    Param("step_timeout", "double", 120.0, "lockstep: wall time a step may wait for a participant before the run "
          "fails", "s", range=(0.1, 86400.0)),
)

RADAR_STATIONS = (
    Param("stations", "string[]", ["TIRA"], "radar station names; the three lists below have one entry per station",
          rule="a non-empty list of distinct station names", check=_distinct_names, nonempty=True),
    Param("station_latitudes_deg", "double[]", [50.6166], "geodetic latitude of each station (WGS-84)", "deg",
          range=(-90.0, 90.0), nonempty=True),
    Param("station_longitudes_deg", "double[]", [7.1296], "east longitude of each station", "deg",
          range=(-180.0, 360.0), nonempty=True),
    Param("station_altitudes_m", "double[]", [300.0], "height of each station above the WGS-84 ellipsoid", "m",
          range=(-500.0, 9000.0), nonempty=True),
    Param("epoch_utc", "string", DEFAULT_EPOCH_UTC, "UTC calendar epoch of sim time 0 (the simulator's)",
          rule="an ISO-8601 UTC date-time, e.g. '2016-07-01T00:00:00'", check=_iso_epoch),
)
"""The ground stations and the epoch of sim time 0: parameters of both the radar sensor and the OD (one value for
both, e.g. under ``/**`` in a params file)."""

RADAR_SIGMAS = (
    Param("sigma_range_m", "double", 10.0, "1-sigma range noise", "m", range=(1.0e-3, 1.0e4)),
    Param("sigma_angle_deg", "double", 0.01, "1-sigma azimuth and elevation noise (TIRA's 0.45 deg L-band beam: "
          "0.01 deg needs an SNR of about 26 dB, which a 10 cm picosatellite at ~1000 km gives)", "deg",
          range=(1.0e-6, 0.9)),
)

RADAR = (
    AUTOSTART,
    *RADAR_STATIONS,
    Param("elevation_mask_deg", "double", 10.0, "elevation mask of every station", "deg", range=(0.0, 89.0)),
    *RADAR_SIGMAS,
    Param("sample_interval", "double", 10.0, "measurement interval during a pass (a pass above 10 deg lasts a few "
          "minutes)", "s", range=(0.1, 600.0)),
    Param("min_separation", "double", 5000.0, "smallest separation the radar resolves (seed 001: 5 km)", "m",
          range=(0.0, 1.0e6)),
    Param("min_pass_measurements", "int", 5, "epochs in view of a pass that delivered no measurement for it to be "
          "reported lost (radar_od's measurements for a pass to count)", range=(1, 100000)),
    Param("seed", "int", 0, "seed of the measurement noise", range=(0, SEED_MAX)),
    Param("track_carrier", "bool", False, "each station also ranges the carrier at the epochs it measures the "
          "picosatellite (/radar/carrier_ranges; its noise from the seed's own stream): radar_od's range biases from "
          "the carrier's GPS orbit (issue 41 part 4)"),
    SCENARIO_FILE,
    _contingency("radar (radar_pass_missed, radar_bias; the others: none here), drawn from the noise seed's own "
                 "stream"),
)

RADAR_OD = (
    AUTOSTART,
    *RADAR_STATIONS,
    *RADAR_SIGMAS,
    Param("passes_required", "int", 2, "counted passes needed for an estimate", range=(1, 1000)),
    Param("min_arc", "double", 36000.0, "smallest span of the passes of an estimate (seed 001: about 12 h)", "s",
          range=(0.0, 2.592e6)),
    Param("min_pass_measurements", "int", 5, "measurements for a pass to count", range=(1, 100000)),
    Param("drift_prior", "bool", True, "the drift rate of the last solution before a burn is a priori information "
          "for the batches after it (core.od.batch.DriftPrior; its measurements precede the burn, so nothing is "
          "counted twice)"),
    Param("density_scale_height_m", "double", 0.0, "density scale height of the drift rate's drag model: the "
          "drift prior carried to the spacecraft's heights after a burn, and the drift rate's growth within a batch "
          "(0: Vallado Table 8-4 at the carrier's altitude, 63.8 km at 515 km)", "m", range=(0.0, 1.0e6)),
    Param("drag_ballistic_ratio", "double", 1.5217, "B_d / (B_d - B_c) of the drift rate's drag model (the default "
          "scenario: 0.0230 / 0.0151 m^2/kg)", range=(1.0, 1.0e6)),
    Param("density_walk", "double", 0.0, "relative 1-sigma random walk of the orbit-mean density per sqrt(day) "
          "between a drift prior and its batch (0: the simulated atmospheres have no random variability)",
          "1/sqrt(day)", range=(0.0, 10.0)),
    Param("od_drag_terms", "bool", True, "the OD model's drag terms: the drift rate's growth within a batch, the "
          "drag-driven dix drift and short-periodic de (core.od.batch); false: the secular drift model alone"),
    Param("range_bias_sigma", "double", 0.0, "a priori 1-sigma of a constant range bias per station, estimated with "
          "the relative orbit (core.od.batch.RangeBiasPrior; the estimate on /diagnostics as range_bias_m); 0: no "
          "bias estimated unless the residual test switches it on", "m", range=(0.0, 1.0e4)),
    Param("range_bias_auto_sigma", "double", 100.0, "a priori 1-sigma of the range biases that an OD's failed "
          "residual test switches on (core.od.batch.bias_state_switch: the OD is solved again with them, and every "
          "later one; a range_bias_estimated finding); 0: never switched on", "m", range=(0.0, 1.0e4)),
    Param("range_bias_alpha", "double", 1.0e-4, "level of that residual test (3 m r^2 against chi-square(3 m - 7), "
          "as the safety monitor's od_residuals)", range=(1.0e-12, 0.5)),
    SCENARIO_FILE,
    Param("prior_od_after", "double", 86400.0, "without a full estimate (passes_required passes over min_arc) this "
          "long after the release (a radar outage), each counted pass gives an OD with the prediction as its prior: "
          "the ejection on record (the footage's, else the commanded one with the SPL's errors; the scenario_file's "
          "nominal drag and its sigma) carried through the executed carrier burns (core.od.batch.predicted_prior); "
          "0: never", "s", range=(0.0, 2.592e6)),
    Param("prior_od_floor", "double", 10.0, "1-sigma added to each a-scaled ROE of the ejection on record in that "
          "prediction (the ejection's three dv components alone span three of the six: what seed 002 Eq. 2 leaves "
          "out, the release's offset, mean against osculating elements, drag on the e/i vectors)", "m",
          range=(1.0e-3, 1.0e5)),
    Param("carrier_position_sigma", "double", 1.0, "1-sigma of the carrier's GPS orbit along a station's line of "
          "sight: with the range noise, the weight of its ranges (/radar/carrier_ranges) in the range biases",
          "m", range=(0.0, 1.0e4)),
)

IC_PLANNER = (
    AUTOSTART,
    RECOVER_TIMEOUT,
    SCENARIO_FILE,
    Param("a_dl_min", "double", _ACQ.a_dl_min, "minimum mean along-track separation, at the ICs and throughout the "
          "acquisition (below a_dl_max)", "m", range=(1.0, 1.0e6)),
    Param("a_dl_max", "double", _ACQ.a_dl_max, "maximum mean along-track separation at the ICs", "m",
          range=(1.0, 1.0e6)),
    Param("a_dl_target", "double", _ACQ.a_dl_target, "aimed |a dl| at the ICs (mid-range: room for drag and OD "
          "errors either way); 0 = free in [a_dl_min, a_dl_max], the cheapest", "m", range=(0.0, 1.0e6)),
    Param("a_dl_target_tol", "double", _ACQ.a_dl_target_tol, "|a dl - a_dl_target| allowed after quantization", "m",
          range=(1.0e-3, 1.0e6)),
    Param("min_ei", "double", _ACQ.min_ei, "minimum |a de|, |a di| and R-N distance (seed 002 Eq. 25)", "m",
          range=(1.0e-3, 1.0e5)),
    Param("fov_half_r_deg", "double", _ACQ.fov_half_r_deg, "camera half field of view, radial (seed 002 Eq. 11)",
          "deg", range=(0.01, 89.0)),
    Param("fov_half_n_deg", "double", _ACQ.fov_half_n_deg, "camera half field of view, normal (seed 002 Eq. 11)",
          "deg", range=(0.01, 89.0)),
    Param("max_burn_dv", "double", _ACQ.max_burn_dv, "largest carrier burn (seed 001 Sec. 2.1)", "m/s",
          range=(1.0e-4, 10.0)),
    Param("dv_quantum", "double", _ACQ.dv_quantum, "burn quantization, at most max_burn_dv (seed 001 Sec. 2.1)",
          "m/s", range=(1.0e-6, 10.0)),
    Param("axes", "string", _ACQ.axes, "candidate burn axes", rule="distinct letters among R, T, N, e.g. 'TN'",
          check=_axes),
    Param("planning_margin", "double", 11400.0, "first burn >= max(OD epoch, now) + margin (two orbits: the "
          "uplink, at the next ground contact); below window", "s", range=(0.0, 2.592e6)),
    Param("window", "double", _ACQ.window, "ICs reached at the last grid epoch within OD epoch + window", "s",
          range=(1.0, 2.592e6)),
    Param("grid_per_orbit", "int", _ACQ.grid_per_orbit, "candidate burn epochs per orbit (at round values of u)",
          range=(1, 360)),
    Param("drift_tolerance", "double", _ACQ.drift_tolerance, "|a da| allowed at the ICs (>= dv_quantum / n, about "
          "0.9 m, to be always reachable)", "m", range=(1.0e-3, 1.0e5)),
    Param("ei_angle_tol_deg", "double", _ACQ.ei_angle_tol_deg, "e/i deviation from (anti-)parallel allowed after "
          "quantization", "deg", range=(1.0e-3, 20.0)),
    Param("j2", "bool", _ACQ.j2, J2.format("prediction")),
    Param("trim", "bool", True, "the final OD's drift trim: one tangential burn when the final OD predicts |a da| at "
          "the IC epoch beyond max(0.9 m, ic_drift_tolerance - 3 sigma); false: no trim"),
    Param("ic_drift_tolerance", "double", 5.0, "the |a da| initial condition the trim protects (the report's drift "
          "check)", "m", range=(1.0e-3, 1.0e5)),
    Param("burn_sigma", "double", 0.05, "1-sigma magnitude error of a carrier burn (the scenario's thruster_sigma): "
          "how well the plan in force knows a da after its burns; an OD that knows it less well is not used",
          range=(0.0, 1.0)),
    Param("replan_on_burn", "bool", True, "re-plan (before the final OD) or re-trim (after it) from the last OD and "
          "the executed-maneuver record when an executed acquisition burn departs from its plan by more than half the "
          "trim lattice in a da (0.9 m at 515 km); false: only a new OD re-plans"),
    Param("ei_margin_sigmas", "double", 2.0, "plans keep |a de|, |a di| and the minimum R-N distance (Eq. 25) this "
          "many 1-sigmas of the OD's |a de| and |a di| above min_ei (about 20 m for a radar OD); without a plan that "
          "meets it, min_ei alone; 0: no margin", range=(0.0, 10.0)),
    Param("final_od_arc", "double", 36000.0, "burn-free radar arc kept before the IC epoch for the final OD "
          "(radar_od's min_arc; radar_od restarts its arc at every burn); 0: none, the final OD is then the first "
          "solution within two planning margins of t_F", "s", range=(0.0, 604800.0)),
    Param("blind_acquisition_after", "double", 86400.0, "without any OD this long after the release (a radar "
          "outage), one tangential burn, planned from the ejection on record (the footage's measured one, else the "
          "commanded one) and the carrier burns executed since, holds the along-track separation for as long again; "
          "the first OD after it plans the acquisition (core.decisions.ic_planner.on_step; seed 001 Sec. 5: the "
          "acquisition within a day); 0: never",
          "s", range=(0.0, 2592000.0)),
)

SAFETY_MONITOR = (
    AUTOSTART,
    SCENARIO_FILE,
    Param("period", "double", 600.0, "sim time between state assessments", "s", range=(1.0, 86400.0)),
    Param("keep_out", "double", _LIM.keep_out, "keep-out sphere radius", "m", range=(1.0, 1.0e6)),
    Param("min_rn_distance", "double", _LIM.min_rn_distance, "e/i separation minimum (seed 002 Eq. 25)", "m",
          range=(1.0e-3, 1.0e5)),
    Param("crossing_min", "double", _LIM.crossing_min, "minimum |T| at an R = 0 transit", "m", range=(1.0e-3, 1.0e6)),
    Param("evaporation", "double", _LIM.evaporation, "formation evaporation distance", "m", range=(1.0, 1.0e8)),
    Param("a_dl_min", "double", _LIM.a_dl_min, "radar separability", "m", range=(1.0e-3, 1.0e6)),
    Param("a_dl_max", "double", _LIM.a_dl_max, "camera detection range", "m", range=(1.0e-3, 1.0e7)),
    Param("window", "double", _LIM.window, "prediction window of a state assessment (about one orbit)", "s",
          range=(1.0, 2.592e6)),
    Param("plan_horizon", "double", _LIM.plan_horizon, "prediction after a plan's last burn", "s",
          range=(1.0, 2.592e6)),
    Param("fov_half_r_deg", "double", math.degrees(_LIM.fov_half_r), "camera half field of view, radial",
          "deg", range=(0.01, 89.0)),
    Param("fov_half_n_deg", "double", math.degrees(_LIM.fov_half_n), "camera half field of view, normal",
          "deg", range=(0.01, 89.0)),
    Param("j2", "bool", True, J2.format("predictions")),
    Param("burn_epoch_tolerance", "double", _ANOM.epoch_tolerance, "a carrier burn of an approved plan not executed "
          "this long after its epoch raises burn_missing, one executed later burn_late (core.safety.anomaly)", "s",
          range=(1.0, 86400.0)),
    Param("burn_magnitude_z", "double", _ANOM.magnitude_z, "an executed carrier burn whose magnitude departs from "
          "the commanded one by more than this many sigmas of the thruster's magnitude error raises burn_magnitude",
          "sigma", range=(0.5, 100.0)),
    Param("burn_pointing_deg", "double", _ANOM.pointing_deg, "an executed carrier burn more than this far off its "
          "commanded direction raises burn_pointing (the attitude error: 30 arcsec per axis)", "deg",
          range=(1.0e-3, 180.0)),
    Param("od_alpha", "double", _ANOM.od_alpha, "an OD whose e/i vectors depart from their prediction (the previous "
          "knowledge carried over the executed burns) beyond the chi-square(4) quantile 1 - od_alpha raises "
          "od_inconsistent", range=(1.0e-12, 0.5)),
    Param("od_model_sigma", "double", _ANOM.od_model_sigma, "model floor added per e/i component to that "
          "prediction's 1-sigma (the secular model against the nonlinear truth)", "m", range=(0.0, 1.0e4)),
    Param("residual_alpha", "double", _ANOM.residual_alpha, "an OD whose post-fit residuals exceed the "
          "chi-square(3 m - 7) quantile 1 - residual_alpha raises od_residuals", range=(1.0e-12, 0.5)),
)

EJECTOR = (
    SCENARIO_FILE,
    Param("ejection_epoch", "double", -1.0, "sim-time epoch of the ejection; negative: at the first time the carrier "
          "reaches u1 after not_before", "s", range=(-1.0e9, 1.0e9)),
    Param("not_before", "double", 0.0, "earliest sim time of an ejection at u1", "s", range=(-1.0e9, 1.0e9)),
    Param("lead_time", "double", 1800.0, "the time-tagged event is published up to this long ahead (more than the "
          "spacing of the truth samples)", "s", range=(0.0, 86400.0)),
    Param("strategy", "string", "double_impulse", "'double_impulse' (the scenario's design) or 'multi_impulse' (the "
          "SPL ejection of seed 001 Sec. 3: 1.53 m/s at u1 = 90 deg)", choices=STRATEGIES),
)

RECORDER = (
    Param("output", "string", "", "bag directory to create ('' = rosbag2_YYYY_MM_DD-HH_MM_SS in the working "
          "directory); an existing non-empty directory is refused"),
    Param("topics", "string[]", [], "topics to record ([] = every topic, hidden _-topics excluded)",
          rule="a list of topic names", check=_topic_names),
    Param("exclude", "string[]", [], "topics never recorded", rule="a list of topic names", check=_topic_names),
    Param("flush_period", "double", 1.0, "wall time between forced chunk completions + fsync", "s",
          range=(1.0e-3, 3600.0)),
)

GROUND_BRIDGE = (
    Param("output_dir", "string", "", "directory of the CCSDS files ('' = ccsds_YYYY_MM_DD-HH_MM_SS in the working "
          "directory, as the recorder names its bag; roe-sep run sets OUT/ccsds)"),
    Param("format", "string", "xml", "file format of the CCSDS files", choices=FORMATS),
    Param("epoch_utc", "string", DEFAULT_EPOCH_UTC, "UTC epoch of sim time 0 (the simulator's)",
          rule="an ISO-8601 UTC date-time, e.g. '2016-07-01T00:00:00'", check=_iso_epoch),
    SCENARIO_FILE,
    Param("carrier_isp", "double", 60.0, "carrier thruster specific impulse (OPM MAN_DELTA_MASS)", "s",
          range=(1.0, 1.0e4)),
    Param("write_period", "double", 86400.0, "sim time between OEM/TDM/CDM updates (0: only the complete set at "
          "the scenario's end and at shutdown)", "s", range=(0.0, 2.592e6)),
    Param("min_write_interval", "double", 10.0, "least wall time between two OEM/TDM/CDM updates (an update due "
          "by write_period waits for it; under the as-fast-as-possible lockstep clock a simulated day passes in "
          "about 2 s, and each update rewrites the whole run's XML OEM); 0: every write_period", "s",
          range=(0.0, 86400.0)),
    Param("input_dir", "string", "", "directory watched for TDM files ('' = no input)"),
    Param("poll_period", "double", 1.0, "wall time between scans of input_dir", "s", range=(0.01, 3600.0)),
    Param("default_sigma_range_m", "double", 10.0, "range sigma of a TDM without one", "m", range=(1.0e-3, 1.0e4)),
    Param("default_sigma_angle_deg", "double", 0.01, "angle sigma of a TDM without one", "deg", range=(1.0e-6, 0.9)),
)

ANALYSIS_SERVER = (
    Param("cluster_file", "string", "", "cluster YAML ('' = the embedded Soyuz-stage example, config/cluster.yaml)",
          rule="'' or the path of a cluster YAML (read at start-up)"),
    Param("deploy_density", "double", USSA76_DENSITY_400KM, "density of a deployment assessment whose request gives "
          "0 (USSA76 at 400 km)", "kg/m^3", range=(0.0, 1.0e-6), read_only=False),
    Param("deploy_step", "double", 600.0, "sampling of the returned distance curve", "s", range=(1.0, 86400.0),
          read_only=False),
    Param("deploy_model", "string", "nonlinear", "relative motion of a deployment assessment: 'nonlinear' (heyoka, "
          "J2-J4 + drag) or 'linear' (the secular ROE model)", choices=MODELS, read_only=False),
)

FOXGLOVE_VIEW = (
    Param("port", "int", 8765, "TCP port on 127.0.0.1 (0 = any free port)", range=(0, 65535)),
    Param("keep_out_radius", "double", 1000.0, "radius of the keep-out sphere drawn", "m", range=(1.0, 1.0e6),
          read_only=False),
)

LIFECYCLE_MANAGER = (
    Param("node_names", "string[]", list(MANAGED), "managed nodes, in start-up order", nonempty=True,
          rule="a non-empty list of node names", check=lambda v: all(v)),
    Param("timeout", "double", 30.0, "wait for each node's service and each transition (a call without an answer "
          "is made again, up to 3 times)", "s", range=(0.1, 3600.0)),
)

TABLES = {"planner": PLANNER, "sim": SIM, "radar": RADAR, "radar_od": RADAR_OD, "ic_planner": IC_PLANNER,
          "safety_monitor": SAFETY_MONITOR, "ejector": EJECTOR, "recorder": RECORDER, "ground_bridge": GROUND_BRIDGE,
          "analysis_server": ANALYSIS_SERVER, "foxglove_view": FOXGLOVE_VIEW, "lifecycle_manager": LIFECYCLE_MANAGER}
"""{executable (= node name): its parameters, in declaration order}."""
CLASSES = {"PlannerNode": "planner", "SimNode": "sim", "RadarNode": "radar", "RadarODNode": "radar_od",
           "IcPlannerNode": "ic_planner", "SafetyMonitorNode": "safety_monitor", "EjectorNode": "ejector",
           "RecorderNode": "recorder",
           "GroundBridgeNode": "ground_bridge", "AnalysisServer": "analysis_server",
           "FoxgloveViewNode": "foxglove_view", "LifecycleManager": "lifecycle_manager"}
"""{node class name: its table}."""


def table(node: str) -> dict:
    """{name: Param} of a node."""
    return {p.name: p for p in TABLES[node]}


# ------------------------------------------------------------------------------------------------ parameter files
def check_overrides(overrides: dict, where: str = "--params") -> None:
    """Every value of a ``{node: {name: value}}`` mapping (``/**``: every node) against the tables; ValueError
    ``WHERE: NODE.NAME = VALUE: must be RULE`` for the first that breaks its rule or names no parameter."""
    for node, values in overrides.items():
        nodes = list(TABLES) if node == "/**" else [node]
        if node != "/**" and node not in TABLES:
            raise ValueError(f"{where}: unknown node {node!r}; nodes: {', '.join(TABLES)}")
        for name, value in (values or {}).items():
            if name in ROS_PARAMETERS or str(name).startswith("qos_overrides."):
                continue
            params = [table(n)[name] for n in nodes if name in table(n)]
            if not params:
                known = "every node's" if node == "/**" else f"{node}'s parameters: {', '.join(table(node))}"
                raise ValueError(f"{where}: {node}.{name}: no such parameter ({known})")
            for p in params:
                why = problem(p, value)
                if why:
                    raise ValueError(f"{where}: {node}.{name} = {show(value)}: {why}")


# ------------------------------------------------------------------------------------------------ text
def _default(p: Param) -> str:
    if p.type == "bool":
        return "true" if p.default else "false"
    if p.type == "string":
        return f"'{p.default}'"
    if p.type in ("string[]", "double[]"):
        return "[" + ", ".join(f"'{v}'" if isinstance(v, str) else repr(v) for v in p.default) + "]"
    return repr(p.default)


def usage(node: str, summary: str = "") -> str:
    """The ``--help`` text of a node's executable: usage, what it is, its parameter table."""
    lines = [f"usage: ros2 run roe_sep {node} [-h] [--ros-args [-p NAME:=VALUE ...] [--params-file FILE]]", ""]
    if summary:
        lines += [summary.strip().splitlines()[0], ""]
    lines.append(f"parameters of /{node} (docs/parameters.md; `ros2 param describe /{node} NAME` while it runs):")
    for p in TABLES[node]:
        unit = f" [{p.unit}]" if p.unit else ""
        access = "read-only" if p.read_only else "settable at run time"
        lines.append(f"  {p.name} ({p.type}, default {_default(p)}{unit}; {access})")
        lines.append(f"      {p.description}")
        lines.append(f"      rule: {rule_text(p)}")
    return "\n".join(lines) + "\n"


def markdown() -> str:
    """docs/parameters.md: one table per node."""
    out = ["# Node parameters", "",
           "Generated from `roe_sep/nodes/parameters.py` by `python -m roe_sep.nodes.parameters --markdown "
           "> docs/parameters.md`; do not edit by hand (test/nodes/test_parameters.py fails when this file is "
           "stale). Every executable prints its table with `--help`.", "",
           "Ranges are inclusive. A read-only parameter is fixed once the node started (a managed node: once it "
           "is configured); `ros2 param set` refuses it. A settable one is refused outside its range and rule. "
           "Every node also has rclpy's `use_sim_time` (bool, false).", ""]
    for node, params in TABLES.items():
        out += [f"## {node}", "", "| name | type | default | unit | rule | read-only | description |",
                "|---|---|---|---|---|---|---|"]
        for p in params:
            cells = [f"`{p.name}`", p.type, f"`{_default(p)}`", p.unit, rule_text(p),
                     "yes" if p.read_only else "no", p.description]
            out.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
        out.append("")
    return "\n".join(out)


def main(argv=None) -> int:
    args = sys.argv[1:] if argv is None else list(argv)
    if args == ["--markdown"]:
        sys.stdout.write(markdown())
        return 0
    if len(args) == 1 and args[0] in TABLES:
        sys.stdout.write(usage(args[0]))
        return 0
    print(f"usage: python -m roe_sep.nodes.parameters --markdown | NODE (one of {', '.join(TABLES)})",
          file=sys.stderr)
    return 2


if __name__ == "__main__":
    raise SystemExit(main())
