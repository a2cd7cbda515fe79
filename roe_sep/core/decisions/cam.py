"""A collision-avoidance manoeuvre (CAM) of the carrier within the first orbit, decided on the ejection the footage
measured (issue 41 part 2; the planner acts on it: :func:`~.planner.ejection_response`): docs/run.md, "The ejection
camera".

The rule (:func:`cam_decision`), from the ground filter's executed ejection (dv and its covariance,
:func:`~roe_sep.core.od.pose.estimate_ejection`):

1. *Off its command*: the measured magnitude departs from the commanded one by more than ``off_sigmas`` of the
   SPL's magnitude error combined with the estimate's (seed 002 Eq. 22: f1 ~ N(1, spl_sigma)), or its direction by
   more than ``off_sigmas`` of the pointing error combined with the estimate's. A nominal ejection is never acted on.
2. *Comes back inside the keep-out*: the trajectory of the measured ejection (the house's relative motion: seed 002
   Eq. 2, the secular J2 propagation with the nominal differential drag, the ROE-to-RTN map), with no burn, from the
   CAM's earliest epoch (the decision plus ``latency``) to ``horizon_orbits`` after the release, has a distance
   less ``sigmas`` of its 1-sigma (the covariance mapped linearly) below ``keep_out`` after its departure (the first
   time it is outside), or never departs at all (a stuck or nearly stuck picosatellite).
3. Then the CAM: a carrier along-track burn of ``dv_cam`` at that earliest epoch, its sign the one whose predicted
   lower-bound distance over the horizon is the larger; ``cleared`` says whether it keeps the keep-out.

The completion of the ejection after it (:func:`completion_burns`) and the CAM undone (:func:`reversal_burn`).
"""

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..relmotion.dynamics import arg_latitude_rate
from ..relmotion.maneuvers import delta_roe
from ..relmotion.orbit import angle_between, mean_motion
from ..relmotion.roe import rtn_position
from ..relmotion.trajectory import Burn, Chief, trajectory
from .common import PlannedBurn


@dataclass(frozen=True)
class CamConfig:
    """The rule's parameters (module docstring): ``keep_out`` [m] (the safety monitor's), ``spl_sigma`` (fraction)
    and ``pointing_sigma`` [rad] of the nominal ejection, ``off_sigmas``, ``sigmas`` of the predicted distance,
    ``latency`` [s] from the decision to the earliest CAM, ``horizon_orbits`` after the release, ``dv_cam`` [m/s],
    the prediction ``step`` [s] and ``j2``."""

    keep_out: float = 1000.0
    spl_sigma: float = 0.1
    pointing_sigma: float = math.radians(1.0)
    off_sigmas: float = 3.0
    sigmas: float = 3.0
    latency: float = 300.0
    horizon_orbits: float = 1.0
    dv_cam: float = 0.1
    step: float = 10.0
    j2: bool = True


@dataclass(frozen=True)
class CamDecision:
    """What :func:`cam_decision` found: ``off`` (and its ``magnitude_z``, ``pointing_z``), ``returns`` (and the
    epoch ``t_inside`` [s] of the first lower-bound distance inside the keep-out after the earliest CAM, None: not;
    ``departs``: whether it leaves the keep-out at all), the smallest lower-bound distance ``closest`` [m] over the
    horizon after the earliest CAM and the departure (-inf: no departure), the ``burn`` (a carrier
    :class:`~.common.PlannedBurn`, None: no CAM), the
    lower-bound distance ``closest_after`` [m] with it (None: no CAM), ``cleared`` and the ``reason``."""

    off: bool
    magnitude_z: float
    pointing_z: float
    returns: bool
    departs: bool
    t_inside: float | None
    closest: float
    burn: PlannedBurn | None
    closest_after: float | None
    cleared: bool
    reason: str


def predicted_distance(dv: ArrayLike, cov: ArrayLike, chief: Chief, times: ArrayLike, burns: tuple = (), *,
                       da_dot: float = 0.0, j2: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """The distance [m] at ``times`` of the picosatellite ejected with ``dv`` at ``chief.t0`` under the relative
    ``burns`` (:class:`~roe_sep.core.relmotion.trajectory.Burn`), and its 1-sigma from the covariance ``cov`` of
    ``dv`` (linear: the distance's gradient in dv, each unit impulse's trajectory; the burns do not depend on dv).

    Parameters
    ----------
    dv, cov : array_like, shapes (3,) and (3, 3)
        The ejection [m/s], RTN, and its covariance [m^2/s^2].
    chief : Chief
        The carrier's a [m], i [rad] and mean argument of latitude u0 [rad] at the release t0 [s].
    times : array_like, shape (m,)
        Epochs [s], >= ``chief.t0``.
    burns : tuple of Burn
        Relative impulses after the release (a carrier burn dv enters as -dv).
    da_dot : float
        The differential-drag rate of da [1/s].
    j2 : bool
        With the J2 secular rates.

    Returns
    -------
    (numpy.ndarray, numpy.ndarray), each shape (m,)
        The distance [m] and its 1-sigma [m].
    """
    t = np.asarray(times, dtype=float)
    a, n = chief.a, float(mean_motion(chief.a))
    u = chief.u_at(t, j2)

    def position(roe0, with_burns, drag):
        roe = trajectory(roe0, chief.t0, burns if with_burns else (), t, chief, j2=j2, da_dot=drag)
        return rtn_position(roe, u) * a  # (m, 3)

    base = position(delta_roe(np.asarray(dv, dtype=float), chief.u0, a, n), True, da_dot)
    columns = np.stack([position(delta_roe(e, chief.u0, a, n), False, 0.0) for e in np.eye(3)], axis=-1)  # (m,3,3)
    rho = np.linalg.norm(base, axis=-1)
    grad = np.einsum("mi,mik->mk", base / np.maximum(rho, 1e-9)[:, None], columns)
    var = np.einsum("mk,kl,ml->m", grad, np.asarray(cov, dtype=float), grad)
    return rho, np.sqrt(np.maximum(var, 0.0))


def _approach(times, lower, t_from, keep_out):
    """Of the lower-bound distance ``lower`` at ``times``: whether it departs (reaches ``keep_out``), the first epoch
    at or after ``t_from`` and after the departure where it is back inside (None: never), and its closest approach
    after both: the smallest local minimum, or the last sample while it still decreases there (inf: none; -inf: no
    departure)."""
    out = np.nonzero(lower >= keep_out)[0]
    if out.size == 0:
        return False, None, -math.inf
    k0 = int(np.searchsorted(times, max(t_from, times[out[0]])))
    seg = lower[k0:]
    inside = np.nonzero(seg < keep_out)[0]
    t_inside = float(times[k0 + inside[0]]) if inside.size else None
    if seg.size < 2:
        return True, t_inside, math.inf
    minima = np.nonzero((seg[1:-1] <= seg[:-2]) & (seg[1:-1] < seg[2:]))[0] + 1
    ends = [seg[-1]] if seg[-1] < seg[-2] else []
    return True, t_inside, float(min([*seg[minima], *ends], default=math.inf))


def cam_decision(dv: ArrayLike, cov: ArrayLike, dv_commanded: ArrayLike, chief: Chief, t_now: float, *,
                 da_dot: float = 0.0, config: CamConfig = CamConfig()) -> CamDecision:
    """Whether the carrier flies a CAM within the first orbit, and which (module docstring).

    Parameters
    ----------
    dv, cov : array_like, shapes (3,) and (3, 3)
        The measured ejection [m/s], RTN, and its covariance [m^2/s^2].
    dv_commanded : array_like, shape (3,)
        The commanded ejection [m/s], RTN.
    chief : Chief
        The carrier's a [m], i [rad] and mean argument of latitude at the release (its epoch t0 [s]: the
        estimate's).
    t_now : float
        The decision's epoch [s] (the footage processed); the earliest CAM is ``latency`` later.
    da_dot : float
        The nominal differential-drag rate of da [1/s].
    config : CamConfig
        The rule's parameters.

    Returns
    -------
    CamDecision
        The findings and the CAM (None: none).
    """
    dv, cmd = np.asarray(dv, dtype=float), np.asarray(dv_commanded, dtype=float)
    cov = np.asarray(cov, dtype=float)
    c = config
    mag, mag_cmd = float(np.linalg.norm(dv)), float(np.linalg.norm(cmd))
    u = dv / mag if mag > 0.0 else np.zeros(3)
    sig_mag = math.sqrt(max(float(u @ cov @ u), 0.0))
    magnitude_z = abs(mag / mag_cmd - 1.0) / math.hypot(c.spl_sigma, sig_mag / mag_cmd)
    angle = float(angle_between(dv, cmd)) if mag > 0.0 else math.pi
    sig_dir = math.sqrt(max(float(np.trace(cov)) - sig_mag ** 2, 0.0) / 2.0) / max(mag, 1e-9)  # per normal axis
    pointing_z = angle / math.hypot(c.pointing_sigma, sig_dir)
    off = magnitude_z > c.off_sigmas or pointing_z > c.off_sigmas

    t_cam = float(t_now) + c.latency
    period = 2.0 * math.pi / float(arg_latitude_rate(chief.a, chief.inc, c.j2))
    t_end = chief.t0 + c.horizon_orbits * period
    if not t_cam < t_end:  # decided too late for a CAM in the horizon (a late estimate, another clock): none
        return CamDecision(off, magnitude_z, pointing_z, False, True, None, math.inf, None, None, False,
                           f"the earliest CAM (t = {t_cam:.0f} s) is past the horizon (t = {t_end:.0f} s): no CAM")
    times = np.arange(chief.t0, t_end + c.step / 2, c.step)
    rho, sig = predicted_distance(dv, cov, chief, times, da_dot=da_dot, j2=c.j2)
    departs, t_inside, closest = _approach(times, rho - c.sigmas * sig, t_cam, c.keep_out)
    returns = (not departs) or t_inside is not None
    args = (off, magnitude_z, pointing_z, returns, departs, t_inside, closest)
    if not off:
        return CamDecision(*args, None, None, False, "the ejection is within its command: no CAM")
    if not returns:
        return CamDecision(*args, None, None, False, "off its command, but the measured trajectory stays outside the "
                                                     "keep-out over the horizon: no CAM")
    best = None
    for sign in (1.0, -1.0):
        burn = Burn(t_cam, (0.0, -sign * c.dv_cam, 0.0))  # a carrier burn enters as the relative -dv
        rho_b, sig_b = predicted_distance(dv, cov, chief, times, (burn,), da_dot=da_dot, j2=c.j2)
        gone, _, low = _approach(times, rho_b - c.sigmas * sig_b, t_cam, c.keep_out)
        low = low if gone else -math.inf  # never out: no clearance at all
        if best is None or low > best[0]:
            best = (low, sign)
    low, sign = best
    u_cam = float(chief.u_at(t_cam, c.j2))
    burn = PlannedBurn.at(t_cam, u_cam, (0.0, sign * c.dv_cam, 0.0), "carrier", "collision_avoidance")
    cleared = bool(low >= c.keep_out)
    why = "never leaves the keep-out" if not departs else f"back inside the keep-out at t = {t_inside:.0f} s"
    return CamDecision(*args, burn, low, cleared,
                       f"off its command ({magnitude_z:.1f} sigma in magnitude, {pointing_z:.1f} in direction) and "
                       f"{why}: a carrier along-track CAM of {sign * c.dv_cam:+.3f} m/s at t = {t_cam:.0f} s "
                       f"({'clears' if cleared else 'does not clear'} the keep-out: " + (
                           "no return over the horizon" if math.isinf(low) and low > 0 else f"{low:.0f} m")
                       + f" at {c.sigmas:g} sigma)")


def completion_burns(dv: ArrayLike, dv_commanded: ArrayLike, *, t_release: float, u_release: float, period: float,
                     t_earliest: float, max_pulse: float) -> tuple:
    """The carrier's completion of an ejection measured off its command (issue 41 part 2): the rest, commanded minus
    measured, flown by the carrier at the release's argument of latitude whole orbits after the release (seed 002
    Eq. 2 is linear in the impulse at a given u, so the pair's e/i vectors and drift become the commanded ejection's;
    only the along-track offset grown meanwhile differs), split into equal pulses of at most ``max_pulse`` on
    successive orbits, the first at or after ``t_earliest``.

    Parameters
    ----------
    dv, dv_commanded : array_like, shape (3,)
        The measured and the commanded ejection [m/s], RTN (the picosatellite's).
    t_release, u_release : float
        The release's epoch [s] and mean argument of latitude [rad].
    period : float
        The orbit's period in argument of latitude [s] (with J2 when the plan has it).
    t_earliest : float
        The first pulse's earliest epoch [s].
    max_pulse : float
        The largest pulse [m/s], > 0.

    Returns
    -------
    tuple of PlannedBurn
        The carrier's pulses (purpose ``ejection_completion``; a carrier burn enters the relative motion as -dv, so
        each is (measured - commanded) / pulses); empty when the rest is zero.
    """
    if not max_pulse > 0.0:
        raise ValueError(f"the completion's largest pulse must be > 0 m/s, got {max_pulse}")
    rest = np.asarray(dv_commanded, dtype=float) - np.asarray(dv, dtype=float)
    norm = float(np.linalg.norm(rest))
    if norm == 0.0:
        return ()
    pulses = max(1, math.ceil(norm / max_pulse - 1e-12))
    first = max(1, math.ceil((t_earliest - t_release) / period - 1e-9))
    return tuple(PlannedBurn.at(t_release + (first + j) * period, u_release, -rest / pulses, "carrier",
                                "ejection_completion") for j in range(pulses))


def reversal_burn(cam: PlannedBurn, period: float, t_after: float) -> PlannedBurn:
    """The CAM undone: the opposite carrier burn at the CAM's argument of latitude, the first whole orbit after the
    CAM later than ``t_after`` [s] (seed 002 Eq. 2: the two cancel in every ROE, only the along-track offset grown
    meanwhile stays).

    Parameters
    ----------
    cam : PlannedBurn
        The CAM.
    period : float
        The orbit's period in argument of latitude [s].
    t_after : float
        The reversal comes after this epoch [s] (the completion's last pulse).

    Returns
    -------
    PlannedBurn
        The reversal (purpose ``collision_avoidance_reversal``).
    """
    orbits = max(1, math.floor((t_after - cam.epoch) / period + 1e-9) + 1)
    return PlannedBurn.at(cam.epoch + orbits * period, cam.u, -np.asarray(cam.dv_rtn, dtype=float), "carrier",
                          "collision_avoidance_reversal")
