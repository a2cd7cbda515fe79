"""Validation of every message a node reads, before it is buffered, counted or used, and of every message the run
report reads from a bag.

A bad message (not finite, an impossible orbit, an implausible impulse, an unknown spacecraft, a negative epoch, a
wrong array size) raises :class:`BadMessage` naming the field; :class:`roe_sep.nodes.lockstep.Lockstep` drops it with
an ERROR on ``/diagnostics`` naming the topic and the field, and the node goes on. Dropped before it is counted, a
bad message cannot take the place of a good one in a lockstep round. The report (:mod:`roe_sep.report`) drops the
same messages from a bag, which records every message on a topic, also a foreign publisher's garbage.

Below the nodes, next to :mod:`roe_sep.interfaces` (core <- interfaces, validate <- nodes <- run/report): messages
are read by their fields only, so the offline tools validate a decoded bag without importing a node; rclpy is
imported only by :func:`validator_for`, which maps the generated message classes.
"""

import math

from .core.constants import R_EARTH
from .errors import BadMessage
from .stamps import NANOSECONDS_PER_SECOND, time_to_sec

MAX_DV = 10.0  # m/s: far above any impulse of the scenario (SPL 1.4-1.5 m/s, carrier burns <= 1.4 m/s)
MAX_ROE_M = 1.0e7  # m: a*delta alpha of a relative orbit still worth the name
MAX_BURNS = 1000
SPACECRAFT = ("carrier", "picosatellite")
ROE_FIELDS = ("a_da", "a_dl", "a_dex", "a_dey", "a_dix", "a_diy")
"""The a*ROE fields [m] of RelativeOrbitalElements (and of an OD estimate), in the core's ROE order."""


def _join(field, name):
    return f"{field}.{name}" if field else name


def _finite(field, value, lo=-math.inf, hi=math.inf, must=None):
    if not (isinstance(value, (int, float)) and math.isfinite(value) and lo <= value <= hi):
        raise BadMessage(field, value, must or f"a finite number in [{lo:g}, {hi:g}]")


def time_of(field, t):
    """A builtin_interfaces/Time: a non-negative sim time [s]."""
    if t.sec < 0 or not 0 <= t.nanosec < NANOSECONDS_PER_SECOND:
        raise BadMessage(field, (t.sec, t.nanosec), "a non-negative time")
    return time_to_sec(t)


ELEMENT_BOUNDS = (  # OrbitalElements field, its range, what it must be
    ("semi_major_axis", R_EARTH + 1.0e5, R_EARTH + 5.0e6, "a low-Earth-orbit semi-major axis [m]"),
    ("eccentricity", 0.0, 0.1, "a near-circular eccentricity in [0, 0.1]"),
    ("inclination", 0.0, math.pi, "an inclination in [0, pi] rad"),
    ("raan", -100.0, 100.0, "a finite angle [rad]"),
    ("arg_perigee", -100.0, 100.0, "a finite angle [rad]"),
    ("mean_arg_latitude", -100.0, 100.0, "a finite angle [rad]"),
)


def elements(field, el):
    """OrbitalElements of a near-circular low Earth orbit (:data:`ELEMENT_BOUNDS`)."""
    for name, lo, hi, must in ELEMENT_BOUNDS:
        _finite(_join(field, name), getattr(el, name), lo, hi, must)


_NUMBER = (int, float)


def _roe_ok(msg) -> bool:
    """True when :func:`roe` accepts ``msg``: its tests in its order, without building the field names (every bound
    is finite, so ``lo <= value <= hi`` fails for NaN and infinities as ``_finite`` does). False (or an exception)
    sends the message through :func:`roe` itself, which raises what it raises."""
    t = msg.header.stamp
    if t.sec < 0 or not 0 <= t.nanosec < NANOSECONDS_PER_SECOND:
        return False
    el = msg.chief
    for name, lo, hi, _ in ELEMENT_BOUNDS:
        value = getattr(el, name)
        if not (isinstance(value, _NUMBER) and lo <= value <= hi):
            return False
    for name in ROE_FIELDS:
        value = getattr(msg, name)
        if not (isinstance(value, _NUMBER) and -MAX_ROE_M <= value <= MAX_ROE_M):
            return False
    cov = msg.covariance
    cov = cov.tolist() if hasattr(cov, "tolist") else list(cov)
    return len(cov) in (0, 36) and all(map(math.isfinite, cov))


def roe_accepted(sec, nanosec, chief, values, covariance):
    """Which messages :func:`roe` accepts, for a topic of RelativeOrbitalElements read as arrays (a bag's fixed
    layout, :func:`roe_sep.bag.cdr.fixed_layout`): stamp ``sec`` and ``nanosec`` (N,), ``chief`` ``{name: (N,)}``
    of :data:`ELEMENT_BOUNDS`, ``values`` ``{name: (N,)}`` of :data:`ROE_FIELDS` (float64) and ``covariance``
    (N, 36): the tests of :func:`_roe_ok`, element-wise (every bound is finite: a comparison fails for NaN and
    infinities as there). A boolean (N,) array."""
    import numpy as np

    ok = (np.asarray(sec) >= 0) & (np.asarray(nanosec) >= 0) & (np.asarray(nanosec) < NANOSECONDS_PER_SECOND)
    for name, lo, hi, _ in ELEMENT_BOUNDS:
        ok &= (lo <= chief[name]) & (chief[name] <= hi)
    for name in ROE_FIELDS:
        ok &= (-MAX_ROE_M <= values[name]) & (values[name] <= MAX_ROE_M)
    return ok & np.isfinite(covariance).all(axis=-1)


def roe(field, msg):
    """RelativeOrbitalElements: stamp, chief and a*ROE [m] plausible; covariance 36 finite entries or empty."""
    try:
        if _roe_ok(msg):
            return
    except Exception:  # noqa: BLE001 -- the checks below raise it again, or say what is wrong
        pass
    time_of(_join(field, "header.stamp"), msg.header.stamp)
    elements(_join(field, "chief"), msg.chief)
    for name in ROE_FIELDS:
        _finite(_join(field, name), getattr(msg, name), -MAX_ROE_M, MAX_ROE_M)
    cov = list(msg.covariance)
    if len(cov) not in (0, 36) or not all(math.isfinite(c) for c in cov):
        raise BadMessage(_join(field, "covariance"), f"{len(cov)} values", "36 finite values (or none)")


def maneuver(field, m):
    """ImpulsiveManeuver: epoch, finite impulse below MAX_DV, a known spacecraft."""
    time_of(_join(field, "epoch"), m.epoch)
    dv = (m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z)
    if not all(math.isfinite(c) for c in dv) or math.sqrt(sum(c * c for c in dv)) > MAX_DV:
        raise BadMessage(_join(field, "dv_rtn"), dv, f"finite, at most {MAX_DV:g} m/s")
    _finite(_join(field, "mean_arg_latitude"), m.mean_arg_latitude, -100.0, 100.0, "a finite angle [rad]")
    if m.spacecraft not in SPACECRAFT:
        raise BadMessage(_join(field, "spacecraft"), m.spacecraft, f"one of {SPACECRAFT}")


def ejection(msg):
    time_of("header.stamp", msg.header.stamp)
    maneuver("ejection", msg.ejection)
    if msg.ejection.spacecraft != "picosatellite":
        raise BadMessage("ejection.spacecraft", msg.ejection.spacecraft, "'picosatellite'")
    elements("chief", msg.chief)


def plan(msg):
    time_of("header.stamp", msg.header.stamp)
    if len(msg.maneuvers) > MAX_BURNS:
        raise BadMessage("maneuvers", f"{len(msg.maneuvers)} burns", f"at most {MAX_BURNS}")
    for k, m in enumerate(msg.maneuvers):
        maneuver(f"maneuvers[{k}]", m)
    if msg.aimed.chief.semi_major_axis != 0.0:  # the state the plan aims at, when it says one
        roe("aimed", msg.aimed)


def orbit_determination(msg):
    time_of("header.stamp", msg.header.stamp)
    roe("estimate", msg.estimate)
    for name in ("a_da_dot", "a_da_dot_sigma", "residual_rms"):
        _finite(name, getattr(msg, name))
    if len(msg.estimate.covariance) != 36:
        raise BadMessage("estimate.covariance", f"{len(msg.estimate.covariance)} values", "36 values")
    for k, v in enumerate(getattr(msg, "a_da_dot_covariance", ())):
        _finite(f"a_da_dot_covariance[{k}]", v)


def safety_status(msg):
    time_of("header.stamp", msg.header.stamp)
    time_of("plan_stamp", msg.plan_stamp)
    if not msg.source:
        raise BadMessage("source", msg.source, "'truth', 'estimate' or 'plan:<topic>'")


def truth(msg):
    roe("", msg)


def truth_rtn(msg):
    """RelativeState of the truth: a stamp, a finite relative position [m] and velocity [m/s]."""
    time_of("header.stamp", msg.header.stamp)
    for name in ("position", "velocity"):
        v = getattr(msg, name)
        for axis in "xyz":
            _finite(f"{name}.{axis}", getattr(v, axis))


def bearing(msg):
    """Vector3Stamped of the camera: a stamp and a unit line of sight."""
    time_of("header.stamp", msg.header.stamp)
    v = (msg.vector.x, msg.vector.y, msg.vector.z)
    if not all(math.isfinite(c) for c in v) or abs(math.sqrt(sum(c * c for c in v)) - 1.0) > 1e-6:
        raise BadMessage("vector", v, "a finite unit vector")


def pose(msg):
    """PoseWithCovarianceStamped of the ejection footage: a stamp, a finite position and a covariance whose position
    block is finite, symmetric and positive definite."""
    time_of("header.stamp", msg.header.stamp)
    p = msg.pose.pose.position
    for name, v in (("x", p.x), ("y", p.y), ("z", p.z)):
        _finite(f"pose.pose.position.{name}", v)
    c = msg.pose.covariance
    if len(c) != 36:
        raise BadMessage("pose.covariance", f"{len(c)} values", "36 values")
    block = [[c[6 * i + j] for j in range(3)] for i in range(3)]
    for i in range(3):
        for j in range(3):
            _finite(f"pose.covariance[{6 * i + j}]", block[i][j])
    a, b, cc = block[0][0], block[0][1], block[0][2]
    d, e, f = block[1][1], block[1][2], block[2][2]
    det2 = a * d - b * b
    det3 = a * (d * f - e * e) - b * (b * f - e * cc) + cc * (b * e - d * cc)
    scale = max(abs(block[k][k]) for k in range(3))
    symmetric = all(abs(block[i][j] - block[j][i]) <= 1e-9 * scale for i in range(3) for j in range(3))
    if not (symmetric and a > 0.0 and det2 > 0.0 and det3 > 0.0):
        raise BadMessage("pose.covariance", block, "a symmetric positive-definite position block")


def executed(msg):
    maneuver("", msg)


def validator_for(msg_type):
    """The validation function of a message type read by our nodes (None: no check)."""
    from geometry_msgs.msg import PoseWithCovarianceStamped, Vector3Stamped
    from roe_sep_msgs.msg import (
        EjectionEvent,
        ImpulsiveManeuver,
        ManeuverPlan,
        OrbitDetermination,
        RelativeOrbitalElements,
        SafetyStatus,
    )

    return {RelativeOrbitalElements: truth, EjectionEvent: ejection, ManeuverPlan: plan, ImpulsiveManeuver: executed,
            OrbitDetermination: orbit_determination, SafetyStatus: safety_status, Vector3Stamped: bearing,
            PoseWithCovarianceStamped: pose}.get(msg_type)
