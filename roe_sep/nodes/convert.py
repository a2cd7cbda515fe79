"""Conversions between roe_sep_msgs messages and core quantities (SI, dimensionless ROE <-> a*ROE meters)."""

import numpy as np
from builtin_interfaces.msg import Time
from geometry_msgs.msg import Vector3
from roe_sep_msgs.msg import ImpulsiveManeuver, OrbitalElements, RelativeOrbitalElements, RelativeState

from .. import interfaces
from ..core.decisions.common import PlannedBurn
from ..core.decisions.ic_planner import EjectionPrior
from ..core.relmotion.roe import wrap_angle
from ..core.truth.execution import relative_impulse
from ..stamps import sec_nanosec, time_to_sec
from ..validate import ROE_FIELDS
from .serialized import Serialized

KEPLER_FIELDS = ("semi_major_axis", "eccentricity", "inclination", "raan", "arg_perigee", "mean_arg_latitude")


def sec_to_time(seconds: float) -> Time:
    """A builtin_interfaces/Time of ``seconds`` (:func:`roe_sep.stamps.sec_nanosec`: finite, nanosecond carry)."""
    sec, nanosec = sec_nanosec(seconds)
    return Time(sec=sec, nanosec=nanosec)


def vector_to_array(v: Vector3) -> np.ndarray:
    return np.array([v.x, v.y, v.z], dtype=float)


def twist_linear(msg) -> tuple[np.ndarray, np.ndarray]:
    """The linear part of a geometry_msgs/TwistWithCovarianceStamped: its vector (3,) and covariance (3, 3), the
    upper-left block of the row-major 6x6 (the footage's ejection estimate: dv [m/s] RTN, [m^2/s^2]); ValueError for
    a covariance of another size or a non-finite vector or block."""
    cov = np.asarray(msg.twist.covariance, dtype=float)
    if cov.size != 36:
        raise ValueError(f"a twist covariance has 36 entries, got {cov.size}")
    dv, block = vector_to_array(msg.twist.twist.linear), cov.reshape(6, 6)[:3, :3].copy()
    if not (np.all(np.isfinite(dv)) and np.all(np.isfinite(block))):
        raise ValueError("non-finite ejection estimate")
    return dv, block


def ejection_prior(event, scenario) -> EjectionPrior:
    """The commanded ejection of a roe_sep_msgs/EjectionEvent with the scenario's SPL errors and nominal drag
    (:meth:`EjectionPrior.commanded`, what the ic_planner and radar_od predict from before any OD); ValueError for a
    non-finite dv or an invalid chief."""
    dv = vector_to_array(event.ejection.dv_rtn)
    kep = elements_to_array(event.chief)
    if not (np.all(np.isfinite(dv)) and np.all(np.isfinite(kep)) and kep[0] > 6.4e6):
        raise ValueError("non-finite dv or invalid chief")
    return EjectionPrior.commanded(time_to_sec(event.header.stamp), kep, event.ejection.mean_arg_latitude, dv,
                                   scenario)


def array_to_vector(a) -> Vector3:
    x, y, z = (float(c) for c in a)
    return Vector3(x=x, y=y, z=z)


def elements_to_array(el: OrbitalElements) -> np.ndarray:
    """Mean Keplerian elements ``[a, e, i, raan, argp, M]`` (M = u - argp) from the message."""
    return np.array([el.semi_major_axis, el.eccentricity, el.inclination, el.raan, el.arg_perigee,
                     el.mean_arg_latitude - el.arg_perigee], dtype=float)


def array_to_elements(kep) -> OrbitalElements:
    """``[a, e, i, raan, argp, M]`` -> message, angles wrapped to [-pi, pi)."""
    a, e, i, raan, argp, m = (float(x) for x in kep)
    return OrbitalElements(semi_major_axis=a, eccentricity=e, inclination=i, raan=float(wrap_angle(raan)),
                           arg_perigee=float(wrap_angle(argp)), mean_arg_latitude=float(wrap_angle(argp + m)))


def roe_to_msg(roe, chief: OrbitalElements, stamp: Time, frame_id=interfaces.CARRIER_RTN_FRAME, covariance=None):
    """Dimensionless ROE -> message in meters (a*delta alpha, a = the chief's semi-major axis)."""
    a = chief.semi_major_axis
    msg = RelativeOrbitalElements(chief=chief)
    msg.header.stamp = stamp
    msg.header.frame_id = frame_id
    for name, value in zip(ROE_FIELDS, np.asarray(roe, dtype=float) * a):
        setattr(msg, name, float(value))
    if covariance is not None:
        msg.covariance = (np.asarray(covariance, dtype=float) * a * a).reshape(36)
    return msg


def truth_fields(kep, roe) -> tuple[np.ndarray, np.ndarray]:
    """The fields of :func:`array_to_elements` (``[a, e, i, raan, argp, u]``, angles wrapped) and of :func:`roe_to_msg`
    (a*ROE [m]) for each row of the mean elements ``kep`` ``(T, 6)`` and the dimensionless ``roe`` ``(T, 6)``, two
    ``(T, 6)`` arrays: one vectorised pass whose element-wise operations are those of the per-row functions, so every
    value is the same to the last bit."""
    kep = np.asarray(kep, dtype=float).reshape(-1, 6)
    roe = np.asarray(roe, dtype=float).reshape(-1, 6)
    chief = np.concatenate([kep[:, :3], wrap_angle(kep[:, 3:5]), wrap_angle(kep[:, 4:5] + kep[:, 5:6])], axis=1)
    return chief, roe * kep[:, :1]


class TruthMessages:
    """The simulator's truth topics, serialized: for each sample the RelativeOrbitalElements (frame
    :data:`~roe_sep.interfaces.TRUTH_FRAME`, the chief of :func:`array_to_elements`, the a*ROE of :func:`roe_to_msg`,
    zero covariance) and the RelativeState (frame :data:`~roe_sep.interfaces.CARRIER_RTN_FRAME`, the true relative
    position and velocity) stamped with its epoch, as the bytes rclpy serializes from those messages
    (:class:`~.serialized.Serialized`, the fields of all samples written in one vectorised pass)."""

    def __init__(self):
        roe, rtn = RelativeOrbitalElements(), RelativeState()
        roe.header.frame_id = interfaces.TRUTH_FRAME
        rtn.header.frame_id = interfaces.CARRIER_RTN_FRAME
        stamp = {"sec": ("header.stamp.sec",), "nanosec": ("header.stamp.nanosec",)}
        self.roe = Serialized(roe, {**stamp, "chief": tuple(f"chief.{n}" for n in KEPLER_FIELDS), "roe": ROE_FIELDS})
        self.rtn = Serialized(rtn, {**stamp, "position": ("position.x", "position.y", "position.z"),
                                    "velocity": ("velocity.x", "velocity.y", "velocity.z")})

    def __call__(self, epochs, samples) -> list[tuple[bytes, bytes]]:
        """``(roe, rtn)`` serialized messages at each of ``epochs`` [s] from the truth's ``samples`` at them, ``(kep
        (T, 6), dimensionless roe (T, 6), (pos (T, 3) [m], vel (T, 3) [m/s]))``."""
        kep, roe, (pos, vel) = samples
        chief, a_roe = truth_fields(kep, roe)
        stamps = [sec_nanosec(t) for t in epochs]
        roe_rows, rtn_rows = self.roe.rows(len(stamps)), self.rtn.rows(len(stamps))
        for rows in (roe_rows, rtn_rows):
            rows["sec"] = [sec for sec, _ in stamps]
            rows["nanosec"] = [nanosec for _, nanosec in stamps]
        roe_rows["chief"], roe_rows["roe"] = chief, a_roe
        rtn_rows["position"] = np.asarray(pos, dtype=float).reshape(-1, 3)
        rtn_rows["velocity"] = np.asarray(vel, dtype=float).reshape(-1, 3)
        return list(zip(Serialized.messages(roe_rows), Serialized.messages(rtn_rows)))


def msg_to_roe(msg: RelativeOrbitalElements) -> np.ndarray:
    """Message -> dimensionless ROE."""
    return np.array([getattr(msg, n) for n in ROE_FIELDS], dtype=float) / msg.chief.semi_major_axis


def maneuver_msg(epoch: float, u: float, dv_rtn, spacecraft: str, purpose: str) -> ImpulsiveManeuver:
    """One impulsive maneuver; ``u`` [rad] wrapped to [-pi, pi) as every angle in our messages."""
    return ImpulsiveManeuver(epoch=sec_to_time(epoch), mean_arg_latitude=float(wrap_angle(u)),
                             dv_rtn=array_to_vector(dv_rtn),
                             spacecraft=spacecraft, purpose=purpose)


def relative_dv(m: ImpulsiveManeuver) -> np.ndarray:
    """The impulse's effect on the relative motion (:func:`roe_sep.core.truth.execution.relative_impulse`)."""
    return relative_impulse(vector_to_array(m.dv_rtn), m.spacecraft)


def plan_burns(maneuvers):
    """ImpulsiveManeuver messages -> :class:`roe_sep.core.relmotion.trajectory.Burn` list (relative impulses)."""
    from ..core.relmotion.trajectory import Burn

    return [Burn(time_to_sec(m.epoch), tuple(relative_dv(m))) for m in maneuvers]


def planned_burn(m: ImpulsiveManeuver) -> PlannedBurn:
    """The maneuver message as the decisions hold it (its stamp, angle and dv unchanged)."""
    return PlannedBurn(m.epoch.sec, m.epoch.nanosec, m.mean_arg_latitude, (m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z),
                       m.spacecraft, m.purpose)


def maneuver(b: PlannedBurn) -> ImpulsiveManeuver:
    """The message of a decision's burn (the inverse of :func:`planned_burn`)."""
    m = ImpulsiveManeuver(mean_arg_latitude=b.u, spacecraft=b.spacecraft, purpose=b.purpose)
    m.epoch.sec, m.epoch.nanosec = b.sec, b.nanosec
    m.dv_rtn.x, m.dv_rtn.y, m.dv_rtn.z = b.dv_rtn
    return m
